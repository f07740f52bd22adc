"""The case studies (paper §"Example Cases"): teach a target behaviour that has no reward and
measure it by the target's own score.

`case_study` runs one (``groupwise case-study``), `film` films its evaluated episodes,
`table` and `continuous_table` tabulate run directories, `target_reference` trains
PPO on the target's own step score (the ceiling of any teacher), `splits_posture` replays a
walker's episodes to tell why a split is not held.
"""
