"""Small analysis helpers: period labels and panel ranges.

All functions are pure and work on plain numpy arrays. Periods, Lyapunov exponents and
Kaplan-Yorke dimensions are not computed anywhere in ``impactchain``: each has one definition, the
simulator's (docs/model.md sections 6.3 and 7.5), and the figures read them from its files
(``/strobe/period``, ``/lyapunov``, ``/sweep/period``, ``/sweep/exponents``,
``/sweep/ky_dimension``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "period_label",
    "panel_ranges",
]


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
