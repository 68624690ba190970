"""Figures of a continuation (periodic orbits followed in one parameter, docs/model.md
sections 11 and 12): the branches with their stability and special points, and the largest
Floquet multiplier.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from impactchain.figures._canvas import _one_axes, _record_sources
from impactchain.figures._data import RunLike, _as_runs, _check_site, _sweep_1d, as_run
from impactchain.figures._style import FigureError, _label, _parameter_label, _title, _unit
from impactchain.figures.sweeps import _bifurcation_points
from impactchain.results import SPECIAL_KINDS, Continuation, Run, Sweep


BRANCH_COLOURS = ("k", "tab:blue", "tab:cyan", "tab:brown", "tab:olive", "tab:pink",
                  "tab:gray")
"""Colour of continued branch 0, 1, 2, ... (cycled)."""
OVER_COLOUR = "0.65"
"""The brute-force bifurcation diagram under continued branches."""
SPECIAL_STYLES = {
    "fold": ("fold", "s", "tab:orange"),
    "period-doubling": ("period doubling", "D", "tab:purple"),
    "neimark-sacker": ("Neimark-Sacker", "^", "tab:green"),
    "grazing": ("grazing", "X", "tab:red"),
    "corner": ("simultaneous impact (corner)", "P", "tab:brown"),
    "section": ("impact at the section", "v", "tab:gray"),
    "branch-point": ("branch point", "o", "tab:cyan"),
}
"""Legend label, marker and colour of each kind of special point of a continuation."""


LOG_SPAN = 10.0
"""Largest Floquet multipliers spanning more than this factor are drawn on a log scale."""


def branches(run: RunLike | Sequence[RunLike], over: RunLike | None = None, site: int = 1,
             ax: Axes | None = None) -> Figure:
    """Continued periodic orbits: the positions of oscillator ``site`` (1-based) at the p
    section crossings of each period-p orbit against the continued parameter.

    Stable orbits are solid lines, unstable ones dashed; each branch (``Continuation.branch``)
    has its colour, and a line ends where the branch or the stability changes (a change of
    stability within a branch keeps the line unbroken). Special points are marked at every
    crossing of their orbit, one marker per kind, with a legend. ``run``: one continuation, or
    several of the same chain and parameter (branches followed from different starts), whose
    branches are coloured in turn. ``over``: a 1-D sweep of the same parameter, on the same
    chain and section, drawn first in grey as the brute-force bifurcation diagram. ``ax``:
    one Axes.
    """
    runs = _as_runs(run, ("continuation",), "branches")
    conts = [_continuation(r) for r in runs]
    first, cont0 = runs[0], conts[0]
    _check_site(site, first.params.n)
    for other, cont in zip(runs[1:], conts[1:]):
        if cont.parameter != cont0.parameter or other.params.n != first.params.n:
            raise FigureError(f"{other.path}: another parameter or chain than {first.path}")
    shown = list(runs)
    sweep = None
    if over is not None:
        over_run = as_run(over, ("sweep",), "branches")
        sweep = _sweep_1d(over_run)
        for r, cont in zip(runs, conts):
            _check_comparable(r, cont, over_run, sweep)
        shown.append(over_run)
    fig, ax = _one_axes(ax, 7.5, 5.0, "branches")
    if sweep is not None:
        _bifurcation_points(ax, sweep, site, colour=OVER_COLOUR)
    offset = 0
    handles: list[Line2D] = []
    specials: list[Line2D] = []
    for cont in conts:
        positions = cont.strobe_x[:, :, site - 1]
        for branch, stable, points in _stability_runs(cont):
            for strand in positions[points].T:
                if np.isfinite(strand).any():
                    _branch_line(ax, cont.values[points], strand, branch + offset, stable)
        for kind, chosen in _specials(cont):
            x = np.concatenate([np.full(cont.period[i], cont.special_value[j])
                                for j, i in chosen])
            y = np.concatenate([positions[i, :cont.period[i]] for _, i in chosen])
            _special_markers(ax, kind, x, y)
        offset += int(cont.branch.max()) + 1 if cont.n_points else 0
        labels = [h.get_label() for h in handles]
        handles += [h for h in _stability_handles(cont) if h.get_label() not in labels]
        labels = [h.get_label() for h in specials]
        specials += [h for h in _special_handles(cont) if h.get_label() not in labels]
    if sweep is not None:
        handles.insert(0, Line2D([], [], linestyle="none", marker=".", color=OVER_COLOUR,
                                 label="sweep"))
    ax.legend(handles=handles + specials, loc="best", fontsize="small", framealpha=0.9)
    ax.set_xlabel(_parameter_label(cont0.parameter))
    ax.set_ylabel(_label("displacement at the section", _unit(first, "continuation/strobe_x"),
                         f"x_{{{site}}}"))
    summary = (_continuation_summary(cont0) if len(conts) == 1 else
               f"{sum(c.n_points for c in conts)} orbits from {len(conts)} starts")
    # (wrapped to the figure: the end reasons of a continuation run long)
    ax.set_title(f"{_title(first, skip=cont0.parameter)}\noscillator {site}; {summary}",
                 fontsize="medium", wrap=True)
    _record_sources(fig, shown)
    return fig


def multipliers(run: RunLike, ax: Axes | None = None) -> Figure:
    """The largest modulus of the Floquet multipliers of the continued orbits against the
    continued parameter, with the unit line where orbits lose stability; on a log scale when
    the moduli span more than a factor :data:`LOG_SPAN`.

    Lines as in :func:`branches` (solid stable, dashed unstable, a colour per branch);
    special points marked, one marker each. ``ax``: one Axes.
    """
    run = as_run(run, ("continuation",), "multipliers")
    cont = _continuation(run)
    fig, ax = _one_axes(ax, 7.0, 4.5, "multipliers")
    modulus = cont.max_multiplier
    for branch, stable, points in _stability_runs(cont):
        _branch_line(ax, cont.values[points], modulus[points], branch, stable)
    ax.axhline(1.0, color="0.3", linewidth=0.8, linestyle=":", gid="unit")
    for kind, chosen in _specials(cont):
        _special_markers(ax, kind, cont.special_value[[j for j, _ in chosen]],
                         modulus[[i for _, i in chosen]])
    positive = modulus[np.isfinite(modulus) & (modulus > 0)]
    if positive.size and positive.max() > LOG_SPAN * positive.min():
        ax.set_yscale("log")
    ax.legend(handles=_stability_handles(cont) + _special_handles(cont), loc="best",
              fontsize="small", framealpha=0.9)
    ax.set_xlabel(_parameter_label(cont.parameter))
    ax.set_ylabel(_label("largest Floquet multiplier", "1", r"|\mu|_{\max}"))
    ax.set_title(f"{_title(run, skip=cont.parameter)}\n{_continuation_summary(cont)}",
                 fontsize="medium", wrap=True)
    _record_sources(fig, [run])
    return fig


def _continuation(run: Run) -> Continuation:
    cont = run.continuation
    if cont is None:
        raise FigureError(f"{run.path}: not a continuation file")
    if cont.n_points == 0:
        raise FigureError(f"{run.path}: the continuation holds no orbit ({cont.end_reason})")
    return cont


def _check_comparable(run: Run, cont: Continuation, over: Run, sweep: Sweep) -> None:
    """A sweep drawn under a continuation: the same parameter, chain and section."""
    if sweep.parameter != cont.parameter:
        raise FigureError(f"{over.path}: a sweep over {sweep.parameter}, the continuation "
                          f"follows {cont.parameter}")
    if over.params.n != run.params.n or over.params.boundary != run.params.boundary:
        raise FigureError(f"{over.path}: a chain of {over.params.n} oscillators with "
                          f"{over.params.boundary} ends, the continuation's has "
                          f"{run.params.n} with {run.params.boundary} ends")
    differ = [f"{name} ({getattr(over.params, name):g}, not {getattr(run.params, name):g})"
              for name in ("amplitude", "omega", "damping", "restitution")
              if name != cont.parameter
              and getattr(over.params, name) != getattr(run.params, name)]
    if cont.parameter != "spacing" and not np.array_equal(over.params.spacing,
                                                          run.params.spacing):
        differ.append("spacing")
    if over.params.phase != cont.phase:
        differ.append(f"section phase ({over.params.phase:g}, not {cont.phase:g})")
    if differ:
        raise FigureError(f"{over.path}: the sweep differs from the continuation in "
                          + ", ".join(differ))


def _stability_runs(cont: Continuation) -> list[tuple[int, bool, np.ndarray]]:
    """(branch, stable, point indices) of each line: the points split where the branch or
    the stability changes. A run that follows one of the same branch starts at that run's
    last point, so that a change of stability does not break the line."""
    runs = []
    start = 0
    for end in range(1, cont.n_points + 1):
        if (end < cont.n_points and cont.branch[end] == cont.branch[start]
                and cont.stable[end] == cont.stable[start]):
            continue
        first = start - 1 if start and cont.branch[start - 1] == cont.branch[start] else start
        runs.append((int(cont.branch[start]), bool(cont.stable[start]), np.arange(first, end)))
        start = end
    return runs


def _branch_line(ax: Axes, x: np.ndarray, y: np.ndarray, branch: int, stable: bool) -> None:
    ax.plot(x, y, color=BRANCH_COLOURS[branch % len(BRANCH_COLOURS)], linewidth=1.2,
            linestyle="-" if stable else "--", marker="." if x.size == 1 else "",
            gid=f"branch-{branch}-{'stable' if stable else 'unstable'}")


def _specials(cont: Continuation) -> list[tuple[str, list[tuple[int, int]]]]:
    """(kind, [(special point j, its point index i), ...]) of each kind present."""
    found = []
    for kind in SPECIAL_KINDS:
        chosen = [(j, int(i)) for j, (i, k) in enumerate(zip(cont.special_index,
                                                             cont.special_kind)) if k == kind]
        if chosen:
            found.append((kind, chosen))
    return found


def _special_markers(ax: Axes, kind: str, x: np.ndarray, y: np.ndarray) -> None:
    label, marker, colour = SPECIAL_STYLES[kind]
    ax.scatter(x, y, marker=marker, s=36, color=colour, edgecolors="k", linewidths=0.5,
               zorder=3, label=label, gid=f"special-{kind}")


def _stability_handles(cont: Continuation) -> list[Line2D]:
    styles = [("stable", "-")] if cont.stable.any() else []
    if not cont.stable.all():
        styles.append(("unstable", "--"))
    return [Line2D([], [], color="k", linestyle=style, label=label) for label, style in styles]


def _special_handles(cont: Continuation) -> list[Line2D]:
    handles = []
    for kind, _ in _specials(cont):
        label, marker, colour = SPECIAL_STYLES[kind]
        handles.append(Line2D([], [], linestyle="none", marker=marker, color=colour,
                              markeredgecolor="k", markeredgewidth=0.5, label=label))
    return handles


def _continuation_summary(cont: Continuation) -> str:
    count = len(np.unique(cont.branch))
    return (f"{cont.n_points} orbits on {count} branch{'es' if count > 1 else ''}; "
            f"stopped: {cont.end_reason}")
