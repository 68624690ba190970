"""One run of the chain: :func:`simulate`, :func:`lyapunov`, :func:`floquet`,
:func:`poincare_jacobian` and :func:`random_start`, and the results they return (public
through :mod:`impactchain.api`)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from impactchain._calls import (
    _STATUS_CAPACITY,
    _STATUS_OK,
    RUN_OUTPUTS,
    _config,
    _extension,
    _float,
    _frozen,
    _int32,
    _keys,
    _n,
    _overrides,
    _raise_for,
    _spacing,
    _used,
    _vector,
    _watched,
)
from impactchain._xarray import tree
from impactchain.schema import SCHEMA_DEFAULT, with_schema_defaults

if TYPE_CHECKING:
    from impactchain.io import Run

IMPACT = 0
"""``event_kind``: an ordinary impact."""
STICK = 1
"""``event_kind``: an impact that ends chatter; the oscillator then rests on the wall."""
RELEASE = 2
"""``event_kind``: a resting oscillator leaves the wall (not a collision)."""
TOUCH = 3
"""``event_kind``: a contact closing slower than its gap can resolve: no impulse and no jump
of the tangent (not a collision)."""

_FIRST_EVENT_CAPACITY = (1024, 1 << 20)  # bounds of the first guess of the event count
_BYTES_PER_EVENT = 24  # time, speed (float64), site, kind (int32)

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

    def to_xarray(self) -> Any:
        """This run as the :class:`xarray.DataTree` of the CLI's file
        (``xarray.open_datatree(path)``): groups ``/params``, ``/strobe``, ``/final``,
        ``/stats`` and, with events, ``/events``, with the file's names, dimensions and
        units (the file schema's)."""
        n = int(self.params["n"])
        values = {**_params_values(self.params), **_final_values(self, n),
                  "/strobe/oscillator": _osc(n), "/strobe/cycle": self.cycle,
                  "/strobe/x": self.x, "/strobe/v": self.v, "/strobe/period": self.periods,
                  "/stats/bond": _bonds(n), "/stats/site_counts": self.site_counts,
                  "/stats/cycles_done": np.int64(self.x.shape[0]),
                  "/stats/@impacts": self.impacts, "/stats/@sticks": self.sticks,
                  "/stats/@releases": self.releases, "/stats/@touches": self.touches,
                  "/stats/@collisions_per_cycle": self.collisions_per_cycle}
        if self.params.get("events"):
            values.update({"/events/time": self.event_time, "/events/site": self.event_site,
                           "/events/speed": self.event_speed, "/events/kind": self.event_kind})
        return tree(values, _root(self.params))


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

    def to_xarray(self) -> Any:
        """This spectrum as the :class:`xarray.DataTree` of the CLI's file: ``/params``,
        ``/lyapunov`` and ``/final``, with the file's names, dimensions and units."""
        n = int(self.params["n"])
        values = {**_params_values(self.params), **_final_values(self, n),
                  "/lyapunov/exponent": _osc(self.exponents.size),
                  "/lyapunov/exponents": self.exponents,
                  "/lyapunov/exponents_per_time": self.exponents_per_time,
                  "/lyapunov/stderr": self.stderr,
                  "/lyapunov/@ky_dimension": self.ky_dimension,
                  "/lyapunov/@collisions_per_cycle": self.collisions_per_cycle}
        if self.stderr_block is not None:
            values["/lyapunov/stderr_block"] = self.stderr_block
        return tree(values, _root(self.params))


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
    params: Mapping[str, Any]
    """The arguments as used (as :attr:`Simulation.params`), with ``jacobian_cycles``."""

    def to_xarray(self) -> Any:
        """The run as the :class:`xarray.DataTree` of the CLI's file: ``/params``, ``/floquet``
        and ``/final``, with the file's names, dimensions and units."""
        return tree({**_params_values(self.params), "/floquet/jacobian": self.jacobian,
                     "/floquet/multipliers_re": self.multipliers.real,
                     "/floquet/multipliers_im": self.multipliers.imag,
                     **_final_values(self, self.x.size)}, _root(self.params))


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
    file_group: Callable[[], Any] | None = field(default=None, repr=False)
    """Makes the ``/continuation`` group of the CLI's file of this run (``to_xarray``)."""

    def to_xarray(self) -> Any:
        """This orbit as the :class:`xarray.Dataset` of the CLI's file of the same input
        (``&continuation max_points = 1``): its ``/continuation`` group, one point (none when
        Newton did not converge, ``end_reason`` then says why), with the file's names,
        dimensions and units, as :func:`continuation` returns it."""
        if self.file_group is None:
            raise ValueError("this PeriodicOrbit was not made by impactchain.api.periodic_orbit")
        return self.file_group()


def _osc(count: int) -> NDArray[np.int32]:
    """A 1-based index coordinate (oscillator, exponent, row, ...), as the files store it."""
    return np.arange(1, count + 1, dtype=np.int32)


def _bonds(n: int) -> NDArray[np.int32]:
    return np.arange(n + 1, dtype=np.int32)


def _params_values(params: Mapping[str, Any]) -> dict[str, Any]:
    """The file's ``/params`` of a run's arguments as used."""
    n = int(params["n"])
    values: dict[str, Any] = {f"/params/@{key}": params[key] for key in (
        "n", "amplitude", "omega", "damping", "restitution", "boundary", "phase", "transient",
        "cycles")}
    values["/params/@drive_period"] = 2 * np.pi / params["omega"]
    values.update({"/params/bond": _bonds(n), "/params/spacing": np.asarray(params["spacing"])})
    return values


def _final_values(result: Any, n: int) -> dict[str, Any]:
    """The file's ``/final`` state of a result: x, v and, when the run's arguments are
    known, the cycle and section phase it ends at."""
    x = getattr(result, "final_x", None)
    v = getattr(result, "final_v", None)
    if x is None:
        x, v = result.x, result.v
    values = {"/final/oscillator": _osc(n), "/final/x": x, "/final/v": v}
    params = getattr(result, "params", None)
    if params:
        values.update({"/final/cycle": np.int64(params["transient"] + params["cycles"]),
                       "/final/phase": np.float64(params["phase"])})
    return values


def _root(params: Mapping[str, Any]) -> dict[str, Any]:
    """The root attributes of a run's tree: the file layout's version, its code version and
    equivalent input, complete (so that :func:`impactchain.io.read_run` reads it as a file)."""
    from impactchain.namelist import equivalent_namelist
    from impactchain.results import SCHEMA_VERSION

    return {"schema_version": SCHEMA_VERSION, "code_version": params["code_version"],
            "input_namelist": equivalent_namelist(params, "vectors" in params), "complete": 1}


# ---------------------------------------------------------------------------- functions


@with_schema_defaults(events=("run", "record_events"))
def simulate(
    n: int,
    amplitude: float,
    omega: float,
    *,
    cycles: int = 100,
    events: bool = SCHEMA_DEFAULT,
    progress: bool = False,
    **keys: Any,
) -> Simulation:
    """Run the chain: ``transient`` unrecorded drive cycles, then ``cycles`` recorded ones.

    Parameters (namelist keys; ranges are checked by the library):
        n: number of oscillators, 1..1e7.
        amplitude: drive amplitude A >= 0. omega: drive angular frequency, 1e-3..1e3.
        cycles: records, 1..1e12.
        events: keep the event stream (time, site, speed, kind of every event).
        progress: show a tqdm progress bar (transient cycles, then records).
        **keys: any other key of the input table (``impactchain --schema``), by its name
            (``damping=0.1``, ``kick=0.5``, ``x0=[...]``) or as ``group.key`` when several
            groups have it (``**{'initial.seed': 3}``), as the CLI's ``--set group.key=value``;
            unknown keys are all named at once, with the reader's "did you mean".
            The common ones: damping b in [0, 1); restitution K in [0, 1]; spacing, one
            value or the n+1 bond spacings, bond 0 first [length]; boundary ``'fixed'`` or
            ``'free'``; x0, v0, arrays of n values [length, length/time] (both absent: at
            rest; v0 absent with x0 given: v = 0); transient, cycles run before recording;
            phase, the drive phase of the section; stick_speed; max_size_mb (also applied
            to the event stream here).

    Returns:
        A :class:`Simulation`; ``x``, ``v`` have shape (cycles, n).

    Raises:
        ValueError: a bad argument, with the CLI's message. TypeError: an argument of the
        wrong type. RuntimeError: the run itself failed (the engine's message).
        KeyboardInterrupt: Ctrl-C; the run stops at its next cycle or record.
    """
    cfg = _config(n, amplitude, omega, cycles, keys)
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
        params=_used(cfg, events=keep_events),
    )


@with_schema_defaults
def lyapunov(
    n: int,
    amplitude: float,
    omega: float,
    *,
    cycles: int = 100,
    vectors: int = SCHEMA_DEFAULT,
    qr_every: int = SCHEMA_DEFAULT,
    window: int = SCHEMA_DEFAULT,
    progress: bool = False,
    **keys: Any,
) -> Lyapunov:
    """Lyapunov spectrum averaged over ``cycles`` drive cycles after ``transient``.

    An orthonormal frame of ``vectors`` tangent vectors (0: all 2n) is carried through the
    exact flow and the saltation matrices of every impact and re-orthonormalised (LAPACK
    QR) every ``qr_every`` cycles (0 <= qr_every <= cycles; 0, the default: at an adaptive
    interval, before the frame's columns are predicted to grow apart by 1e8, which gives the
    exponents of qr_every = 1 to rounding). The leading k exponents do not depend on k.
    ``window`` > 0: also the finite-time exponents over consecutive windows of that many
    recorded cycles (docs/model.md section 7.10; with qr_every > 1 a multiple of it). Other
    arguments and ``**keys`` as :func:`simulate`.

    Returns:
        A :class:`Lyapunov`: ``exponents`` and ``stderr`` (k,) in bits per drive cycle,
        descending, k = vectors or 2n, ``stderr_block`` (k,), and with ``window``
        ``finite_time``.
    """
    cfg = _config(n, amplitude, omega, cycles, keys)
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
        params=_used(cfg, events=False, vectors=cfg["vectors"],
                     qr_every=cfg["qr_every"], window=cfg["window"]),
        stderr_block=_frozen(out["stderr_cycles"][:k]),
        finite_time=finite_time,
    )


@with_schema_defaults(period=("lyapunov", "jacobian_cycles"))
def floquet(
    n: int,
    amplitude: float,
    omega: float,
    *,
    cycles: int = 1,
    period: int = SCHEMA_DEFAULT,
    progress: bool = False,
    **keys: Any,
) -> Floquet:
    """Floquet multipliers: eigenvalues of the ``period``-cycle Poincare-map Jacobian at
    the state reached after ``transient + cycles`` drive cycles (where the CLI evaluates
    it). Run long enough to settle on a period-p orbit for them to be its multipliers.

    ``period``: p in [1, 1000] (the CLI's ``jacobian_cycles``). Other arguments and
    ``**keys`` as :func:`simulate`.

    Returns:
        A :class:`Floquet`: ``multipliers`` (2n,) complex, ``jacobian`` (2n, 2n).
    """
    cfg = _config(n, amplitude, omega, cycles, keys)
    cfg["jacobian"] = 1
    cfg["jacobian_cycles"] = _int32(period, "&lyapunov: jacobian_cycles", "[1, 1000]")
    out = _run(cfg, strobe=False, events=False, progress=progress)
    return Floquet(
        multipliers=_frozen(out["mult_re"] + 1j * out["mult_im"]),
        jacobian=_frozen(out["jac"]),
        x=_frozen(out["final_x"]),
        v=_frozen(out["final_v"]),
        params=_used(cfg, events=False, jacobian_cycles=cfg["jacobian_cycles"]),
    )


@with_schema_defaults(cycles=("lyapunov", "jacobian_cycles"))
def poincare_jacobian(
    x: ArrayLike,
    v: ArrayLike,
    amplitude: float,
    omega: float,
    *,
    cycles: int = SCHEMA_DEFAULT,
    **keys: Any,
) -> NDArray[np.float64]:
    """Jacobian of the ``cycles``-cycle Poincare map at the state (x, v) on the section.

    ``x``, ``v``: (n,) displacements [length] and velocities [length/time] at drive phase
    ``phase`` (as a strobe record of :func:`simulate` with the same phase). The state is a
    fresh start: no oscillator rests on a wall, every collision is searched from here.
    ``cycles``: 1..1000. ``**keys`` as :func:`simulate`'s (x0, v0, transient aside: the
    state is given).

    Returns:
        (2n, 2n) float64 matrix J with J[i, j] = d z'_i / d z_j, the state interleaved as
        z = (x_1, v_1, x_2, v_2, ..., x_n, v_n): the product of the exact propagators and
        saltation matrices met along the way (docs/model.md sections 4 and 7.9).
    """
    xs = _vector(x, "&initial: x0")
    vs = _vector(v, "&initial: v0")
    n = xs.size
    cfg = _config(max(n, 1), amplitude, omega, 1, keys)
    args = {key: cfg[key] for key in ("spacing", "damping", "restitution", "amplitude", "omega",
                                      "boundary", "phase", "stick_speed", "max_size_mb",
                                      "overrides")}
    args.update(x0=xs, v0=vs,
                jacobian_cycles=_int32(cycles, "&lyapunov: jacobian_cycles", "[1, 1000]"))
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
    **keys: Any,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The CLI's seeded random start (``&initial kind='random'``): x_i uniform in
    [-x_amp, x_amp), v_i in [-v_amp, v_amp), from the same portable generator, so that
    ``simulate(..., x0=x, v0=v)`` equals a CLI run with that ``&initial`` group.

    ``x_amp`` must be below half the smallest spacing (no overlapping start), and ``x_amp``
    and ``v_amp`` must not both be 0 (every seed would be the same start, rest): ValueError
    with the CLI's message. ``**keys``: other keys of the table, as :func:`simulate`'s.

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
        overrides=_overrides(_keys(keys, ("initial",))),
    )
    kernels = _extension()
    x, v, status, msg_len, message = kernels.ic_random_start(**args, dry_run=1, nf=0)
    if status == _STATUS_OK:
        x, v, status, msg_len, message = kernels.ic_random_start(**args, dry_run=0, nf=nn)
    _raise_for(status, msg_len, message)
    return _frozen(x), _frozen(v)



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
