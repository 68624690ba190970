"""Figures of an attractor census (docs/model.md section 13): basin fractions, the basin
picture on a plane of starts, and the ensemble of Lyapunov spectra.
"""

from __future__ import annotations

from typing import Any

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Patch
from matplotlib.ticker import MaxNLocator

from impactchain.figures._canvas import _one_axes, _record_sources
from impactchain.figures._data import RunLike, as_run
from impactchain.figures._style import (_SYMBOLS, FigureError, _label, _parameter_label, _title,
                                        _unit)
from impactchain.results import Census, Run


ATTRACTOR_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple",
                     "tab:brown", "tab:pink", "tab:olive", "tab:cyan", "tab:gray",
                     "navy", "gold", "lime", "maroon", "teal", "salmon")
"""Colour of each attractor (or attractor label) of a census, in the order found (cycled)."""
SAMPLE_ALPHA = 0.35
"""In an ensemble of spectra, each sample's own spectrum is drawn this opaque under its
attractor's mean."""
MIRROR_BLEND = 0.55
"""In a basin picture, the samples that reached an attractor's mirror image are drawn in its
colour blended this far towards white."""


def basin_fractions(run: RunLike, ax: Axes | None = None) -> Figure:
    """Basin fractions of a census (``/census``): the fraction of the starts that reached each
    attractor, with its binomial standard error.

    Along a swept parameter: stacked bars at each point, one segment per attractor label
    (kind and period pattern, :meth:`impactchain.io.Census.label`; attractors of one label
    at one point are added up, the legend saying how many there were at most), each with
    its error bar at its top. At one point: a bar per attractor with its error bar, labelled
    by id, kind and period pattern, its count above it. ``ax``: one Axes.
    """
    run = as_run(run, ("census",), "basin-fractions")
    census = _census(run)
    if census.n_points > 1 or census.swept:
        fig, ax = _one_axes(ax, 8.0, 5.0, "basin-fractions")
        _stacked_fractions(ax, census)
    else:
        width = max(6.0, 1.0 + 0.9 * census.n_attractors)
        fig, ax = _one_axes(ax, min(width, 14.0), 5.0, "basin-fractions")
        _point_fractions(ax, census)
    summary = f"{census.samples} starts per point"
    if census.plane is not None:
        summary = (f"{census.samples} starts on the plane ({census.plane[0]}, "
                   f"{census.plane[1]})")
    elif census.mirror == "merge":
        summary += "; mirror images merged"
    ax.set_title(f"{_title(run, skip=census.parameter)}\nbasin fractions: {summary}",
                 fontsize="medium")
    _record_sources(fig, [run])
    return fig


def _census(run: Run) -> Census:
    census = run.census
    if census is None:
        raise FigureError(f"{run.path}: not a census file")
    if census.n_attractors == 0 or census.n_points == 0:
        raise FigureError(f"{run.path}: the census holds no attractor")
    return census


def _point_fractions(ax: Axes, census: Census, point: int = 0) -> None:
    ids = census.attractors_at(point)
    positions = np.arange(ids.size)
    fractions = census.fraction[point, ids]
    errors = census.fraction_stderr[point, ids]
    colours = [ATTRACTOR_COLOURS[k % len(ATTRACTOR_COLOURS)] for k in range(ids.size)]
    ax.bar(positions, fractions, yerr=errors, color=colours, capsize=4, width=0.7,
           error_kw={"elinewidth": 1.0, "ecolor": "k"}, gid="fractions")
    for x, a, f, e in zip(positions, ids, fractions, errors):
        ax.annotate(f"{census.count(point, int(a))}/{census.samples}", (x, f + e),
                    xytext=(0, 3), textcoords="offset points", ha="center", va="bottom",
                    fontsize="small")
    ax.set_xticks(positions, [_wrapped(f"{a}: {census.label(int(a))}") for a in ids],
                  fontsize="small")
    ax.set_xlim(-0.6, ids.size - 0.4)
    ax.set_ylim(0.0, 1.1)
    ax.set_xlabel("attractor: id, kind and periods of the oscillators (left to right)")
    ax.set_ylabel(_label("basin fraction", "1", "f"))


def _wrapped(text: str, width: int = 13) -> str:
    """``text`` broken at blanks into lines of about ``width`` characters."""
    lines: list[str] = []
    for word in text.split():
        if lines and len(lines[-1]) + 1 + len(word) <= width:
            lines[-1] += " " + word
        else:
            lines.append(word)
    return "\n".join(lines)


def _stacked_fractions(ax: Axes, census: Census) -> None:
    labels: list[str] = []
    for a in range(census.n_attractors):
        if census.label(a) not in labels:
            labels.append(census.label(a))
    values = census.values
    steps = np.diff(np.sort(values))
    width = 0.7 * float(steps[steps > 0].min()) if np.any(steps > 0) else 0.7
    bottom = np.zeros(census.n_points)
    handles: list[Patch] = []
    for k, label in enumerate(labels):
        members = np.array([census.label(a) == label for a in range(census.n_attractors)])
        counts = np.array([np.count_nonzero(members[census.sample_attractor[p]])
                           for p in range(census.n_points)])
        fraction = counts / census.samples
        stderr = np.sqrt(fraction * (1 - fraction) / census.samples)
        colour = ATTRACTOR_COLOURS[k % len(ATTRACTOR_COLOURS)]
        ax.bar(values, fraction, width, bottom=bottom, color=colour, edgecolor="white",
               linewidth=0.5, gid=f"fraction-{k}")
        shown = fraction > 0
        ax.errorbar(values[shown], (bottom + fraction)[shown], yerr=stderr[shown],
                    fmt="none", ecolor="k", elinewidth=0.8, capsize=2)
        bottom = bottom + fraction
        most = max(int(np.count_nonzero(members & (census.attractor_point == p)))
                   for p in range(census.n_points))
        text = label if most <= 1 else f"{label} (up to {most} at a point)"
        handles.append(Patch(facecolor=colour, label=text))
    ax.set_ylim(0.0, 1.0)
    ax.set_xticks(values)
    ax.set_xlabel(_parameter_label(census.parameter))
    ax.set_ylabel(_label("basin fraction, stacked", "1", "f"))
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0),
              fontsize="small", title="attractor: kind, periods", title_fontsize="small")


def basin_plane(run: RunLike, point: int = 0, ax: Axes | None = None) -> Figure:
    """A basin picture: the attractor each start of a plane census (``&census plane``)
    reached, drawn as an image over the plane of its two initial coordinates, one colour per
    attractor (starts that reached an attractor's mirror image in a lighter shade), with a
    legend of the attractors and their fractions. ``point``: which point (0-based) of a
    census along a swept parameter. ``ax``: one Axes.
    """
    run = as_run(run, ("census",), "basin-plane")
    census = _census(run)
    if census.plane is None or census.plane_range is None:
        raise FigureError(f"{run.path}: the census has random starts; a basin picture needs "
                          "a plane of starts (&census plane = 'x<i>', 'v<j>')")
    if not 0 <= point < census.n_points:
        raise FigureError(f"point {point} is outside 0..{census.n_points - 1}")
    first, second, ids = census.plane_grid(point)
    m = census.plane_points
    mirrored = census.mirrored[point].reshape(m, m)
    present = np.unique(ids)
    colours: list[Any] = []
    index = np.zeros(ids.shape, dtype=int)
    handles: list[Patch] = []
    for k, a in enumerate(present):
        base = np.array(matplotlib.colors.to_rgba(ATTRACTOR_COLOURS[k % len(ATTRACTOR_COLOURS)]))
        light = base + MIRROR_BLEND * (1 - base)
        light[3] = 1.0
        index[(ids == a) & ~mirrored] = 2 * k
        index[(ids == a) & mirrored] = 2 * k + 1
        colours += [tuple(base), tuple(light)]
        fraction = census.fraction[point, a]
        handles.append(Patch(facecolor=tuple(base),
                             label=f"{a}: {census.label(int(a))}, {100 * fraction:.3g} %"))
    cmap = ListedColormap(colours, name="attractor")
    norm = BoundaryNorm(np.arange(-0.5, len(colours)), cmap.N)
    fig, ax = _one_axes(ax, 8.5, 5.5, "basin-plane")
    lo1, hi1, lo2, hi2 = (float(v) for v in census.plane_range)
    half1, half2 = (hi1 - lo1) / (2 * (m - 1)), (hi2 - lo2) / (2 * (m - 1))
    ax.imshow(index, cmap=cmap, norm=norm, origin="lower", aspect="auto",
              interpolation="nearest",
              extent=(lo1 - half1, hi1 + half1, lo2 - half2, hi2 + half2), gid="basins")
    if mirrored.any():
        handles.append(Patch(facecolor="0.85", label="lighter: its mirror image"))
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0),
              fontsize="small", title="attractor: kind, periods, fraction",
              title_fontsize="small")
    ax.set_xlabel(_coordinate_label(run, census.plane[0]))
    ax.set_ylabel(_coordinate_label(run, census.plane[1]))
    where = ""
    if census.swept:
        words, symbol = _SYMBOLS.get(census.parameter, (census.parameter, census.parameter))
        where = f" at ${symbol}$ = {census.values[point]:g}"
    ax.set_title(f"{_title(run, skip=census.parameter)}{where}\nbasins on the plane "
                 f"({census.plane[0]}, {census.plane[1]}), {m} x {m} starts",
                 fontsize="medium")
    del first, second
    _record_sources(fig, [run])
    return fig


def ensemble_spectra(run: RunLike, ax: Axes | None = None) -> Figure:
    """An ensemble of Lyapunov spectra (a census with ``&census exponents = k``): each
    attractor's mean spectrum against the exponent index, with error bars of +-1 spread
    between its samples (their standard deviation, docs/model.md section 13.4), over every
    sample's own spectrum drawn lighter in the attractor's colour. The legend names each
    attractor (id, kind and period pattern, its point along a sweep) with its basin fraction
    and its number of samples. The attractors' means are set a little apart along the index
    so that their bars do not hide each other; exponents of -infinity (directions removed by
    rests on a wall) are left out. A census of the largest exponent alone (k = 1) is drawn
    the same way, one column. ``ax``: one Axes.
    """
    run = as_run(run, ("census",), "ensemble-spectra")
    census = _census(run)
    unit = _unit(run, "census/sample_exponents")
    k, count = census.k, census.n_attractors
    fig, ax = _one_axes(ax, 9.5, 5.5, "ensemble-spectra")
    index = np.arange(1, k + 1, dtype=float)
    dodge = 0.3 * (np.arange(count) - (count - 1) / 2) / max(count - 1, 1)
    for a in range(count):
        colour = ATTRACTOR_COLOURS[a % len(ATTRACTOR_COLOURS)]
        p = int(census.attractor_point[a])
        members = census.members(a)
        spectra = _finite_only(census.sample_exponents[p, members])
        x = index + dodge[a]
        if k > 1:
            ax.add_collection(LineCollection([np.column_stack((x, row)) for row in spectra],
                                             colors=colour, linewidths=0.6,
                                             alpha=SAMPLE_ALPHA, gid=f"samples-{a}"))
        else:
            ax.plot(np.full(members.size, x[0]), spectra[:, 0], linestyle="none",
                    marker=".", markersize=3, color=colour, alpha=SAMPLE_ALPHA,
                    gid=f"samples-{a}")
        label = f"{a}: {census.label(a)}"
        if census.swept:
            symbol = _SYMBOLS.get(census.parameter, (census.parameter, census.parameter))[1]
            label += f" at ${symbol}$ = {census.values[p]:g}"
        label += f", {100 * census.fraction[p, a]:.3g} % ({members.size} samples)"
        ax.errorbar(x, _finite_only(census.attractor_exponents[a]),
                    yerr=_finite_only(census.attractor_exponents_spread[a]), fmt="o-",
                    markersize=3.5, linewidth=1.0, capsize=2.5, color=colour,
                    markeredgecolor="k", markeredgewidth=0.4, label=_wrapped(label, 44),
                    gid=f"mean-{a}")
    ax.axhline(0.0, color="0.3", linewidth=0.8, linestyle="--", gid="zero")
    ax.autoscale_view()
    ax.set_xlim(0.5, k + 0.5)
    if k <= 20:
        ax.set_xticks(np.arange(1, k + 1))
    else:
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel(_label("exponent index", "1", "j"))
    ax.set_ylabel(_label("Lyapunov exponent", unit, r"\lambda_j"))
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small",
              title="attractor: kind, periods, fraction", title_fontsize="small")
    what = f"the leading {k} exponents" if k > 1 else "the largest exponent"
    lines = "thin lines: each sample's spectrum" if k > 1 else "dots: each sample"
    ax.set_title(f"{_title(run, skip=census.parameter)}\nensemble of spectra: {what} of "
                 f"{census.samples} starts per point\nbars: $\\pm$1 spread between the "
                 f"samples; {lines}", fontsize="medium")
    _record_sources(fig, [run])
    return fig


def _finite_only(values: np.ndarray) -> np.ndarray:
    """``values`` with every non-finite entry NaN (left out of a line or a bar)."""
    return np.where(np.isfinite(values), values, np.nan)


def _coordinate_label(run: Run, name: str) -> str:
    """The axis label of a plane coordinate 'x3' or 'v3'."""
    i = int(name[1:])
    if name[0] == "x":
        return _label(f"initial displacement of oscillator {i}", _unit(run, "census/x0"),
                      f"x_{{{i}}}")
    return _label(f"initial velocity of oscillator {i}", _unit(run, "census/v0"), f"v_{{{i}}}")
