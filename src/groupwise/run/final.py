"""The end of a run: PPO on the frozen learned reward, the agent's video and its download.

`round.train_frozen` is a round without feedback: no pool, no judgements, no reward fit; the
agent trains `steps` more PPO steps on the learned reward as the last fit left it, and is
evaluated on the true reward. Its `RoundRecord` is a row of ``rounds.csv`` like any other
(comparisons, pairs and the reward columns 0 or nan). `publish_agent` films the greedy
policy for one episode (``agent.mp4``, `clips.episode_video`) and packs the checkpoint into
``agent.zip`` with ``agent.json`` beside it (`groupwise.rl.trained_agent`).

The app's worker runs both after a session's last round, after "Finish now" and for
"Continue training" (`groupwise.worker.finishing`); `continue_run` does the same headless for
``groupwise train --from-session DIR`` (more PPO steps, or more rounds answered by a
simulated decision-maker, then the final phase again).
"""

import dataclasses
import json
import logging
import math
import shutil
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from groupwise.agent_file.archive import write_agent_zip
from groupwise.agent_file.summary import (
    AGENT_VIDEO,
    AGENT_ZIP,
    SETTINGS_FILE,
    AgentSummary,
    VideoSummary,
    read_summary,
    round_video_path,
    write_summary,
)
from groupwise.clips.episode_video import write_episode_video
from groupwise.clips.replay import FrameSettings
from groupwise.config import RunConfig
from groupwise.envs import DEFAULT_FRAME_SIZE
from groupwise.episodes.fragments import Trajectory
from groupwise.rl.agent_file import normalisation
from groupwise.rl.policy import Policy
from groupwise.rl.ppo import POLICY_FILE, PPOAgent
from groupwise.rl.rollout import sample_trajectories
from groupwise.run.agent_package import summarise
from groupwise.run.checkpoint import checkpoint_dir, latest_checkpoint
from groupwise.run.progress import CallbackList, ProgressBars, RunCallback, as_callback
from groupwise.run.records import RoundRecord
from groupwise.run.round import run_round, train_frozen
from groupwise.run.run import CONFIG_FILE, Run
from groupwise.run.streams import eval_rng, takeaway_streams
from groupwise.run.takeaway import (
    TakeawayChoice,
    TakeawayConfig,
    choose_round,
    last_round,
    write_choice,
)
from groupwise.teachers import DECISION_MAKERS
from groupwise.teachers.base import Teacher

log = logging.getLogger(__name__)


def publish_agent(
    run: Run,
    frozen: set[int],
    *,
    frame_size: int = DEFAULT_FRAME_SIZE[0],
    callback: RunCallback | None = None,
    choice: TakeawayChoice | None = None,
    video: bool = True,
    round_videos: bool = True,
) -> AgentSummary:
    """Film the run's greedy policy for one episode (``agent.mp4`` in the run's directory)
    and pack its latest checkpoint (`Run.commit`) into ``agent.zip``, with the summary
    ``agent.json`` written last. `frozen`: the rounds without feedback.

    `choice` hands over another round's policy (`groupwise.run.takeaway`; default: the
    last round's, chosen by nobody); `video` off writes no ``agent.mp4``; `round_videos`
    films every round's greedy policy too (``agent-rounds/round-NNNN.mp4``), the clips a
    person picks the take-away agent by on the results page (`agent_package.pick_round`)."""
    out, callback = run.directory, as_callback(callback)
    last = run.next_round - 1
    choice = choice or last_round([last])
    filmed = None
    if video:
        callback.on_phase("video", 0, 1)
        if choice.round == last:
            filmed = _film(run, run.agent.policy(deterministic=True), out / AGENT_VIDEO, frame_size)
        else:
            with _scratch(run) as scratch:
                scratch.load(checkpoint_dir(out, choice.round))
                filmed = _film(
                    run, scratch.policy(deterministic=True), out / AGENT_VIDEO, frame_size
                )
    films = {}
    if round_videos:
        known = {choice.round: filmed} if filmed is not None else {}
        films = _film_rounds(run, frame_size, callback, known)
    callback.on_phase("package", 0, 1)
    summary = summarise(
        run.cfg,
        run.records,
        frozen,
        filmed,
        round_index=choice.round,
        chosen_by=choice.by,
        round_videos=films,
        normalisation=normalisation(run.ppo),
    )
    write_agent_zip(out / AGENT_ZIP, checkpoint_dir(out, choice.round), summary, out)
    write_summary(out, summary)
    return summary


def choose_takeaway(
    run: Run,
    teacher: Teacher,
    cfg: TakeawayConfig,
    callback: RunCallback | None = None,
) -> TakeawayChoice:
    """The round whose greedy policy `teacher` prefers among the run's rounds with a
    checkpoint (`takeaway.choose_round`), written to ``takeaway.json``; the last round
    without asking when `cfg.by` is "last" or only one round has a checkpoint. Each
    round's `cfg.episodes` episodes start from the same reset seeds; the episodes and the
    teacher draw from streams of their own (`streams.takeaway_streams`)."""
    out, callback = run.directory, as_callback(callback)
    rounds = [
        r.round for r in run.records if (checkpoint_dir(out, r.round) / POLICY_FILE).is_file()
    ]
    if cfg.by == "last" or len(rounds) < 2:
        choice = last_round(rounds or [run.next_round - 1])
    else:
        episodes_seed, teacher_rng = takeaway_streams(run.cfg.loop.seed)
        episodes = round_episodes(run, rounds, cfg.episodes, episodes_seed, callback)
        choice = choose_round(episodes, teacher, teacher_rng)
    write_choice(out, choice, cfg)
    return choice


def round_episodes(
    run: Run,
    rounds: Sequence[int],
    n_episodes: int,
    seed: np.random.SeedSequence,
    callback: RunCallback | None = None,
    phase: str = "takeaway",
) -> dict[int, list[Trajectory]]:
    """`n_episodes` greedy episodes of each round's checkpointed policy, every round's from
    the same reset seeds (a generator from `seed` each). `callback` hears `phase`."""
    callback = as_callback(callback)
    episodes = {}
    with _scratch(run) as scratch:
        for done, r in enumerate(rounds):
            callback.on_phase(phase, done, len(rounds))
            scratch.load(checkpoint_dir(run.directory, r))
            episodes[r] = sample_trajectories(
                run.make_env,
                scratch.policy(deterministic=True),
                n_episodes,
                np.random.default_rng(seed),
            )
        callback.on_phase(phase, len(rounds), len(rounds))
    return episodes


@contextmanager
def _scratch(run: Run) -> Iterator[PPOAgent]:
    """A PPO agent of the run's settings (one env, no logs) to load checkpoints into."""
    scratch = PPOAgent(
        run.make_env,
        dataclasses.replace(run.cfg.ppo, n_envs=1, tensorboard=False),
        seed=run.cfg.loop.seed,
    )
    try:
        yield scratch
    finally:
        scratch.close()


def _film(run: Run, policy: Policy, path: Path, frame_size: int) -> VideoSummary:
    """One greedy episode of `policy` (the evaluation's first reset seed) as a video."""
    loop = run.cfg.loop
    episode = sample_trajectories(run.make_env, policy, 1, eval_rng(loop.seed))[0]
    video = write_episode_video(FrameSettings(loop.env, frame_size, frame_size), episode, path)
    return VideoSummary(
        file=path.relative_to(run.directory).as_posix(),
        seconds=round(video.seconds, 6),
        fps=round(video.fps, 6),
        frames=video.frames,
        width=video.width,
        height=video.height,
        episode_return=float(episode.true_rewards.sum()),
        target_score=None if math.isnan(episode.episode_score) else episode.episode_score,
    )


def _film_rounds(
    run: Run, frame_size: int, callback: RunCallback, known: dict[int, VideoSummary]
) -> dict[int, VideoSummary]:
    """Each checkpointed round's greedy policy filmed (``agent-rounds/round-NNNN.mp4``);
    `known`: rounds filmed already (their video is copied, not filmed again)."""
    out = run.directory
    rounds = [
        r.round for r in run.records if (checkpoint_dir(out, r.round) / POLICY_FILE).is_file()
    ]
    films = {}
    with _scratch(run) as scratch:
        for done, r in enumerate(rounds):
            callback.on_phase("video", done, len(rounds))
            path = round_video_path(out, r)
            path.parent.mkdir(exist_ok=True)
            if r in known:
                shutil.copyfile(out / known[r].file, path)
                films[r] = dataclasses.replace(known[r], file=path.relative_to(out).as_posix())
                continue
            scratch.load(checkpoint_dir(out, r))
            films[r] = _film(run, scratch.policy(deterministic=True), path, frame_size)
    return films


def continue_run(
    out: Path,
    *,
    steps: int | None = None,
    rounds: int | None = None,
    decision_maker: str | None = None,
    comparisons: int | None = None,
    frame_size: int | None = None,
    show_progress: bool = True,
) -> list[RoundRecord]:
    """Continue the run (an app session's directory, or a `groupwise train` output) in
    `out` from its latest checkpoint, headless: `steps` more PPO steps on the frozen learned
    reward, or `rounds` more feedback rounds answered by the simulated `decision_maker`
    (`comparisons` per round, default the run's own, or for an app session without a limit
    per round as many as fill its pool; the run's PPO steps per round) followed by its
    `final_steps` on the frozen reward. Writes checkpoints, ``rounds.csv``,
    TensorBoard logs, ``agent.mp4``, ``agent.zip`` and ``agent.json`` into `out`, as the
    app does; ``config.json`` stays as it was.

    Raises:
        FileNotFoundError: `out` has no ``config.json`` or no checkpoint.
        ValueError: not exactly one of `steps` and `rounds`, or `rounds` without a known
            `decision_maker`.
    """
    if (steps is None) == (rounds is None):
        raise ValueError("give either steps or rounds")
    if rounds is not None and decision_maker not in DECISION_MAKERS:
        raise ValueError(
            f"more rounds need a simulated decision-maker to answer them (--dm); "
            f"choose from {', '.join(DECISION_MAKERS)}"
        )
    cfg = RunConfig.load(out / CONFIG_FILE)
    found = latest_checkpoint(out)
    if found is None:
        raise FileNotFoundError(f"{out} has no checkpoint to continue from")
    previous = read_summary(out)
    frozen = _frozen_rounds(cfg, previous, len(found[1]["records"]))
    size = frame_size or (previous.video.width if previous and previous.video else None)
    with Run.create(cfg, out) as run:
        run.restore()
        more = 1 if steps is not None else (rounds or 0) + int(cfg.loop.final_steps > 0)
        bars = ProgressBars(more, desc=cfg.loop.env) if show_progress else None
        callback = CallbackList([_LogReturn(), *([bars] if bars else [])])
        try:
            if steps is not None:
                frozen.add(run.next_round)
                train_frozen(run, steps, callback=callback)
            else:
                assert rounds is not None and decision_maker is not None
                feedback = DECISION_MAKERS[decision_maker](cfg)
                per_round = comparisons or _comparisons_per_round(cfg, out)
                for _ in range(rounds):
                    run_round(run, feedback, per_round, cfg.loop.steps // cfg.loop.rounds, callback)
                if cfg.loop.final_steps > 0:
                    frozen.add(run.next_round)
                    train_frozen(run, cfg.loop.final_steps, callback=callback)
        finally:
            if bars is not None:
                bars.close()
        publish_agent(run, frozen, frame_size=size or DEFAULT_FRAME_SIZE[0])
        return run.records


class _LogReturn(RunCallback):
    def on_round_end(self, record: RoundRecord) -> None:
        log.info("round %d: true return %.2f", record.round, record.true_return_mean)


def _comparisons_per_round(cfg: RunConfig, out: Path) -> int:
    """The run's comparisons per round; for an app session without a limit per round
    (``settings.json``: comparisons_per_round 0) as many as fill its pool."""
    settings = out / SETTINGS_FILE
    if settings.is_file() and json.loads(settings.read_text()).get("comparisons_per_round") == 0:
        return max(1, math.floor(cfg.loop.pool_cap / cfg.loop.pool_factor))
    return max(1, math.ceil(cfg.loop.comparisons / cfg.loop.rounds))


def _frozen_rounds(cfg: RunConfig, previous: AgentSummary | None, records: int) -> set[int]:
    """Rounds without feedback so far: as the previous summary says, else the run's final
    round when it had one (`loop.round_plan`)."""
    if previous is not None:
        return {r.round for r in previous.rounds if not r.feedback}
    final = cfg.loop.rounds
    return {final} if cfg.loop.final_steps > 0 and records > final else set()
