"""Run every recipe, and compare two runs' files value by value: on one machine, a change
meant to keep every number (a refactor, a clean-up) must leave every bit of every recipe's
output as it was.

Every recipe in namelists/ is run with a given simulator in a temporary directory (the recipe
is copied there with its `&output file` pointed at that directory, so figures/runs/ and every
other file are left alone).

    python test/recipes/recipe_runs.py run DIR [--exe EXE] [--jobs N]
    python test/recipes/recipe_runs.py compare DIR_A DIR_B
    python test/recipes/recipe_runs.py compare-versions DIR_V1 DIR_V2

`run` runs every recipe into DIR; run it with each build (`--exe` the other one, e.g. the
previous commit's) and `compare` the two directories: every dataset and every result
attribute, walking all groups, must hold the same bits; a difference is reported with the
first differing element, how many differ and the largest absolute difference. Bits are a
promise on one machine only: across machines, BLAS and libm pick other kernels, and the
recipes are checked by value against tolerances that follow from the physics
(`recipe_reference.py`, in `make test`).

`compare-versions` does the same across a change of the file layout: DIR_V1 holds every
recipe run by a build writing schema version 1, DIR_V2 by one writing version 2 (the
netCDF-4 layout, README "Output"). Every value of a version-1 file is looked up where version
2 keeps it (a scalar instead of a one-element array, a variable-length string instead of a
fixed-length one, /sweep/values as the coordinates /sweep/point and point2, a 2-D sweep's
per-point datasets as (point, point2, ...)) and must hold the same bits; what version 2 left
out (the swept parameters in /params) and what it added (coordinates, dimensions, the drive
period per point) is checked and listed; anything else is a difference, and the exit code 1.

`--exe` defaults to the release build (fpm builds it if needed). Recipes run one at a time
(`--jobs N` for more); OMP_NUM_THREADS is passed on, and no result depends on it.
"""
from __future__ import annotations

import argparse
import fnmatch
import os
import re
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
RECIPES = ROOT / "namelists"
FPM = ROOT / ".venv" / "bin" / "fpm"

# What is not compared, and why: the one place. Every other dataset and attribute is. The
# output holds no wall-clock timestamps, host names or run times (every recipe's file was
# inspected); should one appear, it belongs here. HDF5's own object-header times are not
# datasets or attributes, so comparing contents rather than files ignores them anyway.
EXCLUDED = {
    "/@code_version": "the version string of the build, not a result",
    # the provenance of chain_provenance: where the file was made, not a result (the same
    # results are made by other compilers, flags, BLAS kernels and CPUs)
    "/@compiler": "the compiler that built the program, not a result",
    "/@compiler_options": "the compiler's flags, which name the build's directories",
    "/@blas": "the BLAS the program ran on (name, version, build), not a result",
    "/@blas_kernel": "the kernels the BLAS selected on the CPU, not a result",
    "/@cpu_model": "the CPU the program ran on, not a result",
    "/@input_namelist": "the input text echoed back: it names the &output file, which this "
                        "script points into a temporary directory",
    "/@resolved_namelist": "every key as used, echoed back: it names the same rewritten "
                           "&output file (the physical inputs are compared in /params)",
    "*@units": "describes a dataset, is not a result",
    "*@long_name": "describes a dataset, is not a result",
    "*@model_units": "describes a dataset, is not a result",
    "*@flag_values": "describes a dataset's codes, is not a result",
    "*@flag_meanings": "describes a dataset's codes, is not a result",
    "*@coordinates": "names a dataset's coordinates, is not a result",
    # the dimension scales (HDF5's attributes): which dataset is whose axis, not a result;
    # their references are object addresses, which differ between files of equal content
    "*@CLASS": "marks a dimension scale, is not a result",
    "*@NAME": "names a dimension scale, is not a result",
    "*@DIMENSION_LIST": "references to a dataset's dimension scales, not a result",
    "*@REFERENCE_LIST": "references to the datasets of a dimension scale, not a result",
}

RUN_TIMEOUT = 900    # seconds per recipe: a hung run must fail CI, not stall it


class RecipeError(RuntimeError):
    """A recipe that cannot be run safely here, or a run that failed."""


# ---- running the recipes ----------------------------------------------------------------

def default_exe() -> Path:
    """The release build of the simulator, built by fpm if needed."""
    out = subprocess.run([str(FPM), "run", "--profile", "release", "--runner", "echo"],
                         cwd=ROOT, capture_output=True, text=True, check=True)
    return ROOT / out.stdout.strip().splitlines()[-1]


def namelist_groups(text: str) -> Iterator[tuple[str, int, int]]:
    """(name, start, end) of each `&name ... /` group: `text[start:end]` is the group from
    `&` to its closing `/`. Comments (`!` to the end of a line) and quoted strings are
    skipped, so a `/` or `&` inside them ends or starts nothing."""
    j, quote, start, name = 0, "", -1, ""
    while j < len(text):
        c = text[j]
        if quote:
            if c == quote:
                quote = ""
        elif c == "!":
            j = text.find("\n", j)
            if j < 0:
                break
        elif start < 0 and c == "&":
            start = j
            name = re.match(r"\w*", text[j + 1:]).group(0).lower()
        elif start >= 0 and c in "'\"":
            quote = c
        elif start >= 0 and c == "/":
            yield name, start, j + 1
            start = -1
        j += 1


def redirect_output(text: str, file_name: str) -> str:
    """The recipe with `&output file = 'file_name'` and `overwrite = .false.` (a stray path
    can then never replace an existing file); an `&output` group is added if there is none."""
    groups = {name: (start, end) for name, start, end in namelist_groups(text)}
    initial = text[slice(*groups["initial"])] if "initial" in groups else ""
    if re.search(r"(?i)\bkind\s*=\s*['\"]file['\"]", initial):
        raise RecipeError("starts from another run's file (&initial kind = 'file'), which "
                          "this script does not produce")
    new_file = f"file = '{file_name}'"
    if "output" not in groups:
        return text.rstrip("\n") + f"\n&output {new_file} /\n"
    start, end = groups["output"]
    group = text[start:end]
    key = r"(?i)(?<![\w%])"
    group, found = re.subn(key + r"file\s*=\s*('[^']*'|\"[^\"]*\")", new_file, group)
    if found == 0:
        group = f"&output {new_file} " + group[len("&output"):]
    group = re.sub(key + r"overwrite\s*=\s*[^\s,/]+", "overwrite = .false.", group)
    return text[:start] + group + text[end:]


def run_recipe(exe: Path, recipe: Path, workdir: Path,
               env: dict[str, str | None] | None = None, extra: tuple[str, ...] = (),
               suffix: str = "") -> float:
    """Run one recipe into workdir/<name><suffix>.h5; return the wall time in seconds.
    `env` changes the environment (a forced BLAS or libm kernel; None removes a variable),
    `extra` is added to the command line (`--set` overrides)."""
    name = recipe.stem + suffix
    output = workdir / f"{name}.h5"
    if output.exists():
        raise RecipeError(f"{name}: {output} exists; give a fresh directory")
    try:
        text = redirect_output(recipe.read_text(), output.name)
    except RecipeError as err:
        raise RecipeError(f"{name}: {err}") from None
    (workdir / f"{name}.nml").write_text(text)
    began = time.perf_counter()
    try:
        run = subprocess.run([str(exe), "--quiet", *extra, f"{name}.nml"], cwd=workdir,
                             capture_output=True, text=True, timeout=RUN_TIMEOUT,
                             env={k: v for k, v in {**os.environ, **(env or {})}.items()
                                  if v is not None})
    except subprocess.TimeoutExpired:
        raise RecipeError(f"{name}: still running after {RUN_TIMEOUT} s") from None
    seconds = time.perf_counter() - began
    if run.returncode != 0 or not output.exists():
        raise RecipeError(f"{name}: the simulator failed (exit {run.returncode}): "
                          f"{run.stderr.strip() or run.stdout.strip()}")
    return seconds


def run_recipes(exe: Path, workdir: Path, jobs: int,
                env: dict[str, str | None] | None = None) -> dict[str, Path]:
    """Run every recipe into workdir; print the time of each and in all; {name: file}."""
    recipes = sorted(RECIPES.glob("*.nml"))
    if not recipes:
        raise RecipeError(f"no recipes in {RECIPES}")
    began = time.perf_counter()
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        seconds = list(pool.map(lambda r: run_recipe(exe, r, workdir, env), recipes))
    total = time.perf_counter() - began
    slowest = sorted(zip(recipes, seconds), key=lambda rs: -rs[1])
    print("ran", len(recipes), f"recipes in {total:.1f} s ({jobs} at a time; slowest: "
          + ", ".join(f"{r.stem} {s:.1f} s" for r, s in slowest[:3]) + ")")
    return {r.stem: workdir / f"{r.stem}.h5" for r in recipes}


# ---- reading and hashing ------------------------------------------------------------------

def as_array(value) -> np.ndarray:
    """A dataset's or attribute's value as a numpy array of fixed-size elements (variable-
    length strings become bytes)."""
    array = np.asarray(value)
    if array.dtype.kind == "O":
        items = [v.encode() if isinstance(v, str) else v for v in array.ravel()]
        if not all(isinstance(v, bytes) for v in items):
            raise TypeError(f"cannot compare values of type {type(items[0]).__name__}")
        array = np.array(items, dtype=bytes).reshape(array.shape)
    elif array.dtype.kind == "U":
        array = np.char.encode(array, "utf-8")
    return array


def results(path: Path) -> Iterator[tuple[str, np.ndarray]]:
    """Every compared item of one output file, in a fixed order: (path or path@attribute,
    value), skipping EXCLUDED."""
    with h5py.File(path, "r") as f:
        objects = [("/", f)]
        f.visititems(lambda name, obj: objects.append(("/" + name, obj)))
        for name, obj in objects:
            items = [(name, obj)] if isinstance(obj, h5py.Dataset) else []
            items += [(f"{name}@{attribute}", attribute) for attribute in sorted(obj.attrs)]
            for key, source in items:
                if any(fnmatch.fnmatchcase(key, pattern) for pattern in EXCLUDED):
                    continue
                value = source[()] if isinstance(source, h5py.Dataset) else obj.attrs[source]
                try:
                    yield key, as_array(value)
                except TypeError as err:
                    raise RecipeError(f"{path.name}: {key}: {err}; list it in EXCLUDED "
                                      "if it is not a result") from None


def shape_text(shape: tuple[int, ...]) -> str:
    return "x".join(map(str, shape)) if shape else "scalar"


def differences(problems: list[str]) -> str:
    n = len(problems)
    return f"{n} difference{'' if n == 1 else 's'}; " if n else ""


def summary(identical: dict[str, dict[str, str]]) -> str:
    keys = [key for entries in identical.values() for key in entries]
    attributes = sum("@" in key for key in keys)
    return (f"{len(keys) - attributes} datasets in {len(identical)} recipes identical "
            f"(and {attributes} attributes)")


def describe_difference(a: np.ndarray, b: np.ndarray) -> str | None:
    """None if a and b are the same bits; otherwise where and by how much they differ."""
    if a.dtype.str != b.dtype.str or a.shape != b.shape:
        return (f"was {a.dtype.str} {shape_text(a.shape)}, "
                f"now {b.dtype.str} {shape_text(b.shape)}")
    bytes_a = np.ascontiguousarray(a).reshape(-1).view(np.uint8).reshape(a.size, -1)
    bytes_b = np.ascontiguousarray(b).reshape(-1).view(np.uint8).reshape(b.size, -1)
    differ = (bytes_a != bytes_b).any(axis=1)
    if not differ.any():
        return None
    first = int(np.flatnonzero(differ)[0])
    where = list(map(int, np.unravel_index(first, a.shape))) if a.ndim else "scalar"
    text = (f"{int(differ.sum())} of {a.size} elements differ; first at {where}: "
            f"{a.reshape(-1)[first].item()!r:.60} -> {b.reshape(-1)[first].item()!r:.60}")
    if a.dtype.kind in "iufc":
        kind = np.complex128 if a.dtype.kind == "c" else np.float64
        with np.errstate(invalid="ignore", over="ignore"):    # inf - inf, huge - -huge
            gap = np.abs(a.reshape(-1)[differ].astype(kind) - b.reshape(-1)[differ])
        largest = np.nanmax(gap) if not np.isnan(gap).all() else np.nan
        text += f"; max abs difference {largest:.3g}"
    return text


def compare_dirs(dir_a: Path, dir_b: Path) -> int:
    """Compare the output files of two directories, file by file and value by value."""
    names_a = {p.name for p in dir_a.glob("*.h5")}
    names_b = {p.name for p in dir_b.glob("*.h5")}
    if not names_a | names_b:
        print(f"no .h5 files in {dir_a} or {dir_b}")
        return 1
    problems, identical = [], {}
    for name in sorted(names_a | names_b):
        if name not in names_b or name not in names_a:
            problems.append(f"{name}: only in {dir_a if name in names_a else dir_b}")
            continue
        a = dict(results(dir_a / name))
        b = dict(results(dir_b / name))
        identical[name] = {}
        for key in sorted(a.keys() | b.keys()):
            if key not in b or key not in a:
                problems.append(f"{name}: {key}: only in {dir_a if key in a else dir_b}")
            elif (difference := describe_difference(a[key], b[key])) is not None:
                problems.append(f"{name}: {key}: {difference}")
            else:
                identical[name][key] = ""
    for line in problems:
        print(line)
    print(differences(problems), summary(identical), sep="")
    return 1 if problems else 0


# ---- across the change of layout (schema version 1 -> 2) ---------------------------------

def _text(value: np.ndarray) -> str:
    return b"".join(np.ravel(value).astype(bytes)).decode().rstrip("\x00 ")


def _same_values(a: np.ndarray, b: np.ndarray) -> bool:
    """The same numbers bit for bit (or the same text), one-element arrays equal to scalars."""
    if a.dtype.kind == "S" or b.dtype.kind == "S":
        return _text(a) == _text(b)
    if a.shape != b.shape and not (a.size == b.size == 1):
        return False
    return a.dtype == b.dtype and np.ravel(a).tobytes() == np.ravel(b).tobytes()


def _swept(items: dict[str, np.ndarray]) -> list[str]:
    return [_text(items[key]) for key in ("/sweep@parameter", "/sweep@parameter2")
            if key in items and _text(items[key])]


def version_map(v1: dict[str, np.ndarray], v2: dict[str, np.ndarray]
                ) -> tuple[dict[str, np.ndarray], list[str]]:
    """Version 1's values as version 2 keeps them ({version-2 key: value}), and what version 1
    has that version 2 rightly does not keep (one line each)."""
    mapped, dropped = {}, []
    swept = _swept(v1)
    two_d = len(swept) == 2
    if two_d:
        values = v1["/sweep/values"]
        n1 = int(np.flatnonzero(values[:, 1] != values[0, 1])[0]) \
            if (values[:, 1] != values[0, 1]).any() else values.shape[0]
        n2 = values.shape[0] // n1
    for key, value in v1.items():
        if key == "/@schema_version":
            continue                                   # 1 -> 2, checked by the caller
        name = key.split("@")[-1] if key.startswith("/params@") else ""
        if name in swept or (name == "drive_period" and "omega" in swept) or \
                (key == "/params/spacing" and "spacing" in swept):
            dropped.append(f"{key}: not in /params, as it differs from point to point "
                           f"(the sweep's coordinates hold it)")
            continue
        if key == "/sweep/values":
            if two_d:
                mapped["/sweep/point"] = values[:n1, 0]
                mapped["/sweep/point2"] = values[::n1, 1]
            else:
                mapped["/sweep/point"] = value
            continue
        if two_d and key.startswith("/sweep/") and "@" not in key:
            # points p = i + n1 j, (n_points, ...) -> (n1, n2, ...)
            value = value.reshape((n2, n1) + value.shape[1:]).swapaxes(0, 1)
        mapped[key] = value
    return mapped, dropped


def compare_version_files(v1_path: Path, v2_path: Path) -> tuple[int, list[str], list[str]]:
    """(values identical, explained lines, problems) for one recipe's two files."""
    v1, v2 = dict(results(v1_path)), dict(results(v2_path))
    mapped, explained = version_map(v1, v2)
    problems = []
    versions = [int(np.ravel(v.get("/@schema_version", [0]))[0]) for v in (v1, v2)]
    if versions != [1, 2]:
        problems.append(f"/@schema_version: {versions[0]} and {versions[1]}, not 1 and 2")
    same = 0
    for key, value in mapped.items():
        if key not in v2:
            problems.append(f"{key}: not in the version-2 file")
        elif not _same_values(value, v2[key]):
            problems.append(f"{key}: {describe_difference(value, v2[key]) or 'differs'}")
        else:
            same += 1
    with h5py.File(v2_path, "r") as f:
        for key in sorted(set(v2) - set(mapped) - {"/@schema_version"}):
            obj = f[key.split("@")[0]] if "@" not in key else None
            if obj is not None and obj.attrs.get("CLASS") == b"DIMENSION_SCALE":
                if str(obj.attrs.get("NAME", b"")).find("not a netCDF variable") >= 0:
                    explained.append(f"{key}: new, a dimension ({obj.shape[0]})")
                    continue
                if obj.dtype.kind == "i" and np.array_equal(
                        obj[()], np.arange(obj[0], obj[0] + obj.shape[0])):
                    explained.append(f"{key}: new, the index coordinate {obj[0]}.."
                                     f"{obj[0] + obj.shape[0] - 1}")
                    continue
            if key == "/sweep/drive_period":
                axis = "/sweep/point" if _swept(v1)[0] == "omega" else "/sweep/point2"
                if np.ravel(v2[key]).tobytes() == (2 * np.pi / v2[axis]).tobytes():
                    explained.append(f"{key}: new, 2 pi / {axis} bit for bit")
                    continue
            problems.append(f"{key}: new in version 2, not explained")
    return same, explained, problems


def compare_versions(dir_v1: Path, dir_v2: Path) -> int:
    """Compare every recipe's version-1 file with its version-2 file, value by value."""
    names = sorted({p.name for p in dir_v1.glob("*.h5")} | {p.name for p in dir_v2.glob("*.h5")})
    if not names:
        print(f"no .h5 files in {dir_v1} or {dir_v2}")
        return 1
    problems, total, explained_total = [], 0, 0
    for name in names:
        if not (dir_v1 / name).exists() or not (dir_v2 / name).exists():
            problems.append(f"{name}: only in {dir_v1 if (dir_v1 / name).exists() else dir_v2}")
            continue
        same, explained, wrong = compare_version_files(dir_v1 / name, dir_v2 / name)
        total += same
        explained_total += len(explained)
        print(f"{name}: {same} values identical; {len(explained)} layout changes"
              + "".join(f"\n    {line}" for line in explained if "index coordinate" not in
                        line and "a dimension" not in line))
        problems += [f"{name}: {line}" for line in wrong]
    for line in problems:
        print(line)
    print(differences(problems) + f"{total} values in {len(names)} recipes identical across "
          f"the layouts ({explained_total} layout changes explained)")
    return 1 if problems else 0


# ---- command line ------------------------------------------------------------------------

def workdir_for(keep: Path | None) -> tuple[Path, tempfile.TemporaryDirectory | None]:
    """The directory the recipes run in: `keep` (new or empty, as the redirected recipes and
    their output are written there) or a temporary one that disappears afterwards."""
    if keep is None:
        temporary = tempfile.TemporaryDirectory(prefix="recipe-checksums-")
        return Path(temporary.name), temporary
    if keep.exists() and (not keep.is_dir() or any(keep.iterdir())):
        raise RecipeError(f"{keep} is not an empty directory; give a new one")
    keep.mkdir(parents=True, exist_ok=True)
    return keep.resolve(), None


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    sub = commands.add_parser("run", help="run every recipe into DIR, to `compare` later")
    sub.add_argument("keep", type=Path, metavar="DIR")
    sub.add_argument("--exe", type=Path, help="the simulator (default: the release build)")
    sub.add_argument("--jobs", type=int, default=1, help="recipes run at once")
    sub = commands.add_parser("compare", help="compare two directories of output files")
    sub.add_argument("dir_a", type=Path)
    sub.add_argument("dir_b", type=Path)
    sub = commands.add_parser("compare-versions", help="compare the files of two directories "
                              "across the layouts of schema versions 1 and 2")
    sub.add_argument("dir_v1", type=Path)
    sub.add_argument("dir_v2", type=Path)
    args = parser.parse_args(argv)

    if args.command == "compare":
        return compare_dirs(args.dir_a, args.dir_b)
    if args.command == "compare-versions":
        return compare_versions(args.dir_v1, args.dir_v2)
    try:
        exe = (args.exe or default_exe()).resolve()
        workdir, _ = workdir_for(args.keep)
        run_recipes(exe, workdir, max(1, args.jobs))
    except RecipeError as err:
        print(f"recipe_runs: {err}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
