"""The program's two tables, as ``impactchain --schema`` prints them and the compiled extension
states them (their one home is the Fortran, never re-typed here).

The input schema (src/runs/chain_inputs.f90): every namelist key with its group, type,
default, allowed range, units and help. :func:`inputs` returns it; :func:`default` gives one
key's default, which the functions of :mod:`impactchain.api` use.

The file schema (src/runs/chain_file_table.f90): every dataset, coordinate, dimension and
attribute of the four kinds of file (a run's, a sweep's, a continuation's, a census's).
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
import inspect
import json
from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["inputs", "default", "key", "with_schema_defaults", "SCHEMA_DEFAULT",
           "outputs", "output", "groups", "parameter_units", "label_units", "dims", "attributes",
           "variable", "parameter_label_units", "dataset_units"]


@functools.lru_cache(maxsize=1)
def _inputs() -> tuple[dict[str, Any], ...]:
    from impactchain import _kernels

    text_len, text = _kernels.ic_input_schema()
    if text_len < 0:
        raise RuntimeError(f"the input schema needs {-text_len} bytes, more than the "
                           "extension's buffer")
    return tuple(json.loads(bytes(np.asarray(text[:text_len]).astype(np.uint8)).decode()))


def inputs() -> list[dict[str, Any]]:
    """Every input key, in group order then table order: dicts with ``group``, ``name``,
    ``type``, ``list``, ``required``, ``default`` (``None`` when required or when it depends
    on other keys), ``default_text``, ``range``, ``min``, ``max``, ``choices``, ``units`` and
    ``help`` (the ``"inputs"`` of ``impactchain --schema``)."""
    return [dict(k) for k in _inputs()]


def key(group: str, name: str) -> dict[str, Any]:
    """The schema of ``&group name``."""
    for k in _inputs():
        if k["group"] == group and k["name"] == name:
            return dict(k)
    raise KeyError(f"&{group}: no key {name!r} in the input schema")


def default(group: str, name: str) -> Any:
    """The default of ``&group name`` as the reader uses it (``None``: required, or it
    depends on other keys)."""
    return key(group, name)["default"]


class _SchemaDefault:
    """The default of a function parameter that the input schema gives (see
    :func:`with_schema_defaults`); shown as such where the extension is not built."""

    def __repr__(self) -> str:
        return "<the input schema's default>"


SCHEMA_DEFAULT: Any = _SchemaDefault()

#: Groups searched, in order, for the key a parameter names
_GROUPS = ("chain", "initial", "run", "lyapunov", "output", "continuation", "sweep", "census")
#: Parameters named otherwise than their key
_ALIASES = {"events": ("run", "record_events")}


def _key_of(name: str) -> tuple[str, str]:
    if name in _ALIASES:
        return _ALIASES[name]
    for group in _GROUPS:
        if any(k["group"] == group and k["name"] == name for k in _inputs()):
            return group, name
    raise KeyError(f"no input key for the parameter {name!r}")


def with_schema_defaults(func: Callable[..., Any] | None = None, /,
                         **keys: tuple[str, str]) -> Any:
    """``func`` whose parameters defaulting to :data:`SCHEMA_DEFAULT` take the default of
    an input key: the one ``keys`` names for the parameter (``period=("lyapunov",
    "jacobian_cycles")``), else the key of the same name, first in &chain, &initial, &run,
    &lyapunov, &output, &continuation, &sweep, &census. Its signature (and so ``help()``)
    shows them, and a call without them passes them. Without the extension the signature
    keeps the marker and a call reads the schema (and so says the extension is missing)."""
    if func is None:
        return functools.partial(with_schema_defaults, **keys)
    signature = inspect.signature(func)
    marked = [p.name for p in signature.parameters.values() if p.default is SCHEMA_DEFAULT]

    def resolved() -> inspect.Signature:
        return signature.replace(parameters=[
            p.replace(default=default(*(keys[p.name] if p.name in keys else _key_of(p.name))))
            if p.name in marked else p for p in signature.parameters.values()])

    @functools.wraps(func)
    def call(*args: Any, **kwargs: Any) -> Any:
        bound = resolved().bind(*args, **kwargs)
        bound.apply_defaults()
        return func(*bound.args, **bound.kwargs)

    try:
        call.__signature__ = resolved()  # type: ignore[attr-defined]
    except ImportError:
        call.__signature__ = signature  # type: ignore[attr-defined]
    return call


PARAMETER = "{parameter}"


@functools.cache
def _outputs() -> tuple[dict[str, Any], ...]:
    from impactchain._calls import _extension

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


@functools.cache
def groups() -> tuple[str, ...]:
    """The groups of the file schema (``params``, ``strobe`` ...), in the order of
    :func:`outputs`."""
    names = (entry["path"].split("/")[1] for entry in _outputs())
    return tuple(dict.fromkeys(name for name in names if not name.startswith("@")))


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
