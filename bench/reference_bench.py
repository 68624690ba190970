"""Issue #34's table: impactchain against the independent numba implementation of the same
model (bench/numba_reference.py), the four rows in one process on one core, timed
alternately in the process's CPU time, best of the rounds.

    .venv/bin/python bench/reference_bench.py [--rounds 3] [--min-time 0.5]
    OPENBLAS_CORETYPE=Sandybridge .venv/bin/python bench/reference_bench.py   # other kernels

Both sides start from the same state on the attractor (200 reference cycles from the default
random start) with a fresh frame; impactchain runs through its Python package
(`impactchain.api`, the same Fortran as the CLI), the reference through numba, whose QR is numpy's (`np.linalg.qr` compiled
by numba: LAPACK's dgeqrf + dorgqr). Both sides QR every cycle (impactchain's full spectra
start from unit vectors and factorise only the block of the oscillators impacts have joined,
docs/model.md 7.2; the reference factorises its whole frame); impactchain's default adaptive
schedule (same exponents to 1e-10 bits per cycle, model.md 7.2) is a row of its own.
A call's fixed cost (impactchain's start: the input's checks, the initial frame and its QR,
the result arrays; 0.15 s at n = 256) is not a drive cycle's, so each side's cost per cycle is
the difference of two blocks, of c and c / 4 cycles, over 3 c / 4 (each block the best of the
rounds). `make bench` runs it after run_bench.py. Timings are printed, never asserted.
"""
from __future__ import annotations

import os

# one core: set before numpy, numba or impactchain load a BLAS
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "NUMBA_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import ctypes  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
import numba_reference as ref  # noqa: E402

#: issue #34's rows: name, n, vectors (0: none), impactchain's qr_every, wanted speed-up
ROWS = (("n = 16, no exponents", 16, 0, 1, 6.0),
        ("n = 16, all 32 exponents", 16, 32, 1, 4.0),
        ("n = 16, all 32 exponents, impactchain adaptive QR", 16, 32, 0, 4.0),
        ("n = 64, full spectrum (128)", 64, 128, 1, 3.0),
        ("n = 256, full spectrum (512)", 256, 512, 1, 3.0))
TRANSIENT = 200


def start_state(n: int) -> tuple[np.ndarray, np.ndarray]:
    chain = ref.Chain(ref.Params(**dict(ref.DEFAULT, n=n)))
    chain.run(TRANSIENT)
    return chain.x.copy(), chain.v.copy()


def time_reference(n, k, x0, v0, cycles) -> float:
    """CPU seconds of a block of `cycles` reference cycles from (x0, v0), a fresh frame."""
    chain = ref.Chain(ref.Params(**dict(ref.DEFAULT, n=n)))
    chain.x[:], chain.v[:] = x0, v0
    chain.set_vectors(k)
    t = time.process_time()
    chain.run(cycles)
    return time.process_time() - t


def time_impactchain(n, k, qr_every, x0, v0, cycles) -> float:
    """CPU seconds of one impactchain call of `cycles` cycles from (x0, v0)."""
    from impactchain import api

    keys = dict(damping=ref.DEFAULT["damping"], restitution=ref.DEFAULT["restitution"],
                spacing=ref.DEFAULT["spacing"], transient=0, x0=list(x0), v0=list(v0))
    A, w = ref.DEFAULT["amplitude"], ref.DEFAULT["omega"]
    t = time.process_time()
    if k:
        api.lyapunov(n, A, w, cycles=cycles, vectors=k, qr_every=qr_every, **keys)
    else:
        api.simulate(n, A, w, cycles=cycles, events=False, **keys)
    return time.process_time() - t


def calibrate(timer, min_time: float) -> int:
    """Cycles for a block whose cycles, its fixed cost aside, take about min_time CPU
    seconds (a warm-up call on the way)."""
    fixed = timer(1)
    cycles = 4
    while True:
        seconds = timer(cycles) - fixed
        if seconds >= min_time / 4 or cycles >= 1 << 22:
            return max(8, int(min_time * cycles / max(seconds, 1e-9)))
        cycles *= 4


def blas_kernels() -> list[str]:
    """Every OpenBLAS loaded in this process, with the kernels it chose on this CPU."""
    found = []
    with open("/proc/self/maps") as f:
        paths = sorted({line.split()[-1] for line in f if "openblas" in line.lower()})
    for path in paths:
        lib = ctypes.CDLL(path)
        for prefix in ("scipy_", "", "scipy_openblas64_"):
            for name in (f"{prefix}openblas_get_corename", f"{prefix}openblas_get_corename64_"):
                fn = getattr(lib, name, None)
                if fn is not None:
                    fn.restype = ctypes.c_char_p
                    found.append(f"{Path(path).name}: {fn().decode()}")
                    break
            else:
                continue
            break
    return found


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--min-time", type=float, default=0.5, help="CPU seconds per block")
    args = ap.parse_args(argv)
    load = [os.getloadavg()[0]]
    best: dict[tuple[str, str, int], float] = {}
    plans = []
    for name, n, k, qr_every, want in ROWS:
        x0, v0 = start_state(n)
        ref_timer = lambda c, n=n, k=k, x0=x0, v0=v0: time_reference(n, k, x0, v0, c)  # noqa
        ic_timer = (lambda c, n=n, k=k, q=qr_every, x0=x0, v0=v0:  # noqa: E731
                    time_impactchain(n, k, q, x0, v0, c))
        plans.append((name, want, ref_timer, calibrate(ref_timer, args.min_time),
                       ic_timer, calibrate(ic_timer, args.min_time)))
    for _ in range(args.rounds):
        for name, _, ref_timer, ref_cycles, ic_timer, ic_cycles in plans:
            for side, timer, cycles in (("ic", ic_timer, ic_cycles),
                                        ("ref", ref_timer, ref_cycles)):
                for c in (cycles, cycles // 4):
                    key = (name, side, c)
                    best[key] = min(best.get(key, np.inf), timer(c))
    load.append(os.getloadavg()[0])
    coretype = os.environ.get("OPENBLAS_CORETYPE", "(chosen at run time)")
    print(f"OPENBLAS_CORETYPE={coretype}; loaded: " + "; ".join(blas_kernels()))
    print(f"one thread; CPU time, best of {args.rounds} alternating rounds of >= "
          f"{args.min_time} s blocks; load average {load[0]:.2f} -> {load[1]:.2f}")
    print()
    print("| case | impactchain µs/cycle | numba reference µs/cycle | speed-up | wanted |")
    print("|---|---:|---:|---:|---:|")
    def per_cycle(name, side, cycles):
        return (best[name, side, cycles] - best[name, side, cycles // 4]) / (
            cycles - cycles // 4)

    for name, want, _, ref_cycles, _, ic_cycles in plans:
        ic = per_cycle(name, "ic", ic_cycles) * 1e6
        rf = per_cycle(name, "ref", ref_cycles) * 1e6
        print(f"| {name} | {ic:,.1f} | {rf:,.1f} | {rf / ic:.2f}x | >= {want:g}x |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
