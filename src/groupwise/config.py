"""Typed configuration, one validated dataclass per concern, composed into `RunConfig`.

Every number is a default from SPEC §3 (the paper's study), not a constant. The resolved
config is written as JSON beside every run. The classes are pydantic dataclasses: each
field's type and bounds are its validation (a `ValueError` names the field), they stay
ordinary frozen dataclasses for `dataclasses.replace`/`asdict`, and the interactive app's
session settings (`storage.settings.SessionSettings`) take these models and field types as
they are rather than mirroring them.
"""

import dataclasses
import json
from collections.abc import Mapping
from dataclasses import field
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import ConfigDict, Field, TypeAdapter, model_validator
from pydantic.dataclasses import dataclass

from groupwise.config_history import legacy_loop_fields_moved, removed_dropped
from groupwise.preferences.judgement import MAX_GROUP

_STRICT = ConfigDict(extra="forbid", use_attribute_docstrings=True)
"""Unknown fields fail; each field's docstring is its description (OpenAPI, the page's help)."""

PositiveInt = Annotated[int, Field(ge=1)]
FragmentLength = Annotated[int, Field(ge=1, description="L, steps per behaviour")]
ExplorationFraction = Annotated[
    float, Field(ge=0.0, lt=1.0, description="share of sampled steps with random actions")
]
Seed = Annotated[int, Field(ge=0, le=2**32 - 1, description="everything random derives from it")]
PairDerivation = Annotated[
    Literal["cover", "cartesian"],
    Field(description="how a group judgement becomes pairs: max(m, n) (cover) or m × n"),
]
PairOversample = Annotated[
    float, Field(ge=1, description="pairs per judgement: this many times what the derivation gives")
]
PairCap = Annotated[
    float | None, Field(gt=0, description="keep at most pair_cap × comparisons pairs a round")
]


@dataclass(frozen=True, config=_STRICT)
class RewardConfig:
    """The reward-model ensemble and its Bradley–Terry training (SPEC §3)."""

    ensemble_size: Annotated[int, Field(ge=1, le=32)] = 3
    """K, the number of independently bootstrapped members."""
    hidden_sizes: tuple[PositiveInt, ...] = (64, 64)
    """Hidden layer widths of each member's MLP."""
    activation: str = "relu"
    """Hidden-layer nonlinearity, a key of `groupwise.reward.network.ACTIVATIONS`."""
    lr: Annotated[float, Field(gt=0)] = 1e-3
    """AdamW learning rate."""
    batch_size: PositiveInt = 4
    """Preference pairs per minibatch."""
    epochs: Annotated[int, Field(ge=1, le=1000)] = 3
    """Passes over the (bootstrapped) dataset per fit after round 0. On a simulated 5-round
    session (warm-started ensemble) 3 beat 1 and matched 5 and 10 within seed noise."""
    initial_epoch_multiplier: Annotated[float, Field(ge=1, le=100)] = 10.0
    """Round 0 trains this many times more epochs (its dataset is small and the net fresh):
    with 10 pairs, 30 epochs lifted the round-0 reward's correlation with the truth from
    0.35 (3 epochs) to 0.49, and PPO trains on that reward for a whole round."""
    initial_l2: Annotated[float, Field(ge=0)] = 1e-4
    """Starting weight of the L2 penalty; adapted during training (see `bradley_terry`)."""
    l2_bounds: tuple[float, float] = (1.1, 1.5)
    """Validation/training loss ratio band the adaptive L2 weight aims for (Christiano et al.)."""
    l2_factor: float = 1.2
    """After each epoch with a validation split, the L2 weight is multiplied by this when the
    loss ratio is above `l2_bounds` and divided by it when below."""
    l2_range: tuple[float, float] = (1e-8, 0.1)
    """The adaptive L2 weight stays inside this range. Above ~0.1 the penalty (about 4 for a
    fresh 64-64 member) swamps the cross-entropy and can kill every ReLU for good: the
    reward becomes a constant (seen on small validation splits, `bradley_terry`)."""
    validation_fraction: Annotated[float, Field(ge=0, lt=1)] = 0.2
    """Share of pairs held out for validation, only when there are `min_pairs_for_validation`."""
    min_pairs_for_validation: Annotated[int, Field(ge=0)] = 10
    """Below this many pairs there is no held-out split (tiny datasets must not crash)."""
    bootstrap: bool = True
    """Each member trains on its own resample with replacement of the training pairs."""
    warm_start: bool = True
    """Each fit continues from the last one's weights; off, every fit starts from fresh
    weights (and the initial L2 weight)."""
    standardise_output: bool = False
    """After each fit, centre and scale every member's reward to mean 0, sd 1 over the
    dataset's steps in the reward PPO sees (`RewardEnsemble.standardise_output`)."""
    use_actions: bool = True
    """The members see [obs ; act] (SPEC §3); off, the observation alone. Neither wins on
    every env (ARCHITECTURE.md, "Reward inputs"): observation-only members stopped Pendulum-v1
    seeds from learning to spin (-127 ± 12 vs -233 ± 198) and did better on GridWorld, but
    cannot see a control cost: on the study's Reacher (1,000 steps) the groupwise DM's agents
    collapsed to -865 ± 546 against -199 ± 70 with [obs ; act]."""
    action_term: Literal["joint", "additive", "cost"] = "cost"
    """How the action enters each member's reward (with `use_actions`): "cost" (default),
    f(obs) − Σ_i c_i (a_i / rms_i)², a learned control cost c_i ≥ 0; "additive", f(obs) +
    g(act), two MLPs summed; "joint", one MLP over [obs ; act] (SPEC §3). A joint reward
    learnt from 30-step sums credits the torque that keeps a pendulum near the top (braking,
    0.5 sd of the reward, where the true cost is 0.001 sd) and PPO, braking everywhere, cannot
    swing up; a cost has the form of every SPEC env's true reward and cannot pay an action
    only in some states. Pendulum-v1 at SPEC noise, 5 seeds: −166 ± 68 against −564 ± 290
    for "joint" (docs/results/peer)."""


@dataclass(frozen=True, config=_STRICT)
class PPOConfig:
    """Stable-Baselines3 PPO, the study's defaults (SPEC §3)."""

    n_envs: Annotated[int, Field(ge=1, le=64)] = 8
    """Copies of the env stepped together, in one process; a rollout is n_envs × n_steps."""
    n_steps: Annotated[int, Field(ge=8, le=8192)] = 256
    """Steps per env per rollout."""
    batch_size: Annotated[int, Field(ge=2, le=65536)] = 64
    """Steps per PPO minibatch; at most a rollout (n_envs × n_steps)."""
    n_epochs: Annotated[int, Field(ge=1, le=50)] = 10
    """Passes over each rollout's minibatches."""
    learning_rate: Annotated[float, Field(gt=0, le=1)] = 2e-3
    """Adam learning rate of the policy and value networks (constant)."""
    clip_range: Annotated[float, Field(gt=0)] = 0.1
    """PPO's clip ε: how far one update may move the policy's probability ratio from 1."""
    gamma: Annotated[float, Field(gt=0, le=1)] = 0.97
    """Discount of the returns PPO maximises (and of the reward normaliser's running return)."""
    gae_lambda: Annotated[float, Field(ge=0, le=1)] = 0.95
    """λ of generalised advantage estimation: 0 one-step TD, 1 Monte Carlo returns."""
    ent_coef: Annotated[float, Field(ge=0)] = 0.01
    """Weight of the entropy bonus in the loss (keeps the policy exploring)."""
    net_arch: Annotated[
        tuple[Annotated[int, Field(ge=1, le=1024)], ...], Field(min_length=1, max_length=4)
    ] = (32, 32)
    """Hidden layer widths of the policy network and, separately, of the value network."""
    normalize_obs: bool = True
    """Running observation normalisation (VecNormalize)."""
    normalize_reward: bool = True
    """Scale the reward by a running return std (VecNormalize): the env's own reward, and a
    learned one when `standardise_reward` is off."""
    reset_reward_norm: bool = False
    """Forget the running reward statistics at the start of every round's training (the
    reward function changed with the fit before it)."""
    standardise_reward: bool = True
    """Centre and scale the learned reward per step by its running mean and sd over PPO's
    rollouts (imitation's `NormalizedRewardNet`), instead of scaling it by the return std.
    At SPEC noise, 15 seeds: Hopper-v4 643 ± 620 and Walker2d-v4 195 ± 176, against
    imitation's 622 and 181 and the return scaling's 483 and 88 (10 seeds); Pendulum-v1
    level (−168 against −166); the stand-up and the backflip 5/5 (issue 41,
    docs/results/peer, docs/results/case-studies/std-step)."""
    tensorboard: bool = True
    """Write TensorBoard logs under the run directory."""

    @model_validator(mode="after")
    def _batch_fits(self) -> "PPOConfig":
        if self.batch_size > self.n_envs * self.n_steps:
            raise ValueError(
                f"ppo batch_size {self.batch_size} is larger than a rollout "
                f"(n_envs × n_steps = {self.n_envs * self.n_steps})"
            )
        return self


@dataclass(frozen=True, config=_STRICT)
class LoopConfig:
    """The RLHF rounds (SPEC §3)."""

    env: str = "GridWorld"
    """A groupwise env name (see `groupwise.envs.ENVS`) or any Gymnasium id."""
    decision_maker: str = "pairwise"
    """Who gives feedback: a simulated decision-maker from `groupwise.teachers.DECISION_MAKERS`,
    or "human" (a person, through the app)."""
    comparisons: PositiveInt = 100
    """Total comparisons (queries) over the whole session."""
    rounds: PositiveInt = 5
    """Number of rounds R; feedback is gathered R times."""
    steps: Annotated[int, Field(ge=0)] = 100_000
    """Total PPO env steps over the RLHF phase, split evenly over the rounds."""
    final_steps: Annotated[int, Field(ge=0)] = 0
    """Extra PPO steps on the frozen learned reward after the last round."""
    schedule: Literal["constant", "hyperbolic", "inverse_quadratic"] = "constant"
    """How comparisons after round 0 are spread over the rounds."""
    initial_fraction: Annotated[float, Field(gt=0, le=1)] = 0.1
    """Share of all comparisons asked in round 0."""
    fragment_length: FragmentLength = 30
    """L, steps per behaviour (and frames per clip)."""
    exploration_fraction: ExplorationFraction = 0.05
    """Share of sampled steps that take random actions (0.25 in the interactive app)."""
    pool_size: Annotated[int, Field(ge=2)] | None = None
    """Pool size N of every round (the app's); None: pool_factor × the round's comparisons."""
    pool_factor: Annotated[float, Field(gt=0)] = 2.0
    """Pool size N = pool_factor × comparisons this round (when pool_size is None) ..."""
    pool_cap: Annotated[int, Field(ge=2)] = 200
    """... capped at this many behaviours."""
    pool_oversample: Annotated[float, Field(ge=1)] = 2.0
    """Sample episodes for this many times N windows, of which N are kept ..."""
    pool_windows_max: Annotated[int, Field(ge=2)] | None = 1000
    """... of at most this many windows, or N where N is more (None: no limit). Sampling is
    most of a large round's preparation (a 1,000-behaviour app round sampling 2,000
    windows: 38 of 55 CPU-s), and the selection matters less once the pool is larger than
    a person compares in a round; pools of up to 500, every headless run's among them,
    keep the whole oversample (issue 22)."""
    pool_selection: Literal["uncertain", "random"] = "uncertain"
    """... those the ensemble is most uncertain about (SPEC §3.2), or a random N."""
    pool_variants: Annotated[int, Field(ge=0)] = 0
    """Biased variants of the current policy (`rl.policy.biased_variants`, drawn anew each
    round) that a share `pool_variant_share` of the windows is sampled from, so that a pool
    shows behaviours the policy itself rarely reaches (issue 20); 0: every window from the
    current policy (SPEC §3.1)."""
    pool_variant_share: Annotated[float, Field(ge=0, le=1)] = 0.5
    """... the share of the windows they give ..."""
    pool_variant_scale: Annotated[float, Field(ge=0, le=1)] = 0.5
    """... and how far each pushes the actions: a fixed offset per action dimension of up
    to this share of half its range."""
    candidate_pairs: PositiveInt = 10
    """Pairwise active learning: random candidate pairs scored per query."""
    eval_episodes: Annotated[int, Field(ge=0)] = 5
    """Episodes of the true reward used to measure the policy after each round."""
    pair_derivation: PairDerivation = "cover"
    """How a group judgement becomes preference pairs (SPEC §6), a key of
    `groupwise.preferences.PAIR_DERIVATIONS`: "cover" (max(m, n) pairs) or "cartesian"
    (m × n pairs, the earlier CLRVis method, for ablations)."""
    pair_cap: PairCap = None
    """Keep at most ⌊pair_cap × comparisons⌋ derived pairs per round, drawn at random (SPEC §8's
    capped ablation uses 1.0: the group DMs get no more pairs than the pairwise DM); None keeps
    every pair."""
    pair_oversample: PairOversample = 1.0
    """Each judgement yields ⌊pair_oversample × k + ½⌋ pairs, k being what `pair_derivation`
    gives (the extra ones from further draws of it; `preferences.pairs.oversample_pairs`).
    The paper's reference code drew twice as many pairs per judgement: the study's
    ``pairs2x`` ablation uses 2.0."""
    max_group_size: Annotated[int, Field(ge=2)] = MAX_GROUP
    """Largest group the group DMs compare (paper §6: 8 keeps comparisons humanly possible)."""
    seed: Seed = 0
    """Every random generator of the run derives from it (`run.streams.round_streams`)."""


@dataclass(frozen=True, config=_STRICT)
class TeacherConfig:
    """How the simulated decision-makers perceive and answer (SPEC §7; `groupwise.teachers`).

    A person answering through the page uses none of it; the rounds' diagnostics still
    measure pools in its noise unit (``return_sd_over_noise``)."""

    noise_sigma: Annotated[float, Field(ge=0)] = 0.25
    """Decision-maker noise per step (SPEC §7): ε ~ N(0, (L·σ)²) per behaviour per judgement."""
    gamma: Annotated[float, Field(gt=0, le=1)] = 0.9
    """Myopic imperfect teachers ("<dm>-myopic"): discount per step back from the last (B-Pref)."""
    mistake: Annotated[float, Field(ge=0, le=1)] = 0.1
    """Mistake-prone teachers ("<dm>-mistake"): probability of flipping a label (B-Pref)."""
    skip_quantile: Annotated[float, Field(ge=0, le=1)] = 0.1
    """Skipping teachers ("<dm>-skip"): skip when both groups look worse than this quantile
    of the pool's true returns."""
    equal_fraction: Annotated[float, Field(ge=0)] = 0.1
    """Equal-when-close teachers ("<dm>-equal"): answer equal when the groups' mean returns
    differ by less than this many standard deviations of the pool's true returns."""
    interactive_gap: Annotated[float, Field(ge=0)] = 1.0
    """The "interactive-distinct" DM compares only groups whose mean true returns differ by at
    least this many per-behaviour noise sds (L·σ); the spec's Interactive-DM uses 0."""
    interactive_clear: Annotated[float, Field(ge=0)] = 1.0
    """The "interactive-clear" DM compares groups whose mean true returns differ by at least
    this many typical member deviations (`query.interactive.clear_gaps`)."""
    label_error: Annotated[float, Field(gt=0, lt=0.5)] | None = None
    """A teacher calibrated to people: its noise set per pool so that this share of its
    comparisons of two behaviours of unequal return is wrong (`teachers.calibration`; the
    paper's user study: 0.108–0.128, so 0.12); None: `noise_sigma` per step (SPEC §7)."""
    pace_s: Annotated[float, Field(gt=0)] | None = None
    """Seconds of a virtual clock the teacher takes per comparison (a timed teacher,
    `groupwise.run.continuous`); None: untimed, the rounds' records carry no clock."""


@dataclass(frozen=True, config=_STRICT)
class TrainingConfig:
    """When the agent trains: after each round's feedback, or all the time (issue 24)."""

    mode: Literal["rounds", "continuous"] = "rounds"
    """"rounds": PPO trains after the teacher ended the round (SPEC §8, the study's
    protocol); "continuous": PPO trains while the teacher answers, the reward model refitting
    between rollouts as pairs arrive (needs a timed teacher headless)."""
    ppo_steps_per_s: Annotated[float, Field(gt=0)] = 3000.0
    """PPO env steps per second of a timed teacher's clock (default: one core's measured
    throughput on Hopper, `python -m benchmarks ppo_throughput`)."""
    refit_pairs: PositiveInt = 20
    """Continuous training refits the reward model once this many new pairs arrived ..."""
    refit_s: Annotated[float, Field(gt=0)] = 60.0
    """... or this many seconds after the last fit, whichever comes first (with new pairs)."""
    kept_share: Annotated[float, Field(ge=0, le=0.5)] = 0.2
    """Continuous training: the share of each fresh pool (from round 1 on) sampled from the
    policy the person's answers prefer so far, beside what PPO does now; PPO goes back to
    that policy when every reward member pays its behaviours more, by more than chance
    (`run.kept_policy`). 0: none, every behaviour from PPO's latest rollouts."""
    pretrain_steps: Annotated[int, Field(ge=0)] = 0
    """PPO steps of unsupervised pre-training before round 0, paid a state-entropy bonus
    instead of the learned reward (`groupwise.run.pretrain`, PEBBLE), so that the first
    pools show more different behaviours; 0: none (issue 20)."""
    pretrain_k: Annotated[int, Field(ge=1, le=100)] = 5
    """k of the pre-training's k-nearest-neighbour entropy estimate (PEBBLE's 5)."""
    pretrain_states: Annotated[int, Field(ge=10, le=1_000_000)] = 10_000
    """Recent states each state's nearest neighbours are looked for among in pre-training."""
    teach_log_std: Annotated[float, Field(ge=-5.0, le=1.0)] | None = None
    """log σ of PPO's action noise once pre-training ends (`rl.ppo.PPOAgent.pretrain`;
    pre-training explores at SB3's initial 0, σ = 1 of a ±1 action range). The person judges
    PPO's sampled behaviours (a fresh pool is cut from its rollouts) and takes away its greedy
    policy; at σ = 1 the two differ (the stand-up's seed 1: 9 of 10 greedy episodes stand up
    and sit down, 4 of 10 sampled ones). None: as pre-training leaves it. Needs continuous
    actions."""


@dataclass(frozen=True, config=_STRICT)
class TreeConfig:
    """How the behaviour tree is cut (SPEC §4; `groupwise.behaviour.tree`)."""

    levels: PositiveInt = 4
    """Number of level bands; the root is at this level, leaves at 0."""
    method: Literal["complete", "average", "ward"] = "complete"
    """Linkage of the DTW distances (`behaviour.linkage.LINKAGE_METHODS`)."""
    bands: Literal["counts", "linear", "geometric"] = "counts"
    """Threshold spacing (`behaviour.bands.BANDS`): level l holds about N / k^l clusters
    ("counts"), or cuts at fixed fractions of the root height ("linear", the paper's; or
    "geometric")."""
    balance: Annotated[float, Field(ge=1.0)] | None = 2.0
    """Size caps after the cut (`behaviour.balance`, issue 22): a node at level l >= 2
    below the root holding more than max(8, balance · k^l) leaves, or more than half the
    pool, is split by its own sub-tree unless its behaviours are indistinguishable, and a
    level-1 node by more than 8; None: the bands alone."""
    top_balance: Annotated[float, Field(ge=1.0)] | None = 1.25
    """With `balance`, the top level's cap (`behaviour.balance`, issue 40): a top-level
    cluster (the root's child) holds at most max(8, top_balance · N / k) leaves, that many
    times the mean of the k the cut aims for; None: `balance` alone. On Hopper pools of
    random and trained policies the largest top-level cluster held up to 48 % of 100 and
    32 % of 1,000 behaviours with `balance` alone, at most 39 % and 22 % with 1.25
    (docs/results/tree-balance)."""
    dtw_band: Annotated[float, Field(gt=0.0, le=1.0)] | None = 0.2
    """Sakoe–Chiba radius of the DTW distances as a share of the behaviours' length L:
    ceil(share · L) steps (`behaviour.dtw`; None: no band). 0.2 kept the tree close to exact
    DTW's on 1.5 s Hopper behaviours and halved the time (docs/results/dtw-options)."""
    dtw_stride: PositiveInt = 1
    """Coarser time step of the DTW distances: the means of this many consecutive steps are
    aligned (`behaviour.dtw`; 1: every step). Clips and the reward model keep every step."""


@dataclass(frozen=True, config=_STRICT)
class RunConfig:
    """A whole run: the rounds, the simulated teacher, the reward model, PPO and the
    behaviour tree."""

    loop: LoopConfig = field(default_factory=LoopConfig)
    """The RLHF rounds: env, budgets, pool, pairs."""
    teacher: TeacherConfig = field(default_factory=TeacherConfig)
    """The simulated decision-maker's perception and imperfections."""
    reward: RewardConfig = field(default_factory=RewardConfig)
    """The reward-model ensemble and its training."""
    ppo: PPOConfig = field(default_factory=PPOConfig)
    """The policy's PPO."""
    tree: TreeConfig = field(default_factory=TreeConfig)
    """How the behaviour tree is cut."""
    training: TrainingConfig = field(default_factory=TrainingConfig)
    """When the agent trains: after each round's feedback, or while the teacher answers."""

    def to_json(self) -> str:
        return json.dumps(dataclasses.asdict(self), indent=2)

    def save(self, path: Path) -> None:
        path.write_text(self.to_json() + "\n")

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "RunConfig":
        """Validate a config read from JSON (lists become tuples; unknown fields fail).

        Configs written with an old name of a loop field (`config_history.LEGACY_LOOP_FIELDS`:
        the teacher fields before `TeacherConfig` existed, "oracle") are read as if written
        now; the fields of mechanisms removed since (`config_history.REMOVED_FIELDS`) are
        dropped, with a warning when one was in use.

        Raises:
            ValueError: a field fails validation, or an old and a new name give one field.
        """
        return _RUN_CONFIG.validate_python(removed_dropped(legacy_loop_fields_moved(data)))

    def merged(self, partial: Mapping[str, Any]) -> "RunConfig":
        """This config with the fields `partial` gives replaced, section by section (a
        partial config: ``{"loop": {"pool_variants": 8}}`` changes one field; a whole one
        replaces every field), validated as `from_dict` does.

        Raises:
            ValueError: `partial` is not a JSON object of sections, or a field fails
                validation.
        """
        if not isinstance(partial, Mapping):
            raise ValueError(f"a config is a JSON object, got {type(partial).__name__}")
        base = dataclasses.asdict(self)
        merged = dict(base)
        for section, fields in legacy_loop_fields_moved(dict(partial)).items():
            if section in base and isinstance(fields, Mapping):
                merged[section] = {**base[section], **fields}
            else:
                merged[section] = fields  # validation names an unknown section or bad value
        return RunConfig.from_dict(merged)

    @classmethod
    def load(cls, path: Path) -> "RunConfig":
        return cls.from_dict(json.loads(path.read_text()))


_RUN_CONFIG = TypeAdapter(RunConfig)
