"""A round's pool made and shown: sampled from a policy (`sampling`, from its `sources`) and
published for the page as clips, tree and candidates (`publish`, in the directory format of
`files`).

The data it is made of sit below it: episodes and their windows (`groupwise.episodes`), and
the pool with its distances and tree (`groupwise.behaviour.pool.BehaviourPool`). Import from
the submodules; this package imports nothing.
"""
