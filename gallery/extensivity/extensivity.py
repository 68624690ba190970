"""Is the Lyapunov spectrum of the chain extensive? Spectra of chains of N = 16 ... 4096
oscillators at two parameter sets where every bond collides, their density lambda_i against
i / N, and the Kaplan-Yorke dimension per oscillator D_KY / N with its uncertainty
(issue 20, item 5; gallery/extensivity/README.md says what came out).

    python gallery/extensivity/extensivity.py run [--jobs 2] [--exe EXE] [--only NAME ...]
    python gallery/extensivity/extensivity.py report [-o gallery/extensivity/extensivity.png]

`run` writes each case's namelist into gallery/extensivity/runs/ and runs the simulator there
(the release build, built by fpm if needed), skipping cases whose file exists; the wall time
of each goes to runs/timings.json. `report` reads the files with impactchain.io, prints a
table, writes results.json next to this script and draws the figure.

The two sets (the chain has fixed walls and spacing 1 in both):

- `conservative`: no drive, no damping, elastic impacts (A = 0, b = 0, K = 1), started with
  the same energy per oscillator at every N (x uniform in [-0.3, 0.3], v uniform in [-4, 4],
  then v scaled so that the energy is exactly N times that of the uniform law's mean). The
  flow keeps the energy, so the chain is the same gas at every N and chaotic along its whole
  length; its spectrum is symmetric and sums to zero, so D_KY = 2N exactly.
- `damped`: the driven, weakly damped chain A = 2.5, w = 1.5, b = 0.001, K = 0.999 from a
  random start (seed 1, x_amp 0.3, v_amp 1), after a transient of several thousand cycles
  (the start is forgotten after some 120 cycles of damping). Energy enters only at the walls
  (the drive moves every oscillator alike), yet with this little damping every bond collides
  up to N = 1024.

Full spectra for N <= 256; the leading 256 exponents for N = 1024 and 4096 (i / N up to 1/4
and 1/16). The damped chain of 4096 collides only within about 1040 bonds of each wall (the
same after 3000 and 12000 cycles of transient): it is there to show what a quiet middle does.

Errors: the simulator's standard errors of each exponent (blocking plateau); D_KY / N by a
jackknife over 10 blocks of the run, rebuilt from the running estimates (/lyapunov/running), with the
stored D_KY as the value.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
RUNS = HERE / "runs"
FPM = ROOT / ".venv" / "bin" / "fpm"
E0 = 0.5 * (16.0 / 3.0 + 0.03)
"""Mean energy per oscillator of x uniform in [-0.3, 0.3] and v uniform in [-4, 4]."""
BLOCKS = 10
LEAD = 0.26
"""The leading part of the spectrum drawn on its own, i / N up to this."""


@dataclass(frozen=True)
class Case:
    """One run: a parameter set, a chain length, the exponents wanted, the cycles."""

    family: str  # 'conservative' or 'damped'
    n: int
    k: int  # 0: all 2n
    transient: int
    cycles: int
    align: int = 100

    @property
    def name(self) -> str:
        return f"{self.family}_n{self.n}" + (f"_k{self.k}" if self.k else "")


CASES = [
    *(Case("conservative", n, 0, 200, c) for n, c in ((16, 4000), (32, 4000), (64, 4000),
                                                       (128, 3000), (256, 1500))),
    Case("conservative", 1024, 256, 200, 600),
    Case("conservative", 4096, 256, 100, 200, align=50),
    *(Case("damped", n, 0, 3000, c) for n, c in ((16, 4000), (32, 4000), (64, 4000),
                                                 (128, 3000), (256, 1500))),
    Case("damped", 1024, 256, 4000, 600),
    Case("damped", 4096, 256, 3000, 200, align=50),
]


def namelist(case: Case) -> str:
    lyapunov = f"&lyapunov vectors = {case.k}, align = {case.align} /"
    run = (f"&run transient = {case.transient}, cycles = {case.cycles}, "
           "record_events = .false. /")
    output = f"&output file = '{case.name}.h5', overwrite = .true. /"
    if case.family == "conservative":
        x, v = conservative_start(case.n)
        return "\n".join([
            f"! {case.name}: A = 0, b = 0, K = 1, energy {E0:.6f} per oscillator",
            f"&chain n = {case.n}, amplitude = 0.0, omega = 1.5, damping = 0.0, "
            "restitution = 1.0 /",
            "&initial kind = 'explicit',",
            "  x0 = " + _values(x) + ",",
            "  v0 = " + _values(v) + " /",
            run, lyapunov, output, ""])
    return "\n".join([
        f"! {case.name}: the driven chain with weak damping",
        f"&chain n = {case.n}, amplitude = 2.5, omega = 1.5, damping = 0.001, "
        "restitution = 0.999 /",
        "&initial kind = 'random', seed = 1, x_amp = 0.3, v_amp = 1.0 /",
        run, lyapunov, output, ""])


def conservative_start(n: int, seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """x uniform in [-0.3, 0.3], v uniform in [-4, 4], v scaled to the energy n E0."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-0.3, 0.3, n)
    v = rng.uniform(-4.0, 4.0, n)
    kinetic = n * E0 - 0.5 * float(np.sum(x * x))
    return x, v * math.sqrt(2.0 * kinetic / float(np.sum(v * v)))


def _values(values: np.ndarray) -> str:
    items = [repr(float(a)) for a in values]
    return ",\n    ".join(", ".join(items[i:i + 4]) for i in range(0, len(items), 4))


def simulator() -> Path:
    out = subprocess.run([str(FPM), "run", "--profile", "release", "--runner", "echo"],
                         cwd=ROOT, capture_output=True, text=True, check=True)
    return ROOT / out.stdout.strip().splitlines()[-1]


def run_cases(exe: Path, cases: list[Case], jobs: int) -> None:
    RUNS.mkdir(exist_ok=True)
    timings_path = RUNS / "timings.json"
    timings = json.loads(timings_path.read_text()) if timings_path.exists() else {}

    def one(case: Case) -> tuple[str, float]:
        (RUNS / f"{case.name}.nml").write_text(namelist(case))
        began = time.perf_counter()
        done = subprocess.run([str(exe), "--quiet", f"{case.name}.nml"], cwd=RUNS,
                              capture_output=True, text=True)
        seconds = time.perf_counter() - began
        if done.returncode != 0:
            raise RuntimeError(f"{case.name}: {done.stderr.strip()}")
        print(f"  {case.name:28s} {seconds:7.1f} s", flush=True)
        return case.name, seconds

    todo = [c for c in cases if not (RUNS / f"{c.name}.h5").exists()]
    began = time.perf_counter()
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        for name, seconds in pool.map(one, sorted(todo, key=lambda c: -c.n * (c.k or 2 * c.n))):
            timings[name] = round(seconds, 2)
    timings_path.write_text(json.dumps(timings, indent=1, sort_keys=True) + "\n")
    print(f"ran {len(todo)} cases in {time.perf_counter() - began:.0f} s ({jobs} at a time)")


# ---------------------------------------------------------------------------------- report


def ky_dimension(exponents: np.ndarray) -> float:
    """j + (l_1 + ... + l_j) / |l_(j+1)| with j the largest index whose partial sum is >= 0
    (docs/model.md section 7.5), for the jackknife samples; checked against the stored value."""
    lam = np.sort(exponents)[::-1]
    partial = np.cumsum(lam)
    if partial[0] < 0:
        return 0.0
    j = int(np.flatnonzero(partial >= 0)[-1]) + 1
    if j == lam.size:
        return float(lam.size)
    return j + float(partial[j - 1]) / abs(float(lam[j]))


def block_sums(run, blocks: int = BLOCKS) -> tuple[np.ndarray, np.ndarray]:
    """(cycles of each block, (blocks, k) sums of the exponents over it): consecutive blocks of
    about equal length, rebuilt from the running means at the rows nearest their ends."""
    lyap = run.lyapunov
    counted = lyap.running_cycle - run.params.transient  # cycles averaged at each row
    totals = lyap.running * counted[:, None]  # sums so far
    ends = [int(np.argmin(np.abs(counted - counted[-1] * b / blocks)))
            for b in range(1, blocks + 1)]
    ends[-1] = counted.size - 1
    previous_cycles, previous = 0, np.zeros(lyap.running.shape[1])
    lengths, sums = [], []
    for end in ends:
        lengths.append(counted[end] - previous_cycles)
        sums.append(totals[end] - previous)
        previous_cycles, previous = counted[end], totals[end]
    return np.array(lengths, dtype=float), np.array(sums)


def jackknife_ky(run) -> float:
    """Standard error of D_KY by the jackknife over the blocks of :func:`block_sums`."""
    lengths, sums = block_sums(run)
    total, cycles = sums.sum(axis=0), lengths.sum()
    values = np.array([ky_dimension((total - sums[b]) / (cycles - lengths[b]))
                       for b in range(lengths.size)])
    m = values.size
    return math.sqrt((m - 1) / m * float(np.sum((values - values.mean()) ** 2)))


def summarise(case: Case, timings: dict) -> dict:
    from impactchain.io import read_run

    run = read_run(RUNS / f"{case.name}.h5", require=("lyapunov", "stats"))
    lyap, stats = run.lyapunov, run.stats
    rate = stats.site_counts / run.params.cycles  # collisions per cycle on each bond
    row = {
        "family": case.family, "n": case.n, "k": int(lyap.exponents.size),
        "transient": case.transient, "cycles": case.cycles,
        "seconds": timings.get(case.name),
        "lambda_1": float(lyap.exponents[0]), "stderr_1": float(lyap.stderr[0]),
        "positive": int(np.count_nonzero(lyap.exponents > 0)),
        "collisions_per_cycle": float(stats.collisions_per_cycle),
        "bonds_colliding": int(np.count_nonzero(stats.site_counts)),
        "bond_rate_min": float(rate.min()), "bond_rate_mean": float(rate.mean()),
        "bond_rate_middle": float(rate[case.n // 2 - case.n // 16:case.n // 2 + case.n // 16
                                       + 1].mean()),
    }
    if lyap.exponents.size == 2 * case.n:
        ours = ky_dimension(lyap.exponents)
        if not math.isclose(ours, lyap.ky_dimension, rel_tol=1e-9, abs_tol=1e-9):
            raise RuntimeError(f"{case.name}: D_KY {ours} here, {lyap.ky_dimension} stored")
        row["ky_per_n"] = lyap.ky_dimension / case.n
        row["ky_per_n_stderr"] = jackknife_ky(run) / case.n
        row["sum_bits_per_n"] = float(lyap.exponents.sum()) / case.n
    return row


def report(output: Path) -> None:
    from impactchain.io import read_run

    timings_path = RUNS / "timings.json"
    timings = json.loads(timings_path.read_text()) if timings_path.exists() else {}
    present = [c for c in CASES if (RUNS / f"{c.name}.h5").exists()]
    rows = [summarise(c, timings) for c in present]
    print(f"{'case':26s} {'k':>5s} {'cycles':>6s} {'s':>6s} {'lambda_1':>15s} {'pos':>5s} "
          f"{'bonds hit':>10s} {'rate min/mid/mean':>18s} {'D_KY/N':>18s}")
    for c, r in zip(present, rows):
        ky = (f"{r['ky_per_n']:.4f} +- {r['ky_per_n_stderr']:.4f}" if "ky_per_n" in r else "")
        print(f"{c.name:26s} {r['k']:5d} {r['cycles']:6d} {r['seconds'] or 0:6.0f} "
              f"{r['lambda_1']:7.3f} +- {r['stderr_1']:.3f} {r['positive']:5d} "
              f"{r['bonds_colliding']:5d}/{c.n + 1:<5d}"
              f"{r['bond_rate_min']:6.2f}/{r['bond_rate_middle']:5.2f}/{r['bond_rate_mean']:5.2f} "
              f"{ky:>18s}")
    runs = [read_run(RUNS / f"{c.name}.h5") for c in present]
    compare_to_reference(runs, present)
    (HERE / "results.json").write_text(json.dumps(rows, indent=1) + "\n")
    figure(runs, present, rows, output)


#: the ranges of i / N over which each length is compared with the reference N = 256
RANGES = ((0.03, 0.25), (0.25, 1.0))
REFERENCE_N = 256


def compare_to_reference(runs: list, cases: list[Case]) -> None:
    """Each spectrum against its family's N = 256, interpolated at the same i / N: the mean
    difference over each range of RANGES (bits per cycle), the largest, and the mean difference
    in units of the combined standard error, sqrt(se**2 + se_ref**2), averaged over the range."""
    print(f"\nagainst N = {REFERENCE_N} of the same family, at the same i/N:")
    print(f"{'case':26s} {'range':>12s} {'mean diff':>10s} {'largest':>9s} {'errors':>7s}")
    for family in sorted({c.family for c in cases}):
        pairs = [(run, c) for run, c in zip(runs, cases) if c.family == family]
        ref = [run for run, c in pairs if c.n == REFERENCE_N]
        if not ref:
            continue
        ref_lam, ref_err = ref[0].lyapunov.exponents, ref[0].lyapunov.stderr
        ref_x = np.arange(1, ref_lam.size + 1) / REFERENCE_N
        for run, case in pairs:
            if case.n == REFERENCE_N:
                continue
            lam, err = run.lyapunov.exponents, run.lyapunov.stderr
            x = np.arange(1, lam.size + 1) / case.n
            for low, high in RANGES:
                inside = (x >= low) & (x <= high) & (x <= ref_x[-1])
                if np.count_nonzero(inside) < 2:
                    continue
                diff = lam[inside] - np.interp(x[inside], ref_x, ref_lam)
                combined = np.hypot(err[inside], np.interp(x[inside], ref_x, ref_err))
                print(f"{case.name:26s} [{low:.2f}, {high:.2f}] {diff.mean():+10.4f} "
                      f"{diff[np.argmax(np.abs(diff))]:+9.4f} "
                      f"{diff.mean() / combined.mean():+7.1f}")


def figure(runs: list, cases: list[Case], rows: list[dict], output: Path) -> None:
    from matplotlib import colormaps
    from matplotlib.figure import Figure

    from impactchain import __version__

    families = ("conservative", "damped")
    titles = {"conservative": "conservative: $A$ = 0, $b$ = 0, $K$ = 1",
              "damped": "driven, weakly damped: $A$ = 2.5, $\\omega$ = 1.5, $b$ = 0.001, "
                        "$K$ = 0.999"}
    sizes = sorted({c.n for c in cases})
    cmap = colormaps["viridis"]
    colour = {n: cmap(0.9 * i / max(1, len(sizes) - 1)) for i, n in enumerate(sizes)}
    fig = Figure(figsize=(17.0, 8.4), layout="constrained")
    axes = fig.subplots(2, 4, gridspec_kw={"width_ratios": [1.25, 1.25, 1.1, 0.8]})
    ky_values = [r["ky_per_n"] + sign * r["ky_per_n_stderr"] for r in rows if "ky_per_n" in r
                 for sign in (-1, 1)]
    ky_range = (min(ky_values) - 0.005, max(ky_values) + 0.005) if ky_values else (0, 2.1)
    for row_axes, family in zip(axes, families):
        whole, lead, rate, ky = row_axes
        shown: list[np.ndarray] = []
        for run, case, r in zip(runs, cases, rows):
            if case.family != family:
                continue
            lam, err = run.lyapunov.exponents, run.lyapunov.stderr
            x = np.arange(1, lam.size + 1) / case.n
            label = f"N = {case.n}" + ("" if lam.size == 2 * case.n else f", first {lam.size}")
            for axis in (whole, lead):
                axis.fill_between(x, lam - err, lam + err, color=colour[case.n], alpha=0.3,
                                  linewidth=0)
                axis.plot(x, lam, color=colour[case.n], linewidth=1.0, label=label)
            shown.append(lam[x <= LEAD])
            site_rate = run.stats.site_counts / run.params.cycles
            rate.plot(np.arange(case.n + 1) / case.n, site_rate, color=colour[case.n],
                      linewidth=0.8, label=f"N = {case.n}")
            if "ky_per_n" in r:
                ky.errorbar(case.n, r["ky_per_n"], yerr=r["ky_per_n_stderr"], fmt="o",
                            color=colour[case.n], capsize=3)
        for axis in (whole, lead):
            axis.axhline(0.0, color="0.3", linewidth=0.7, linestyle="--")
            axis.set_xlabel("exponent index per oscillator $i/N$ [1]")
            axis.set_ylabel("Lyapunov exponent $\\lambda_i$ [bits per drive cycle]")
        whole.set_title(f"{titles[family]}\nthe whole spectrum (bands: $\\pm$1 standard "
                        "error)", fontsize="medium")
        lead.set_xlim(0.0, LEAD)
        low, high = (float(f(np.concatenate(shown))) for f in (np.min, np.max))
        lead.set_ylim(low - 0.05 * (high - low), high + 0.05 * (high - low))
        lead.set_title("the leading quarter: N = 1024 and 4096 add their first 256",
                       fontsize="medium")
        lead.legend(fontsize="small", loc="upper right")
        rate.set_ylim(bottom=0.0)
        rate.set_xlabel("bond position per oscillator $k/N$ [1]")
        rate.set_ylabel("collisions per drive cycle on the bond [1/cycle]")
        rate.set_title("where the chain collides", fontsize="medium")
        ky.set_xscale("log", base=2)
        ky.set_ylim(*ky_range)
        ky.set_xlim(10, 400)
        ky.set_xlabel("oscillators $N$ [1]")
        ky.set_ylabel("Kaplan-Yorke dimension per oscillator $D_{KY}/N$ [1]")
        ky.set_title("$D_{KY}/N$, full spectra\n(bars: jackknife over 10 blocks)",
                     fontsize="medium")
    sources = "\n".join(f"{RUNS.relative_to(ROOT)}/{c.name}.h5" for c in cases)
    fig.suptitle("Extensivity of the Lyapunov spectrum: $\\lambda_i$ against $i/N$",
                 fontsize="large")
    fig.savefig(output, dpi=150, metadata={
        "Software": f"impactchain.figures {__version__}; gallery/extensivity/extensivity.py",
        "Source": sources, "Title": "Extensivity of the Lyapunov spectrum"})
    print(f"wrote {output}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("run", help="run the cases whose files are missing")
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--exe", type=Path, help="the simulator (default: the release build)")
    p.add_argument("--only", nargs="+", metavar="NAME", help="only these cases")
    p = sub.add_parser("report", help="table, results.json and the figure")
    p.add_argument("-o", "--output", type=Path, default=HERE / "extensivity.png")
    sub.add_parser("list", help="the cases and their namelists' first lines")
    args = parser.parse_args(argv)
    if args.command == "list":
        for case in CASES:
            print(case.name, case)
        return 0
    if args.command == "run":
        cases = [c for c in CASES if not args.only or c.name in args.only]
        run_cases((args.exe or simulator()).resolve(), cases, max(1, args.jobs))
        return 0
    report(args.output)
    return 0


if __name__ == "__main__":
    os.environ.setdefault("MPLBACKEND", "Agg")
    sys.exit(main())
