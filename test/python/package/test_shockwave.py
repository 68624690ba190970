"""impactchain.shockwave: the construction on hand-made event streams."""

from __future__ import annotations

import numpy as np
import pytest

from impactchain.shockwave import Wave, build_shock_waves

T = 2.0  # drive period of the hand-made streams


def _as_pairs(wave: Wave) -> list[tuple[float, int]]:
    return list(zip(wave.times.tolist(), wave.sites.tolist()))


def _build(events: list[tuple[float, int]], n: int, **kwargs: float) -> list[Wave]:
    time = [t for t, _ in events]
    site = [k for _, k in events]
    return build_shock_waves(time, site, n, T, **kwargs)


def test_clean_left_to_right_cascade() -> None:
    events = [(0.0, 0), (0.1, 1), (0.2, 2), (0.3, 3)]
    waves = _build(events, n=4)
    assert len(waves) == 1
    assert waves[0].side == "left"
    assert _as_pairs(waves[0]) == events


def test_cascade_reaching_the_right_wall_starts_a_right_wave() -> None:
    events = [(0.0, 0), (0.1, 1), (0.2, 2)]
    waves = _build(events, n=2)
    assert [w.side for w in waves] == ["left", "right"]
    assert _as_pairs(waves[0]) == events
    assert _as_pairs(waves[1]) == [(0.2, 2)]


def test_overlapping_waves_extend_the_oldest_first() -> None:
    events = [(0.0, 0), (0.1, 1), (0.2, 0), (0.3, 2), (0.4, 1), (0.5, 2), (0.6, 3)]
    first, second = _build(events, n=5)
    assert _as_pairs(first) == [(0.0, 0), (0.1, 1), (0.3, 2), (0.6, 3)]
    assert _as_pairs(second) == [(0.2, 0), (0.4, 1), (0.5, 2)]


def test_oldest_wins_when_two_waves_wait_at_the_same_site() -> None:
    events = [(0.0, 0), (0.1, 0), (0.2, 1), (0.3, 1)]
    first, second = _build(events, n=3)
    assert _as_pairs(first) == [(0.0, 0), (0.2, 1)]
    assert _as_pairs(second) == [(0.1, 0), (0.3, 1)]


def test_wave_dies_when_the_wait_is_exceeded() -> None:
    events = [(0.0, 0), (0.5, 1), (0.5 + T + 0.01, 2), (10.0, 3)]
    waves = _build(events, n=4)
    assert len(waves) == 1
    assert _as_pairs(waves[0]) == [(0.0, 0), (0.5, 1)]


def test_wait_exactly_max_wait_keeps_the_wave_alive() -> None:
    events = [(0.0, 0), (T, 1)]
    assert _as_pairs(_build(events, n=3)[0]) == events
    assert _as_pairs(_build(events, n=3, max_wait=0.5)[0]) == [(0.0, 0)]


def test_dead_wave_is_never_revived() -> None:
    events = [(0.0, 0), (5 * T, 0), (5 * T + 0.1, 1)]
    old, new = _build(events, n=3)
    assert _as_pairs(old) == [(0.0, 0)]
    assert _as_pairs(new) == [(5 * T, 0), (5 * T + 0.1, 1)]


def test_right_wall_waves() -> None:
    events = [(1.0, 4), (1.1, 3), (1.2, 2), (1.3, 4), (1.4, 3), (1.5, 1)]
    first, second = _build(events, n=4)
    assert first.side == second.side == "right"
    assert _as_pairs(first) == [(1.0, 4), (1.1, 3), (1.2, 2), (1.5, 1)]
    assert _as_pairs(second) == [(1.3, 4), (1.4, 3)]


def test_one_collision_extends_a_left_and_a_right_wave() -> None:
    events = [(0.0, 0), (0.05, 4), (0.1, 1), (0.15, 3), (0.2, 2)]
    left, right = _build(events, n=4)
    assert (left.side, right.side) == ("left", "right")
    assert _as_pairs(left) == [(0.0, 0), (0.1, 1), (0.2, 2)]
    assert _as_pairs(right) == [(0.05, 4), (0.15, 3), (0.2, 2)]


def test_wall_hit_extends_an_arriving_wave_and_starts_a_new_one() -> None:
    events = [(0.0, 2), (0.1, 1), (0.2, 0)]
    right, left = _build(events, n=2)
    assert _as_pairs(right) == [(0.0, 2), (0.1, 1), (0.2, 0)]
    assert left.side == "left" and _as_pairs(left) == [(0.2, 0)]


def test_collisions_outside_waves_are_dropped() -> None:
    assert _build([(0.0, 2), (0.1, 1), (0.2, 3)], n=5) == []


def test_events_are_processed_in_time_order() -> None:
    events = [(0.2, 2), (0.0, 0), (0.1, 1)]
    (wave,) = _build(events, n=4)
    assert _as_pairs(wave) == sorted(events)


def test_releases_are_ignored_when_kind_is_given() -> None:
    waves = build_shock_waves([0.0, 0.1, 0.2], [0, 1, 2], 4, T, kind=[0, 2, 1])
    assert [_as_pairs(w) for w in waves] == [[(0.0, 0)]]


def test_touches_are_ignored_when_kind_is_given() -> None:
    # a touch (kind 3) has no impulse: it neither extends nor starts a wave
    waves = build_shock_waves([0.0, 0.1, 0.2], [0, 1, 2], 4, T, kind=[0, 3, 0])
    assert [_as_pairs(w) for w in waves] == [[(0.0, 0)]]


def test_single_oscillator_between_walls() -> None:
    waves = _build([(0.0, 0), (0.5, 1), (1.0, 0)], n=1)
    assert [(w.side, _as_pairs(w)) for w in waves] == [
        ("left", [(0.0, 0), (0.5, 1)]),
        ("right", [(0.5, 1), (1.0, 0)]),
        ("left", [(1.0, 0)]),
    ]


def test_empty_stream() -> None:
    assert build_shock_waves(np.array([]), np.array([], dtype=int), 3, T) == []


def test_wave_arrays_are_read_only() -> None:
    (wave,) = _build([(0.0, 0), (0.1, 1)], n=3)
    assert len(wave) == 2 and wave.start == 0.0
    with pytest.raises(ValueError):
        wave.times[0] = 1.0


@pytest.mark.parametrize(
    ("time", "site", "n", "message"),
    [
        ([0.0], [5], 4, "sites must lie in 0..4"),
        ([0.0, 1.0], [0], 4, "differ in length"),
        ([0.0], [0], 0, "n = 0"),
    ],
)
def test_invalid_input(time: list[float], site: list[int], n: int, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        build_shock_waves(time, site, n, T)
