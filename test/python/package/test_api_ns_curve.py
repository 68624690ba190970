"""api.curve with follow = 'neimark-sacker': an asymmetric chain of two oscillators whose
period-1 branch has a Neimark-Sacker point, its curve in (A, w) from Python the CLI file's
/curve bit for bit, a complex pair on the unit circle at every point; a branch without the
point is a result; a follow value no curve has is the CLI's error."""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from impactchain import api
from test_api import assert_same_bits, cli, namelist, run_cli  # noqa: F401 (fixture)

# spacings 1.3, 1.07, 0.59 (no mirror symmetry): the period-1 orbit from A = 3.13 down has a
# Neimark-Sacker point at A = 2.8863037 (w = 1.6)
CHAIN = dict(n=2, omega=1.6, spacing=[1.3, 1.07, 0.59], restitution=0.87, damping=0.105,
             phase=0.37, transient=300)
BRANCH = dict(parameter="amplitude", stop=2.0, step=-0.05, max_points=8)
CURVE = dict(follow="neimark-sacker", parameter2="omega", stop2=1.8, step2=0.02)


def _namelist(amplitude: float, group: dict[str, Any]) -> str:
    keys = ", ".join(f"{key} = {value!r}" for key, value in group.items())
    return (namelist(**CHAIN, amplitude=amplitude, cycles=1, events=False)
            + f"&continuation {keys} /\n")


def test_ns_curve_is_the_cli_file(cli: Path, tmp_path: Path) -> None:  # noqa: F811
    """The tree's /curve is the file's; it starts at the branch's Neimark-Sacker point and
    has a complex pair of modulus 1 (to 1e-8) at every point."""
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    result = run_cli(cli, _namelist(3.13, {**BRANCH, "max_points": 12, **CURVE}), tmp_path)
    assert result.returncode == 0, result.stderr
    tree = api.curve(**CHAIN, amplitude=3.13, **{**BRANCH, "max_points": 12}, **CURVE)
    with xr.open_datatree(tmp_path / "run.h5", engine="h5netcdf") as files:
        assert_same_bits(tree["curve"].to_dataset(), files["curve"].to_dataset().load())
    curve, branch = tree["curve"], tree["continuation"]
    assert curve.attrs["follow"] == "neimark-sacker" and curve.sizes["curve_point"] == 12
    (ns,) = [j for j, kind in enumerate(branch["special_kind"].values)
             if kind == "neimark-sacker"]
    assert float(curve["values"][0]) == pytest.approx(float(branch["special_value"][ns]),
                                                      abs=1e-10)
    re, im = curve["multipliers_re"].values, curve["multipliers_im"].values
    distance = np.where(im != 0, np.abs(np.hypot(re, im) - 1), np.inf).min(axis=1)
    assert distance.max() < 1e-8


def test_no_ns_point_is_a_result() -> None:
    """The branch stopped above its Neimark-Sacker point: no curve points, the reason, and
    the branch kept."""
    tree = api.curve(**CHAIN, amplitude=3.13, **{**BRANCH, "stop": 3.0}, **CURVE)
    assert tree["curve"].sizes["curve_point"] == 0
    assert tree["curve"].attrs["end_reason"] == "no neimark-sacker located on branch 0"
    assert tree["continuation"].sizes["point"] >= 2


def test_unknown_follow_is_the_clis_error() -> None:
    with pytest.raises(ValueError, match="neimark-sacker"):
        api.curve(**CHAIN, amplitude=3.13, **BRANCH, **{**CURVE, "follow": "torus"})


def test_ns_curve_ends_at_a_1_2_resonance() -> None:
    """A four-oscillator chain's Neimark-Sacker curve followed down in w ends where its pair
    turns real at -1: named a 1:2 resonance, its last pair on the unit circle near -1."""
    chain = dict(n=4, omega=1.13, spacing=[0.76, 1.13, 0.93, 0.6, 0.73], restitution=0.68,
                 damping=0.092, phase=0.39, transient=300)
    tree = api.curve(**chain, amplitude=2.64, parameter="amplitude", stop=1.0, step=-0.05,
                     max_points=300, follow="neimark-sacker", parameter2="omega", stop2=0.5,
                     step2=-0.03)
    curve = tree["curve"]
    assert curve.attrs["end_reason"].startswith("1:2 resonance near amplitude = ")
    re, im = curve["multipliers_re"].values[-1], curve["multipliers_im"].values[-1]
    pair = np.argmin(np.where(im > 0, np.abs(np.hypot(re, im) - 1), np.inf))
    assert abs(np.hypot(re[pair], im[pair]) - 1) < 1e-8
    assert np.hypot(re[pair] + 1, im[pair]) < 0.1
