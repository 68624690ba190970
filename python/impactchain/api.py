"""Call the impactchain kernels on numpy arrays, without namelists or files.

The functions here run the very same Fortran code as the command line
(``fpm run --profile release -- input.nml``), through the f2py extension
``impactchain._kernels`` (built when the package is installed: ``pip install .``, which
``make`` runs). Results are bit-identical to the CLI's on the equivalent namelist, and every
bad argument raises a :class:`ValueError` carrying the CLI's own message (``"&chain:
damping = 1.2000000 is outside [0, 1)"``): the checks are the library's
``validate_config``, not a copy of them.

Python and the equivalent namelist / CLI output:

- ``simulate(n, amplitude, omega, ...)``: ``&chain``, ``&initial``, ``&run``; the file's
  ``/strobe``, ``/events``, ``/final``, ``/stats``.
- ``lyapunov(..., vectors=k, qr_every=q)``: ``&lyapunov enabled=T, vectors=k,
  qr_every=q``; ``/lyapunov``.
- ``floquet(..., period=p)``: ``&lyapunov enabled=F, jacobian=T, jacobian_cycles=p``;
  ``/floquet``.
- ``poincare_jacobian(x, v, ...)``: the same kernel at any state (the CLI evaluates it
  only at the final state of a run).
- ``random_start(n, seed, x_amp, v_amp)``: ``&initial kind='random'``.
- ``sweep(..., parameter='amplitude', start, stop, step, ...)``: ``&sweep``; the file's
  ``/sweep`` as an :class:`xarray.Dataset` with the same names (needs xarray).
- ``continuation(..., parameter='amplitude', stop, step, ...)``: ``&continuation``; the
  file's ``/continuation`` as an :class:`xarray.Dataset`, identical to the file's as xarray
  reads it (needs xarray).
- ``periodic_orbit(..., period=p)``: ``&continuation max_points = 1`` (Newton only): the
  orbit of that file's one point, with Newton's history and the Jacobian.

Long calls (:func:`simulate`, :func:`lyapunov`, :func:`floquet`, :func:`sweep`,
:func:`continuation`, :func:`periodic_orbit`) run the Fortran in a worker thread with the GIL
released while this thread watches it: Ctrl-C stops the computation at its next transient
cycle, strobe record, sweep point or orbit, or within a cycle of millions of events (within a
second unless one orbit alone takes longer) and raises :class:`KeyboardInterrupt`; nothing is
returned from a stopped call. The same holds for calls running in worker threads (a
``ThreadPoolExecutor``'s): importing this module in the main thread lets Ctrl-C stop every
running kernel, unless a program or notebook has put its own SIGINT handler in place.
``progress=True`` shows a tqdm progress bar (needs tqdm).

Argument names are the namelist keys. ``x0 = v0 = None`` is a start at rest
(``kind='rest'``); arrays are ``kind='explicit'`` (``v0 = None`` then means v = 0).
``spacing`` is one number (uniform) or the n+1 bond spacings, bond 0 (left wall) first.

Units are the model's reduced ones (docs/model.md section 1.5): time in units of 1/(natural angular
frequency), so one drive cycle lasts ``T = 2 pi / omega``; lengths in the unit of
``spacing``; velocities in length/time. A run starts at t = 0 at drive phase 0; strobe
record j (j = 1..cycles) is taken at t = (transient + j) T + phase/omega.

Example::

    from impactchain import api
    sim = api.simulate(16, amplitude=1.7, omega=1.5, transient=500, cycles=200)
    sim.x.shape                           # (200, 16)
    lyap = api.lyapunov(16, 1.7, 1.5, transient=100, cycles=300)
    lyap.exponents[:3], lyap.stderr[:3]   # bits per drive cycle, descending
    api.floquet(15, 2.16, 1.5, transient=2000, period=2).multipliers  # (30,) complex
"""

from __future__ import annotations

import operator
import signal
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from impactchain import schema
from impactchain.schema import SCHEMA_DEFAULT, with_schema_defaults
from impactchain.schema import key as schema_key

try:
    from impactchain import _kernels
except ImportError as _exc:  # not built yet: say how to build it when a function is called
    _kernels = None
    _IMPORT_ERROR: ImportError | None = _exc
else:
    _IMPORT_ERROR = None

if TYPE_CHECKING:
    from impactchain.io import Run

__all__ = [
    "Simulation",
    "Lyapunov",
    "Floquet",
    "PeriodicOrbit",
    "simulate",
    "lyapunov",
    "floquet",
    "poincare_jacobian",
    "random_start",
    "sweep",
    "continuation",
    "periodic_orbit",
    "extension_available",
    "provenance",
    "IMPACT",
    "STICK",
    "RELEASE",
    "TOUCH",
]

IMPACT = 0
"""``event_kind``: an ordinary impact."""
STICK = 1
"""``event_kind``: an impact that ends chatter; the oscillator then rests on the wall."""
RELEASE = 2
"""``event_kind``: a resting oscillator leaves the wall (not a collision)."""
TOUCH = 3
"""``event_kind``: a contact closing slower than its gap can resolve: no impulse and no jump
of the tangent (not a collision)."""

_STATUS_OK, _STATUS_INVALID, _STATUS_FAILED, _STATUS_CAPACITY = 0, 1, 2, 3
_STATUS_STOPPED = 5
_POLL_SECONDS = 0.05  # how often the calling thread looks at a running kernel
#: chain_monitor's stages, as (description, unit) of a progress bar
_STAGES = {1: ("transient", "cycle"), 2: ("records", "cycle"), 3: ("sweep", "point")}
#: The same for a continuation, whose unit of progress is an orbit found on a branch
_CONTINUATION_STAGES = {**_STAGES, 3: ("orbits", "orbit")}
_INT32 = (-(2**31), 2**31 - 1)
_INT64 = (-(2**63), 2**63 - 1)
_FIRST_EVENT_CAPACITY = (1024, 1 << 20)  # bounds of the first guess of the event count
_BYTES_PER_EVENT = 24  # time, speed (float64), site, kind (int32)

#: Outputs of ``_kernels.ic_run``, in f2py's order (checked by test/python/package/test_api.py).
RUN_OUTPUTS = (
    "final_x", "final_v", "periods", "site_counts", "counts", "collisions_per_cycle", "nev",
    "k", "exponents", "stderr_bits", "stderr_cycles", "per_time", "ky", "jac", "mult_re",
    "mult_im", "status", "msg_len", "message",
)
#: Outputs of ``_kernels.ic_sweep``, in f2py's order (checked by test/python/package/test_api.py).
SWEEP_OUTPUTS = (
    "sizes", "values", "collisions", "period", "exponents", "stderr_bits", "stderr_cycles",
    "ky", "status", "msg_len", "message",
)
#: Outputs of ``_kernels.ic_continuation``, in f2py's order (checked by
#: test/python/package/test_api.py).
CONTINUATION_OUTPUTS = (
    "sizes", "values", "x", "v", "periods", "branch", "mult_re", "mult_im", "stable",
    "min_gap", "min_impact_speed", "impacts", "residual", "iterations", "special_index",
    "special_kind", "special_value", "end_reason", "start_x", "start_v", "start_jac",
    "start_mult_re", "start_mult_im", "start_residuals", "start_bonds", "start_min_gap",
    "start_min_impact_speed", "start_reason", "status", "msg_len", "message",
)
#: ic_continuation's sizes: points, special points, longest period, length of end_reason,
#: start converged, start residuals, start impacts, length of start_reason
_CONTINUATION_SIZES = ("npcap", "nscap", "nlong", "ntext", None, "nrcap", "nbcap", "ntext")
_FIRST_CONTINUATION_BYTES = 64 << 20  # memory of the first guess of a continuation's points


def extension_available() -> bool:
    """Whether the compiled extension ``impactchain._kernels`` could be imported."""
    return _kernels is not None


# ------------------------------------------------------------------------------ results


@dataclass(frozen=True, eq=False)
class Simulation:
    """Strobe records and events of one run (the CLI's ``/strobe``, ``/events``, ...).

    Arrays are read-only. ``n`` oscillators, ``cycles`` records, ``m`` events.
    """

    x: NDArray[np.float64]
    """(cycles, n) displacement of each oscillator from its equilibrium point at the
    section [length]; row j is drive cycle ``cycle[j]``."""
    v: NDArray[np.float64]
    """(cycles, n) velocity at the section [length/time]."""
    cycle: NDArray[np.int64]
    """(cycles,) drive-cycle index of each record: transient + 1 .. transient + cycles."""
    event_time: NDArray[np.float64]
    """(m,) time of each event since the start of the run [time]; only events of the
    recorded cycles (none during the transient), in time order. Empty when
    ``events=False``."""
    event_site: NDArray[np.int32]
    """(m,) bond of each event, 0..n: 0 the left wall | oscillator 1, k oscillators k |
    k+1, n oscillator n | right wall."""
    event_speed: NDArray[np.float64]
    """(m,) approach speed before the event, >= 0 [length/time]."""
    event_kind: NDArray[np.int32]
    """(m,) :data:`IMPACT`, :data:`STICK`, :data:`RELEASE` or :data:`TOUCH`."""
    final_x: NDArray[np.float64]
    """(n,) displacement at the end of the run (equal to ``x[-1]``) [length]."""
    final_v: NDArray[np.float64]
    """(n,) velocity at the end of the run [length/time]."""
    periods: NDArray[np.int32]
    """(n,) period of each oscillator in drive cycles, 0 when none up to 16 is found: the
    CLI's ``/strobe/period``, by the same Fortran rule over the last min(cycles, 80)
    records (docs/model.md section 6.3)."""
    site_counts: NDArray[np.int64]
    """(n+1,) impacts on each bond 0..n during the recorded cycles."""
    impacts: int
    """Impacts during the recorded cycles."""
    sticks: int
    """Impacts that ended in a sticking contact."""
    releases: int
    """Sticking contacts that let go."""
    touches: int
    """Contacts closing slower than their gap can resolve (no impulse; not impacts)."""
    collisions_per_cycle: float
    """Impacts per recorded drive cycle."""
    drive_period: float
    """T = 2 pi / omega [time]."""
    phase: float
    """Drive phase of the section [rad]."""
    params: Mapping[str, Any] = field(default_factory=dict)
    """The arguments as used (``n``, ``amplitude``, ..., ``spacing`` as n+1 values,
    ``x0``, ``v0`` or None for a start at rest, ``events``): what :meth:`to_run` needs to
    describe the run."""

    @property
    def time(self) -> NDArray[np.float64]:
        """(cycles,) time of each record since the start of the run [time]."""
        return self.cycle * self.drive_period + self.phase / (2 * np.pi) * self.drive_period

    def to_run(self, lyapunov: Lyapunov | None = None) -> Run:
        """This result as a :class:`impactchain.io.Run`, as if read from the CLI's file, so that
        the figure functions of :mod:`impactchain.figures` draw it (they call this themselves when
        given a Simulation). ``lyapunov``: a spectrum of the same parameters to add."""
        from impactchain.io import run_from_api

        return run_from_api(self, lyapunov)


@dataclass(frozen=True, eq=False)
class Lyapunov:
    """A Lyapunov spectrum (the CLI's ``/lyapunov``), read-only arrays of k exponents."""

    exponents: NDArray[np.float64]
    """(k,) exponents in bits per drive cycle, descending."""
    stderr: NDArray[np.float64]
    """(k,) standard error of each exponent, bits per drive cycle, read where it levels off
    with the block size (docs/model.md section 7.4)."""
    exponents_per_time: NDArray[np.float64]
    """(k,) the same exponents in nats per unit time."""
    ky_dimension: float
    """Kaplan-Yorke dimension of the k exponents (meaningful when k = 2n)."""
    collisions_per_cycle: float
    """Impacts per drive cycle over the averaged cycles (enters the sum rule)."""
    final_x: NDArray[np.float64]
    """(n,) displacement at the end of the run [length]."""
    final_v: NDArray[np.float64]
    """(n,) velocity at the end of the run [length/time]."""
    params: Mapping[str, Any] = field(default_factory=dict)
    """The arguments as used (as :attr:`Simulation.params`, with ``vectors``,
    ``qr_every``, ``window``)."""
    stderr_block: NDArray[np.int64] | None = None
    """(k,) drive cycles per block at which each standard error was read."""
    finite_time: Any = None
    """With ``window``: the finite-time exponents, an :class:`impactchain.io.FiniteTime`
    (``exponents`` (windows, k) in the frame's column order, ``descending`` in that of
    ``exponents``; ``cycle`` (windows,)), as the CLI's ``/finite_time``."""

    def to_run(self) -> Run:
        """This spectrum as a :class:`impactchain.io.Run` (``Run.lyapunov``, without running
        estimates), for :func:`impactchain.figures.spectrum`."""
        from impactchain.io import run_from_api

        return run_from_api(None, self)


@dataclass(frozen=True, eq=False)
class Floquet:
    """Jacobian of the p-cycle Poincare map at the end of a run, and its eigenvalues."""

    multipliers: NDArray[np.complex128]
    """(2n,) eigenvalues of ``jacobian`` (LAPACK dgeev order, as the CLI's
    ``/floquet/multipliers_re``, ``_im``). On a period-p orbit: its Floquet multipliers."""
    jacobian: NDArray[np.float64]
    """(2n, 2n) d(state after p cycles)/d(state), the state interleaved as
    (x_1, v_1, x_2, v_2, ..., x_n, v_n) (the engine's tangent layout, as in the CLI)."""
    x: NDArray[np.float64]
    """(n,) displacement where the Jacobian was evaluated (the end of the run) [length]."""
    v: NDArray[np.float64]
    """(n,) velocity there [length/time]."""


@dataclass(frozen=True, eq=False)
class PeriodicOrbit:
    """A period-p orbit of the stroboscopic map found by Newton shooting (docs/model.md
    section 11), or Newton's last iterate when it did not converge. Arrays are read-only."""

    converged: bool
    """Whether Newton converged (|P^p(z) - z| <= 1e-11 (1 + |z|), maximum norms)."""
    reason: str
    """Why Newton stopped without converging ('' when it converged)."""
    residuals: NDArray[np.float64]
    """(iterations + 1,) |P^p(z) - z| / (1 + |z|) of each iterate, the guess first."""
    x: NDArray[np.float64]
    """(n,) displacement on the section: the orbit's (or the last iterate's) state
    [length]."""
    v: NDArray[np.float64]
    """(n,) velocity on the section [length/time]."""
    multipliers: NDArray[np.complex128]
    """(2n,) Floquet multipliers, eigenvalues of ``jacobian`` (LAPACK dgeev order, as the
    file's ``multipliers_re``, ``_im``); empty when Newton did not converge."""
    impacts: int
    """Impacts over one period."""
    impact_bonds: NDArray[np.int32]
    """(impacts,) the bond of each impact of one period, in time order: 0 the left wall |
    oscillator 1, k oscillators k | k+1, n oscillator n | right wall."""
    min_impact_speed: float
    """Smallest impact speed over one period [length/time] (inf: no impacts)."""
    min_gap: float
    """Smallest gap at a local minimum over one period, other than a bond's own impacts
    [length] (inf: none, or Newton did not converge): near 0 a new impact is about to
    appear (grazing)."""
    stable: bool
    """Every multiplier inside the unit circle (False when Newton did not converge)."""
    jacobian: NDArray[np.float64]
    """(2n, 2n) Jacobian of P^p at ``x``, ``v``, the state interleaved as (x_1, v_1, ...,
    x_n, v_n) (as :attr:`Floquet.jacobian`)."""


# ---------------------------------------------------------------------------- functions


@with_schema_defaults
def simulate(
    n: int,
    amplitude: float,
    omega: float,
    damping: float = SCHEMA_DEFAULT,
    restitution: float = SCHEMA_DEFAULT,
    spacing: float | ArrayLike = SCHEMA_DEFAULT,
    boundary: str = SCHEMA_DEFAULT,
    x0: ArrayLike | None = None,
    v0: ArrayLike | None = None,
    transient: int = SCHEMA_DEFAULT,
    cycles: int = 100,
    events: bool = SCHEMA_DEFAULT,
    *,
    phase: float = SCHEMA_DEFAULT,
    stick_speed: float = SCHEMA_DEFAULT,
    max_size_mb: float = SCHEMA_DEFAULT,
    progress: bool = False,
) -> Simulation:
    """Run the chain: ``transient`` unrecorded drive cycles, then ``cycles`` recorded ones.

    Parameters (namelist keys; ranges are checked by the library):
        n: number of oscillators, 1..1e7.
        amplitude: drive amplitude A >= 0. omega: drive angular frequency, 1e-3..1e3.
        damping: b in [0, 1). restitution: K in [0, 1].
        spacing: one value (uniform) or the n+1 bond spacings, bond 0 first; > 0 [length].
        boundary: ``'fixed'`` (walls at both ends) or ``'free'`` (no walls).
        x0, v0: initial displacements / velocities, arrays of n values [length,
            length/time]; both None: at rest; v0 None with x0 given: v = 0.
        transient: cycles run before recording, 0..1e12. cycles: records, 1..1e12.
        events: keep the event stream (time, site, speed, kind of every event).
        phase: drive phase of the section in [0, 2 pi). stick_speed: the rebound speed
            below which chatter on a wall ends in sticking, (0, 1].
        max_size_mb: refuse runs whose records need more memory (the CLI's
            ``&output max_size_mb``, also applied to the event stream here).
        progress: show a tqdm progress bar (transient cycles, then records).

    Returns:
        A :class:`Simulation`; ``x``, ``v`` have shape (cycles, n).

    Raises:
        ValueError: a bad argument, with the CLI's message. TypeError: an argument of the
        wrong type. RuntimeError: the run itself failed (the engine's message).
        KeyboardInterrupt: Ctrl-C; the run stops at its next cycle or record.
    """
    cfg = _config(n, amplitude, omega, damping, restitution, spacing, boundary, x0, v0,
                  transient, cycles, phase, stick_speed, max_size_mb)
    keep_events = bool(events)
    out = _run(cfg, strobe=True, events=keep_events, progress=progress)
    nev = int(out["nev"])
    counts = out["counts"]
    return Simulation(
        x=_frozen(out["x"].T),
        v=_frozen(out["v"].T),
        cycle=_frozen(out["cycle"]),
        event_time=_frozen(out["ev_time"][:nev]),
        event_site=_frozen(out["ev_site"][:nev]),
        event_speed=_frozen(out["ev_speed"][:nev]),
        event_kind=_frozen(out["ev_kind"][:nev]),
        final_x=_frozen(out["final_x"]),
        final_v=_frozen(out["final_v"]),
        periods=_frozen(out["periods"]),
        site_counts=_frozen(out["site_counts"]),
        impacts=int(counts[0]),
        sticks=int(counts[1]),
        releases=int(counts[2]),
        touches=int(counts[3]),
        collisions_per_cycle=float(out["collisions_per_cycle"]),
        drive_period=2 * np.pi / cfg["omega"],
        phase=cfg["phase"],
        params=_used(cfg, boundary, events=keep_events),
    )


@with_schema_defaults
def lyapunov(
    n: int,
    amplitude: float,
    omega: float,
    damping: float = SCHEMA_DEFAULT,
    restitution: float = SCHEMA_DEFAULT,
    spacing: float | ArrayLike = SCHEMA_DEFAULT,
    boundary: str = SCHEMA_DEFAULT,
    x0: ArrayLike | None = None,
    v0: ArrayLike | None = None,
    transient: int = SCHEMA_DEFAULT,
    cycles: int = 100,
    vectors: int = SCHEMA_DEFAULT,
    *,
    qr_every: int = SCHEMA_DEFAULT,
    window: int = SCHEMA_DEFAULT,
    phase: float = SCHEMA_DEFAULT,
    stick_speed: float = SCHEMA_DEFAULT,
    max_size_mb: float = SCHEMA_DEFAULT,
    progress: bool = False,
) -> Lyapunov:
    """Lyapunov spectrum averaged over ``cycles`` drive cycles after ``transient``.

    An orthonormal frame of ``vectors`` tangent vectors (0: all 2n) is carried through the
    exact flow and the saltation matrices of every impact and re-orthonormalised (LAPACK
    QR) every ``qr_every`` cycles (0 <= qr_every <= cycles; 0, the default: at an adaptive
    interval, before the frame's columns are predicted to grow apart by 1e8, which gives the
    exponents of qr_every = 1 to rounding). The leading k exponents do not depend on k.
    ``window`` > 0: also the finite-time exponents over consecutive windows of that many
    recorded cycles (docs/model.md section 7.10; with qr_every > 1 a multiple of it). Other
    arguments as :func:`simulate`.

    Returns:
        A :class:`Lyapunov`: ``exponents`` and ``stderr`` (k,) in bits per drive cycle,
        descending, k = vectors or 2n, ``stderr_block`` (k,), and with ``window``
        ``finite_time``.
    """
    cfg = _config(n, amplitude, omega, damping, restitution, spacing, boundary, x0, v0,
                  transient, cycles, phase, stick_speed, max_size_mb)
    cfg["lyapunov"] = 1
    cfg["vectors"] = _int32(vectors, "&lyapunov: vectors", "[0, 2n] (0 means all 2n)")
    cfg["qr_every"] = _int32(qr_every, "&lyapunov: qr_every", "[0, cycles] (0: adaptive)")
    cfg["window"] = _int32(window, "&lyapunov: window", "[0, cycles] (0: none)")
    out = _run(cfg, strobe=False, events=False, progress=progress)
    k = int(out["k"])
    finite_time = None
    if cfg["window"] > 0:
        from impactchain.io import FiniteTime

        finite_time = FiniteTime(window=cfg["window"], cycle=_frozen(out["window_cycle"]),
                                 exponents=_frozen(out["windows"][:k].T))
    return Lyapunov(
        exponents=_frozen(out["exponents"][:k]),
        stderr=_frozen(out["stderr_bits"][:k]),
        exponents_per_time=_frozen(out["per_time"][:k]),
        ky_dimension=float(out["ky"]),
        collisions_per_cycle=float(out["collisions_per_cycle"]),
        final_x=_frozen(out["final_x"]),
        final_v=_frozen(out["final_v"]),
        params=_used(cfg, boundary, events=False, vectors=cfg["vectors"],
                     qr_every=cfg["qr_every"], window=cfg["window"]),
        stderr_block=_frozen(out["stderr_cycles"][:k]),
        finite_time=finite_time,
    )


@with_schema_defaults(period=("lyapunov", "jacobian_cycles"))
def floquet(
    n: int,
    amplitude: float,
    omega: float,
    damping: float = SCHEMA_DEFAULT,
    restitution: float = SCHEMA_DEFAULT,
    spacing: float | ArrayLike = SCHEMA_DEFAULT,
    boundary: str = SCHEMA_DEFAULT,
    x0: ArrayLike | None = None,
    v0: ArrayLike | None = None,
    transient: int = SCHEMA_DEFAULT,
    cycles: int = 1,
    period: int = SCHEMA_DEFAULT,
    *,
    phase: float = SCHEMA_DEFAULT,
    stick_speed: float = SCHEMA_DEFAULT,
    max_size_mb: float = SCHEMA_DEFAULT,
    progress: bool = False,
) -> Floquet:
    """Floquet multipliers: eigenvalues of the ``period``-cycle Poincare-map Jacobian at
    the state reached after ``transient + cycles`` drive cycles (where the CLI evaluates
    it). Run long enough to settle on a period-p orbit for them to be its multipliers.

    ``period``: p in [1, 1000] (the CLI's ``jacobian_cycles``). Other arguments as
    :func:`simulate`.

    Returns:
        A :class:`Floquet`: ``multipliers`` (2n,) complex, ``jacobian`` (2n, 2n).
    """
    cfg = _config(n, amplitude, omega, damping, restitution, spacing, boundary, x0, v0,
                  transient, cycles, phase, stick_speed, max_size_mb)
    cfg["jacobian"] = 1
    cfg["jacobian_cycles"] = _int32(period, "&lyapunov: jacobian_cycles", "[1, 1000]")
    out = _run(cfg, strobe=False, events=False, progress=progress)
    return Floquet(
        multipliers=_frozen(out["mult_re"] + 1j * out["mult_im"]),
        jacobian=_frozen(out["jac"]),
        x=_frozen(out["final_x"]),
        v=_frozen(out["final_v"]),
    )


@with_schema_defaults(cycles=("lyapunov", "jacobian_cycles"))
def poincare_jacobian(
    x: ArrayLike,
    v: ArrayLike,
    amplitude: float,
    omega: float,
    damping: float = SCHEMA_DEFAULT,
    restitution: float = SCHEMA_DEFAULT,
    spacing: float | ArrayLike = SCHEMA_DEFAULT,
    boundary: str = SCHEMA_DEFAULT,
    cycles: int = SCHEMA_DEFAULT,
    *,
    phase: float = SCHEMA_DEFAULT,
    stick_speed: float = SCHEMA_DEFAULT,
    max_size_mb: float = SCHEMA_DEFAULT,
) -> NDArray[np.float64]:
    """Jacobian of the ``cycles``-cycle Poincare map at the state (x, v) on the section.

    ``x``, ``v``: (n,) displacements [length] and velocities [length/time] at drive phase
    ``phase`` (as a strobe record of :func:`simulate` with the same phase). The state is a
    fresh start: no oscillator rests on a wall, every collision is searched from here.
    ``cycles``: 1..1000. Other arguments as :func:`simulate`.

    Returns:
        (2n, 2n) float64 matrix J with J[i, j] = d z'_i / d z_j, the state interleaved as
        z = (x_1, v_1, x_2, v_2, ..., x_n, v_n): the product of the exact propagators and
        saltation matrices met along the way (docs/model.md sections 4 and 7.9).
    """
    xs = _vector(x, "&initial: x0")
    vs = _vector(v, "&initial: v0")
    n = xs.size
    args = dict(
        spacing=_spacing(spacing),
        damping=_float(damping, "damping"),
        restitution=_float(restitution, "restitution"),
        amplitude=_float(amplitude, "amplitude"),
        omega=_float(omega, "omega"),
        boundary=_name(boundary, "boundary"),
        x0=xs,
        v0=vs,
        phase=_float(phase, "phase"),
        stick_speed=_float(stick_speed, "stick_speed"),
        max_size_mb=_float(max_size_mb, "max_size_mb"),
        jacobian_cycles=_int32(cycles, "&lyapunov: jacobian_cycles", "[1, 1000]"),
    )
    kernels = _extension()
    jac, status, msg_len, message = kernels.ic_jacobian(**args, dry_run=1, mj=0)
    if status == _STATUS_OK:  # valid: now with room for the result
        jac, status, msg_len, message = kernels.ic_jacobian(**args, dry_run=0, mj=2 * n)
    _raise_for(status, msg_len, message)
    return _frozen(jac)


@with_schema_defaults
def random_start(
    n: int,
    seed: int = SCHEMA_DEFAULT,
    x_amp: float = SCHEMA_DEFAULT,
    v_amp: float = SCHEMA_DEFAULT,
    spacing: float | ArrayLike = SCHEMA_DEFAULT,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The CLI's seeded random start (``&initial kind='random'``): x_i uniform in
    [-x_amp, x_amp), v_i in [-v_amp, v_amp), from the same portable generator, so that
    ``simulate(..., x0=x, v0=v)`` equals a CLI run with that ``&initial`` group.

    ``x_amp`` must be below half the smallest spacing (no overlapping start), and ``x_amp``
    and ``v_amp`` must not both be 0 (every seed would be the same start, rest): ValueError
    with the CLI's message.

    Returns:
        (x, v), each (n,) float64 [length, length/time].
    """
    nn = _n(n)
    args = dict(
        n=nn,
        spacing=_spacing(spacing),
        seed=_int32(seed, "&initial: seed", "the 32-bit integers"),
        x_amp=_float(x_amp, "x_amp"),
        v_amp=_float(v_amp, "v_amp"),
    )
    kernels = _extension()
    x, v, status, msg_len, message = kernels.ic_random_start(**args, dry_run=1, nf=0)
    if status == _STATUS_OK:
        x, v, status, msg_len, message = kernels.ic_random_start(**args, dry_run=0, nf=nn)
    _raise_for(status, msg_len, message)
    return _frozen(x), _frozen(v)


@with_schema_defaults
def sweep(
    n: int,
    amplitude: float,
    omega: float,
    damping: float = SCHEMA_DEFAULT,
    restitution: float = SCHEMA_DEFAULT,
    spacing: float | ArrayLike = SCHEMA_DEFAULT,
    boundary: str = SCHEMA_DEFAULT,
    x0: ArrayLike | None = None,
    v0: ArrayLike | None = None,
    transient: int = SCHEMA_DEFAULT,
    cycles: int = 100,
    *,
    parameter: str,
    start: float,
    stop: float,
    step: float,
    mode: str = SCHEMA_DEFAULT,
    parameter2: str | None = None,
    start2: float | None = None,
    stop2: float | None = None,
    step2: float | None = None,
    lyapunov: bool = False,
    vectors: int = SCHEMA_DEFAULT,
    qr_every: int = SCHEMA_DEFAULT,
    phase: float = SCHEMA_DEFAULT,
    stick_speed: float = SCHEMA_DEFAULT,
    max_size_mb: float = SCHEMA_DEFAULT,
    threads: int = 0,
    progress: bool = False,
) -> Any:
    """A parameter sweep (bifurcation diagram, Lyapunov scan): the CLI's ``&sweep``.

    ``parameter`` (``'amplitude'``, ``'omega'``, ``'damping'``, ``'restitution'`` or
    ``'spacing'``) runs from ``start`` to ``stop`` in steps of ``step``; its value among the
    run's arguments is replaced at each point. ``mode='continuation'`` starts each point from
    the final state of the one before (the paper's procedure), ``'independent'`` every point
    from ``x0``, ``v0``. ``parameter2``, ``start2``, ``stop2``, ``step2``: a second axis, each
    of its values a branch of its own (a 2-D grid). Each point runs ``transient`` cycles and
    records ``cycles`` strobe records; with ``lyapunov=True`` also ``vectors`` exponents (0:
    all 2n). Branches run on ``threads`` OpenMP threads (0: ``OMP_NUM_THREADS``, else every
    core); the numbers are the same for any count, and the CLI's on the same namelist.
    Ctrl-C stops the sweep once the points running finish (:class:`KeyboardInterrupt`);
    ``progress=True`` shows a tqdm bar of the points. Other arguments as :func:`simulate`.

    Returns:
        An :class:`xarray.Dataset`, the CLI file's ``/sweep`` group
        (``xarray.open_dataset(path, engine="h5netcdf", group="sweep")``) with the same
        names: dimensions ``point`` (the values of ``parameter``; ``point2`` for
        ``parameter2``), ``record``, ``oscillator``, ``exponent``; variables ``x``
        (point, [point2,] record, oscillator), ``collisions_per_cycle``, ``period``
        (0: aperiodic), with ``lyapunov`` also ``exponents``, ``stderr`` (bits per drive
        cycle) and ``ky_dimension``, and ``drive_period`` in an ``omega`` sweep;
        attributes ``parameter``, ``parameter2`` ('' for 1-D), ``mode`` and the run's
        other arguments.

    Raises:
        ImportError: xarray is missing. ValueError, TypeError, RuntimeError: as
        :func:`simulate` (a point outside its range names the point).
    """
    try:
        import xarray as xr
    except ImportError:
        raise ImportError("api.sweep returns an xarray.Dataset: pip install xarray") from None
    cfg = _config(n, amplitude, omega, damping, restitution, spacing, boundary, x0, v0,
                  transient, cycles, phase, stick_speed, max_size_mb)
    for name in ("record_events", "jacobian", "jacobian_cycles"):
        del cfg[name]
    cfg["lyapunov"] = int(bool(lyapunov))
    cfg["vectors"] = _int32(vectors, "&lyapunov: vectors", "[0, 2n] (0 means all 2n)")
    cfg["qr_every"] = _int32(qr_every, "&lyapunov: qr_every", "[0, cycles] (0: adaptive)")
    two_d = parameter2 is not None
    if two_d and (start2 is None or stop2 is None or step2 is None):
        raise ValueError("&sweep: parameter2 needs start2, stop2 and step2")
    args = dict(
        cfg,
        parameter=_name(parameter, "parameter"),
        start=_float(start, "start"),
        stop=_float(stop, "stop"),
        step=_float(step, "step"),
        mode=_name(mode, "mode"),
        parameter2=_name(parameter2 if two_d else "", "parameter2"),
        start2=_float(start2, "start2") if two_d else 0.0,
        stop2=_float(stop2, "stop2") if two_d else 0.0,
        step2=_float(step2, "step2") if two_d else 0.0,
        threads=_int32(threads, "threads", "the non-negative 32-bit integers"),
    )
    if args["threads"] < 0:
        raise ValueError(f"threads = {args['threads']} is outside [0, 2**31) (0: the default)")
    kernels = _extension()
    no_control = np.zeros(4, dtype=np.int64)
    out = dict(zip(SWEEP_OUTPUTS, kernels.ic_sweep(**args, dry_run=1, nf=1, nc=1, npts=1,
                                                   kcap=0, x=np.empty((1, 1, 1), order="F"),
                                                   control=no_control), strict=True))
    _raise_for(out["status"], out["msg_len"], out["message"])
    n1, n2, k = (int(i) for i in out["sizes"])
    sizes = dict(nf=cfg["n"], nc=cfg["cycles"], npts=n1 * n2, kcap=k)
    x = np.empty((cfg["n"], cfg["cycles"], n1 * n2), order="F")
    result = _watched(kernels.ic_sweep, dict(args, dry_run=0, x=x, **sizes), progress)
    out = dict(zip(SWEEP_OUTPUTS, result, strict=True), x=x)
    _raise_for(out["status"], out["msg_len"], out["message"])
    return _sweep_dataset(xr, out, cfg, args, n1, n2, k, boundary)


def _sweep_dataset(xr: Any, out: dict[str, Any], cfg: dict[str, Any], args: dict[str, Any],
                   n1: int, n2: int, k: int, boundary: str) -> Any:
    """ic_sweep's arrays (point p = i + n1 j, Fortran order) as the file's /sweep group:
    the same dimensions, coordinates, variables and variable attributes (``units`` UDUNITS'
    as in the file, ``model_units`` the reduced ones)."""
    parameter = _text(args["parameter"])
    parameter2 = _text(args["parameter2"])
    two_d = len(parameter2) > 0

    def grid(a: Any) -> NDArray[Any]:
        """(..., n1 n2) in Fortran order -> (n1, [n2,] ...), the file's layout."""
        a = np.moveaxis(np.asarray(a), -1, 0)           # [p, ...], p = i + n1 j
        a = np.swapaxes(a.reshape((n2, n1) + a.shape[1:]), 0, 1)  # [i, j, ...]
        return np.ascontiguousarray(a if two_d else a[:, 0])

    axes = 2 if two_d else 1

    def described(name: str, values: Any, parameter: str | None = None,
                  along: int = 1) -> tuple[Any, ...]:
        return schema.variable(f"/sweep/{name}", values, parameter, axes, along)

    values = np.asarray(out["values"])
    coords = {
        "point": described("point", values[0, :n1].copy(), parameter),
        "oscillator": described("oscillator", np.arange(1, cfg["n"] + 1, dtype=np.int32)),
    }
    if two_d:
        coords["point2"] = described("point2", values[1, ::n1].copy(), parameter2)
    data = {
        "x": described("x", grid(np.asarray(out["x"]).transpose(1, 0, 2))),
        "collisions_per_cycle": described("collisions_per_cycle", grid(out["collisions"])),
        "period": described("period", grid(out["period"])),
    }
    if k > 0:
        coords["exponent"] = described("exponent", np.arange(1, k + 1, dtype=np.int32))
        data["exponents"] = described("exponents", grid(out["exponents"]))
        data["stderr"] = described("stderr", grid(out["stderr_bits"]))
        data["stderr_block"] = described("stderr_block", grid(out["stderr_cycles"]))
        data["ky_dimension"] = described("ky_dimension", grid(out["ky"]))
    if "omega" in (parameter, parameter2):
        along = 1 if parameter == "omega" else 2
        axis = ("point", "point2")[along - 1]
        data["drive_period"] = described("drive_period", 2 * np.pi / coords[axis][1],
                                         along=along)
    attrs: dict[str, Any] = dict(parameter=parameter, parameter2=parameter2,
                                 mode=_text(args["mode"]))
    attrs.update({key: cfg[key] for key in ("n", "amplitude", "omega", "damping",
                                             "restitution", "transient", "cycles", "phase")
                  if key not in (parameter, parameter2)})
    used = _used(cfg, boundary, events=False, vectors=cfg["vectors"], qr_every=cfg["qr_every"])
    if parameter != "spacing" and parameter2 != "spacing":
        attrs["spacing"] = np.asarray(used["spacing"])
    attrs.update(boundary=used["boundary"], stick_speed=cfg["stick_speed"],
                 code_version=used["code_version"],
                 input_namelist=_sweep_namelist(used, k > 0, attrs, args))
    return xr.Dataset(data, coords=coords, attrs=attrs)


def _sweep_namelist(used: Mapping[str, Any], lyapunov: bool, attrs: Mapping[str, Any],
                    args: Mapping[str, Any]) -> str:
    """The command-line input equal to this sweep (io's equivalent namelist + &sweep)."""
    from impactchain.io import _equivalent_namelist

    text = _equivalent_namelist(used, lyapunov)
    group = (f"&sweep parameter = '{attrs['parameter']}', start = {args['start']!r}, "
             f"stop = {args['stop']!r}, step = {args['step']!r}, mode = '{attrs['mode']}'")
    if attrs["parameter2"]:
        group += (f", parameter2 = '{attrs['parameter2']}', start2 = {args['start2']!r}, "
                  f"stop2 = {args['stop2']!r}, step2 = {args['step2']!r}")
    return text + group + " /\n"


def _text(name: NDArray[np.int32]) -> str:
    """A name passed to the kernels as byte values (:func:`_name`), as text."""
    return bytes(np.asarray(name).astype(np.uint8)).decode()


@with_schema_defaults
def continuation(
    n: int,
    amplitude: float,
    omega: float,
    damping: float = SCHEMA_DEFAULT,
    restitution: float = SCHEMA_DEFAULT,
    spacing: float | ArrayLike = SCHEMA_DEFAULT,
    boundary: str = SCHEMA_DEFAULT,
    x0: ArrayLike | None = None,
    v0: ArrayLike | None = None,
    transient: int = SCHEMA_DEFAULT,
    *,
    parameter: str,
    stop: float,
    step: float,
    period: int = SCHEMA_DEFAULT,
    max_points: int = SCHEMA_DEFAULT,
    doublings: int = SCHEMA_DEFAULT,
    phase: float = SCHEMA_DEFAULT,
    stick_speed: float = SCHEMA_DEFAULT,
    progress: bool = False,
) -> Any:
    """Branches of periodic orbits followed in one parameter: the CLI's ``&continuation``.

    Newton finds the period-``period`` orbit from the state on the section (drive phase
    ``phase``) after ``transient`` cycles from ``x0``, ``v0``; pseudo-arclength continuation
    then follows its branch in ``parameter`` (``'amplitude'``, ``'omega'``, ``'damping'``,
    ``'restitution'`` or ``'spacing'``, whose value among the arguments is the start) towards
    ``stop``, first step ``step`` (its sign: the direction), at most ``max_points`` orbits per
    branch, and ``doublings`` levels of the period-doubled branches born at its period
    doublings (docs/model.md section 12). Folds, period doublings, Neimark-Sacker points and
    grazings are located; a branch ends at a grazing, at a bound of the parameter, after
    ``max_points`` or when Newton fails, and says why (``end_reason``). Other arguments as
    :func:`simulate`. Ctrl-C stops the work at its next transient cycle or orbit
    (:class:`KeyboardInterrupt`); ``progress=True`` shows a tqdm bar of them.

    Returns:
        An :class:`xarray.Dataset`, identical to the CLI file's ``/continuation`` group
        (``xarray.open_dataset(path, engine="h5netcdf", group="continuation")``) for the
        same input: dimensions ``point`` (the orbits, branch after branch), ``oscillator``,
        ``multiplier``, ``iterate`` (section crossings of the longest period), ``special``;
        variables ``values`` (the parameter), ``x``, ``v``, ``strobe_x`` (NaN beyond a
        point's period), ``period``, ``branch``, ``multipliers_re``, ``multipliers_im``,
        ``stable``, ``min_gap``, ``min_impact_speed`` (inf: none), ``impacts_per_period``,
        ``residual``, ``iterations``, ``special_index`` (0-based point), ``special_kind``,
        ``special_value``; attributes ``parameter``, ``phase``, ``start``, ``stop``,
        ``step``, ``end_reason``. A failure of Newton at the start is a result: no point,
        and ``end_reason`` says why.

    Raises:
        ImportError: xarray is missing. ValueError: a bad argument, with the CLI's message.
        TypeError: an argument of the wrong type. RuntimeError: the engine failed.
        KeyboardInterrupt: Ctrl-C.
    """
    try:
        import xarray as xr
    except ImportError:
        raise ImportError("api.continuation returns an xarray.Dataset: pip install xarray"
                          ) from None
    cfg, args = _continuation_args(n, amplitude, omega, damping, restitution, spacing,
                                   boundary, x0, v0, transient, phase, stick_speed, parameter,
                                   stop, step, period, max_points, doublings)
    out = _continue(args, progress)
    return _continuation_dataset(xr, out, cfg, args)


@with_schema_defaults
def periodic_orbit(
    n: int,
    amplitude: float,
    omega: float,
    damping: float = SCHEMA_DEFAULT,
    restitution: float = SCHEMA_DEFAULT,
    spacing: float | ArrayLike = SCHEMA_DEFAULT,
    boundary: str = SCHEMA_DEFAULT,
    x0: ArrayLike | None = None,
    v0: ArrayLike | None = None,
    transient: int = SCHEMA_DEFAULT,
    period: int = SCHEMA_DEFAULT,
    *,
    phase: float = SCHEMA_DEFAULT,
    stick_speed: float = SCHEMA_DEFAULT,
    progress: bool = False,
) -> PeriodicOrbit:
    """The period-``period`` orbit (p in 1..10000 drive cycles) that Newton shooting finds
    from the state on the section (drive phase ``phase``) after ``transient`` cycles from
    ``x0``, ``v0``: the CLI's ``&continuation max_points = 1`` run (the same Fortran call;
    the orbit is that file's one point). Other arguments as :func:`simulate`.

    Returns:
        A :class:`PeriodicOrbit`. Newton's failure is a result, not an exception:
        ``converged`` False and ``reason`` (an orbit that rests on a wall, no decrease of the
        residual at a grazing, ...), with the last iterate's state, Jacobian and impacts.

    Raises:
        ValueError: a bad argument, with the CLI's message. TypeError: an argument of the
        wrong type. RuntimeError: the engine failed. KeyboardInterrupt: Ctrl-C.
    """
    _, args = _continuation_args(n, amplitude, omega, damping, restitution, spacing,
                                 boundary, x0, v0, transient, phase, stick_speed,
                                 "amplitude", 0.0, 0.0, period, 1, 0)
    out = _continue(args, progress)
    converged = bool(out["sizes"][4])
    multipliers = out["start_mult_re"] + 1j * out["start_mult_im"]
    return PeriodicOrbit(
        converged=converged,
        reason=_text(out["start_reason"]),
        residuals=_frozen(out["start_residuals"]),
        x=_frozen(out["start_x"]),
        v=_frozen(out["start_v"]),
        multipliers=_frozen(multipliers if converged else np.zeros(0, dtype=np.complex128)),
        impacts=int(out["start_bonds"].size),
        impact_bonds=_frozen(out["start_bonds"]),
        min_impact_speed=float(out["start_min_impact_speed"]),
        min_gap=float(out["start_min_gap"]),
        stable=bool(out["stable"][0]) if out["values"].size else False,
        jacobian=_frozen(out["start_jac"]),
    )


def _continuation_args(n: Any, amplitude: Any, omega: Any, damping: Any, restitution: Any,
                       spacing: Any, boundary: Any, x0: Any, v0: Any, transient: Any,
                       phase: Any, stick_speed: Any, parameter: Any, stop: Any, step: Any,
                       period: Any, max_points: Any, doublings: Any
                       ) -> tuple[dict[str, Any], dict[str, Any]]:
    """The run's arguments (as :func:`_config`) and those of ``ic_continuation``."""
    cfg = _config(n, amplitude, omega, damping, restitution, spacing, boundary, x0, v0,
                  transient, 1, phase, stick_speed, 4096.0)
    args = {key: cfg[key] for key in ("n", "spacing", "damping", "restitution", "amplitude",
                                      "omega", "boundary", "explicit", "x0", "v0",
                                      "transient", "phase", "stick_speed")}
    args.update(
        parameter=_name(parameter, "parameter"),
        stop=_float(stop, "stop"),
        step=_float(step, "step"),
        period=_int32(period, "&continuation: period", "1..10000 (drive cycles)"),
        max_points=_int32(max_points, "&continuation: max_points", ">= 1"),
        doublings=_int32(doublings, "&continuation: doublings", "0..8"),
    )
    return cfg, args


def _continue(args: dict[str, Any], progress: bool) -> dict[str, Any]:
    """Validate, then run ``ic_continuation`` with room for the results guessed; once more
    with the exact room if a guess was short (the run repeats itself bit for bit). The
    outputs come back cut to their sizes."""
    kernels = _extension()
    no_control = np.zeros(4, dtype=np.int64)
    out = dict(zip(CONTINUATION_OUTPUTS, kernels.ic_continuation(
        **args, dry_run=1, nscap=1, ntext=1, nrcap=1, nbcap=1,
        strobe_x=np.empty((1, 1, 1), order="F"), control=no_control), strict=True))
    _raise_for(out["status"], out["msg_len"], out["message"])
    room = _first_room(args)
    for _ in range(2):
        strobe = np.empty((args["n"], room["nlong"], room["npcap"]), order="F")
        call = dict(args, dry_run=0, strobe_x=strobe,
                    **{k: room[k] for k in ("nscap", "ntext", "nrcap", "nbcap")})
        result = _watched(kernels.ic_continuation, call, progress, _CONTINUATION_STAGES)
        out = dict(zip(CONTINUATION_OUTPUTS, result, strict=True), strobe_x=strobe)
        if out["status"] != _STATUS_CAPACITY:
            break
        for key, size in zip(_CONTINUATION_SIZES, out["sizes"]):
            if key is not None:
                room[key] = max(room[key], int(size))
    _raise_for(out["status"], out["msg_len"], out["message"])
    points, specials, longest, reason, _, residuals, impacts, start_reason = (
        int(i) for i in out["sizes"])
    cut = {"strobe_x": (slice(None), slice(longest), slice(points)),
           "x": (slice(None), slice(points)), "v": (slice(None), slice(points)),
           "mult_re": (slice(None), slice(points)), "mult_im": (slice(None), slice(points)),
           "special_kind": (slice(None), slice(specials)),
           "end_reason": slice(reason), "start_reason": slice(start_reason),
           "start_residuals": slice(residuals), "start_bonds": slice(impacts)}
    for key in ("values", "periods", "branch", "stable", "min_gap", "min_impact_speed",
                "impacts", "residual", "iterations"):
        cut[key] = slice(points)
    for key in ("special_index", "special_value"):
        cut[key] = slice(specials)
    return {key: value[cut[key]] if key in cut else value for key, value in out.items()}


def _first_room(args: dict[str, Any]) -> dict[str, int]:
    """ic_continuation's capacities for a first call: every crossing of the longest period
    the branches can have, the points of max_points per branch and a few special points
    (within about 64 MB), and ample room for texts, Newton's residuals and impacts."""
    n, period = args["n"], args["period"]
    nlong = period * 2 ** args["doublings"]
    per_point = 8 * (n * nlong + 6 * n + 8)
    return dict(npcap=min(args["max_points"] * (1 + args["doublings"]) + 16,
                          max(16, _FIRST_CONTINUATION_BYTES // per_point)),
                nlong=nlong, nscap=64, ntext=4096, nrcap=64,
                nbcap=min(max(1024, 16 * (n + 1) * period), 1 << 20))


def _continuation_dataset(xr: Any, out: dict[str, Any], cfg: dict[str, Any],
                          args: dict[str, Any]) -> Any:
    """ic_continuation's arrays (Fortran order) as the file's /continuation group: the same
    dimensions, coordinates, variables, their attributes (the file schema's)
    and the group's attributes."""
    parameter = _text(args["parameter"])
    points = out["values"].size
    n = cfg["n"]

    def described(name: str, values: Any) -> tuple[Any, ...]:
        return schema.variable(f"/continuation/{name}", np.ascontiguousarray(values),
                               parameter)

    def index(name: str, first: int, count: int) -> tuple[Any, ...]:
        return described(name, np.arange(first, first + count, dtype=np.int32))

    kinds = [bytes(np.asarray(k).astype(np.uint8)).split(b"\0")[0].decode()
             for k in np.asarray(out["special_kind"]).T]
    coords = {
        "point": index("point", 0, points),
        "oscillator": index("oscillator", 1, n),
        "multiplier": index("multiplier", 1, 2 * n),
        "iterate": index("iterate", 1, out["strobe_x"].shape[1]),
        "special": index("special", 0, len(kinds)),
    }
    data = {
        "values": described("values", out["values"]),
        "x": described("x", out["x"].T),
        "v": described("v", out["v"].T),
        "strobe_x": described("strobe_x", out["strobe_x"].transpose(2, 1, 0)),
        "period": described("period", out["periods"]),
        "branch": described("branch", out["branch"]),
        "multipliers_re": described("multipliers_re", out["mult_re"].T),
        "multipliers_im": described("multipliers_im", out["mult_im"].T),
        "stable": described("stable", out["stable"]),
        "min_gap": described("min_gap", out["min_gap"]),
        "min_impact_speed": described("min_impact_speed", out["min_impact_speed"]),
        "impacts_per_period": described("impacts_per_period", out["impacts"]),
        "residual": described("residual", out["residual"]),
        "iterations": described("iterations", out["iterations"]),
        "special_index": described("special_index", out["special_index"]),
        "special_kind": described("special_kind", np.array(kinds, dtype=str)),
        "special_value": described("special_value", out["special_value"]),
    }
    spacing = np.asarray(cfg["spacing"])
    start = float(spacing[0]) if parameter == "spacing" else cfg[parameter]
    attrs = dict(parameter=parameter, phase=cfg["phase"], start=start, stop=args["stop"],
                 step=args["step"], end_reason=_text(out["end_reason"]))
    return xr.Dataset(data, coords=coords, attrs=attrs)


# ------------------------------------------------------------------------------ helpers


def _extension() -> Any:
    if _kernels is None:
        raise ImportError(
            "the compiled extension impactchain._kernels is missing: install the package "
            "with `pip install .` (or `make`) from the repository; an import of "
            f"impactchain from the source tree has no extension ({_IMPORT_ERROR})")
    return _kernels


def _config(n: Any, amplitude: Any, omega: Any, damping: Any, restitution: Any,
            spacing: Any, boundary: Any, x0: Any, v0: Any, transient: Any, cycles: Any,
            phase: Any, stick_speed: Any, max_size_mb: Any) -> dict[str, Any]:
    """The arguments of ``ic_run`` describing one run (Python types converted only)."""
    nn = _n(n)
    explicit = x0 is not None or v0 is not None
    xs = np.zeros(max(nn, 0)) if x0 is None and explicit else _vector(x0, "&initial: x0")
    return dict(
        n=nn,
        spacing=_spacing(spacing),
        damping=_float(damping, "damping"),
        restitution=_float(restitution, "restitution"),
        amplitude=_float(amplitude, "amplitude"),
        omega=_float(omega, "omega"),
        boundary=_name(boundary, "boundary"),
        explicit=int(explicit),
        x0=xs,
        v0=_vector(v0, "&initial: v0"),
        transient=_int64(transient, "&run: transient", "[0, 1e12]"),
        cycles=_int64(cycles, "&run: cycles", "[1, 1e12]"),
        phase=_float(phase, "phase"),
        stick_speed=_float(stick_speed, "stick_speed"),
        max_size_mb=_float(max_size_mb, "max_size_mb"),
        record_events=0,
        lyapunov=0,
        vectors=0,
        qr_every=1,
        jacobian=0,
        jacobian_cycles=1,
    )


def _used(cfg: dict[str, Any], boundary: str, **extra: Any) -> Mapping[str, Any]:
    """The arguments of a run as used, read-only (``Simulation.params``)."""
    n = cfg["n"]
    start = bool(cfg["explicit"])
    x0 = cfg["x0"] if start else None
    v0 = (cfg["v0"] if cfg["v0"].size else np.zeros(n)) if start else None
    used = dict(
        n=n, amplitude=cfg["amplitude"], omega=cfg["omega"], damping=cfg["damping"],
        restitution=cfg["restitution"],
        spacing=_frozen(np.broadcast_to(cfg["spacing"], (n + 1,)).copy()),
        boundary=boundary.strip().lower(), x0=None if x0 is None else _frozen(x0.copy()),
        v0=None if v0 is None else _frozen(np.array(v0, dtype=np.float64)),
        transient=cfg["transient"], cycles=cfg["cycles"], phase=cfg["phase"],
        stick_speed=cfg["stick_speed"], code_version=_code_version(), **extra)
    return MappingProxyType(used)


def provenance() -> Mapping[str, str]:
    """Where the extension runs: ``code_version``, ``compiler``, ``compiler_options``, ``blas``
    (name, version, build), ``blas_kernel`` (the kernels the BLAS selected on this CPU) and
    ``cpu_model``; the root attributes of the files the command line writes on this machine
    and the lines of ``impactchain --version`` (one table: src/base/chain_provenance.f90).
    (``compiler_options`` are the extension's own, which name other build directories.)"""
    text_len, text = _extension().ic_provenance()
    lines = bytes(np.asarray(text[:text_len]).astype(np.uint8)).decode().splitlines()
    return MappingProxyType(dict(line.split(": ", 1) for line in lines))


def _code_version() -> str:
    from impactchain import __version__

    return f"impactchain.api {__version__}"


def _run(cfg: dict[str, Any], strobe: bool, events: bool, progress: bool = False
         ) -> dict[str, Any]:
    """Validate, allocate, run; retry once with the exact event count if it was short."""
    kernels = _extension()
    cfg = dict(cfg, record_events=int(events), window=cfg.get("window", 0))
    out = _call_run(kernels, cfg, dry_run=True)
    _raise_for(out["status"], out["msg_len"], out["message"])
    n = cfg["n"]
    k = (cfg["vectors"] or 2 * n) if cfg["lyapunov"] else 0
    sizes = dict(nr=n if strobe else 0, nc=cfg["cycles"] if strobe else 0, nf=n,
                 kcap=k, mj=2 * n if cfg["jacobian"] else 0)
    capacity = 0
    if events:
        low, high = _FIRST_EVENT_CAPACITY
        capacity = int(min(max(low, 4 * (n + 1) * cfg["cycles"]), high))
    sizes["nw"] = cfg["cycles"] // cfg["window"] if cfg["window"] > 0 else 0
    out = _call_run(kernels, cfg, dry_run=False, ncap=capacity, progress=progress, **sizes)
    if out["status"] == _STATUS_CAPACITY:
        need = int(out["nev"])
        megabytes = need * _BYTES_PER_EVENT / 1e6
        if megabytes > cfg["max_size_mb"]:
            raise ValueError(
                f"events: this run has {need} events, about {megabytes:.6g} MB, more than "
                f"max_size_mb = {cfg['max_size_mb']:.8g}; pass events=False or raise "
                "max_size_mb")
        out = _call_run(kernels, cfg, dry_run=False, ncap=need, progress=progress, **sizes)
    _raise_for(out["status"], out["msg_len"], out["message"])
    return out


def _call_run(kernels: Any, cfg: dict[str, Any], dry_run: bool, nr: int = 0, nc: int = 0,
              nf: int = 0, ncap: int = 0, kcap: int = 0, mj: int = 0, nw: int = 0,
              progress: bool = False) -> dict[str, Any]:
    # records, events and finite-time windows in arrays allocated here, untouched (np.empty):
    # the kernel fills them with the GIL released (f2py refuses a size 0 there: one element
    # when none is kept)
    keep_strobe = nr > 0 and nc > 0
    nr, nc, ncap = max(nr, 1), max(nc, 1), max(ncap, 1)
    records = dict(x=np.empty((nr, nc), order="F"), v=np.empty((nr, nc), order="F"),
                   cycle=np.empty(nc, dtype=np.int64), ev_time=np.empty(ncap),
                   ev_site=np.empty(ncap, dtype=np.int32), ev_speed=np.empty(ncap),
                   ev_kind=np.empty(ncap, dtype=np.int32),
                   windows=np.empty((kcap if nw else 1, max(nw, 1)), order="F"),
                   window_cycle=np.empty(max(nw, 1), dtype=np.int64))
    args = dict(cfg, dry_run=int(dry_run), keep_strobe=int(keep_strobe), nr=nr, nc=nc, nf=nf,
                ncap=ncap, kcap=kcap, mj=mj, kw=kcap if nw else 1, nw=max(nw, 1), **records)
    if dry_run:
        result = kernels.ic_run(**args, control=np.zeros(4, dtype=np.int64))
    else:
        result = _watched(kernels.ic_run, args, progress)
    return dict(zip(RUN_OUTPUTS, result, strict=True)) | records


class _RunningKernels:
    """The control arrays of the kernels running now, in any thread, so that Ctrl-C stops
    them all: Python delivers SIGINT to the main thread only, and a kernel running in a
    worker (a ``ThreadPoolExecutor``'s) would otherwise go on to its end while the executor
    waits for it. A kernel that a worker starts within a second after Ctrl-C (the next task
    an executor had queued) is stopped at once too, so that the executor's wait ends."""

    _AFTER_INTERRUPT = 1.0  # seconds after Ctrl-C in which new kernels of workers stop

    def __init__(self) -> None:
        # (reentrant: the handler runs in the main thread, which may hold it then)
        self._lock = threading.RLock()
        self._controls: dict[int, NDArray[np.int64]] = {}
        self._interrupted_at = -float("inf")

    def __len__(self) -> int:
        with self._lock:
            return len(self._controls)

    def add(self, control: NDArray[np.int64]) -> None:
        with self._lock:
            self._controls[id(control)] = control
            if (threading.current_thread() is not threading.main_thread()
                    and time.monotonic() - self._interrupted_at < self._AFTER_INTERRUPT):
                control[0] = 1

    def remove(self, control: NDArray[np.int64]) -> None:
        with self._lock:
            self._controls.pop(id(control), None)

    def on_interrupt(self, signum: int, frame: Any) -> None:
        """SIGINT: every kernel asked to stop, then Python's KeyboardInterrupt as always."""
        with self._lock:
            self._interrupted_at = time.monotonic()
            for control in self._controls.values():
                control[0] = 1
        signal.default_int_handler(signum, frame)


_RUNNING = _RunningKernels()


def _stop_kernels_on_interrupt() -> None:
    """Let Ctrl-C reach kernels in worker threads: Python's own SIGINT handler, if it is the
    one in place, is replaced by one that also stops them (a program's or a notebook's own
    handler is left alone). Only the main thread can set a handler: done at import there."""
    if threading.current_thread() is not threading.main_thread():
        return
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, _RUNNING.on_interrupt)


_stop_kernels_on_interrupt()


def _watched(kernel: Callable[..., Any], args: dict[str, Any], progress: bool,
             stages: Mapping[int, tuple[str, str]] = _STAGES) -> Any:
    """``kernel(**args, control=...)`` in a worker thread, watched from this one.

    The kernel releases the GIL and polls ``control`` (int64, 4 values: chain_bridge's
    shared_monitor_t) at every transient cycle, record and sweep point, and every few
    thousand events within a cycle: control[0] set here asks it to stop; it keeps
    control[1:4] = stage, done, total. Ctrl-C here (this thread gets Python's signals) sets
    the flag, waits for the kernel to stop, and re-raises; Ctrl-C while this runs in another
    thread sets it too (_RUNNING), and the kernel's stop is raised here.
    """
    control = np.zeros(4, dtype=np.int64)
    outcome: dict[str, Any] = {}

    def work() -> None:
        try:
            outcome["result"] = kernel(**args, control=control)
        except BaseException as exc:  # handed to the calling thread
            outcome["error"] = exc

    bar = _ProgressBar(stages) if progress else None
    worker = threading.Thread(target=work, name="impactchain-kernel", daemon=True)
    _RUNNING.add(control)
    worker.start()
    try:
        while worker.is_alive():
            worker.join(_POLL_SECONDS)
            if bar is not None:
                bar.show(control)
    except KeyboardInterrupt:
        control[0] = 1
        worker.join()
        raise
    finally:
        _RUNNING.remove(control)
        if bar is not None:
            bar.close()
    if "error" in outcome:
        raise outcome["error"]
    return outcome["result"]


class _ProgressBar:
    """A tqdm bar per stage of a watched kernel (a new one when the stage changes)."""

    def __init__(self, stages: Mapping[int, tuple[str, str]] = _STAGES) -> None:
        try:
            from tqdm.auto import tqdm
        except ImportError:
            raise ImportError("progress=True needs tqdm: pip install tqdm") from None
        self._tqdm = tqdm
        self._stages = stages
        self._bar: Any = None
        self._stage = 0

    def show(self, control: NDArray[np.int64]) -> None:
        stage, done, total = (int(c) for c in control[1:4])
        if stage not in self._stages:
            return
        if stage != self._stage:
            self.close()
            description, unit = self._stages[stage]
            self._bar = self._tqdm(total=total, desc=description, unit=unit, leave=False)
            self._stage = stage
        self._bar.total = total
        self._bar.update(done - self._bar.n)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None


def _raise_for(status: int, msg_len: int, message: NDArray[np.int32]) -> None:
    if status == _STATUS_OK:
        return
    text = bytes(np.asarray(message[:msg_len]).astype(np.uint8)).decode("utf-8", "replace")
    if status == _STATUS_INVALID:
        raise ValueError(text)
    if status == _STATUS_FAILED:
        raise RuntimeError(text)
    if status == _STATUS_STOPPED:  # (Ctrl-C while the call ran in another thread)
        raise KeyboardInterrupt(text)
    raise RuntimeError(f"impactchain extension (status {status}): {text}")


def _frozen(a: NDArray[Any]) -> NDArray[Any]:
    a = np.asarray(a)
    a.setflags(write=False)
    return a


def _float(value: Any, name: str) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(
            value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a real number, not {type(value).__name__}")
    return float(value)


def _integer(value: Any, name: str) -> int:
    if isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be an integer, not bool")
    try:
        return operator.index(value)
    except TypeError:
        raise TypeError(f"{name} must be an integer, not {type(value).__name__}") from None


def _int32(value: Any, key: str, allowed: str) -> int:
    """An integer argument; one beyond 32 bits gets the CLI's message for that key."""
    i = _integer(value, key.split(": ")[-1])
    if not _INT32[0] <= i <= _INT32[1]:
        raise ValueError(f"{key} = {i} is outside {allowed}")
    return i


def _n(value: Any) -> int:
    """n, refused outside the CLI's range before anything of size n is made (the kernels
    check it too, but only after their arguments, sized by n, exist)."""
    n = _integer(value, "n")
    # (refused here, before any allocation, as the reader would: the table's range)
    most = int(schema_key("chain", "n")["max"])
    if not 1 <= n <= most:
        raise ValueError(f"&chain: n = {n} is outside [1, {most}]")
    return n


def _int64(value: Any, key: str, allowed: str) -> int:
    i = _integer(value, key.split(": ")[-1])
    if not _INT64[0] <= i <= _INT64[1]:
        raise ValueError(f"{key} = {i} is outside {allowed}")
    return i


def _vector(value: Any, key: str, length: str = "n") -> NDArray[np.float64]:
    """A 1-D float64 array (empty for None); lengths are checked by the library."""
    if value is None:
        return np.zeros(0)
    name = key.split(": ")[-1]
    if np.iscomplexobj(value):  # (a cast would drop the imaginary part with a warning)
        raise TypeError(f"{name} must be an array of real numbers, not complex")
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be an array of real numbers") from None
    if a.ndim != 1:
        raise ValueError(f"{key} must be a 1-D array of {length} values, got shape {a.shape}")
    return np.ascontiguousarray(a)


def _spacing(value: Any) -> NDArray[np.float64]:
    """One value (uniform) or n+1 values, as the namelist's ``spacing``."""
    if np.ndim(value) == 0:
        return np.array([_float(value, "spacing")])
    return _vector(value, "&chain: spacing", "n+1")


def _name(value: Any, name: str) -> NDArray[np.int32]:
    """A keyword value as the namelist reader sees it (trimmed, lower case), as bytes."""
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a string, not {type(value).__name__}")
    return np.frombuffer(value.strip().lower().encode(), dtype=np.uint8).astype(np.int32)
