"""Cusp points on fold curves (docs/model.md 12.6): the single impact oscillator (n = 1, the
wall 0.5 away, the other 100, b = 0.05, K = 0.8) has, near w = 0.399, a period-1 orbit with six
wall impacts per drive period whose one-parameter branches in A are S-shaped: two folds with
the same impacts between them, which come together as w grows and are gone beyond the cusp.
Its fold curve in (A, w) is located through two cusps, each confirmed by a multiplier +1 and
the curve's turn in both parameters, and checked against the one-parameter runs: the two
folds' distance in A follows the cusp's 3/2 law about the located w."""
from __future__ import annotations

import numpy as np
import pytest

from impactchain import api

OSCILLATOR = dict(damping=0.05, restitution=0.8, spacing=[0.5, 100.0], boundary="fixed")
#: a state near the six-impact orbit at w = 0.3988, A = 0.97625 (Newton from there)
START = dict(transient=0, x0=[-0.35746746], v0=[0.27758252])


def _cusps(step2: float, stop2: float) -> list[tuple[float, float, np.ndarray]]:
    tree = api.curve(1, 0.97625, 0.3988, parameter="amplitude", stop=0.977, step=2e-5,
                     follow="fold", parameter2="omega", stop2=stop2, step2=step2,
                     max_points=120, **START, **OSCILLATOR)
    c = tree["curve"]
    mu = c["multipliers_re"].values + 1j * c["multipliers_im"].values
    return [(float(c["values"][i]), float(c["values2"][i]), mu[i])
            for k, i in zip(c["codim2_kind"].values, c["codim2_index"].values)
            if str(k) == "cusp"]


def _folds(omega: float, amplitude: float) -> list[float]:
    """The folds of the six-impact branch from `amplitude` (above its grazing and period
    doubling) up 1e-3."""
    run = api.continuation(1, amplitude, omega, parameter="amplitude", stop=amplitude + 1e-3,
                           step=1e-5, max_points=400, **START, **OSCILLATOR)
    kinds = [str(k) for k in run["special_kind"].values]
    assert set(kinds) <= {"fold"} and (run["impacts_per_period"].values == 6).all()
    return [float(v) for v in run["special_value"].values]


@pytest.fixture(scope="module")
def upper() -> tuple[float, float, np.ndarray]:
    (cusp,) = _cusps(0.0005, 0.4)
    return cusp


def test_two_cusps_located_and_confirmed(upper: tuple[float, float, np.ndarray]) -> None:
    (lower,) = _cusps(-0.0005, 0.397)
    for a, w, mu in (upper, lower):
        print(f"cusp at A = {a:.10f}, w = {w:.10f}, |multiplier - 1| = {np.abs(mu - 1).min():.1e}")
        assert np.abs(mu - 1).min() < 1e-8
    assert upper[0] == pytest.approx(0.97541141, abs=1e-7)
    assert upper[1] == pytest.approx(0.39901257, abs=1e-7)
    assert lower[0] == pytest.approx(0.97877780, abs=1e-7)
    assert lower[1] == pytest.approx(0.39825705, abs=1e-7)


def test_one_parameter_folds_follow_the_three_halves_law(
        upper: tuple[float, float, np.ndarray]) -> None:
    """Below the located w_c two folds, their distance d(w) = C (w_c - w)**1.5 (the cusp's
    normal form): the ratio of d at two w is the law's with w_c from the curve, to 5 % (the
    next term is O(w_c - w) relative); beyond w_c, no fold."""
    w_c = upper[1]
    d = {}
    for w, amplitude in ((0.3989, 0.9757), (0.3990, 0.9753)):
        folds = _folds(w, amplitude)
        assert len(folds) == 2
        d[w] = abs(folds[0] - folds[1])
    law = ((w_c - 0.3989) / (w_c - 0.3990)) ** 1.5
    print(f"d = {d[0.3989]:.3e}, {d[0.3990]:.3e}: ratio {d[0.3989] / d[0.3990]:.3f}, law {law:.3f}")
    assert d[0.3989] / d[0.3990] == pytest.approx(law, rel=0.05)
    assert _folds(w_c + 1e-5, 0.9752) == []
