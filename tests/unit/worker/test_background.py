"""The worker's background process (the curve's evaluator): a process that died is started
again by the next submission, so continuous training keeps its curve after, say, the kernel
killed one for memory."""

import os
import signal
from concurrent.futures.process import BrokenProcessPool

from groupwise.worker.background import NICENESS, BackgroundProcess


def _pid_and_niceness() -> tuple[int, int]:
    return os.getpid(), os.nice(0)


def test_a_background_process_that_died_is_started_again(tmp_path):
    process = BackgroundProcess(f"sqlite:///{tmp_path / 'groupwise.db'}")
    try:
        first, niceness = process.submit(_pid_and_niceness).result(timeout=120)
        assert first != os.getpid() and niceness == min(19, os.nice(0) + NICENESS)
        os.kill(first, signal.SIGKILL)
        answers: list[int] = []
        for _ in range(50):  # the pool notices the death on its own thread, soon
            try:
                answers.append(process.submit(_pid_and_niceness).result(timeout=120)[0])
                break
            except BrokenProcessPool:
                continue
        assert answers and answers[0] not in (first, os.getpid())
    finally:
        process.close()
