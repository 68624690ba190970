"""Fixtures: small synthetic impactchain files in the schema_version 1 layout.

``write_run`` writes what the Fortran side writes, including its habits: scalar
attributes as one-element arrays, space-padded fixed-length strings, and a ``units``
attribute on every dataset.

Periods, exponents and Kaplan-Yorke dimensions are stored, as the simulator stores them,
and the figures must show the stored values (``impactchain`` never computes them). So that a
figure that did compute them would be caught, the stored Kaplan-Yorke dimensions are not
those of the stored exponents, and ``write_run(periods=[...])`` stores periods other than
those of the strobe record.
"""

from __future__ import annotations

import math
import shutil
import subprocess
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import h5py
import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

ROOT = Path(__file__).resolve().parents[3]
FPM = ROOT / ".venv" / "bin" / "fpm"


@pytest.fixture(scope="session")
def simulator() -> Path:
    """The simulator built with the release profile (skipped when fpm is not there)."""
    if not FPM.exists() or shutil.which("gfortran") is None:
        pytest.skip("the simulator cannot be built here (no fpm or gfortran)")
    out = subprocess.run([str(FPM), "run", "--profile", "release", "--runner", "echo"],
                         cwd=ROOT, capture_output=True, text=True, check=True)
    path = ROOT / out.stdout.strip().splitlines()[-1]
    assert path.exists(), out.stdout + out.stderr
    return path


PERIODS = (1, 2, 4, 0)
"""Period of oscillator i is PERIODS[(i - 1) % 4] in the synthetic strobe record."""

DEFAULT_SWEEP: dict[str, Any] = {
    "parameter": "amplitude",
    "parameter2": "",
    "points": 7,
    "cycles": 5,
    "exponents": 6,
    "ky_dimension": True,
    "mode": "down",
}


def _fixed(text: str, width: int | None = None) -> np.bytes_:
    """A fixed-length, space-padded string, as Fortran writes it."""
    raw = text.encode()
    return np.bytes_(raw.ljust(width or len(raw) + 3))


def _one(value: Any, dtype: Any) -> np.ndarray:
    """A one-element array attribute, as h5fortran-style writers store scalars."""
    return np.array([value], dtype=dtype)


def _dataset(group: h5py.Group, name: str, data: Any, units: str) -> None:
    group.create_dataset(name, data=data)
    group[name].attrs["units"] = units


def strobe_record(n: int, records: int, seed: int = 1) -> np.ndarray:
    """Synthetic strobe displacements (records, n) with the periods of PERIODS."""
    rng = np.random.default_rng(seed)
    x = np.empty((records, n))
    j = np.arange(records)
    for i in range(n):
        period = PERIODS[i % len(PERIODS)]
        if period == 0:
            x[:, i] = 0.25 * rng.standard_normal(records)
        else:
            x[:, i] = 0.3 * np.cos(2 * math.pi * j / period + i) - 0.05 * i
    return x


def cascade_events(n: int, cycles: np.ndarray, period: float) -> tuple[np.ndarray, ...]:
    """A left cascade 0..n and a right cascade n..0 in every cycle."""
    times, sites = [], []
    for c in cycles:
        for k in range(n + 1):
            times.append((c + 0.05 + 0.04 * k) * period)
            sites.append(k)
        for k in range(n, -1, -1):
            times.append((c + 0.55 + 0.04 * (n - k)) * period)
            sites.append(k)
    time = np.array(times)
    site = np.array(sites)
    return time, site, np.full(time.shape, 0.5), np.zeros(time.shape, dtype=np.int64)


def write_run(
    path: str | Path,
    n: int = 4,
    records: int = 30,
    events: bool | Mapping[str, Any] | None = True,
    lyapunov: bool = False,
    sweep: bool | Mapping[str, Any] | None = None,
    *,
    strobe: bool = True,
    periods: bool | Sequence[int] = True,
    boundary: str = "fixed",
    spacing: np.ndarray | None = None,
    phase: float = 0.0,
    first_cycle: int = 100,
    schema_version: int | None = 1,
    complete: int = 1,
    omega: float = 1.5,
    transpose_strobe: bool = False,
    seed: int | None = None,
    clv: bool | Mapping[str, Any] | None = None,
) -> Path:
    """Write a synthetic run file and return its path.

    ``events``: True for :func:`cascade_events`, a mapping with ``time``, ``site`` and
    optionally ``speed``, ``kind`` for a given stream, False/None for no /events group.
    ``sweep``: True or a mapping overriding :data:`DEFAULT_SWEEP`. ``periods``: True
    stores /strobe/period as the record's own (:data:`PERIODS`), a sequence stores those
    values instead, False stores none. ``seed``: a random start with this seed, written
    into the input namelist and a ``resolved_namelist`` as the simulator writes them
    (without it: a start at rest, and no resolved namelist, as in an older file).
    ``clv``: True or a mapping overriding :data:`DEFAULT_CLV` for a /clv group.
    """
    path = Path(path)
    period = 2 * math.pi / omega
    spacing = np.ones(n + 1) if spacing is None else np.asarray(spacing, dtype=float)
    cycle = first_cycle + np.arange(records)
    with h5py.File(path, "w") as f:
        if schema_version is not None:
            f.attrs["schema_version"] = _one(schema_version, np.int32)
        f.attrs["code_version"] = _fixed("0.1.0")
        f.attrs["input_namelist"] = "&chain\n n = %d\n/\n" % n
        if seed is not None:
            f.attrs["input_namelist"] += (
                f"! a random start\n&initial kind = 'random', seed = {seed}, x_amp = 0.3,\n"
                "   v_amp = 1.0 /\n&output file = 'ignored.h5' /\n")
            f.attrs["resolved_namelist"] = (
                f"&chain n = {n}, spacing = 1.00000000000000, boundary = '{boundary}' /\n"
                f"&initial kind = 'random', seed = {seed}, x_amp = 0.300000000000000, "
                "v_amp = 1.00000000000000 /\n"
                f"&run transient = {first_cycle}, cycles = {records} /\n")
        f.attrs["complete"] = _one(complete, np.int32)
        _write_params(f, n, spacing, boundary, omega, period, phase, first_cycle, records)
        for name, x in (("initial", np.zeros(n)), ("final", np.full(n, 0.1))):
            g = f.create_group(name)
            _dataset(g, "x", x, "a")
            _dataset(g, "v", -x, "a/time")
        _dataset(f["final"], "cycle", first_cycle + records, "cycles")
        _dataset(f["final"], "phase", phase, "rad")
        if strobe:
            _write_strobe(f, n, records, cycle, periods, transpose_strobe)
        if events:
            stream = cascade_events(n, cycle, period) if events is True else (
                np.asarray(events["time"], dtype=float),
                np.asarray(events["site"]),
                np.asarray(events.get("speed", np.ones(len(events["time"])))),
                np.asarray(events.get("kind", np.zeros(len(events["time"]), dtype=int))),
            )
            _write_events(f, stream)
        _write_stats(f, n)
        if lyapunov:
            _write_lyapunov(f, n, records)
        if sweep:
            _write_sweep(f, n, {**DEFAULT_SWEEP, **(sweep if isinstance(sweep, Mapping) else {})})
        if clv:
            _write_clv(f, n, cycle, {**DEFAULT_CLV, **(clv if isinstance(clv, Mapping) else {})})
    return path


def _write_params(f: h5py.File, n: int, spacing: np.ndarray, boundary: str, omega: float,
                  period: float, phase: float, transient: int, cycles: int) -> None:
    g = f.create_group("params")
    g.attrs["n"] = _one(n, np.int32)
    g.attrs["damping"] = 0.05
    g.attrs["restitution"] = 0.7
    g.attrs["amplitude"] = 1.7
    g.attrs["omega"] = omega
    g.attrs["boundary"] = _fixed(boundary, 8)
    g.attrs["drive_period"] = period
    g.attrs["phase"] = phase
    g.attrs["transient"] = _one(transient, np.int32)
    g.attrs["cycles"] = _one(cycles, np.int32)
    _dataset(g, "spacing", spacing, "a")


def _write_strobe(f: h5py.File, n: int, records: int, cycle: np.ndarray,
                  periods: bool | Sequence[int], transpose: bool) -> None:
    g = f.create_group("strobe")
    x = strobe_record(n, records)
    v = -0.5 * strobe_record(n, records, seed=2)
    _dataset(g, "x", x.T if transpose else x, "a")
    _dataset(g, "v", v.T if transpose else v, "a/time")
    _dataset(g, "cycle", cycle, "cycles")
    if periods is True:
        periods = [PERIODS[i % 4] for i in range(n)]
    if periods is not False:
        _dataset(g, "period", np.asarray(periods, dtype=np.int32), "cycles")


def _write_events(f: h5py.File, stream: tuple[np.ndarray, ...]) -> None:
    g = f.create_group("events")
    for name, data, units in zip(("time", "site", "speed", "kind"), stream,
                                 ("time", "1", "a/time", "1")):
        _dataset(g, name, data, units)


def _write_stats(f: h5py.File, n: int) -> None:
    g = f.create_group("stats")
    g.attrs["collisions_per_cycle"] = 2.0 * (n + 1)
    g.attrs["impacts"] = _one(60, np.int64)
    g.attrs["sticks"] = _one(0, np.int64)
    g.attrs["releases"] = _one(0, np.int64)
    _dataset(g, "site_counts", np.full(n + 1, 2), "1")


def lyapunov_spectrum(n: int) -> np.ndarray:
    """A synthetic descending spectrum of 2n exponents, bits/cycle."""
    return np.linspace(0.4, -1.2, 2 * n)


def _write_lyapunov(f: h5py.File, n: int, records: int) -> None:
    g = f.create_group("lyapunov")
    exponents = lyapunov_spectrum(n)
    steps = np.arange(1, records + 1)[:, None]
    _dataset(g, "exponents", exponents, "bits/cycle")
    _dataset(g, "exponents_per_time", exponents * math.log(2) / 4.0, "1/time")
    _dataset(g, "stderr", np.full(2 * n, 0.02), "bits/cycle")
    _dataset(g, "running", exponents + 0.5 / steps, "bits/cycle")
    g.attrs["ky_dimension"] = 3.5  # not that of the exponents (4.44 for n = 4)
    g.attrs["positive_sum"] = float(exponents[exponents > 0].sum())
    g.attrs["collisions_per_cycle"] = 2.0 * (n + 1)


def sweep_values(spec: Mapping[str, Any]) -> np.ndarray:
    """Parameter values of a synthetic sweep: decreasing, or (points, 2) for 2-D."""
    values = np.linspace(2.0, 1.0, spec["points"])
    if spec["parameter2"]:
        return np.column_stack((values, np.linspace(1.4, 1.6, spec["points"])))
    return values


def _write_sweep(f: h5py.File, n: int, spec: Mapping[str, Any]) -> None:
    g = f.create_group("sweep")
    g.attrs["parameter"] = _fixed(spec["parameter"])
    g.attrs["parameter2"] = _fixed(spec["parameter2"], 1) if spec["parameter2"] else ""
    g.attrs["mode"] = _fixed(spec["mode"])
    values = sweep_values(spec)
    points, cycles = spec["points"], spec["cycles"]
    x = (np.arange(points)[:, None, None] * 0.1 + np.arange(cycles)[None, :, None] * 0.01
         + np.arange(n)[None, None, :])
    _dataset(g, "values", values, "1")
    _dataset(g, "x", x, "a")
    _dataset(g, "collisions_per_cycle", np.linspace(0.0, 3.0, points), "1/cycle")
    _dataset(g, "period", np.ones((points, n), dtype=np.int64), "cycles")
    k = spec["exponents"]
    if k:
        exponents = np.linspace(0.5, -1.0, k)[None, :] - 0.1 * np.arange(points)[:, None]
        _dataset(g, "exponents", exponents, "bits/cycle")
        _dataset(g, "stderr", np.full((points, k), 0.01), "bits/cycle")
        if spec["ky_dimension"]:
            # not those of the exponents (e.g. point 0: 4 + 0.2/0.7 for k = 6)
            _dataset(g, "ky_dimension", np.linspace(0.0, 3.0, points), "1")


DEFAULT_CLV: dict[str, Any] = {
    "transient": 10,
    "store": 2,
    "save": 1,
    "unstable": 1,
}
"""The synthetic /clv of ``write_run(clv=True)``: records without vectors at the end, vectors
with site weights, records with saved vectors, unstable vectors."""


def clv_weights(n: int, records: int, stored: int) -> np.ndarray:
    """Synthetic site weights (records, stored, n), each row summing to 1: vectors 1, 3, ...
    on the left half of the chain (oscillators 1..n//2), vectors 2, 4, ... on the right."""
    r = np.arange(records)[:, None, None]
    j = np.arange(stored)[None, :, None]
    i = np.arange(n)[None, None, :]
    left = i < n // 2
    on = np.where(j % 2 == 0, left, ~left)
    w = on * (1.0 + 0.5 * np.cos(2 * math.pi * r / 7 + i + j))
    return w / w.sum(axis=2, keepdims=True)


def clv_min_angles(records: int) -> np.ndarray:
    """Synthetic smallest angles (records,), rad: log-spaced from 0.01 to 1.5, shuffled."""
    return np.random.default_rng(5).permutation(np.geomspace(0.01, 1.5, records))


def clv_exponents(n: int) -> np.ndarray:
    """The vectors' growth rates: not those of /lyapunov, so that a figure showing those
    instead would be caught."""
    return lyapunov_spectrum(n) + 0.01


def _write_clv(f: h5py.File, n: int, cycle: np.ndarray, spec: Mapping[str, Any]) -> None:
    """/clv as the simulator writes it (h5py order: records first)."""
    g = f.create_group("clv")
    k, stored, save = 2 * n, spec["store"], spec["save"]
    kept = cycle[: cycle.size - spec["transient"]]
    records = kept.size
    weights = clv_weights(n, records, stored)
    ipr = np.tile(np.linspace(0.3, 0.9, k), (records, 1))
    ipr[:, :stored] = (weights ** 2).sum(axis=2)
    _dataset(g, "cycle", kept, "1")
    _dataset(g, "exponents", clv_exponents(n), "bit")
    _dataset(g, "stderr", np.full(k, 0.03), "bit")
    _dataset(g, "stderr_block", np.full(k, 4, dtype=np.int64), "1")
    _dataset(g, "ipr", ipr, "1")
    _dataset(g, "min_angle", clv_min_angles(records), "radian")
    if stored:
        _dataset(g, "site_weight", weights, "1")
    if save:
        vectors = np.random.default_rng(7).standard_normal((save, k, 2 * n))
        _dataset(g, "vectors", vectors / np.linalg.norm(vectors, axis=2, keepdims=True), "1")
        _dataset(g, "saved_cycle", kept[records - save:], "1")
    for name in ("exponents", "stderr"):
        g[name].attrs["model_units"] = "bits per drive cycle"
    g.attrs["clv_transient"] = _one(spec["transient"], np.int32)
    g.attrs["unstable"] = _one(spec["unstable"], np.int32)


@pytest.fixture
def make_run(tmp_path: Path) -> Callable[..., Path]:
    """``make_run(name, **kw)`` writes ``tmp_path/name`` with :func:`write_run`."""

    def make(name: str = "run.h5", **kwargs: Any) -> Path:
        return write_run(tmp_path / name, **kwargs)

    return make


@pytest.fixture
def run_file(make_run: Callable[..., Path]) -> Path:
    """A default run: n = 4, 30 records, cascade events, Lyapunov spectrum."""
    return make_run("run.h5", lyapunov=True)


@pytest.fixture
def sweep_file(make_run: Callable[..., Path]) -> Path:
    """A default 1-D sweep file with exponents and Kaplan-Yorke dimensions."""
    return make_run("sweep.h5", strobe=False, events=False, sweep=True)
