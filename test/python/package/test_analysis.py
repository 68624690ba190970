"""impactchain.analysis: period labels and panel ranges."""

from __future__ import annotations

import numpy as np
import pytest

from impactchain.analysis import panel_ranges, period_label


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
