"""Figures of the paper, built from :mod:`post.io` dataclasses.

Every function returns a :class:`matplotlib.figure.Figure` made with ``Figure()`` (no
pyplot, no global state); the caller saves it. Time in the space-time-amplitude and
shock-wave figures is in drive cycles, t/T, so that the strobe record of cycle c sits at
c + phase/(2 pi) and both figures share panel ranges for the same options.

Shock-wave layout: each panel is a pair of stacked axes with the same time range on the
y axis and the same x axis (equilibrium position of the colliding site, see
:attr:`post.io.Params.site_positions`): waves started at the right wall in the upper
axes, waves started at the left wall in the lower axes. Each wave is drawn as a thin line
through its collisions, with a dot at every collision.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib import colormaps
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from post.analysis import panel_ranges, period_label
from post.io import Run, Strobe, Sweep
from post.shockwave import Wave, build_shock_waves

__all__ = [
    "FigureError",
    "space_amplitude",
    "space_time_amplitude",
    "shock_wave",
    "poincare",
    "bifurcation",
    "lyapunov",
    "ky_dimension",
    "spectrum",
    "wave_points",
]

WALL_STYLE = {"color": "0.25", "linewidth": 4.0, "solid_capstyle": "butt", "zorder": 0.5}
LEFT_COLOUR = "tab:blue"
RIGHT_COLOUR = "tab:red"
OVERLAY_COLOURS = ("tab:red", "tab:green", "tab:blue", "tab:orange", "tab:purple",
                   "tab:brown", "tab:pink", "tab:olive", "tab:cyan", "tab:gray")

_SYMBOLS = {
    "amplitude": ("drive amplitude", "A"),
    "omega": ("drive frequency", r"\omega"),
    "damping": ("damping", "b"),
    "restitution": ("restitution", "K"),
    "spacing": ("spacing", "a"),
}


class FigureError(ValueError):
    """The data or the options cannot make the requested figure."""


# ------------------------------------------------------------------------ space-amplitude


def space_amplitude(
    runs: Sequence[Run], cycles: int | None = None, periods: str = "file"
) -> Figure:
    """Overlaid strobe snapshots: displacement at the section against equilibrium position.

    One line per recorded cycle (the last ``cycles`` records), one colour per run; walls
    as thick vertical lines when the boundary is fixed. ``periods``: ``'file'`` labels
    each site with the period the simulator stored, ``/strobe/period`` (found over the
    run's last records, docs/model.md section 6.3, whatever ``cycles`` shows; no labels
    for a file without it), ``'none'`` shows no labels.
    """
    if not runs:
        raise FigureError("space-amplitude needs at least one run")
    if periods not in ("file", "none"):
        raise FigureError(f"periods = {periods!r} must be 'file' or 'none'")
    fig = Figure(figsize=(8.0, 5.0), layout="constrained")
    ax = fig.add_subplot()
    colours = _overlay_colours(len(runs))
    label_rows = 0
    for index, (run, colour) in enumerate(zip(runs, colours)):
        strobe = _strobe(run)
        rows = _last(strobe.x, cycles)
        pos = run.params.equilibrium
        lines = ax.plot(pos, rows.T, color=colour, linewidth=0.5, marker="o", markersize=1.8)
        for line in lines:
            line.set_gid(f"strobe-{index}")
        labels = None if periods == "none" else strobe.period
        if labels is not None:
            _period_labels(ax, pos, labels, colour, label_rows)
            label_rows += 1
    _draw_walls(ax, runs)
    ax.set_xlim(*_x_limits(runs))
    ax.set_xlabel(_with_unit("equilibrium position", runs[0].unit("params/spacing")))
    ax.set_ylabel(_with_unit("displacement $x_i$ at the section", runs[0].unit("strobe/x")))
    if len(runs) > 1:
        handles = [Line2D([], [], color=c, label=r.name) for r, c in zip(runs, colours)]
        ax.legend(handles=handles, loc="lower right", fontsize="small")
    shown = min(_strobe(runs[0]).n_record, cycles or _strobe(runs[0]).n_record)
    ax.set_title(f"{_title(runs[0])}\nlast {shown} cycles", pad=6 + 11 * label_rows,
                 fontsize="medium")
    return fig


def _period_labels(ax: Axes, pos: np.ndarray, periods: np.ndarray, colour: str, row: int) -> None:
    transform = ax.get_xaxis_transform()
    for x, p in zip(pos, periods):
        ax.text(x, 1.01 + 0.045 * row, period_label(int(p)), transform=transform,
                ha="center", va="bottom", fontsize=7, color=colour, clip_on=False,
                gid="period")


# ------------------------------------------------------------------- space-time-amplitude


def space_time_amplitude(
    run: Run, panel_cycles: int = 60, panels: int | None = None, start: int | None = None
) -> Figure:
    """3-D waterfall of strobe snapshots: site on X, time (cycles) on Y, displacement on Z.

    The record from cycle ``start`` (default: the first recorded) is split into panels of
    ``panel_cycles`` cycles (at most 8 by default).
    """
    strobe = _strobe(run)
    ranges = _ranges(strobe.cycle, panel_cycles, panels, start)
    n_rows, n_cols = _grid(len(ranges))
    fig = Figure(figsize=(5.6 * n_cols, 4.6 * n_rows), layout="constrained")
    pos = run.params.equilibrium
    offset = run.params.section_offset
    z_limits = _padded(strobe.x)
    for p, (start, stop) in enumerate(ranges):
        ax = fig.add_subplot(n_rows, n_cols, p + 1, projection="3d")
        chosen = (strobe.cycle >= start) & (strobe.cycle < stop)
        for cycle, row in zip(strobe.cycle[chosen], strobe.x[chosen]):
            ax.plot(pos, np.full(pos.shape, cycle + offset), row, color="k", linewidth=0.6)
        ax.set_xlim(*_x_limits([run]))
        ax.set_ylim(start + offset, stop + offset)
        ax.set_zlim(*z_limits)
        ax.set_xlabel("equilibrium position", fontsize="small")
        ax.set_ylabel("time / T (cycles)", fontsize="small")
        ax.set_zlabel("$x$", fontsize="small")
        ax.tick_params(labelsize="x-small")
        ax.set_title(f"({chr(ord('a') + p)}) cycles {start}-{stop - 1}", fontsize="small")
        ax.view_init(elev=32, azim=-62)
    fig.suptitle(_title(run), fontsize="medium")
    return fig


# ------------------------------------------------------------------------------ shock-wave


def shock_wave(
    run: Run,
    panel_cycles: int = 60,
    panels: int | None = None,
    max_wait: float = 1.0,
    start: int | None = None,
) -> Figure:
    """Shock-wave plot (docs/model.md section 10.4): collision time against site position.

    Right-wall waves in the upper axes and left-wall waves in the lower axes of each
    panel; panels as in :func:`space_time_amplitude` for the same options. Waves are
    built from all events up to the end of the last panel, so a wave that began before
    ``start`` keeps its history.
    """
    if run.events is None:
        raise FigureError(f"{run.path}: no events recorded, the shock-wave plot needs them")
    if max_wait <= 0:
        raise FigureError(f"max_wait = {max_wait} must be > 0")
    params = run.params
    period = params.drive_period
    events = run.events
    if run.strobe is not None and run.strobe.n_record:
        cycles = run.strobe.cycle
    elif events.time.size:
        cycles = np.floor(events.time / period - params.section_offset).astype(np.int64)
    else:
        raise FigureError(f"{run.path}: no strobe records and no events to plot")
    ranges = _ranges(cycles, panel_cycles, panels, start)
    before_end = events.time < (ranges[-1][1] + params.section_offset) * period
    waves = build_shock_waves(events.time[before_end], events.site[before_end], params.n,
                              period, max_wait, kind=events.kind[before_end])
    n_rows, n_cols = _grid(len(ranges))
    fig = Figure(figsize=(5.0 * n_cols, 5.2 * n_rows), layout="constrained")
    outer = fig.add_gridspec(n_rows, n_cols)
    x_limits = _x_limits([run])
    for p, (start, stop) in enumerate(ranges):
        inner = outer[p // n_cols, p % n_cols].subgridspec(2, 1, hspace=0.0)
        upper = fig.add_subplot(inner[0])
        lower = fig.add_subplot(inner[1], sharex=upper)
        t0, t1 = start + params.section_offset, stop + params.section_offset
        for ax, side, colour in ((upper, "right", RIGHT_COLOUR), (lower, "left", LEFT_COLOUR)):
            ax.set_label(f"shock-{side}-{p}")
            side_waves = [w for w in waves if w.side == side]
            _draw_waves(ax, side_waves, params.site_positions, period, (t0, t1), colour)
            if params.walls:
                for x in (0.0, params.length):
                    ax.axvline(x, gid="wall", **WALL_STYLE)
            ax.set_ylim(t0, t1)
            ax.set_xlim(*x_limits)
            ax.set_ylabel("time / T (cycles)", fontsize="small")
            ax.tick_params(labelsize="x-small")
            ax.text(1.01, 0.5, f"from the {side} wall", transform=ax.transAxes,
                    rotation=90, ha="left", va="center", fontsize="small", color=colour)
        upper.tick_params(labelbottom=False)
        lower.set_xlabel("equilibrium position of the colliding site", fontsize="small")
        upper.set_title(f"({chr(ord('a') + p)}) cycles {start}-{stop - 1}", fontsize="small")
    title = f"{_title(run)}; wave dies after {max_wait:g} T without a collision"
    shown = events.time[before_end] >= (ranges[0][0] + params.section_offset) * period
    if events.time.size and not shown.any():
        title += (f"\nno collision in the shown cycles: the events span t/T = "
                  f"{events.time.min() / period:.6g} to {events.time.max() / period:.6g}")
    fig.suptitle(title, fontsize="medium")
    return fig


def wave_points(
    waves: Sequence[Wave], site_positions: np.ndarray, drive_period: float,
    window: tuple[float, float],
) -> np.ndarray:
    """(x, t/T) of every wave collision with t/T in the half-open ``window``, shape (m, 2)."""
    if not waves:
        return np.empty((0, 2))
    x = np.concatenate([site_positions[w.sites] for w in waves])
    t = np.concatenate([w.times for w in waves]) / drive_period
    keep = (t >= window[0]) & (t < window[1])
    return np.column_stack((x[keep], t[keep]))


def _draw_waves(
    ax: Axes, waves: Sequence[Wave], site_positions: np.ndarray, drive_period: float,
    window: tuple[float, float], colour: str,
) -> None:
    segments = []
    for wave in waves:
        t = wave.times / drive_period
        if len(wave) > 1 and t[-1] >= window[0] and t[0] < window[1]:
            segments.append(np.column_stack((site_positions[wave.sites], t)))
    ax.add_collection(LineCollection(segments, colors=colour, linewidths=0.7, alpha=0.7,
                                     gid="waves"), autolim=False)
    points = wave_points(waves, site_positions, drive_period, window)
    ax.scatter(points[:, 0], points[:, 1], s=5, color=colour, linewidths=0, gid="collisions")


# -------------------------------------------------------------------------------- poincare


def poincare(run: Run, site: int = 1, cycles: int | None = None) -> Figure:
    """Poincare section (x, v) of oscillator ``site`` (1-based), coloured by cycle."""
    strobe = _strobe(run)
    _check_site(site, run.params.n)
    x = _last(strobe.x[:, site - 1], cycles)
    v = _last(strobe.v[:, site - 1], cycles)
    cycle = _last(strobe.cycle, cycles)
    fig = Figure(figsize=(6.0, 5.0), layout="constrained")
    ax = fig.add_subplot()
    points = ax.scatter(x, v, c=cycle, cmap="viridis", s=14, linewidths=0, gid="section")
    fig.colorbar(points, ax=ax, label="cycle")
    ax.set_xlabel(_with_unit(f"$x_{{{site}}}$", run.unit("strobe/x")))
    ax.set_ylabel(_with_unit(f"$v_{{{site}}}$", run.unit("strobe/v")))
    ax.set_title(f"{_title(run)}\noscillator {site}, section phase "
                 f"{run.params.phase:.3g} rad, {x.size} cycles", fontsize="medium")
    return fig


# ---------------------------------------------------------------------------- bifurcation


def bifurcation(run: Run, sites: Sequence[int] | None = None) -> Figure:
    """Bifurcation diagram: recorded strobe positions against the swept parameter.

    One panel per oscillator (``sites``, 1-based; all by default).
    """
    sweep = _sweep_1d(run)
    sites = list(range(1, run.params.n + 1)) if sites is None else list(sites)
    if not sites:
        raise FigureError("no sites to plot")
    for site in sites:
        _check_site(site, run.params.n)
    n_rows, n_cols = _grid(len(sites), max_cols=2 if len(sites) <= 8 else 4)
    fig = Figure(figsize=(5.0 * n_cols, 2.6 * n_rows + 0.6), layout="constrained")
    first = None
    for index, site in enumerate(sites):
        ax = fig.add_subplot(n_rows, n_cols, index + 1, sharex=first)
        if first is None:
            first = ax
        _bifurcation_points(ax, sweep, site)
        ax.set_ylabel(f"$x_{{{site}}}$")
        ax.set_title(f"oscillator {site}", fontsize="small")
        if index + n_cols < len(sites):
            ax.tick_params(labelbottom=False)
        else:
            ax.set_xlabel(_parameter_label(sweep.parameter), fontsize="small")
    fig.suptitle(_title(run, skip=sweep.parameter), fontsize="medium")
    return fig


def _bifurcation_points(ax: Axes, sweep: Sweep, site: int) -> None:
    cycles = sweep.x.shape[1]
    ax.plot(np.repeat(sweep.values, cycles), sweep.x[:, :, site - 1].reshape(-1),
            linestyle="none", marker=".", markersize=1.0, color="k", rasterized=True,
            gid=f"bifurcation-{site}")


# ------------------------------------------------------------------------------- lyapunov


def lyapunov(runs: Sequence[Run], k: int = 10, with_bifurcation: bool = False) -> Figure:
    """The largest ``k`` Lyapunov exponents (bits/cycle) against the swept parameter.

    One column per sweep file; with ``with_bifurcation`` a bifurcation panel of
    oscillator 1 above the exponents (the paper's fig. 11).
    """
    if not runs:
        raise FigureError("lyapunov needs at least one sweep file")
    if k < 1:
        raise FigureError(f"k = {k} must be >= 1")
    n_rows = 2 if with_bifurcation else 1
    fig = Figure(figsize=(5.5 * len(runs), 3.2 * n_rows + 0.6), layout="constrained")
    for column, run in enumerate(runs):
        sweep = _sweep_1d(run)
        if sweep.exponents is None:
            raise FigureError(f"{run.path}: the sweep has no Lyapunov exponents")
        top = None
        if with_bifurcation:
            top = fig.add_subplot(n_rows, len(runs), column + 1)
            _bifurcation_points(top, sweep, 1)
            top.set_ylabel("$x_1$")
            top.tick_params(labelbottom=False)
            top.set_title(_title(run, skip=sweep.parameter), fontsize="small")
        ax = fig.add_subplot(n_rows, len(runs), (n_rows - 1) * len(runs) + column + 1,
                             sharex=top)
        _exponent_lines(ax, sweep, k)
        ax.set_xlabel(_parameter_label(sweep.parameter))
        ax.set_ylabel(_with_unit("Lyapunov exponents", run.unit("sweep/exponents",
                                                                 "bits/cycle")))
        if top is None:
            ax.set_title(_title(run, skip=sweep.parameter), fontsize="small")
    return fig


def _exponent_lines(ax: Axes, sweep: Sweep, k: int) -> None:
    assert sweep.exponents is not None
    shown = min(k, sweep.exponents.shape[1])
    style = _sweep_style(sweep.values)
    colours = _ramp(shown)
    for j in range(shown):
        ax.plot(sweep.values, sweep.exponents[:, j], color=colours[j], linewidth=0.8,
                gid=f"exponent-{j + 1}", **style)
    ax.axhline(0.0, color="0.3", linewidth=0.8, linestyle="--", gid="zero")
    ax.text(0.01, 0.98, f"largest {shown} exponents", transform=ax.transAxes,
            ha="left", va="top", fontsize="x-small")


# --------------------------------------------------------------------------- ky-dimension


def ky_dimension(runs: Sequence[Run]) -> Figure:
    """Kaplan-Yorke dimension against the swept parameter, one line per sweep file.

    Draws ``/sweep/ky_dimension``, the simulator's value at each point (docs/model.md
    section 7.5). A 2-D sweep is drawn as a scatter coloured by the dimension.
    """
    if not runs:
        raise FigureError("ky-dimension needs at least one sweep file")
    fig = Figure(figsize=(7.0, 4.5), layout="constrained")
    ax = fig.add_subplot()
    colours = _overlay_colours(len(runs))
    differing = _differing_parameters(runs)
    for run, colour in zip(runs, colours):
        sweep = _sweep(run)
        dimension = _sweep_ky(run, sweep)
        label = ", ".join(f"${_SYMBOLS[name][1]}$ = {getattr(run.params, name):g}"
                          for name in differing) or run.name
        if sweep.is_2d:
            if len(runs) > 1:
                raise FigureError("ky-dimension overlays only 1-D sweeps")
            points = ax.scatter(sweep.values[:, 0], sweep.values[:, 1], c=dimension,
                                cmap="magma", s=16, linewidths=0, gid="ky")
            fig.colorbar(points, ax=ax, label="Kaplan-Yorke dimension $D_{KY}$")
            ax.set_xlabel(_parameter_label(sweep.parameter))
            ax.set_ylabel(_parameter_label(sweep.parameter2))
        else:
            ax.plot(sweep.values, dimension, color=colour, linewidth=0.9, label=label,
                    gid="ky", **_sweep_style(sweep.values, marker="."))
            ax.set_xlabel(_parameter_label(sweep.parameter))
            ax.set_ylabel("Kaplan-Yorke dimension $D_{KY}$")
    if len(runs) > 1:
        ax.legend(fontsize="small")
    first = runs[0].sweep
    skip = (first.parameter, first.parameter2) if first is not None else ()
    ax.set_title(_title(runs[0], skip=(*skip, *differing)), fontsize="medium")
    return fig


def _differing_parameters(runs: Sequence[Run]) -> list[str]:
    """Model parameters whose values differ between overlaid runs (for their labels)."""
    names = ("amplitude", "omega", "damping", "restitution")
    return [name for name in names
            if len({getattr(run.params, name) for run in runs}) > 1]


def _sweep_ky(run: Run, sweep: Sweep) -> np.ndarray:
    if sweep.ky_dimension is None:
        raise FigureError(f"{run.path}: the sweep has no Kaplan-Yorke dimensions "
                          "(/sweep/ky_dimension; written with &lyapunov)")
    return sweep.ky_dimension


# ------------------------------------------------------------------------------- spectrum


def spectrum(run: Run) -> Figure:
    """Lyapunov spectrum of one run with error bars, and convergence of the estimates."""
    lyap = run.lyapunov
    if lyap is None:
        raise FigureError(f"{run.path}: no Lyapunov exponents in this run")
    unit = run.unit("lyapunov/exponents", "bits/cycle")
    fig = Figure(figsize=(11.0, 4.6), layout="constrained")
    left, right = fig.subplots(1, 2)
    index = np.arange(1, lyap.exponents.size + 1)
    left.errorbar(index, lyap.exponents, yerr=lyap.stderr, fmt="o", markersize=3,
                  capsize=2, color="k", gid="spectrum")
    left.axhline(0.0, color="0.3", linewidth=0.8, linestyle="--", gid="zero")
    left.set_xlabel("index $j$")
    left.set_ylabel(_with_unit(r"$\lambda_j$", unit))
    left.set_title(f"$D_{{KY}}$ = {lyap.ky_dimension:.3f}, sum of positive = "
                   f"{lyap.positive_sum:.3g} {unit}", fontsize="small")
    steps, step_label = _running_axis(run)
    colours = _ramp(lyap.exponents.size)
    for j in range(lyap.exponents.size):
        right.plot(steps, lyap.running[:, j], color=colours[j], linewidth=0.7,
                   gid=f"running-{j + 1}")
    right.axhline(0.0, color="0.3", linewidth=0.8, linestyle="--", gid="zero")
    right.set_xlabel(step_label)
    right.set_ylabel(_with_unit("running estimate", unit))
    right.set_title("convergence of the running estimates", fontsize="small")
    fig.suptitle(_title(run), fontsize="medium")
    return fig


def _running_axis(run: Run) -> tuple[np.ndarray, str]:
    assert run.lyapunov is not None
    if run.lyapunov.running_cycle is not None:
        return run.lyapunov.running_cycle, "cycle"
    m = run.lyapunov.running.shape[0]
    if run.strobe is not None and run.strobe.cycle.size == m:
        return run.strobe.cycle, "cycle"
    return np.arange(1, m + 1), "recorded cycles"


# -------------------------------------------------------------------------------- helpers


def _strobe(run: Run) -> Strobe:
    if run.strobe is None:
        raise FigureError(f"{run.path}: no strobe records")
    if run.strobe.n_record == 0:
        raise FigureError(f"{run.path}: the strobe record is empty")
    return run.strobe


def _sweep(run: Run) -> Sweep:
    if run.sweep is None:
        raise FigureError(f"{run.path}: not a sweep file")
    if run.sweep.values.shape[0] == 0:
        raise FigureError(f"{run.path}: the sweep is empty")
    return run.sweep


def _sweep_1d(run: Run) -> Sweep:
    sweep = _sweep(run)
    if sweep.is_2d:
        raise FigureError(f"{run.path}: a 2-D sweep ({sweep.parameter}, {sweep.parameter2}); "
                          "this figure needs a 1-D sweep")
    return sweep


def _check_site(site: int, n: int) -> None:
    if not 1 <= site <= n:
        raise FigureError(f"site {site} is outside 1..{n}")


def _last(values: np.ndarray, count: int | None) -> np.ndarray:
    if count is None:
        return values
    if count < 1:
        raise FigureError(f"cycles = {count} must be >= 1")
    return values[-count:]


def _ranges(
    cycles: np.ndarray, panel_cycles: int, panels: int | None, start: int | None
) -> list[tuple[int, int]]:
    try:
        return panel_ranges(cycles, panel_cycles, panels, start)
    except ValueError as exc:
        raise FigureError(str(exc)) from exc


def _grid(count: int, max_cols: int = 2) -> tuple[int, int]:
    cols = min(count, max_cols)
    return -(-count // cols), cols


def _padded(values: np.ndarray, fraction: float = 0.05) -> tuple[float, float]:
    low, high = float(np.nanmin(values)), float(np.nanmax(values))
    pad = fraction * (high - low) or 0.1 * max(1.0, abs(high))
    return low - pad, high + pad


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


def _sweep_style(values: np.ndarray, marker: str = "") -> dict[str, str]:
    """Lines for a monotonic sweep, dots only when the parameter goes back and forth."""
    steps = np.diff(values)
    monotonic = bool(np.all(steps > 0) or np.all(steps < 0))
    if monotonic:
        return {"marker": marker, "markersize": 2.5} if marker else {}
    return {"linestyle": "none", "marker": marker or ".", "markersize": 2.5}


def _parameter_label(name: str) -> str:
    if name in _SYMBOLS:
        words, symbol = _SYMBOLS[name]
        return f"{words} ${symbol}$"
    return name


def _with_unit(label: str, unit: str) -> str:
    return f"{label} [{unit}]" if unit and unit not in ("1", "-") else label


def _title(run: Run, skip: str | Sequence[str] = ()) -> str:
    skipped = {skip} if isinstance(skip, str) else set(skip)
    p = run.params
    parts = [f"n = {p.n}"]
    for name, value in (("amplitude", p.amplitude), ("omega", p.omega),
                        ("damping", p.damping), ("restitution", p.restitution)):
        if name not in skipped:
            parts.append(f"${_SYMBOLS[name][1]}$ = {value:g}")
    parts.append(f"{p.boundary} ends")
    title = ", ".join(parts)
    if not run.complete:
        title += " (interrupted run)"
    return title
