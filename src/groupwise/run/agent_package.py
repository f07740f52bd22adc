"""A run's take-away agent packed: the summary of its rounds (`summarise`) and another
round's policy handed over instead (`pick_round`). What the files hold is
`groupwise.agent_file`'s; this module knows the run's directory (its checkpoints and
records) and imports no RL, so the app's server can repack an agent.
"""

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from groupwise.agent_file.archive import write_agent_zip
from groupwise.agent_file.summary import (
    AGENT_ZIP,
    FORMAT,
    SUMMARY_FILE,
    ZIP_NORMALISER,
    ZIP_POLICY,
    ZIP_REWARD,
    AgentSummary,
    ObsNormalisation,
    RoundSummary,
    TargetSummary,
    VideoSummary,
    measure_of,
    read_summary,
    target_of,
    write_summary,
)
from groupwise.config import RunConfig
from groupwise.run.checkpoint import checkpoint_dir


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def summarise(
    cfg: RunConfig,
    records: Sequence[Any],
    frozen: set[int],
    video: VideoSummary | None,
    *,
    round_index: int | None = None,
    chosen_by: str = "last",
    round_videos: Mapping[int, VideoSummary] | None = None,
    normalisation: ObsNormalisation,
) -> AgentSummary:
    """The summary of a run whose rounds are `records` (`loop.RoundRecord`s) handing over
    round `round_index`'s policy (default: the last round's); `frozen` holds the indices of
    rounds without feedback, `round_videos` each round's clip, `normalisation` how the
    policy's observations were normalised (`groupwise.rl.agent_file.normalisation`).

    Raises:
        KeyError: no record of `round_index`.
    """
    by_round = {int(r.round): r for r in records}
    last = records[-1] if round_index is None else by_round[round_index]
    target = target_of(cfg.loop.env)
    films = round_videos or {}
    return AgentSummary(
        format=FORMAT,
        env=cfg.loop.env,
        round=int(last.round),
        chosen_by=chosen_by,
        env_steps=int(last.env_steps),
        measure=measure_of(cfg.loop.env),
        true_return_mean=_finite(last.true_return_mean),
        true_return_std=_finite(last.true_return_std),
        target=None if target is None else TargetSummary.of(target),
        target_score_mean=_finite(last.target_score_mean),
        target_score_std=_finite(last.target_score_std),
        normalize_obs=normalisation.normalize_obs,
        clip_obs=normalisation.clip_obs,
        epsilon=normalisation.epsilon,
        rounds=tuple(
            RoundSummary(
                round=int(r.round),
                feedback=int(r.round) not in frozen,
                judgements=int(r.judgements),
                pairs_total=int(r.pairs_total),
                env_steps=int(r.env_steps),
                true_return_mean=_finite(r.true_return_mean),
                true_return_std=_finite(r.true_return_std),
                target_score_mean=_finite(r.target_score_mean),
                target_score_std=_finite(r.target_score_std),
                video=films.get(int(r.round)),
            )
            for r in records
        ),
        video=video,
    )


class UnknownRoundError(LookupError):
    """The run has no round of that index."""


class NoCheckpointError(LookupError):
    """The round's checkpoint is not (or no longer) in the run's directory."""


def pick_round(directory: Path, round_index: int, chosen_by: str = "person") -> AgentSummary:
    """Hand over round `round_index`'s policy instead: ``agent.zip`` repacked from that
    round's checkpoint and ``agent.json`` rewritten (its round, steps and scores; `chosen_by`;
    the video is the round's clip when it was filmed). The rounds' records are the
    summary's, so nothing is evaluated again.

    Raises:
        FileNotFoundError: the run has no summary (no agent published).
        UnknownRoundError: the summary has no round `round_index`.
        NoCheckpointError: its checkpoint is missing (the reason in the message).
    """
    summary = read_summary(directory)
    if summary is None:
        raise FileNotFoundError(f"{directory} has no {SUMMARY_FILE}")
    rounds = {r.round: r for r in summary.rounds}
    if round_index not in rounds:
        raise UnknownRoundError(
            f"no round {round_index}: the run has rounds {min(rounds)} to {max(rounds)}"
        )
    checkpoint = checkpoint_dir(directory, round_index)
    missing = [
        n for n in (ZIP_POLICY, ZIP_NORMALISER, ZIP_REWARD) if not (checkpoint / n).is_file()
    ]
    if missing:
        raise NoCheckpointError(
            f"round {round_index}'s checkpoint has no {', '.join(missing)} (it was not kept, "
            "or the session was imported without its checkpoints): its policy cannot be "
            "packaged"
        )
    chosen = rounds[round_index]
    video = chosen.video or (summary.video if summary.round == round_index else None)
    picked = replace(
        summary,
        round=round_index,
        chosen_by=chosen_by,
        env_steps=chosen.env_steps,
        true_return_mean=chosen.true_return_mean,
        true_return_std=chosen.true_return_std,
        target_score_mean=chosen.target_score_mean,
        target_score_std=chosen.target_score_std,
        video=video,
    )
    write_agent_zip(directory / AGENT_ZIP, checkpoint, picked, directory)
    write_summary(directory, picked)
    return picked
