"""The shock-wave figure (docs/model.md section 10.4): collision cascades from the walls.

Each panel is a pair of stacked axes with the same time range on the y axis and the same x axis
(equilibrium position of the colliding site, see :attr:`impactchain.io.Params.site_positions`):
waves started at the right wall in the upper axes, waves started at the left wall in the lower
axes. Each wave is drawn as a thin line through its collisions, with a dot at every collision.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure

from impactchain.figures._canvas import _axes_list, _new_figure, _record_sources, _root
from impactchain.figures._data import RunLike, _ranges, as_run
from impactchain.figures._style import (LEFT_COLOUR, RIGHT_COLOUR, TIME_LABEL_UNIT, WALL_STYLE,
                                        FigureError, _grid, _label, _title, _unit, _x_limits)
from impactchain.shockwave import Wave, build_shock_waves


def shock_wave(
    run: RunLike,
    panel_cycles: int = 60,
    panels: int | None = None,
    max_wait: float = 1.0,
    start: int | None = None,
    ax: Sequence[Axes] | None = None,
) -> Figure:
    """Shock-wave plot (docs/model.md section 10.4): collision time against site position.

    Right-wall waves in the upper axes and left-wall waves in the lower axes of each
    panel; panels as in :func:`space_time_amplitude` for the same options. Waves are
    built from all events up to the end of the last panel, so a wave that began before
    ``start`` keeps its history. ``ax``: two Axes per panel, (upper, lower) of panel 1,
    then of panel 2, ...
    """
    run = as_run(run, ("events",), "shock-wave")
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
    owned = ax is None
    if ax is None:
        n_rows, n_cols = _grid(len(ranges))
        fig: Figure = _new_figure(5.0 * n_cols, 5.2 * n_rows)
        outer = fig.add_gridspec(n_rows, n_cols)
        pairs = []
        for p in range(len(ranges)):
            inner = outer[p // n_cols, p % n_cols].subgridspec(2, 1, hspace=0.0)
            upper = fig.add_subplot(inner[0])
            pairs.append((upper, fig.add_subplot(inner[1], sharex=upper)))
    else:
        given = _axes_list(ax, 2 * len(ranges), "shock-wave")
        pairs = list(zip(given[0::2], given[1::2]))
        fig = _root(given[0])
    x_limits = _x_limits([run])
    time_label = _label("time", TIME_LABEL_UNIT, "t")
    for p, ((upper, lower), (first, stop)) in enumerate(zip(pairs, ranges)):
        t0, t1 = first + params.section_offset, stop + params.section_offset
        for axis, side, colour in ((upper, "right", RIGHT_COLOUR),
                                   (lower, "left", LEFT_COLOUR)):
            axis.set_label(f"shock-{side}-{p}")
            side_waves = [w for w in waves if w.side == side]
            _draw_waves(axis, side_waves, params.site_positions, period, (t0, t1), colour)
            if params.walls:
                for x in (0.0, params.length):
                    axis.axvline(x, gid="wall", **WALL_STYLE)
            axis.set_ylim(t0, t1)
            axis.set_xlim(*x_limits)
            axis.set_ylabel(time_label, fontsize="small")
            axis.tick_params(labelsize="x-small")
            axis.text(1.01, 0.5, f"from the {side} wall", transform=axis.transAxes,
                      rotation=90, ha="left", va="center", fontsize="small", color=colour)
        upper.tick_params(labelbottom=False)
        lower.set_xlabel(_label("equilibrium position of the colliding site",
                                _unit(run, "params/spacing")), fontsize="small")
        upper.set_title(f"({chr(ord('a') + p)}) cycles {first}-{stop - 1}", fontsize="small")
    title = f"{_title(run)}; wave dies after {max_wait:g} T without a collision"
    shown = events.time[before_end] >= (ranges[0][0] + params.section_offset) * period
    if events.time.size and not shown.any():
        title += (f"\nno collision in the shown cycles: the events span t/T = "
                  f"{events.time.min() / period:.6g} to {events.time.max() / period:.6g}")
    if owned:
        fig.suptitle(title, fontsize="medium")
    _record_sources(fig, [run])
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
