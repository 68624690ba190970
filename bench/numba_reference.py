"""An independent implementation of the impacting chain (docs/model.md) with numba: the
reference that issue #34's table measures impactchain against.

It shares no code with impactchain and follows only the model's equations:

- the closed-form flow of each driven damped oscillator between impacts (section 2): the
  free part y = x - xp is carried by M(tau), every oscillator's free part and tangent rows
  stored at one epoch per drive cycle, so an impact touches only its two oscillators;
- event-driven impacts (section 3): every bond keeps the time of its next zero; a pair gap is
  an unforced damped oscillation around its spacing, whose first closing is bracketed between
  an extremum and the next minimum (both in closed form) and refined by safeguarded Newton;
  a wall gap carries the drive and is advanced by steps over which a bound on its second
  derivative proves it positive; restitution K between neighbours and at the walls;
- the tangent frame carried through the flow by M(tau) and across impacts by the saltation
  matrices of sections 4.3 and 4.4;
- numpy's QR of the frame every drive cycle (`np.linalg.qr` compiled by numba: LAPACK's
  dgeqrf + dorgqr), the exponents the means of log|diag R| (section 7.2), in bits per cycle.

Rests, touches and the cluster rule (section 5) are not implemented: on the paper's default
chain no approach is slow enough to need them (`check` says how slow the slowest was). A wall
approach slower than STICK_SPEED stops the run with an error rather than chatter for ever.

    .venv/bin/python bench/numba_reference.py check [--cycles N]   # against impactchain
"""
from __future__ import annotations

import argparse
import math
import sys

import numpy as np
from numba import njit

#: the refinement's tolerance on an impact time (time units)
TIME_TOL = 1e-13
#: a wall search stops when the gap is below this (lengths; the spacing is of order 1)
GAP_TOL = 1e-12
#: wall approaches slower than this would need the rest rule of model.md 5.3
STICK_SPEED = 1e-7
#: a wall search gives up after this many certified steps and looks again from there
MAX_WALL_STEPS = 64


class Params:
    """The chain's parameters and the derived constants of the flow (model.md 2.1, 2.2)."""

    def __init__(self, n=16, amplitude=1.7, omega=1.5, damping=0.05, restitution=0.7,
                 spacing=1.0):
        b, w, A = damping, omega, amplitude
        d2 = (1 - w * w) ** 2 + (2 * b * w) ** 2
        self.n, self.A, self.w, self.b, self.K = n, A, w, b, restitution
        self.a = np.full(n + 1, float(spacing))
        self.gam = math.sqrt(1 - b * b)
        self.P, self.Q = A * (1 - w * w) / d2, -2 * b * w * A / d2
        self.T = 2 * math.pi / w
        self.amp = A / math.sqrt(d2)

    def packed(self) -> np.ndarray:
        """What the compiled functions take as p: A, w, b, K, gam, P, Q, T, amp (indices 0-8)."""
        return np.array([self.A, self.w, self.b, self.K, self.gam, self.P, self.Q, self.T,
                         self.amp])


@njit(cache=True)
def _forced(p, s):
    """xp, vp, ap (the forced response and its derivatives) at in-cycle time s."""
    w, P, Q = p[1], p[5], p[6]
    sn, cs = math.sin(w * s), math.cos(w * s)
    xp = P * sn + Q * cs
    return xp, w * (P * cs - Q * sn), -w * w * xp


@njit(cache=True)
def _prop(p, tau):
    """M(tau) of model.md 2.2 as (m11, m12, m21, m22)."""
    b, gam = p[2], p[4]
    e = math.exp(-b * tau)
    cs, sn = math.cos(gam * tau), math.sin(gam * tau) / gam
    return e * (cs + b * sn), e * sn, -e * sn, e * (cs - b * sn)


@njit(cache=True)
def _free_now(p, ye, ve, i, tau):
    """Free part of oscillator i at time epoch + tau."""
    m11, m12, m21, m22 = _prop(p, tau)
    return m11 * ye[i] + m12 * ve[i], m21 * ye[i] + m22 * ve[i]


@njit(cache=True)
def _pair_gap(b, gam, a, c, s, tau):
    """Gap a + e^(-b tau) (c cos + s sin)(gam tau) and its rate."""
    e, cs, sn = math.exp(-b * tau), math.cos(gam * tau), math.sin(gam * tau)
    return (a + e * (c * cs + s * sn),
            e * ((gam * s - b * c) * cs - (gam * c + b * s) * sn))


@njit(cache=True)
def _pair_search(p, a, z, zd):
    """First downward zero after now of a + z(tau), z an unforced free oscillation with
    z(0) = z, z'(0) = zd; inf if it never closes (the first minimum is above zero)."""
    b, gam = p[2], p[4]
    c, s = z, (zd + b * z) / gam
    r, phi = math.hypot(c, s), math.atan2(s, c)
    # minima of z at gam tau - phi = pi - asin(b) (mod 2 pi), value -r gam e^(-b tau)
    theta = phi + math.pi - math.asin(b)
    theta -= 2 * math.pi * math.floor(theta / (2 * math.pi))
    t_min = theta / gam
    if a - r * gam * math.exp(-b * t_min) > 0:
        return np.inf
    lo, hi = max(0.0, t_min - math.pi / gam), t_min
    t = lo
    for _ in range(100):
        g, gd = _pair_gap(b, gam, a, c, s, t)
        if g > 0:
            lo = t
        else:
            hi = t
        step = -g / gd if gd < 0 else np.inf
        t_new = t + step
        if not (lo < t_new < hi):
            t_new = 0.5 * (lo + hi)
        if abs(t_new - t) < TIME_TOL or hi - lo < TIME_TOL:
            return t_new
        t = t_new
    return t


@njit(cache=True)
def _wall_search(p, a, side, y, yd, s0, horizon):
    """Advance the wall gap of the oscillator with free part (y, yd) at time s0 by steps that
    keep it provably positive; return (tau, hit): the impact time or where to look again."""
    b, gam, amp, w = p[2], p[4], p[8], p[1]
    r = math.hypot(y, (yd + b * y) / gam)
    bound = r + w * w * amp
    tau = 0.0
    for _ in range(MAX_WALL_STEPS):
        m11, m12, m21, m22 = _prop(p, tau)
        xp, vp, _ = _forced(p, s0 + tau)
        g = a + side * (m11 * y + m12 * yd + xp)
        gd = side * (m21 * y + m22 * yd + vp)
        if g < GAP_TOL and gd < 0:
            return tau, True
        h = (gd + math.sqrt(gd * gd + 2 * bound * max(g, 0.0))) / bound
        if g < GAP_TOL:
            h = max(h, 1e-9)
        tau += h
        if tau > horizon:
            return horizon, False
    return tau, False


@njit(cache=True)
def _schedule(p, a, ye, ve, s, epoch, bond, n):
    """Next event time (in-cycle, may exceed T) of one bond and whether it is an impact."""
    tau = s - epoch
    if bond == 0 or bond == n:
        i = 0 if bond == 0 else n - 1
        y, yd = _free_now(p, ye, ve, i, tau)
        side = 1.0 if bond == 0 else -1.0
        dt, hit = _wall_search(p, a[bond], side, y, yd, s, p[7])
        return s + dt, hit
    y1, yd1 = _free_now(p, ye, ve, bond - 1, tau)
    y2, yd2 = _free_now(p, ye, ve, bond, tau)
    return s + _pair_search(p, a[bond], y2 - y1, yd2 - yd1), True


@njit(cache=True)
def _to_epoch(p, tau, y, yd):
    """M(tau)^-1 (y, yd): a value at epoch + tau referred back to the epoch."""
    m11, m12, m21, m22 = _prop(p, tau)
    det = m11 * m22 - m12 * m21
    return (m22 * y - m12 * yd) / det, (-m21 * y + m11 * yd) / det


@njit(cache=True)
def _salt_rows(p, tau, frame, i, s11, s12, s21, s22):
    """Apply the 2x2 saltation matrix S to oscillator i's tangent rows, stored at the epoch:
    M(tau)^-1 S M(tau), column by column."""
    m11, m12, m21, m22 = _prop(p, tau)
    det = m11 * m22 - m12 * m21
    for c in range(frame.shape[1]):
        x0, v0 = frame[2 * i, c], frame[2 * i + 1, c]
        dx, dv = m11 * x0 + m12 * v0, m21 * x0 + m22 * v0
        dx, dv = s11 * dx + s12 * dv, s21 * dx + s22 * dv
        frame[2 * i, c] = (m22 * dx - m12 * dv) / det
        frame[2 * i + 1, c] = (-m21 * dx + m11 * dv) / det


@njit(cache=True)
def _salt_pair(p, tau, frame, i, q, qa):
    """The saltation matrix of a pair impact (model.md 4.4) on oscillators i, i + 1."""
    m11, m12, m21, m22 = _prop(p, tau)
    det = m11 * m22 - m12 * m21
    j = i + 1
    for c in range(frame.shape[1]):
        x1, v1 = frame[2 * i, c], frame[2 * i + 1, c]
        x2, v2 = frame[2 * j, c], frame[2 * j + 1, c]
        dx1, dv1 = m11 * x1 + m12 * v1, m21 * x1 + m22 * v1
        dx2, dv2 = m11 * x2 + m12 * v2, m21 * x2 + m22 * v2
        ex1 = (1 - q) * dx1 + q * dx2
        ev1 = -qa * dx1 + (1 - q) * dv1 + qa * dx2 + q * dv2
        ex2 = q * dx1 + (1 - q) * dx2
        ev2 = qa * dx1 + q * dv1 - qa * dx2 + (1 - q) * dv2
        frame[2 * i, c] = (m22 * ex1 - m12 * ev1) / det
        frame[2 * i + 1, c] = (-m21 * ex1 + m11 * ev1) / det
        frame[2 * j, c] = (m22 * ex2 - m12 * ev2) / det
        frame[2 * j + 1, c] = (-m21 * ex2 + m11 * ev2) / det


@njit(cache=True)
def _wall_impact(p, a, ye, ve, frame, s, epoch, bond, n):
    """Restitution at a wall (model.md 3.2) and its saltation matrix (4.3); the speed."""
    tau, K, b, A, w = s - epoch, p[3], p[2], p[0], p[1]
    i = 0 if bond == 0 else n - 1
    y, yd = _free_now(p, ye, ve, i, tau)
    xp, vp, _ = _forced(p, s)
    x, v = y + xp, yd + vp
    u = -v if bond == 0 else v
    if u < STICK_SPEED:
        raise RuntimeError("a wall approach slower than STICK_SPEED: rests not implemented")
    vplus = -K * v
    ye[i], ve[i] = _to_epoch(p, tau, y, vplus - vp)
    if frame.shape[1] > 0:
        force = -x + A * math.sin(w * s)
        acc_m, acc_p = force - 2 * b * v, force - 2 * b * vplus
        _salt_rows(p, tau, frame, i, -K, 0.0, (K * acc_m + acc_p) / v, -K)
    return u


@njit(cache=True)
def _pair_impact(p, a, ye, ve, frame, s, epoch, bond):
    """Restitution between oscillators bond, bond + 1 (model.md 3.1; 0-based bond - 1 and
    bond) and the saltation matrix of 4.4; the approach speed."""
    tau, K = s - epoch, p[3]
    i, j = bond - 1, bond
    y1, yd1 = _free_now(p, ye, ve, i, tau)
    y2, yd2 = _free_now(p, ye, ve, j, tau)
    u = yd1 - yd2
    q = 0.5 * (1 + K)
    ye[i], ve[i] = _to_epoch(p, tau, y1, yd1 - q * u)
    ye[j], ve[j] = _to_epoch(p, tau, y2, yd2 + q * u)
    if frame.shape[1] > 0:
        _salt_pair(p, tau, frame, i, q, q * a[bond] / u)
    return u


@njit(cache=True)
def _end_cycle(p, ye, ve, frame, epoch, n):
    """Carry every free part and tangent row from the epoch to the cycle's end (t = T, the
    next cycle's 0: xp has period T)."""
    m11, m12, m21, m22 = _prop(p, p[7] - epoch)
    for i in range(n):
        ye[i], ve[i] = m11 * ye[i] + m12 * ve[i], m21 * ye[i] + m22 * ve[i]
    if frame.shape[1] > 0:
        for i in range(n):
            for c in range(frame.shape[1]):
                x0, v0 = frame[2 * i, c], frame[2 * i + 1, c]
                frame[2 * i, c] = m11 * x0 + m12 * v0
                frame[2 * i + 1, c] = m21 * x0 + m22 * v0


@njit(cache=True)
def run_cycles(p, a, x, v, frame, cycles, logs, counts):
    """Run `cycles` drive cycles from in-cycle time 0 with state (x, v) (updated in place),
    the tangent frame (2n x k, updated) QR-factorised at the end of every cycle, log|R(j,j)|
    added to logs[j]; counts[c] is the number of impacts in cycle c. Returns the slowest
    approach speed met."""
    n, T = x.shape[0], p[7]
    xp0, vp0, _ = _forced(p, 0.0)
    ye, ve = x - xp0, v - vp0
    times = np.empty(n + 1)
    hits = np.zeros(n + 1, dtype=np.bool_)
    epoch, s, slowest = 0.0, 0.0, np.inf
    for bond in range(n + 1):
        times[bond], hits[bond] = _schedule(p, a, ye, ve, s, epoch, bond, n)
    for c in range(cycles):
        impacts = 0
        while True:
            bond = np.argmin(times)
            s = times[bond]
            if s >= T:
                break
            if not hits[bond]:
                times[bond], hits[bond] = _schedule(p, a, ye, ve, s, epoch, bond, n)
                continue
            if bond == 0 or bond == n:
                u = _wall_impact(p, a, ye, ve, frame, s, epoch, bond, n)
            else:
                u = _pair_impact(p, a, ye, ve, frame, s, epoch, bond)
            slowest = min(slowest, u)
            impacts += 1
            for nb in range(max(0, bond - 1), min(n, bond + 1) + 1):
                times[nb], hits[nb] = _schedule(p, a, ye, ve, s, epoch, nb, n)
        _end_cycle(p, ye, ve, frame, epoch, n)
        epoch, s = 0.0, 0.0
        times -= T
        counts[c] = impacts
        if frame.shape[1] > 0:
            q, r = np.linalg.qr(frame)
            for j in range(frame.shape[1]):
                logs[j] += math.log(abs(r[j, j]))
            frame[:, :] = q
    xp0, vp0, _ = _forced(p, 0.0)
    x[:] = ye + xp0
    v[:] = ve + vp0
    return slowest


class Chain:
    """A chain on the reference: its state at drive phase 0 and its tangent frame."""

    def __init__(self, params: Params, seed=1, x_amp=0.3, v_amp=0.3, vectors=0):
        rng = np.random.default_rng(seed)
        n = params.n
        self.p, self.packed = params, params.packed()
        self.x = rng.uniform(-x_amp, x_amp, n)
        self.v = rng.uniform(-v_amp, v_amp, n)
        self.set_vectors(vectors)
        self.slowest = np.inf

    def set_vectors(self, k: int) -> None:
        """A fresh orthonormal frame of k vectors (generic, seeded), and no sums yet."""
        m = 2 * self.p.n
        if k:
            g = np.random.default_rng(12345).standard_normal((m, k))
            self.frame = np.ascontiguousarray(np.linalg.qr(g)[0])
        else:
            self.frame = np.zeros((m, 0))
        self.logs = np.zeros(k)
        self.cycles = 0
        self.counts: list[np.ndarray] = []

    def run(self, cycles: int) -> None:
        counts = np.zeros(cycles, dtype=np.int64)
        slow = run_cycles(self.packed, self.p.a, self.x, self.v, self.frame, cycles,
                          self.logs, counts)
        self.slowest = min(self.slowest, slow)
        self.cycles += cycles
        self.counts.append(counts)

    def collisions(self) -> np.ndarray:
        return np.concatenate(self.counts) if self.counts else np.zeros(0, dtype=np.int64)

    def exponents(self) -> np.ndarray:
        """Bits per drive cycle, descending."""
        return np.sort(self.logs / self.cycles / math.log(2))[::-1]

    def sum_rule(self) -> float:
        """The exact sum of all 2n exponents (model.md 9), bits per cycle, from this run's
        collision count: every oscillator contracts by e^(-2 b T) per cycle, every impact
        by K^2."""
        c = self.collisions().sum() / self.cycles
        p = self.p
        return (-2 * p.b * p.T * p.n + 2 * c * math.log(p.K)) / math.log(2)


def block_error(values: np.ndarray, blocks: int = 20) -> float:
    """Standard error of the mean of a correlated series from `blocks` block means."""
    m = len(values) // blocks
    means = values[: m * blocks].reshape(blocks, m).mean(axis=1)
    return float(means.std(ddof=1) / math.sqrt(blocks))


# ------------------------------------------------------------------ check against impactchain

#: the paper's default chain (namelists/default.nml)
DEFAULT = dict(n=16, amplitude=1.7, omega=1.5, damping=0.05, restitution=0.7, spacing=1.0)
#: exponents agree within this many combined standard errors (the two trajectories part after
#: a few hundred cycles, so only the statistics can agree)
SIGMAS = 4.0
#: the sum of all 2n exponents against the exact rule, bits per cycle
SUM_RULE_TOL = 1e-9


def impactchain_run(x0, v0, transient: int, cycles: int):
    """impactchain's spectrum (QR every cycle) and per-cycle collision counts from x0, v0."""
    from impactchain import api

    keys = dict(damping=DEFAULT["damping"], restitution=DEFAULT["restitution"],
                spacing=DEFAULT["spacing"], boundary="fixed", transient=transient,
                x0=list(x0), v0=list(v0))
    n, A, w = DEFAULT["n"], DEFAULT["amplitude"], DEFAULT["omega"]
    ly = api.lyapunov(n, A, w, cycles=cycles, vectors=0, qr_every=1, **keys)
    sim = api.simulate(n, A, w, cycles=cycles, events=True, **keys)
    T = 2 * math.pi / w
    impact = (sim.event_kind == 0) | ((sim.event_kind == 1) & (sim.event_speed > 0))
    cycle = np.floor(sim.event_time[impact] / T).astype(np.int64) - transient
    counts = np.bincount(cycle[(cycle >= 0) & (cycle < cycles)], minlength=cycles)
    return ly, counts, int(sim.sticks), int(sim.touches)


def check(cycles: int, transient: int = 500, seed: int = 1) -> bool:
    """The reference against impactchain on the paper's default chain from the same start:
    collisions per cycle (mean, spread) and all 32 exponents within SIGMAS combined standard
    errors, and the reference's sum rule to SUM_RULE_TOL. Prints a table; True if all hold."""
    chain = Chain(Params(**DEFAULT), seed=seed)
    x0, v0 = chain.x.copy(), chain.v.copy()
    chain.run(transient)
    chain.set_vectors(2 * DEFAULT["n"])
    units = np.zeros((0, 2 * DEFAULT["n"]))
    unit = cycles // 40
    for _ in range(40):
        before = chain.logs.copy()
        chain.run(unit)
        units = np.vstack([units, (chain.logs - before) / unit / math.log(2)])
    ly, counts, sticks, touches = impactchain_run(x0, v0, transient, 40 * unit)
    ref_counts = chain.collisions()
    # the reference's exponents are column sums; sort columns by their mean, as impactchain
    order = np.argsort(-units.mean(axis=0))
    ref = units.mean(axis=0)[order]
    ref_se = np.array([block_error(units[:, j], 10) for j in order])
    ok = True
    print(f"paper default chain, {transient} + {40 * unit} cycles from the same random start "
          f"(seed {seed}); impactchain: {sticks} rests, {touches} touches")
    print(f"collisions per cycle: reference {ref_counts.mean():.4f} +- "
          f"{block_error(ref_counts.astype(float)):.4f} (sd {ref_counts.std():.3f}), "
          f"impactchain {counts.mean():.4f} +- {block_error(counts.astype(float)):.4f} "
          f"(sd {counts.std():.3f})")
    diff = abs(ref_counts.mean() - counts.mean())
    limit = SIGMAS * math.hypot(block_error(ref_counts.astype(float)),
                                block_error(counts.astype(float)))
    ok &= diff <= limit
    print(f"  difference {diff:.4f}, allowed {limit:.4f}: {'ok' if diff <= limit else 'FAIL'}")
    print("exponent  reference (+- se)  impactchain (+- se)  |diff| / combined se")
    worst = 0.0
    for j in range(len(ref)):
        z = abs(ref[j] - ly.exponents[j]) / math.hypot(ref_se[j], ly.stderr[j])
        worst = max(worst, z)
        print(f"{j + 1:8d}  {ref[j]: .5f} ({ref_se[j]:.5f})  {ly.exponents[j]: .5f} "
              f"({ly.stderr[j]:.5f})  {z:.2f}")
    ok &= worst <= SIGMAS
    print(f"largest difference {worst:.2f} combined standard errors, allowed {SIGMAS}: "
          f"{'ok' if worst <= SIGMAS else 'FAIL'}")
    rule = abs(chain.exponents().sum() - chain.sum_rule())
    ok &= rule <= SUM_RULE_TOL
    print(f"sum rule: reference sum {chain.exponents().sum():.12f}, exact "
          f"{chain.sum_rule():.12f} bits/cycle, |diff| {rule:.1e} (allowed {SUM_RULE_TOL:g}); "
          f"impactchain |diff| "
          f"{abs(ly.exponents.sum() - _rule(ly.collisions_per_cycle)):.1e}")
    print(f"slowest approach in the reference: {chain.slowest:.3g} (rests need < "
          f"{STICK_SPEED:g})")
    return bool(ok)


def _rule(c: float) -> float:
    p = Params(**DEFAULT)
    return (-2 * p.b * p.T * p.n + 2 * c * math.log(p.K)) / math.log(2)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    c = sub.add_parser("check", help="compare with impactchain on the paper's default chain")
    c.add_argument("--cycles", type=int, default=40000)
    c.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    return 0 if check(args.cycles, seed=args.seed) else 1


if __name__ == "__main__":
    sys.exit(main())
