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
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import h5py
import numpy as np

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
    "ATTRACTOR_KINDS",
    "Census",
    "period_pattern",
    "Clv",
    "FiniteTime",
    "Run",
    "FILE_UNITS",
    "read_run",
    "read_continuation",
    "read_census",
    "run_from_api",
    "run_from_sweep",
    "is_sweep_dataset",
    "namelist_groups",
]

SCHEMA_VERSION = 2
"""The file layout the simulator writes (``Run.schema_version`` of a run made in memory)."""

READABLE_VERSIONS = (1, 2)
"""The file layouts this module reads."""

IMPACT = 0
"""``/events/kind``: an ordinary impact."""
STICK = 1
"""``/events/kind``: an impact that starts a sticking contact."""
RELEASE = 2
"""``/events/kind``: release from a sticking contact (not a collision)."""
TOUCH = 3
"""``/events/kind``: a contact closing slower than its gap can resolve: no impulse (not a
collision)."""

class _FileUnits(Mapping[str, str]):
    """The unit of each dataset in the model's reduced units (docs/model.md section 1.5): a
    version-2 file's ``model_units`` attribute, else its ``units`` (UDUNITS'); the units of a
    run made in memory (:func:`run_from_api`) and the defaults of the figures' axis labels.
    Read from the file schema (:mod:`impactchain.schema`) when first asked."""

    def _units(self) -> dict[str, str]:
        from impactchain import schema

        return schema.dataset_units()

    def __getitem__(self, key: str) -> str:
        return self._units()[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._units())

    def __len__(self) -> int:
        return len(self._units())


FILE_UNITS: Mapping[str, str] = _FileUnits()
"""The unit of each dataset (``group/name``), as the file schema gives it (see
:class:`_FileUnits`)."""

OPTIONAL_GROUPS = ("initial", "final", "strobe", "events", "stats", "lyapunov", "sweep",
                   "continuation", "census", "clv", "finite_time")

_HINTS = {
    "strobe": "the run recorded no strobe snapshots",
    "events": "events were not recorded in this run",
    "lyapunov": "Lyapunov exponents were not computed in this run",
    "sweep": "this is not a parameter-sweep file",
    "sweep/exponents": "the sweep did not compute Lyapunov exponents",
    "sweep/ky_dimension": "the sweep did not compute Lyapunov exponents",
    "continuation": "this is not a continuation file",
    "census": "this is not a census file (no &census in its input)",
    "clv": "covariant Lyapunov vectors were not computed in this run: &lyapunov covariant = "
           ".false.",
    "clv/site_weight": "the run stored no site weights of covariant vectors: &lyapunov "
                       "clv_store = 0, or no covariant = .true.",
    "finite_time": "the run computed no finite-time Lyapunov exponents: &lyapunov window = 0",
}

SPECIAL_KINDS = ("fold", "period-doubling", "neimark-sacker", "grazing")
"""``/continuation/special_kind``: the special points a continuation locates."""

ATTRACTOR_KINDS = ("periodic", "chaotic", "aperiodic-nonchaotic")
"""``/census/attractor_kind``: what a census's attractor is (docs/model.md section 13.2)."""


class SchemaError(ValueError):
    """The file is missing, not HDF5, of another schema, or lacks needed data."""


@dataclass(frozen=True, eq=False)
class Params:
    """Run parameters from ``/params`` (docs/model.md sections 1 and 6)."""

    n: int
    damping: float
    restitution: float
    amplitude: float
    omega: float
    boundary: str
    drive_period: float
    phase: float
    transient: int
    cycles: int
    spacing: np.ndarray  # (n+1,): bond 0 = left wall|osc 1, ..., bond n = osc n|right wall

    @property
    def walls(self) -> bool:
        """True when both end walls are present (``boundary == 'fixed'``)."""
        return self.boundary == "fixed"

    @property
    def length(self) -> float:
        """Position of the right wall: the sum of all spacings."""
        return float(np.sum(self.spacing))

    @property
    def equilibrium(self) -> np.ndarray:
        """Equilibrium position of oscillators 1..n, shape (n,)."""
        return np.cumsum(self.spacing)[: self.n]

    @property
    def site_positions(self) -> np.ndarray:
        """Position of collision sites 0..n, shape (n+1,).

        Site k (bond k) is attributed to oscillator k, the left one of the pair (the
        paper's convention), so site 0 (the left wall hit) sits at the left wall, 0.
        """
        return np.concatenate(([0.0], self.equilibrium))

    @property
    def section_offset(self) -> float:
        """Section phase as a fraction of a drive cycle: record ``c`` is at t/T = c + offset."""
        return self.phase / (2.0 * math.pi)


@dataclass(frozen=True, eq=False)
class State:
    """A chain state: displacements ``x`` and velocities ``v``, shape (n,)."""

    x: np.ndarray
    v: np.ndarray


@dataclass(frozen=True, eq=False)
class FinalState(State):
    """The last state of a run, at absolute drive cycle ``cycle`` and drive ``phase``."""

    cycle: int = 0
    phase: float = 0.0


@dataclass(frozen=True, eq=False)
class Strobe:
    """Poincare-section records: state at t = cycle*T + phase/omega."""

    x: np.ndarray  # (n_record, n)
    v: np.ndarray  # (n_record, n)
    cycle: np.ndarray  # (n_record,) absolute cycle index
    period: np.ndarray | None  # (n,) the simulator's period per oscillator, 0 = aperiodic

    @property
    def n_record(self) -> int:
        """Number of recorded cycles."""
        return int(self.x.shape[0])


@dataclass(frozen=True, eq=False)
class Events:
    """Collision events in time order as written (time from the start of the run)."""

    time: np.ndarray  # (n_events,)
    site: np.ndarray  # (n_events,) 0..n
    speed: np.ndarray  # (n_events,) approach speed >= 0
    kind: np.ndarray  # (n_events,) IMPACT, STICK, RELEASE or TOUCH

    @property
    def collisions(self) -> np.ndarray:
        """Mask of events that are collisions (impacts, including sticking ones)."""
        return (self.kind == IMPACT) | (self.kind == STICK)


@dataclass(frozen=True, eq=False)
class Stats:
    """Collision counts over the recorded cycles."""

    collisions_per_cycle: float
    impacts: int
    sticks: int
    releases: int
    site_counts: np.ndarray  # (n+1,)
    cycles_done: int | None = None  # records done (params.cycles planned); None: older file
    touches: int | None = None  # contacts without impulse (kind TOUCH); None: older file


@dataclass(frozen=True, eq=False)
class Lyapunov:
    """Lyapunov spectrum of one run, descending, in bits per drive cycle."""

    exponents: np.ndarray  # (k,) bits/cycle
    exponents_per_time: np.ndarray  # (k,) nats/time
    stderr: np.ndarray  # (k,) bits/cycle
    running: np.ndarray  # (m, k) bits/cycle, a bounded selection of the QR steps
    ky_dimension: float
    positive_sum: float
    collisions_per_cycle: float
    running_cycle: np.ndarray | None = None  # (m,) drive cycle of each running row
    stderr_block: np.ndarray | None = None  # (k,) drive cycles per block; None: older file


@dataclass(frozen=True, eq=False)
class Sweep:
    """A parameter sweep: records and (optionally) exponents at each parameter point."""

    parameter: str
    parameter2: str  # '' for a 1-D sweep
    mode: str
    values: np.ndarray  # (n_points,) or (n_points, 2); point p = i + n1*j in a 2-D sweep
    x: np.ndarray  # (n_points, cycles, n)
    collisions_per_cycle: np.ndarray  # (n_points,)
    period: np.ndarray  # (n_points, n) the simulator's period per oscillator, 0 = aperiodic
    exponents: np.ndarray | None = None  # (n_points, k) bits/cycle
    stderr: np.ndarray | None = None  # (n_points, k) bits/cycle
    ky_dimension: np.ndarray | None = None  # (n_points,) written with the exponents
    drive_period: np.ndarray | None = None  # (n_points,) in an omega sweep (version 2)

    @property
    def is_2d(self) -> bool:
        """True for a sweep over two parameters."""
        return bool(self.parameter2) or self.values.ndim == 2


@dataclass(frozen=True, eq=False)
class Continuation:
    """Periodic orbits continued in one parameter (``/continuation``), one per point.

    Point ``i`` is a period-``period[i]`` orbit of the stroboscopic map at ``parameter =
    values[i]``, on branch ``branch[i]`` (0: the first; 1, 2, ...: branches switched to at
    period doublings). Special points (folds, period doublings, Neimark-Sacker points,
    grazings) are stored as points too: ``values[special_index[j]] == special_value[j]``,
    except at a grazing where an impact's speed vanishes (``special_value`` is then where the
    speed extrapolates to zero, a little past the last orbit Newton converged on).
    """

    parameter: str  # amplitude, omega, damping, restitution or spacing
    phase: float  # drive phase of the section, rad
    end_reason: str  # why the continuation stopped
    values: np.ndarray  # (P,) the continued parameter at each point
    x: np.ndarray  # (P, n) the orbit's state on the section
    v: np.ndarray  # (P, n)
    strobe_x: np.ndarray  # (P, L, n) the p section crossings (iterate 1 = x), NaN beyond p
    period: np.ndarray  # (P,) drive cycles per period of the orbit
    branch: np.ndarray  # (P,)
    multipliers_re: np.ndarray  # (P, 2n) Floquet multipliers
    multipliers_im: np.ndarray  # (P, 2n)
    stable: np.ndarray  # (P,) bool: every |multiplier| < 1
    min_gap: np.ndarray  # (P,) smallest gap at a local minimum over a period (inf: none)
    min_impact_speed: np.ndarray  # (P,) inf: the orbit has no impacts
    impacts_per_period: np.ndarray  # (P,)
    residual: np.ndarray  # (P,) Newton's last residual
    iterations: np.ndarray  # (P,) Newton's steps
    special_index: np.ndarray  # (S,) 0-based index of the special point into the points
    special_kind: np.ndarray  # (S,) str, one of SPECIAL_KINDS
    special_value: np.ndarray  # (S,) the parameter at the special point

    @property
    def n_points(self) -> int:
        """Number of points, P."""
        return int(self.values.shape[0])

    @property
    def multipliers(self) -> np.ndarray:
        """The Floquet multipliers as complex numbers, (P, 2n)."""
        return self.multipliers_re + 1j * self.multipliers_im

    @property
    def max_multiplier(self) -> np.ndarray:
        """The largest modulus of the multipliers at each point, (P,)."""
        return np.max(np.abs(self.multipliers), axis=1)

    @property
    def special_points(self) -> list[tuple[int, str, float]]:
        """The special points as (index into the points, kind, parameter value)."""
        return [(int(i), str(kind), float(value)) for i, kind, value
                in zip(self.special_index, self.special_kind, self.special_value)]


def period_pattern(periods: Iterable[int]) -> str:
    """The oscillators' periods left to right, runs of one period written ``p×count``:
    ``'1×8 2×8'`` for eight period-1 oscillators then eight period-2 ones; ``0`` is aperiodic
    (``'0×16'``)."""
    runs: list[list[int]] = []
    for p in (int(p) for p in periods):
        if runs and runs[-1][0] == p:
            runs[-1][1] += 1
        else:
            runs.append([p, 1])
    return " ".join(f"{p}×{count}" for p, count in runs)


@dataclass(frozen=True, eq=False)
class Census:
    """An attractor census (``/census``, docs/model.md section 13): the attractors reached
    from ``samples`` starts at each of P points, and each one's basin fraction.

    Attractor ``a`` (0-based, ids in the order found) belongs to point
    ``attractor_point[a]``; sample ``s`` (0-based here, sample ``s + 1`` of the file's
    ``sample`` axis) of point ``p`` reached ``sample_attractor[p, s]``, its mirror image
    when ``mirrored[p, s]``. ``values`` holds the swept parameter at each point (a census
    along a ``&sweep``), or the point index 0 at one point (``parameter == ''``). A census on a
    plane of starts has ``plane`` (two coordinates such as ``('x3', 'v3')``), ``plane_range``
    and ``plane_points``; its sample ``1 + i + m j`` sits at grid point ``i`` of the first
    coordinate and ``j`` of the second (:meth:`plane_grid`).

    Each sample keeps its ``k`` leading Lyapunov exponents (``&census exponents``, 1 by
    default; ``sample_exponents[..., 0]`` is ``lambda1``), and each attractor the mean of its
    samples' and the spread between them (their standard deviation, ``n - 1`` in the
    denominator, 0 for one sample; docs/model.md section 13.4). A file written before the
    census kept them (``ensemble_stored`` false) gets ``k = 1`` from ``lambda1``: the mean and
    spread of its samples' ``lambda1``, their standard errors NaN (not stored per sample).
    """

    parameter: str  # the swept parameter, '' at one point
    samples: int
    seed: int
    x_amp: float
    v_amp: float
    tolerance: float
    mirror: str  # 'merge' or 'separate'
    rule: str  # the classification in words
    values: np.ndarray  # (P,) the swept parameter at each point (index 0 at one point)
    x0: np.ndarray  # (P, N, n) each sample's start
    v0: np.ndarray  # (P, N, n)
    sample_attractor: np.ndarray  # (P, N) the attractor (id) each sample reached
    mirrored: np.ndarray  # (P, N) bool: it reached the attractor's mirror image
    lambda1: np.ndarray  # (P, N) each sample's largest exponent, bits/cycle
    attractor_kind: np.ndarray  # (A,) str, one of ATTRACTOR_KINDS
    attractor_period: np.ndarray  # (A, n) the oscillators' periods, 0 = aperiodic
    attractor_lambda1: np.ndarray  # (A,) the representative's largest exponent
    attractor_lambda1_stderr: np.ndarray  # (A,)
    attractor_x: np.ndarray  # (A, n) the representative's state at its last record
    attractor_v: np.ndarray  # (A, n)
    attractor_point: np.ndarray  # (A,) the point (0-based) where it was found
    attractor_sample: np.ndarray  # (A,) its representative, the first sample (1-based)
    attractor_sites: np.ndarray  # (A, n+1) fraction of its impacts on each bond
    fraction: np.ndarray  # (P, A) basin fraction at each point (0 at other points)
    fraction_stderr: np.ndarray  # (P, A) binomial sqrt(f (1 - f) / N)
    sample_exponents: np.ndarray  # (P, N, k) each sample's leading exponents, descending
    sample_exponents_stderr: np.ndarray  # (P, N, k) their standard errors (NaN: not stored)
    attractor_exponents: np.ndarray  # (A, k) the mean over the attractor's samples
    attractor_exponents_spread: np.ndarray  # (A, k) the standard deviation between them
    ensemble_stored: bool = True  # False: an older file, the four above made from lambda1
    plane: tuple[str, str] | None = None  # the two coordinates of a plane of starts
    plane_range: np.ndarray | None = None  # (4,) min, max of the first, then the second
    plane_points: int = 0  # grid points along each coordinate (0: random starts)

    @property
    def n_points(self) -> int:
        """Number of points, P."""
        return int(self.values.shape[0])

    @property
    def n_attractors(self) -> int:
        """Number of attractors, A (over all points)."""
        return int(self.attractor_kind.shape[0])

    @property
    def swept(self) -> bool:
        """True for a census along a swept parameter."""
        return bool(self.parameter)

    @property
    def k(self) -> int:
        """Number of leading exponents of each sample."""
        return int(self.sample_exponents.shape[2])

    def members(self, a: int) -> np.ndarray:
        """The samples (0-based) of attractor ``a``'s point that reached it, in order."""
        return np.flatnonzero(self.sample_attractor[int(self.attractor_point[a])] == a)

    def pattern(self, a: int) -> str:
        """Attractor ``a``'s period pattern (:func:`period_pattern`)."""
        return period_pattern(self.attractor_period[a])

    def label(self, a: int) -> str:
        """``'periodic 1×8 2×8'``, ``'chaotic'``, ...: attractor ``a``'s kind, with its
        period pattern when any oscillator has a period (``'aperiodic-nonchaotic 8×1 0×14'``:
        the first oscillator periodic, the others not)."""
        kind = str(self.attractor_kind[a])
        return f"{kind} {self.pattern(a)}" if self.attractor_period[a].any() else kind

    def attractors_at(self, point: int) -> np.ndarray:
        """The ids of the attractors found at ``point`` (0-based)."""
        return np.flatnonzero(self.attractor_point == point)

    def count(self, point: int, a: int) -> int:
        """How many of ``point``'s samples reached attractor ``a``."""
        return int(np.count_nonzero(self.sample_attractor[point] == a))

    def plane_grid(self, point: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A plane census's grid at ``point``: the first coordinate's values (m,), the
        second's (m,), and the attractor ids (m, m) indexed [j, i] (second, first), as the
        starts hold them."""
        if self.plane is None:
            raise ValueError("this census has random starts, not a plane of starts")
        m = self.plane_points
        starts = {"x": self.x0[point], "v": self.v0[point]}

        def column(name: str) -> np.ndarray:
            return starts[name[0]][:, int(name[1:]) - 1]

        first, second = (column(name).reshape(m, m) for name in self.plane)
        ids = self.sample_attractor[point].reshape(m, m)
        return first[0, :].copy(), second[:, 0].copy(), ids.copy()


@dataclass(frozen=True, eq=False)
class Clv:
    """Covariant Lyapunov vectors (``/clv``, docs/model.md section 14), record by record.

    The records with vectors are the run's first ``R`` strobe records (``cycle``, the drive
    cycle of each, as ``/strobe/cycle``); the last ``clv_transient`` records of the run only
    brought the backward pass to convergence and have none. Vector ``i`` (0-based here,
    ``i + 1`` in the file's coordinate) is in the order of the QR frame's columns, that of the
    exponents of ``/lyapunov`` sorted descending. The per-oscillator weight of a vector is
    ``x_i**2 + v_i**2`` of its two components at oscillator ``i``, normalised to sum 1.
    """

    cycle: np.ndarray  # (R,) drive cycle of each record with vectors
    exponents: np.ndarray  # (k,) bits/cycle: each vector's own growth rate
    stderr: np.ndarray  # (k,) bits/cycle, by blocking
    stderr_block: np.ndarray  # (k,) records per block at which stderr was read off
    ipr: np.ndarray  # (R, k) inverse participation ratio of the weights, 1/n .. 1
    min_angle: np.ndarray  # (R,) rad: unstable span against the other vectors (NaN: none)
    clv_transient: int  # records at the end of the run without vectors
    unstable: int  # u: positive exponents of /lyapunov, the vectors spanning E_u
    site_weight: np.ndarray | None = None  # (R, m, n) of the first m vectors; clv_store = 0
    vectors: np.ndarray | None = None  # (r, k, 2n) unit vectors, x(1), v(1), x(2), ...
    saved_cycle: np.ndarray | None = None  # (r,) drive cycle of each record in ``vectors``

    @property
    def n_record(self) -> int:
        """Number of records with vectors, R."""
        return int(self.cycle.shape[0])

    @property
    def k(self) -> int:
        """Number of covariant vectors."""
        return int(self.exponents.shape[0])

    @property
    def stored(self) -> int:
        """Number of leading vectors whose site weights are stored, m (``clv_store``)."""
        return 0 if self.site_weight is None else int(self.site_weight.shape[1])


@dataclass(frozen=True, eq=False)
class FiniteTime:
    """Finite-time Lyapunov exponents (``/finite_time``, docs/model.md section 7.10): the
    growth per cycle of each tangent-frame column over consecutive windows of ``window``
    recorded cycles, counted from the first record, in bits per drive cycle.

    Exponent ``j`` (0-based here, ``j + 1`` in the file's ``exponent`` coordinate) is column
    ``j`` of the frame: the order of ``/lyapunov/exponents`` unless two exponents cross within
    their errors; ``-inf`` in the windows after its direction collapsed (section 7.8). A run
    stopped early holds the windows it finished. :attr:`descending` puts the columns in the
    order of ``/lyapunov/exponents`` whatever happened.
    """

    window: int  # recorded cycles per window
    cycle: np.ndarray  # (w,) drive cycle at the end of each window
    exponents: np.ndarray  # (w, k) bits/cycle

    @property
    def n_windows(self) -> int:
        """Number of windows, w."""
        return int(self.cycle.shape[0])

    @property
    def k(self) -> int:
        """Number of exponents (frame columns)."""
        return int(self.exponents.shape[1])

    @property
    def descending(self) -> np.ndarray:
        """(w, k): the columns reordered so that their means over the windows descend, the
        order of ``/lyapunov/exponents`` (which sorts the columns' means over every recorded
        cycle: the same means when the windows cover the run); ``-inf`` columns last, ties
        in column order."""
        with np.errstate(invalid="ignore"):
            means = self.exponents.mean(axis=0) if self.n_windows else np.zeros(self.k)
        means = np.where(np.isnan(means), -np.inf, means)
        return self.exponents[:, np.argsort(-means, kind="stable")]


@dataclass(frozen=True, eq=False)
class Run:
    """One impactchain output file."""

    path: str
    schema_version: int
    code_version: str
    input_namelist: str
    complete: bool
    params: Params
    initial: State | None = None
    final: FinalState | None = None
    strobe: Strobe | None = None
    events: Events | None = None
    stats: Stats | None = None
    lyapunov: Lyapunov | None = None
    sweep: Sweep | None = None
    continuation: Continuation | None = None
    census: Census | None = None
    clv: Clv | None = None
    finite_time: FiniteTime | None = None
    units: Mapping[str, str] = field(default_factory=dict)
    resolved_namelist: str = ""  # every key as used; '' for an older file

    @property
    def name(self) -> str:
        """File name without directory and extension, for legends."""
        base = os.path.basename(self.path)
        return base[:-3] if base.endswith(".h5") else base

    def unit(self, dataset: str, default: str = "") -> str:
        """The ``units`` attribute of a dataset (e.g. ``'strobe/x'``), or ``default``."""
        return self.units.get(dataset.strip("/"), default)

    def namelist(self) -> dict[str, dict[str, str]]:
        """The input as ``{group: {key: value text}}``: the resolved namelist (every key as
        used) when the file has one, else the input text (only the keys given)."""
        return namelist_groups(self.resolved_namelist or self.input_namelist)

    def to_run(self) -> Run:
        """This run (the protocol the figure functions accept, see :func:`run_from_api`)."""
        return self


# ----------------------------------------------------------------------------- reading


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
    if "schema_version" not in f.attrs:
        raise SchemaError(
            f"{path}: no 'schema_version' attribute; not an impactchain output file"
        )
    version = _int(f.attrs["schema_version"], path, "schema_version")
    if version not in READABLE_VERSIONS:
        raise SchemaError(
            f"{path}: schema_version {version} is not supported (this impactchain package "
            f"reads schema_version {' and '.join(map(str, READABLE_VERSIONS))})"
        )
    if "params" not in f:
        raise SchemaError(f"{path}: no /params group")


def _check_required(
    f: h5py.File, path: str, require: Iterable[str], purpose: str | None
) -> None:
    for entry in require:
        options = [item.strip("/") for item in entry.split("|")]
        if any(option in f for option in options):
            continue
        names = " or ".join(f"/{option}" for option in options)
        need = f", needed by {purpose}" if purpose else ""
        hint = _HINTS.get(options[0])
        reason = f" ({hint})" if hint else ""
        raise SchemaError(f"{path}: no {names}{need}{reason}")


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
        "census": lambda g: _read_census(g, path, n),
        "clv": lambda g: _read_clv(g, path, n),
        "finite_time": lambda g: _read_finite_time(g, path),
    }
    parts: dict[str, Any] = {}
    for name, reader in readers.items():
        if name in wanted and name in f:
            parts[name] = reader(f[name])
    return Run(
        path=path,
        schema_version=_int(f.attrs["schema_version"], path, "schema_version"),
        code_version=_str(f.attrs.get("code_version", "")),
        input_namelist=_str(f.attrs.get("input_namelist", "")),
        complete=bool(_int(f.attrs.get("complete", 1), path, "complete")),
        params=params,
        units=MappingProxyType(_collect_units(f)),
        resolved_namelist=_str(f.attrs.get("resolved_namelist", "")),
        **parts,
    )


def _read_params(f: h5py.File, path: str) -> Params:
    g = f["params"]
    # a version-2 sweep leaves out what differs from point to point, a continuation its
    # parameter
    swept = set(_swept(f, path)) if "sweep" in f and _version(f, path) >= 2 else set()
    if "continuation" in f:
        swept.add(_str(_attr(f["continuation"], path, "parameter")))
    if "census" in f and _str(f["census"].attrs.get("parameter", "")):
        swept.add(_str(f["census"].attrs["parameter"]))
    if "omega" in swept:
        swept.add("drive_period")
    attrs = {name: math.nan if name in swept and name not in g.attrs else _attr(g, path, name)
             for name in _PARAM_TYPES}
    n = _int(attrs["n"], path, "params/n")
    if n < 1:
        raise SchemaError(f"{path}: /params n = {n} must be >= 1")
    if "spacing" in swept and "spacing" not in g:
        spacing = _frozen(np.full(n + 1, math.nan))
    else:
        spacing = _dataset(g, path, "spacing", (n + 1,), float)
    values: dict[str, Any] = {}
    for name, kind in _PARAM_TYPES.items():
        where = f"params/{name}"
        if kind is int:
            values[name] = _int(attrs[name], path, where)
        elif kind is float:
            values[name] = _float(attrs[name], path, where)
        else:
            values[name] = _str(attrs[name])
    values["spacing"] = spacing
    return Params(**values)


_PARAM_TYPES: dict[str, type] = {
    "n": int,
    "damping": float,
    "restitution": float,
    "amplitude": float,
    "omega": float,
    "boundary": str,
    "drive_period": float,
    "phase": float,
    "transient": int,
    "cycles": int,
}


def _read_state(g: h5py.Group, path: str, n: int) -> State:
    return State(
        x=_dataset(g, path, "x", (n,), float),
        v=_dataset(g, path, "v", (n,), float),
    )


def _read_final(g: h5py.Group, path: str, n: int) -> FinalState:
    return FinalState(
        x=_dataset(g, path, "x", (n,), float),
        v=_dataset(g, path, "v", (n,), float),
        cycle=_int(_dataset(g, path, "cycle", None, int), path, f"{g.name}/cycle"),
        phase=_float(_dataset(g, path, "phase", None, float), path, f"{g.name}/phase"),
    )


def _read_strobe(g: h5py.Group, path: str, n: int) -> Strobe:
    x = _dataset(g, path, "x", (None, n), float)
    m = x.shape[0]
    period = _dataset(g, path, "period", (n,), int) if "period" in g else None
    return Strobe(
        x=x,
        v=_dataset(g, path, "v", (m, n), float),
        cycle=_dataset(g, path, "cycle", (m,), int),
        period=period,
    )


def _read_events(g: h5py.Group, path: str, n: int) -> Events:
    time = _dataset(g, path, "time", (None,), float)
    m = time.shape[0]
    site = _dataset(g, path, "site", (m,), int)
    if m and (site.min() < 0 or site.max() > n):
        raise SchemaError(
            f"{path}: /events/site holds values outside 0..{n} "
            f"(found {site.min()}..{site.max()})"
        )
    kind = _dataset(g, path, "kind", (m,), int)
    if m and not np.isin(kind, (IMPACT, STICK, RELEASE, TOUCH)).all():
        raise SchemaError(f"{path}: /events/kind holds values other than 0, 1, 2, 3")
    return Events(time=time, site=site, speed=_dataset(g, path, "speed", (m,), float), kind=kind)


def _read_stats(g: h5py.Group, path: str, n: int) -> Stats:
    return Stats(
        collisions_per_cycle=_float(_attr(g, path, "collisions_per_cycle"), path,
                                    "stats/collisions_per_cycle"),
        impacts=_int(_attr(g, path, "impacts"), path, "stats/impacts"),
        sticks=_int(_attr(g, path, "sticks"), path, "stats/sticks"),
        releases=_int(_attr(g, path, "releases"), path, "stats/releases"),
        site_counts=_dataset(g, path, "site_counts", (n + 1,), int),
        cycles_done=_int(_dataset(g, path, "cycles_done", None, int), path,
                         "stats/cycles_done") if "cycles_done" in g else None,
        touches=_int(_attr(g, path, "touches"), path, "stats/touches")
        if "touches" in g.attrs else None,
    )


def _read_lyapunov(g: h5py.Group, path: str) -> Lyapunov:
    exponents = _dataset(g, path, "exponents", (None,), float)
    k = exponents.shape[0]
    running = _dataset(g, path, "running", (None, k), float)
    return Lyapunov(
        exponents=exponents,
        exponents_per_time=_dataset(g, path, "exponents_per_time", (k,), float),
        stderr=_dataset(g, path, "stderr", (k,), float),
        running=running,
        ky_dimension=_float(_attr(g, path, "ky_dimension"), path, "lyapunov/ky_dimension"),
        positive_sum=_float(_attr(g, path, "positive_sum"), path, "lyapunov/positive_sum"),
        collisions_per_cycle=_float(_attr(g, path, "collisions_per_cycle"), path,
                                    "lyapunov/collisions_per_cycle"),
        running_cycle=_dataset(g, path, "running_cycle", (running.shape[0],), int)
        if "running_cycle" in g else None,
        stderr_block=_dataset(g, path, "stderr_block", (k,), int)
        if "stderr_block" in g else None,
    )


def _version(f: h5py.File, path: str) -> int:
    return _int(f.attrs["schema_version"], path, "schema_version")


def _swept(f: h5py.File, path: str) -> list[str]:
    """The swept parameters of a sweep's file."""
    g = f["sweep"]
    names = [_str(_attr(g, path, "parameter"))]
    if "parameter2" in g.attrs and _str(g.attrs["parameter2"]):
        names.append(_str(g.attrs["parameter2"]))
    return names


def _read_sweep(g: h5py.Group, path: str, n: int) -> Sweep:
    if "point" in g:
        return _read_sweep_v2(g, path, n)
    parameter2 = _str(_attr(g, path, "parameter2"))
    values = _dataset(g, path, "values", (None, 2) if parameter2 else (None,), float)
    p = values.shape[0]
    exponents = _dataset(g, path, "exponents", (p, None), float) if "exponents" in g else None
    k = None if exponents is None else exponents.shape[1]
    return Sweep(
        parameter=_str(_attr(g, path, "parameter")),
        parameter2=parameter2,
        mode=_str(_attr(g, path, "mode")),
        values=values,
        x=_dataset(g, path, "x", (p, None, n), float),
        collisions_per_cycle=_dataset(g, path, "collisions_per_cycle", (p,), float),
        period=_dataset(g, path, "period", (p, n), int),
        exponents=exponents,
        stderr=_dataset(g, path, "stderr", (p, k), float) if "stderr" in g else None,
        ky_dimension=_dataset(g, path, "ky_dimension", (p,), float)
        if "ky_dimension" in g else None,
    )


def _read_sweep_v2(g: h5py.Group, path: str, n: int) -> Sweep:
    """Version 2: the point axes (point, point2) first; returned flattened as version 1."""
    parameter2 = _str(g.attrs.get("parameter2", ""))
    point = _dataset(g, path, "point", (None,), float)
    n1 = point.shape[0]
    if parameter2:
        point2 = _dataset(g, path, "point2", (None,), float)
        n2 = point2.shape[0]
        axes: tuple[int, ...] = (n1, n2)
    else:
        point2 = None
        axes = (n1,)
    values = _point_values(point, point2)

    def per_point(name: str, tail: tuple[int | None, ...], dtype: type) -> np.ndarray:
        return _frozen(_flat_points(_dataset(g, path, name, axes + tail, dtype), bool(parameter2)))

    exponents = per_point("exponents", (None,), float) if "exponents" in g else None
    k = None if exponents is None else exponents.shape[1]
    drive_period = None
    if "drive_period" in g:
        along = "point" if _str(_attr(g, path, "parameter")) == "omega" else "point2"
        period = _dataset(g, path, "drive_period", (n1 if along == "point" else n2,), float)
        if parameter2:
            period = np.tile(period, n2) if along == "point" else np.repeat(period, n1)
        drive_period = _frozen(period)
    return Sweep(
        parameter=_str(_attr(g, path, "parameter")),
        parameter2=parameter2,
        mode=_str(_attr(g, path, "mode")),
        values=_frozen(values),
        x=per_point("x", (None, n), float),
        collisions_per_cycle=per_point("collisions_per_cycle", (), float),
        period=per_point("period", (n,), int),
        exponents=exponents,
        stderr=per_point("stderr", (k,), float) if "stderr" in g else None,
        ky_dimension=per_point("ky_dimension", (), float) if "ky_dimension" in g else None,
        drive_period=drive_period,
    )


def _read_continuation(g: h5py.Group, path: str, n: int) -> Continuation:
    values = _dataset(g, path, "values", (None,), float)
    p = values.shape[0]
    period = _dataset(g, path, "period", (p,), int)
    if p and period.min() < 1:
        raise SchemaError(f"{path}: {g.name}/period holds {period.min()}; periods are >= 1")
    strobe_x = _dataset(g, path, "strobe_x", (p, None, n), float)
    if p and strobe_x.shape[1] < period.max():
        raise SchemaError(f"{path}: {g.name}/strobe_x has {strobe_x.shape[1]} iterates, "
                          f"fewer than the largest period {period.max()}")
    stable = _dataset(g, path, "stable", (p,), int)
    if not np.isin(stable, (0, 1)).all():
        raise SchemaError(f"{path}: {g.name}/stable holds values other than 0 and 1")
    special_index = _dataset(g, path, "special_index", (None,), int)
    s = special_index.shape[0]
    if s and (special_index.min() < 0 or special_index.max() >= p):
        raise SchemaError(f"{path}: {g.name}/special_index holds values outside 0..{p - 1} "
                          f"(found {special_index.min()}..{special_index.max()})")
    special_kind = _strings(g, path, "special_kind", (s,))
    unknown = sorted({str(kind) for kind in special_kind} - set(SPECIAL_KINDS))
    if unknown:
        raise SchemaError(f"{path}: {g.name}/special_kind holds {', '.join(map(repr, unknown))}"
                          f" (known: {', '.join(SPECIAL_KINDS)})")
    return Continuation(
        parameter=_str(_attr(g, path, "parameter")),
        phase=_float(_attr(g, path, "phase"), path, f"{g.name}/phase"),
        end_reason=_str(_attr(g, path, "end_reason")),
        values=values,
        x=_dataset(g, path, "x", (p, n), float),
        v=_dataset(g, path, "v", (p, n), float),
        strobe_x=strobe_x,
        period=period,
        branch=_dataset(g, path, "branch", (p,), int),
        multipliers_re=_dataset(g, path, "multipliers_re", (p, 2 * n), float),
        multipliers_im=_dataset(g, path, "multipliers_im", (p, 2 * n), float),
        stable=_frozen(stable == 1),
        min_gap=_dataset(g, path, "min_gap", (p,), float),
        min_impact_speed=_dataset(g, path, "min_impact_speed", (p,), float),
        impacts_per_period=_dataset(g, path, "impacts_per_period", (p,), int),
        residual=_dataset(g, path, "residual", (p,), float),
        iterations=_dataset(g, path, "iterations", (p,), int),
        special_index=special_index,
        special_kind=special_kind,
        special_value=_dataset(g, path, "special_value", (s,), float),
    )


def _read_census(g: h5py.Group, path: str, n: int) -> Census:
    values = _dataset(g, path, "point", (None,), float)
    p = values.shape[0]
    x0 = _dataset(g, path, "x0", (p, None, n), float)
    s = x0.shape[1]
    samples = _int(_attr(g, path, "samples"), path, f"{g.name}/samples")
    if s != samples:
        raise SchemaError(f"{path}: {g.name}/x0 holds {s} samples, its 'samples' attribute "
                          f"{samples}")
    kinds = _strings(g, path, "attractor_kind", (None,))
    a = kinds.shape[0]
    unknown = sorted({str(kind) for kind in kinds} - set(ATTRACTOR_KINDS))
    if unknown:
        raise SchemaError(f"{path}: {g.name}/attractor_kind holds "
                          f"{', '.join(map(repr, unknown))} (known: {', '.join(ATTRACTOR_KINDS)})")
    ids = _dataset(g, path, "sample_attractor", (p, s), int)
    if ids.size and (ids.min() < 0 or ids.max() >= a):
        raise SchemaError(f"{path}: {g.name}/sample_attractor holds ids outside 0..{a - 1}")
    point = _dataset(g, path, "attractor_point", (a,), int)
    if a and (point.min() < 0 or point.max() >= p):
        raise SchemaError(f"{path}: {g.name}/attractor_point holds points outside "
                          f"0..{p - 1}")
    mirrored = _dataset(g, path, "mirrored", (p, s), int)
    if not np.isin(mirrored, (0, 1)).all():
        raise SchemaError(f"{path}: {g.name}/mirrored holds values other than 0 and 1")
    plane = None
    plane_range = None
    plane_points = 0
    if "plane" in g.attrs:
        names = tuple(_str(g.attrs["plane"]).split())
        bad = [name for name in names if not re.fullmatch(r"[xv][0-9]+", name)
               or not 1 <= int(name[1:]) <= n]
        if len(names) != 2 or bad:
            raise SchemaError(f"{path}: {g.name} attribute 'plane' = "
                              f"{_str(g.attrs['plane'])!r} is not two coordinates x<i> or "
                              f"v<i>, i in 1..{n}")
        plane = (names[0], names[1])
        plane_range = _frozen(np.asarray(_attr(g, path, "plane_range"), dtype=float))
        if plane_range.shape != (4,):
            raise SchemaError(f"{path}: {g.name} attribute 'plane_range' has "
                              f"{plane_range.size} values, expected 4")
        plane_points = _int(_attr(g, path, "plane_points"), path, f"{g.name}/plane_points")
        if plane_points**2 != s:
            raise SchemaError(f"{path}: {g.name}: plane_points = {plane_points} does not "
                              f"square to the {s} samples")
    lambda1 = _dataset(g, path, "lambda1", (p, s), float)
    stored = "sample_exponents" in g
    if stored:
        exponents = _dataset(g, path, "sample_exponents", (p, s, None), float)
        k = exponents.shape[2]
        exponents_stderr = _dataset(g, path, "sample_exponents_stderr", (p, s, k), float)
        attractor_exponents = _dataset(g, path, "attractor_exponents", (a, k), float)
        spread = _dataset(g, path, "attractor_exponents_spread", (a, k), float)
    else:
        exponents = _frozen(lambda1[:, :, np.newaxis].copy())
        exponents_stderr = _frozen(np.full(exponents.shape, np.nan))
        attractor_exponents, spread = _ensembles(exponents, ids, point, a)
    return Census(
        parameter=_str(_attr(g, path, "parameter")),
        samples=samples,
        seed=_int(_attr(g, path, "seed"), path, f"{g.name}/seed"),
        x_amp=_float(_attr(g, path, "x_amp"), path, f"{g.name}/x_amp"),
        v_amp=_float(_attr(g, path, "v_amp"), path, f"{g.name}/v_amp"),
        tolerance=_float(_attr(g, path, "tolerance"), path, f"{g.name}/tolerance"),
        mirror=_str(_attr(g, path, "mirror")),
        rule=_str(g.attrs.get("rule", "")),
        values=values,
        x0=x0,
        v0=_dataset(g, path, "v0", (p, s, n), float),
        sample_attractor=ids,
        mirrored=_frozen(mirrored == 1),
        lambda1=lambda1,
        attractor_kind=kinds,
        attractor_period=_dataset(g, path, "attractor_period", (a, n), int),
        attractor_lambda1=_dataset(g, path, "attractor_lambda1", (a,), float),
        attractor_lambda1_stderr=_dataset(g, path, "attractor_lambda1_stderr", (a,), float),
        attractor_x=_dataset(g, path, "attractor_x", (a, n), float),
        attractor_v=_dataset(g, path, "attractor_v", (a, n), float),
        attractor_point=point,
        attractor_sample=_dataset(g, path, "attractor_sample", (a,), int),
        attractor_sites=_dataset(g, path, "attractor_sites", (a, n + 1), float),
        fraction=_dataset(g, path, "fraction", (p, a), float),
        fraction_stderr=_dataset(g, path, "fraction_stderr", (p, a), float),
        sample_exponents=exponents,
        sample_exponents_stderr=exponents_stderr,
        attractor_exponents=attractor_exponents,
        attractor_exponents_spread=spread,
        ensemble_stored=stored,
        plane=plane,
        plane_range=plane_range,
        plane_points=plane_points,
    )


def _ensembles(exponents: np.ndarray, ids: np.ndarray, point: np.ndarray,
               a: int) -> tuple[np.ndarray, np.ndarray]:
    """(A, k) the mean of each attractor's samples' exponents and their standard deviation
    (n - 1; 0 for one sample), as the simulator's census defines them: -infinity in some
    member makes the mean -infinity and the spread +infinity (0 when every member's is)."""
    k = exponents.shape[2]
    mean = np.zeros((a, k))
    spread = np.zeros((a, k))
    for attractor in range(a):
        values = exponents[int(point[attractor])][ids[int(point[attractor])] == attractor]
        if values.shape[0] == 0:
            continue
        with np.errstate(invalid="ignore"):
            mean[attractor] = values.mean(axis=0)
        for j in range(k):
            column = values[:, j]
            if column.size == 1:
                continue
            if np.isfinite(column).all():
                spread[attractor, j] = column.std(ddof=1)
            elif not (column == column[0]).all():
                spread[attractor, j] = np.inf
    return _frozen(mean), _frozen(spread)


def _read_clv(g: h5py.Group, path: str, n: int) -> Clv:
    exponents = _dataset(g, path, "exponents", (None,), float)
    k = exponents.shape[0]
    cycle = _dataset(g, path, "cycle", (None,), int)
    r = cycle.shape[0]
    unstable = _int(_attr(g, path, "unstable"), path, f"{g.name}@unstable")
    if not 0 <= unstable <= k:
        raise SchemaError(f"{path}: {g.name}@unstable = {unstable} is outside 0..{k}")
    site_weight = None
    if "site_weight" in g:
        site_weight = _dataset(g, path, "site_weight", (r, None, n), float)
        if site_weight.shape[1] > k:
            raise SchemaError(f"{path}: {g.name}/site_weight holds {site_weight.shape[1]} "
                              f"vectors, more than the {k} of {g.name}/exponents")
    vectors = saved_cycle = None
    if "vectors" in g or "saved_cycle" in g:
        saved_cycle = _dataset(g, path, "saved_cycle", (None,), int)
        vectors = _dataset(g, path, "vectors", (saved_cycle.shape[0], k, 2 * n), float)
    return Clv(
        cycle=cycle,
        exponents=exponents,
        stderr=_dataset(g, path, "stderr", (k,), float),
        stderr_block=_dataset(g, path, "stderr_block", (k,), int),
        ipr=_dataset(g, path, "ipr", (r, k), float),
        min_angle=_dataset(g, path, "min_angle", (r,), float),
        clv_transient=_int(_attr(g, path, "clv_transient"), path, f"{g.name}@clv_transient"),
        unstable=unstable,
        site_weight=site_weight,
        vectors=vectors,
        saved_cycle=saved_cycle,
    )


def _read_finite_time(g: h5py.Group, path: str) -> FiniteTime:
    window = _int(_attr(g, path, "window"), path, f"{g.name}@window")
    if window < 1:
        raise SchemaError(f"{path}: {g.name}@window = {window} must be >= 1")
    cycle = _dataset(g, path, "cycle", (None,), int)
    return FiniteTime(
        window=window,
        cycle=cycle,
        exponents=_dataset(g, path, "exponents", (cycle.shape[0], None), float),
    )


# ------------------------------------------------------------------------------- namelists


def namelist_groups(text: str) -> dict[str, dict[str, str]]:
    """``{group: {key: value text}}`` of a Fortran namelist text, lower-case names.

    Enough of the namelist syntax for the simulator's input and resolved namelists:
    ``!`` comments, quoted strings, ``key = value`` pairs separated by commas or
    newlines, list values (``x0 = 0.1, 0.2``) kept as their text. A later group of the
    same name adds to the earlier one.
    """
    groups: dict[str, dict[str, str]] = {}
    for name, body in _namelist_bodies(_strip_comments(text)):
        group = groups.setdefault(name, {})
        keys = list(_KEY.finditer(_mask_strings(body)))
        for key, following in zip(keys, [*keys[1:], None]):
            end = following.start() if following is not None else len(body)
            value = body[key.end():end].strip().rstrip(",").strip()
            group[key.group(1).lower()] = value
    return groups


_KEY = re.compile(r"(?:^|(?<=[,\s]))([A-Za-z]\w*)\s*=(?!=)")


def _strip_comments(text: str) -> str:
    lines = []
    for line in text.splitlines():
        quote = ""
        for i, char in enumerate(line):
            if quote:
                if char == quote:
                    quote = ""
            elif char in "'\"":
                quote = char
            elif char == "!":
                line = line[:i]
                break
        lines.append(line)
    return "\n".join(lines)


def _namelist_bodies(text: str) -> Iterable[tuple[str, str]]:
    """(group name, body) of every ``&group ... /`` (a ``/`` inside quotes is text)."""
    i = 0
    while (start := text.find("&", i)) >= 0:
        match = re.match(r"&([A-Za-z]\w*)", text[start:])
        if match is None:
            i = start + 1
            continue
        j, quote = start + match.end(), ""
        while j < len(text):
            char = text[j]
            if quote:
                if char == quote:
                    quote = ""
            elif char in "'\"":
                quote = char
            elif char == "/":
                break
            j += 1
        yield match.group(1).lower(), text[start + match.end():j]
        i = j + 1


def _mask_strings(body: str) -> str:
    """``body`` with the inside of quoted strings replaced by ``#`` (same length), so that
    the key search finds no ``key =`` inside a string value."""
    out, quote = [], ""
    for char in body:
        if quote:
            if char == quote:
                quote = ""
                out.append(char)
            else:
                out.append("#")
        else:
            if char in "'\"":
                quote = char
            out.append(char)
    return "".join(out)


# ------------------------------------------------------------------------ in-memory runs

IN_MEMORY = "(in memory, impactchain.api)"
"""``Run.path`` of a run made by :func:`run_from_api`."""


def run_from_api(simulation: Any = None, lyapunov: Any = None) -> Run:
    """A :class:`Run` from the in-memory results of :mod:`impactchain.api`, for the figures.

    ``simulation``: a ``impactchain.api.Simulation`` (strobe records, events, statistics, final
    state); ``lyapunov``: a ``impactchain.api.Lyapunov`` (exponents and their standard errors;
    no running estimates). Either or both; with both they must come from the same
    parameters. Their ``params`` (the arguments as used) give ``Run.params``, and the
    equivalent namelist becomes ``Run.input_namelist``; units are the simulator's
    (:data:`FILE_UNITS`). ``api.Simulation.to_run()`` and ``api.Lyapunov.to_run()`` call
    this.
    """
    if simulation is None and lyapunov is None:
        raise ValueError("run_from_api needs a simulation, a Lyapunov result or both")
    sources = [r for r in (simulation, lyapunov) if r is not None]
    settings = [dict(getattr(r, "params", None) or {}) for r in sources]
    if not settings[0]:
        raise ValueError(f"{type(sources[0]).__name__} has no params: "
                         "not an impactchain.api result")
    config = settings[0]
    if len(settings) == 2:
        model = ("n", "amplitude", "omega", "damping", "restitution", "boundary", "phase")
        differ = [k for k in model if settings[0].get(k) != settings[1].get(k)]
        if differ:
            raise ValueError("the simulation and the Lyapunov result differ in "
                             + ", ".join(differ))
    n = int(config["n"])
    spacing = np.broadcast_to(np.asarray(config["spacing"], dtype=float), (n + 1,))
    omega = float(config["omega"])
    params = Params(
        n=n, damping=float(config["damping"]), restitution=float(config["restitution"]),
        amplitude=float(config["amplitude"]), omega=omega, boundary=str(config["boundary"]),
        drive_period=2 * math.pi / omega, phase=float(config["phase"]),
        transient=int(config["transient"]), cycles=int(config["cycles"]),
        spacing=_frozen(spacing),
    )
    parts: dict[str, Any] = {}
    x0, v0 = config.get("x0"), config.get("v0")
    if x0 is not None and v0 is not None:
        parts["initial"] = State(x=_frozen(x0), v=_frozen(v0))
    if simulation is not None:
        parts.update(_simulation_parts(simulation, params, bool(config.get("events", True))))
    if lyapunov is not None:
        exponents = _frozen(lyapunov.exponents)
        parts["lyapunov"] = Lyapunov(
            exponents=exponents,
            exponents_per_time=_frozen(lyapunov.exponents_per_time),
            stderr=_frozen(lyapunov.stderr),
            running=_frozen(np.empty((0, exponents.size))),
            ky_dimension=float(lyapunov.ky_dimension),
            positive_sum=math.nan,  # not returned by impactchain.api
            collisions_per_cycle=float(lyapunov.collisions_per_cycle),
            stderr_block=getattr(lyapunov, "stderr_block", None),
        )
        if getattr(lyapunov, "finite_time", None) is not None:
            parts["finite_time"] = lyapunov.finite_time
        if "final" not in parts:
            parts["final"] = FinalState(
                x=_frozen(lyapunov.final_x), v=_frozen(lyapunov.final_v),
                cycle=params.transient + params.cycles, phase=params.phase)
    merged = {**settings[-1], **config}
    return Run(
        path=IN_MEMORY,
        schema_version=SCHEMA_VERSION,
        code_version=str(config.get("code_version", "")),
        input_namelist=_equivalent_namelist(merged, lyapunov is not None),
        complete=True,
        params=params,
        units=FILE_UNITS,
        **parts,
    )


def is_sweep_dataset(data: Any) -> bool:
    """Is ``data`` an :func:`impactchain.api.sweep` result (an xarray Dataset of /sweep)?"""
    attrs = getattr(data, "attrs", None)
    return (hasattr(data, "data_vars") and isinstance(attrs, Mapping)
            and "parameter" in attrs and "input_namelist" in attrs)


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


def run_from_sweep(ds: Any) -> Run:
    """A :class:`Run` holding the sweep of :func:`impactchain.api.sweep` (an xarray Dataset),
    for the figures: ``Run.sweep`` with its points in the file's order (version 1's flat
    list, p = i + n1 j), ``Run.params`` from the Dataset's attributes (NaN for the swept
    parameters, as in a sweep file)."""
    if not is_sweep_dataset(ds):
        raise TypeError(f"{type(ds).__name__} is not a sweep of impactchain.api.sweep")
    attrs = ds.attrs
    two_d = bool(attrs["parameter2"])

    def flat(name: str) -> np.ndarray | None:
        return _frozen(_flat_points(np.asarray(ds[name].values), two_d)) if name in ds else None

    values = _point_values(np.asarray(ds["point"].values),
                           np.asarray(ds["point2"].values) if two_d else None)
    drive_period = None
    if "drive_period" in ds:
        axis = 0 if attrs["parameter"] == "omega" else 1
        drive_period = _frozen(2 * math.pi / np.atleast_2d(values.T)[axis])
    sweep = Sweep(parameter=str(attrs["parameter"]), parameter2=str(attrs["parameter2"]),
                  mode=str(attrs["mode"]), values=_frozen(values), x=flat("x"),
                  collisions_per_cycle=flat("collisions_per_cycle"), period=flat("period"),
                  exponents=flat("exponents"), stderr=flat("stderr"),
                  ky_dimension=flat("ky_dimension"), drive_period=drive_period)
    n = int(attrs["n"])
    nan = math.nan
    omega = float(attrs.get("omega", nan))
    params = Params(
        n=n, damping=float(attrs.get("damping", nan)),
        restitution=float(attrs.get("restitution", nan)),
        amplitude=float(attrs.get("amplitude", nan)), omega=omega,
        boundary=str(attrs["boundary"]), drive_period=2 * math.pi / omega,
        phase=float(attrs["phase"]), transient=int(attrs["transient"]),
        cycles=int(attrs["cycles"]),
        spacing=_frozen(np.asarray(attrs.get("spacing", np.full(n + 1, nan)), dtype=float)),
    )
    return Run(path=IN_MEMORY, schema_version=SCHEMA_VERSION,
               code_version=str(attrs["code_version"]),
               input_namelist=str(attrs["input_namelist"]), complete=True, params=params,
               units=FILE_UNITS, sweep=sweep)


def _simulation_parts(sim: Any, params: Params, events: bool) -> dict[str, Any]:
    parts: dict[str, Any] = {
        "strobe": Strobe(x=_frozen(sim.x), v=_frozen(sim.v),
                         cycle=_frozen(np.asarray(sim.cycle, dtype=np.int64)),
                         period=_frozen(np.asarray(sim.periods, dtype=np.int64))),
        "stats": Stats(collisions_per_cycle=float(sim.collisions_per_cycle),
                       impacts=int(sim.impacts), sticks=int(sim.sticks),
                       releases=int(sim.releases),
                       site_counts=_frozen(np.asarray(sim.site_counts, dtype=np.int64)),
                       cycles_done=int(sim.x.shape[0]), touches=int(sim.touches)),
        "final": FinalState(x=_frozen(sim.final_x), v=_frozen(sim.final_v),
                            cycle=params.transient + params.cycles, phase=params.phase),
    }
    if events:
        parts["events"] = Events(
            time=_frozen(sim.event_time),
            site=_frozen(np.asarray(sim.event_site, dtype=np.int64)),
            speed=_frozen(sim.event_speed),
            kind=_frozen(np.asarray(sim.event_kind, dtype=np.int64)))
    return parts


_LISTED_START = 1000
"""The equivalent namelist of an in-memory run lists x0 and v0 up to this many values."""


def _equivalent_namelist(config: Mapping[str, Any], lyapunov: bool) -> str:
    """The input namelist of a command-line run equal to this in-memory one."""

    def real(value: Any) -> str:
        return repr(float(value))

    spacing = np.atleast_1d(np.asarray(config["spacing"], dtype=float))
    lines = [
        "! made in memory by impactchain.api; the equivalent command-line input:",
        f"&chain n = {int(config['n'])}, amplitude = {real(config['amplitude'])}, "
        f"omega = {real(config['omega'])}, damping = {real(config['damping'])}, "
        f"restitution = {real(config['restitution'])}, "
        f"spacing = {', '.join(real(a) for a in spacing)}, "
        f"boundary = '{config['boundary']}' /",
    ]
    x0, v0 = config.get("x0"), config.get("v0")
    if x0 is None or v0 is None:
        lines.append("&initial kind = 'rest' /")
    elif len(x0) > _LISTED_START:
        lines.append(f"&initial kind = 'explicit' /  ! x0 and v0: {len(x0)} values each, "
                     "not listed")
    else:
        lines.append(f"&initial kind = 'explicit', x0 = {', '.join(map(real, x0))}, "
                     f"v0 = {', '.join(map(real, v0))} /")
    record = ".true." if config.get("events", False) else ".false."
    lines.append(f"&run transient = {int(config['transient'])}, cycles = "
                 f"{int(config['cycles'])}, phase = {real(config['phase'])}, "
                 f"stick_speed = {real(config['stick_speed'])}, record_events = {record} /")
    if lyapunov:
        window = int(config.get("window", 0))
        lines.append(f"&lyapunov enabled = .true., vectors = {int(config.get('vectors', 0))}, "
                     f"qr_every = {int(config.get('qr_every', 1))}"
                     + (f", window = {window}" if window else "") + " /")
    return "\n".join(lines) + "\n"


def _frozen(values: Any) -> np.ndarray:
    out = np.array(values, dtype=np.float64 if np.asarray(values).dtype.kind == "f"
                   else np.asarray(values).dtype)
    out.setflags(write=False)
    return out


# ----------------------------------------------------------------------------- helpers


def _attr(g: h5py.Group, path: str, name: str) -> Any:
    if name not in g.attrs:
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
    if name not in g:
        raise SchemaError(f"{path}: no {where} dataset")
    obj = g[name]
    if not isinstance(obj, h5py.Dataset):
        raise SchemaError(f"{path}: {where} is not a dataset")
    data = np.asarray(obj[()])
    if shape is None:
        if data.size != 1:
            raise SchemaError(f"{path}: {where} should be a scalar, found shape {data.shape}")
        data = data.reshape(())
    else:
        _check_shape(data.shape, shape, path, where)
    out = np.array(data, dtype=np.float64 if dtype is float else np.int64)
    out.setflags(write=False)
    return out


def _strings(g: h5py.Group, path: str, name: str, shape: tuple[int | None, ...]) -> np.ndarray:
    """Read the string dataset ``g/name`` (variable- or fixed-length) as a read-only array
    of str, checking its shape."""
    where = f"{g.name}/{name}"
    if name not in g:
        raise SchemaError(f"{path}: no {where} dataset")
    obj = g[name]
    if not isinstance(obj, h5py.Dataset) or obj.dtype.kind not in "SUO":
        raise SchemaError(f"{path}: {where} is not a dataset of strings")
    data = np.asarray(obj[()], dtype=object)
    _check_shape(data.shape, shape, path, where)
    out = np.array([_str(item) for item in data.reshape(-1)], dtype=str).reshape(data.shape)
    out.setflags(write=False)
    return out


def _check_shape(
    found: tuple[int, ...], expected: tuple[int | None, ...], path: str, where: str
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
