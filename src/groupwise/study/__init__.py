"""Studies: the simulated RLHF study (SPEC §8) and the clustering study (SPEC §4).

Simulated study: `runner` runs (env, DM, seed) cells locally or on Ray, `profiles` sizes
them, `cells` and `results` read what they wrote, `statistics` holds the pure statistics,
`figures` draws, `report` writes ``report.md``. Clustering study: `clustering`,
`clustering_plot`, `policy_mix`.

Nothing is imported here, so importing one study does not load the other's dependencies.
"""
