"""Two-parameter charts (docs/model.md section 12.6): fold, period-doubling, grazing and
branch-point curves drawn in the plane of their two parameters over a brute-force map of a
two-parameter sweep.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from functools import reduce

import numpy as np
from matplotlib.axes import Axes
from matplotlib.colors import BoundaryNorm, ListedColormap, TwoSlopeNorm
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from impactchain.figures._canvas import _one_axes, _parent, _record_sources
from impactchain.figures._data import RunLike, _as_runs, _sweep, as_run
from impactchain.figures._style import (FigureError, _label, _padded, _parameter_label, _ramp,
                                        _title)
from impactchain.figures.orbits import SPECIAL_STYLES
from impactchain.results import Curve, Run, Sweep


IMPACTS_CAP = 16
"""A chart's map of impacts per drive cycle: one colour per whole number up to this, one
above (chatter runs to tens, the orbits told apart have a few)."""
APERIODIC_COLOUR = "0.55"
"""A chart's map of periods: the points where some oscillator is aperiodic."""
CODIM2_STYLE = {"marker": "*", "s": 110, "color": "gold", "edgecolors": "k",
                "linewidths": 0.6, "zorder": 4}
"""Codimension-two points met along a curve."""
QUANTITIES = ("period", "impacts", "exponent")
"""What a chart's map can show: the period of the chain, impacts per drive cycle, or the
largest Lyapunov exponent."""
EXPONENT_CMAP = "RdBu_r"
"""A chart's map of the largest exponent: blue below zero (periodic), white at zero (a
torus, a bifurcation), red above (chaos), on a scale centred at zero."""
EXPONENT_SCALE = 95
"""The exponent map's scale reaches the percentile of |exponent| over the grid (a few
violent points, deep in the chatter, would bleach the rest)."""


def chart(curves: RunLike | Sequence[RunLike], over: RunLike | None = None,
          quantity: str = "period", ax: Axes | None = None) -> Figure:
    """Fold, period-doubling, grazing, branch-point and Neimark-Sacker curves (``/curve``) as
    lines in the plane of their two parameters, each in its kind's colour
    (:data:`orbits.SPECIAL_STYLES`), its start (the one-parameter run's special point) marked
    with the kind's marker on a dotted line at its value of the second parameter, and
    codimension-two points (those within the axes)
    as stars.

    ``curves``: one curve file (or :func:`impactchain.api.curve` tree) or several of the same
    chain and the same two parameters. ``over``: a two-parameter sweep (``&sweep`` with
    ``parameter2``, or :func:`impactchain.api.sweep`'s Dataset) of those two parameters, in
    either order, on the same chain, drawn first as an image of its grid (each cell centred
    on its point): ``quantity`` ``'period'`` the period of the chain (the least common
    multiple of its oscillators' periods; aperiodic in grey), ``'impacts'`` the impacts per
    drive cycle over its records (one colour per whole number up to :data:`IMPACTS_CAP`),
    ``'exponent'`` the largest Lyapunov exponent in bits per drive cycle (a sweep with
    ``&lyapunov``; :data:`EXPONENT_CMAP`).
    The axes are the curves' parameters, their limits the map's cells (the curves clipped
    to them), or the curves' points without a map. ``ax``: one Axes.
    """
    if quantity not in QUANTITIES:
        raise FigureError(f"quantity = {quantity!r}: one of {', '.join(QUANTITIES)}")
    runs = _as_runs(curves, ("curve",), "chart")
    found = [_curve(r) for r in runs]
    first, curve0 = runs[0], found[0]
    for other, curve in zip(runs[1:], found[1:]):
        if (curve.parameter, curve.parameter2) != (curve0.parameter, curve0.parameter2):
            raise FigureError(f"{other.path}: a curve in ({curve.parameter}, "
                              f"{curve.parameter2}), {first.path}'s is in "
                              f"({curve0.parameter}, {curve0.parameter2})")
        _check_chain(other, first)
    fig, ax = _one_axes(ax, 8.0, 5.5, "chart")
    shown = list(runs)
    if over is None:
        extent = (*_padded(np.concatenate([c.values for c in found])),
                  *_padded(np.concatenate([c.values2 for c in found])))
    else:
        map_run = as_run(over, ("sweep",), "chart --over")
        _check_chain(map_run, first)
        extent = _draw_map(ax, map_run, _sweep(map_run), curve0, quantity)
        shown.append(map_run)
    handles = _draw_curves(ax, found, extent)
    ax.set_xlim(*extent[:2])
    ax.set_ylim(*extent[2:])
    ax.legend(handles=handles, loc="best", fontsize="small", framealpha=0.9)
    ax.set_xlabel(_parameter_label(curve0.parameter))
    ax.set_ylabel(_parameter_label(curve0.parameter2))
    points = sum(c.values.size for c in found)
    ax.set_title(f"{_title(first, skip=(curve0.parameter, curve0.parameter2))}\n"
                 f"{points} points on {len(found)} curve{'s' if len(found) > 1 else ''}",
                 fontsize="medium", wrap=True)
    _record_sources(fig, shown)
    return fig


def map_grid(sweep: Sweep, parameter: str, parameter2: str,
             values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A two-parameter sweep's per-point ``values`` (P,) on its grid: the grid's values of
    ``parameter`` (n1,) and ``parameter2`` (n2,), each ascending, and ``values`` as (n2, n1),
    rows along ``parameter2`` (an image's rows, from below). The sweep may run over the two
    in either order and either direction."""
    if not sweep.is_2d or {sweep.parameter, sweep.parameter2} != {parameter, parameter2}:
        raise FigureError(f"the map is a sweep over ({sweep.parameter}, "
                          f"{sweep.parameter2 or 'nothing else'}); the curves are in "
                          f"({parameter}, {parameter2})")
    inner = int(np.count_nonzero(sweep.values[:, 1] == sweep.values[0, 1]))
    outer = sweep.values.shape[0] // inner
    first = sweep.values[:inner, 0]
    second = sweep.values[::inner, 1]
    grid = np.asarray(values).reshape(outer, inner)  # (p = i + n1 j: j the row)
    if sweep.parameter != parameter:
        first, second, grid = second, first, grid.T
    columns, rows = np.argsort(first), np.argsort(second)
    return first[columns], second[rows], grid[np.ix_(rows, columns)]


def chain_period(periods: np.ndarray) -> np.ndarray:
    """The period of the chain at each point from its oscillators' periods (P, n): their
    least common multiple, 0 where any oscillator is aperiodic (period 0)."""
    periods = np.asarray(periods, dtype=np.int64)
    lcm = reduce(np.lcm, periods.T, np.ones(periods.shape[0], dtype=np.int64))
    return np.where((periods > 0).all(axis=1), lcm, 0)


def _curve(run: Run) -> Curve:
    curve = run.curve
    if curve is None:
        raise FigureError(f"{run.path}: no /curve group (&continuation follow)")
    if curve.values.size == 0:
        raise FigureError(f"{run.path}: the curve holds no point ({curve.end_reason})")
    if curve.follow not in SPECIAL_STYLES:
        raise FigureError(f"{run.path}: a curve of {curve.follow!r} points")
    return curve


def _check_chain(run: Run, first: Run) -> None:
    """The same chain: n, and the ends, damping and restitution where both runs know them
    (a swept parameter is NaN in a file's /params; an api result's continuation knows
    neither its ends nor its parameters)."""
    p, q = run.params, first.params
    differ = [f"n ({p.n}, not {q.n})"] if p.n != q.n else []
    if p.boundary and q.boundary and p.boundary != q.boundary:
        differ.append(f"ends ({p.boundary}, not {q.boundary})")
    differ += [f"{name} ({getattr(p, name):g}, not {getattr(q, name):g})"
               for name in ("damping", "restitution")
               if not _same(getattr(p, name), getattr(q, name))]
    if differ:
        raise FigureError(f"{run.path}: another chain than {first.path}: " + ", ".join(differ))


def _same(a: float, b: float) -> bool:
    return math.isnan(a) or math.isnan(b) or a == b


def _draw_map(ax: Axes, run: Run, sweep: Sweep, curve: Curve,
              quantity: str) -> tuple[float, float, float, float]:
    """The sweep's grid as an image, cells centred on its points, with a colour bar in whole
    numbers (the largest exponent: a continuous one); the image's extent."""
    if quantity == "exponent":
        return _draw_exponent_map(ax, run, sweep, curve)
    if quantity == "impacts":
        per_point = np.minimum(np.rint(sweep.collisions_per_cycle), IMPACTS_CAP + 1)
    else:
        per_point = chain_period(sweep.period)
    first, second, grid = map_grid(sweep, curve.parameter, curve.parameter2, per_point)
    extent = (*_cell_edges(first), *_cell_edges(second))
    present = np.unique(grid).astype(np.int64)
    colours = _ramp(len(present))
    if quantity == "period":
        colours = [APERIODIC_COLOUR if p == 0 else c for p, c in zip(present, colours)]
        names = ["aperiodic" if p == 0 else str(p) for p in present]
        label = _label("period", "drive cycles")
    else:
        names = [f"> {IMPACTS_CAP}" if p > IMPACTS_CAP else str(p) for p in present]
        label = _label("impacts per drive cycle (nearest whole number)", "1")
    cmap = ListedColormap(colours, name=f"chart-{quantity}")
    image = ax.imshow(np.searchsorted(present, grid), cmap=cmap,
                      norm=BoundaryNorm(np.arange(-0.5, len(present)), cmap.N), origin="lower",
                      aspect="auto", interpolation="nearest", extent=extent, gid="map")
    bar = _parent(ax).colorbar(image, ax=ax, label=label, ticks=np.arange(len(present)))
    bar.ax.set_yticklabels(names)
    return extent


def _draw_exponent_map(ax: Axes, run: Run, sweep: Sweep,
                       curve: Curve) -> tuple[float, float, float, float]:
    """The largest exponent on the sweep's grid, on a diverging scale centred at zero; the
    image's extent."""
    if sweep.exponents is None or sweep.exponents.shape[1] == 0:
        raise FigureError(f"{run.path}: the map shows the largest exponent, and this sweep "
                          "has none (&lyapunov)")
    first, second, grid = map_grid(sweep, curve.parameter, curve.parameter2,
                                   sweep.exponents[:, 0])
    extent = (*_cell_edges(first), *_cell_edges(second))
    reach = max(float(np.nanpercentile(np.abs(grid), EXPONENT_SCALE)), 1e-12)
    image = ax.imshow(grid, cmap=EXPONENT_CMAP, norm=TwoSlopeNorm(0.0, -reach, reach),
                      origin="lower", aspect="auto", interpolation="nearest", extent=extent,
                      gid="map")
    _parent(ax).colorbar(image, ax=ax, extend="both",
                         label=_label("largest Lyapunov exponent", "bits/cycle"))
    return extent


def _cell_edges(values: np.ndarray) -> tuple[float, float]:
    """The outer edges of cells centred on an evenly spaced grid's values."""
    low, high = float(values.min()), float(values.max())
    half = (high - low) / (2 * (values.size - 1)) if values.size > 1 else 0.5
    return low - half, high + half


def _draw_curves(ax: Axes, curves: Sequence[Curve],
                 extent: tuple[float, float, float, float]) -> list[Line2D]:
    """Each curve a line in its kind's colour, its start marked on a dotted line at its
    second parameter's value; codimension-two points within ``extent`` starred. The
    legend's handles."""
    x0, x1, y0, y1 = extent
    handles: dict[str, Line2D] = {}
    for curve in curves:
        label, marker, colour = SPECIAL_STYLES[curve.follow]
        ax.axhline(curve.values2[0], color="0.3", linewidth=0.8, linestyle=":",
                   gid="start-value2")
        ax.plot(curve.values, curve.values2, color=colour, linewidth=1.8,
                gid=f"curve-{curve.follow}")
        ax.scatter(curve.values[:1], curve.values2[:1], marker=marker, s=40, color=colour,
                   edgecolors="k", linewidths=0.5, zorder=3, gid=f"start-{curve.follow}")
        handles.setdefault(curve.follow, Line2D([], [], color=colour, linewidth=1.8,
                                                marker=marker, markeredgecolor="k",
                                                markeredgewidth=0.5, label=f"{label} curve"))
        for i, kind in zip(curve.codim2_index, curve.codim2_kind):
            if not (x0 <= curve.values[i] <= x1 and y0 <= curve.values2[i] <= y1):
                continue
            ax.scatter(curve.values[i], curve.values2[i], gid=f"codim2-{kind}", **CODIM2_STYLE)
            handles.setdefault(f"codim2 {kind}", Line2D(
                [], [], linestyle="none", marker="*", markersize=10, color="gold",
                markeredgecolor="k", label=str(kind)))
    return list(handles.values())

