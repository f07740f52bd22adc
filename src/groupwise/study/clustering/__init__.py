"""The clustering study (SPEC §4; the paper's supplement §1): which way of grouping behaviours
gives groups whose true returns are alike.

`policy_mix` samples behaviours with varied returns, `methods` cuts and scores them, `runner`
runs the study, `report` and `plot` write its table and figure. ``groupwise clustering-study``
is its command.
"""
