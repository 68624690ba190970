"""Figures of a parameter sweep (docs/model.md section 8): the bifurcation diagram, the largest
Lyapunov exponents and the Kaplan-Yorke dimension against the swept parameter.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.cm import ScalarMappable
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure

from impactchain.figures._canvas import (_axes_list, _new_figure, _one_axes, _parent,
                                         _record_sources, _root)
from impactchain.figures._data import (RunLike, _as_runs, _check_site, _differing_parameters,
                                       _sweep, _sweep_1d, as_run, run_labels)
from impactchain.figures._style import (BAND_ALPHA, FigureError, _grid, _index_colours,
                                        _index_ticks, _label, _outside, _overlay_colours, _padded,
                                        _parameter_label, _same_limits, _sweep_style, _title, _unit)
from impactchain.results import Run, Sweep


def bifurcation(run: RunLike, sites: Sequence[int] | None = None,
                ax: Sequence[Axes] | None = None) -> Figure:
    """Bifurcation diagram: recorded strobe positions against the swept parameter.

    One panel per oscillator (``sites``, 1-based; all by default), all with the same
    displacement range. ``ax``: one Axes per site, in the order of ``sites``.
    """
    run = as_run(run, ("sweep",), "bifurcation")
    sweep = _sweep_1d(run)
    sites = list(range(1, run.params.n + 1)) if sites is None else list(sites)
    if not sites:
        raise FigureError("no sites to plot")
    for site in sites:
        _check_site(site, run.params.n)
    n_rows, n_cols = _grid(len(sites), max_cols=2 if len(sites) <= 8 else 4)
    owned = ax is None
    if ax is None:
        fig: Figure = _new_figure(5.0 * n_cols, 2.6 * n_rows + 0.6)
        axes: list[Axes] = []
        for index in range(len(sites)):
            axes.append(fig.add_subplot(n_rows, n_cols, index + 1,
                                        sharex=axes[0] if axes else None))
    else:
        axes = _axes_list(ax, len(sites), "bifurcation")
        fig = _root(axes[0])
    y_limits = _padded(sweep.x[:, :, [s - 1 for s in sites]])
    unit = _unit(run, "sweep/x")
    for index, (axis, site) in enumerate(zip(axes, sites)):
        _bifurcation_points(axis, sweep, site)
        axis.set_ylim(*y_limits)
        axis.set_ylabel(_label("displacement", unit, f"x_{{{site}}}"), fontsize="small")
        axis.set_title(f"oscillator {site}", fontsize="small")
        if owned and index + n_cols < len(sites):
            axis.tick_params(labelbottom=False)
        else:
            axis.set_xlabel(_parameter_label(sweep.parameter), fontsize="small")
    if owned:
        fig.suptitle(_title(run, skip=sweep.parameter), fontsize="medium")
    _record_sources(fig, [run])
    return fig


def _bifurcation_points(ax: Axes, sweep: Sweep, site: int, colour: str = "k") -> None:
    cycles = sweep.x.shape[1]
    ax.plot(np.repeat(sweep.values, cycles), sweep.x[:, :, site - 1].reshape(-1),
            linestyle="none", marker=".", markersize=1.0, color=colour, rasterized=True,
            gid=f"bifurcation-{site}")


def lyapunov(runs: RunLike | Sequence[RunLike], k: int = 10, with_bifurcation: bool = False,
             ax: Sequence[Axes] | None = None) -> Figure:
    """The largest ``k`` Lyapunov exponents (bits/cycle) against the swept parameter.

    One column per sweep file; with ``with_bifurcation`` a bifurcation panel of
    oscillator 1 above the exponents (the paper's fig. 11). Each exponent is a line with a
    band of +-1 stored standard error (``/sweep/stderr``; bars for a sweep that goes back
    and forth), coloured by its index j, with a colour bar for j. All exponent panels share
    one y range, all bifurcation panels another. ``ax``: the axes row by row: with
    ``with_bifurcation`` the bifurcation axes of every column, then the exponent axes;
    otherwise one exponent Axes per column.
    """
    runs = _as_runs(runs, ("sweep", "sweep/exponents"), "lyapunov")
    if not runs:
        raise FigureError("lyapunov needs at least one sweep file")
    if k < 1:
        raise FigureError(f"k = {k} must be >= 1")
    sweeps = [_sweep_1d(run) for run in runs]
    for run, sweep in zip(runs, sweeps):
        if sweep.exponents is None:
            raise FigureError(f"{run.path}: the sweep has no Lyapunov exponents")
    n_rows, n_cols = (2 if with_bifurcation else 1), len(runs)
    owned = ax is None
    if ax is None:
        row_height = 3.4 if n_cols > 1 else 4.2
        fig: Figure = _new_figure(max(8.0, 5.6 * n_cols) + 1.0, row_height * n_rows + 0.8)
        grid = fig.subplots(n_rows, n_cols, squeeze=False, sharex="col")
        axes = list(grid.ravel())
    else:
        axes = _axes_list(ax, n_rows * n_cols, "lyapunov")
        fig = _root(axes[0])
    tops = axes[:n_cols] if with_bifurcation else []
    bottoms = axes[(n_rows - 1) * n_cols:]
    shown = max(min(k, s.exponents.shape[1]) for s in sweeps)  # type: ignore[union-attr]
    cmap, norm = _index_colours(shown)
    for column, (run, sweep) in enumerate(zip(runs, sweeps)):
        title = _title(run, skip=sweep.parameter)
        if tops:
            top = tops[column]
            _bifurcation_points(top, sweep, 1)
            top.set_ylabel(_label("displacement", _unit(run, "sweep/x"), "x_1"))
            if owned:
                top.tick_params(labelbottom=False)
            top.set_title(title, fontsize="small")
        bottom = bottoms[column]
        _exponent_lines(bottom, sweep, k, cmap, norm)
        bottom.set_xlabel(_parameter_label(sweep.parameter))
        bottom.set_ylabel(_label("Lyapunov exponents", _unit(run, "sweep/exponents"),
                                 r"\lambda_j"))
        if not tops:
            bottom.set_title(title, fontsize="small")
    if tops:
        _same_limits(tops, [s.x[:, :, 0] for s in sweeps])
    _same_limits(bottoms, [_exponent_range(s, k) for s in sweeps])
    if shown > 1:
        bar = _parent(bottoms[0]).colorbar(
            ScalarMappable(norm=norm, cmap=cmap), ax=bottoms, ticks=_index_ticks(shown),
            label=_label("exponent index", "1", "j"), pad=0.02, fraction=0.04, aspect=25)
        bar.ax.set_gid("colorbar-index")
        bar.minorticks_off()
    if owned:
        full = max(2 * run.params.n for run in runs)
        which = f"all {shown}" if shown == full else f"the largest {shown} of {full}"
        errors = [s.stderr[:, :shown] for s in sweeps if s.stderr is not None]
        note = ""
        if errors:
            finite = np.concatenate([e[np.isfinite(e)] for e in errors])
            largest = float(finite.max()) if finite.size else 0.0
            note = (f", bands of $\\pm$1 standard error (at most {largest:.2g} "
                    f"{_unit(runs[0], 'sweep/stderr')})")
        fig.suptitle(f"{which} Lyapunov exponents{note}", fontsize="medium")
    _record_sources(fig, runs)
    return fig


def _exponent_lines(ax: Axes, sweep: Sweep, k: int, cmap: ListedColormap,
                    norm: BoundaryNorm) -> None:
    assert sweep.exponents is not None
    shown = min(k, sweep.exponents.shape[1])
    style = _sweep_style(sweep.values)
    monotonic = "linestyle" not in style
    for j in range(shown):
        colour = cmap(norm(j + 1)) if cmap.N > 1 else "k"
        exponent = sweep.exponents[:, j]
        if sweep.stderr is not None:
            error = sweep.stderr[:, j]
            if monotonic:
                ax.fill_between(sweep.values, exponent - error, exponent + error,
                                color=colour, alpha=BAND_ALPHA, linewidth=0,
                                gid=f"stderr-{j + 1}")
            else:
                bars = ax.errorbar(sweep.values, exponent, yerr=error, fmt="none",
                                   ecolor=colour, elinewidth=0.6, alpha=0.6)
                for collection in bars.lines[2]:
                    collection.set_gid(f"stderr-{j + 1}")
        ax.plot(sweep.values, exponent, color=colour, linewidth=0.7,
                gid=f"exponent-{j + 1}", **style)
    ax.axhline(0.0, color="0.3", linewidth=0.8, linestyle="--", gid="zero")


def _exponent_range(sweep: Sweep, k: int) -> np.ndarray:
    assert sweep.exponents is not None
    shown = min(k, sweep.exponents.shape[1])
    values = sweep.exponents[:, :shown]
    if sweep.stderr is not None:
        error = sweep.stderr[:, :shown]
        values = np.concatenate((values - error, values + error))
    return np.append(values[np.isfinite(values)], 0.0)


def ky_dimension(runs: RunLike | Sequence[RunLike], labels: Sequence[str] | None = None,
                 ax: Axes | None = None, ylim: tuple[float, float] | None = None) -> Figure:
    """Kaplan-Yorke dimension against the swept parameter, one line per sweep file.

    Draws ``/sweep/ky_dimension``, the simulator's value at each point (docs/model.md
    section 7.5; the file stores no standard error for it). Several files get a legend:
    ``labels``, or by default :func:`run_labels` (the parameter that differs). A 2-D
    sweep is drawn as a scatter coloured by the dimension, with a colour bar. ``ax``: one
    Axes. ``ylim``: a range shared with other figures (1-D sweeps; the title says how many
    values fall outside it).

    From a partial spectrum (``&lyapunov vectors`` = k < 2n) the title says "k of 2n
    exponents", and a point whose partial sums stay >= 0 through all k exponents (the stored
    value is then k) is only a lower bound of the dimension: it is marked (open triangles)
    and named in the legend.
    """
    runs = _as_runs(runs, ("sweep", "sweep/ky_dimension"), "ky-dimension")
    if not runs:
        raise FigureError("ky-dimension needs at least one sweep file")
    if labels is not None and len(labels) != len(runs):
        raise FigureError(f"{len(labels)} labels for {len(runs)} runs")
    fig, ax = _one_axes(ax, 7.0, 4.5, "ky-dimension")
    colours = _overlay_colours(len(runs))
    swept = {name for run in runs if run.sweep is not None
             for name in (run.sweep.parameter, run.sweep.parameter2) if name}
    names = list(labels) if labels is not None else run_labels(runs, skip=swept)
    dimension_label = _label("Kaplan-Yorke dimension", "1", "D_{KY}")
    overlaid = len(runs) > 1 or labels is not None
    bounds: list[Artist] = []
    partial: list[str] = []
    for run, colour, name in zip(runs, colours, names):
        sweep = _sweep(run)
        dimension = _sweep_ky(run, sweep)
        computed, full = _spectrum_size(run, sweep)
        bound = _ky_lower_bound(dimension, computed, full)
        if computed < full and f"{computed} of {full}" not in partial:
            partial.append(f"{computed} of {full}")
        what = f"lower bound ({computed} of {full} exponents)"
        if sweep.is_2d:
            if len(runs) > 1:
                raise FigureError("ky-dimension overlays only 1-D sweeps")
            points = ax.scatter(sweep.values[:, 0], sweep.values[:, 1], c=dimension,
                                cmap="magma", s=16, linewidths=0, gid="ky")
            _parent(ax).colorbar(points, ax=ax, label=dimension_label)
            if bound.any():
                bounds.append(ax.scatter(sweep.values[bound, 0], sweep.values[bound, 1],
                                         marker="^", s=30, facecolors="none", edgecolors="k",
                                         linewidths=0.6, label=what, gid="lower-bound"))
            ax.set_xlabel(_parameter_label(sweep.parameter))
            ax.set_ylabel(_parameter_label(sweep.parameter2))
        else:
            ax.plot(sweep.values, dimension, color=colour, linewidth=0.9, label=name,
                    gid="ky", **_sweep_style(sweep.values, marker="."))
            if bound.any():
                (marks,) = ax.plot(sweep.values[bound], dimension[bound], linestyle="none",
                                   marker="^", markersize=5, markerfacecolor="none",
                                   color=colour, label=f"{name}: {what}" if name else what,
                                   gid="lower-bound")
                bounds.append(marks)
            ax.set_xlabel(_parameter_label(sweep.parameter))
            ax.set_ylabel(dimension_label)
            ax.set_ylim(bottom=0.0)
    if overlaid:
        ax.legend(fontsize="small")
    elif bounds:
        ax.legend(handles=bounds, fontsize="small")
    differing = _differing_parameters(runs)
    note = ""
    if partial:
        note = f"\nfrom {' and '.join(partial)} exponents"
        if bounds:
            note += "; open triangles: lower bounds"
    if not any(_sweep(run).is_2d for run in runs):
        note += _outside(ax, ylim, [_sweep_ky(run, _sweep(run)) for run in runs])
    ax.set_title(_title(runs[0], skip=(*swept, *differing)) + note, fontsize="medium")
    _record_sources(fig, runs)
    return fig


def _spectrum_size(run: Run, sweep: Sweep) -> tuple[int, int]:
    """(k, 2n): the exponents computed at each point of a sweep, and the full spectrum's."""
    full = 2 * run.params.n
    if sweep.exponents is None:
        return full, full
    return int(sweep.exponents.shape[1]), full


def _ky_lower_bound(dimension: np.ndarray, computed: int, full: int) -> np.ndarray:
    """Where a stored Kaplan-Yorke dimension is only a lower bound: from a partial spectrum
    (computed < full), the points whose partial sums stayed >= 0 through every computed
    exponent, for which the simulator stores the number computed (docs/model.md 7.5)."""
    dimension = np.asarray(dimension, dtype=float)
    if computed >= full:
        return np.zeros(dimension.shape, dtype=bool)
    return dimension >= computed


def _sweep_ky(run: Run, sweep: Sweep) -> np.ndarray:
    if sweep.ky_dimension is None:
        raise FigureError(f"{run.path}: the sweep has no Kaplan-Yorke dimensions "
                          "(/sweep/ky_dimension; written with &lyapunov)")
    return sweep.ky_dimension
