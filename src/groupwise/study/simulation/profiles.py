"""Study profiles: how big each cell of a simulated study is (SPEC §8).

A profile fixes everything of a cell but its env, decision-maker and seed: the comparisons,
the rounds, the PPO step budgets per env and the evaluation. Seven ship:

- ``paper``: SPEC §8 as written, for a cluster (``--ray``). 400 comparisons in 5 rounds,
  then a long PPO run on the frozen learned reward. The paper gives no step budgets; its
  training curves do: HalfCheetah ran past six million steps ("it took six million steps
  before the average of Groupwise-DM overtook Interactive-DM") and Walker2d past three
  ("slopes downward after 2–3 million steps"). We take 7 M steps for HalfCheetah, 5 M for
  Hopper and Walker2d, 2 M for Reacher and 1 M for the two small envs, 0.5 M (0.2 M for the
  small envs) of them in the RLHF rounds. At the ~1,650 PPO steps/s one core managed here
  (see `LOCAL`), that is 315 M steps ≈ 53 core-hours for 6 envs × 3 DMs × 5 seeds: about
  3.5 h on 16 cores, 27 h on 2.
- ``local``: the largest budget that runs the same 90 cells in a night (≤ 10 h; 8–9 h
  extrapolated from measured cells) on two cores; the arithmetic is in `LOCAL`'s docstring.
- ``session``: the paper's protocol on GridWorld, MountainCarContinuous and Reacher with a
  fifth of ``local``'s PPO budgets: about an hour on two cores (the study in ``docs/results``).
- ``mujoco``: Hopper, HalfCheetah and Walker2d at 120 k + 120 k PPO steps per cell, beside
  ``session`` (about 50 min on two cores, minutes on a 16-core machine).
- ``dmc``: DeepMind Control's Walker-walk and Cheetah-run at 100 preferences (issue 42).
- ``quick``: GridWorld and MountainCarContinuous, 2 seeds, tiny budgets: a few minutes on two
  cores, for CI and for trying the pipeline.
- ``smoke`` (hidden): the tiniest cell that still runs every phase, for the tests.

Every profile only sets `RunConfig` fields; whatever it leaves alone keeps the defaults of
`groupwise.config` (SPEC §3). An ablation (`ablations.ABLATIONS`) changes one of them after.
"""

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field

from groupwise.config import (
    LoopConfig,
    PPOConfig,
    RewardConfig,
    RunConfig,
)
from groupwise.recipes import PPO_PRESETS, RECIPES, RecipeName
from groupwise.study.simulation.ablations import ablate


@dataclass(frozen=True)
class EnvBudget:
    """PPO env steps of one cell."""

    steps: int
    """Steps over the RLHF rounds (`LoopConfig.steps`, split evenly over the rounds)."""
    final_steps: int
    """Steps on the frozen learned reward after the last round (`LoopConfig.final_steps`)."""

    @property
    def total(self) -> int:
        return self.steps + self.final_steps


@dataclass(frozen=True)
class StudyProfile:
    """Everything of a study cell except (env, DM, seed)."""

    name: str
    """Key in `PROFILES` and the name written into ``study.json``."""
    summary: str
    """One line for ``--help`` and the report."""
    envs: tuple[str, ...]
    """Envs run when the command names none."""
    dms: tuple[str, ...]
    """Decision-makers run when the command names none (those of them that are registered)."""
    seeds: int
    """Seeds (0 … seeds−1) run when the command names no count."""
    comparisons: int
    """Comparisons (queries) per cell (`LoopConfig.comparisons`)."""
    rounds: int
    """Feedback rounds per cell (`LoopConfig.rounds`)."""
    budgets: Mapping[str, EnvBudget]
    """PPO budgets per env name; envs not listed get `default_budget`."""
    default_budget: EnvBudget
    """PPO budget of any env not in `budgets` (e.g. a Gymnasium id)."""
    eval_episodes: int = 5
    """True-reward episodes measured after every round (`LoopConfig.eval_episodes`)."""
    ppo: PPOConfig = field(default_factory=PPOConfig)
    """PPO settings of every cell."""
    reward: RewardConfig = field(default_factory=RewardConfig)
    """Reward-model settings of every cell."""
    pair_cap: float | None = None
    """`LoopConfig.pair_cap` of every cell: 1.0 holds every DM to `comparisons` preference
    pairs, as benchmarks counted in preferences (labelled pairs) are."""
    hidden: bool = False
    """Left out of the CLI's help (test-only profiles)."""

    def budget(self, env: str) -> EnvBudget:
        return self.budgets.get(env, self.default_budget)

    def run_config(self, env: str, dm: str, seed: int, ablation: str | None = None) -> RunConfig:
        """The full configuration of cell (env, dm, seed), changed by `ablation` if given
        (a key of `ablations.ABLATIONS`, e.g. ``capped``: SPEC §8's capped pairs).

        Raises:
            ValueError: a value `LoopConfig` rejects, or an unknown ablation.
        """
        budget = self.budget(env)
        values: dict[str, object] = {
            "env": env,
            "decision_maker": dm,
            "comparisons": self.comparisons,
            "rounds": self.rounds,
            "steps": budget.steps,
            "final_steps": budget.final_steps,
            "eval_episodes": self.eval_episodes,
            "seed": seed,
            "pair_cap": self.pair_cap,
        }
        loop = dataclasses.replace(LoopConfig(), **values)  # type: ignore[arg-type]  # mixed value types
        # SPEC §8's protocol by name (recipes.RECIPES), then the profile's own reward and PPO
        config = RECIPES[STUDY_RECIPE].apply(RunConfig(loop=loop), env)
        config = dataclasses.replace(config, reward=self.reward, ppo=self.ppo)
        return ablate(config, ablation)


STUDY_RECIPE: RecipeName = "paper"
"""The recipe of every study cell (`recipes.RECIPES`): SPEC §8's protocol, whatever the CLI's
and the app's default recipe is."""

PAPER_DMS = ("pairwise", "groupwise", "interactive")
"""The paper's three decision-makers (SPEC §7); any other registered DM can be asked for."""
_SMALL_ENVS = ("GridWorld", "MountainCarContinuous")
_ALL_ENVS = ("Hopper", "HalfCheetah", "Walker2d", "Reacher", "MountainCarContinuous", "GridWorld")


def _budgets(steps: Mapping[str, tuple[int, int]]) -> dict[str, EnvBudget]:
    """`EnvBudget`s by env from (steps, final_steps) pairs."""
    return {env: EnvBudget(steps=s, final_steps=f) for env, (s, f) in steps.items()}


PAPER = StudyProfile(
    name="paper",
    summary="SPEC §8 as written: 400 comparisons, 1–7 M PPO steps per cell (a cluster's job)",
    envs=_ALL_ENVS,
    dms=PAPER_DMS,
    seeds=5,
    comparisons=400,
    rounds=5,
    budgets=_budgets(
        {
            "Hopper": (500_000, 4_500_000),
            "HalfCheetah": (500_000, 6_500_000),
            "Walker2d": (500_000, 4_500_000),
            "Reacher": (500_000, 1_500_000),
            "MountainCarContinuous": (200_000, 800_000),
            "GridWorld": (200_000, 800_000),
        }
    ),
    default_budget=EnvBudget(steps=500_000, final_steps=4_500_000),
    eval_episodes=10,
)

# The profiles below run the paper's protocol (its envs, DMs, seeds, 400 comparisons in 5
# rounds) at smaller budgets: copies of PAPER with what they change.
LOCAL = dataclasses.replace(
    PAPER,
    name="local",
    summary="the paper's 90 cells in a night (8–9 h) on 2 cores: 400 comparisons, "
    "0.4–1.5 M PPO steps per cell",
    budgets=_budgets(
        {
            "Hopper": (300_000, 900_000),
            "HalfCheetah": (400_000, 1_100_000),
            "Walker2d": (400_000, 1_100_000),
            "Reacher": (200_000, 600_000),
            "MountainCarContinuous": (100_000, 300_000),
            "GridWorld": (100_000, 300_000),
        }
    ),
    default_budget=EnvBudget(steps=300_000, final_steps=900_000),
    eval_episodes=5,
)
"""Sized from measured cells on this 2-core machine, two cells running at once.

Measured (groupwise DM, 400 comparisons in 5 rounds of 2,048 PPO steps, then 81,920 steps
on the frozen reward): PPO ran at 1,500 (Hopper, Walker2d), 1,740 (Reacher) and 1,950
(HalfCheetah) env steps/s per worker; GridWorld and the pairwise DM alike. The rest of a
round (pool sampling 1–3 s, feedback ≤ 0.2 s, reward fit ≤ 1.4 s with 1,272 pairs,
evaluation 0.5–1.6 s) is ~6 s, so ~40 s per cell with process start-up. Budget: 15 cells
per env × (1.2 + 1.5 + 1.5 + 0.8 + 0.4 + 0.4) M steps = 87 M steps; at 1,500 steps/s that
is 58,000 core-s, plus 90 × 40 s = 3,600 s, over 2 cores ≈ 30,800 s ≈ 8.6 h (7.8 h at the
measured mean of 1,650 steps/s). The longest cell (1.5 M steps, ~17 min) leaves no long
tail. A quarter of each budget is spent in the feedback rounds. Other processes on the
machine slow it down in proportion.
"""

SESSION = dataclasses.replace(
    PAPER,
    name="session",
    summary="GridWorld, MountainCarContinuous and Reacher, 5 seeds, 400 comparisons, "
    "80–160 k PPO steps per cell: about an hour on 2 cores",
    envs=("GridWorld", "MountainCarContinuous", "Reacher"),
    budgets={
        "Reacher": EnvBudget(steps=80_000, final_steps=80_000),
    },
    default_budget=EnvBudget(steps=40_000, final_steps=40_000),
    eval_episodes=5,
    ppo=PPOConfig(tensorboard=False),
)
"""The study that fits in one working session: the paper's protocol (400 comparisons in 5
rounds, three DMs, five seeds) on the three cheapest envs, with a fifth of `LOCAL`'s PPO
budgets. 45 cells × (80–160 k steps) = 4.8 M steps. Measured: 74 min for the 45 cells on 2
workers, on a machine shared with other test runs."""

MUJOCO = dataclasses.replace(
    PAPER,
    name="mujoco",
    summary="Hopper, HalfCheetah and Walker2d, 400 comparisons in 5 rounds, 120 k + 120 k "
    "PPO steps per cell",
    envs=("Hopper", "HalfCheetah", "Walker2d"),
    budgets={},
    default_budget=EnvBudget(steps=120_000, final_steps=120_000),
    eval_episodes=5,
    ppo=PPOConfig(tensorboard=False),
)
"""The paper's protocol on its three MuJoCo locomotion envs at a budget beside `SESSION`'s:
45 cells × 240 k steps = 10.8 M steps. Measured: 36 cells (4 DMs × 3 seeds) took 38 min on
2 workers of a 2-core machine (106–152 s a cell), so the 45 of five seeds take about 50."""

DMC = dataclasses.replace(
    PAPER,
    name="dmc",
    summary="DeepMind Control's Walker-walk and Cheetah-run at 100 preferences, 2 seeds, "
    "100 k + 200 k PPO steps per cell",
    envs=("dm_control/walker-walk-v0", "dm_control/cheetah-run-v0"),
    seeds=2,
    comparisons=100,
    pair_cap=1.0,
    budgets={},
    default_budget=EnvBudget(steps=100_000, final_steps=200_000),
    eval_episodes=5,
    ppo=dataclasses.replace(PPO_PRESETS["mujoco"], tensorboard=False),
)
"""The paper's protocol on two DeepMind Control tasks (the ``[dmc]`` extra), counted as the
preference-based RL literature counts (issue 42): 100 preferences, i.e. 100 comparisons with
every DM held to one preference pair per comparison (`pair_cap` 1.0), in 5 rounds, then PPO
on the frozen learned reward; PPO's MuJoCo settings (both are MuJoCo bodies with 1,000-step
episodes). 300 k PPO steps per cell: a fraction of the 0.5–1 M SAC steps the published
tables (PEBBLE, SURF, QPA, PPE) run, sized so that the 12 cells and their 4 true-reward
references (`reference.train_on_true_reward`) fit in a session on two cores
(`research/dmc_study.py`). Measured: PPO runs at ~1,500 env steps/s on Walker-walk, one core."""

QUICK = StudyProfile(
    name="quick",
    summary="GridWorld and MountainCarContinuous, 2 seeds, tiny budgets: ~2 min on 2 cores",
    envs=_SMALL_ENVS,
    dms=PAPER_DMS,
    seeds=2,
    comparisons=40,
    rounds=2,
    budgets={},
    default_budget=EnvBudget(steps=16_384, final_steps=16_384),
    eval_episodes=2,
    reward=RewardConfig(epochs=2, initial_epoch_multiplier=3.0),
    ppo=PPOConfig(tensorboard=False),
)
"""Measured: the 12 cells took 110 s on this 2-core machine (13–20 s each, two at a time)."""

SMOKE = StudyProfile(
    name="smoke",
    summary="the smallest cell that runs every phase (tests only)",
    envs=("GridWorld",),
    dms=PAPER_DMS,
    seeds=1,
    comparisons=16,  # with 6 or 10 the group DMs found no comparison on GridWorld (0 pairs)
    rounds=2,
    budgets={},
    default_budget=EnvBudget(steps=512, final_steps=256),
    eval_episodes=1,
    reward=RewardConfig(epochs=1, initial_epoch_multiplier=2.0),
    ppo=PPOConfig(n_envs=2, n_steps=128, batch_size=64, n_epochs=1, tensorboard=False),
    hidden=True,
)

PROFILES: dict[str, StudyProfile] = {
    p.name: p for p in (PAPER, LOCAL, SESSION, MUJOCO, DMC, QUICK, SMOKE)
}
"""Every profile by name; `StudyProfile.hidden` ones are for tests."""
