"""Checked reads of HDF5 attributes and datasets into read-only numpy arrays, each failure a
:class:`SchemaError` naming the file and the object, and the order in which a 2-D sweep's points
are listed (version 1's flat list, point p = i + n1 j).

Every name a reader passes here is resolved in the file schema (:mod:`impactchain.schema`)
before the file is looked at: a reader naming a path the table lacks fails at once with
:class:`ReaderPathError`, whatever the file holds, and a shape a version-2 file gets wrong is
reported with the table's dimension names.
"""

from __future__ import annotations

from typing import Any

import h5py
import numpy as np

from impactchain import schema


class SchemaError(ValueError):
    """The file is missing, not HDF5, of another schema, or lacks needed data."""


class ReaderPathError(LookupError):
    """A reader names a path the file schema lacks: a fault of the reader, not of the file
    (not a KeyError, so that no caller takes it for a malformed file)."""


#: What a schema_version 1 file holds under a path that version 2, the one the file schema
#: describes, no longer writes (a sweep's values are version 2's /sweep/point and point2)
VERSION1_PATHS = frozenset({"/sweep/values"})

_REQUIRED = object()


def _entry(g: h5py.Group, name: str, attribute: bool = False) -> dict[str, Any] | None:
    """The file schema's entry of ``g/name`` (``g/@name`` for an attribute); ``None`` for a
    path of :data:`VERSION1_PATHS`."""
    where = f"{g.name.rstrip('/')}/{'@' if attribute else ''}{name}"
    if where in VERSION1_PATHS:
        return None
    try:
        return schema.output(where)
    except KeyError:
        raise ReaderPathError(f"the reader names {where}, which the file schema lacks "
                              "(impactchain --schema)") from None


def _group(f: h5py.File, name: str) -> bool:
    """Whether the file has group ``/name``, a group of the file schema."""
    if name not in schema.groups():
        raise ReaderPathError(f"the reader names the group /{name}, which the file schema "
                              "lacks (impactchain --schema)")
    return name in f


def _has(g: h5py.Group, name: str) -> bool:
    """Whether the file has dataset ``g/name``, an entry of the file schema."""
    _entry(g, name)
    return name in g


def _has_attr(g: h5py.Group, name: str) -> bool:
    """Whether the file has attribute ``g/@name``, an entry of the file schema."""
    _entry(g, name, attribute=True)
    return name in g.attrs


def _version(g: h5py.Group, path: str) -> int:
    return _int(_attr(g.file, path, "schema_version"), path, "schema_version")


def _dims(g: h5py.Group, path: str, entry: dict[str, Any] | None,
          rank: int) -> tuple[str, ...] | None:
    """The table's dimension names of a dataset read with ``rank`` axes from a version-2
    file (``None`` for version 1, whose layout the table does not describe); a rank the
    table does not give the entry is the reader's fault."""
    if entry is None or _version(g, path) < 2:
        return None
    for axes in (1, 2):  # a 2-D sweep's datasets have the axis point2 too
        names = schema.dims(entry, axes)
        if len(names) == rank:
            return names
    raise ReaderPathError(f"the reader reads {entry['path']} with {rank} axes; the file "
                          f"schema gives it the dims {tuple(entry['dims'])}")


def _frozen(values: Any) -> np.ndarray:
    out = np.array(values, dtype=np.float64 if np.asarray(values).dtype.kind == "f"
                   else np.asarray(values).dtype)
    out.setflags(write=False)
    return out


def _point_values(point: np.ndarray, point2: np.ndarray | None) -> np.ndarray:
    """A sweep's parameter values as version 1 lists them: (n1,), or (n1 n2, 2) with point
    p = i + n1 j at (point[i], point2[j])."""
    if point2 is None:
        return np.array(point)
    return np.column_stack([np.tile(point, point2.size), np.repeat(point2, point.size)])


def _flat_points(data: np.ndarray, two_d: bool) -> np.ndarray:
    """Per-point data (n1, [n2,] ...) as version 1 lists it: (n1 n2, ...), p = i + n1 j."""
    if not two_d:
        return data
    n1, n2 = data.shape[:2]
    return np.swapaxes(data, 0, 1).reshape((n1 * n2,) + data.shape[2:])


def _attr(g: h5py.Group, path: str, name: str, default: Any = _REQUIRED) -> Any:
    """Attribute ``g/@name``; when the file lacks it, ``default`` if one is given, else a
    :class:`SchemaError`."""
    _entry(g, name, attribute=True)
    if name not in g.attrs:
        if default is not _REQUIRED:
            return default
        raise SchemaError(f"{path}: {g.name} lacks attribute '{name}'")
    return g.attrs[name]


def _dataset(
    g: h5py.Group,
    path: str,
    name: str,
    shape: tuple[int | None, ...] | None,
    dtype: type,
) -> np.ndarray:
    """Read ``g/name`` as a read-only array, checking its shape (None = any extent).

    ``shape=None`` reads a scalar (shape () or (1,)).
    """
    where = f"{g.name}/{name}"
    entry = _entry(g, name)
    if name not in g:
        raise SchemaError(f"{path}: no {where} dataset")
    obj = g[name]
    if not isinstance(obj, h5py.Dataset):
        raise SchemaError(f"{path}: {where} is not a dataset")
    dims = _dims(g, path, entry, 0 if shape is None else len(shape))
    data = np.asarray(obj[()])
    if shape is None:
        if data.size != 1:
            raise SchemaError(f"{path}: {where} should be a scalar, found shape {data.shape}")
        data = data.reshape(())
    else:
        _check_shape(data.shape, shape, path, where, dims)
    out = np.array(data, dtype=np.float64 if dtype is float else np.int64)
    out.setflags(write=False)
    return out


def _strings(g: h5py.Group, path: str, name: str, shape: tuple[int | None, ...]) -> np.ndarray:
    """Read the string dataset ``g/name`` (variable- or fixed-length) as a read-only array
    of str, checking its shape."""
    where = f"{g.name}/{name}"
    entry = _entry(g, name)
    if name not in g:
        raise SchemaError(f"{path}: no {where} dataset")
    obj = g[name]
    if not isinstance(obj, h5py.Dataset) or obj.dtype.kind not in "SUO":
        raise SchemaError(f"{path}: {where} is not a dataset of strings")
    data = np.asarray(obj[()], dtype=object)
    _check_shape(data.shape, shape, path, where, _dims(g, path, entry, len(shape)))
    out = np.array([_str(item) for item in data.reshape(-1)], dtype=str).reshape(data.shape)
    out.setflags(write=False)
    return out


def _check_shape(
    found: tuple[int, ...], expected: tuple[int | None, ...], path: str, where: str,
    dims: tuple[str, ...] | None = None,
) -> None:
    ok = len(found) == len(expected) and all(
        e is None or f == e for f, e in zip(found, expected)
    )
    if ok:
        return
    want = "(" + ", ".join("*" if e is None else str(e) for e in expected) + ")"
    message = f"{path}: {where} has shape {found}, expected {want}"
    if len(found) == len(expected) == 2 and found[::-1] != found:
        flipped = all(e is None or f == e for f, e in zip(found[::-1], expected))
        if flipped:
            message += " (axes transposed: the record axis must come first in h5py order)"
    if dims is not None:
        message += f"; its dims in the file schema: ({', '.join(dims)})"
    raise SchemaError(message)


def _collect_units(f: h5py.File) -> dict[str, str]:
    units: dict[str, str] = {}

    def visit(name: str, obj: Any) -> None:
        # version 2: the reduced unit in model_units (units is UDUNITS': 1 for it)
        for key in ("model_units", "units"):
            if isinstance(obj, h5py.Dataset) and key in obj.attrs:
                units[name] = _str(obj.attrs[key])
                break

    f.visititems(visit)
    return units


def _item(value: Any) -> Any:
    arr = np.asarray(value)
    if arr.size != 1:
        raise ValueError(f"expected a single value, found shape {arr.shape}")
    return arr.reshape(-1)[0]


def _int(value: Any, path: str, where: str) -> int:
    try:
        item = _item(value)
        number = int(item)
        if number != item:
            raise ValueError(f"{item!r} is not an integer")
        return number
    except (TypeError, ValueError) as exc:
        raise SchemaError(f"{path}: {where} is not an integer ({exc})") from exc


def _float(value: Any, path: str, where: str) -> float:
    try:
        return float(_item(value))
    except (TypeError, ValueError) as exc:
        raise SchemaError(f"{path}: {where} is not a number ({exc})") from exc


def _str(value: Any) -> str:
    """Decode an HDF5 string attribute (variable- or fixed-length, maybe padded)."""
    if isinstance(value, np.ndarray):
        value = value.reshape(-1)[0] if value.size == 1 else b"".join(
            v if isinstance(v, bytes) else str(v).encode() for v in value.reshape(-1)
        )
    if isinstance(value, bytes):
        value = value.decode("utf-8", errors="replace")
    return str(value).rstrip("\x00 ").rstrip()
