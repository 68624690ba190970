"""Read impactchain HDF5 output (schema_version 2, and the older version 1).

This is the only module that knows the file layout and its axis order. Everything
else in ``impactchain`` works on the frozen dataclasses returned by :func:`read_run`, whose
arrays are read-only numpy arrays with the record axis first:

========================  ======================  ===================================
HDF5 path                 dataclass field         shape (h5py / numpy order)
========================  ======================  ===================================
/params (attributes)      ``Run.params``          scalars; ``spacing`` (n+1,)
/initial, /final          ``Run.initial/final``   ``x``, ``v`` (n,)
/strobe                   ``Run.strobe``          ``x``, ``v`` (n_record, n); ``cycle``;
                                                  ``period`` (n,)
/events                   ``Run.events``          ``time``, ``site``, ... (n_events,)
/stats                    ``Run.stats``           ``site_counts`` (n+1,), ``cycles_done``
/lyapunov                 ``Run.lyapunov``        ``exponents`` (k,), ``running`` (m, k),
                                                  ``running_cycle`` (m,), ``ky_dimension``,
                                                  ``stderr_block`` (k,)
/finite_time              ``Run.finite_time``     ``exponents`` (w, k), ``cycle`` (w,),
                                                  ``window``
/sweep                    ``Run.sweep``           ``x`` (n_points, cycles, n), ``period``
                                                  (n_points, n), ``exponents`` (n_points,
                                                  k), ``ky_dimension`` (n_points,)
/continuation             ``Run.continuation``    ``values`` (P,), ``x`` (P, n),
                                                  ``strobe_x`` (P, L, n), ``multipliers_re``
                                                  (P, 2n), ``special_index`` (S,), ...
/curve                    ``Run.curve``           ``values``, ``values2`` (C,), ``x`` (C, n),
                                                  ``multipliers_re`` (C, 2n), ...
/census                   ``Run.census``          ``x0``, ``v0`` (P, N, n),
                                                  ``sample_attractor`` (P, N),
                                                  ``sample_exponents`` (P, N, k),
                                                  ``attractor_period`` (A, n),
                                                  ``attractor_exponents`` (A, k),
                                                  ``fraction`` (P, A), ...
/clv                      ``Run.clv``             ``cycle`` (R,), ``ipr`` (R, k),
                                                  ``site_weight`` (R, m, n), ``min_angle``
                                                  (R,), ``exponents`` (k,), ``vectors``
                                                  (r, k, 2n), ...
========================  ======================  ===================================

Version 2 (README "Output") is netCDF-4 readable: every group carries its dimensions and
coordinates (``xarray.open_dataset(path, engine="h5netcdf", group="strobe")``), a sweep
stores its parameter values as the coordinates ``/sweep/point`` (and ``point2``), a 2-D
sweep's per-point datasets as (point, point2, ...), and ``/params`` lacks the swept
parameters (``NaN`` in :class:`Params`; ``drive_period`` too in an omega sweep, whose
``Sweep.drive_period`` has it per point). A continuation file (periodic orbits followed in
one parameter) is laid out the same way: ``/continuation`` with the dimensions ``point``,
``oscillator``, ``multiplier``, ``iterate`` and ``special``, and ``/params`` without the
continued parameter; so is a census file (attractors and their basin fractions, at one point
or along a swept parameter): ``/census`` with ``point``, ``sample``, ``oscillator``,
``attractor``, ``bond`` and ``exponent``, and ``/params`` without the swept parameter. This module
returns both versions in the same dataclasses, a 2-D sweep's points flattened in version 1's
order (the first parameter varying fastest), so nothing downstream depends on the version.

Every group except ``/params`` is optional; a figure states what it needs through
``read_run(path, require=...)`` and gets a :class:`SchemaError` naming the missing
piece when the file lacks it. The Fortran writer stores arrays as ``(n, n_record)``
so that they appear here as ``(n_record, n)``; a file with the other order is rejected
rather than silently transposed. Periods, exponents and Kaplan-Yorke dimensions are the
simulator's, as stored; nothing in ``impactchain`` computes them again.

Every path this module and ``_readers`` read or test for is an entry of the file schema
(:mod:`impactchain.schema`, the table the simulator writes by), resolved before the file is
looked at: a name the table lacks is a :class:`~impactchain._hdf5.ReaderPathError` at once, and
so is a rank other than its dims'; the types of ``/params`` are the table's dtypes. Only
``/sweep/values`` of version 1 is not in the table. ``Run.units`` keeps what the file itself
says (a version-1 file's own units).

The dataclasses live in :mod:`impactchain.results`, one reader per group in ``_readers``, the
namelist text in :mod:`impactchain.namelist` and runs made in memory in
:mod:`impactchain.inmemory`; this module reads files and names all of them, as before.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Iterable
from types import MappingProxyType
from typing import Any

import h5py
import numpy as np

from impactchain._hdf5 import (SchemaError, _attr, _collect_units, _dataset, _entry, _float,
                               _frozen, _group, _has, _has_attr, _int, _str, _version)
from impactchain._readers import (_read_census, _read_clv, _read_continuation, _read_curve,
                                  _read_events, _read_final, _read_finite_time, _read_lyapunov,
                                  _read_state, _read_stats, _read_strobe, _read_sweep)
from impactchain.inmemory import IN_MEMORY, is_sweep_dataset, run_from_api, run_from_sweep
# (impactchain.api imports the namelist writer from here under this name)
from impactchain.namelist import equivalent_namelist as _equivalent_namelist
from impactchain.namelist import namelist_groups
from impactchain.results import (ATTRACTOR_KINDS, FILE_UNITS, IMPACT, RELEASE, SCHEMA_VERSION,
                                 SPECIAL_KINDS, STICK, TOUCH, Census, Clv, Continuation, Curve,
                                 Events, FinalState, FiniteTime, Lyapunov, Params, Run, State,
                                 Stats, Strobe, Sweep, period_pattern)


__all__ = [
    "SCHEMA_VERSION",
    "READABLE_VERSIONS",
    "IMPACT",
    "STICK",
    "RELEASE",
    "TOUCH",
    "SchemaError",
    "Params",
    "State",
    "FinalState",
    "Strobe",
    "Events",
    "Stats",
    "Lyapunov",
    "Sweep",
    "SPECIAL_KINDS",
    "Continuation",
    "Curve",
    "ATTRACTOR_KINDS",
    "Census",
    "period_pattern",
    "Clv",
    "FiniteTime",
    "Run",
    "FILE_UNITS",
    "read_run",
    "read_continuation",
    "read_curve",
    "read_census",
    "run_from_api",
    "run_from_sweep",
    "is_sweep_dataset",
    "namelist_groups",
]


READABLE_VERSIONS = (1, 2)
"""The file layouts this module reads."""


OPTIONAL_GROUPS = ("initial", "final", "strobe", "events", "stats", "lyapunov", "sweep",
                   "continuation", "curve", "census", "clv", "finite_time")

_HINTS = {
    "strobe": "the run recorded no strobe snapshots",
    "events": "events were not recorded in this run",
    "lyapunov": "Lyapunov exponents were not computed in this run",
    "sweep": "this is not a parameter-sweep file",
    "sweep/exponents": "the sweep did not compute Lyapunov exponents",
    "sweep/ky_dimension": "the sweep did not compute Lyapunov exponents",
    "continuation": "this is not a continuation file",
    "curve": "the continuation followed no curve: no &continuation follow in its input",
    "census": "this is not a census file (no &census in its input)",
    "clv": "covariant Lyapunov vectors were not computed in this run: &lyapunov covariant = "
           ".false.",
    "clv/site_weight": "the run stored no site weights of covariant vectors: &lyapunov "
                       "clv_store = 0, or no covariant = .true.",
    "finite_time": "the run computed no finite-time Lyapunov exponents: &lyapunov window = 0",
}


def read_run(
    path: str | os.PathLike[str],
    require: Iterable[str] = (),
    groups: Iterable[str] | None = None,
    purpose: str | None = None,
) -> Run:
    """Read an impactchain output file.

    ``require`` lists HDF5 paths relative to the root (``'events'``,
    ``'sweep/exponents'``); an entry ``'a|b'`` is satisfied by either. A missing one
    raises :class:`SchemaError`, whose message names ``purpose`` (e.g. the figure).
    ``groups`` restricts which optional groups are loaded (all present ones when None);
    required groups are always loaded.
    """
    path = os.fspath(path)
    _check_file(path)
    try:
        with h5py.File(path, "r") as f:
            _check_schema(f, path)
            _check_required(f, path, require, purpose)
            wanted = _wanted_groups(require, groups)
            return _read(f, path, wanted)
    except OSError as exc:
        raise SchemaError(f"{path}: cannot read HDF5 file ({exc})") from exc
    except KeyError as exc:
        raise SchemaError(f"{path}: malformed file ({exc})") from exc


def read_continuation(path: str | os.PathLike[str]) -> Continuation:
    """The ``/continuation`` group of a continuation file (:class:`SchemaError` when the file
    has none); ``read_run(path).continuation`` with the rest of the file."""
    run = read_run(path, require=("continuation",), groups=("continuation",))
    assert run.continuation is not None
    return run.continuation


def read_curve(path: str | os.PathLike[str]) -> Curve:
    """The ``/curve`` group of a continuation file with ``&continuation follow``
    (:class:`SchemaError` when the file has none); ``read_run(path).curve``."""
    run = read_run(path, require=("curve",), groups=("curve",))
    assert run.curve is not None
    return run.curve


def read_census(path: str | os.PathLike[str]) -> Census:
    """The ``/census`` group of a census file (:class:`SchemaError` when the file has
    none); ``read_run(path).census`` with the rest of the file."""
    run = read_run(path, require=("census",), groups=("census",))
    assert run.census is not None
    return run.census


def _check_file(path: str) -> None:
    if not os.path.exists(path):
        raise SchemaError(f"{path}: no such file")
    if not os.path.isfile(path):
        raise SchemaError(f"{path}: not a regular file")
    if not h5py.is_hdf5(path):
        raise SchemaError(f"{path}: not an HDF5 file")


def _check_schema(f: h5py.File, path: str) -> None:
    if not _has_attr(f, "schema_version"):
        raise SchemaError(
            f"{path}: no 'schema_version' attribute; not an impactchain output file"
        )
    version = _version(f, path)
    if version not in READABLE_VERSIONS:
        raise SchemaError(
            f"{path}: schema_version {version} is not supported (this impactchain package "
            f"reads schema_version {' and '.join(map(str, READABLE_VERSIONS))})"
        )
    if not _group(f, "params"):
        raise SchemaError(f"{path}: no /params group")


def _check_required(
    f: h5py.File, path: str, require: Iterable[str], purpose: str | None
) -> None:
    for entry in require:
        options = [item.strip("/") for item in entry.split("|")]
        if any(_present(f, option) for option in options):
            continue
        names = " or ".join(f"/{option}" for option in options)
        need = f", needed by {purpose}" if purpose else ""
        hint = _HINTS.get(options[0])
        reason = f" ({hint})" if hint else ""
        raise SchemaError(f"{path}: no {names}{need}{reason}")


def _present(f: h5py.File, option: str) -> bool:
    """Whether the file has ``option``, a group (``events``) or dataset (``sweep/exponents``)
    of the file schema."""
    group, _, name = option.partition("/")
    if not name:
        return _group(f, group)
    if not _group(f, group):
        _has(f, option)  # the path must be the table's even where the group is absent
        return False
    return _has(f[group], name)


def _wanted_groups(require: Iterable[str], groups: Iterable[str] | None) -> set[str]:
    if groups is None:
        return set(OPTIONAL_GROUPS)
    wanted = {g.strip("/") for g in groups}
    for entry in require:
        wanted.update(item.strip("/").split("/")[0] for item in entry.split("|"))
    return wanted


def _read(f: h5py.File, path: str, wanted: set[str]) -> Run:
    params = _read_params(f, path)
    n = params.n
    readers = {
        "initial": lambda g: _read_state(g, path, n),
        "final": lambda g: _read_final(g, path, n),
        "strobe": lambda g: _read_strobe(g, path, n),
        "events": lambda g: _read_events(g, path, n),
        "stats": lambda g: _read_stats(g, path, n),
        "lyapunov": lambda g: _read_lyapunov(g, path),
        "sweep": lambda g: _read_sweep(g, path, n),
        "continuation": lambda g: _read_continuation(g, path, n),
        "curve": lambda g: _read_curve(g, path, n),
        "census": lambda g: _read_census(g, path, n),
        "clv": lambda g: _read_clv(g, path, n),
        "finite_time": lambda g: _read_finite_time(g, path),
    }
    parts: dict[str, Any] = {}
    for name, reader in readers.items():
        if name in wanted and _group(f, name):
            parts[name] = reader(f[name])
    return Run(
        path=path,
        schema_version=_version(f, path),
        code_version=_str(_attr(f, path, "code_version", "")),
        input_namelist=_str(_attr(f, path, "input_namelist", "")),
        complete=bool(_int(_attr(f, path, "complete", 1), path, "complete")),
        params=params,
        units=MappingProxyType(_collect_units(f)),
        resolved_namelist=_str(_attr(f, path, "resolved_namelist", "")),
        **parts,
    )


def _read_params(f: h5py.File, path: str) -> Params:
    g = f["params"]
    # a version-2 sweep leaves out what differs from point to point, a continuation its
    # parameter
    swept = set(_swept(f, path)) if _group(f, "sweep") and _version(f, path) >= 2 else set()
    if _group(f, "continuation"):
        swept.add(_str(_attr(f["continuation"], path, "parameter")))
    if _group(f, "census") and _str(_attr(f["census"], path, "parameter", "")):
        swept.add(_str(_attr(f["census"], path, "parameter")))
    if "omega" in swept:
        swept.add("drive_period")
    types = _param_types(g)
    attrs = {name: math.nan if name in swept and not _has_attr(g, name)
             else _attr(g, path, name) for name in types}
    n = _int(attrs["n"], path, "params/n")
    if n < 1:
        raise SchemaError(f"{path}: /params n = {n} must be >= 1")
    if "spacing" in swept and not _has(g, "spacing"):
        spacing = _frozen(np.full(n + 1, math.nan))
    else:
        spacing = _dataset(g, path, "spacing", (n + 1,), float)
    values: dict[str, Any] = {}
    for name, kind in types.items():
        where = f"params/{name}"
        if kind is int:
            values[name] = _int(attrs[name], path, where)
        elif kind is float:
            values[name] = _float(attrs[name], path, where)
        else:
            values[name] = _str(attrs[name])
    values["spacing"] = spacing
    return Params(**values)


#: The Python type of each of the file schema's dtypes
_TYPES: dict[str, type] = {"int32": int, "int64": int, "float64": float, "string": str}


def _param_types(g: h5py.Group) -> dict[str, type]:
    """The attributes of /params that :class:`Params` holds, each with the type its dtype
    in the file schema reads as (``spacing``, a dataset, apart)."""
    return {field.name: _TYPES[_entry(g, field.name, attribute=True)["dtype"]]
            for field in dataclasses.fields(Params) if field.name != "spacing"}


def _swept(f: h5py.File, path: str) -> list[str]:
    """The swept parameters of a sweep's file."""
    g = f["sweep"]
    names = [_str(_attr(g, path, "parameter"))]
    if _str(_attr(g, path, "parameter2", "")):
        names.append(_str(_attr(g, path, "parameter2")))
    return names
