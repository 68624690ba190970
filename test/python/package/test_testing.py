"""impactchain.testing, the invariants the test suites assert: the sum rule's expected value
and the check itself (it must pass on a spectrum that obeys the rule and fail on one that does
not)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from impactchain.testing import assert_sum_rule, sum_rule_expected

CASE = dict(n=3, damping=0.05, omega=1.5, restitution=0.7, collisions_per_cycle=4.0)


def spectrum_with_sum(total_nats: float, n: int = 3) -> np.ndarray:
    """2n descending exponents in bits per cycle whose sum is total_nats nats."""
    bits = np.linspace(0.5, -1.5, 2 * n)
    return bits + (total_nats / math.log(2) - bits.sum()) / (2 * n)


def test_expected_sum() -> None:
    period = 2 * math.pi / 1.5
    assert sum_rule_expected(**CASE) == pytest.approx(-2 * 0.05 * 3 * period
                                                      + 2 * math.log(0.7) * 4, rel=1e-15)
    assert sum_rule_expected(**{**CASE, "collisions_per_cycle": 0.0}) == pytest.approx(
        -2 * 0.05 * 3 * period, rel=1e-15)
    assert sum_rule_expected(**{**CASE, "restitution": 0.0}) == -math.inf
    assert sum_rule_expected(**{**CASE, "restitution": 0.0, "collisions_per_cycle": 0.0}) < 0


def test_passes_and_fails() -> None:
    expected = sum_rule_expected(**CASE)
    assert assert_sum_rule(spectrum_with_sum(expected), **CASE, sticks=0)
    with pytest.raises(AssertionError, match="sum rule x: sum of the exponents"):
        assert_sum_rule(spectrum_with_sum(expected + 1e-6), **CASE, sticks=0, label="x")
    with pytest.raises(AssertionError, match="not all 2n"):
        assert_sum_rule(spectrum_with_sum(expected)[:5], **CASE, sticks=0)
    with pytest.raises(AssertionError, match="sum"):
        assert_sum_rule(np.full(6, -np.inf), **CASE, sticks=0)


def test_restitution_zero_needs_minus_infinity() -> None:
    case = {**CASE, "restitution": 0.0}
    assert assert_sum_rule(np.array([0.1, 0, -1, -2, -3, -np.inf]), **case, sticks=0)
    with pytest.raises(AssertionError, match="must be -infinity"):
        assert_sum_rule(spectrum_with_sum(-40.0), **case, sticks=0)


def test_rests_are_left_out() -> None:
    assert not assert_sum_rule(np.full(6, -np.inf), **CASE, sticks=3)
