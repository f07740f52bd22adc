"""Aliases shared by every module: arrays (shapes are documented where arrays are declared)
and the progress function long steps report through."""

from collections.abc import Callable
from typing import TypeAlias

import numpy as np
import numpy.typing as npt

FloatArray: TypeAlias = npt.NDArray[np.floating]
IntArray: TypeAlias = npt.NDArray[np.integer]

ProgressFn: TypeAlias = Callable[[int, int], None]
"""(done, total) -> None, in the step's own unit (PPO steps, clips, DTW pairs): what a long
step reports to a run's `RunCallback.on_phase` (`groupwise.run.progress`)."""
