"""impactchain.api, the Python interface to the Fortran kernels (the f2py extension
impactchain._kernels).

What these tests demonstrate:

1. Python and the CLI (``fpm run --profile release`` on the equivalent namelist) give
   bit-identical strobe records, event streams, final states, statistics, periods, Lyapunov
   spectra and Floquet Jacobians (``test_bit_identical_to_cli``, ``test_example_...``);
   every full spectrum obeys the sum rule (``impactchain.testing.assert_sum_rule``).
2. Every validation error of the library surfaces as a Python ValueError with exactly the
   CLI's message (``test_errors_match_cli``); Python-only misuse raises TypeError /
   ValueError with a clear message (``test_python_side_errors``).
3. No leaks: 10,000 short calls do not grow the process's resident memory (``test_no_leak``).
4. The example examples/python/fig1c_space_amplitude.py reproduces its recipe bit for bit
   and draws with the gallery's figure function. (That ``pip install`` builds the extension
   in a fresh environment is test/python/package/test_install.py's; ``make test`` installs the package
   before running pytest.)
5. Long calls stop on Ctrl-C and show progress; sweeps and continuations of periodic orbits
   return the CLI file's groups (``/sweep``, ``/continuation``) as xarray reads them, bit for
   bit; a periodic orbit is the CLI's Newton-only continuation point.

Tests that need the extension are skipped when it cannot be imported, unless the
environment variable IMPACTCHAIN_REQUIRE_EXTENSION is set (``make test`` sets it), in which
case they fail loudly.
"""

from __future__ import annotations

import importlib.util
import math
import os
import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import pytest

from impactchain import _calls, _continuations, _runs, api
from impactchain.testing import assert_sum_rule

ROOT = Path(__file__).resolve().parents[3]
FPM = ROOT / ".venv" / "bin" / "fpm"
EXAMPLE = ROOT / "examples" / "python" / "fig1c_space_amplitude.py"

pytestmark = pytest.mark.skipif(
    not api.extension_available() and "IMPACTCHAIN_REQUIRE_EXTENSION" not in os.environ,
    reason="the extension impactchain._kernels is not installed (`make build` or "
           "`pip install .`); set IMPACTCHAIN_REQUIRE_EXTENSION=1 to fail instead of skipping",
)


# ----------------------------------------------------------------------------- the CLI


@pytest.fixture(scope="session")
def cli() -> Path:
    """The simulator built with the release profile, as the extension is."""
    out = subprocess.run([str(FPM), "run", "--profile", "release", "--runner", "echo"],
                         cwd=ROOT, capture_output=True, text=True, check=True)
    path = ROOT / out.stdout.strip().splitlines()[-1]
    assert path.exists(), out.stdout + out.stderr
    return path


def _values(values: Any) -> str:
    """Numbers as a namelist list; repr() round-trips every double exactly."""
    return ", ".join(repr(float(v)) for v in np.atleast_1d(np.asarray(values, dtype=float)))


def namelist(n: int, amplitude: float, omega: float, damping: float = 0.05,
             restitution: float = 0.7, spacing: Any = 1.0, boundary: str = "fixed",
             x0: Any = None, v0: Any = None, transient: int = 0, cycles: int = 100,
             events: bool = True, phase: float = 0.0, stick_speed: float = 1.0e-9,
             max_size_mb: float = 4096.0, lyapunov: bool = False, vectors: int = 0,
             qr_every: int = 0, period: int | None = None, random: dict | None = None,
             window: int = 0) -> str:
    """The namelist equivalent to a call of impactchain.api with these arguments."""
    lines = [f"&chain n = {n}, amplitude = {_values(amplitude)}, omega = {_values(omega)}, "
             f"damping = {_values(damping)}, restitution = {_values(restitution)}, "
             f"spacing = {_values(spacing)}, boundary = '{boundary}' /"]
    if random is not None:
        lines.append(f"&initial kind = 'random', seed = {random['seed']}, "
                     f"x_amp = {_values(random['x_amp'])}, v_amp = {_values(random['v_amp'])} /")
    elif x0 is not None or v0 is not None:
        x = np.zeros(n) if x0 is None else x0
        v = "" if v0 is None else f", v0 = {_values(v0)}"
        lines.append(f"&initial kind = 'explicit', x0 = {_values(x)}{v} /")
    lines.append(f"&run transient = {transient}, cycles = {cycles}, phase = {_values(phase)}, "
                 f"record_events = {'T' if events else 'F'}, "
                 f"stick_speed = {_values(stick_speed)} /")
    if lyapunov or period is not None:
        lines.append(f"&lyapunov enabled = {'T' if lyapunov else 'F'}, vectors = {vectors}, "
                     f"qr_every = {qr_every}, jacobian = {'T' if period is not None else 'F'}, "
                     f"jacobian_cycles = {1 if period is None else period}"
                     + (f", window = {window}" if window else "") + " /")
    lines.append(f"&output file = 'run.h5', overwrite = T, "
                 f"max_size_mb = {_values(max_size_mb)} /")
    return "\n".join(lines) + "\n"


def run_cli(exe: Path, text: str, workdir: Path) -> subprocess.CompletedProcess:
    (workdir / "input.nml").write_text(text)
    return subprocess.run([str(exe), "--quiet", "input.nml"], cwd=workdir,
                          capture_output=True, text=True, timeout=300)


def cli_error(exe: Path, text: str, workdir: Path) -> str:
    """The message the CLI prints for an input it refuses."""
    result = run_cli(exe, text, workdir)
    assert result.returncode == 1, (result.stdout, result.stderr)
    assert not (workdir / "run.h5").exists()
    match = re.fullmatch(r"impactchain: error: (.*)\n", result.stderr, re.S)
    assert match, result.stderr
    return match.group(1)


# ------------------------------------------------------------------ 1. bit-identical to CLI

CASES: dict[str, dict[str, Any]] = {
    # the paper's fig. 1c chain, chaotic, from the CLI's seeded random start
    "fig1c-chaotic": dict(n=16, amplitude=1.7, omega=1.5, transient=200, cycles=200,
                          random=dict(seed=1, x_amp=0.3, v_amp=1.0), vectors=0, period=1),
    # free ends, one spacing per bond, another section phase, explicit x0 with v0 = 0,
    # part of the spectrum with QR every other cycle, a 2-cycle Jacobian
    "free-disordered": dict(n=6, amplitude=2.0, omega=1.9, damping=0.1, restitution=0.5,
                            spacing=[1.0, 0.9, 1.1, 1.05, 0.95, 1.0, 1.2], boundary="free",
                            x0=[0.1, -0.2, 0.05, 0.3, -0.1, 0.0], phase=1.0, transient=20,
                            cycles=50, vectors=3, qr_every=2, period=2),
    # chatter that ends in sticking on the walls, and releases; more events than the first
    # guess of the event buffer, so the API's retry path runs
    "sticking": dict(n=4, amplitude=0.6, omega=0.5, restitution=0.2, spacing=0.3,
                     x0=[0.01, -0.02, 0.0, 0.02], v0=[0.1, 0.0, -0.1, 0.2], transient=50,
                     cycles=50, vectors=0, period=1),
    # a start at rest, strong drive
    "rest-strong": dict(n=8, amplitude=3.5, omega=1.5, transient=30, cycles=40, vectors=5,
                        period=1),
}


def _initial(case: dict[str, Any]) -> tuple[Any, Any]:
    if "random" in case:
        r = case["random"]
        return api.random_start(case["n"], seed=r["seed"], x_amp=r["x_amp"], v_amp=r["v_amp"])
    return case.get("x0"), case.get("v0")


def _model_args(case: dict[str, Any]) -> dict[str, Any]:
    keys = ("damping", "restitution", "spacing", "boundary", "transient", "cycles", "phase")
    return {k: case[k] for k in keys if k in case}


@pytest.mark.parametrize("qr_every, window", [(0, 20), (2, 10)])
def test_finite_time_windows_are_the_cli_file(cli: Path, tmp_path: Path, qr_every: int,
                                              window: int) -> None:
    """api.lyapunov(window=W): the standard errors' block sizes and the finite-time exponents
    of the CLI's /lyapunov/stderr_block and /finite_time, bit for bit."""
    args = dict(n=6, amplitude=2.0, omega=1.9, transient=30, cycles=200, vectors=5,
                qr_every=qr_every)
    x0 = [0.1, -0.2, 0.05, 0.3, -0.1, 0.0]
    result = run_cli(cli, namelist(**args, x0=x0, events=False, lyapunov=True, window=window),
                     tmp_path)
    assert result.returncode == 0, result.stderr
    lyap = api.lyapunov(**args, x0=x0, window=window)
    assert lyap.params["window"] == window
    with h5py.File(tmp_path / "run.h5") as f:
        np.testing.assert_array_equal(lyap.exponents, f["lyapunov/exponents"][:], strict=True)
        np.testing.assert_array_equal(lyap.stderr, f["lyapunov/stderr"][:], strict=True)
        np.testing.assert_array_equal(lyap.stderr_block, f["lyapunov/stderr_block"][:],
                                      strict=True)
        np.testing.assert_array_equal(lyap.finite_time.exponents,
                                      f["finite_time/exponents"][:], strict=True)
        np.testing.assert_array_equal(lyap.finite_time.cycle, f["finite_time/cycle"][:],
                                      strict=True)
    assert lyap.finite_time.window == window and lyap.finite_time.n_windows == 200 // window
    assert lyap.to_run().finite_time is lyap.finite_time
    assert api.lyapunov(**args, x0=x0).finite_time is None
    with pytest.raises(ValueError, match="window = 201 is outside"):
        api.lyapunov(**args, x0=x0, window=201)


@pytest.mark.parametrize("name", CASES)
def test_bit_identical_to_cli(name: str, cli: Path, tmp_path: Path) -> None:
    case = CASES[name]
    run_cli_args = {k: v for k, v in case.items()}
    result = run_cli(cli, namelist(**run_cli_args, lyapunov=True), tmp_path)
    assert result.returncode == 0, result.stderr

    x0, v0 = _initial(case)
    common = dict(n=case["n"], amplitude=case["amplitude"], omega=case["omega"], x0=x0, v0=v0,
                  **_model_args(case))
    sim = api.simulate(**common)
    lyap = api.lyapunov(**common, vectors=case["vectors"], qr_every=case.get("qr_every", 0))
    flo = api.floquet(**common, period=case["period"])

    with h5py.File(tmp_path / "run.h5") as f:
        if x0 is not None:
            np.testing.assert_array_equal(f["initial/x"][:], x0, strict=True)
        if v0 is not None:
            np.testing.assert_array_equal(f["initial/v"][:], v0, strict=True)
        np.testing.assert_array_equal(sim.x, f["strobe/x"][:], strict=True)
        np.testing.assert_array_equal(sim.v, f["strobe/v"][:], strict=True)
        np.testing.assert_array_equal(sim.cycle, f["strobe/cycle"][:].astype(np.int64))
        np.testing.assert_array_equal(sim.periods, f["strobe/period"][:])
        for field in ("time", "site", "speed", "kind"):
            np.testing.assert_array_equal(getattr(sim, "event_" + field),
                                          f["events/" + field][:])
        np.testing.assert_array_equal(sim.final_x, f["final/x"][:], strict=True)
        np.testing.assert_array_equal(sim.final_v, f["final/v"][:], strict=True)
        np.testing.assert_array_equal(sim.site_counts, f["stats/site_counts"][:])
        stats = {k: np.ravel(v)[0] for k, v in f["stats"].attrs.items()}
        assert (sim.impacts, sim.sticks, sim.releases) == (
            stats["impacts"], stats["sticks"], stats["releases"])
        assert sim.collisions_per_cycle == stats["collisions_per_cycle"]

        g = f["lyapunov"]
        np.testing.assert_array_equal(lyap.exponents, g["exponents"][:], strict=True)
        np.testing.assert_array_equal(lyap.stderr, g["stderr"][:], strict=True)
        np.testing.assert_array_equal(lyap.exponents_per_time, g["exponents_per_time"][:],
                                      strict=True)
        ky = {k: np.ravel(v)[0] for k, v in g.attrs.items()}.get("ky_dimension")
        if ky is not None:
            assert lyap.ky_dimension == ky
        params = {k: np.ravel(v)[0] for k, v in f["params"].attrs.items()}

        g = f["floquet"]
        np.testing.assert_array_equal(flo.jacobian, g["jacobian"][:], strict=True)
        np.testing.assert_array_equal(flo.multipliers.real, g["multipliers_re"][:])
        np.testing.assert_array_equal(flo.multipliers.imag, g["multipliers_im"][:])
        np.testing.assert_array_equal(flo.x, f["final/x"][:])

    k = case["vectors"] or 2 * case["n"]
    assert lyap.exponents.shape == lyap.stderr.shape == (k,)
    finite = np.isfinite(lyap.exponents)
    assert np.all(np.diff(lyap.exponents[finite]) <= 0)
    # directions removed by rests on the walls are -infinity, and come last
    assert np.all(lyap.exponents[~finite] == -np.inf) and np.all(np.diff(finite.astype(int)) <= 0)
    if k == 2 * case["n"]:
        # the same run as sim's (bit-identical records), so it has sim's rests
        assert_sum_rule(lyap.exponents, n=case["n"], damping=float(params["damping"]),
                        omega=case["omega"], restitution=float(params["restitution"]),
                        collisions_per_cycle=lyap.collisions_per_cycle, sticks=sim.sticks,
                        label=name)
    assert sim.x.shape == sim.v.shape == (case["cycles"], case["n"])
    if name == "sticking":  # the case is what it claims to be
        assert sim.sticks > 0 and sim.releases > 0
        assert sim.event_time.size > _runs._FIRST_EVENT_CAPACITY[0]


def test_shapes_units_and_readonly() -> None:
    sim = api.simulate(5, 1.8, 1.47, transient=3, cycles=7, phase=0.5)
    assert sim.x.shape == sim.v.shape == (7, 5) and sim.x.dtype == np.float64
    np.testing.assert_array_equal(sim.cycle, np.arange(4, 11))
    np.testing.assert_array_equal(sim.x[-1], sim.final_x)
    assert sim.drive_period == pytest.approx(2 * math.pi / 1.47)
    np.testing.assert_allclose(sim.time, (sim.cycle + 0.5 / (2 * math.pi)) * sim.drive_period)
    assert sim.site_counts.shape == (6,) and sim.site_counts.sum() == sim.impacts
    assert np.all(np.diff(sim.event_time) >= 0) and np.all(sim.event_time >= 3 * sim.drive_period)
    assert sim.event_site.min() >= 0 and sim.event_site.max() <= 5
    with pytest.raises(ValueError):
        sim.x[0, 0] = 1.0
    quiet = api.simulate(5, 1.8, 1.47, transient=3, cycles=7, phase=0.5, events=False)
    assert quiet.event_time.shape == (0,)
    np.testing.assert_array_equal(quiet.x, sim.x)


def test_event_buffer_retry_is_invisible(monkeypatch: pytest.MonkeyPatch) -> None:
    """A first guess of 1 event (retry) and of a million (no retry) give the same run."""
    args = dict(n=4, amplitude=1.7, omega=1.5, transient=5, cycles=30)
    monkeypatch.setattr(_runs, "_FIRST_EVENT_CAPACITY", (1, 1))
    small = api.simulate(**args)
    monkeypatch.setattr(_runs, "_FIRST_EVENT_CAPACITY", (10**6, 10**6))
    large = api.simulate(**args)
    assert small.event_time.size > 1
    for field in ("x", "v", "event_time", "event_site", "event_speed", "event_kind"):
        np.testing.assert_array_equal(getattr(small, field), getattr(large, field))


def test_no_impacts_is_the_linear_response() -> None:
    """Far apart oscillators never touch: the mean exponent is -b T nats per cycle and the
    records are the forced response P sin(w t) + Q cos(w t) once the start has decayed."""
    b, w, a = 0.05, 1.5, 0.1
    lyap = api.lyapunov(3, a, w, damping=b, spacing=100.0, cycles=20)
    assert np.mean(lyap.exponents) * math.log(2) == pytest.approx(-b * 2 * math.pi / w,
                                                                  rel=1e-12)
    assert lyap.collisions_per_cycle == 0
    # no impacts at all, so no rests
    assert_sum_rule(lyap.exponents, n=3, damping=b, omega=w, restitution=0.7,
                    collisions_per_cycle=lyap.collisions_per_cycle, sticks=0)
    sim = api.simulate(3, a, w, damping=b, spacing=100.0, transient=2000, cycles=3)
    d2 = (1 - w**2) ** 2 + (2 * b * w) ** 2
    np.testing.assert_allclose(sim.x, -2 * b * w * a / d2, rtol=1e-9)  # Q, at w t = 0
    np.testing.assert_allclose(sim.v, w * a * (1 - w**2) / d2, rtol=1e-9)  # w P


def test_poincare_jacobian_against_finite_differences() -> None:
    """The analytic Jacobian at a state equals central differences of simulate()."""
    n, args = 4, dict(amplitude=1.7, omega=1.5)
    start = api.simulate(n, **args, transient=30, cycles=1)
    z = np.column_stack([start.final_x, start.final_v]).ravel()  # (x1, v1, x2, v2, ...)

    def step(z: np.ndarray) -> np.ndarray:
        r = api.simulate(n, **args, x0=z[0::2], v0=z[1::2], cycles=2, events=False)
        return np.column_stack([r.final_x, r.final_v]).ravel()

    jac = api.poincare_jacobian(start.final_x, start.final_v, **args, cycles=2)
    assert jac.shape == (2 * n, 2 * n)
    eps = 1e-7
    fd = np.column_stack([(step(z + eps * e) - step(z - eps * e)) / (2 * eps)
                          for e in np.eye(2 * n)])
    # error of the differences: collision times are roots found to ~1e-15, divided by eps
    np.testing.assert_allclose(jac, fd, rtol=0, atol=1e-7)


def test_poincare_jacobian_matches_floquet_at_the_same_state() -> None:
    """floquet() evaluates the same kernel at the end of a run; poincare_jacobian() starts a
    fresh chain there, whose collision times are searched anew: equal to rounding."""
    flo = api.floquet(8, 1.7, 1.5, transient=50)
    jac = api.poincare_jacobian(flo.x, flo.v, 1.7, 1.5)
    np.testing.assert_allclose(jac, flo.jacobian, rtol=0, atol=1e-12)


def test_threads_give_the_same_results() -> None:
    """The layer keeps no state and f2py releases the GIL: threads are safe."""
    amplitudes = np.linspace(1.5, 2.5, 8)

    def job(a: float) -> api.Simulation:
        return api.simulate(8, a, 1.5, transient=100, cycles=100)

    serial = [job(a) for a in amplitudes]
    with ThreadPoolExecutor(4) as pool:
        parallel = list(pool.map(job, amplitudes))
    for s, p in zip(serial, parallel):
        np.testing.assert_array_equal(s.x, p.x)
        np.testing.assert_array_equal(s.event_time, p.event_time)


@pytest.mark.parametrize("kernel, names", [("ic_run", "RUN_OUTPUTS"),
                                           ("ic_sweep", "SWEEP_OUTPUTS"),
                                           ("ic_continuation", "CONTINUATION_OUTPUTS")])
def test_extension_outputs_in_documented_order(kernel: str, names: str) -> None:
    """api.RUN_OUTPUTS / SWEEP_OUTPUTS / CONTINUATION_OUTPUTS name the tuples f2py returns; a
    reordered layer must fail here."""
    first_line = getattr(_calls._extension(), kernel).__doc__.splitlines()[0]
    returned = first_line.split(" = ")[0].split(",")
    assert tuple(returned) == getattr(api, names)


# ---------------------------------------------------------------- 2. errors as exceptions

BASE = dict(n=4, amplitude=1.7, omega=1.5, cycles=5)
# (function, arguments beyond BASE, namelist arguments beyond BASE); None: same as Python
BAD: dict[str, tuple[str, dict[str, Any], dict[str, Any] | None]] = {
    "damping > 1": ("simulate", dict(damping=1.2), None),
    "damping < 0": ("simulate", dict(damping=-0.1), None),
    "restitution": ("simulate", dict(restitution=1.3), None),
    "amplitude": ("simulate", dict(amplitude=-1.0), None),
    "omega = 0": ("simulate", dict(omega=0.0), None),
    "omega NaN": ("simulate", dict(omega=float("nan")), None),
    "resonance": ("simulate", dict(damping=0.0, omega=1.0), None),
    "n = 0": ("simulate", dict(n=0), None),
    "n < 0": ("simulate", dict(n=-3), None),
    "n too large": ("simulate", dict(n=10**7 + 1), None),
    "spacing count": ("simulate", dict(spacing=[1.0, 1.0, 1.0]), None),
    "spacing < 0": ("simulate", dict(spacing=[1.0, 1.0, -1.0, 1.0, 1.0]), None),
    "spacing inf": ("simulate", dict(spacing=float("inf")), None),
    "boundary": ("simulate", dict(boundary="open"), None),
    "x0 count": ("simulate", dict(x0=[0.0, 0.0, 0.0]), None),
    "v0 count": ("simulate", dict(x0=[0.0] * 4, v0=[0.0] * 3), None),
    "x0 NaN": ("simulate", dict(x0=[0.0, float("nan"), 0.0, 0.0]), None),
    "overlap": ("simulate", dict(x0=[-1.5, 0.0, 0.0, 0.0]), None),
    "transient": ("simulate", dict(transient=-1), None),
    "cycles = 0": ("simulate", dict(cycles=0), None),
    "cycles > 1e12": ("simulate", dict(cycles=10**12 + 1), None),
    "phase": ("simulate", dict(phase=7.0), None),
    "stick_speed": ("simulate", dict(stick_speed=0.0), None),
    "too large": ("simulate", dict(n=1000, cycles=10**6), None),
    "vectors": ("lyapunov", dict(vectors=9), dict(lyapunov=True, vectors=9)),
    "qr_every": ("lyapunov", dict(qr_every=6), dict(lyapunov=True, qr_every=6)),
    "period 0": ("floquet", dict(period=0), dict(period=0)),
    "period 1001": ("floquet", dict(period=1001), dict(period=1001)),
}


# Messages that differ between Python and the CLI (none at present); strict xfail.
KNOWN_DIFFERENCES: dict[str, str] = {}


@pytest.mark.parametrize("name", [
    pytest.param(name, marks=pytest.mark.xfail(strict=True, reason=KNOWN_DIFFERENCES[name]))
    if name in KNOWN_DIFFERENCES else name for name in BAD])
def test_errors_match_cli(name: str, cli: Path, tmp_path: Path) -> None:
    function, args, nml_args = BAD[name]
    nml_args = args if nml_args is None else nml_args
    expected = cli_error(cli, namelist(**{**BASE, **nml_args}), tmp_path)
    with pytest.raises(ValueError) as info:
        getattr(api, function)(**{**BASE, **args})
    assert str(info.value) == expected


def test_random_start_errors_match_cli(cli: Path, tmp_path: Path) -> None:
    expected = cli_error(cli, namelist(**BASE, random=dict(seed=3, x_amp=0.6, v_amp=0.1)),
                         tmp_path)
    with pytest.raises(ValueError) as info:
        api.random_start(4, seed=3, x_amp=0.6, v_amp=0.1)
    assert str(info.value) == expected
    assert "x_amp" in expected


def test_random_start_without_amplitudes_is_refused_as_by_the_cli(cli: Path,
                                                                    tmp_path: Path) -> None:
    """x_amp = v_amp = 0 (their defaults) would start every seed from rest: refused, with the
    CLI's words, whether the amplitudes are left out or given as 0."""
    expected = cli_error(cli, namelist(**BASE) + "&initial kind = 'random', seed = 3 /\n",
                         tmp_path)
    assert expected.startswith("&initial: kind = 'random' needs x_amp or v_amp above 0")
    assert "x_amp in [0, half the smallest spacing = " in expected
    assert "v_amp in [0, 1e6]" in expected
    for amplitudes in ({}, dict(x_amp=0.0, v_amp=0.0)):
        with pytest.raises(ValueError) as info:
            api.random_start(4, seed=3, **amplitudes)
        assert str(info.value) == expected
    x1, v1 = api.random_start(4, seed=1, v_amp=0.1)  # one amplitude is enough: seeds differ
    x2, v2 = api.random_start(4, seed=2, v_amp=0.1)
    assert not np.any(x1) and not np.any(x2) and np.all(v1 != v2)


def test_random_start_is_the_cli_start(cli: Path, tmp_path: Path) -> None:
    x, v = api.random_start(7, seed=11, x_amp=0.4, v_amp=2.0, spacing=0.9)
    run_cli(cli, namelist(7, 1.0, 1.5, spacing=0.9, cycles=1,
                          random=dict(seed=11, x_amp=0.4, v_amp=2.0)), tmp_path)
    with h5py.File(tmp_path / "run.h5") as f:
        np.testing.assert_array_equal(x, f["initial/x"][:], strict=True)
        np.testing.assert_array_equal(v, f["initial/v"][:], strict=True)


def test_jacobian_errors() -> None:
    with pytest.raises(ValueError, match=r"^&lyapunov: jacobian_cycles = 0 is outside"):
        api.poincare_jacobian(np.zeros(3), np.zeros(3), 1.0, 1.5, cycles=0)
    with pytest.raises(ValueError, match=r"^initial state: the gap of bond 0"):
        api.poincare_jacobian([-2.0, 0.0], [0.0, 0.0], 1.0, 1.5)
    with pytest.raises(ValueError, match=r"^&initial: v0 needs n = 2 values"):
        api.poincare_jacobian([0.0, 0.0], [0.0], 1.0, 1.5)
    with pytest.raises(ValueError, match=r"^&chain: n = 0 is outside"):
        api.poincare_jacobian([], [], 1.0, 1.5)


PYTHON_ONLY: dict[str, tuple[str, dict[str, Any], type[Exception], str]] = {
    "n float": ("simulate", dict(n=4.0), TypeError, r"^n must be an integer, not float$"),
    "n str": ("simulate", dict(n="4"), TypeError, r"^n must be an integer, not str$"),
    "n bool": ("simulate", dict(n=True), TypeError, r"^n must be an integer, not bool$"),
    "n beyond int32": ("simulate", dict(n=2**40), ValueError,
                       r"^&chain: n = 1099511627776 is outside \[1, 10000000\]$"),
    "cycles beyond int64": ("simulate", dict(cycles=2**70), ValueError,
                            r"^&run: cycles = 1180591620717411303424 is outside \[1, 1e12\]$"),
    "amplitude None": ("simulate", dict(amplitude=None), TypeError,
                       r"^amplitude must be a real number, not NoneType$"),
    "amplitude str": ("simulate", dict(amplitude="1.7"), TypeError,
                      r"^amplitude must be a real number, not str$"),
    "boundary type": ("simulate", dict(boundary=1), TypeError,
                      r"^boundary must be a string, not int$"),
    "x0 2-D": ("simulate", dict(x0=np.zeros((2, 2))), ValueError,
               r"^&initial: x0 must be a 1-D array of n values, got shape \(2, 2\)$"),
    "x0 text": ("simulate", dict(x0=["a", "b", "c", "d"]), TypeError,
                r"^x0 must be an array of real numbers$"),
    "spacing 2-D": ("simulate", dict(spacing=np.ones((5, 1))), ValueError,
                    r"^&chain: spacing must be a 1-D array"),
    "vectors float": ("lyapunov", dict(vectors=1.5), TypeError,
                      r"^vectors must be an integer, not float$"),
    "events over max_size_mb": ("simulate", dict(n=4, amplitude=0.6, omega=0.5,
                                                 restitution=0.2, spacing=0.3, cycles=50,
                                                 max_size_mb=0.01), ValueError,
                                r"^events: this run has \d+ events, about .* MB, more than "
                                r"max_size_mb = 0.01; pass events=False or raise max_size_mb$"),
    "tangent memory": ("lyapunov", dict(n=20000, cycles=1), ValueError,
                       r"^&lyapunov: the tangent vectors of this run need about .* MB of "
                       r"memory, more than &output max_size_mb = 4096.0000; lower vectors, "
                       r"leave jacobian off, or raise max_size_mb$"),
}


@pytest.mark.parametrize("name", PYTHON_ONLY)
def test_python_side_errors(name: str) -> None:
    function, args, error, pattern = PYTHON_ONLY[name]
    with pytest.raises(error, match=pattern):
        getattr(api, function)(**{**BASE, **args})


def test_engine_failure_is_a_runtime_error(monkeypatch: pytest.MonkeyPatch) -> None:
    """Status 2 (the run failed) and unknown statuses raise RuntimeError, never pass."""
    message = np.frombuffer(b"engine: stuck", dtype=np.uint8).astype(np.int32)
    with pytest.raises(RuntimeError, match="^engine: stuck$"):
        _calls._raise_for(2, message.size, message)
    with pytest.raises(RuntimeError, match=r"status 4"):
        _calls._raise_for(4, message.size, message)


# -------------------------------------------------------------------------- 3. no leaks


def _rss_kib() -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    raise AssertionError("no VmRSS in /proc/self/status")


def test_no_leak() -> None:
    """10,000 short calls (n = 4, 5 cycles) after a warm-up of 500: RSS grows < 5 MB.

    The calls rotate through every entry point, including refused inputs (their error
    paths free what they allocated too)."""
    zeros = np.zeros(4)

    def calls(count: int) -> None:
        for i in range(count):
            kind = i % 7
            if kind == 0:
                api.simulate(4, 1.7, 1.5, cycles=5)
            elif kind == 1:
                lyap = api.lyapunov(4, 1.7, 1.5, cycles=5)
                # from rest, five cycles: impacts but no rests (api.simulate shows sticks = 0)
                assert_sum_rule(lyap.exponents, n=4, damping=0.05, omega=1.5,
                                restitution=0.7, collisions_per_cycle=lyap.collisions_per_cycle,
                                sticks=0)
            elif kind == 2:
                api.floquet(4, 1.7, 1.5, cycles=5)
            elif kind == 3:
                api.poincare_jacobian(zeros, zeros, 1.7, 1.5)
            elif kind == 4:
                api.random_start(4, seed=i, x_amp=0.3)
            elif kind == 5:
                with pytest.raises(ValueError):
                    api.simulate(4, 1.7, 1.5, damping=1.5, cycles=5)
            else:
                api.periodic_orbit(4, 1.7, 1.5, transient=5)

    calls(500)
    before = _rss_kib()
    calls(10_000)
    growth = _rss_kib() - before
    assert growth < 5 * 1024, f"resident memory grew by {growth} KiB over 10,000 calls"


# ------------------------------------------------------------------------- 4. the example


def _example() -> Any:
    spec = importlib.util.spec_from_file_location("fig1c_example", EXAMPLE)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_example_reproduces_the_fig1c_recipe(cli: Path, tmp_path: Path) -> None:
    """The example's data are those of `fpm run -- namelists/fig1c.nml`, bit for bit."""
    text = (ROOT / "namelists" / "fig1c.nml").read_text()
    # (the group ends at the first '/' outside quotes: its file name holds one)
    text = re.sub(r"&output(?:'[^']*'|[^'/])*/", "&output file = 'run.h5' /", text)
    result = run_cli(cli, text, tmp_path)
    assert result.returncode == 0, result.stderr
    sim = _example().compute()
    with h5py.File(tmp_path / "run.h5") as f:
        np.testing.assert_array_equal(sim.x, f["strobe/x"][:], strict=True)
        np.testing.assert_array_equal(sim.v, f["strobe/v"][:], strict=True)


def test_example_draws_with_the_figure_function() -> None:
    """The example draws the in-memory result with impactchain.figures.space_amplitude: the lines
    are the simulation's strobe rows."""
    example = _example()
    sim = example.compute(transient=20, cycles=15)
    (ax,) = example.draw(sim, seed=1).axes
    lines = [ln for ln in ax.get_lines() if ln.get_gid() == "strobe-0"]
    assert len(lines) == 15
    np.testing.assert_array_equal(lines[3].get_ydata(), sim.x[3])
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["random start, seed 1"]


def test_example_writes_a_png(tmp_path: Path) -> None:
    out = tmp_path / "fig1c.png"
    result = subprocess.run([sys.executable, str(EXAMPLE), str(out), "--transient", "100",
                             "--cycles", "50"], capture_output=True, text=True, timeout=120,
                            cwd=tmp_path)  # the installed package, from any directory
    assert result.returncode == 0, result.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    from PIL import Image

    with Image.open(out) as image:  # drawn by impactchain.figures: resolution and provenance
        assert image.info["dpi"] == pytest.approx((150, 150), abs=0.05)
        text = dict(image.text)
    assert text["Software"].startswith("impactchain.api 0.1.0; impactchain.figures ")
    assert text["Source"] == "(in memory, impactchain.api)"
    assert "&chain n = 16, amplitude = 1.7, omega = 1.5" in text["Description"]
    assert "&run transient = 100, cycles = 50" in text["Description"]
    bad = subprocess.run([sys.executable, str(EXAMPLE), str(out), "--amplitude", "-1"],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "&chain: amplitude = -1.0000000 is outside" in bad.stderr


# --------------------------------------- 4. long calls: Ctrl-C, progress; sweeps from Python

# A child process makes one long call (hours if never stopped) with a progress bar; the parent
# sends SIGINT (Ctrl-C) once the bar shows (the kernel has reported its first unit of work, on
# any machine) and measures how long the call takes to raise.
_LONG_CALLS = {
    "records": "api.simulate(16, 1.7, 1.5, cycles=10**6, events=False)",
    "transient": "api.simulate(16, 1.7, 1.5, transient=10**10, cycles=2)",
    "exponents": "api.lyapunov(16, 1.7, 1.5, transient=10, cycles=10**6)",
    "sweep": ("api.sweep(8, 6.0, 1.9, transient=250, cycles=50, parameter='amplitude', "
              "start=6.0, stop=1.0, step=-1e-5, threads=1)"),
    "continuation": ("api.continuation(16, 1.7, 1.5, transient=10**10, "
                     "parameter='amplitude', stop=3.0, step=0.01)"),
}
_CHILD = """
import signal, sys, time
signal.signal(signal.SIGINT, signal.default_int_handler)  # as at a terminal, even if this
# test runs where SIGINT is ignored (a background job): the child would inherit that
from impactchain import api
print("calling", flush=True)
try:
    {call}
except KeyboardInterrupt:
    print("KeyboardInterrupt", time.monotonic(), flush=True)
    sys.exit(0)
print("returned", flush=True)
"""


@pytest.mark.parametrize("name", sorted(_LONG_CALLS))
def test_ctrl_c_stops_a_long_call(name: str) -> None:
    """SIGINT during a call that would run for hours raises KeyboardInterrupt promptly (the
    kernel polls a stop flag at every cycle, record and sweep point; the wait is printed)."""
    import select
    import signal
    import time

    pytest.importorskip("tqdm")
    call = _LONG_CALLS[name][:-1] + ", progress=True)"
    child = subprocess.Popen([sys.executable, "-c", _CHILD.format(call=call)],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert child.stdout is not None
        assert child.stdout.readline() == "calling\n"
        assert child.stderr is not None  # the bar's first drawing: the kernel is running
        ready, _, _ = select.select([child.stderr], [], [], 120)
        assert ready and os.read(child.stderr.fileno(), 4096), "no progress bar"
        sent = time.monotonic()
        child.send_signal(signal.SIGINT)
        out, err = child.communicate(timeout=60)
    finally:
        child.kill()
    words = out.split()
    assert child.returncode == 0 and words[:1] == ["KeyboardInterrupt"], (out, err)
    waited = float(words[1]) - sent
    print(f"{name}: KeyboardInterrupt {waited:.3f} s after SIGINT")
    assert waited < 10  # (a second on an idle machine; the call itself would take hours)


def test_progress_bar_shows_and_changes_nothing(capfd: pytest.CaptureFixture[str]) -> None:
    """progress=True draws tqdm bars on stderr (the transient, then the records) and leaves
    every number as it was."""
    pytest.importorskip("tqdm")
    args = dict(n=16, amplitude=1.7, omega=1.5, transient=30000, cycles=30000, events=False)
    quiet = api.simulate(**args)
    capfd.readouterr()
    shown = api.simulate(**args, progress=True)
    err = capfd.readouterr().err
    assert "transient" in err and "records" in err and "cycle" in err, err
    np.testing.assert_array_equal(quiet.x, shown.x)
    np.testing.assert_array_equal(quiet.final_v, shown.final_v)


def _sweep_namelist(sweep: str, **kwargs: Any) -> str:
    return namelist(**kwargs) + sweep + "\n"


SWEEPS: dict[str, tuple[dict[str, Any], str]] = {
    # figure 10's kind: a continuation in A with exponents
    "amplitude-continuation": (
        dict(parameter="amplitude", start=2.4, stop=2.0, step=-0.1, lyapunov=True, vectors=4),
        "&sweep parameter = 'amplitude', start = 2.4, stop = 2.0, step = -0.1 /"),
    # a 2-D grid (omega along the branches, so drive_period is there), independent points
    "grid-independent": (
        dict(parameter="restitution", start=0.5, stop=0.7, step=0.1, parameter2="omega",
             start2=1.8, stop2=1.9, step2=0.1, mode="independent"),
        "&sweep parameter = 'restitution', start = 0.5, stop = 0.7, step = 0.1, "
        "mode = 'independent', parameter2 = 'omega', start2 = 1.8, stop2 = 1.9, "
        "step2 = 0.1 /"),
}


@pytest.mark.parametrize("name", sorted(SWEEPS))
def test_sweep_is_the_cli_file(name: str, cli: Path, tmp_path: Path) -> None:
    """api.sweep returns the CLI file's /sweep group as xarray reads it: the same
    dimensions, coordinates, variables and attributes, every value bit for bit."""
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    python_args, group = SWEEPS[name]
    run = dict(n=4, amplitude=2.2, omega=1.9, x0=[0.1, -0.1, 0.05, 0.0], transient=40,
               cycles=6)
    text = _sweep_namelist(group, **run, events=False,
                           lyapunov=bool(python_args.get("lyapunov")),
                           vectors=python_args.get("vectors", 0))
    result = run_cli(cli, text, tmp_path)
    assert result.returncode == 0, result.stderr
    ds = api.sweep(**run, **python_args, threads=2)
    with xr.open_dataset(tmp_path / "run.h5", engine="h5netcdf", group="sweep") as f:
        xr.testing.assert_identical(ds.drop_attrs(deep=False), f.load().drop_attrs(deep=False))
        for key in ("parameter", "parameter2", "mode"):
            assert ds.attrs[key] == f.attrs[key]
    # the figures take the Dataset as they take the file: the same Sweep, field by field
    from impactchain import figures
    from impactchain.io import read_run, run_from_sweep

    mine, theirs = run_from_sweep(ds), read_run(tmp_path / "run.h5")
    for name in ("values", "x", "collisions_per_cycle", "period", "exponents", "stderr",
                 "ky_dimension", "drive_period"):
        a, b = getattr(mine.sweep, name), getattr(theirs.sweep, name)
        assert (a is None) == (b is None), name
        if a is not None:
            np.testing.assert_array_equal(a, b, err_msg=name)
    assert mine.params.n == theirs.params.n and mine.params.cycles == theirs.params.cycles
    assert "&sweep parameter = " in mine.input_namelist
    if not mine.sweep.is_2d:
        figures.bifurcation(ds, sites=[1])


def test_sweep_threads_and_errors() -> None:
    """1 and 2 threads give the same bits; a bad sweep raises the CLI's message."""
    args = dict(n=4, amplitude=2.2, omega=1.9, transient=20, cycles=4, parameter="amplitude",
                start=2.0, stop=2.6, step=0.1, mode="independent", lyapunov=True)
    one = api.sweep(**args, threads=1)
    two = api.sweep(**args, threads=2)
    for var in one.data_vars:
        np.testing.assert_array_equal(one[var].values, two[var].values)
    assert one.x.dims == ("point", "record", "oscillator")
    with pytest.raises(ValueError, match="^&sweep: parameter = 'omgea' is not one of"):
        api.sweep(**{**args, "parameter": "omgea"})
    with pytest.raises(ValueError, match=r"^&sweep: point 2 \(amplitude = -0\.1.*\): "
                                         r"&chain: amplitude = -0\.1"):
        api.sweep(**{**args, "start": 0.0, "stop": -0.5, "step": -0.1})
    with pytest.raises(ValueError, match="parameter2 needs start2, stop2 and step2"):
        api.sweep(**args, parameter2="omega")


# Sweeps too large for memory, refused up front: (api.sweep's arguments, the &sweep group)
TOO_LARGE: dict[str, tuple[dict[str, Any], str]] = {
    # 5,000,001 points of 200 records, 32 GB: numpy's MemoryError before the check
    "long axis": (dict(parameter="amplitude", start=1.0, stop=6.0, step=1e-6),
                  "&sweep parameter = 'amplitude', start = 1.0, stop = 6.0, step = 1e-06 /"),
    "grid": (dict(parameter="amplitude", start=1.0, stop=2.0, step=1e-4, parameter2="omega",
                  start2=1.0, stop2=2.0, step2=1.25e-4),
             "&sweep parameter = 'amplitude', start = 1.0, stop = 2.0, step = 0.0001, "
             "parameter2 = 'omega', start2 = 1.0, stop2 = 2.0, step2 = 0.000125 /"),
    "max_size_mb": (dict(parameter="amplitude", start=1.0, stop=2.0, step=1e-3,
                         max_size_mb=0.5),
                    "&sweep parameter = 'amplitude', start = 1.0, stop = 2.0, step = 0.001 /"),
}


@pytest.mark.parametrize("name", sorted(TOO_LARGE))
def test_sweep_too_large_is_a_value_error(name: str, cli: Path, tmp_path: Path) -> None:
    """A sweep over max_size_mb (file or memory) or over 1e7 points raises ValueError with
    the CLI's message, from the dry run, before any array of its size is allocated."""
    python_args, group = TOO_LARGE[name]
    run = dict(n=4, amplitude=4.15, omega=1.5, cycles=200 if name == "long axis" else 10)
    limit = python_args.get("max_size_mb", 4096.0)
    expected = cli_error(cli, _sweep_namelist(group, **run, events=False, max_size_mb=limit),
                         tmp_path)
    assert expected.startswith("&sweep: ")
    with pytest.raises(ValueError) as info:
        api.sweep(**run, **python_args)
    assert str(info.value) == expected


def test_extension_needs_no_executable_stack() -> None:
    """The extension's ELF marks the stack non-executable: the library passes no internal
    procedures (which would need trampolines on the stack; monitors are objects), so it
    loads where executable stacks are refused."""
    import struct

    path = Path(_calls._extension().__file__)
    data = path.read_bytes()
    assert data[:4] == b"\x7fELF" and data[4] == 2, "a 64-bit ELF"  # ELFCLASS64
    phoff, = struct.unpack_from("<Q", data, 0x20)
    phentsize, phnum = struct.unpack_from("<HH", data, 0x36)
    flags = {}
    for i in range(phnum):
        p_type, p_flags = struct.unpack_from("<II", data, phoff + i * phentsize)
        flags[p_type] = p_flags
    pt_gnu_stack, pf_x = 0x6474E551, 1
    assert pt_gnu_stack in flags and not flags[pt_gnu_stack] & pf_x


# ------------------------------------------- 5. periodic orbits and their branches, from Python

# Figure 10's chain (n = 8, b = 0.05, K = 0.5, omega = 1.9) from rest after 5 cycles
FIG10 = dict(n=8, omega=1.9, damping=0.05, restitution=0.5, transient=5)
CONTINUATIONS: dict[str, tuple[float, dict[str, Any], list[str], float]] = {
    # A = 1 upwards: the forced response, no impacts, until the walls are grazed, and on
    # through the grazing onto the orbits with two wall impacts, through their own grazing
    # onto four impacts, to an impact at the section
    "grazing": (1.0, dict(parameter="amplitude", stop=3.5, step=0.1),
                ["grazing", "grazing", "section"], 2.616906570743),
    # A = 3 downwards on the impacting branch: it folds back near A = 2.885
    "fold": (3.0, dict(parameter="amplitude", stop=2.0, step=-0.05), ["fold"], 2.8851913052),
}


def _continuation_namelist(amplitude: float, group: dict[str, Any]) -> str:
    keys = ", ".join(f"{key} = {value!r}" for key, value in group.items())
    return (namelist(**{**FIG10, "amplitude": amplitude}, cycles=1, events=False)
            + f"&continuation {keys} /\n")


def _file_group(xr: Any, path: Path) -> Any:
    with xr.open_dataset(path, engine="h5netcdf", group="continuation") as f:
        return f.load()


def assert_same_bits(mine: Any, theirs: Any) -> None:
    """xarray's identical, and every float of every variable the same bits (NaN included)."""
    import xarray as xr

    xr.testing.assert_identical(mine, theirs)
    for name in mine.variables:
        a, b = mine[name].values, theirs[name].values
        if a.dtype.kind == "f":
            np.testing.assert_array_equal(a.view(np.uint64), b.view(np.uint64), err_msg=name)


@pytest.mark.parametrize("name", sorted(CONTINUATIONS))
def test_continuation_is_the_cli_file(name: str, cli: Path, tmp_path: Path) -> None:
    """api.continuation returns the CLI file's /continuation group as xarray reads it: the
    same dimensions, coordinates, variables, attributes (the group's too), every value bit
    for bit; the special point it ends at or passes is where it is known to be."""
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    amplitude, group, kinds, where = CONTINUATIONS[name]
    result = run_cli(cli, _continuation_namelist(amplitude, group), tmp_path)
    assert result.returncode == 0, result.stderr
    ds = api.continuation(**FIG10, amplitude=amplitude, **group)
    assert_same_bits(ds, _file_group(xr, tmp_path / "run.h5"))
    assert list(ds.special_kind.values) == kinds
    assert abs(float(ds.special_value[0]) - where) < 1e-8
    assert ds.attrs["start"] == amplitude and ds.attrs["parameter"] == "amplitude"
    assert (ds.iterations >= 0).all() and (ds.residual >= 0).all()
    assert float(ds.residual.max()) <= 1e-9  # converged orbits, Newton's last residuals
    assert ds.x.dims == ("point", "oscillator") and ds.strobe_x.sizes["iterate"] == 1


def test_continuation_takes_the_other_continuation_keys(cli: Path, tmp_path: Path) -> None:
    """A key of &continuation that api.continuation does not name (branch_points) goes as the
    CLI's: the chain of 12's branch point and the two branches switched to there, the same
    file group bit for bit."""
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    chain = dict(n=12, omega=2.3, damping=0.02, restitution=0.85, transient=500)
    group = dict(parameter="amplitude", stop=5.01, step=0.001)
    text = (namelist(**chain, amplitude=5.0, cycles=1, events=False)
            + "&continuation parameter = 'amplitude', stop = 5.01, step = 0.001, "
            "branch_points = 1 /\n")
    result = run_cli(cli, text, tmp_path)
    assert result.returncode == 0, result.stderr
    ds = api.continuation(**chain, amplitude=5.0, **group, branch_points=1)
    assert_same_bits(ds, _file_group(xr, tmp_path / "run.h5"))
    assert sorted(set(ds.branch.values.tolist())) == [0, 1, 2]
    assert "branch-point" in list(ds.special_kind.values)
    assert ds.parent.values.tolist() == [-1, 0, 0] and ds.parent.dims == ("branch_index",)
    assert list(ds.origin_kind.values) == ["", "branch-point", "branch-point"]


def test_continuation_capacity_retry_is_invisible(monkeypatch: pytest.MonkeyPatch) -> None:
    """With room for one of everything at first, the call runs again with the sizes the
    first call reported, and returns what the first guess gives."""
    xr = pytest.importorskip("xarray")
    amplitude, group, _, _ = CONTINUATIONS["fold"]
    ample = api.continuation(**FIG10, amplitude=amplitude, **group)
    monkeypatch.setattr(_continuations, "_first_room", lambda args: dict(
        npcap=1, nlong=1, nscap=1, ntext=1, nrcap=1, nbcap=1, nocap=1))
    xr.testing.assert_identical(api.continuation(**FIG10, amplitude=amplitude, **group), ample)


def test_periodic_orbit_is_the_cli_point(cli: Path, tmp_path: Path) -> None:
    """api.periodic_orbit is the one point of the CLI's &continuation max_points = 1 file
    (an impacting orbit of figure 10's chain), with Newton's history, its Jacobian (whose
    eigenvalues are the multipliers) and the bonds of its impacts (those of the simulator's
    events over one period from the orbit's state)."""
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    text = _continuation_namelist(3.0, dict(parameter="amplitude", max_points=1))
    assert run_cli(cli, text, tmp_path).returncode == 0
    f = _file_group(xr, tmp_path / "run.h5")
    assert f.sizes["point"] == 1
    orbit = api.periodic_orbit(**FIG10, amplitude=3.0)
    assert orbit.converged and orbit.reason == "" and orbit.stable == bool(f.stable[0])
    np.testing.assert_array_equal(orbit.x, f.x[0])
    np.testing.assert_array_equal(orbit.v, f.v[0])
    np.testing.assert_array_equal(orbit.multipliers.real, f.multipliers_re[0])
    np.testing.assert_array_equal(orbit.multipliers.imag, f.multipliers_im[0])
    assert orbit.min_gap == float(f.min_gap[0])
    assert orbit.min_impact_speed == float(f.min_impact_speed[0])
    assert orbit.impacts == int(f.impacts_per_period[0]) == orbit.impact_bonds.size > 0
    assert orbit.residuals[-1] == float(f.residual[0])
    assert orbit.residuals.size == int(f.iterations[0]) + 1
    # the same Fortran call as a continuation of one point
    assert_same_bits(api.continuation(**FIG10, amplitude=3.0, parameter="amplitude", stop=0.0,
                                      step=0.0, max_points=1), f)
    eigenvalues = np.linalg.eigvals(orbit.jacobian)
    for mu in orbit.multipliers:
        assert np.min(np.abs(eigenvalues - mu)) < 1e-10
    sim = api.simulate(8, 3.0, 1.9, damping=0.05, restitution=0.5, x0=orbit.x, v0=orbit.v,
                       cycles=1)
    hits = (sim.event_kind == api.IMPACT) | ((sim.event_kind == api.STICK)
                                            & (sim.event_speed > 0))
    np.testing.assert_array_equal(orbit.impact_bonds, sim.event_site[hits])
    for array in (orbit.x, orbit.multipliers, orbit.jacobian, orbit.impact_bonds):
        assert not array.flags.writeable


def test_newton_failure_is_a_result(cli: Path, tmp_path: Path) -> None:
    """An orbit that rests on the left wall once per cycle (test_corners' chain): Newton
    fails, which is a result with its reason, not an exception; the continuation from there
    has no point and says why, as the CLI's file does."""
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    chain = dict(n=2, amplitude=1.0, omega=0.4, damping=0.1, restitution=0.5,
                 spacing=[0.5, 0.5, 3.0], x0=[0.0, 0.0])
    orbit = api.periodic_orbit(**chain)
    assert not orbit.converged and "sticks on a wall" in orbit.reason
    assert orbit.multipliers.size == 0 and not orbit.stable and orbit.min_gap == math.inf
    assert orbit.residuals.size >= 1 and orbit.jacobian.shape == (4, 4)
    text = namelist(**chain, cycles=1, events=False) + \
        "&continuation parameter = 'amplitude', max_points = 1 /\n"
    assert run_cli(cli, text, tmp_path).returncode == 0
    f = _file_group(xr, tmp_path / "run.h5")
    ds = api.continuation(**chain, parameter="amplitude", stop=0.0, step=0.0, max_points=1)
    assert_same_bits(ds, f)
    assert ds.sizes["point"] == 0 and orbit.reason in ds.attrs["end_reason"]


# (the API's arguments beyond FIG10 at A = 1, the namelist's &continuation group)
BAD_CONTINUATIONS: dict[str, tuple[dict[str, Any], str]] = {
    "parameter": (dict(parameter="amplitdue", stop=2.0, step=0.1),
                  "parameter = 'amplitdue', stop = 2.0, step = 0.1"),
    "period": (dict(parameter="amplitude", stop=2.0, step=0.1, period=0),
               "parameter = 'amplitude', stop = 2.0, step = 0.1, period = 0"),
    "doublings": (dict(parameter="amplitude", stop=2.0, step=0.1, doublings=9),
                  "parameter = 'amplitude', stop = 2.0, step = 0.1, doublings = 9"),
    "step sign": (dict(parameter="amplitude", stop=2.0, step=-0.1),
                  "parameter = 'amplitude', stop = 2.0, step = -0.1"),
    "stop invalid": (dict(parameter="restitution", stop=1.5, step=0.1),
                     "parameter = 'restitution', stop = 1.5, step = 0.1"),
    "spacing list": (dict(parameter="spacing", stop=1.5, step=0.1,
                          spacing=[1.0] * 8 + [1.1]),
                     "parameter = 'spacing', stop = 1.5, step = 0.1"),
}


@pytest.mark.parametrize("name", sorted(BAD_CONTINUATIONS))
def test_continuation_errors_match_cli(name: str, cli: Path, tmp_path: Path) -> None:
    """A bad &continuation raises ValueError with the CLI's message, before any work."""
    args, group = BAD_CONTINUATIONS[name]
    chain = {**FIG10, "amplitude": 1.0, "spacing": args.get("spacing", 1.0)}
    text = namelist(**chain, cycles=1, events=False) + f"&continuation {group} /\n"
    expected = cli_error(cli, text, tmp_path)
    assert expected.startswith("&continuation")
    call = {key: value for key, value in args.items() if key != "spacing"}
    with pytest.raises(ValueError) as info:
        api.continuation(**chain, **call)
    assert str(info.value) == expected
    if name == "period":
        with pytest.raises(ValueError, match=re.escape(expected)):
            api.periodic_orbit(**{**chain, "period": 0})


def test_continuation_progress_shows_and_changes_nothing(
        capfd: pytest.CaptureFixture[str]) -> None:
    """progress=True draws a bar of the transient, then one of the orbits found, and leaves
    every number as it was."""
    xr = pytest.importorskip("xarray")
    pytest.importorskip("tqdm")
    args = dict(n=64, amplitude=3.0, omega=1.9, damping=0.05, restitution=0.5,
                transient=200_000, parameter="amplitude", stop=2.0, step=-0.05)
    quiet = api.continuation(**args)
    capfd.readouterr()
    shown = api.continuation(**args, progress=True)
    err = capfd.readouterr().err
    assert "transient" in err and "orbits" in err, err
    xr.testing.assert_identical(quiet, shown)


@pytest.mark.parametrize("call", [
    lambda: api.random_start(2 * 10**9),
    lambda: api.simulate(10**9, 1.7, 1.5),
    lambda: api.lyapunov(10**9, 1.7, 1.5),
], ids=["random_start", "simulate", "lyapunov"])
def test_huge_n_is_refused_before_anything_is_allocated(call: Any) -> None:
    """Issue 30, 9: n beyond the CLI's range is refused at once, with the CLI's message
    (before, random_start(2*10**9) used 15 GB over 29 s before its ValueError): a limit on
    the address space far below what n = 1e9 would take makes any allocation fail."""
    import resource
    import time
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    started = time.time()
    resource.setrlimit(resource.RLIMIT_AS, (8 * 2**30, hard))
    try:
        with pytest.raises(ValueError, match=r"^&chain: n = \d+ is outside \[1, 10000000\]$"):
            call()
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))
    assert time.time() - started < 2


def test_complex_x0_is_refused() -> None:
    """Issue 30, 9: a complex x0 or v0 is refused, not cast with a numpy warning."""
    for key in ("x0", "v0"):
        with pytest.raises(TypeError, match=f"^{key} must be an array of real numbers, "
                                            "not complex$"):
            api.simulate(3, 1.7, 1.5, cycles=2, **{key: np.array([0.1, 0, 0]) + 0.5j})


_POOL_CHILD = """
import signal, sys, time
signal.signal(signal.SIGINT, signal.default_int_handler)  # as at a terminal, even if this
# test runs where SIGINT is ignored (a background job): the child would inherit that
from concurrent.futures import ThreadPoolExecutor
from impactchain import _calls, api
calls = [lambda: api.simulate(16, 1.7, 1.5, transient=10**10, cycles=2)] * 3
try:
    with ThreadPoolExecutor(2) as pool:
        futures = [pool.submit(call) for call in calls]
        while len(_calls._RUNNING) < 2:  # both workers' kernels have started
            time.sleep(0.01)
        print("running", flush=True)
        for future in futures:
            future.result()
except KeyboardInterrupt:
    print("KeyboardInterrupt", flush=True)
    sys.exit(0)
print("returned", flush=True)
"""


def test_ctrl_c_stops_kernels_in_a_thread_pool() -> None:
    """Issue 30, 9: Ctrl-C stops kernels running in a ThreadPoolExecutor's workers (Python
    gives the signal to the main thread only) and the task the executor had queued, so that
    the executor's wait ends and KeyboardInterrupt comes out. Before, the workers' calls
    (hours each) went on and the program hung in the executor's wait."""
    import signal

    child = subprocess.Popen([sys.executable, "-c", _POOL_CHILD], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
    try:
        assert child.stdout is not None
        assert child.stdout.readline() == "running\n"
        child.send_signal(signal.SIGINT)
        out, err = child.communicate(timeout=120)  # (hours if the kernels went on)
    finally:
        child.kill()
    assert child.returncode == 0 and out.split() == ["KeyboardInterrupt"], (out, err)


# ------------------------------------------------- 6. any input key, one data model (xarray)

KICKED = dict(n=6, amplitude=1.7, omega=1.5, transient=5, cycles=30)


def _strobe_of(path: Path) -> tuple[np.ndarray, np.ndarray]:
    with h5py.File(path) as f:
        return f["strobe/x"][()], f["strobe/v"][()]


def test_any_input_key_is_the_cli_run(cli: Path, tmp_path: Path) -> None:
    """Issue 31, 2: &initial kick, which has no argument of its own, set from Python by its
    name or as group.key: the CLI's records for the same namelist, bit for bit (and not
    those of a run without it)."""
    text = namelist(**KICKED).replace("&run", "&initial kick = 0.75 /\n&run", 1)
    assert run_cli(cli, text, tmp_path).returncode == 0
    x, v = _strobe_of(tmp_path / "run.h5")
    for keys in ({"kick": 0.75}, {"initial.kick": 0.75}):
        sim = api.simulate(**KICKED, **keys)
        np.testing.assert_array_equal(sim.x.view(np.uint64), x.view(np.uint64))
        np.testing.assert_array_equal(sim.v.view(np.uint64), v.view(np.uint64))
        assert sim.params["overrides"] == ("initial.kick=0.75",)
    assert not np.array_equal(api.simulate(**KICKED).x, x)


def test_any_input_key_in_every_function() -> None:
    """Every run function passes the keys it has no argument for (here &run max_period,
    &initial kick): a bad value gets the reader's message for that key."""
    orbit = {key: value for key, value in KICKED.items() if key != "cycles"}
    calls = {
        "simulate": lambda **k: api.simulate(**KICKED, **k),
        "lyapunov": lambda **k: api.lyapunov(**KICKED, **k),
        "floquet": lambda **k: api.floquet(**KICKED, **k),
        "poincare_jacobian": lambda **k: api.poincare_jacobian(np.zeros(3), np.zeros(3), 1.7,
                                                               1.5, **k),
        "random_start": lambda **k: api.random_start(4, v_amp=0.1, **k),
        "sweep": lambda **k: api.sweep(**KICKED, parameter="amplitude", start=1.7, stop=1.8,
                                       step=0.1, **k),
        "continuation": lambda **k: api.continuation(**orbit, parameter="amplitude",
                                                     stop=1.8, step=0.1, **k),
        "periodic_orbit": lambda **k: api.periodic_orbit(**orbit, **k),
    }
    for name, call in calls.items():
        with pytest.raises(ValueError, match=r"&initial: kick = 50000000\. is outside"):
            call(**{"initial.kick": 5e7})
        with pytest.raises(ValueError, match=r"max_period"):
            call(max_period=-1)


def test_unknown_keys_are_named_at_once() -> None:
    """Issue 32, 8 from Python: the paper's symbols and misspelt keys, every one named in
    one message with the reader's "did you mean"."""
    with pytest.raises(ValueError) as caught:
        api.simulate(6, 1.7, 1.5, w=1.5, K=0.7, kik=0.1)
    message = str(caught.value)
    assert "3 unknown keys" in message, message
    assert "did you mean 'omega'" in message and "did you mean 'restitution'" in message
    assert "did you mean 'kick'" in message
    with pytest.raises(ValueError, match=r"unknown key 'kik'.*did you mean 'kick'"):
        api.simulate(6, 1.7, 1.5, kik=0.1)
    with pytest.raises(TypeError, match=r"^file is a key of &initial and &output: name one"):
        api.simulate(6, 1.7, 1.5, file="a.h5")
    with pytest.raises(TypeError, match=r"&lyapunov enabled is not set through \*\*keys"):
        api.simulate(6, 1.7, 1.5, enabled=True)


def _small_files(cli: Path, folder: Path) -> dict[str, Path]:
    """A run, a sweep, a continuation (branch) and a census file, as the recipes write them
    (small ones of the same kinds)."""
    inputs = {
        "run": namelist(**KICKED, lyapunov=True, period=1),
        "sweep": namelist(**{**KICKED, "cycles": 5}, events=False)
        + "&sweep parameter = 'amplitude', start = 1.7, stop = 1.9, step = 0.1 /\n",
        "branch": _continuation_namelist(3.0, CONTINUATIONS["fold"][1]),
        "census": namelist(**{**KICKED, "cycles": 20}, events=False)
        + "&census samples = 6, seed = 1, x_amp = 0.3, v_amp = 1.0 /\n",
    }
    files = {}
    for kind, text in inputs.items():
        (folder / kind).mkdir()
        result = run_cli(cli, text, folder / kind)
        assert result.returncode == 0, result.stderr
        files[kind] = folder / kind / "run.h5"
    return files


def test_open_datatree_reads_every_kind_of_file(cli: Path, tmp_path: Path) -> None:
    """Issue 32, 5: ``xarray.open_datatree(file)`` reads a whole run, sweep, branch and census
    file: every group, each dataset with the file schema's dimensions and units."""
    xr = pytest.importorskip("xarray")
    from impactchain import schema

    groups = {"run": {"strobe", "events", "final", "stats", "lyapunov", "floquet", "params"},
              "sweep": {"sweep", "params"}, "branch": {"continuation", "params"},
              "census": {"census", "params"}}
    for kind, path in _small_files(cli, tmp_path).items():
        with xr.open_datatree(path, engine="h5netcdf") as tree:
            assert groups[kind] <= set(tree.children), (kind, list(tree.children))
            assert tree.attrs["schema_version"] >= 1
            for group in groups[kind]:
                for name, variable in tree[group].variables.items():
                    entry = schema.output(f"/{group}/{name}")
                    if entry["units"]:
                        assert variable.attrs["units"] == entry["units"], (group, name)


def test_results_convert_to_the_files_tree(cli: Path, tmp_path: Path) -> None:
    """Issue 32, 5: ``to_xarray()`` of simulate, lyapunov and floquet results is the tree of
    the CLI's file: the same names, dimensions and units in each group, the same values."""
    xr = pytest.importorskip("xarray")
    assert run_cli(cli, namelist(**KICKED, lyapunov=True, period=1), tmp_path).returncode == 0
    trees = [api.simulate(**KICKED).to_xarray(), api.lyapunov(**KICKED).to_xarray(),
             api.floquet(**KICKED, period=1).to_xarray()]
    with xr.open_datatree(tmp_path / "run.h5", engine="h5netcdf") as file:
        for tree in trees:
            for group in tree.children:
                mine, theirs = tree[group].ds, file[group].ds
                for name, variable in mine.variables.items():
                    assert name in theirs.variables, (group, name)
                    assert variable.dims == theirs[name].dims, (group, name)
                    assert variable.attrs.get("units") == theirs[name].attrs.get("units")
                for name in mine.attrs:
                    assert name in theirs.attrs, (group, name)
        for name in ("x", "v"):
            np.testing.assert_array_equal(trees[0]["strobe"][name].values,
                                          file["strobe"][name].values)
        np.testing.assert_array_equal(trees[1]["lyapunov/exponents"].values,
                                      file["lyapunov/exponents"].values)
        np.testing.assert_array_equal(trees[2]["floquet/jacobian"].values,
                                      file["floquet/jacobian"].values)
    # each tree is a file's: its root says so, and a Floquet tree's equivalent input is the
    # CLI's run of the same Jacobian
    for tree in trees:
        assert tree.attrs["schema_version"] >= 2 and tree.attrs["complete"] == 1
    floquet_input = trees[2].attrs["input_namelist"]
    assert "jacobian = .true., jacobian_cycles = 1" in floquet_input
    (tmp_path / "again").mkdir()
    assert run_cli(cli, floquet_input, tmp_path / "again").returncode == 0
    [written] = (tmp_path / "again").glob("*.h5")
    with xr.open_datatree(written, engine="h5netcdf") as again:
        np.testing.assert_array_equal(trees[2]["floquet/jacobian"].values,
                                      again["floquet/jacobian"].values)


def test_census_is_the_cli_file(cli: Path, tmp_path: Path) -> None:
    """api.census returns the CLI's census file as an xarray tree, every value the same;
    its keys go as the CLI's --set, so a wrong one gets the CLI's message."""
    xr = pytest.importorskip("xarray")
    path = _small_files(cli, tmp_path)["census"]
    mine = api.census(**{**KICKED, "cycles": 20}, samples=6, seed=1, x_amp=0.3, v_amp=1.0)
    with xr.open_datatree(path, engine="h5netcdf") as file:
        xr.testing.assert_identical(mine["census"].ds, file["census"].ds)
        xr.testing.assert_identical(mine["params"].ds, file["params"].ds)
    with pytest.raises(ValueError, match=r"samples"):
        api.census(6, 1.7, 1.5, samples=0)


def test_figures_take_files_trees_and_results_alike(cli: Path, tmp_path: Path) -> None:
    """Issue 32, 5: the figures draw a file, its xarray tree or Dataset, and api results
    alike: branches and multipliers of api.continuation (which failed with "SchemaError:
    values: no such file" and "give an impactchain.api result"), the run figures of a
    tree."""
    xr = pytest.importorskip("xarray")
    import matplotlib.pyplot as plt

    from impactchain import figures

    files = _small_files(cli, tmp_path)
    amplitude, group, _, _ = CONTINUATIONS["fold"]
    ds = api.continuation(**FIG10, amplitude=amplitude, **group)
    tree = xr.open_datatree(files["branch"], engine="h5netcdf")
    for draw in (figures.branches, figures.multipliers):
        lines = []
        for data in (files["branch"], ds, tree):
            fig = draw(data)
            lines.append([line.get_ydata() for line in fig.axes[0].get_lines()])
            plt.close(fig)
        for drawn in lines[1:]:
            assert len(drawn) == len(lines[0])
            for a, b in zip(drawn, lines[0]):
                np.testing.assert_array_equal(a, b)
    run_tree = xr.open_datatree(files["run"], engine="h5netcdf")
    simulation = api.simulate(**KICKED)
    for data in (files["run"], run_tree, run_tree["strobe"], simulation,
                 simulation.to_xarray()):
        plt.close(figures.space_time_amplitude(data))
    tree.close()
    run_tree.close()


def test_periodic_orbit_converts_to_the_files_group(cli: Path, tmp_path: Path) -> None:
    """PeriodicOrbit.to_xarray() is the CLI file's /continuation group of the same input
    (&continuation max_points = 1), bit for bit, and the figures draw the orbit as that."""
    xr = pytest.importorskip("xarray")
    import matplotlib.pyplot as plt

    from impactchain import figures

    text = _continuation_namelist(3.0, dict(parameter="amplitude", max_points=1))
    assert run_cli(cli, text, tmp_path).returncode == 0
    orbit = api.periodic_orbit(**FIG10, amplitude=3.0)
    assert_same_bits(orbit.to_xarray(), _file_group(xr, tmp_path / "run.h5"))
    for draw in (figures.multipliers, figures.branches):
        plt.close(draw(orbit))
