"""A written file against the file schema (`impactchain --schema`'s "outputs", the table of
src/runs/chain_file_table.f90): every dataset, dimension and attribute the file holds is in
the table with the same dims, dtype, units, model_units and long_name, and every entry the
table says a file of its kind always holds is there. Used by test_file_schema.py and, on
every recipe's file, by test_recipes.py.
"""
from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import Any

import h5py
import numpy as np

# what netCDF and HDF5's dimension scales add to a dataset, and netCDF's flags: not the table's
BOOKKEEPING = {"CLASS", "NAME", "REFERENCE_LIST", "DIMENSION_LIST", "_Netcdf4Dimid",
               "_Netcdf4Coordinates", "flag_values", "flag_meanings", "coordinates"}
DESCRIPTION = {"units", "long_name", "model_units"}
BARE_DIMENSION = "This is a netCDF dimension but not a netCDF variable"
PARAMETER = "{parameter}"


def read_schema(exe: Path) -> list[dict[str, Any]]:
    """The outputs half of `impactchain --schema`."""
    result = subprocess.run([str(exe), "--schema"], capture_output=True, text=True,
                            timeout=60, check=True)
    document = json.loads(result.stdout)
    assert document["schema_version"] == 1 and isinstance(document["inputs"], list)
    return document["outputs"]


def text(value: Any) -> str:
    if isinstance(value, bytes):
        return value.decode()
    if isinstance(value, np.ndarray):
        return text(value.flat[0])
    return str(value)


def dtype_name(dtype: np.dtype) -> str:
    if h5py.check_string_dtype(dtype) is not None or dtype.kind in "SUO":
        return "string"
    return {"f8": "float64", "i4": "int32", "i8": "int64", "i1": "int8"}.get(dtype.str[1:],
                                                                          dtype.str)


def file_kind(f: h5py.File) -> str:
    return next((kind for kind in ("sweep", "continuation", "census") if kind in f), "run")


def expected_dims(entry: dict[str, Any], f: h5py.File) -> tuple[str, ...]:
    """The entry's dims in this file: `name?` in a 2-D sweep only, of `a|b` the sweep axis
    of omega."""
    two_d = "sweep/point2" in f
    omega_second = two_d and text(f["sweep"].attrs.get("parameter2", "")) == "omega"
    names = []
    for name in entry["dims"]:
        if name.endswith("?"):
            if not two_d:
                continue
            name = name[:-1]
        if "|" in name:
            name = name.split("|")[1 if omega_second else 0]
        names.append(name)
    return tuple(names)


def parameter_of(path: str, f: h5py.File) -> str | None:
    """The swept or continued parameter a `{parameter}` of `path` stands for."""
    group = path.split("/")[1]
    key = "parameter2" if path in ("/sweep/point2", "/curve/values2") else "parameter"
    if group in f and key in f[group].attrs:
        return text(f[group].attrs[key])
    return None


def resolved(value: str | None, parameter: str | None, units: dict[str, str | None]):
    if value == PARAMETER:
        return units.get(parameter)
    if value is not None and parameter is not None:
        return value.replace(PARAMETER, parameter)
    return value


def check_dataset(path: str, ds: h5py.Dataset, candidates: list[dict[str, Any]],
                  f: h5py.File, units: dict[str, str | None]) -> list[str]:
    """'' for a match with one of the path's entries, else what differs from each."""
    attrs = ds.attrs
    if text(attrs.get("NAME", "")).startswith(BARE_DIMENSION):
        found = {"kind": "dimension", "dims": (path.rsplit("/", 1)[1],)}
    else:
        is_scale = text(attrs.get("CLASS", "")) == "DIMENSION_SCALE"
        found = {"kind": "dataset", "dtype": dtype_name(ds.dtype),
                 "units": text(attrs["units"]) if "units" in attrs else None,
                 "model_units": text(attrs["model_units"]) if "model_units" in attrs else None,
                 "long_name": text(attrs["long_name"]) if "long_name" in attrs else None,
                 "dims": ((path.rsplit("/", 1)[1],) if is_scale else
                          tuple(d[0].name.rsplit("/", 1)[1] if len(d) else "?"
                                for d in ds.dims))}
    problems = []
    for entry in candidates:
        parameter = parameter_of(path, f)
        want = {"kind": entry["kind"], "dims": expected_dims(entry, f)}
        if entry["kind"] == "dataset":
            want.update(dtype=entry["dtype"], units=entry["units"],
                        model_units=resolved(entry["model_units"], parameter, units),
                        long_name=resolved(entry["long_name"], parameter, units))
        differs = {key: (found.get(key), value) for key, value in want.items()
                   if found.get(key) != value}
        if not differs:
            return []
        problems.append(f"{path}: " + "; ".join(f"{key} is {got!r}, the table says {value!r}"
                                                for key, (got, value) in differs.items()))
    return problems


def schema_differences(h5: Path, schema: list[dict[str, Any]]) -> list[str]:
    """Every disagreement between the file and the table, one line each ([] when none)."""
    problems: list[str] = []
    with h5py.File(h5, "r") as f:
        kind = file_kind(f)
        entries = [e for e in schema if e["file"] == kind or e["when"] == "header"]
        by_path: dict[str, list[dict[str, Any]]] = {}
        for entry in entries:
            by_path.setdefault(entry["path"], []).append(entry)
        units = {e["path"].rsplit("@", 1)[-1].rsplit("/", 1)[-1]: e["model_units"]
                 for e in schema if e["path"].startswith("/params/")}
        seen = set()

        def attributes(path: str, obj: Any) -> None:
            for name, value in obj.attrs.items():
                if isinstance(obj, h5py.Dataset) and name in BOOKKEEPING | DESCRIPTION:
                    continue
                where = (path.rstrip("/") + "/@" + name) if path != "/" else "/@" + name
                seen.add(where)
                if isinstance(obj, h5py.Dataset):
                    problems.append(f"{where}: an attribute of a dataset the table lacks")
                elif where not in by_path:
                    problems.append(f"{where}: not in the table")
                elif by_path[where][0]["dtype"] != dtype_name(np.asarray(value).dtype):
                    problems.append(f"{where}: dtype {dtype_name(np.asarray(value).dtype)}, "
                                    f"the table says {by_path[where][0]['dtype']}")

        def visit(name: str, obj: Any) -> None:
            path = "/" + name
            attributes(path, obj)
            if not isinstance(obj, h5py.Dataset):
                return
            seen.add(path)
            if path not in by_path:
                problems.append(f"{path}: not in the table")
            else:
                problems.extend(check_dataset(path, obj, by_path[path], f, units))

        attributes("/", f)
        f.visititems(visit)
        required = {e["path"] for e in entries
                    if e["when"] == "always" or (kind == "run" and e["when"] == "header")}
        problems.extend(f"{path}: the table says a {kind} file always holds it"
                        for path in sorted(required - seen))
    return problems
