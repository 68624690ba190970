"""The command line's continuation runs (`&continuation`): bad input named with its key and the
allowed range, exit 1 and no file; a Newton failure written as a result; the /continuation
group's layout; where each branch began; an existing output never overwritten; what Newton
alone found, told."""
from __future__ import annotations

import re

import h5py
import numpy as np
import pytest
import xarray as xr

from impactchain.io import SchemaError, read_run
from simulator import impactchain_exe, run_namelist  # noqa: F401 (fixture)

CHAIN = ("&chain n = 8, spacing = 1.0, damping = 0.05, restitution = 0.5, amplitude = 1.0, "
         "omega = 1.9 /\n&run transient = 5 /\n")

BAD = {
    "unknown parameter": ("parameter = 'mass', stop = 2, step = 0.1",
                          ["parameter = 'mass' is not one of amplitude, omega, damping, "
                           "restitution, spacing"]),
    "step of the wrong sign": ("parameter = 'amplitude', stop = 2, step = -0.1",
                               ["step = -0.1", "sign of stop - start"]),
    "zero step": ("parameter = 'amplitude', stop = 2, step = 0", ["step = 0", "nonzero"]),
    "stop at the start": ("parameter = 'amplitude', stop = 1, step = 0.1",
                          ["stop = 1", "differ from the start"]),
    "step beyond stop": ("parameter = 'amplitude', stop = 1.5, step = 1",
                         ["|step| = 1", "larger than |stop - start|"]),
    "period": ("parameter = 'amplitude', stop = 2, step = 0.1, period = 0",
               ["period = 0", "1..10000"]),
    "max_points": ("parameter = 'amplitude', stop = 2, step = 0.1, max_points = 0",
                   ["max_points = 0", ">= 1"]),
    "doublings": ("parameter = 'amplitude', stop = 2, step = 0.1, doublings = -1",
                  ["doublings = -1", "0..8"]),
    "branch_points": ("parameter = 'amplitude', stop = 2, step = 0.1, branch_points = 5",
                      ["branch_points = 5", "0..4"]),
    "stop out of range": ("parameter = 'restitution', stop = 1.5, step = 0.1",
                          ["&continuation: stop = 1.5", "restitution"]),
    "stop and step missing": ("parameter = 'amplitude'", ["stop and step are required"]),
    "follow without stop2": ("parameter = 'amplitude', stop = 2, step = 0.1, follow = 'fold', "
                             "parameter2 = 'omega', step2 = 0.01",
                             ["&continuation: follow = 'fold'", "parameter2, stop2 and step2"]),
    "follow without parameter2": ("parameter = 'amplitude', stop = 2, step = 0.1, "
                                  "follow = 'fold', stop2 = 2, step2 = 0.01",
                                  ["&continuation: follow = 'fold'",
                                   "parameter2, stop2 and step2"]),
    "follow unknown": ("parameter = 'amplitude', stop = 2, step = 0.1, follow = 'cusp', "
                       "parameter2 = 'omega', stop2 = 2, step2 = 0.01",
                       ["follow = 'cusp'", "fold", "period-doubling"]),
    "parameter2 the parameter": ("parameter = 'amplitude', stop = 2, step = 0.1, "
                                 "follow = 'fold', parameter2 = 'amplitude', stop2 = 2, "
                                 "step2 = 0.01",
                                 ["&continuation: parameter2 = 'amplitude'",
                                  "differ from parameter = 'amplitude'"]),
    "stop2 out of range": ("parameter = 'amplitude', stop = 2, step = 0.1, follow = 'fold', "
                           "parameter2 = 'restitution', stop2 = 1.5, step2 = 0.01",
                           ["&continuation: stop2 = 1.5", "restitution"]),
    "zero step2": ("parameter = 'amplitude', stop = 2, step = 0.1, follow = 'fold', "
                   "parameter2 = 'omega', stop2 = 2, step2 = 0",
                   ["&continuation: step2 = 0", "nonzero"]),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_continuation_input_is_refused(impactchain_exe, tmp_path, case):
    keys, needles = BAD[case]
    text = CHAIN + f"&continuation {keys} /\n&output file = 'bad.h5' /\n"
    result = run_namelist(impactchain_exe, text, tmp_path, check=False)
    assert result.returncode == 1
    for needle in needles:
        assert needle in result.stderr, result.stderr
    assert not list(tmp_path.glob("*.h5*"))


def test_continuation_with_a_sweep_is_refused(impactchain_exe, tmp_path):
    text = (CHAIN + "&continuation parameter = 'amplitude', stop = 2, step = 0.1 /\n"
            "&sweep parameter = 'amplitude', start = 1, stop = 2, step = 0.5 /\n"
            "&output file = 'bad.h5' /\n")
    result = run_namelist(impactchain_exe, text, tmp_path, check=False)
    assert result.returncode == 1
    assert "cannot be combined with &sweep" in result.stderr
    assert not list(tmp_path.glob("*.h5*"))


def test_grazing_branch_file(impactchain_exe, tmp_path):
    """The non-impacting branch of figure 10's chain: its file, read as netCDF by xarray,
    holds the forced response at every point up to the grazing
    A = sqrt((1 - w^2)^2 + (2 b w)^2) (docs/model.md section 12.3), which is stored once, and
    goes on through it onto the orbits with the two impacts of the wall bonds."""
    text = (CHAIN + "&continuation parameter = 'amplitude', stop = 3.5, step = 0.1, "
            "max_points = 30 /\n"
            "&output file = 'branch.h5' /\n")
    result = run_namelist(impactchain_exe, text, tmp_path)
    ds = xr.open_dataset(tmp_path / "branch.h5", engine="h5netcdf", group="continuation")
    assert ds.attrs["parameter"] == "amplitude"
    assert ds.attrs["end_kind"].strip() == "max_points"
    assert "grazing at   2.6169065707434" in result.stdout
    assert "max_points = 30 reached" in result.stdout
    w, b = 1.9, 0.05
    d2 = (1 - w**2) ** 2 + (2 * b * w) ** 2
    kinds = list(ds.special_kind.values.astype(str))
    assert kinds[0] == "grazing"
    assert abs(float(ds.special_value[0]) - np.sqrt(d2)) < 1e-10
    g = int(ds.special_index[0])
    amplitude = ds["values"].values
    assert abs(amplitude[g] - np.sqrt(d2)) < 1e-10
    assert (np.abs(amplitude - np.sqrt(d2)) < 1e-8).sum() == 1   # stored once
    xp = -2 * b * w * amplitude / d2           # the forced response at phase 0: Q
    assert np.allclose(ds.x.values[:g], xp[:g, None], atol=1e-12, rtol=0)
    assert (ds.stable.values[:g + 1] == 1).all()
    assert ((ds.residual.values >= 0) & (ds.residual.values <= 1e-11)).all()
    impacts = ds.impacts_per_period.values
    assert (impacts[:g + 1] == 0).all() and (impacts[g + 1:] == 2).all()
    # (max_points counts the points stepped to; the located special points come on top)
    assert len(amplitude) == 30 + len(kinds) and (amplitude[g + 1:] < np.sqrt(d2)).all()
    assert np.isinf(ds.min_impact_speed.values[:g + 1]).all()
    assert np.isclose(ds.min_impact_speed.values[g + 1], 1e-3, rtol=1e-3)
    assert ds.x.dims == ("point", "oscillator")
    assert ds.multipliers_re.dims == ("point", "multiplier")
    with h5py.File(tmp_path / "branch.h5") as f:
        assert "amplitude" not in f["params"].attrs    # it varies along the branch


def test_newton_failure_is_a_result(impactchain_exe, tmp_path):
    """A start from which Newton cannot converge (figure 10's chain at A = 6, where the
    attractor is not period 1) writes a file with no points and the reason."""
    text = CHAIN.replace("amplitude = 1.0", "amplitude = 6.0").replace("transient = 5",
                                                                        "transient = 250")
    text += ("&continuation parameter = 'amplitude', stop = 5, step = -0.05 /\n"
             "&output file = 'none.h5' /\n")
    result = run_namelist(impactchain_exe, text, tmp_path)
    assert "Newton failed at the start" in result.stdout
    assert "ends: newton" in result.stdout
    with h5py.File(tmp_path / "none.h5") as f:
        assert f["continuation/values"].shape == (0,)
        assert "Newton failed" in f["continuation"].attrs["end_reason"]
        assert f["continuation"].attrs["end_kind"] == "newton"


#: The unstable period-1 orbit with 22 impacts of a chain of 12 (Newton from rest after 500
#: cycles at A = 5).
CHAIN12 = ("&chain n = 12, amplitude = 5.0, omega = 2.3, damping = 0.02, restitution = 0.85, "
           "spacing = 1.0, boundary = 'fixed' /\n&initial kind = 'rest' /\n"
           "&run transient = 500 /\n")


def test_branch_goes_through_a_corner(impactchain_exe, tmp_path):
    """Continued down from A = 5, the orbit reaches a corner near A = 4.8296, where
    oscillator 4 is hit by both neighbours at one instant (the map jumps there): the corner is
    written as a special point (not a grazing: neither monitor is near zero), and the branch
    goes on along the orbits with the 22 impacts in another order to the bound (the run used
    to stop with an error, then to end there)."""
    text = (CHAIN12 + "&continuation parameter = 'amplitude', stop = 4.8, step = -0.01 /\n"
            "&output file = 'corner.h5' /\n")
    result = run_namelist(impactchain_exe, text, tmp_path)
    assert "corner at" in result.stdout and "ends: bound" in result.stdout
    with h5py.File(tmp_path / "corner.h5") as f:
        g = f["continuation"]
        assert g.attrs["end_kind"] == "bound"
        assert [k.decode() for k in g["special_kind"][:]] == ["corner"]
        c = g["special_index"][0]
        assert 8 <= c < g["values"].shape[0] - 1
        assert abs(g["special_value"][0] - 4.8295554) < 1e-6
        assert g["values"][-1] == 4.8
        assert (g["min_gap"][:] > 0.1).all() and (g["min_impact_speed"][:] > 0.1).all()
        assert (g["impacts_per_period"][:] == 22).all()
        # the orbit jumps at the corner: a new family, not a continuation
        jump = np.hypot(np.linalg.norm(g["x"][c + 1] - g["x"][c]),
                        np.linalg.norm(g["v"][c + 1] - g["v"][c]))
        assert jump > 1e-3


def test_corner_beyond_the_bound(impactchain_exe, tmp_path):
    """The same branch to A = 4.84: a step that overshoots both the bound and the corner
    beyond it ends on the bound, where the orbit still has its 22 impacts, as a run with
    ten times smaller steps does."""
    text = (CHAIN12 + "&continuation parameter = 'amplitude', stop = 4.84, step = -0.01 /\n"
            "&output file = 'bound.h5' /\n")
    run_namelist(impactchain_exe, text, tmp_path)
    with h5py.File(tmp_path / "bound.h5") as f:
        g = f["continuation"]
        assert g.attrs["end_kind"] == "bound"
        assert g["values"][-1] == 4.84 and g["impacts_per_period"][-1] == 22


def test_newton_failure_keeps_the_branch(impactchain_exe, tmp_path):
    """Continued in the damping down to 0, the corrector's iterates leave the physical range
    and Newton fails at the smallest step: the branch ends named a Newton failure, with
    every point found before it written."""
    text = (CHAIN12 + "&continuation parameter = 'damping', stop = 0.0, step = -0.005 /\n"
            "&output file = 'newton.h5' /\n")
    result = run_namelist(impactchain_exe, text, tmp_path)
    assert "ends: newton" in result.stdout
    with h5py.File(tmp_path / "newton.h5") as f:
        g = f["continuation"]
        assert g.attrs["end_kind"] == "newton"
        assert "Newton failed at damping" in g.attrs["end_reason"]
        assert g["values"].shape[0] > 10 and g["values"][0] == 0.02


def test_existing_output_is_kept(impactchain_exe, tmp_path):
    (tmp_path / "keep.h5").write_bytes(b"mine")
    text = (CHAIN + "&continuation parameter = 'amplitude', stop = 2, step = 0.1 /\n"
            "&output file = 'keep.h5' /\n")
    result = run_namelist(impactchain_exe, text, tmp_path, check=False)
    assert result.returncode == 1
    assert "exists" in result.stderr
    assert (tmp_path / "keep.h5").read_bytes() == b"mine"


NEWTON_ONLY = ("&continuation parameter = 'amplitude', max_points = 1 /\n"
               "&output file = 'orbit.h5' /\n")


def newton_summary(stdout: str) -> dict[str, str]:
    """The lines 'converged: ...', 'stability: ...', 'impacts per period: ...' by their
    first word(s)."""
    found = {}
    for line in stdout.splitlines():
        name, _, rest = line.strip().partition(": ")
        if name in ("converged", "stability", "impacts per period"):
            found[name] = rest
    return found


def check_against_the_file(stdout: str, path, stable: bool) -> None:
    """The summary says what the file holds of its one orbit."""
    told = newton_summary(stdout)
    with h5py.File(path) as f:
        c = f["continuation"]
        assert c["values"].shape == (1,)
        modulus = np.hypot(c["multipliers_re"][0], c["multipliers_im"][0])
        residual = float(c["residual"][0])
        impacts = int(c["impacts_per_period"][0])
        assert bool(c["stable"][0]) == stable
    steps = re.fullmatch(r"yes, Newton steps (\d+), residual \|P\(z\) - z\| / \(1 \+ \|z\|\) "
                         r"= (\S+)", told["converged"])
    assert steps, told
    assert float(steps.group(2)) == pytest.approx(residual, rel=0.01)
    outside = int((modulus > 1).sum())
    assert (outside > 0) == (not stable)
    want = (f"{'stable' if stable else 'unstable'}, {outside} of {modulus.size} Floquet "
            f"multipliers outside the unit circle, largest modulus ")
    assert told["stability"].startswith(want), told
    assert float(told["stability"][len(want):]) == pytest.approx(modulus.max(), rel=1e-5)
    assert told["impacts per period"] == f"{impacts} (period 1)"


def test_newton_only_tells_a_stable_orbit(impactchain_exe, tmp_path):
    """Issue 32, 8: max_points = 1 says whether Newton converged (steps, residual), the
    orbit's stability with its multipliers outside the unit circle and the largest modulus,
    and its impacts per period (figure 10's chain at A = 3, from rest: stable, 8 impacts)."""
    text = CHAIN.replace("amplitude = 1.0", "amplitude = 3.0") + NEWTON_ONLY
    result = run_namelist(impactchain_exe, text, tmp_path)
    check_against_the_file(result.stdout, tmp_path / "orbit.h5", stable=True)


def test_newton_only_tells_an_unstable_orbit(impactchain_exe, tmp_path):
    """The unstable orbit at A = 3 beyond the fold at A = 2.885 (figure 10's chain: found by
    following the branch from rest round the fold), started from its state: unstable, a
    complex pair outside the unit circle."""
    text = CHAIN.replace("amplitude = 1.0", "amplitude = 3.0")
    fold = text + ("&continuation parameter = 'amplitude', stop = 2.0, step = -0.05 /\n"
                   "&output file = 'fold.h5' /\n")
    run_namelist(impactchain_exe, fold, tmp_path, name="fold.nml")
    with h5py.File(tmp_path / "fold.h5") as f:
        c = f["continuation"]
        assert c["values"][-1] == 3.0 and not c["stable"][-1]
        x, v = c["x"][-1], c["v"][-1]
    start = ("&initial kind = 'explicit', x0 = " + ", ".join(repr(float(a)) for a in x) +
             ", v0 = " + ", ".join(repr(float(a)) for a in v) + " /\n")
    text = text.replace("transient = 5", "transient = 0") + start + NEWTON_ONLY
    result = run_namelist(impactchain_exe, text, tmp_path)
    check_against_the_file(result.stdout, tmp_path / "orbit.h5", stable=False)
    assert "unstable, 2 of 16" in result.stdout


def test_newton_only_tells_a_failure(impactchain_exe, tmp_path):
    """Newton that does not converge (A = 6, the attractor not period 1): 'no', its steps
    and last residual, and no stability."""
    text = CHAIN.replace("amplitude = 1.0", "amplitude = 6.0").replace("transient = 5",
                                                                        "transient = 250")
    result = run_namelist(impactchain_exe, text + NEWTON_ONLY, tmp_path)
    told = newton_summary(result.stdout)
    assert re.fullmatch(r"no, Newton steps \d+, residual .* = \d\.\d\dE[-+]\d\d",
                        told["converged"]), told
    assert told["stability"] == "unknown (no orbit converged)"
    assert "impacts per period" not in told


def test_impact_at_the_section_ends_a_branch(impactchain_exe, tmp_path):
    """Continued in the restitution, an impact of the orbit drifts onto the section (phase 0)
    near K = 0.89847: a gap of the state on the section vanishes and the map of that section
    jumps. The branch ends named so, not as a failure of Newton ("a negative gap")."""
    text = (CHAIN12 + "&continuation parameter = 'restitution', stop = 1.0, step = 0.02 /\n"
            "&output file = 'section.h5' /\n")
    result = run_namelist(impactchain_exe, text, tmp_path)
    assert "ends: section" in result.stdout
    with h5py.File(tmp_path / "section.h5") as f:
        g = f["continuation"]
        assert g.attrs["end_kind"] == "section"
        # (after a branch point on the way: the mirror-symmetric orbit's pitchfork)
        assert [k.decode() for k in g["special_kind"][:]] == ["branch-point", "section"]
        assert g["special_index"][-1] == g["values"].shape[0] - 1
        assert abs(g["special_value"][-1] - 0.8984724) < 1e-6
        x = g["x"][-1]
        gaps = np.r_[1 + x[0], 1 + np.diff(x), 1 - x[-1]]
        assert gaps.min() < 1e-6


def test_branch_point_file(impactchain_exe, tmp_path):
    """Continued up from A = 5, a real multiplier of the mirror-symmetric orbit crosses +1 at
    A = 5.0040468 while the parameter goes on: a branch point, located with a multiplier 1 to
    1e-8; the branch is followed on through it, every orbit on it its own mirror image half a
    drive period later."""
    text = (CHAIN12 + "&continuation parameter = 'amplitude', stop = 5.01, step = 0.001 /\n"
            "&output file = 'bp.h5' /\n")
    result = run_namelist(impactchain_exe, text, tmp_path)
    assert "branch-point at" in result.stdout
    with h5py.File(tmp_path / "bp.h5") as f:
        g = f["continuation"]
        assert g.attrs["end_kind"] == "bound"
        assert [k.decode() for k in g["special_kind"][:]] == ["branch-point"]
        assert abs(g["special_value"][0] - 5.0040468) < 1e-7
        i = g["special_index"][0]
        rho = g["multipliers_re"][i] + 1j * g["multipliers_im"][i]
        assert np.abs(rho - 1).min() < 1e-8
        assert (g["symmetric"][:] == 1).all()
        assert i < g["values"].shape[0] - 1       # the branch goes on through it


def test_switching_at_the_branch_point(impactchain_exe, tmp_path):
    """The same run with branch_points = 1: after branch 0, the two branches crossing at its
    branch point, 1 and 2, each from the branch point's orbit, in /continuation like the
    doubled branches. Their orbits are not their own mirror images (branch 0's are), they
    move off the branch point, and the same steps along the two reach the same A (the suite
    `switch` compares their states by the mirror, by Newton at the same A)."""
    text = (CHAIN12 + "&continuation parameter = 'amplitude', stop = 5.01, step = 0.001, "
            "branch_points = 1 /\n&output file = 'switch.h5' /\n")
    result = run_namelist(impactchain_exe, text, tmp_path)
    assert "branch-point at" in result.stdout
    with h5py.File(tmp_path / "switch.h5") as f:
        g = f["continuation"]
        branch = g["branch"][:]
        assert sorted(set(branch)) == [0, 1, 2]
        assert len(g.attrs["end_kind"].splitlines()) == 3
        kinds = [k.decode() for k in g["special_kind"][:]]
        bp = g["special_index"][kinds.index("branch-point")]
        assert branch[bp] == 0
        one, two = np.flatnonzero(branch == 1), np.flatnonzero(branch == 2)
        for first in (one[0], two[0]):
            assert g["values"][first] == g["values"][bp]
            assert (g["x"][first] == g["x"][bp]).all() and (g["v"][first] == g["v"][bp]).all()
        assert g["parent"][:].tolist() == [-1, 0, 0]
        assert g["origin_point"][:].tolist() == [-1, bp, bp]
        assert [k.decode() for k in g["origin_kind"][:]] == ["", "branch-point", "branch-point"]
        assert (g["symmetric"][:bp + 1] == 1).all()
        assert (g["symmetric"][one[1:]] == 0).all() and (g["symmetric"][two[1:]] == 0).all()
        rho = g["multipliers_re"][:] + 1j * g["multipliers_im"][:]
        assert np.abs(rho[bp] - 1).min() < 1e-8
        # mirror images: the same steps from the branch point reach the same A (to the
        # conditioning of J - I there, a multiplier within 1e-4 of 1), apart in the state
        k = min(len(one), len(two), 6)
        assert np.allclose(g["values"][one[:k]], g["values"][two[:k]], rtol=0, atol=1e-6)
        assert (g["impacts_per_period"][np.r_[one, two]] == 22).all()
        assert np.abs(g["x"][one[k - 1]] - g["x"][two[k - 1]]).max() > 1e-3



FOLD = """&chain n = 8, amplitude = 3.0, omega = 1.9, damping = 0.05, restitution = 0.5,
       spacing = 1.0, boundary = 'fixed' /
&initial kind = 'rest' /
&run transient = 5 /
&continuation parameter = 'amplitude', stop = 2.0, step = -0.05, max_points = 12,
       follow = 'fold', parameter2 = 'omega', stop2 = 1.95, step2 = 0.01 /
&output file = 'curve.h5' /
"""


# a single impact oscillator whose period-1 orbit doubles on the way down from A = 8 (the
# suite `branch`'s), with the period-2 branch switched to there
OSCILLATOR = ("&chain n = 1, spacing = 0.5, 100.0, damping = 0.05, restitution = 0.8, "
              "amplitude = 8.0, omega = 2.5, boundary = 'fixed' /\n&initial kind = 'rest' /\n"
              "&run transient = 1000 /\n&continuation parameter = 'amplitude', stop = 4.5, "
              "step = -0.05, doublings = 1 /\n&output file = 'pd.h5' /\n")


def test_doubled_branch_says_where_it_began(impactchain_exe, tmp_path):
    """With doublings = 1, branch 1 began on branch 0 at its period doubling, whose orbit
    (parameter, state) is branch 1's first point; branch 0 began nowhere (-1, -1, ''). xarray
    sees the three on the dimension branch_index, impactchain.io reads them, and refuses a
    parent that is not an earlier branch."""
    run_namelist(impactchain_exe, OSCILLATOR, tmp_path)
    with xr.open_dataset(tmp_path / "pd.h5", engine="h5netcdf", group="continuation") as ds:
        assert ds.parent.dims == ds.origin_point.dims == ds.origin_kind.dims == ("branch_index",)
        assert ds.branch_index.values.tolist() == [0, 1]
        assert ds.parent.values.tolist() == [-1, 0]
        assert list(ds.origin_kind.values) == ["", "period-doubling"]
        kinds = list(ds.special_kind.values)
        pd = int(ds.special_index[kinds.index("period-doubling")])
        assert ds.origin_point.values.tolist() == [-1, pd]
        assert int(ds.branch[pd]) == 0 and int(ds.period[pd]) == 1
        first = int(np.flatnonzero(ds.branch.values == 1)[0])
        assert int(ds.period[first]) == 2
        assert float(ds["values"][first]) == float(ds["values"][pd])
        for name in ("x", "v"):
            assert np.abs(ds[name][first] - ds[name][pd]).max() <= 1e-10
    cont = read_run(tmp_path / "pd.h5").continuation
    assert cont.parent.tolist() == [-1, 0] and cont.origin_point.tolist() == [-1, pd]
    assert cont.origin_kind.tolist() == ["", "period-doubling"]
    with h5py.File(tmp_path / "pd.h5", "r+") as f:
        f["continuation/parent"][1] = 1
    with pytest.raises(SchemaError, match="parent holds a branch that is not an earlier one"):
        read_run(tmp_path / "pd.h5")


def test_fold_curve_file(impactchain_exe, tmp_path):
    """Figure 10's fold (namelists/fig10_fold.nml) followed in (A, w) (docs/model.md 12.6):
    /curve starts at the located fold, has a multiplier +1 at every point and runs towards
    stop2."""
    run_namelist(impactchain_exe, FOLD, tmp_path)
    with h5py.File(tmp_path / "curve.h5") as f:
        cont, curve = f["continuation"], f["curve"]
        kinds = list(cont["special_kind"][:].astype(str))
        fold = cont["special_value"][kinds.index("fold")]
        assert {k: curve.attrs[k].decode() if isinstance(curve.attrs[k], bytes) else
                curve.attrs[k] for k in ("follow", "parameter", "parameter2")} == {
            "follow": "fold", "parameter": "amplitude", "parameter2": "omega"}
        values, values2 = curve["values"][:], curve["values2"][:]
        assert len(values) == 12
        # (the curve refines its start at fixed w, to the one-parameter fold's accuracy)
        assert abs(values[0] - fold) < 1e-8 and values2[0] == 1.9
        assert np.all(np.diff(values2) > 0) and values2[-1] <= 1.95
        m = curve["multipliers_re"][:] + 1j * curve["multipliers_im"][:]
        assert curve["x"].shape == (12, 8) and m.shape == (12, 16)
        assert np.abs(m - 1).min(axis=1).max() < 1e-6


GRAZING = """&chain n = 8, amplitude = 1.0, omega = 1.9, damping = 0.05, restitution = 0.5,
       spacing = 1.0, boundary = 'fixed' /
&initial kind = 'rest' /
&run transient = 5 /
&continuation parameter = 'amplitude', stop = 3.0, step = 0.1, max_points = 20,
       follow = 'grazing', parameter2 = 'omega', stop2 = 1.2, step2 = -0.25 /
&output file = 'grazing.h5' /
"""


def test_grazing_curve_file(impactchain_exe, tmp_path):
    """Figure 10's grazing from rest (namelists/fig10_free.nml) followed in (A, w)
    (docs/model.md 12.6): /curve starts at the located grazing and lies on the closed form
    A = a sqrt((1 - w**2)**2 + (2 b w)**2) at every point, the forced response touching
    both walls."""
    run_namelist(impactchain_exe, GRAZING, tmp_path)
    with h5py.File(tmp_path / "grazing.h5") as f:
        cont, curve = f["continuation"], f["curve"]
        kinds = list(cont["special_kind"][:].astype(str))
        grazing = cont["special_value"][kinds.index("grazing")]
        follow = curve.attrs["follow"]
        assert (follow.decode() if isinstance(follow, bytes) else follow) == "grazing"
        values, values2 = curve["values"][:], curve["values2"][:]
        assert abs(values[0] - grazing) < 1e-10 and values2[0] == 1.9
        assert len(values) >= 3 and np.all(np.diff(values2) < 0)
        assert np.abs(values - np.hypot(1 - values2**2, 2 * 0.05 * values2)).max() < 1e-10


def test_no_point_to_follow_is_said(impactchain_exe, tmp_path):
    """A branch without a fold: /curve has no points and says why; the run succeeds."""
    text = (CHAIN + "&continuation parameter = 'amplitude', stop = 1.2, step = 0.05, "
            "max_points = 4, follow = 'fold', parameter2 = 'omega', stop2 = 2, step2 = 0.01 /\n"
            "&output file = 'none.h5' /\n")
    run_namelist(impactchain_exe, text, tmp_path)
    with h5py.File(tmp_path / "none.h5") as f:
        assert f["curve"]["values"].shape == (0,)
        reason = f["curve"].attrs["end_reason"]
        assert "no fold" in (reason.decode() if isinstance(reason, bytes) else reason)


def test_branch_point_curve_file(impactchain_exe, tmp_path):
    """The chain of 12's branch point (A = 5.0040468 at w = 2.3) followed in (A, w) with
    follow = 'branch-point' (docs/model.md 12.6): /curve starts at the located branch point,
    has a real multiplier +1 at every point (the suite `bpcurve` checks the orbits' symmetry,
    the eigenvector's oddness and the one-parameter branch points along it) and ends at
    stop2."""
    text = (CHAIN12 + "&continuation parameter = 'amplitude', stop = 5.01, step = 0.001, "
            "follow = 'branch-point', parameter2 = 'omega', stop2 = 2.302, step2 = 0.005 /\n"
            "&output file = 'bpcurve.h5' /\n")
    run_namelist(impactchain_exe, text, tmp_path)
    with h5py.File(tmp_path / "bpcurve.h5") as f:
        cont, curve = f["continuation"], f["curve"]
        kinds = list(cont["special_kind"][:].astype(str))
        bp = cont["special_value"][kinds.index("branch-point")]
        attrs = {k: curve.attrs[k].decode() if isinstance(curve.attrs[k], bytes) else
                 curve.attrs[k] for k in ("follow", "parameter", "parameter2", "end_reason")}
        assert attrs == {"follow": "branch-point", "parameter": "amplitude",
                         "parameter2": "omega", "end_reason": "bound"}
        values, values2 = curve["values"][:], curve["values2"][:]
        assert abs(values[0] - bp) < 1e-8 and values2[0] == 2.3
        assert len(values) >= 2 and np.all(np.diff(values2) > 0) and values2[-1] <= 2.302
        rho = curve["multipliers_re"][:] + 1j * curve["multipliers_im"][:]
        assert curve["x"].shape == (len(values), 12) and rho.shape == (len(values), 24)
        assert np.abs(rho - 1).min(axis=1).max() < 1e-8
        assert curve["codim2_index"].shape == (0,)


def test_no_branch_point_to_follow_is_said(impactchain_exe, tmp_path):
    """follow = 'branch-point' on a branch without one: /curve has no points and says why;
    the branch is written, the run succeeds."""
    text = (CHAIN + "&continuation parameter = 'amplitude', stop = 1.2, step = 0.05, "
            "max_points = 4, follow = 'branch-point', parameter2 = 'omega', stop2 = 2, "
            "step2 = 0.01 /\n&output file = 'none.h5' /\n")
    run_namelist(impactchain_exe, text, tmp_path)
    with h5py.File(tmp_path / "none.h5") as f:
        assert f["continuation"]["values"].shape == (4,)
        assert f["curve"]["values"].shape == (0,)
        reason = f["curve"].attrs["end_reason"]
        reason = reason.decode() if isinstance(reason, bytes) else reason
        assert reason == "no branch-point located on branch 0"
