"""What a figure takes: a run, a path to a file or an in-memory result of
:mod:`impactchain.api`, made a :class:`impactchain.io.Run`; the legend labels telling overlaid
runs apart; the parts of a run each figure needs, with a :class:`FigureError` when absent.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from typing import Any, Protocol, Union, runtime_checkable

import numpy as np

from impactchain.analysis import panel_ranges
from impactchain.figures._style import _SYMBOLS, FigureError
from impactchain.inmemory import (is_continuation_dataset, is_curve_tree, is_sweep_dataset,
                                  is_tree, run_from_continuation, run_from_curve, run_from_sweep,
                                  run_from_tree)
from impactchain.io import read_run
from impactchain.results import Run, Strobe, Sweep


@runtime_checkable
class SupportsRun(Protocol):
    """An in-memory result a figure can draw: ``to_run()`` gives its :class:`Run`."""

    def to_run(self) -> Run: ...


RunLike = Union[Run, str, "os.PathLike[str]", SupportsRun, Any]
"""What the figure functions take for one run: a :class:`Run`, a path to a file, an
:mod:`impactchain.api` result, an xarray tree of a file (``xarray.open_datatree(path)``, an
api result's ``to_xarray()``), the Dataset of ``api.sweep`` or ``api.continuation``, or the
tree of ``api.curve``."""


def as_run(data: RunLike, require: Iterable[str] = (), purpose: str | None = None) -> Run:
    """The :class:`Run` of ``data``: a Run, a file path (read with ``require``, see
    :func:`impactchain.io.read_run`), an object with ``to_run()`` (``impactchain.api``
    results), an xarray tree of a file, the Dataset of :func:`impactchain.api.sweep` or
    :func:`impactchain.api.continuation`, or the tree of :func:`impactchain.api.curve`."""
    if isinstance(data, Run):
        return data
    if isinstance(data, (str, os.PathLike)):
        return read_run(data, require=require, purpose=purpose)
    if is_curve_tree(data):
        return run_from_curve(data)
    if is_tree(data):
        return run_from_tree(data, require, purpose)
    if is_sweep_dataset(data):
        return run_from_sweep(data)
    if is_continuation_dataset(data):
        return run_from_continuation(data)
    if isinstance(data, SupportsRun):
        run = data.to_run()
        if not isinstance(run, Run):
            raise TypeError(f"{type(data).__name__}.to_run() returned "
                            f"{type(run).__name__}, not an impactchain.io.Run")
        return run
    if callable(getattr(data, "to_xarray", None)) and not hasattr(data, "data_vars"):
        return as_run(data.to_xarray(), require, purpose)  # (api.PeriodicOrbit)
    raise TypeError(f"cannot draw a {type(data).__name__}: give an impactchain.io.Run, a path "
                    "to an impactchain file, an xarray tree of one or an impactchain.api "
                    "result")


def _as_runs(data: RunLike | Sequence[RunLike], require: Iterable[str] = (),
             purpose: str | None = None) -> list[Run]:
    single = (isinstance(data, (Run, str, os.PathLike)) or isinstance(data, SupportsRun)
              or is_tree(data) or hasattr(data, "data_vars")  # (a Dataset is one result)
              or hasattr(data, "to_xarray"))
    items = [data] if single else list(data)  # type: ignore[arg-type]
    return [as_run(item, require, purpose) for item in items]


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


def _differing_parameters(runs: Sequence[Run]) -> list[str]:
    """Model parameters whose values differ between overlaid runs (for their labels)."""
    names = ("amplitude", "omega", "damping", "restitution")
    return [name for name in names
            if len({getattr(run.params, name) for run in runs}) > 1]


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
