"""The scorers' helpers match the NumPy expressions they replace, bit for bit (issue 22)."""

import math
import struct

import numpy as np

from groupwise.envs.scorers import TOPPLE, UPRIGHT, ramp


def _bits(value: float) -> bytes:
    return struct.pack("<d", value)


def test_ramp_is_numpys_clip_bit_for_bit() -> None:
    rng = np.random.default_rng(0)
    edges = [0.0, -0.0, 1.0, -1.0, 0.5, math.inf, -math.inf, math.nan, 5e-324, -5e-324]
    xs = [*edges, *rng.normal(0.0, 2.0, 2000).tolist(), *rng.uniform(-0.1, 1.1, 2000).tolist()]
    bounds = [(0.0, 1.0), (0.1, 0.3), TOPPLE, (UPRIGHT, math.pi / 2), (-1.0, 0.0)]
    for low, high in bounds:
        for x in xs:
            expected = float(np.clip((x - low) / (high - low), 0.0, 1.0))
            got = ramp(x, low, high)
            assert type(got) is float
            assert _bits(got) == _bits(expected) or (math.isnan(got) and math.isnan(expected))
