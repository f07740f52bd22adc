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

import json
import logging
import math
from pathlib import Path

from groupwise.clips.episode_video import write_episode_video
from groupwise.clips.replay import FrameSettings
from groupwise.config import RunConfig
from groupwise.envs import DEFAULT_FRAME_SIZE
from groupwise.oracles import ORACLES
from groupwise.rl.rollout import sample_trajectories
from groupwise.run.agent_package import (
    AGENT_VIDEO,
    AGENT_ZIP,
    SETTINGS_FILE,
    SUMMARY_FILE,
    AgentSummary,
    VideoSummary,
    read_summary,
    summarise,
    write_agent_zip,
)
from groupwise.run.checkpoint import checkpoint_dir, latest_checkpoint
from groupwise.run.progress import CallbackList, ProgressBars, RunCallback, as_callback
from groupwise.run.records import RoundRecord
from groupwise.run.round import run_round, train_frozen
from groupwise.run.run import CONFIG_FILE, Run
from groupwise.run.streams import eval_rng

log = logging.getLogger(__name__)


def publish_agent(
    run: Run,
    frozen: set[int],
    *,
    frame_size: int = DEFAULT_FRAME_SIZE[0],
    callback: RunCallback | None = None,
) -> AgentSummary:
    """Film the run's greedy policy for one episode (``agent.mp4`` in the run's directory)
    and pack its latest checkpoint (`Run.commit`) into ``agent.zip``, with the summary
    ``agent.json`` written last. `frozen`: the rounds without feedback."""
    loop, out, callback = run.cfg.loop, run.directory, as_callback(callback)
    callback.on_phase("video", 0, 1)
    episode = sample_trajectories(
        run.make_env, run.agent.policy(deterministic=True), 1, eval_rng(loop.seed)
    )[0]
    video = write_episode_video(
        FrameSettings(loop.env, frame_size, frame_size), episode, out / AGENT_VIDEO
    )
    callback.on_phase("package", 0, 1)
    summary = summarise(
        run.cfg,
        run.records,
        frozen,
        VideoSummary(
            file=AGENT_VIDEO,
            seconds=round(video.seconds, 6),
            fps=round(video.fps, 6),
            frames=video.frames,
            width=video.width,
            height=video.height,
            episode_return=float(episode.true_rewards.sum()),
            target_score=None if math.isnan(episode.episode_score) else episode.episode_score,
        ),
    )
    round_index = run.next_round - 1
    write_agent_zip(out / AGENT_ZIP, checkpoint_dir(out, round_index), summary, out)
    partial = out / f".{SUMMARY_FILE}.partial"
    partial.write_text(summary.to_json() + "\n")
    partial.replace(out / SUMMARY_FILE)
    return summary


def continue_run(
    out: Path,
    *,
    steps: int | None = None,
    rounds: int | None = None,
    oracle: str | None = None,
    comparisons: int | None = None,
    frame_size: int | None = None,
    show_progress: bool = True,
) -> list[RoundRecord]:
    """Continue the run (an app session's directory, or a `groupwise train` output) in
    `out` from its latest checkpoint, headless: `steps` more PPO steps on the frozen learned
    reward, or `rounds` more feedback rounds answered by the simulated decision-maker
    `oracle` (`comparisons` per round, default the run's own, or for an app session without
    a limit per round as many as fill its pool; the run's PPO steps per round)
    followed by its `final_steps` on the frozen reward. Writes checkpoints, ``rounds.csv``,
    TensorBoard logs, ``agent.mp4``, ``agent.zip`` and ``agent.json`` into `out`, as the
    app does; ``config.json`` stays as it was.

    Raises:
        FileNotFoundError: `out` has no ``config.json`` or no checkpoint.
        ValueError: not exactly one of `steps` and `rounds`, or `rounds` without a known
            `oracle`.
    """
    if (steps is None) == (rounds is None):
        raise ValueError("give either steps or rounds")
    if rounds is not None and oracle not in ORACLES:
        raise ValueError(
            f"more rounds need a simulated decision-maker to answer them (--dm); "
            f"choose from {', '.join(ORACLES)}"
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
                assert rounds is not None and oracle is not None
                feedback = ORACLES[oracle](cfg)
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
