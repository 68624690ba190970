"""The baseline of the benchmark: the chain as a researcher would write it without
impactchain, with scipy's solve_ivp and one terminal event function per bond.

Between impacts solve_ivp integrates all 2n first-order equations; at the earliest bond
closing (event direction -1) it stops, the collision law of docs/model.md section 3 is applied,
and integration restarts from the impact. Nothing here is vectorised beyond numpy: that is
the point of a baseline.

    python bench/scipy_baseline.py --state STATE.json [--min-time 0.5] [--repeats 3]

starts from the state (x, v on the section, drive phase 0) that the Fortran benchmark reached
after its transient, doubles the number of cycles (from 2) until one run takes --min-time,
then prints one JSON object: seconds (best of --repeats runs of that many cycles, each from
the same state), cycles, collisions, peak_kib.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

# The paper's default case (its figures 1c and 4-8, README "Gallery"); a = 1, fixed walls.
AMPLITUDE, OMEGA, DAMPING, RESTITUTION, SPACING = 1.7, 1.5, 0.05, 0.7, 1.0

#: (method, rtol, atol) of the two baselines: tolerances that resolve collision times to
#: about 1e-8 (what a careful researcher would use), and scipy's defaults (a lower bound for
#: the speed-up, with collision times good to a few digits only).
SETTINGS = {
    "tight": ("DOP853", 1e-9, 1e-12),
    "default": ("RK45", 1e-3, 1e-6),
}


def simulate(x0: np.ndarray, v0: np.ndarray, cycles: int, method: str, rtol: float,
             atol: float) -> int:
    """Integrate `cycles` drive cycles from (x0, v0) at drive phase 0; returns the number
    of impacts."""
    n = len(x0)
    period = 2 * math.pi / OMEGA

    def rhs(t, s):
        x, v = s[:n], s[n:]
        return np.concatenate([v, -2 * DAMPING * v - x + AMPLITUDE * np.sin(OMEGA * t)])

    def gap_event(bond):
        if bond == 0:
            def event(t, s):
                return SPACING + s[0]
        elif bond == n:
            def event(t, s):
                return SPACING - s[n - 1]
        else:
            def event(t, s):
                return SPACING + s[bond] - s[bond - 1]
        event.terminal = True
        event.direction = -1
        return event

    events = [gap_event(k) for k in range(n + 1)]
    t, t_end = 0.0, cycles * period
    state = np.concatenate([x0, v0]).astype(float)
    impacts = 0
    while t < t_end:
        sol = solve_ivp(rhs, (t, t_end), state, method=method, rtol=rtol, atol=atol,
                        events=events)
        if sol.status != 1:
            break
        hits = [(te[0], k) for k, te in enumerate(sol.t_events) if len(te)]
        t_hit, site = min(hits)
        state = sol.y_events[site][0].copy()
        v = state[n:]
        if site == 0:
            v[0] = -RESTITUTION * v[0]
        elif site == n:
            v[n - 1] = -RESTITUTION * v[n - 1]
        else:
            l, r = site - 1, site
            vl, vr = v[l], v[r]
            s = (1 + RESTITUTION) / 2
            v[l], v[r] = (1 - s) * vl + s * vr, s * vl + (1 - s) * vr
        impacts += 1
        t = t_hit
        if impacts > 10000 * max(cycles, 1):
            raise RuntimeError("baseline: runaway impact sequence (chatter)")
    return impacts


def peak_kib() -> int:
    """VmHWM of this process in KiB (-1 where /proc is missing)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return -1


def measure(x0, v0, min_time: float, repeats: int, setting: str) -> dict:
    """Calibrate the number of cycles to `min_time`, then the best of `repeats` runs of
    that many cycles, all from the same state."""
    method, rtol, atol = SETTINGS[setting]
    simulate(x0, v0, 1, method, rtol, atol)  # warm-up: imports, first-call overheads
    cycles = 2
    while True:
        start = time.perf_counter()
        simulate(x0, v0, cycles, method, rtol, atol)
        if time.perf_counter() - start >= min_time:
            break
        cycles *= 2
    best, impacts = math.inf, 0
    for _ in range(repeats):
        start = time.perf_counter()
        count = simulate(x0, v0, cycles, method, rtol, atol)
        elapsed = time.perf_counter() - start
        if elapsed < best:
            best, impacts = elapsed, count
    return {"setting": setting, "method": method, "rtol": rtol, "atol": atol,
            "seconds": best, "cycles": cycles, "collisions": impacts, "peak_kib": peak_kib()}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--state", required=True,
                   help="JSON file with x and v on the section (from the Fortran benchmark)")
    p.add_argument("--min-time", type=float, default=0.5,
                   help="seconds one timed run must last at least (default 0.5)")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--setting", choices=sorted(SETTINGS), default="tight")
    args = p.parse_args(argv)
    with open(args.state) as f:
        state = json.load(f)
    result = measure(np.array(state["x"]), np.array(state["v"]), args.min_time, args.repeats,
                     args.setting)
    json.dump(result, sys.stdout)
    print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
