"""The file schema: every dataset, coordinate, dimension and attribute of the four kinds of
file (a run's, a sweep's, a continuation's, a census's), as ``impactchain --schema`` prints
them, read from the compiled extension; the table's one home is the Fortran
(src/runs/chain_file_table.f90), never re-typed here.

Each entry of :func:`outputs` is a dict with ``file``, ``path`` (``/group/name``, or
``/group/@name`` for an attribute), ``kind`` (``dataset``, ``attribute``, or ``dimension``: a
netCDF dimension without values), ``dims`` (h5py's order; ``name?`` only in a 2-D sweep,
``a|b`` either one: the axis a sweep's omega runs along), ``dtype``, ``units``,
``model_units`` (the reduced unit, ``None`` for none; ``{parameter}``: that of the swept or
continued parameter, whose name ``{parameter}`` stands for in ``long_name``), ``long_name``
and ``when`` (``always``, ``header``: the start of every kind of file, or the input that
makes a file hold it, in words).
"""
from __future__ import annotations

import copy
import functools
import json
from typing import Any

import numpy as np

__all__ = ["outputs", "output", "parameter_units", "label_units", "dims", "attributes",
           "variable", "parameter_label_units", "dataset_units"]

PARAMETER = "{parameter}"


@functools.cache
def _outputs() -> tuple[dict[str, Any], ...]:
    from impactchain.api import _extension

    text_len, text = _extension().ic_output_schema()
    if text_len > len(text):
        raise RuntimeError(f"ic_output_schema: {text_len} bytes do not fit its buffer of "
                           f"{len(text)}")
    return tuple(json.loads(bytes(np.asarray(text[:text_len]).astype(np.uint8)).decode()))


def outputs() -> list[dict[str, Any]]:
    """Every entry of the file schema, in the order a file is written (a fresh copy)."""
    return copy.deepcopy(list(_outputs()))


def output(path: str, when: str | None = None) -> dict[str, Any]:
    """The entry of ``path`` (``/strobe/x``, ``/params/@omega``; the leading ``/``
    optional); where two entries share a path (``/census/point``), the one of ``when``."""
    key = path if path.startswith("/") else "/" + path
    for entry in _outputs():
        if entry["path"] == key and (when is None or entry["when"] == when):
            return copy.deepcopy(entry)
    raise KeyError(f"the file schema has no entry {key!r}")


def parameter_units(name: str) -> str | None:
    """The reduced unit of model parameter ``name`` (that of its ``/params`` entry), ``None``
    for a pure number."""
    for path in (f"/params/@{name}", f"/params/{name}"):
        try:
            return output(path)["model_units"]
        except KeyError:
            pass
    raise KeyError(f"{name!r} is not a parameter of /params")


def label_units(path: str, parameter: str | None = None) -> str:
    """The unit an axis label shows for ``path``: its reduced unit, else its UDUNITS unit
    (``1`` for a pure number); ``parameter`` resolves ``{parameter}``."""
    entry = output(path)
    units = entry["model_units"]
    if units == PARAMETER:
        units = parameter_units(parameter) if parameter else None
    return units or entry["units"] or "1"


def dims(entry: dict[str, Any], axes: int = 1, along: int = 1) -> tuple[str, ...]:
    """The entry's dimensions in one file: ``name?`` kept only with ``axes`` = 2 (a 2-D
    sweep), of ``a|b`` the ``along``-th."""
    names = []
    for name in entry["dims"]:
        if name.endswith("?"):
            if axes != 2:
                continue
            name = name[:-1]
        if "|" in name:
            name = name.split("|")[along - 1]
        names.append(name)
    return tuple(names)


def attributes(entry: dict[str, Any], parameter: str | None = None) -> dict[str, str]:
    """The attributes a file gives the entry's dataset: ``long_name``, ``units`` and, when it
    has one, ``model_units`` (``parameter`` resolves ``{parameter}``)."""
    long_name = entry["long_name"]
    model_units = entry["model_units"]
    if parameter is not None:
        long_name = long_name.replace(PARAMETER, parameter)
    if model_units == PARAMETER:
        model_units = parameter_units(parameter) if parameter else None
    attrs = {"long_name": long_name, "units": entry["units"]}
    if model_units:
        attrs["model_units"] = model_units
    return attrs


def variable(path: str, values: Any, parameter: str | None = None, axes: int = 1,
             along: int = 1) -> tuple[tuple[str, ...], Any, dict[str, str]]:
    """``(dims, values, attrs)`` of dataset ``path`` as a file holds it: xarray's form of a
    variable."""
    entry = output(path)
    return (dims(entry, axes, along), values, attributes(entry, parameter))


def parameter_label_units(name: str) -> str:
    """The unit an axis label shows for model parameter ``name`` (``1`` for a pure number
    or a name /params does not hold)."""
    for path in (f"/params/@{name}", f"/params/{name}"):
        try:
            return label_units(path)
        except KeyError:
            pass
    return "1"


def dataset_units() -> dict[str, str]:
    """``group/name`` -> the unit an axis label shows, for every dataset whose unit is its
    own (not a swept parameter's)."""
    return {entry["path"][1:]: label_units(entry["path"]) for entry in _outputs()
            if entry["kind"] == "dataset" and entry["model_units"] != PARAMETER}
