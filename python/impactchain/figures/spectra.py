"""Figures of one run's Lyapunov spectrum (docs/model.md section 7): the spectrum with the
convergence of its running estimates, and the histograms of the finite-time exponents.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.cm import ScalarMappable
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from impactchain.figures._canvas import _axes_list, _new_figure, _parent, _record_sources, _root
from impactchain.figures._data import RunLike, _as_runs, _differing_parameters, as_run, run_labels
from impactchain.figures._style import (FigureError, _cycle_label, _index_colours, _index_ticks,
                                        _label, _overlay_colours, _same_limits, _title, _unit)
from impactchain.figures.sweeps import _ky_lower_bound
from impactchain.results import FiniteTime, Run


def spectrum(run: RunLike, ax: Axes | Sequence[Axes] | None = None) -> Figure:
    """Lyapunov spectrum of one run with error bars (+-1 stored standard error), and the
    convergence of the running estimates coloured by index j (with a colour bar), on the
    same y range. A run without running estimates (``impactchain.api.lyapunov``) gets the
    spectrum alone. ``ax``: one Axes (the spectrum) or two (spectrum, convergence).
    """
    run = as_run(run, ("lyapunov",), "spectrum")
    lyap = run.lyapunov
    if lyap is None:
        raise FigureError(f"{run.path}: no Lyapunov exponents in this run")
    unit = _unit(run, "lyapunov/exponents")
    has_running = lyap.running.shape[0] > 0
    owned = ax is None
    if ax is None:
        fig: Figure = _new_figure(11.0 if has_running else 6.0, 4.6)
        axes = list(np.ravel(fig.subplots(1, 2 if has_running else 1, squeeze=False)))
    else:
        count = 1 if isinstance(ax, Axes) else len(np.ravel(np.asarray(ax, dtype=object)))
        axes = _axes_list(ax, 2 if count == 2 else 1, "spectrum")
        fig = _root(axes[0])
    left = axes[0]
    index = np.arange(1, lyap.exponents.size + 1)
    left.errorbar(index, lyap.exponents, yerr=lyap.stderr, fmt="o", markersize=3,
                  capsize=2, color="k", gid="spectrum")
    left.axhline(0.0, color="0.3", linewidth=0.8, linestyle="--", gid="zero")
    left.set_xlabel(_label("exponent index", "1", "j"))
    left.set_ylabel(_label("Lyapunov exponent", unit, r"\lambda_j"))
    summary = f"$D_{{KY}}$ = {lyap.ky_dimension:.3f}"
    full = 2 * run.params.n
    if _ky_lower_bound(np.array(lyap.ky_dimension), lyap.exponents.size, full):
        summary = (f"$D_{{KY}}$ $\\geq$ {lyap.ky_dimension:.3f} (a lower bound: "
                   f"{lyap.exponents.size} of {full} exponents)")
    if math.isfinite(lyap.positive_sum):
        summary += f", sum of positive = {lyap.positive_sum:.3g} {unit}"
    left.set_title(f"{summary}\nbars: $\\pm$1 standard error", fontsize="small")
    ranges = [np.concatenate((lyap.exponents - lyap.stderr, lyap.exponents + lyap.stderr,
                              [0.0]))]
    if len(axes) == 2 and has_running:
        right = axes[1]
        steps, step_label = _running_axis(run)
        count = lyap.exponents.size
        cmap, norm = _index_colours(count)
        for j in range(count):
            right.plot(steps, lyap.running[:, j], color=cmap(norm(j + 1)), linewidth=0.7,
                       gid=f"running-{j + 1}")
        right.axhline(0.0, color="0.3", linewidth=0.8, linestyle="--", gid="zero")
        right.set_xlabel(step_label)
        right.set_ylabel(_label("running estimate", unit, r"\lambda_j"))
        right.set_title("convergence of the running estimates", fontsize="small")
        if count > 1:
            bar = _parent(right).colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=right,
                                          ticks=_index_ticks(count),
                                          label=_label("exponent index", "1", "j"))
            bar.ax.set_gid("colorbar-index")
            bar.minorticks_off()
        ranges.append(lyap.running)
        _same_limits(axes, ranges)
    elif len(axes) == 2:
        axes[1].text(0.5, 0.5, "no running estimates in this run", ha="center",
                     va="center", transform=axes[1].transAxes, gid="no-running")
    if owned:
        fig.suptitle(_title(run), fontsize="medium")
    _record_sources(fig, [run])
    return fig


def _running_axis(run: Run) -> tuple[np.ndarray, str]:
    assert run.lyapunov is not None
    if run.lyapunov.running_cycle is not None:
        return run.lyapunov.running_cycle, _cycle_label(run)
    m = run.lyapunov.running.shape[0]
    if run.strobe is not None and run.strobe.cycle.size == m:
        return run.strobe.cycle, _cycle_label(run)
    return np.arange(1, m + 1), _label("recorded cycles", _unit(run, "strobe/cycle"))


FINITE_TIME_BINS = 100
"""At most this many bins in a histogram of :func:`finite_time` (numpy's automatic choice
below that)."""
FINITE_TIME_FILL = 0.25
"""Opacity of a histogram's fill in :func:`finite_time` (its outline is opaque)."""


def finite_time(
    runs: RunLike | Sequence[RunLike],
    exponents: int | Sequence[int] = 1,
    bins: int | None = None,
    labels: Sequence[str] | None = None,
    ax: Axes | Sequence[Axes] | None = None,
) -> Figure:
    """How far finite stretches of the trajectory stray from the Lyapunov exponent: the
    histogram (a probability density) of the finite-time exponents ``/finite_time/exponents``
    over the run's windows of ``W`` cycles (docs/model.md section 7.10), with the run's
    exponent ``/lyapunov/exponents`` as a dashed line in a band of +-1 stored standard error
    ``/lyapunov/stderr`` (section 7.4).

    ``exponents``: 1-based indices in the order of ``/lyapunov/exponents`` (each the frame
    column whose windows' mean is that exponent, :attr:`FiniteTime.descending`: two nearly
    equal exponents may have crossed columns), one panel each, sharing the density axis;
    default the largest. Several runs (the same chain with windows of 10, 100 and 1000 cycles) overlay in
    colours, each histogram over its own range; they narrow as ``W`` grows. A run's legend
    entry gives its exponent and standard error, and on a second line ``W``, the number
    ``N`` of windows and ``sd/sqrt(N)`` of their exponents, an estimate of the standard error
    independent of the blocking one (close to it once a window is longer than the
    correlation time), with the cycles per block at which that one was read
    (``/lyapunov/stderr_block``). Windows after a direction collapsed (``-inf``) are counted
    there, not drawn. A run without ``/lyapunov`` (stopped early) gets no line. ``bins``: per
    histogram (default: numpy's choice, at most :data:`FINITE_TIME_BINS`). ``labels``: one
    per run, put before its exponent (default: what differs between the runs besides the
    window, :func:`run_labels`). ``ax``: one Axes per exponent.
    """
    runs = _as_runs(runs, ("finite_time",), "finite-time")
    if not runs:
        raise FigureError("finite-time needs at least one file")
    if labels is not None and len(labels) != len(runs):
        raise FigureError(f"{len(labels)} labels for {len(runs)} runs")
    chosen = [exponents] if isinstance(exponents, (int, np.integer)) else list(exponents)
    if not chosen:
        raise FigureError("finite-time needs at least one exponent")
    if bins is not None and bins < 1:
        raise FigureError(f"bins = {bins} must be >= 1")
    windows = [_finite_time(run) for run in runs]
    for run, ft in zip(runs, windows):
        for j in chosen:
            if not 1 <= j <= ft.k:
                raise FigureError(f"{run.path}: exponent {j} is outside 1..{ft.k}, the "
                                  "exponents of /finite_time")
    owned = ax is None
    if ax is None:
        fig: Figure = _new_figure(max(7.4, 5.4 * len(chosen) + 1.4), 5.0 + 0.35 * len(runs))
        axes = list(np.ravel(fig.subplots(1, len(chosen), sharey=True, squeeze=False)))
    else:
        axes = _axes_list(ax, len(chosen), "finite-time")
        fig = _root(axes[0])
    names = list(labels) if labels is not None else _finite_time_labels(runs, windows)
    colours = _overlay_colours(len(runs))
    unit = _unit(runs[0], "finite_time/exponents")
    for index, (axis, j) in enumerate(zip(axes, chosen)):
        handles = []
        for i, (run, ft, colour, name) in enumerate(zip(runs, windows, colours, names)):
            values = ft.descending[:, j - 1]
            finite = values[np.isfinite(values)]
            if finite.size == 0:
                raise FigureError(f"{run.path}: exponent {j} is -infinity in every window "
                                  "(its direction collapsed)")
            axis.hist(finite, bins=_finite_time_edges(finite, bins), density=True,
                      histtype="stepfilled", facecolor=matplotlib.colors.to_rgba(
                          colour, FINITE_TIME_FILL), edgecolor=colour, linewidth=1.0,
                      gid=f"histogram-{i + 1}")
            lyap = run.lyapunov
            if lyap is not None and j <= lyap.exponents.size \
                    and math.isfinite(lyap.exponents[j - 1]):
                mean, error = float(lyap.exponents[j - 1]), float(lyap.stderr[j - 1])
                axis.axvspan(mean - error, mean + error, color=colour, alpha=0.15,
                             linewidth=0, gid=f"stderr-{i + 1}")
                axis.axvline(mean, color=colour, linestyle="--", linewidth=1.2,
                             gid=f"exponent-{i + 1}")
            handles.append(Patch(facecolor=matplotlib.colors.to_rgba(colour, FINITE_TIME_FILL),
                                 edgecolor=colour,
                                 label=_finite_time_entry(run, ft, j, finite, name)))
        # below the axes: the narrowest histogram reaches the top
        axis.legend(handles=handles, fontsize="x-small", loc="upper center",
                    bbox_to_anchor=(0.5, -0.16))
        axis.set_xlabel(_label("finite-time exponent", unit, f"\\lambda_{{{j}}}"))
        if index == 0 or not owned:
            axis.set_ylabel(_label("probability density", f"1/({unit})"))
    if owned:
        fig.suptitle(f"{_title(runs[0], skip=_differing_parameters(runs))}\nfinite-time "
                     "exponents over windows of W cycles; dashed: the run's exponent, band: "
                     "$\\pm$1 standard error", fontsize="medium")
    _record_sources(fig, runs)
    return fig


def _finite_time(run: Run) -> FiniteTime:
    if run.finite_time is None:
        raise FigureError(f"{run.path}: no /finite_time (the run computed no finite-time "
                          "Lyapunov exponents: &lyapunov window = 0)")
    if run.finite_time.n_windows == 0:
        raise FigureError(f"{run.path}: /finite_time holds no window (the run ended before "
                          f"its first {run.finite_time.window} cycles)")
    return run.finite_time


def _finite_time_edges(values: np.ndarray, bins: int | None) -> np.ndarray:
    if bins is not None:
        return np.histogram_bin_edges(values, bins)
    edges = np.histogram_bin_edges(values, "auto")
    if edges.size - 1 > FINITE_TIME_BINS:
        edges = np.histogram_bin_edges(values, FINITE_TIME_BINS)
    return edges


def _finite_time_labels(runs: Sequence[Run], windows: Sequence[FiniteTime]) -> list[str]:
    """What tells the runs apart besides the window (which each legend entry gives): none
    when only the window differs."""
    names = run_labels(runs)
    generic = [f"run {i}" for i in range(1, len(runs) + 1)]
    if len(runs) < 2 or (names == generic and len({ft.window for ft in windows}) == len(runs)):
        return ["" for _ in runs]
    return names


def _finite_time_entry(run: Run, ft: FiniteTime, j: int, finite: np.ndarray,
                       name: str) -> str:
    """A run's legend entry: its exponent, then ``W = ... cycles, N windows, sd/sqrt(N) =
    ... vs stderr = ... (blocks of ... cycles)``."""
    lyap = run.lyapunov
    prefix = f"{name}: " if name else ""
    count = finite.size
    collapsed = ft.n_windows - count
    spread = (f"sd/$\\sqrt{{N}}$ = {float(np.std(finite, ddof=1)) / math.sqrt(count):.3g}"
              if count > 1 else "sd/$\\sqrt{N}$: one window")
    second = f"W = {ft.window} cycles, {count} windows"
    if collapsed:
        second += f" (+{collapsed} at $-\\infty$)"
    second += f", {spread}"
    if lyap is None or j > lyap.exponents.size:
        return f"{prefix}no /lyapunov in this run\n{second}"
    mean, error = float(lyap.exponents[j - 1]), float(lyap.stderr[j - 1])
    if not math.isfinite(mean):
        return f"{prefix}$\\lambda_{{{j}}}$ = {mean:.4g} (collapsed)\n{second}"
    second += f" vs stderr = {error:.3g}"
    if lyap.stderr_block is not None:
        second += f" (blocks of {int(lyap.stderr_block[j - 1])} cycles)"
    return f"{prefix}$\\lambda_{{{j}}}$ = {mean:.4g} $\\pm$ {error:.3g}\n{second}"
