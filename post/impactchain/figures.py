"""Figures of the paper, built from :mod:`impactchain.io` runs.

Every figure function takes its data as a :class:`impactchain.io.Run`, a path to an impactchain
HDF5 file, or an in-memory result of :mod:`impactchain.api` (anything with a ``to_run()`` method
returning a Run: ``api.Simulation``, ``api.Lyapunov``), and returns a
:class:`matplotlib.figure.Figure`, without pyplot or global state. With ``ax=None`` the
function makes its own figure (a :class:`ProvenanceFigure`); with ``ax=`` (one Axes, or a
sequence of them for a multi-panel figure, in the order each function documents) it draws
there and returns the root figure of those axes, leaving that figure's title to the caller.

Conventions, the same in every figure:

- Axis labels read ``name $symbol$ [unit]``: a short name, the symbol where the quantity has
  one, and the unit in brackets, ``[1]`` for a dimensionless quantity. Units are the
  ``units`` attributes of the datasets shown (:data:`impactchain.io.FILE_UNITS` for a run made in
  memory); the model parameters, which the file stores without units, are in the model's
  reduced units as the file schema gives them (:func:`impactchain.schema.parameter_units`,
  docs/model.md section 1.5): ``A`` and the spacing ``a`` in [length], ``w`` in [1/time],
  ``b`` and ``K`` in [1].
- Colour that encodes a number has a colour bar; colour that tells runs apart has a legend
  naming the parameter or the seed that differs (:func:`run_labels`), never a file name.
- Panels that show the same quantity share their limits (y, or z in 3-D).
- Lyapunov exponents are drawn with their stored standard errors (bands, or bars for a
  sweep that goes back and forth).
- Saving a figure with :func:`save` (or ``savefig`` of a figure made here) writes the code
  version, the input namelists and the source file names into the file's metadata
  (:func:`metadata`).

Time in the space-time-amplitude and shock-wave figures is in drive cycles, t/T, so that
the strobe record of cycle c sits at c + phase/(2 pi) and both figures share panel ranges
for the same options.

Shock-wave layout: each panel is a pair of stacked axes with the same time range on the
y axis and the same x axis (equilibrium position of the colliding site, see
:attr:`impactchain.io.Params.site_positions`): waves started at the right wall in the upper
axes, waves started at the left wall in the lower axes. Each wave is drawn as a thin line
through its collisions, with a dot at every collision.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol, Union, runtime_checkable

import matplotlib
import numpy as np
from matplotlib import colormaps
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.cm import ScalarMappable
from matplotlib.collections import LineCollection
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure, SubFigure
from matplotlib.font_manager import FontProperties
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import MaxNLocator

from impactchain import __version__
from impactchain.analysis import panel_ranges, period_label
from impactchain import schema
from impactchain.io import (FILE_UNITS, SPECIAL_KINDS, Census, Clv, Continuation, FiniteTime,
                            Run, Strobe, Sweep, is_sweep_dataset, read_run, run_from_sweep)
from impactchain.shockwave import Wave, build_shock_waves

__all__ = [
    "FigureError",
    "ProvenanceFigure",
    "RunLike",
    "SupportsRun",
    "as_run",
    "run_labels",
    "metadata",
    "save",
    "space_amplitude",
    "space_time_amplitude",
    "shock_wave",
    "poincare",
    "bifurcation",
    "lyapunov",
    "ky_dimension",
    "spectrum",
    "branches",
    "multipliers",
    "basin_fractions",
    "basin_plane",
    "ensemble_spectra",
    "clv_space_time",
    "clv_ipr",
    "clv_angles",
    "finite_time",
    "wave_points",
]

WALL_STYLE = {"color": "0.25", "linewidth": 4.0, "solid_capstyle": "butt", "zorder": 0.5}
LEFT_COLOUR = "tab:blue"
RIGHT_COLOUR = "tab:red"
OVERLAY_COLOURS = ("tab:red", "tab:green", "tab:blue", "tab:orange", "tab:purple",
                   "tab:brown", "tab:pink", "tab:olive", "tab:cyan", "tab:gray")
BAND_ALPHA = 0.35
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
}
"""Legend label, marker and colour of each kind of special point of a continuation."""
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
CLV_CMAP = "Blues"
"""Colour map of a covariant vector's weight along the chain (0: white)."""
IMPACT_COLOUR = "tab:red"
"""Collisions drawn over the weight of a covariant vector."""
NEAR_TANGENCY = 0.1
"""rad: a smallest angle below this counts as a near-tangency in :func:`clv_angles`."""
LOG_SPAN = 10.0
"""Largest Floquet multipliers spanning more than this factor are drawn on a log scale."""

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


# ------------------------------------------------------------------------------ inputs


@runtime_checkable
class SupportsRun(Protocol):
    """An in-memory result a figure can draw: ``to_run()`` gives its :class:`Run`."""

    def to_run(self) -> Run: ...


RunLike = Union[Run, str, "os.PathLike[str]", SupportsRun]
"""What the figure functions take for one run."""


def as_run(data: RunLike, require: Iterable[str] = (), purpose: str | None = None) -> Run:
    """The :class:`Run` of ``data``: a Run, a file path (read with ``require``, see
    :func:`impactchain.io.read_run`), an object with ``to_run()`` (``impactchain.api``
    results) or the Dataset of :func:`impactchain.api.sweep`."""
    if isinstance(data, Run):
        return data
    if isinstance(data, (str, os.PathLike)):
        return read_run(data, require=require, purpose=purpose)
    if is_sweep_dataset(data):
        return run_from_sweep(data)
    if isinstance(data, SupportsRun):
        run = data.to_run()
        if not isinstance(run, Run):
            raise TypeError(f"{type(data).__name__}.to_run() returned "
                            f"{type(run).__name__}, not an impactchain.io.Run")
        return run
    raise TypeError(f"cannot draw a {type(data).__name__}: give an impactchain.io.Run, a path "
                    "to an impactchain file or an impactchain.api result")


def _as_runs(data: RunLike | Sequence[RunLike], require: Iterable[str] = (),
             purpose: str | None = None) -> list[Run]:
    single = (isinstance(data, (Run, str, os.PathLike)) or isinstance(data, SupportsRun)
              or is_sweep_dataset(data))
    items = [data] if single else list(data)  # type: ignore[arg-type]
    return [as_run(item, require, purpose) for item in items]


# -------------------------------------------------------------------------------- axes


def _axes_list(ax: Axes | Sequence[Axes] | np.ndarray, count: int, what: str) -> list[Axes]:
    """The given axes as a list of ``count`` (a 2-D array is taken row by row)."""
    if isinstance(ax, Axes):
        items = [ax]
    else:
        items = list(np.ravel(np.asarray(ax, dtype=object)))
    if len(items) != count:
        raise FigureError(f"{what} draws into {count} axes, {len(items)} given")
    for item in items:
        if not isinstance(item, Axes):
            raise FigureError(f"{what}: ax holds a {type(item).__name__}, not a "
                              "matplotlib Axes")
    return items


def _root(ax: Axes) -> Figure:
    """The figure holding ``ax`` (the root one when ``ax`` is in a subfigure)."""
    fig: Any = _parent(ax)
    while isinstance(fig, SubFigure):
        fig = fig.figure if fig.figure is not fig else fig.get_figure()
    assert isinstance(fig, Figure)
    return fig


def _parent(ax: Axes) -> Figure | SubFigure:
    """The (sub)figure holding ``ax``: where its colour bar goes."""
    fig = ax.get_figure()
    assert fig is not None
    return fig


def _one_axes(ax: Axes | Sequence[Axes] | np.ndarray | None, width: float, height: float,
              what: str) -> tuple[Figure, Axes]:
    """The one axes a figure draws into: the caller's (and its figure), or a new figure's."""
    if ax is None:
        fig: Figure = _new_figure(width, height)
        return fig, fig.add_subplot()
    (given,) = _axes_list(ax, 1, what)
    return _root(given), given


def _new_figure(width: float, height: float) -> ProvenanceFigure:
    return ProvenanceFigure(figsize=(width, height), layout="constrained")


# -------------------------------------------------------------------------- provenance


@dataclass(frozen=True)
class _Source:
    path: str
    code_version: str
    input_namelist: str
    resolved_namelist: str


_PROVENANCE = "impactchain_sources"


def _record_sources(fig: Figure, runs: Sequence[Run]) -> None:
    """Note on ``fig`` which runs it shows (for :func:`metadata`)."""
    sources: list[_Source] = getattr(fig, _PROVENANCE, None) or []
    for run in runs:
        source = _Source(run.path, run.code_version, run.input_namelist,
                         run.resolved_namelist)
        if source not in sources:
            sources.append(source)
    setattr(fig, _PROVENANCE, sources)


def metadata(fig: Figure, fmt: str = "png") -> dict[str, str]:
    """File metadata of a figure drawn here, for ``savefig(metadata=...)`` in ``fmt``.

    PNG: ``Software`` (impactchain code version of every file shown, the version of
    ``impactchain.figures`` and of matplotlib), ``Title``, ``Source`` (the files, one a
    line), ``Description`` (their input namelists, each after a ``! source:`` line) and
    ``Comment`` (the resolved namelists: every key as used). PDF: ``Creator``, ``Title``,
    ``Subject`` (the inputs), ``Keywords`` (the files). SVG: ``Creator``, ``Title``,
    ``Description``, ``Source``.
    Other formats: none. A figure that shows no run gets only the software versions.
    """
    fmt = fmt.lower().lstrip(".")
    sources: list[_Source] = getattr(fig, _PROVENANCE, None) or []
    versions = list(dict.fromkeys(s.code_version for s in sources if s.code_version))
    code = [v if v.startswith("impactchain") else f"impactchain {v}" for v in versions]
    software = "; ".join([*(code or ["impactchain"]), f"impactchain.figures {__version__}",
                          f"Matplotlib {matplotlib.__version__}"])
    files = "\n".join(s.path for s in sources)
    inputs = "\n".join(f"! source: {s.path}\n{s.input_namelist.rstrip()}" for s in sources
                       if s.input_namelist)
    resolved = "\n".join(f"! source: {s.path}\n{s.resolved_namelist.rstrip()}"
                         for s in sources if s.resolved_namelist)
    title = _figure_title(fig)
    if fmt == "png":
        data = {"Software": software, "Title": title, "Source": files,
                "Description": inputs, "Comment": resolved}
    elif fmt == "pdf":
        data = {"Creator": software, "Title": title, "Subject": inputs, "Keywords": files}
    elif fmt == "svg":
        data = {"Creator": software, "Title": title, "Description": inputs, "Source": files}
    else:
        return {}
    return {key: value for key, value in data.items() if value}


def _figure_title(fig: Figure) -> str:
    suptitle = fig.get_suptitle() if hasattr(fig, "get_suptitle") else ""
    if suptitle:
        return " ".join(suptitle.split())
    for ax in fig.axes:
        if ax.get_title():
            return " ".join(ax.get_title().split())
    return ""


def _format_of(fname: Any, given: str | None) -> str:
    if given:
        return given.lower()
    if isinstance(fname, (str, os.PathLike)):
        suffix = Path(fname).suffix.lower().lstrip(".")
        if suffix:
            return suffix
    return str(matplotlib.rcParams["savefig.format"]).lower()


class ProvenanceFigure(Figure):
    """A Figure whose ``savefig`` writes :func:`metadata` (explicit metadata win)."""

    def savefig(self, fname: Any, **kwargs: Any) -> None:  # type: ignore[override]
        fmt = _format_of(fname, kwargs.get("format"))
        found = metadata(self, fmt)
        if found:
            kwargs["metadata"] = {**found, **(kwargs.get("metadata") or {})}
        super().savefig(fname, **kwargs)


def save(fig: Figure, fname: str | os.PathLike[str] | Any, dpi: float = 150,
         format: str | None = None, **kwargs: Any) -> None:  # noqa: A002
    """``fig.savefig`` with :func:`metadata`, for any figure drawn here (also one made by
    the caller and passed as ``ax=``). ``format``: from the file name by default."""
    fmt = _format_of(fname, format)
    found = metadata(fig, fmt)
    if found:
        kwargs["metadata"] = {**found, **(kwargs.get("metadata") or {})}
    Figure.savefig(fig, fname, dpi=dpi, format=fmt, **kwargs)


# ------------------------------------------------------------------------------ labels


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


def run_labels(runs: Sequence[RunLike], skip: Iterable[str] = ()) -> list[str]:
    """Legend labels telling overlaid runs apart by what differs between them.

    In order: the model parameters that differ (``$A$ = 2.2``; ``skip`` names parameters
    not to use, e.g. a swept one), else the keys of ``&initial`` that differ (``seed 4``),
    else those of ``&run`` (``transient = 500``), else ``run 1``, ``run 2``, ... Never a
    file name.
    """
    runs = [as_run(r) for r in runs]
    if len(runs) < 2:
        return ["" for _ in runs]
    skipped = set(skip)
    model = [name for name in ("n", "amplitude", "omega", "damping", "restitution")
             if name not in skipped and len({getattr(r.params, name) for r in runs}) > 1]
    boundary = len({r.params.boundary for r in runs}) > 1
    spacing = "spacing" not in skipped and len({tuple(r.params.spacing) for r in runs}) > 1
    if model or boundary or spacing:
        labels = []
        for run in runs:
            parts = [f"${_SYMBOLS[name][1]}$ = {getattr(run.params, name):g}"
                     for name in model]
            if spacing:
                a = run.params.spacing
                parts.append(f"$a$ = {a[0]:g}" if np.all(a == a[0]) else "spacing varies")
            if boundary:
                parts.append(f"{run.params.boundary} ends")
            labels.append(", ".join(parts))
        return labels
    for group, describe in (("initial", _initial_label), ("run", _run_group_label)):
        keys = _differing_keys([r.namelist().get(group, {}) for r in runs])
        if keys:
            labels = [describe(r.namelist().get(group, {}), keys) for r in runs]
            if len(set(labels)) == len(labels):
                return labels
    return [f"run {i}" for i in range(1, len(runs) + 1)]


def _value(text: str) -> Any:
    text = text.strip().strip("'\"")
    try:
        return float(text.replace("d", "e").replace("D", "e"))
    except ValueError:
        return text.lower()


def _differing_keys(groups: Sequence[dict[str, str]]) -> list[str]:
    keys = list(dict.fromkeys(k for g in groups for k in g))
    return [k for k in keys
            if len({_value(g[k]) if k in g else None for g in groups}) > 1]


def _shown(text: str) -> str:
    value = _value(text)
    return f"{value:g}" if isinstance(value, float) else str(value)


def _initial_label(group: dict[str, str], keys: Sequence[str]) -> str:
    kind = _shown(group.get("kind", "rest"))
    parts = []
    if "kind" in keys:
        parts.append(f"{kind} start")
    if kind == "random":
        if "seed" in keys or "kind" in keys:
            parts.append(f"seed {_shown(group.get('seed', '1'))}")
        for key, symbol in (("x_amp", r"x_{\mathrm{amp}}"), ("v_amp", r"v_{\mathrm{amp}}")):
            if key in keys and key in group:
                parts.append(f"${symbol}$ = {_shown(group[key])}")
    if kind == "file" and ("file" in keys) and "file" in group:
        parts.append("continued run")
    return ", ".join(parts) or f"{kind} start"


def _run_group_label(group: dict[str, str], keys: Sequence[str]) -> str:
    return ", ".join(f"{key} = {_shown(group[key])}" for key in keys
                     if key in group and key in ("transient", "cycles", "phase",
                                                 "stick_speed"))


# ------------------------------------------------------------------------ space-amplitude


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


# ------------------------------------------------------------------- space-time-amplitude


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


# ------------------------------------------------------------------------------ shock-wave


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


# -------------------------------------------------------------------------------- poincare


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


# ---------------------------------------------------------------------------- bifurcation


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


# ------------------------------------------------------------------------------- lyapunov


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


# --------------------------------------------------------------------------- ky-dimension


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


# ------------------------------------------------------------------ covariant vectors


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


# ------------------------------------------------------------------ finite-time exponents


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


# --------------------------------------------------------------------------- continuation


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


# --------------------------------------------------------------------------------- census


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
