"""The README.md of ``agent.zip``: what it holds and how to load it, with and without
groupwise."""

from groupwise.agent_file.summary import AgentSummary
from groupwise.agent_file.text import format_value, score_text


def readme(summary: AgentSummary) -> str:
    """The zip's README.md: what it holds and how to load it."""
    judged = sum(r.judgements for r in summary.rounds)
    feedback = sum(r.feedback for r in summary.rounds)
    score = score_text(
        summary.target,
        summary.measure,
        (summary.true_return_mean, summary.true_return_std),
        (summary.target_score_mean, summary.target_score_std),
    )
    target = summary.target
    scored = (
        f"Evaluated after round {summary.round} (the greedy policy over the run's evaluation "
        f"episodes): **{score}**."
    )
    if target is not None:
        scored += (
            f"\n\nThe target {target.name} counts {target.unit} per episode; an episode "
            f"succeeds from {format_value(target.threshold)} (stretch: "
            f"{format_value(target.stretch)}). The per-step sum adds up the target's per-step "
            "scores (the true reward a simulated teacher perceives); the episode score says "
            "whether teaching worked."
        )
    evaluated = (
        f'"{target.unit} per episode … (threshold {format_value(target.threshold)}) · '
        f'per-step sum … {target.step_unit}"'
        if target is not None
        else '"true return … ± …"'
    )
    per_round = summary.measure + (" and the episode score" if target is not None else "")
    return f"""# groupwise agent: {summary.env}, round {summary.round}

A PPO policy trained by groupwise on a reward model learned from preferences:
{judged} judgements over {feedback} feedback round(s), {summary.env_steps:,} PPO env steps
in all.

{scored}

## Load it with groupwise

```python
import groupwise

agent = groupwise.load_agent("agent.zip")
action = agent.predict(obs)                 # one observation, or a batch (B, obs_dim)
result = agent.evaluate("{summary.env}", episodes=5, seed=0)   # or an env, or a factory
print(result)                               # {evaluated}
result.returns                              # each episode's true return (the per-step sum)
result.scores                               # a target env's episode scores (None elsewhere)
reward = agent.reward_model()               # the learned reward ensemble
```

`predict` applies the saved observation normaliser before the policy, greedy by default
(`deterministic=False` samples). `evaluate` plays whole episodes and returns each one's true
return (the sum of ``info["true_reward"]``, a target env's per-step scores) and, in a
target env, its episode score (``info["target_total"]`` at the end, in the target's unit).

## Load it without groupwise

```python
import numpy as np
from stable_baselines3 import PPO

model = PPO.load("policy.zip", device="cpu")
norm = np.load("vecnormalize.npz")
def act(obs):
    x = np.clip((obs - norm["obs_mean"]) / np.sqrt(norm["obs_var"] + {summary.epsilon}),
                -{summary.clip_obs}, {summary.clip_obs})
    return model.predict(x, deterministic=True)[0]
```

(observations are normalised only when `agent.json`'s `normalize_obs` is true).

## Files

| file | holds |
|---|---|
| `policy.zip` | the Stable-Baselines3 PPO policy (`PPO.load`); it acts on normalised observations |
| `vecnormalize.npz` | the observation normaliser: `obs_mean`, `obs_var` (and return statistics) |
| `reward.pt` | the learned reward ensemble (`groupwise.RewardEnsemble.load`) |
| `agent.json` | env, round, steps, the {per_round} per round, the normaliser's constants |
| `config.json` | the run's configuration (`groupwise.RunConfig.load`) |
| `settings.json` | the app session's settings (sessions of the app only) |
| `rounds.csv` | one row per round, as `groupwise train` and the app write it |
"""
