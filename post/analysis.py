"""Small analysis helpers: Kaplan-Yorke dimension, period detection, panel ranges.

All functions are pure and work on plain numpy arrays.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "BITS_PER_NAT",
    "kaplan_yorke",
    "kaplan_yorke_rows",
    "detect_period",
    "detect_periods",
    "period_label",
    "panel_ranges",
]

BITS_PER_NAT = 1.0 / math.log(2.0)
"""Multiply an exponent in nats by this to get bits."""


def kaplan_yorke(exponents: ArrayLike, full_dimension: int | None = None) -> float:
    """Kaplan-Yorke (Lyapunov) dimension of a spectrum (docs/model.md section 7.5).

    The exponents are sorted descending; with ``j`` the largest index such that
    ``l1 + ... + lj >= 0``, ``D = j + (l1 + ... + lj) / |l(j+1)|``. ``D = 0`` when
    ``l1 < 0``; when the sum of all exponents is >= 0 the attractor fills phase space
    and ``D`` is the number of exponents. If the spectrum is truncated (fewer exponents
    than ``full_dimension``) and its whole sum is >= 0, ``D`` cannot be determined and
    NaN is returned. The result does not depend on the unit of the exponents.
    """
    spectrum = np.sort(np.asarray(exponents, dtype=np.float64).reshape(-1))[::-1]
    if spectrum.size == 0 or np.isnan(spectrum).any():
        return math.nan
    partial = np.cumsum(spectrum)
    nonnegative = np.flatnonzero(partial >= 0.0)
    if nonnegative.size == 0:
        return 0.0
    j = int(nonnegative[-1]) + 1  # number of exponents in the largest non-negative sum
    if j == spectrum.size:
        if full_dimension is not None and spectrum.size < full_dimension:
            return math.nan
        return float(j)
    return j + float(partial[j - 1]) / abs(float(spectrum[j]))


def kaplan_yorke_rows(exponents: ArrayLike, full_dimension: int | None = None) -> np.ndarray:
    """:func:`kaplan_yorke` of each row of an (n_points, k) array."""
    rows = np.atleast_2d(np.asarray(exponents, dtype=np.float64))
    return np.array([kaplan_yorke(row, full_dimension) for row in rows])


def detect_period(series: ArrayLike, max_period: int | None = None, rtol: float = 1e-6) -> int:
    """Smallest period p of a strobe series, or 0 if none is found (aperiodic).

    ``series`` holds one oscillator's displacement at successive sections. p is accepted
    when ``|s[j+p] - s[j]| <= rtol * max(1, max|s|)`` for every j of the series; periods
    up to ``max_period`` (default: half the series length) are tried.
    """
    s = np.asarray(series, dtype=np.float64).reshape(-1)
    if s.size < 2:
        return 0
    limit = s.size // 2 if max_period is None else min(max_period, s.size - 1)
    tol = rtol * max(1.0, float(np.max(np.abs(s))))
    for p in range(1, limit + 1):
        if np.all(np.abs(s[p:] - s[:-p]) <= tol):
            return p
    return 0


def detect_periods(x: ArrayLike, max_period: int | None = None, rtol: float = 1e-6) -> np.ndarray:
    """:func:`detect_period` of each column of an (n_record, n) strobe array."""
    arr = np.asarray(x, dtype=np.float64)
    return np.array([detect_period(arr[:, i], max_period, rtol) for i in range(arr.shape[1])],
                    dtype=np.int64)


def period_label(period: int) -> str:
    """'P1', 'P2', ... for a period, 'ap' for 0 (aperiodic)."""
    return "ap" if period <= 0 else f"P{period}"


def panel_ranges(
    cycles: ArrayLike,
    panel_cycles: int,
    panels: int | None = None,
    start: int | None = None,
    max_panels: int = 8,
) -> list[tuple[int, int]]:
    """Half-open cycle ranges ``[start, stop)`` that split a record into panels.

    Panels are ``panel_cycles`` long and begin at ``start`` (default: the first recorded
    cycle). With ``panels=None`` there are as many as needed to show every record from
    ``start`` on (the last one may be partly empty), at most ``max_panels``; otherwise
    exactly ``panels`` of them.
    """
    if panel_cycles < 1:
        raise ValueError(f"panel_cycles = {panel_cycles} must be >= 1")
    c = np.asarray(cycles).reshape(-1)
    if c.size == 0:
        raise ValueError("no recorded cycles to split into panels")
    first, last = int(c.min()), int(c.max())
    if start is None:
        start = first
    elif not first <= start <= last:
        raise ValueError(f"start cycle {start} is outside the recorded cycles {first}..{last}")
    if panels is None:
        panels = min(max_panels, (last - start) // panel_cycles + 1)
    if panels < 1:
        raise ValueError(f"panels = {panels} must be >= 1")
    return [(start + p * panel_cycles, start + (p + 1) * panel_cycles) for p in range(panels)]
