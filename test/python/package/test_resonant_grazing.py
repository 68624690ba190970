"""Resonant grazing (docs/model.md 12.6): the fold and period-doubling curves of the single
impact oscillator's one-impact period-1 orbits leave the grazing curve quadratically tangent at
the resonance w* = 2 sqrt(1 - b**2) (Simpson and Ghosh 2026), checked against a closed form of
the orbits and their multipliers.

The oscillator: n = 1, x'' + 2 b x' + x = A sin(w t), the left wall sigma = 0.5 away, the right
one 100 (never reached). A one-impact orbit of period tau = p 2 pi / w, impact speed s, has the
free part y = x - xp just after its impact fixed by y+ = M(tau) y+ + (0, (1 + r) s), so
y+ = (1 + r) s u with u = (I - M(tau))^-1 (0, 1) (M of model.md 2.2); the impact at x = -sigma
with incoming speed s then asks of the forced response xp (amplitude R = A / sqrt(D2))

    xp = -sigma - alpha s,   xp' = beta s,   alpha = (1 + r) u1,   beta = (1 + r)(1 - u2) - 1,

so (sigma + alpha s)**2 + (beta s / w)**2 = R**2 (Budd and Dux's relation of test_budd_dux,
with damping and any p). Its smallest R over s is the fold,

    A_f(w) = sqrt(D2) sigma |beta| / w / sqrt(alpha**2 + (beta / w)**2),

at s_f = -sigma alpha / (alpha**2 + (beta / w)**2) > 0 where alpha < 0, while the grazing is
A_g = sigma sqrt(D2). The orbit's multipliers are those of S M(tau), S = [[-r, 0], [k, -r]]
the saltation matrix of the impact (model.md 4.3), k = -(1 + r)(sigma + F) / s, F the drive
at the impact, (1 - w**2) xp + 2 b xp'; so det(I + S M) = 0, a multiplier -1, where

    (1 + r)(w**2 sigma / s + 2 b beta - (1 - w**2) alpha) = (1 - r tr M + r**2 det M) / M12,

one s, and R of the relation above: A_pd(w). u1 = M12 / det(I - M) vanishes with
sin(sqrt(1 - b**2) tau) (the square-root term of the grazing map vanishes): for p = 1 first at
w* = 2 sqrt(1 - b**2), where M(tau) = -e I, e = exp(-b tau); alpha < 0 (a fold) below it,
M12 > 0 (a period doubling) above. Expanding, A - A_g = c (w - w*)**2 + O((w - w*)**3) with
M12' = e tau / w and beta = (1 + r) e / (1 + e) - 1 at w*,

    fold:     c = -sqrt(D2) sigma (1 + r)**2 w**2 M12'**2 / (2 beta**2 (1 + e)**4),
    doubling: c = sqrt(D2) sigma (1 + r)**2 w**2 M12'**2 / (1 + r e)**2
                  * (1 / (1 + e)**2 + beta**2 / (2 (1 + r e)**2))."""
from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from impactchain import api

B, R, SIGMA, P = 0.05, 0.8, 0.5, 1
GAM = math.sqrt(1 - B * B)
W_STAR = 2 * P * GAM  # the largest root of sin(GAM * P * 2 pi / w) = 0 (w = 2 p GAM / m, m = 1)
OSCILLATOR = dict(damping=B, restitution=R, spacing=[SIGMA, 100.0], period=P)


def _d2(w: float) -> float:
    return (1 - w * w) ** 2 + (2 * B * w) ** 2


def grazing(w: float) -> float:
    """The grazing curve of the forced response (model.md 2.1)."""
    return SIGMA * math.sqrt(_d2(w))


def _propagator(w: float) -> tuple[np.ndarray, float, float]:
    """M(tau) of one orbit period, alpha, beta."""
    tau = P * 2 * math.pi / w
    cs, sn = math.cos(GAM * tau), math.sin(GAM * tau) / GAM
    m = math.exp(-B * tau) * np.array([[cs + B * sn, sn], [-sn, cs - B * sn]])
    u = np.linalg.solve(np.eye(2) - m, [0.0, 1.0])
    return m, (1 + R) * u[0], (1 + R) * (1 - u[1]) - 1


def fold(w: float) -> float:
    """The fold of the one-impact orbits at frequency w, from the closed form above."""
    _, alpha, beta = _propagator(w)
    return math.sqrt(_d2(w)) * SIGMA * abs(beta) / w / math.hypot(alpha, beta / w)


def doubling(w: float) -> float:
    """The period doubling of the one-impact orbits at frequency w, from the closed form."""
    m, alpha, beta = _propagator(w)
    growth = (1 - R * np.trace(m) + R**2 * np.linalg.det(m)) / ((1 + R) * m[0, 1])
    speed = w * w * SIGMA / (growth - 2 * B * beta + (1 - w * w) * alpha)
    return math.sqrt(_d2(w)) * math.hypot(SIGMA + alpha * speed, beta * speed / w)


def leading_coefficients() -> dict[str, float]:
    """c of A - A_g = c (w - w*)**2 for the fold and the period doubling."""
    tau = P * 2 * math.pi / W_STAR
    e = math.exp(-B * tau)
    beta = (1 + R) * e / (1 + e) - 1
    common = math.sqrt(_d2(W_STAR)) * SIGMA * (1 + R) ** 2 * (e * tau) ** 2
    return {"fold": -common / (2 * beta**2 * (1 + e) ** 4),
            "period-doubling": common / (1 + R * e) ** 2
            * (1 / (1 + e) ** 2 + beta**2 / (2 * (1 + R * e) ** 2))}


def _curve(follow: str, offset: float, last: float, step2: float) -> tuple[np.ndarray, np.ndarray]:
    """The special point `follow` located at w* + offset (from the impacting orbit at 1.03 A_g,
    down in A), followed in (A, w) towards w* + last."""
    pytest.importorskip("xarray")
    w0 = W_STAR + offset
    tree = api.curve(1, 1.03 * grazing(w0), w0, parameter="amplitude",
                     stop=0.8 * grazing(w0), step=-0.002 * grazing(w0), follow=follow,
                     parameter2="omega", stop2=W_STAR + last, step2=step2, max_points=60,
                     transient=3000, **OSCILLATOR)
    curve = tree["curve"]
    print(f"{follow}: {curve.attrs['end_reason']}")
    return curve["values"].values, curve["values2"].values


@pytest.fixture(scope="module")
def fold_curve() -> tuple[np.ndarray, np.ndarray]:
    return _curve("fold", -0.04, -0.002, 0.1)


@pytest.fixture(scope="module")
def doubling_curve() -> tuple[np.ndarray, np.ndarray]:
    """Slow impacts (speed 0.005 at w* + 0.0045) need short steps: the curve stops there."""
    return _curve("period-doubling", 0.04, 0.0045, -0.02)


def _on_closed_form(points: tuple[np.ndarray, np.ndarray], closed_form: Any) -> None:
    amplitude, omega = points
    assert len(amplitude) >= 6 and abs(omega[-1] - W_STAR) < 0.006
    error = max(abs(a - closed_form(w)) / a for a, w in zip(amplitude, omega, strict=True))
    print(f"{len(amplitude)} points, largest relative distance from the closed form {error:.1e}")
    assert error < 1e-10


def _tangent(points: tuple[np.ndarray, np.ndarray], kind: str, sign: float) -> None:
    """q = (A - A_g) / (w - w*)**2 along the curve tends to c. At the offsets nearest
    delta = 0.01 and delta / 2, 4 q(delta) / q(delta / 2) (the ratio of the differences at
    delta and delta / 2, scaled to an exact halving) is 4 but for the next-order term, which
    the closed forms put at -0.06 (fold) and +0.03 (doubling) there; 0.15 admits only a power
    2 +- 0.05. The differences are not zero and have the sign `sign`, and the parabola through
    q at the three points nearest w* reaches c at w* to 1e-3 (its remainder O(delta**3))."""
    amplitude, omega = points
    offset = abs(omega - W_STAR)
    difference = np.array([a - grazing(w) for a, w in zip(amplitude, omega, strict=True)])
    assert np.all(sign * difference > 1e-6)
    q = difference / offset**2
    far, near = (int(np.argmin(abs(offset - d))) for d in (0.01, 0.005))
    ratio = 4 * q[far] / q[near]
    nearest = np.argsort(offset)[:3]
    limit = np.polyval(np.polyfit(offset[nearest], q[nearest], 2), 0.0)
    c = leading_coefficients()[kind]
    print(f"offsets {offset[far]:.5f}, {offset[near]:.5f}: ratio {ratio:.4f}; parabola through "
          f"{np.sort(offset[nearest])} -> {limit:.5f}, leading-order c {c:.5f}")
    assert abs(ratio - 4) < 0.15
    assert abs(limit / c - 1) < 1e-3


def test_fold_curve_is_the_closed_form(fold_curve: tuple[np.ndarray, np.ndarray]) -> None:
    _on_closed_form(fold_curve, fold)


def test_fold_curve_tangent_below_grazing(fold_curve: tuple[np.ndarray, np.ndarray]) -> None:
    _tangent(fold_curve, "fold", -1.0)


def test_doubling_curve_is_the_closed_form(doubling_curve: tuple[np.ndarray, np.ndarray]
                                           ) -> None:
    _on_closed_form(doubling_curve, doubling)


def test_doubling_curve_tangent_above_grazing(doubling_curve: tuple[np.ndarray, np.ndarray]
                                              ) -> None:
    _tangent(doubling_curve, "period-doubling", 1.0)
