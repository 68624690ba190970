"""post.analysis: Kaplan-Yorke dimension, period detection, panel ranges."""

from __future__ import annotations

import math

import numpy as np
import pytest

from post.analysis import (
    BITS_PER_NAT,
    detect_period,
    detect_periods,
    kaplan_yorke,
    kaplan_yorke_rows,
    panel_ranges,
    period_label,
)


@pytest.mark.parametrize(
    ("spectrum", "expected"),
    [
        ([1.0, -0.5, -2.0], 2.25),
        ([-2.0, -0.5, 1.0], 2.25),  # order of the input does not matter
        ([-0.1, -0.5, -2.0], 0.0),
        ([0.5, 0.2, -0.1], 3.0),  # the sum of all is >= 0: full dimension
        ([0.0, -1.0], 1.0),
        ([1.0, -2.0], 1.5),
        ([0.3, 0.1, -0.2, -0.4], 3.5),
    ],
)
def test_kaplan_yorke(spectrum: list[float], expected: float) -> None:
    assert kaplan_yorke(spectrum) == pytest.approx(expected)


def test_kaplan_yorke_is_unit_free() -> None:
    spectrum = np.array([1.0, -0.5, -2.0])
    assert kaplan_yorke(spectrum * BITS_PER_NAT) == pytest.approx(2.25)


def test_kaplan_yorke_truncated_spectrum_is_undecided() -> None:
    assert math.isnan(kaplan_yorke([0.5, 0.2], full_dimension=6))
    assert kaplan_yorke([0.5, 0.2], full_dimension=2) == 2.0
    assert kaplan_yorke([0.5, -1.0], full_dimension=6) == pytest.approx(1.5)


def test_kaplan_yorke_rows() -> None:
    rows = kaplan_yorke_rows([[1.0, -0.5, -2.0], [-1.0, -2.0, -3.0]])
    np.testing.assert_allclose(rows, [2.25, 0.0])


def test_detect_period() -> None:
    j = np.arange(40)
    assert detect_period(np.full(40, 0.3)) == 1
    assert detect_period(np.cos(np.pi * j)) == 2
    assert detect_period(np.cos(2 * np.pi * j / 5)) == 5
    assert detect_period(np.random.default_rng(0).standard_normal(40)) == 0
    assert detect_period([1.0]) == 0


def test_detect_periods_per_column() -> None:
    j = np.arange(24)[:, None]
    x = np.hstack([np.zeros((24, 1)), np.cos(np.pi * j), np.cos(2 * np.pi * j / 3)])
    np.testing.assert_array_equal(detect_periods(x), [1, 2, 3])


@pytest.mark.parametrize(("period", "label"), [(0, "ap"), (1, "P1"), (12, "P12")])
def test_period_label(period: int, label: str) -> None:
    assert period_label(period) == label


def test_panel_ranges() -> None:
    cycles = np.arange(100, 580)
    assert panel_ranges(cycles, 60) == [(100 + 60 * p, 160 + 60 * p) for p in range(8)]
    assert panel_ranges(cycles, 60, panels=2) == [(100, 160), (160, 220)]
    assert panel_ranges(np.arange(10, 100), 60) == [(10, 70), (70, 130)]
    assert panel_ranges(np.arange(2000), 60) == panel_ranges(np.arange(480), 60)


def test_panel_ranges_reject_bad_input() -> None:
    with pytest.raises(ValueError, match="panel_cycles"):
        panel_ranges(np.arange(5), 0)
    with pytest.raises(ValueError, match="no recorded cycles"):
        panel_ranges(np.array([]), 10)


def test_panel_ranges_from_a_start_cycle() -> None:
    cycles = np.arange(0, 480)
    assert panel_ranges(cycles, 60, start=240) == [(240 + 60 * p, 300 + 60 * p) for p in range(4)]
    assert panel_ranges(cycles, 60, panels=1, start=479) == [(479, 539)]
    with pytest.raises(ValueError, match="start cycle 480 is outside"):
        panel_ranges(cycles, 60, start=480)
