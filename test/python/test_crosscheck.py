"""Collision times against an independent integration with scipy's solve_ivp (event
functions, rtol 1e-12), from the same explicit initial state: n = 4, 5 drive cycles."""
from __future__ import annotations

import h5py
import numpy as np
from scipy.integrate import solve_ivp

from simulator import impactchain_exe, run_namelist  # noqa: F401 (fixture)

N, A, W, B, K, SPACING = 4, 1.7, 1.5, 0.05, 0.7, 1.0
X0 = [0.3, -0.2, 0.25, -0.1]
V0 = [1.2, -0.8, 0.5, -1.1]


def reference_events(cycles: int) -> list[tuple[float, int]]:
    """Event-driven integration of the chain with solve_ivp; returns (time, site)."""
    period = 2 * np.pi / W

    def rhs(t, s):
        x, v = s[:N], s[N:]
        return np.concatenate([v, -2 * B * v - x + A * np.sin(W * t)])

    def gap_event(bond):
        def event(t, s):
            x = s[:N]
            if bond == 0:
                return SPACING + x[0]
            if bond == N:
                return SPACING - x[N - 1]
            return SPACING + x[bond] - x[bond - 1]
        event.terminal = True
        event.direction = -1
        return event

    events = [gap_event(k) for k in range(N + 1)]
    t, state, t_end = 0.0, np.array(X0 + V0, float), cycles * period
    found: list[tuple[float, int]] = []
    while t < t_end:
        sol = solve_ivp(rhs, (t, t_end), state, method="DOP853", rtol=1e-12, atol=1e-13,
                        events=events)
        if sol.status != 1:
            break
        hits = [(te[0], k) for k, te in enumerate(sol.t_events) if len(te)]
        t_hit, site = min(hits)
        state = sol.y_events[site][0].copy()
        x, v = state[:N], state[N:]
        if site == 0:
            v[0] = -K * v[0]
        elif site == N:
            v[N - 1] = -K * v[N - 1]
        else:
            l, r = site - 1, site
            vl, vr = v[l], v[r]
            s = (1 + K) / 2
            v[l], v[r] = (1 - s) * vl + s * vr, s * vl + (1 - s) * vr
        found.append((t_hit, site))
        t = t_hit
    return found


def test_collision_times_match_solve_ivp(impactchain_exe, tmp_path):
    text = f"""
&chain n = {N}, amplitude = {A}, omega = {W}, damping = {B}, restitution = {K} /
&initial kind = 'explicit', x0 = {', '.join(map(str, X0))}, v0 = {', '.join(map(str, V0))} /
&run transient = 0, cycles = 5 /
&output file = 'run.h5' /
"""
    run_namelist(impactchain_exe, text, tmp_path)
    with h5py.File(tmp_path / "run.h5") as f:
        times = f["events/time"][:]
        sites = f["events/site"][:]
    reference = reference_events(5)
    assert len(reference) > 20
    assert len(times) == len(reference)
    ref_t = np.array([t for t, _ in reference])
    ref_s = np.array([s for _, s in reference])
    np.testing.assert_array_equal(sites, ref_s)
    np.testing.assert_allclose(times, ref_t, rtol=0, atol=1e-8)
