"""The study's figures: prepared arrays in, one PNG out per function.

Uses Matplotlib's object-oriented API on the Agg canvas (no pyplot, no display, no global
backend switch), so it works headless and from any thread.
"""

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from groupwise.study.simulation.statistics import Interval
from groupwise.types import FloatArray

DPI = 120


@dataclass(frozen=True)
class Band:
    """A mean curve and its confidence band, all of shape (points,)."""

    steps: FloatArray
    mean: FloatArray
    low: FloatArray
    high: FloatArray


def training_curves(
    panels: Mapping[str, Mapping[str, Band]], dms: Sequence[str], path: Path
) -> Path:
    """True return vs env steps, one panel per env, one line and shaded band per DM.

    Args:
        panels: ``{env: {dm: band}}``, drawn in the mapping's order.
        dms: every DM, in the order that fixes their colours.
    """
    envs = list(panels)
    cols = min(3, max(1, len(envs)))
    rows = math.ceil(len(envs) / cols) if envs else 1
    figure = _figure(4.2 * cols, 3.2 * rows)
    colours = _colours(dms)
    for index, env in enumerate(envs):
        axes = figure.add_subplot(rows, cols, index + 1)
        for dm, band in panels[env].items():
            axes.plot(band.steps, band.mean, marker="o", ms=3, color=colours[dm], label=dm)
            axes.fill_between(band.steps, band.low, band.high, color=colours[dm], alpha=0.2)
        axes.set_title(env)
        axes.set_xlabel("env steps")
        axes.set_ylabel("true return")
        axes.grid(alpha=0.3)
        axes.legend(fontsize="small")
    return _save(figure, path)


def pairs_and_errors(
    envs: Sequence[str],
    pairs: Mapping[str, FloatArray],
    errors: Mapping[str, FloatArray],
    path: Path,
) -> Path:
    """Grouped bars: mean preference pairs (left) and label error rate (right) per env, DM.

    Args:
        pairs, errors: ``{dm: array[envs]}`` of means over seeds (NaN: no finished run).
    """
    figure = _figure(max(6.0, 1.6 * len(envs) + 2.0) * 2, 3.6)
    colours = _colours(list(pairs))
    width = 0.8 / max(1, len(pairs))
    x = np.arange(len(envs))
    for index, (title, data) in enumerate(
        (("preference pairs", pairs), ("label error rate", errors))
    ):
        axes = figure.add_subplot(1, 2, index + 1)
        for k, (dm, values) in enumerate(data.items()):
            axes.bar(x + k * width, np.nan_to_num(values), width, color=colours[dm], label=dm)
        axes.set_xticks(x + width * (len(data) - 1) / 2, list(envs), rotation=20, fontsize="small")
        axes.set_title(title)
        axes.grid(axis="y", alpha=0.3)
        axes.legend(fontsize="small")
    return _save(figure, path)


def normalised_returns(
    pooled: Mapping[str, FloatArray],
    iqms: Mapping[str, tuple[float, Interval]],
    title: str,
    path: Path,
) -> Path:
    """Box plots of the normalised final returns (left) and IQM with 95 % CI (right) per DM.

    Args:
        pooled: ``{dm: array[values]}``, one value per finished (env, seed).
        iqms: ``{dm: (iqm, interval)}``.
    """
    dms = list(pooled)
    figure = _figure(10.0, 3.6)
    figure.suptitle(title)
    colours = _colours(dms)
    boxes = figure.add_subplot(1, 2, 1)
    data = [np.asarray(pooled[dm])[np.isfinite(pooled[dm])] for dm in dms]
    if any(d.size for d in data):
        plot = boxes.boxplot(data, patch_artist=True, medianprops={"color": "black"})
        boxes.set_xticks(range(1, len(dms) + 1), dms, fontsize="small")
        if len(dms) > 4:  # more DM names than that side by side overlap: slant them
            boxes.tick_params(axis="x", labelrotation=25)
            for label in boxes.get_xticklabels():
                label.set_horizontalalignment("right")
        for patch, dm in zip(plot["boxes"], dms, strict=True):
            patch.set_facecolor(colours[dm])
            patch.set_alpha(0.6)
    boxes.set_ylabel("normalised final return")
    boxes.grid(axis="y", alpha=0.3)
    bars = figure.add_subplot(1, 2, 2)
    for k, dm in enumerate(dms):
        centre, interval = iqms[dm]
        bars.errorbar(
            [centre],
            [k],
            xerr=[[centre - interval.low], [interval.high - centre]],
            fmt="o",
            color=colours[dm],
            capsize=4,
        )
    bars.set_yticks(range(len(dms)), dms)
    bars.set_ylim(-0.5, len(dms) - 0.5)
    bars.set_xlabel("IQM of normalised final return (95 % CI)")
    bars.grid(axis="x", alpha=0.3)
    return _save(figure, path)


def _figure(width: float, height: float) -> Figure:
    figure = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def _colours(dms: Sequence[str]) -> dict[str, tuple[float, ...]]:
    from matplotlib import colormaps

    palette = colormaps["tab10"]
    return {dm: tuple(palette(i % 10)) for i, dm in enumerate(dms)}


def _save(figure: Figure, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=DPI)
    return path
