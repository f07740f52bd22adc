"""A round's behaviours: episodes cut into windows (`fragments`), sampled from a policy
(`sampling`), held with the ensemble's predictions (`behaviours.BehaviourPool`), named
``b<i>`` (`ids`), and published for the page as clips, tree and candidates (`publish`, in
the directory format of `files`).

Import from the submodules; this package imports nothing, so `behaviour` may name
behaviours (`ids`) without pulling in the pool.
"""
