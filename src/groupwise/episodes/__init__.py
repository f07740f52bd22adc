"""Episodes and the windows cut from them: the leaf data types every layer shares.

`fragments`: `Trajectory` (one whole episode), `Fragment` (a window of L steps of one, the
unit a person judges), tiling episodes into windows and stacking them; `ids`: behaviour i of
a pool is named ``b<i>``. Both import nothing of groupwise but `types`, so the behaviour
space, clips, queries, rollouts and storage share them without importing each other.

Import from the submodules; this package imports nothing.
"""
