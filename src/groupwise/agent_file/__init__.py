"""The take-away agent's file format: what ``agent.zip`` and its summary ``agent.json`` hold.

    README.md          how to load it, with and without groupwise (`readme`)
    agent.json         `summary.AgentSummary`: env, round, steps, the true return per round
                       (and a target env's episode score), the observation normalisation
    policy.zip         the Stable-Baselines3 PPO policy (it acts on normalised observations)
    vecnormalize.npz   the observation normaliser's running mean and variance
    reward.pt          the learned reward ensemble (`RewardEnsemble.load`)
    config.json        the core's `RunConfig` of the run
    settings.json      the app session's settings (app sessions only)
    rounds.csv         one row per round, as the run wrote it

`summary` (names and the summary's types), `text` (the scores in words), `readme` and
`archive` (writing and reading the zip) import neither torch, SB3 nor the run: the app's
server reads summaries; `groupwise.run.agent_package` makes one from a run, and
`groupwise.rl.trained_agent.load_agent` loads the policy. Import from the submodules; this
package imports nothing.
"""
