"""`JobProgress`: a round's phases as the page's bar and message."""

from groupwise.worker.progress import JobProgress


class _Reports:
    def __init__(self) -> None:
        self.reports: list[tuple[str, float, str, bool]] = []

    def report(self, phase: str, fraction: float, message: str, *, force: bool = False) -> None:
        self.reports.append((phase, fraction, message, force))


def _progress() -> tuple[JobProgress, _Reports]:
    recorded = _Reports()
    return JobProgress(recorded), recorded  # type: ignore[arg-type]  # a reporter that records


def test_ppo_says_it_counts_whole_rollouts():
    """1 step asked runs a whole rollout: the count is what runs (issue 23: "PPO 1 / 1")."""
    progress, recorded = _progress()
    progress.on_phase("ppo", 0, 2048)
    progress.on_phase("ppo", 2048, 2048)
    messages = [message for _, _, message, _ in recorded.reports]
    assert messages == [
        "PPO 0 / 2,048 steps (the steps asked, rounded up to whole rollouts)",
        "PPO 2,048 / 2,048 steps (the steps asked, rounded up to whole rollouts)",
    ]


def test_the_pool_phases_fill_the_bar_in_order_and_report_when_due():
    progress, recorded = _progress()
    progress.on_phase("load", 0, 1)
    for phase, total in (("sample", 400), ("dtw", 120), ("clips", 16)):
        for done in range(0, total + 1, total // 4):
            progress.on_phase(phase, done, total)
    progress.on_phase("suggestions", 0, 1)
    fractions = [fraction for _, fraction, _, _ in recorded.reports]
    assert fractions == sorted(fractions) and 0 < fractions[0] and fractions[-1] < 1
    for phase in ("sample", "dtw", "clips"):  # each moves the bar, 5 reports, 5 places
        assert len({f for p, f, _, _ in recorded.reports if p == phase}) == 5, phase
    # the frequent ones are written when due, not each forced to the database
    forced = {phase for phase, _, _, force in recorded.reports if force}
    assert forced == {"load", "suggestions"}
