"""Every recipe's results against stored reference values, with tolerances that follow from
the physics: the check that holds on any machine, whatever kernels its BLAS and libm select.

    python test/recipes/recipe_reference.py check   [--exe EXE] [--jobs N] [--kernels K] [--keep DIR]
    python test/recipes/recipe_reference.py compute [--exe EXE] [--jobs N]

`check` runs every recipe in namelists/ and compares its output with
test/recipes/reference.json: numbers, not hashes. When a value is off it names the recipe,
the value (dataset and index), the two numbers, the difference and the tolerance it broke,
and the rule that set that tolerance; it ends with one line, "N values in M recipes within
their tolerances", and exits 1 on any failure. `--kernels machine` (the default) runs with the
kernels BLAS and libm select on this CPU; `--kernels second` forces other code paths (see
SECOND_KERNELS), so that one `make test` shows the checks hold on two.

`compute` writes the reference. Run it only when results are meant to change (a physics fix, a
recipe edited or added), commit it with that change and say why the numbers moved.

What is compared, and how, is decided once from the reference run and stored with its numbers
(the "plan"): which runs and sweep points are periodic, which chaotic, and the horizon up to
which a chaotic trajectory can be compared. The rules and their tolerances are in RULES below,
each with its reason; what is not compared is in NOT_COMPARED, each with its reason.
Bit-identity is a promise on one machine only (a rerun, threads, MPI, a continued run, Python
and the command line: their own tests); `recipe_runs.py compare` checks it for a refactor.
"""
from __future__ import annotations

import argparse
import fnmatch
import json
import math
import sys
from pathlib import Path
from statistics import NormalDist

import h5py
import numpy as np

from recipe_runs import (EXCLUDED, RECIPES, RecipeError, default_exe, run_recipe,
                         run_recipes, workdir_for)

REFERENCE = Path(__file__).resolve().parent / "reference.json"

# ---- the rules: every tolerance, with its reason (the one home) ----------------------------

REGULAR_RTOL = 1e-9       # non-chaotic results
SPECIAL_POINT_MULTIPLIER = 1e-6  # |multiplier - 1| of a located fold or branch point, at most
HORIZON_START = 1e-12     # where a chaotic trajectory's difference starts
HORIZON_TOL = 1e-6        # and how far it may grow before records stop being compared
FALSE_ALARM = 0.0027      # two-sided, that of 3 standard errors for one value
MIN_BLOCKS = 16           # docs/model.md 7.4: levels of the blocking rule have >= 16 blocks
STDERR_RTOL = 3 * math.sqrt(2) / math.sqrt(2 * (MIN_BLOCKS - 1))
RESIDUAL_LIMIT = 1e-9     # a Newton solution's final residual

RULES = {
    "exact": "an input, a count, a code or a label: the same on every machine",
    "regular": f"a non-chaotic result (a periodic strobe, a periodic orbit and what is "
               f"measured on it, a converged Newton solution): rounding differences "
               f"(1e-16 to 8e-11 measured between BLAS kernels) are damped or solved away, "
               f"not amplified; |d| <= {REGULAR_RTOL:g} x the largest magnitude of the value",
    "multiplier": f"Floquet multipliers, matched pairwise: {REGULAR_RTOL:g} x the point's "
                  f"largest multiplier (a rounding error dJ of the Jacobian moves every "
                  f"eigenvalue by about |dJ|, Bauer-Fike, and |J| is about the largest), "
                  f"widened by 1/v for the point's slowest impact speed v < 1 (the saltation "
                  f"matrices carry 1/v, so the Jacobian and its rounding grow like 1/v near a "
                  f"grazing)",
    "horizon": f"a chaotic trajectory up to its horizon: a difference of {HORIZON_START:g} "
               f"(ten times the accuracy of the impact times) grows by 2**(lambda c) in c "
               f"cycles, lambda the largest exponent plus 3 standard errors (bits per "
               f"cycle); records up to the cycle where that reaches {HORIZON_TOL:g} are "
               f"compared to {HORIZON_TOL:g} x the largest magnitude of the value",
    "statistic": "a statistic (a time average, an exponent, a dimension): within z combined "
                 "standard errors, z = 3 for a single value; for the m statistics of one "
                 "recipe, the threshold that keeps the chance of any false alarm at that of 3 "
                 "(0.27 %, Sidak); never below 1e-9 x the largest magnitude of the value",
    "stderr": f"a standard error by blocking (docs/model.md 7.4): its own uncertainty is at "
              f"most se / sqrt(2 (M - 1)) with M >= {MIN_BLOCKS} blocks; within 3 of those, "
              f"combined: |d| <= {STDERR_RTOL:.3f} se; never below {REGULAR_RTOL:g} x the "
              f"largest error of the value (an exactly periodic direction's error is rounding)",
    "newton_residual": f"Newton's final residual: rounding, not a result; below "
                       f"{RESIDUAL_LIMIT:g}",
}

# What is not compared, and why. Everything else in a file is, by one of RULES; a dataset
# the rules do not know fails the check until it is given a rule or a reason here.
NOT_COMPARED = {
    # the build's version and provenance, the input echoed back, what describes a dataset
    # and HDF5's own bookkeeping: recipe_runs' list, the same for both scripts
    **EXCLUDED,
    "/final/*": "a chaotic run's final state lies beyond the trajectory's horizon (its "
                "statistics are compared instead); a periodic run's is compared",
    "/stats/site_counts": "a chaotic run's impacts per bond: counts along a trajectory "
                          "beyond its horizon (the collisions per cycle are compared as a "
                          "statistic); a periodic run's are compared",
    "/stats@*": "a chaotic run's counts along a trajectory beyond its horizon (collisions per "
                "cycle are compared as a statistic); a periodic run's are compared",
    "/events/*": "a chaotic run's events beyond its horizon (those within it are compared)",
    "/lyapunov/exponents_per_time": "the exponents in other units: /lyapunov/exponents is "
                                    "compared",
    "/lyapunov/running": "running estimates along the trajectory: their end is "
                         "/lyapunov/exponents, compared",
    "/lyapunov/running_cycle": "the cycles of the running estimates",
    "/lyapunov/qr_step": "when the adaptive QR steps fell: a numerical schedule that "
                         "rounding may shift by a cycle, not a result (the exponents are "
                         "compared)",
    "*/stderr_block": "the block size at which the blocking rule read its plateau: a "
                      "discrete choice among levels whose errors agree (the errors are "
                      "compared)",
    "/lyapunov@collisions_per_cycle": "the same number as /stats@collisions_per_cycle",
    "/clv/vectors": "covariant vectors at a saved cycle of a chaotic run: beyond the "
                    "horizon, and each defined up to sign (their exponents and time "
                    "averages of their weights and angles are compared)",
    "/continuation/iterations": "Newton's iteration count: a stopping test on rounding-level "
                                "numbers may take one step more or fewer (the solution and "
                                "its residual are compared)",
    "/sweep/collisions_per_cycle[chaotic]": "a chaotic point's collisions per cycle: the file "
                                            "holds only the mean, without the per-cycle "
                                            "series its error needs (periodic points are "
                                            "compared)",
    "*@_Netcdf4Dimid": "netCDF's dimension bookkeeping, not a result",
}

# The second code path of `--kernels second`: BLAS and libm forced off the kernels they select
# by CPU. OpenBLAS (DYNAMIC_ARCH builds) takes its kernel from OPENBLAS_CORETYPE (Prescott:
# SSE3, which every x86-64 CPU has, unlike the AVX2 and AVX-512 kernels selected on current
# CPUs); BLIS 0.9 from BLIS_ARCH_TYPE, by number (25: 'generic'); glibc's libm drops its FMA
# and AVX2 variants of exp, sin, cos, ... by GLIBC_TUNABLES. Each library ignores the others'
# variables.
SECOND_KERNELS = {"OPENBLAS_CORETYPE": "Prescott", "BLIS_ARCH_TYPE": "25",
                  "GLIBC_TUNABLES": "glibc.cpu.hwcaps=-AVX2,-FMA,-FMA4,-AVX,-AVX512F"}
# The machine's own kernels: nothing forced (a variable set in the environment is removed).
MACHINE_KERNELS = {name: None for name in SECOND_KERNELS}


# ---- reading ---------------------------------------------------------------------------------

def read(f: h5py.File, key: str):
    """The value of `path` or `path@attribute` (strings as str, numbers as numpy arrays)."""
    path, _, attribute = key.partition("@")
    obj = f[path or "/"]
    value = obj.attrs[attribute] if attribute else obj[()]
    if isinstance(value, bytes):
        return value.decode()
    if isinstance(value, np.ndarray) and value.dtype.kind in "SO":
        return [v.decode() if isinstance(v, bytes) else str(v) for v in value.ravel()]
    return value.decode() if isinstance(value, np.bytes_) else value


def every_key(f: h5py.File) -> list[str]:
    """Every dataset and attribute of a file, as `path` and `path@attribute`."""
    keys = [f"/@{a}" for a in f.attrs]

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset):
            keys.append("/" + name)
        keys.extend(f"/{name}@{a}" for a in obj.attrs)
    f.visititems(visit)
    return keys


def blocking_stderr(series: np.ndarray) -> np.ndarray:
    """The standard error of the mean of each column of `series` (time along axis 0) by
    blocking, read where it stops changing with the block size: the rule of docs/model.md
    7.4 with units of one record. Columns too short for two levels get infinity."""
    shape = np.shape(series)[1:]
    x = np.asarray(series, dtype=float).reshape(len(series), -1)
    levels = []
    while x.shape[0] >= MIN_BLOCKS:
        m = x.shape[0]
        se = x.std(axis=0, ddof=1) / math.sqrt(m)
        levels.append((se, se / math.sqrt(2 * (m - 1))))
        x = 0.5 * (x[:m // 2 * 2:2] + x[1:m // 2 * 2:2])
    if len(levels) < 2:
        return np.full(shape, np.inf)
    result = levels[-1][0].copy()
    found = np.zeros(result.shape, dtype=bool)
    for i, (se, s) in enumerate(levels):
        agree = np.ones(result.shape, dtype=bool)
        for se2, s2 in levels[i + 1:]:
            agree &= np.abs(se2 - se) <= 2 * np.sqrt(s ** 2 + s2 ** 2)
        take = agree & ~found
        result[take] = se[take]
        found |= take
    return result.reshape(shape)


def ky_sigma(exponents: np.ndarray, stderr: np.ndarray) -> float:
    """A bound on the standard error of the Kaplan-Yorke dimension (docs/model.md 7.5) from
    its exponents' errors: |dD/dl(i)| summed with each error (correlations ignored, so this
    bounds the propagated error from above)."""
    finite = np.isfinite(exponents)
    total, j = 0.0, 0
    while j < len(exponents) and finite[j] and total + exponents[j] >= 0:
        total += exponents[j]
        j += 1
    if j == 0 or j == len(exponents) or not finite[j]:
        return float(np.sum(stderr[:j][np.isfinite(stderr[:j])])) if j else 0.0
    nxt = abs(exponents[j])
    return float(np.sum(stderr[:j]) / nxt + total / nxt ** 2 * stderr[j])


# ---- what is compared: the plan, then the values ---------------------------------------------

def file_kind(f: h5py.File) -> str:
    for kind in ("continuation", "sweep", "strobe"):
        if kind in f:
            return "run" if kind == "strobe" else kind
    raise RecipeError(f"{f.filename}: neither a run, a sweep nor a continuation")


def make_plan(f: h5py.File, lambda1: tuple[float, float] | None) -> dict:
    """What is compared in this recipe's files, decided from the reference run."""
    kind = file_kind(f)
    plan: dict = {"kind": kind}
    if kind == "run":
        plan["periodic"] = bool((f["/strobe/period"][()] > 0).all())
        if not plan["periodic"]:
            if "lyapunov" in f:
                lambda1 = (float(f["/lyapunov/exponents"][0]), float(f["/lyapunov/stderr"][0]))
            if lambda1 is None:
                raise RecipeError(f"{f.filename}: a chaotic run needs its largest exponent")
            rate = lambda1[0] + 3 * lambda1[1]
            plan["lambda1"] = list(lambda1)
            plan["horizon_cycle"] = (math.log2(HORIZON_TOL / HORIZON_START) / rate
                                     if rate > 0 else math.inf)
    elif kind == "sweep":
        period = f["/sweep/period"][()]
        period = period.reshape(-1, period.shape[-1])
        plan["periodic_points"] = [bool(p) for p in (period > 0).all(axis=1)]
    return plan


def points(f: h5py.File, path: str) -> np.ndarray:
    """A sweep's per-point dataset with its point axes (one, or two for a 2-D sweep) made
    one."""
    value = f[path][()]
    return value.reshape((-1,) + value.shape[2:]) if "point2" in f["/sweep"] else value


def per_cycle_collisions(f: h5py.File) -> np.ndarray:
    """Impacts in each recorded drive cycle, from the event stream (docs/model.md 6.2)."""
    kind = f["/events/kind"]
    meanings = read(f, "/events/kind@flag_meanings").split()
    codes = [int(c) for c, m in zip(kind.attrs["flag_values"], meanings)
             if m.startswith("impact")]
    is_impact = np.isin(kind[()], codes)
    period = float(f["/params"].attrs["drive_period"])
    phase = float(f["/params"].attrs["phase"]) / float(f["/params"].attrs["omega"])
    cycles = f["/strobe/cycle"][()].astype(float)
    edges = np.concatenate([[cycles[0] - 1], cycles]) * period + phase
    counts, _ = np.histogram(f["/events/time"][()][is_impact], bins=edges)
    return counts.astype(float)


def quantities(f: h5py.File, plan: dict) -> tuple[dict, set[str]]:
    """({name: (rule, value, sigma or None, extra)}, the file's keys they cover), by the
    plan. `extra` carries what a rule needs beyond the value (the multipliers' speeds)."""
    q: dict = {}
    covered: set[str] = set()
    keys = every_key(f)

    def take(key, rule, value=None, sigma=None, extra=None, name=None):
        q[name or key] = (rule, read(f, key) if value is None else value, sigma, extra)
        covered.add(key)

    for key in keys:
        if key.startswith(("/params", "/initial", "/@schema_version", "/@complete")) \
                and not key.endswith(("@units", "@long_name", "@model_units")):
            if "@" not in key or not fnmatch.fnmatchcase(key, "*@[A-Z_]*"):
                take(key, "exact")
    kind = plan["kind"]
    if kind == "run":
        run_quantities(f, plan, keys, take)
    elif kind == "sweep":
        sweep_quantities(f, plan, keys, take)
    else:
        continuation_quantities(f, keys, take)
    return q, covered


def run_quantities(f, plan, keys, take):
    for key in ("/strobe/cycle", "/strobe/oscillator", "/strobe/period", "/stats/cycles_done",
                "/stats/bond"):
        take(key, "exact")
    events = "events" in f
    if plan["periodic"]:
        for key in ("/strobe/x", "/strobe/v", "/final/x", "/final/v", "/final/time_in_cycle",
                    "/final/phase", "/final/event_time", "/stats@collisions_per_cycle"):
            take(key, "regular")
        for key in ("/final/cycle", "/final/contact", "/final/event_action", "/final/bond",
                    "/final/oscillator", "/stats/site_counts", "/stats@impacts",
                    "/stats@releases", "/stats@sticks", "/stats@touches"):
            take(key, "exact")
        if events:
            take("/events/time", "regular")
            take("/events/speed", "regular")
            take("/events/kind", "exact")
            take("/events/site", "exact")
    else:
        cycle = f["/strobe/cycle"][()]
        within = cycle <= plan["horizon_cycle"]
        for key in ("/strobe/x", "/strobe/v"):
            if within.any():
                take(key, "horizon", f[key][()][within], name=f"{key}[within horizon]")
        x, v = f["/strobe/x"][()], f["/strobe/v"][()]
        take("/strobe/x", "statistic", x.mean(axis=0), blocking_stderr(x),
             name="/strobe/x: time average")
        take("/strobe/v", "statistic", (v ** 2).mean(axis=0), blocking_stderr(v ** 2),
             name="/strobe/v: time average of v**2")
        if events:
            ends = f["/events/time"][()] <= plan["horizon_cycle"] * float(
                f["/params"].attrs["drive_period"])
            if ends.any():
                for key, rule in (("/events/time", "horizon"), ("/events/speed", "horizon"),
                                  ("/events/kind", "exact"), ("/events/site", "exact")):
                    take(key, rule, f[key][()][ends], name=f"{key}[within horizon]")
            counts = per_cycle_collisions(f)
            take("/stats@collisions_per_cycle", "statistic", np.array([counts.mean()]),
                 blocking_stderr(counts[:, None]), name="collisions per cycle (events)")
    if "lyapunov" in f:
        exponents, stderr = f["/lyapunov/exponents"][()], f["/lyapunov/stderr"][()]
        take("/lyapunov/exponent", "exact")
        take("/lyapunov/exponents", "statistic", sigma=stderr)
        take("/lyapunov/stderr", "stderr")
        take("/lyapunov@ky_dimension", "statistic", sigma=ky_sigma(exponents, stderr))
        positive = exponents > 0
        take("/lyapunov@positive_sum", "statistic", sigma=float(np.sum(stderr[positive])))
    if "clv" in f:
        for key in ("/clv/component", "/clv/cycle", "/clv/leading_vector", "/clv/oscillator",
                    "/clv/saved_cycle", "/clv/vector", "/clv@clv_transient", "/clv@unstable"):
            take(key, "exact")
        take("/clv/exponents", "statistic", sigma=f["/clv/stderr"][()])
        take("/clv/stderr", "stderr")
        for key in ("/clv/ipr", "/clv/min_angle", "/clv/site_weight"):
            series = f[key][()]
            take(key, "statistic", series.mean(axis=0), blocking_stderr(series),
                 name=f"{key}: time average")


def sweep_quantities(f, plan, keys, take):
    periodic = np.array(plan["periodic_points"])
    for key in keys:
        if key.startswith("/sweep@") or key in ("/sweep/point", "/sweep/point2",
                                                 "/sweep/record", "/sweep/oscillator",
                                                 "/sweep/exponent", "/sweep/drive_period",
                                                 "/sweep/period"):
            if not fnmatch.fnmatchcase(key, "*@[A-Z_]*"):
                take(key, "exact")
    x = points(f, "/sweep/x")
    if periodic.any():
        # a point of a periodic orbit: the orbit is the same on every machine or none
        take("/sweep/x", "regular", x[periodic, -1], name="/sweep/x: last record [periodic]")
        take("/sweep/collisions_per_cycle", "regular",
             points(f, "/sweep/collisions_per_cycle")[periodic],
             name="/sweep/collisions_per_cycle [periodic]")
    if (~periodic).any():
        chaotic = x[~periodic]
        sigma = np.stack([blocking_stderr(p) for p in chaotic])
        take("/sweep/x", "statistic", chaotic.mean(axis=1), sigma,
             name="/sweep/x: record mean [chaotic]")
    if "exponents" in f["/sweep"]:
        exponents, stderr = points(f, "/sweep/exponents"), points(f, "/sweep/stderr")
        take("/sweep/exponents", "statistic", exponents, stderr)
        take("/sweep/stderr", "stderr")
        take("/sweep/ky_dimension", "statistic", points(f, "/sweep/ky_dimension"),
             np.array([ky_sigma(e, s) for e, s in zip(exponents, stderr)]))


def continuation_quantities(f, keys, take):
    for key in keys:
        if not key.startswith("/continuation") or fnmatch.fnmatchcase(key, "*@[A-Z_]*"):
            continue
        name = key.rsplit("/", 1)[-1]
        if name in ("values", "x", "v", "strobe_x", "min_gap", "min_impact_speed",
                    "special_value"):
            take(key, "regular")
        elif name in ("branch", "impacts_per_period", "period", "special_kind",
                      "special_index", "iterate", "oscillator", "multiplier", "point",
                      "special", "branch_index", "parent", "origin_point", "origin_kind") or \
                "@" in key:
            take(key, "exact")
    speed = f["/continuation/min_impact_speed"][()]
    multipliers = f["/continuation/multipliers_re"][()] + \
        1j * f["/continuation/multipliers_im"][()]
    take("/continuation/multipliers_re", "multiplier", multipliers, extra=speed,
         name="/continuation/multipliers")
    take("/continuation/multipliers_im", "multiplier", multipliers, extra=speed,
         name="/continuation/multipliers")
    take("/continuation/residual", "newton_residual")
    # stable: exact, except where the largest multiplier sits on the unit circle within
    # its tolerance (a special point stored on the branch)
    stable = f["/continuation/stable"][()]
    margin = np.abs(np.abs(multipliers).max(axis=1) - 1) > multiplier_rtol(speed)
    take("/continuation/stable", "exact", np.where(margin, stable, -1),
         name="/continuation/stable (off the unit circle)")
    # symmetric: exact, except at a point with a multiplier at +1 (a located fold or branch
    # point): there the corrector may leave the orbit off the mirror-symmetric set by as much
    # as the second multiplier near +1 allows (fig10_fold: 2.5e-5), beyond the label's 1e-7
    symmetric = f["/continuation/symmetric"][()]
    at_one = np.abs(multipliers - 1).min(axis=1) <= SPECIAL_POINT_MULTIPLIER
    take("/continuation/symmetric", "exact", np.where(at_one, -1, symmetric),
         name="/continuation/symmetric (off a multiplier +1)")


def multiplier_rtol(speed: np.ndarray) -> np.ndarray:
    return REGULAR_RTOL / np.minimum(1.0, np.abs(speed))


# ---- comparing -------------------------------------------------------------------------------

STORED_DIGITS = 12   # significant digits of a stored value that is compared with a tolerance
                     # (>= 1e-9 of its scale): rounding it costs at most 5e-12 of that


def to_json(value, exact: bool = True):
    if isinstance(value, (str, list)) and not isinstance(value, np.ndarray):
        if isinstance(value, list) and value and not isinstance(value[0], str):
            return to_json(np.asarray(value))
        return value
    a = np.asarray(value)
    if a.dtype.kind == "c":
        return {"re": to_json(a.real, exact), "im": to_json(a.imag, exact)}
    if exact or a.dtype.kind != "f":
        return a.tolist()
    return np.vectorize(lambda v: float(f"{v:.{STORED_DIGITS}g}"), otypes=[float])(a).tolist() \
        if a.size else a.tolist()


def from_json(value):
    if isinstance(value, dict):
        return np.asarray(value["re"]) + 1j * np.asarray(value["im"])
    if isinstance(value, str) or (isinstance(value, list) and value and
                                  isinstance(value[0], str)):
        return value
    return np.asarray(value, dtype=float)


def sidak_z(m: int) -> float:
    """The threshold in standard errors that keeps m tests' chance of any false alarm at
    FALSE_ALARM (3 for m = 1)."""
    single = 1 - (1 - FALSE_ALARM) ** (1 / max(m, 1))
    return NormalDist().inv_cdf(1 - single / 2)


def match_multipliers(ref: np.ndarray, new: np.ndarray) -> np.ndarray:
    """`new` reordered, point by point, to pair each reference multiplier with the nearest
    unused fresh one (their order is LAPACK's, which a kernel may change among equals)."""
    out = np.empty_like(new)
    for p in range(ref.shape[0]):
        free = list(range(new.shape[1]))
        for i in np.argsort(-np.abs(ref[p]), kind="stable"):
            j = min(free, key=lambda j: abs(new[p, j] - ref[p, i]))
            out[p, i] = new[p, j]
            free.remove(j)
    return out


def compare_entry(name: str, entry: dict, fresh: tuple, z: float) -> tuple[int, list[str]]:
    """(values compared, problems) for one stored entry against its fresh counterpart."""
    rule = entry["rule"]
    ref, new = from_json(entry["value"]), fresh[1]
    if isinstance(ref, (str, list)) or isinstance(new, (str, list)):
        same = (ref if isinstance(ref, str) else list(ref)) == \
            (new if isinstance(new, str) else list(new))
        count = len(ref) if isinstance(ref, list) else 1
        return count, [] if same else [f"{name}: {new!r:.200} (reference {ref!r:.200}); rule "
                                       f"{rule}: must be equal"]
    new = np.asarray(new)
    if rule == "multiplier":
        new = np.asarray(new, dtype=complex)
    else:
        new = np.asarray(new, dtype=float)
    if ref.shape != new.shape:
        return 1, [f"{name}: shape {new.shape} (reference {ref.shape}); rule {rule}"]
    if rule == "multiplier":
        new = match_multipliers(ref, new)
        speed = np.asarray(entry["extra"], dtype=float)
        largest = np.abs(ref).max(axis=1, keepdims=True)
        tol = np.broadcast_to(multiplier_rtol(speed)[:, None] * largest, ref.shape)
    elif rule == "exact":
        tol = np.zeros(ref.shape)
    elif rule == "newton_residual":
        tol = None
    else:
        finite = np.abs(ref[np.isfinite(ref)])
        scale = finite.max() if finite.size else 0.0
        if rule == "regular":
            tol = np.full(ref.shape, REGULAR_RTOL * scale)
        elif rule == "horizon":
            tol = np.full(ref.shape, HORIZON_TOL * scale)
        elif rule == "stderr":
            tol = np.maximum(STDERR_RTOL * np.maximum(np.abs(ref), np.abs(new)),
                             REGULAR_RTOL * scale)
        elif rule == "statistic":
            s_ref = np.asarray(entry["sigma"], dtype=float)
            s_new = np.asarray(fresh[2], dtype=float)
            tol = np.maximum(z * np.sqrt(s_ref ** 2 + s_new ** 2), REGULAR_RTOL * scale)
            tol = np.broadcast_to(tol, ref.shape)
        else:
            raise RecipeError(f"{name}: unknown rule {rule}")
    if rule == "newton_residual":
        bad = ~(np.abs(new) <= RESIDUAL_LIMIT)
        tol = np.full(ref.shape, RESIDUAL_LIMIT)
        diff = np.abs(new)
    else:
        both_inf = (ref == new) & ~np.isfinite(ref)
        with np.errstate(invalid="ignore"):
            diff = np.where(both_inf, 0.0, np.abs(new - ref))
        bad = ~(diff <= tol)
    n = int(ref.size)
    if not bad.any():
        return n, []
    worst = np.unravel_index(int(np.argmax(np.where(bad, diff / np.maximum(tol, 1e-300),
                                                    0))), ref.shape)
    where = list(map(int, worst)) if ref.ndim else "scalar"
    what = "its size" if rule == "newton_residual" else "differs by"
    return n, [f"{name}: {int(bad.sum())} of {n} values out of tolerance; worst at {where}: "
               f"{new[worst]!r:.40} (reference {ref[worst]!r:.40}), {what} "
               f"{diff[worst]:.3g} > tolerance {tol[worst]:.3g} (rule {rule}"
               + (f", z = {z:.2f}" if rule == "statistic" else "") + ")"]


def uncovered(keys: list[str], covered: set[str], plan: dict) -> list[str]:
    """Keys of a file that no rule compares and NOT_COMPARED does not explain."""
    left = []
    for key in keys:
        if key in covered:
            continue
        patterns = [p for p in NOT_COMPARED if fnmatch.fnmatchcase(key, p)]
        if not patterns:
            left.append(key)
    return left


def recipe_entries(path: Path, plan: dict) -> tuple[dict, list[str]]:
    """The stored form of one file's values by its plan, and keys left unexplained."""
    with h5py.File(path, "r") as f:
        q, covered = quantities(f, plan)
        left = uncovered(every_key(f), covered, plan)
    entries = {}
    for name, (rule, value, sigma, extra) in q.items():
        entry = {"rule": rule, "value": to_json(value, exact=rule == "exact")}
        if sigma is not None:
            entry["sigma"] = to_json(sigma, exact=False)
        if extra is not None:
            entry["extra"] = to_json(extra, exact=False)
        entries[name] = entry
    return entries, left


def check_recipe(name: str, stored: dict, path: Path) -> tuple[int, list[str]]:
    plan = stored["plan"]
    with h5py.File(path, "r") as f:
        try:
            fresh, covered = quantities(f, plan)
        except (KeyError, ValueError, IndexError) as err:
            return 0, [f"{name}: cannot be read by the reference's plan ({plan['kind']}): {err}"]
        left = uncovered(every_key(f), covered, plan)
    problems = [f"{name}: {key}: in the file, but compared by no rule and not listed in "
                f"NOT_COMPARED" for key in left]
    m = sum(np.size(from_json(e["value"])) for e in stored["values"].values()
            if e["rule"] == "statistic")
    z = sidak_z(m)
    total = 0
    for key, entry in stored["values"].items():
        if key not in fresh:
            problems.append(f"{name}: {key}: missing from the fresh output")
            continue
        n, lines = compare_entry(key, entry, fresh[key], z)
        total += n
        problems += [f"{name}: {line}" for line in lines]
    for key in sorted(set(fresh) - set(stored["values"])):
        problems.append(f"{name}: {key}: new, not in the reference")
    return total, problems


# ---- the two commands ------------------------------------------------------------------------

def largest_exponent(exe: Path, recipe: Path, workdir: Path) -> tuple[float, float]:
    """The largest Lyapunov exponent and its error of a recipe's run (bits per cycle), from
    the same run with one tangent vector: what a chaotic run's horizon needs."""
    run_recipe(exe, recipe, workdir, extra=("--set", "lyapunov.enabled=.true.", "--set",
                                            "lyapunov.vectors=1", "--set",
                                            "run.record_events=.false."), suffix="_lambda1")
    with h5py.File(workdir / f"{recipe.stem}_lambda1.h5", "r") as f:
        return float(f["/lyapunov/exponents"][0]), float(f["/lyapunov/stderr"][0])


def compute(exe: Path, workdir: Path, jobs: int, runs: Path | None) -> dict:
    if runs is None:
        files = run_recipes(exe, workdir, jobs, MACHINE_KERNELS)
    else:
        files = recipe_files(runs)
    reference: dict = {}
    for name, path in files.items():
        with h5py.File(path, "r") as f:
            needs = file_kind(f) == "run" and not (f["/strobe/period"][()] > 0).all() \
                and "lyapunov" not in f
        lambda1 = largest_exponent(exe, RECIPES / f"{name}.nml", workdir) if needs else None
        with h5py.File(path, "r") as f:
            plan = make_plan(f, lambda1)
        entries, left = recipe_entries(path, plan)
        if left:
            raise RecipeError(f"{name}: compared by no rule and not in NOT_COMPARED: "
                              + ", ".join(left))
        reference[name] = {"plan": plan, "values": entries}
    return reference


def recipe_files(runs: Path) -> dict[str, Path]:
    return {r.stem: runs / f"{r.stem}.h5" for r in sorted(RECIPES.glob("*.nml"))}


def check(exe: Path, workdir: Path, jobs: int, kernels: str, reference_file: Path,
          runs: Path | None) -> int:
    stored = json.loads(reference_file.read_text())
    env = SECOND_KERNELS if kernels == "second" else MACHINE_KERNELS
    files = run_recipes(exe, workdir, jobs, env) if runs is None else recipe_files(runs)
    problems, total = [], 0
    for name in sorted(set(stored) | set(files)):
        if name not in files:
            problems.append(f"{name}: in the reference, but there is no namelists/{name}.nml")
        elif name not in stored:
            problems.append(f"{name}: a recipe the reference does not know")
        else:
            n, lines = check_recipe(name, stored[name], files[name])
            total += n
            problems += lines
    for line in problems:
        print(line)
    failed = f"{len(problems)} failure{'s' if len(problems) != 1 else ''}; " if problems else ""
    how = f"the files in {runs}" if runs is not None else f"{kernels} kernels"
    print(f"{failed}{total} values in {len(stored)} recipes within their tolerances ({how})"
          if not problems else
          f"{failed}{total} values compared in {len(stored)} recipes ({how})")
    return 1 if problems else 0


def reference_text(reference: dict) -> str:
    """The reference as JSON, a line per recipe's plan and per value (diffs stay readable)."""
    lines = ["{"]
    for i, name in enumerate(sorted(reference)):
        recipe = reference[name]
        lines.append(f' "{name}": {{')
        lines.append(f'  "plan": {json.dumps(recipe["plan"], sort_keys=True)},')
        lines.append('  "values": {')
        keys = sorted(recipe["values"])
        for j, key in enumerate(keys):
            text = json.dumps(recipe["values"][key], sort_keys=True, separators=(",", ":"))
            lines.append(f"   {json.dumps(key)}: {text}" + ("," if j < len(keys) - 1 else ""))
        lines.append("  }")
        lines.append(" }" + ("," if i < len(reference) - 1 else ""))
    lines.append("}")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    for command, text in (("check", "run every recipe and compare with the reference"),
                          ("compute", "run every recipe and write the reference")):
        sub = commands.add_parser(command, help=text)
        sub.add_argument("--exe", type=Path, help="the simulator (default: the release build)")
        sub.add_argument("--jobs", type=int, default=1, help="recipes run at once")
        sub.add_argument("--reference", type=Path, default=REFERENCE,
                         help="default: test/recipes/reference.json")
        sub.add_argument("--keep", type=Path, metavar="DIR",
                         help="run in DIR (new or empty) and keep the output files")
        sub.add_argument("--runs", type=Path, metavar="DIR",
                         help="take the recipes' files from DIR (`recipe_runs.py run DIR`, or "
                              "an earlier --keep) instead of running them")
        if command == "check":
            sub.add_argument("--kernels", choices=("machine", "second"), default="machine",
                             help="the kernels BLAS and libm select here, or a second code "
                                  "path forced (default: machine)")
    args = parser.parse_args(argv)
    try:
        exe = (args.exe or default_exe()).resolve()
        workdir, temporary = workdir_for(args.keep)
        try:
            if args.command == "check":
                return check(exe, workdir, max(1, args.jobs), args.kernels, args.reference,
                             args.runs)
            reference = compute(exe, workdir, max(1, args.jobs), args.runs)
        finally:
            if temporary is not None:
                temporary.cleanup()
    except RecipeError as err:
        print(f"recipe_reference: {err}", file=sys.stderr)
        return 1
    args.reference.write_text(reference_text(reference))
    values = sum(np.size(from_json(e["value"])) for r in reference.values()
                 for e in r["values"].values())
    print(f"wrote {args.reference}: {values} values in {len(reference)} recipes")
    return 0


if __name__ == "__main__":
    sys.exit(main())
