"""Figures of one run's strobe record (docs/model.md section 6): the space-amplitude
snapshots, the space-time-amplitude waterfall and the Poincare section.
"""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.font_manager import FontProperties
from matplotlib.lines import Line2D
from matplotlib.ticker import MaxNLocator

from impactchain.analysis import period_label
from impactchain.figures._canvas import (ProvenanceFigure, _axes_list, _one_axes, _parent,
                                         _record_sources, _root)
from impactchain.figures._data import (RunLike, _as_runs, _check_site, _differing_parameters, _last,
                                       _ranges, _strobe, as_run, run_labels)
from impactchain.figures._style import (TIME_LABEL_UNIT, FigureError, _cycle_label, _draw_walls,
                                        _grid, _label, _outside, _overlay_colours, _padded, _title,
                                        _unit, _x_limits)


def space_amplitude(
    runs: RunLike | Sequence[RunLike],
    cycles: int | None = None,
    periods: str = "file",
    labels: Sequence[str] | None = None,
    ax: Axes | None = None,
    ylim: tuple[float, float] | None = None,
) -> Figure:
    """Overlaid strobe snapshots: displacement at the section against equilibrium position.

    One line per recorded cycle (the last ``cycles`` records), one colour per run; walls
    as thick vertical lines when the boundary is fixed. ``periods``: ``'file'`` labels
    each site with the period the simulator stored, ``/strobe/period`` (found over the
    run's last records, docs/model.md section 6.3, whatever ``cycles`` shows; no labels
    for a file without it), ``'none'`` shows no labels. Several runs get a legend:
    ``labels``, or by default :func:`run_labels` (the parameter or seed that differs).
    ``ax``: one Axes to draw into. ``ylim``: a displacement range shared with other figures
    (the title says how many values fall outside it).
    """
    runs = _as_runs(runs, ("strobe",), "space-amplitude")
    if not runs:
        raise FigureError("space-amplitude needs at least one run")
    if periods not in ("file", "none"):
        raise FigureError(f"periods = {periods!r} must be 'file' or 'none'")
    if labels is not None and len(labels) != len(runs):
        raise FigureError(f"{len(labels)} labels for {len(runs)} runs")
    fig, ax = _one_axes(ax, 8.0, 5.0, "space-amplitude")
    colours = _overlay_colours(len(runs))
    label_rows = 0
    for index, (run, colour) in enumerate(zip(runs, colours)):
        strobe = _strobe(run)
        rows = _last(strobe.x, cycles)
        pos = run.params.equilibrium
        lines = ax.plot(pos, rows.T, color=colour, linewidth=0.5, marker="o", markersize=1.8)
        for line in lines:
            line.set_gid(f"strobe-{index}")
        shown_periods = None if periods == "none" else strobe.period
        if shown_periods is not None:
            _period_labels(ax, pos, shown_periods, colour, label_rows)
            label_rows += 1
    _draw_walls(ax, runs)
    ax.set_xlim(*_x_limits(runs))
    ax.set_xlabel(_label("equilibrium position", _unit(runs[0], "params/spacing")))
    ax.set_ylabel(_label("displacement at the section", _unit(runs[0], "strobe/x"), "x_i"))
    names = list(labels) if labels is not None else run_labels(runs)
    if len(runs) > 1 or labels is not None:
        handles = [Line2D([], [], color=c, marker="o", markersize=3, label=name)
                   for name, c in zip(names, colours)]
        ax.legend(handles=handles, loc="best", fontsize="small", framealpha=0.9)
    shown = min(_strobe(runs[0]).n_record, cycles or _strobe(runs[0]).n_record)
    differing = _differing_parameters(runs)
    note = "; labels: period in drive cycles, ap = aperiodic" if label_rows else ""
    note += _outside(ax, ylim, [_last(_strobe(run).x, cycles) for run in runs])
    ax.set_title(f"{_title(runs[0], skip=differing)}\nlast {shown} cycles{note}",
                 pad=6 + 11 * label_rows, fontsize="medium")
    _record_sources(fig, runs)
    return fig


def _period_labels(ax: Axes, pos: np.ndarray, periods: np.ndarray, colour: str, row: int) -> None:
    transform = ax.get_xaxis_transform()
    for x, p in zip(pos, periods):
        ax.text(x, 1.01 + 0.045 * row, period_label(int(p)), transform=transform,
                ha="center", va="bottom", fontsize=7, color=colour, clip_on=False,
                gid="period")


def space_time_amplitude(
    run: RunLike, panel_cycles: int = 60, panels: int | None = None,
    start: int | None = None, ax: Sequence[Axes] | None = None,
) -> Figure:
    """3-D waterfall of strobe snapshots: site on X, time (cycles) on Y, displacement on Z.

    The record from cycle ``start`` (default: the first recorded) is split into panels of
    ``panel_cycles`` cycles (at most 8 by default). All panels share the displacement
    axis (the range of the whole record). ``ax``: one 3-D Axes per panel
    (``projection='3d'``), in panel order.
    """
    run = as_run(run, ("strobe",), "space-time-amplitude")
    strobe = _strobe(run)
    ranges = _ranges(strobe.cycle, panel_cycles, panels, start)
    owned = ax is None
    if ax is None:
        n_rows, n_cols = _grid(len(ranges))
        # 3-D axes: placed by hand (constrained layout does not see their axis labels)
        fig: Figure = ProvenanceFigure(figsize=(5.6 * n_cols, 4.8 * n_rows + 0.4))
        fig.subplots_adjust(left=0.0, right=0.97, bottom=0.02,
                            top=1.0 - 0.7 / (4.8 * n_rows + 0.4), wspace=0.02, hspace=0.08)
        axes = [fig.add_subplot(n_rows, n_cols, p + 1, projection="3d")
                for p in range(len(ranges))]
    else:
        axes = _axes_list(ax, len(ranges), "space-time-amplitude")
        if any(a.name != "3d" for a in axes):
            raise FigureError("space-time-amplitude draws into 3-D axes "
                              "(add_subplot(..., projection='3d'))")
        fig = _root(axes[0])
    pos = run.params.equilibrium
    offset = run.params.section_offset
    z_limits = _padded(strobe.x)
    for p, (ax3, (first, stop)) in enumerate(zip(axes, ranges)):
        chosen = (strobe.cycle >= first) & (strobe.cycle < stop)
        for cycle, row in zip(strobe.cycle[chosen], strobe.x[chosen]):
            ax3.plot(pos, np.full(pos.shape, cycle + offset), row, color="k", linewidth=0.6)
        ax3.set_xlim(*_x_limits([run]))
        ax3.set_ylim(first + offset, stop + offset)
        ax3.set_zlim(*z_limits)
        ax3.set_xlabel(_label("equilibrium position", _unit(run, "params/spacing")),
                       fontsize="small")
        ax3.set_ylabel(_label("time", TIME_LABEL_UNIT, "t"), fontsize="small")
        ax3.set_zlabel(_label("displacement", _unit(run, "strobe/x"), "x_i"),
                       fontsize="small")
        ax3.tick_params(labelsize="x-small")
        ax3.set_title(f"({chr(ord('a') + p)}) cycles {first}-{stop - 1}", fontsize="small")
        ax3.view_init(elev=32, azim=-62)
    if owned:
        fig.suptitle(_title(run), fontsize="medium")
    _record_sources(fig, [run])
    return fig


def poincare(run: RunLike, site: int = 1, cycles: int | None = None,
             ax: Axes | None = None) -> Figure:
    """Poincare section (x, v) of oscillator ``site`` (1-based), coloured by cycle, with
    a colour bar. ``ax``: one Axes."""
    run = as_run(run, ("strobe",), "poincare")
    strobe = _strobe(run)
    _check_site(site, run.params.n)
    x = _last(strobe.x[:, site - 1], cycles)
    v = _last(strobe.v[:, site - 1], cycles)
    cycle = _last(strobe.cycle, cycles)
    fig, ax = _one_axes(ax, 6.0, 5.0, "poincare")
    points = ax.scatter(x, v, c=cycle, cmap="viridis", s=14, linewidths=0, gid="section")
    _parent(ax).colorbar(points, ax=ax, label=_cycle_label(run))
    ax.xaxis.set_major_locator(_SpacedLocator())
    ax.set_xlabel(_label("displacement", _unit(run, "strobe/x"), f"x_{{{site}}}"))
    ax.set_ylabel(_label("velocity", _unit(run, "strobe/v"), f"v_{{{site}}}"))
    ax.set_title(f"{_title(run)}\noscillator {site}, section phase "
                 f"{run.params.phase:.3g} rad, {x.size} cycles", fontsize="medium")
    _record_sources(fig, [run])
    return fig


class _SpacedLocator(MaxNLocator):
    """Ticks of an x axis far enough apart for their labels. Matplotlib's automatic ticks
    allow for labels three characters wide, so labels such as -0.875 at steps of 0.025 run
    together (figure 8); this takes fewer ticks, with the same steps, until the widest label
    (estimated at 0.65 em a character) and an em between labels fit between two ticks."""

    STEPS = (1.0, 2.0, 2.5, 5.0, 10.0)

    def __init__(self) -> None:
        super().__init__(nbins="auto", steps=list(self.STEPS))

    def tick_values(self, vmin: float, vmax: float) -> np.ndarray:
        ticks = super().tick_values(vmin, vmax)
        axis = self.axis
        if axis is None or axis.axes is None or not vmax != vmin:
            return ticks
        low, high = sorted((vmin, vmax))
        length = abs(axis.axes.bbox.width)
        em = (FontProperties(size=matplotlib.rcParams["xtick.labelsize"]).get_size_in_points()
              * axis.axes.get_figure(root=True).dpi / 72.0)
        bins = len(ticks)
        while bins > 1:
            shown = ticks[(ticks >= low) & (ticks <= high)]
            if shown.size < 2:
                break
            labels = axis.major.formatter.format_ticks(list(shown))
            room = (shown[1] - shown[0]) / (high - low) * length
            if room >= (0.65 * max(len(label) for label in labels) + 1.0) * em:
                break
            bins -= 1
            ticks = MaxNLocator(nbins=bins, steps=list(self.STEPS)).tick_values(vmin, vmax)
        return ticks
