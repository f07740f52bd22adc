"""Studies, one subpackage each:

- `simulation`: the simulated RLHF study (SPEC §8): (env, DM, seed) cells run locally or on
  Ray (`runner`), sized by `profiles`, varied by `ablations`, read back by `cells` and
  `results`, summarised by `statistics`, drawn by `figures`, written up by `report`;
- `clustering`: the clustering study (SPEC §4): behaviours from a mix of policies
  (`policy_mix`), cut by each method (`methods`), run by `runner`, reported and plotted;
- `case_studies`: teaching a target behaviour without a reward (`groupwise case-study`),
  its film, results tables, the reference PPO on the target's own score, and the walker's
  posture analysis.

Nothing is imported here, so importing one study does not load the other's dependencies.
"""
