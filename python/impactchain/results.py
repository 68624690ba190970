"""A run's contents as the package hands them out: frozen dataclasses with read-only numpy
arrays, record axis first (the table of :mod:`impactchain.io` maps each to its HDF5 path), the
codes and names their datasets hold, and the units of each dataset.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field

import numpy as np

from impactchain.namelist import namelist_groups

__all__ = [
    "SCHEMA_VERSION", "IMPACT", "STICK", "RELEASE", "TOUCH", "FILE_UNITS", "SPECIAL_KINDS",
    "ATTRACTOR_KINDS", "Params", "State", "FinalState", "Strobe", "Events", "Stats", "Lyapunov",
    "Sweep", "Continuation", "Curve", "period_pattern", "Census", "Clv", "FiniteTime", "Run",
]


SCHEMA_VERSION = 2
"""The file layout the simulator writes (``Run.schema_version`` of a run made in memory)."""


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
    run made in memory (:func:`impactchain.inmemory.run_from_api`) and the defaults of the
    figures' axis labels. Read from the file schema (:mod:`impactchain.schema`) when first
    asked."""

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


SPECIAL_KINDS = ("fold", "period-doubling", "neimark-sacker", "grazing", "corner", "section",
                 "branch-point")
"""``/continuation/special_kind``: the special points a continuation locates."""

ATTRACTOR_KINDS = ("periodic", "chaotic", "aperiodic-nonchaotic")
"""``/census/attractor_kind``: what a census's attractor is (docs/model.md section 13.2)."""


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
    period doublings and branch points). Branch ``b`` began on branch ``parent[b]`` at its
    point ``origin_point[b]``, a special point of kind ``origin_kind[b]``, whose orbit is
    ``b``'s first point (branch 0: -1, -1, ''; None in files written before these datasets).
    Special points (folds, period doublings, Neimark-Sacker points,
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
    parent: np.ndarray | None = None  # (B,) the branch each branch began on, -1: none
    origin_point: np.ndarray | None = None  # (B,) 0-based point it began at, -1: none
    origin_kind: np.ndarray | None = None  # (B,) str, that point's special kind, '': none

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


@dataclass(frozen=True, eq=False)
class Curve:
    """A fold, period-doubling, grazing or Neimark-Sacker curve in two parameters
    (``/curve``): from the first such point of branch 0 of the file's continuation, one orbit
    per point at ``parameter = values[i]``, ``parameter2 = values2[i]``, with a multiplier +1
    (a fold) or -1 (a period doubling), a gap touching zero (a grazing) or a complex pair on
    the unit circle (a Neimark-Sacker point). No points when the branch had
    no such point (``end_reason`` says so).
    """

    follow: str  # fold, period-doubling, grazing or neimark-sacker
    parameter: str  # the continued parameter
    parameter2: str  # the curve's second parameter
    end_reason: str  # why the curve ended, or why it has no points
    values: np.ndarray  # (C,) the continued parameter at each point
    values2: np.ndarray  # (C,) the second parameter at each point
    x: np.ndarray  # (C, n) the orbit's state on the section
    v: np.ndarray  # (C, n)
    multipliers_re: np.ndarray  # (C, 2n) Floquet multipliers
    multipliers_im: np.ndarray  # (C, 2n)
    codim2_index: np.ndarray  # (K,) 0-based point of each codimension-two point
    codim2_kind: np.ndarray  # (K,) str: fold-flip, 1:1, 1:2, cusp, fold-grazing, doubling-grazing

    @property
    def multipliers(self) -> np.ndarray:
        """The Floquet multipliers as complex numbers, (C, 2n)."""
        return self.multipliers_re + 1j * self.multipliers_im


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
    curve: Curve | None = None
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
        """This run (the protocol the figure functions accept, see
        :func:`impactchain.inmemory.run_from_api`)."""
        return self
