"""api.curve: a fold followed in two parameters from Python is the CLI file's /continuation
and /curve as xarray.open_datatree reads them, bit for bit; a branch without the point is a
result; the kernel's outputs are in the documented order."""
from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from impactchain import _calls, api
from test_api import FIG10, assert_same_bits, cli, namelist, run_cli  # noqa: F401 (fixture)

# Figure 10's fold (A = 2.885 at w = 1.9, namelists/fig10_fold.nml) followed in w
FOLD = dict(parameter="amplitude", stop=2.0, step=-0.05, max_points=12)
CURVE = dict(follow="fold", parameter2="omega", stop2=1.95, step2=0.01)


def _namelist(amplitude: float, group: dict[str, Any]) -> str:
    keys = ", ".join(f"{key} = {value!r}" for key, value in group.items())
    return (namelist(**{**FIG10, "amplitude": amplitude}, cycles=1, events=False)
            + f"&continuation {keys} /\n")


def _file_tree(path: Path) -> Any:
    xr = pytest.importorskip("xarray")
    with xr.open_datatree(path, engine="h5netcdf") as tree:
        return {group: tree[group].to_dataset().load() for group in ("continuation", "curve")}


def test_curve_is_the_cli_file(cli: Path, tmp_path: Path) -> None:  # noqa: F811
    """The tree's two groups are the file's: names, dimensions, attributes, every value."""
    pytest.importorskip("h5netcdf")
    result = run_cli(cli, _namelist(3.0, {**FOLD, **CURVE}), tmp_path)
    assert result.returncode == 0, result.stderr
    tree = api.curve(**FIG10, amplitude=3.0, **FOLD, **CURVE)
    assert set(tree.children) == {"continuation", "curve"}
    files = _file_tree(tmp_path / "run.h5")
    for group in ("continuation", "curve"):
        assert_same_bits(tree[group].to_dataset(), files[group])
    curve = tree["curve"]
    assert curve.sizes["curve_point"] == 12 and curve.attrs["parameter2"] == "omega"
    assert abs(float(curve["values"][0]) - 2.8851913052) < 1e-8


def test_curve_keeps_the_continuation(cli: Path, tmp_path: Path) -> None:  # noqa: F811
    """/continuation of a curve's tree is api.continuation's for the same branch."""
    tree = api.curve(**FIG10, amplitude=3.0, **FOLD, **CURVE)
    assert_same_bits(tree["continuation"].to_dataset(),
                     api.continuation(**FIG10, amplitude=3.0, **FOLD))


def test_no_point_to_follow_is_a_result() -> None:
    """The forced response below its grazing has no fold: no points, and the reason."""
    tree = api.curve(**FIG10, amplitude=1.0, parameter="amplitude", stop=1.2, step=0.05,
                     max_points=4, **CURVE)
    assert tree["curve"].sizes["curve_point"] == 0
    assert "no fold" in tree["curve"].attrs["end_reason"]


def test_no_branch_point_to_follow_is_a_result() -> None:
    """follow = 'branch-point' from Python: the forced response has none, no points, and the
    reason (the curve itself: the suite `bpcurve` and test_continuation_cli.py)."""
    tree = api.curve(**FIG10, amplitude=1.0, parameter="amplitude", stop=1.2, step=0.05,
                     max_points=4, **{**CURVE, "follow": "branch-point"})
    assert tree["continuation"].sizes["point"] == 4
    assert tree["curve"].sizes["curve_point"] == 0
    assert tree["curve"].attrs["follow"] == "branch-point"
    assert tree["curve"].attrs["end_reason"] == "no branch-point located on branch 0"


def test_bad_curve_keys_are_the_clis_errors() -> None:
    with pytest.raises(ValueError, match="step2 = 0"):
        api.curve(**FIG10, amplitude=3.0, **FOLD, **{**CURVE, "step2": 0.0})
    with pytest.raises(ValueError, match="parameter2 = 'amplitude'"):
        api.curve(**FIG10, amplitude=3.0, **FOLD, **{**CURVE, "parameter2": "amplitude"})


def test_curve_outputs_in_documented_order() -> None:
    """api.CURVE_OUTPUTS names the tuple f2py returns; a reordered layer must fail here."""
    first_line = _calls._extension().ic_curve.__doc__.splitlines()[0]
    assert tuple(first_line.split(" = ")[0].split(",")) == api.CURVE_OUTPUTS


def test_io_reads_the_curve(cli: Path, tmp_path: Path) -> None:  # noqa: F811
    """impactchain.io reads /curve (read_curve, Run.curve) as the file holds it."""
    from impactchain import io

    result = run_cli(cli, _namelist(3.0, {**FOLD, **CURVE}), tmp_path)
    assert result.returncode == 0, result.stderr
    curve = io.read_curve(tmp_path / "run.h5")
    assert (curve.follow, curve.parameter, curve.parameter2) == ("fold", "amplitude", "omega")
    assert curve.values.shape == (12,) and curve.x.shape == (12, 8)
    assert abs(curve.multipliers - 1).min(axis=1).max() < 1e-6
    assert io.read_run(tmp_path / "run.h5").curve is not None
    result = run_cli(cli, _namelist(3.0, FOLD), tmp_path)
    assert result.returncode == 0, result.stderr
    with pytest.raises(io.SchemaError, match="no &continuation follow"):
        io.read_curve(tmp_path / "run.h5")


def test_grazing_curve_is_the_closed_form() -> None:
    """Figure 10's grazing of its forced response, followed in w from Python: every point on
    A = a sqrt((1 - w**2)**2 + (2 b w)**2) (docs/model.md 12.6)."""
    np = pytest.importorskip("numpy")
    tree = api.curve(**FIG10, amplitude=1.0, parameter="amplitude", stop=3.0, step=0.1,
                     max_points=20, follow="grazing", parameter2="omega", stop2=1.2,
                     step2=-0.25)
    curve = tree["curve"]
    assert curve.attrs["follow"] == "grazing" and curve.sizes["curve_point"] >= 3
    a, w = curve["values"].values, curve["values2"].values
    assert np.abs(a - np.hypot(1 - w**2, 2 * 0.05 * w)).max() < 1e-10


# Two oscillators, unequal spacings (no mirror symmetry): the first period doubling from rest
# at A = 0.3, w = 1.4 upwards, followed up in w (docs/model.md 12.6, suite codim2)
TWO = dict(n=2, omega=1.4, damping=0.02, restitution=0.8, spacing=[1.0, 0.7, 1.3],
           transient=20)
DOUBLING = dict(parameter="amplitude", stop=6.0, step=0.05, max_points=300)
DOUBLING_CURVE = dict(follow="period-doubling", parameter2="omega", stop2=2.6, step2=0.03)


def test_codim2_points_in_the_file(cli: Path, tmp_path: Path) -> None:  # noqa: F811
    """The fold-flip and 1:2 points of the doubling curve are stored in the file's /curve as
    curve points, named as documented, their multipliers +1 and -1 (fold-flip), twice -1 (1:2);
    the api's tree is the file's."""
    pytest.importorskip("h5netcdf")
    text = (namelist(**{**TWO, "amplitude": 0.3}, cycles=1, events=False)
            + "&continuation " + ", ".join(f"{key} = {value!r}" for key, value in
                                           {**DOUBLING, **DOUBLING_CURVE}.items()) + " /\n")
    result = run_cli(cli, text, tmp_path)
    assert result.returncode == 0, result.stderr
    curve = _file_tree(tmp_path / "run.h5")["curve"]
    assert list(curve["codim2_kind"].values) == ["fold-flip", "1:2"]
    multipliers = curve["multipliers_re"].values + 1j * curve["multipliers_im"].values
    flip, resonance = (multipliers[int(i)] for i in curve["codim2_index"].values)
    assert min(abs(flip - 1)) < 1e-8 and min(abs(flip + 1)) < 1e-8
    assert sorted(abs(resonance + 1))[1] < 1e-5
    tree = api.curve(**TWO, amplitude=0.3, **DOUBLING, **DOUBLING_CURVE)
    assert_same_bits(tree["curve"].to_dataset(), curve)
