"""Shock waves: cascades of collisions running from a wall along the chain.

The construction of the paper (docs/model.md section 10.4), made definite where the paper is
silent. Sites follow the paper's convention: "oscillator k has collided" means bond k,
so site 0 is a hit on the left wall, site k (1..n-1) the collision of oscillators k and
k+1, and site n a hit on the right wall.

Rules, applied to the events in time order (ties keep their input order):

1. A left-wall hit (site 0) starts a new *left* wave; a right-wall hit (site n) starts a
   new *right* wave.
2. A collision at site k (1..n) extends the **oldest** live left wave whose last site is
   k-1; a collision at site k (0..n-1) extends the oldest live right wave whose last site
   is k+1. One collision may extend one left and one right wave (two cascades crossing),
   and a wall hit may both extend a wave arriving at that wall and start a new one.
3. A wave is *live* while the time since its last event is at most
   ``max_wait * drive_period`` (default one drive cycle). Once that wait is exceeded it is
   dead for good: later collisions never extend it.
4. A collision that extends no wave and is not a wall hit belongs to no wave.
5. A wave never takes two points from one event, and an event does not extend the wave
   it has just started.

"Oldest" means earliest start; among waves that started together, the first created.
Releases from sticking contacts are not collisions; pass ``kind`` to have them ignored.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["Wave", "build_shock_waves"]

RELEASE_KIND = 2
TOUCH_KIND = 3

Side = Literal["left", "right"]


@dataclass(frozen=True, eq=False)
class Wave:
    """One shock wave: the collisions it is made of, in time order."""

    side: Side  # 'left': started at the left wall, runs to larger sites
    times: np.ndarray  # (m,) collision times, same unit as the input
    sites: np.ndarray  # (m,) collision sites, consecutive (+1 for left, -1 for right)

    @property
    def start(self) -> float:
        """Time of the wall hit that started the wave."""
        return float(self.times[0])

    def __len__(self) -> int:
        return int(self.times.shape[0])


@dataclass
class _Growing:
    """A wave under construction."""

    side: Side
    times: list[float] = field(default_factory=list)
    sites: list[int] = field(default_factory=list)

    def add(self, time: float, site: int) -> None:
        self.times.append(time)
        self.sites.append(site)

    def freeze(self) -> Wave:
        times = np.array(self.times, dtype=np.float64)
        sites = np.array(self.sites, dtype=np.int64)
        times.setflags(write=False)
        sites.setflags(write=False)
        return Wave(self.side, times, sites)


def build_shock_waves(
    time: ArrayLike,
    site: ArrayLike,
    n: int,
    drive_period: float,
    max_wait: float = 1.0,
    kind: ArrayLike | None = None,
) -> list[Wave]:
    """Group collision events into left and right shock waves (rules in the module doc).

    ``time`` and ``site`` are the event times and sites (0..n); ``kind``, if given, drops
    releases (kind 2) and touches (kind 3), which are not collisions. Returns the waves in
    order of creation (start time).
    """
    times, sites = _collisions(time, site, n, kind)
    if drive_period <= 0 or max_wait < 0:
        raise ValueError("drive_period must be > 0 and max_wait >= 0")
    wait = max_wait * drive_period
    waves: list[_Growing] = []
    left: list[_Growing] = []  # live left waves, oldest first
    right: list[_Growing] = []  # live right waves, oldest first
    next_death = math.inf  # no live wave dies before this time
    for t, k in zip(times.tolist(), sites.tolist()):
        if t > next_death:
            left = [w for w in left if t - w.times[-1] <= wait]
            right = [w for w in right if t - w.times[-1] <= wait]
            next_death = min((w.times[-1] + wait for w in (*left, *right)), default=math.inf)
        if k >= 1:
            _extend_oldest(left, t, k, previous=k - 1)
        if k <= n - 1:
            _extend_oldest(right, t, k, previous=k + 1)
        if k == 0:
            waves.append(_start(left, "left", t, k))
        if k == n:
            waves.append(_start(right, "right", t, k))
        if k in (0, n):
            next_death = min(next_death, t + wait)
    return [w.freeze() for w in waves]


def _collisions(
    time: ArrayLike, site: ArrayLike, n: int, kind: ArrayLike | None
) -> tuple[np.ndarray, np.ndarray]:
    """Validated collision times and sites, sorted by time (stable)."""
    times = np.asarray(time, dtype=np.float64).reshape(-1)
    sites = np.asarray(site).reshape(-1)
    if times.shape != sites.shape:
        raise ValueError(f"time and site differ in length ({times.size} vs {sites.size})")
    if n < 1:
        raise ValueError(f"n = {n} must be >= 1")
    if sites.size and (sites.min() < 0 or sites.max() > n):
        raise ValueError(f"sites must lie in 0..{n}")
    sites = sites.astype(np.int64)
    if kind is not None:
        kinds = np.asarray(kind).reshape(-1)
        if kinds.shape != times.shape:
            raise ValueError("kind and time differ in length")
        keep = (kinds != RELEASE_KIND) & (kinds != TOUCH_KIND)
        times, sites = times[keep], sites[keep]
    order = np.argsort(times, kind="stable")
    return times[order], sites[order]


def _extend_oldest(live: Sequence[_Growing], t: float, k: int, previous: int) -> None:
    """Append (t, k) to the first (oldest) live wave whose last site is ``previous``."""
    for wave in live:
        if wave.sites[-1] == previous:
            wave.add(t, k)
            return


def _start(live: list[_Growing], side: Side, t: float, k: int) -> _Growing:
    wave = _Growing(side)
    wave.add(t, k)
    live.append(wave)
    return wave
