"""How every figure is drawn and labelled: the shared colours and styles, the axis-label
convention ``name $symbol$ [unit]``, titles, and the limits shared between panels.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib import colormaps
from matplotlib.axes import Axes
from matplotlib.colors import BoundaryNorm, ListedColormap

from impactchain import schema
from impactchain.results import FILE_UNITS, Run


WALL_STYLE = {"color": "0.25", "linewidth": 4.0, "solid_capstyle": "butt", "zorder": 0.5}
LEFT_COLOUR = "tab:blue"
RIGHT_COLOUR = "tab:red"
OVERLAY_COLOURS = ("tab:red", "tab:green", "tab:blue", "tab:orange", "tab:purple",
                   "tab:brown", "tab:pink", "tab:olive", "tab:cyan", "tab:gray")
BAND_ALPHA = 0.35


_SYMBOLS = {
    "n": ("oscillators", "n"),
    "amplitude": ("drive amplitude", "A"),
    "omega": ("drive frequency", r"\omega"),
    "damping": ("damping", "b"),
    "restitution": ("restitution", "K"),
    "spacing": ("spacing", "a"),
}
class FigureError(ValueError):
    """The data or the options cannot make the requested figure."""


def _label(name: str, unit: str, symbol: str = "") -> str:
    """``name $symbol$ [unit]``: the axis-label convention of every figure."""
    text = f"{name} ${symbol}$" if symbol else name
    return f"{text} [{unit or '1'}]"


def _parameter_label(name: str) -> str:
    words, symbol = _SYMBOLS.get(name, (name, ""))
    return _label(words, schema.parameter_label_units(name), symbol)


def _unit(run: Run, dataset: str) -> str:
    return run.unit(dataset, FILE_UNITS.get(dataset, ""))


def _cycle_label(run: Run, name: str = "cycle", symbol: str = "c") -> str:
    return _label(name, _unit(run, "strobe/cycle"), symbol)


TIME_LABEL_UNIT = "drive cycles"


def _title(run: Run, skip: str | Sequence[str] = ()) -> str:
    skipped = {skip} if isinstance(skip, str) else set(skip)
    p = run.params
    parts = [f"n = {p.n}"]
    for name, value in (("amplitude", p.amplitude), ("omega", p.omega),
                        ("damping", p.damping), ("restitution", p.restitution)):
        if name not in skipped and not math.isnan(value):  # (NaN: a group alone, no /params)
            parts.append(f"${_SYMBOLS[name][1]}$ = {value:g}")
    if p.boundary:
        parts.append(f"{p.boundary} ends")
    title = ", ".join(parts)
    if not run.complete:
        title += " (interrupted run)"
    return title


def _padded(values: np.ndarray, fraction: float = 0.05) -> tuple[float, float]:
    finite = np.asarray(values)[np.isfinite(values)]
    if finite.size == 0:
        return -1.0, 1.0
    low, high = float(finite.min()), float(finite.max())
    pad = fraction * (high - low) or 0.1 * max(1.0, abs(high))
    return low - pad, high + pad


def _same_limits(axes: Sequence[Axes], values: Sequence[np.ndarray]) -> None:
    """One y range for panels of the same quantity: that of all their values."""
    low, high = _padded(np.concatenate([np.ravel(v) for v in values]))
    for axis in axes:
        axis.set_ylim(low, high)


def _outside(ax: Axes, ylim: tuple[float, float] | None, values: Sequence[np.ndarray]) -> str:
    """Set a given y range; a title note when some values fall outside it."""
    if ylim is None:
        return ""
    low, high = (float(v) for v in ylim)
    if not low < high:
        raise FigureError(f"ylim = {ylim}: the lower limit must be below the upper one")
    ax.set_ylim(low, high)
    data = np.concatenate([np.ravel(v) for v in values])
    count = int(np.count_nonzero((data < low) | (data > high)))
    return f"\n{count} of {data.size} values outside the y range shown" if count else ""


def _x_limits(runs: Sequence[Run]) -> tuple[float, float]:
    low = min(0.0, *(float(r.params.equilibrium.min()) for r in runs))
    high = max(r.params.length for r in runs)
    pad = 0.03 * (high - low)
    return low - pad, high + pad


def _draw_walls(ax: Axes, runs: Sequence[Run]) -> None:
    positions = sorted({x for r in runs if r.params.walls for x in (0.0, r.params.length)})
    for x in positions:
        ax.axvline(x, gid="wall", **WALL_STYLE)


def _overlay_colours(count: int) -> list[str]:
    if count == 1:
        return ["k"]
    return [OVERLAY_COLOURS[i % len(OVERLAY_COLOURS)] for i in range(count)]


def _ramp(count: int) -> list[tuple[float, float, float, float]]:
    cmap = colormaps["viridis"]
    return [cmap(0.9 * j / max(1, count - 1)) for j in range(count)]


def _sweep_style(values: np.ndarray, marker: str = "") -> dict[str, Any]:
    """Lines for a monotonic sweep, dots only when the parameter goes back and forth."""
    steps = np.diff(values)
    monotonic = bool(np.all(steps > 0) or np.all(steps < 0))
    if monotonic:
        return {"marker": marker, "markersize": 2.5} if marker else {}
    return {"linestyle": "none", "marker": marker or ".", "markersize": 2.5}


def _grid(count: int, max_cols: int = 2) -> tuple[int, int]:
    cols = min(count, max_cols)
    return -(-count // cols), cols


def _index_colours(count: int) -> tuple[ListedColormap, BoundaryNorm]:
    """A discrete colour map for exponent indices 1..count, and its norm."""
    cmap = ListedColormap(_ramp(count), name="exponent-index")
    norm = BoundaryNorm(np.arange(0.5, count + 1.0), cmap.N)
    return cmap, norm


def _index_ticks(count: int) -> list[int]:
    if count <= 12:
        return list(range(1, count + 1))
    step = math.ceil(count / 8)
    ticks = list(range(1, count + 1, step))
    if ticks[-1] != count:
        ticks.append(count)
    return ticks
