"""Invariants every run of the simulator satisfies, as assertions for test suites.

The one place the Python tests (``test/python/package``, ``test/python``) check them, so that every
suite applies the same rule with the same tolerance.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["SUM_RULE_TOL", "sum_rule_expected", "assert_sum_rule"]

SUM_RULE_TOL = 1e-9
"""Tolerance of the sum rule, relative to the larger of 1 and the expected sum (nats per
cycle): the sum of the logarithms of the QR diagonals is exact to the rounding of each
cycle's determinant."""


def sum_rule_expected(n: int, damping: float, omega: float, restitution: float,
                      collisions_per_cycle: float) -> float:
    """Sum of all 2n Lyapunov exponents in nats per drive cycle: ``-2 b n T + 2 ln(K) c``.

    The flow contracts phase-space volume by ``exp(-2 b n T)`` per cycle ``T = 2 pi / w``
    and every impact by ``K**2`` (the determinant of its saltation matrix); ``c`` is the
    mean number of impacts per cycle. ``-inf`` for ``K = 0`` with impacts.
    """
    period = 2 * math.pi / omega
    expected = -2 * damping * n * period
    if collisions_per_cycle > 0:
        if restitution == 0:
            return -math.inf
        expected += 2 * math.log(restitution) * collisions_per_cycle
    return expected


def assert_sum_rule(exponents: ArrayLike, *, n: int, damping: float, omega: float,
                    restitution: float, collisions_per_cycle: float, sticks: int,
                    label: str = "") -> bool:
    """Assert the sum rule on a full spectrum (``exponents`` in bits per drive cycle, all 2n).

    Returns True when it was checked, False for a run excluded from it: one with rests on a
    wall (``sticks > 0``).
    """
    spectrum = np.asarray(exponents, dtype=np.float64).reshape(-1)
    where = f"sum rule{' ' + label if label else ''}"
    assert spectrum.size == 2 * n, f"{where}: {spectrum.size} exponents, not all 2n = {2 * n}"
    # Excluded: runs with rests on a wall. A rest zeroes the resting oscillator's tangent
    # rows (the Jacobian is singular, as the true infinite chatter sequence makes it), so the
    # sum is -infinity whatever K; such runs are treated separately.
    if sticks > 0:
        return False
    expected = sum_rule_expected(n, damping, omega, restitution, collisions_per_cycle)
    total = float(np.sum(spectrum)) * math.log(2)  # bits -> nats
    if math.isinf(expected):
        assert total == -math.inf, (
            f"{where}: K = 0 with {collisions_per_cycle} impacts per cycle, the sum must be "
            f"-infinity, got {total!r} nats per cycle")
        return True
    assert math.isfinite(total), f"{where}: sum {total!r}, want {expected!r} nats per cycle"
    tol = SUM_RULE_TOL * max(1.0, abs(expected))
    assert abs(total - expected) <= tol, (
        f"{where}: sum of the exponents {total!r}, want {expected!r} nats per cycle "
        f"(-2 b n T + 2 ln(K) c with c = {collisions_per_cycle!r}); "
        f"difference {total - expected:.3e}, tolerance {tol:.1e}")
    return True
