"""Figures of covariant Lyapunov vectors (docs/model.md section 14): where a vector lives along
the chain over time, its participation ratio, and the angles between the unstable and the
other vectors.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from impactchain.figures._canvas import (_axes_list, _new_figure, _one_axes, _parent,
                                         _record_sources, _root)
from impactchain.figures._data import RunLike, as_run
from impactchain.figures._style import (TIME_LABEL_UNIT, WALL_STYLE, FigureError, _label, _title,
                                        _unit, _x_limits)
from impactchain.results import Clv, Run


CLV_CMAP = "Blues"
"""Colour map of a covariant vector's weight along the chain (0: white)."""
IMPACT_COLOUR = "tab:red"
"""Collisions drawn over the weight of a covariant vector."""
NEAR_TANGENCY = 0.1
"""rad: a smallest angle below this counts as a near-tangency in :func:`clv_angles`."""


def clv_space_time(
    run: RunLike,
    vector: int | Sequence[int] = 1,
    cycles: int | None = None,
    start: int | None = None,
    ax: Axes | Sequence[Axes] | None = None,
) -> Figure:
    """Where a covariant Lyapunov vector lives along the chain, record by record: its
    per-oscillator weight (``/clv/site_weight``, docs/model.md section 14.4) as colour, the
    oscillator's equilibrium position on x and time (drive cycles) on y, with the collisions
    of ``/events`` (when the run recorded them) as dots: the counterpart of :func:`shock_wave`.

    ``vector``: the 1-based index of a stored vector (one of the first ``clv_store``), or a
    sequence of them, one panel each, side by side with one time axis and one colour scale.
    Each oscillator's cell spans from the middle of the bond on its left to the middle of
    the bond on its right (the first and the last reach the walls), so that a collision on
    bond k (between oscillators k and k + 1, 0 and n + 1 the walls) is drawn on the edge
    between the two cells it couples (a wall hit on the wall), at its time t/T; the record
    of cycle c sits at t/T = c + phase/(2 pi), as in the other space-time figures.
    ``start``: the first cycle shown (default: the first record with vectors); ``cycles``:
    how many records from there (default: all; a few hundred at most keep the collisions
    apart). ``ax``: one Axes per vector.
    """
    run = as_run(run, ("clv/site_weight",), "clv-space-time")
    clv = _clv(run)
    if clv.site_weight is None or clv.stored == 0:
        raise FigureError(f"{run.path}: no /clv/site_weight (the run stored no site weights: "
                          "&lyapunov clv_store = 0)")
    chosen = [vector] if isinstance(vector, (int, np.integer)) else list(vector)
    if not chosen:
        raise FigureError("clv-space-time needs at least one vector")
    for v in chosen:
        if not 1 <= v <= clv.stored:
            raise FigureError(f"vector {v} is outside 1..{clv.stored}, the vectors whose "
                              "site weights the run stored (clv_store)")
    rows = _record_window(clv.cycle, start, cycles)
    cycle = clv.cycle[rows]
    params = run.params
    offset = params.section_offset
    edges_x = _cell_edges(run)
    edges_t = np.concatenate((cycle - 0.5, [cycle[-1] + 0.5])) + offset
    window = (float(edges_t[0]), float(edges_t[-1]))
    owned = ax is None
    if ax is None:
        fig: Figure = _new_figure(3.6 * len(chosen) + 1.4, 6.4)
        axes = list(np.ravel(fig.subplots(1, len(chosen), sharey=True, squeeze=False)))
    else:
        axes = _axes_list(ax, len(chosen), "clv-space-time")
        fig = _root(axes[0])
    weights = clv.site_weight[rows]
    top = float(np.max(weights[:, [v - 1 for v in chosen], :]))
    impacts = _collision_points(run, window)
    mesh = None
    for index, (axis, v) in enumerate(zip(axes, chosen)):
        mesh = axis.pcolormesh(edges_x, edges_t, weights[:, v - 1, :], cmap=CLV_CMAP,
                               vmin=0.0, vmax=top, rasterized=True, gid=f"weight-{v}")
        if impacts is not None:
            axis.scatter(impacts[:, 0], impacts[:, 1], s=2.0, color=IMPACT_COLOUR,
                         linewidths=0, gid="collisions")
        if params.walls:
            for x in (0.0, params.length):
                axis.axvline(x, gid="wall", **WALL_STYLE)
        axis.set_xlim(*_x_limits([run]))
        axis.set_ylim(*window)
        axis.set_xlabel(_label("equilibrium position", _unit(run, "params/spacing")),
                        fontsize="small")
        if index == 0 or not owned:
            axis.set_ylabel(_label("time", TIME_LABEL_UNIT, "t"), fontsize="small")
        mean_ipr = float(np.mean(clv.ipr[rows, v - 1]))
        axis.set_title(f"vector {v}: $\\lambda_{{{v}}}$ = {clv.exponents[v - 1]:.3f} "
                       f"$\\pm$ {clv.stderr[v - 1]:.3f}\nmean IPR over these records "
                       f"{mean_ipr:.3f}",
                       fontsize="small")
        axis.tick_params(labelsize="x-small")
    assert mesh is not None
    bar = _parent(axes[-1]).colorbar(mesh, ax=axes, shrink=0.9,
                                     label=_label("weight of the oscillator", "1", "w_i"))
    bar.ax.set_gid("colorbar-weight")
    if owned:
        dots = ("; dots: collisions" if impacts is not None
                else "; no events recorded (&run record_events)")
        fig.suptitle(f"{_title(run)}\ncovariant vectors at cycles {cycle[0]}-{cycle[-1]}"
                     f"{dots}", fontsize="medium")
    _record_sources(fig, [run])
    return fig


def clv_ipr(run: RunLike, ax: Axes | Sequence[Axes] | None = None) -> Figure:
    """How many oscillators each covariant vector is spread over: the inverse participation
    ratio ``/clv/ipr`` averaged over the records (1/n: spread evenly, 1: one oscillator),
    with the band between its quartiles over the records, against the vector index; below,
    the vectors' own growth rates ``/clv/exponents`` with error bars of ``/clv/stderr``, the
    unstable ones (the first ``unstable``) filled. ``ax``: one Axes (the IPR alone) or two
    (IPR, exponents).
    """
    run = as_run(run, ("clv",), "clv-ipr")
    clv = _clv(run)
    owned = ax is None
    if ax is None:
        fig: Figure = _new_figure(7.0, 6.4)
        axes = list(fig.subplots(2, 1, sharex=True))
    else:
        count = 1 if isinstance(ax, Axes) else len(np.ravel(np.asarray(ax, dtype=object)))
        axes = _axes_list(ax, 2 if count == 2 else 1, "clv-ipr")
        fig = _root(axes[0])
    index = np.arange(1, clv.k + 1)
    mean = clv.ipr.mean(axis=0)
    low, high = np.percentile(clv.ipr, [25.0, 75.0], axis=0)
    upper = axes[0]
    upper.fill_between(index, low, high, color="0.8", linewidth=0, gid="ipr-quartiles")
    upper.plot(index, mean, color="k", marker="o", markersize=3, linewidth=0.8,
               gid="ipr-mean")
    n = run.params.n
    upper.axhline(1.0 / n, color="0.3", linewidth=0.8, linestyle="--", gid="ipr-even")
    upper.text(1.0, 1.0 / n, " 1/n", transform=upper.get_yaxis_transform(), ha="left",
               va="center", fontsize="x-small", color="0.3")
    upper.set_ylim(0.0, min(1.0, 1.08 * float(max(high.max(), mean.max()))))
    upper.set_ylabel(_label("inverse participation ratio", _unit(run, "clv/ipr"),
                            r"\mathrm{IPR}"))
    upper.set_title(f"mean over {clv.n_record} records (cycles {clv.cycle[0]}-"
                    f"{clv.cycle[-1]}); band: quartiles over the records", fontsize="small")
    if len(axes) == 2:
        lower = axes[1]
        unit = _unit(run, "clv/exponents")
        unstable = index <= clv.unstable
        for mask, face, gid in ((unstable, "k", "exponents-unstable"),
                                (~unstable, "white", "exponents-stable")):
            if mask.any():
                lower.errorbar(index[mask], clv.exponents[mask], yerr=clv.stderr[mask],
                               fmt="o", markersize=3.5, capsize=2, color="k",
                               markerfacecolor=face, gid=gid)
        lower.axhline(0.0, color="0.3", linewidth=0.8, linestyle="--", gid="zero")
        lower.set_ylabel(_label("growth rate", unit, r"\lambda_j"))
        lower.set_title(f"the vectors' growth rates, bars: $\\pm$1 standard error; filled: "
                        f"the {clv.unstable} unstable", fontsize="small")
        lower.set_xlabel(_label("covariant vector index", "1", "j"))
        if owned:
            upper.tick_params(labelbottom=False)
    else:
        upper.set_xlabel(_label("covariant vector index", "1", "j"))
    if owned:
        fig.suptitle(_title(run), fontsize="medium")
    _record_sources(fig, [run])
    return fig


def clv_angles(run: RunLike, bins: int = 40, near: float = NEAR_TANGENCY,
               ax: Axes | None = None) -> Figure:
    """Histogram of ``/clv/min_angle``, the smallest angle between the unstable subspace
    (the first ``unstable`` vectors) and any other covariant vector, record by record
    (docs/model.md section 14.4), in ``bins`` logarithmically spaced bins from the smallest
    angle found to pi/2: a monitor of hyperbolicity (a distribution reaching down to zero
    means near-tangencies). The title gives the fraction of records below ``near`` rad,
    marked by a dashed line. Records without such a pair (NaN) are counted, not drawn.
    ``ax``: one Axes.
    """
    run = as_run(run, ("clv",), "clv-angles")
    clv = _clv(run)
    if bins < 1:
        raise FigureError(f"bins = {bins} must be >= 1")
    if not near > 0:
        raise FigureError(f"near = {near} must be > 0")
    angle = clv.min_angle[np.isfinite(clv.min_angle)]
    if angle.size == 0:
        raise FigureError(f"{run.path}: /clv/min_angle holds no angle (the run has "
                          f"{clv.unstable} unstable of {clv.k} vectors: no unstable-stable "
                          "pair)")
    positive = angle[angle > 0]
    smallest = float(positive.min()) if positive.size else near
    edges = np.geomspace(min(smallest, near) / 1.05, math.pi / 2, bins + 1)
    fig, ax = _one_axes(ax, 6.4, 4.6, "clv-angles")
    counts, _, _ = ax.hist(np.clip(angle, edges[0], None), bins=edges, color="0.45",
                           edgecolor="k", linewidth=0.4, gid="min-angle")
    ax.set_xscale("log")
    ax.set_xlim(edges[0], edges[-1])
    ax.axvline(near, color="tab:red", linewidth=1.0, linestyle="--", gid="near")
    below = int(np.count_nonzero(angle < near))
    ax.set_xlabel(_label("smallest angle, unstable span to the other vectors",
                         _unit(run, "clv/min_angle"), r"\theta_{\min}"))
    ax.set_ylabel(_label("records", "1"))
    ax.set_ylim(0.0, 1.08 * float(counts.max()))
    missing = clv.min_angle.size - angle.size
    note = f"; {missing} records without an angle" if missing else ""
    ax.set_title(f"{_title(run)}\n{below} of {angle.size} records ({below / angle.size:.1%}) "
                 f"below {near:g} rad; smallest {float(angle.min()):.3g} rad, median "
                 f"{float(np.median(angle)):.3g} rad{note}", fontsize="medium")
    _record_sources(fig, [run])
    return fig


def _clv(run: Run) -> Clv:
    if run.clv is None:
        raise FigureError(f"{run.path}: no covariant Lyapunov vectors in this run")
    if run.clv.n_record == 0:
        raise FigureError(f"{run.path}: /clv holds no record with vectors")
    return run.clv


def _record_window(cycle: np.ndarray, start: int | None, count: int | None) -> np.ndarray:
    """Indices of the records from cycle ``start`` (default: the first), ``count`` of them
    (default: all)."""
    first = int(cycle[0]) if start is None else start
    if not int(cycle[0]) <= first <= int(cycle[-1]):
        raise FigureError(f"start cycle {first} is outside the records with vectors "
                          f"{cycle[0]}..{cycle[-1]}")
    if count is not None and count < 1:
        raise FigureError(f"cycles = {count} must be >= 1")
    rows = np.flatnonzero(cycle >= first)
    return rows if count is None else rows[:count]


def _cell_edges(run: Run) -> np.ndarray:
    """x of the edges of the oscillators' cells, (n + 1,): edge k is where bond k's
    collisions are drawn, the middle of the bond between oscillators k and k + 1, and the
    walls (0 and the length) for bonds 0 and n."""
    pos = run.params.equilibrium
    return np.concatenate(([0.0], 0.5 * (pos[:-1] + pos[1:]), [run.params.length]))


def _collision_points(run: Run, window: tuple[float, float]) -> np.ndarray | None:
    """(x, t/T) of every collision in the time window, x the middle of its bond, (m, 2); None
    when the run recorded no events."""
    if run.events is None:
        return None
    events = run.events
    t = events.time / run.params.drive_period
    keep = events.collisions & (t >= window[0]) & (t < window[1])
    return np.column_stack((_cell_edges(run)[events.site[keep]], t[keep]))
