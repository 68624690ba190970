"""Where a figure is drawn and how it is saved: the caller's axes or a new figure, and the
provenance (code version, inputs, source files) written into the saved file's metadata.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure, SubFigure

from impactchain import __version__
from impactchain.figures._style import FigureError
from impactchain.results import Run


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
