"""The simulated RLHF study (SPEC §8): every (env, decision-maker, seed) cell a headless run.

`runner` runs the cells locally (spawn workers) or on Ray, `profiles` sizes them, `ablations`
names one-field changes of a cell's config, `cells` and `results` read what the cells wrote,
`statistics` holds the pure statistics (IQM, bootstrap intervals, Welch tests), `figures`
draws, `report` and `report_tables` write ``report.md`` beside the paper's numbers (`paper`).
``groupwise study`` and ``groupwise report`` are its commands.
"""
