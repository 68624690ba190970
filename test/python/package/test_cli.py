"""The command line: ``python -m impactchain``, in-process and as a subprocess."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure

from impactchain import cli
from impactchain.cli import COMMANDS, main
from impactchain.io import read_run

MakeRun = Callable[..., Path]


def _run_module(*args: str | Path) -> subprocess.CompletedProcess[str]:
    """``python -m impactchain ARGS``: the installed package, as a user runs it."""
    env = {**os.environ, "MPLBACKEND": "Agg"}
    return subprocess.run([sys.executable, "-m", "impactchain", *map(str, args)],
                          capture_output=True, text=True, env=env, timeout=60, check=False)


def _error_line(stderr: str) -> str:
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    assert lines[0].startswith("impactchain: error: ")
    return lines[0]


# ----------------------------------------------------------------------- subprocess


def test_help_lists_every_figure() -> None:
    result = _run_module("--help")
    assert result.returncode == 0
    for name in (*COMMANDS, "all"):
        assert name in result.stdout


def test_module_writes_png(run_file: Path, tmp_path: Path) -> None:
    out = tmp_path / "sa.png"
    result = _run_module("space-amplitude", run_file, "-o", out)
    assert result.returncode == 0, result.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_module_missing_file(tmp_path: Path) -> None:
    out = tmp_path / "x.png"
    result = _run_module("poincare", tmp_path / "absent.h5", "-o", out)
    assert result.returncode == 2
    assert "absent.h5: no such file" in _error_line(result.stderr)
    assert "Traceback" not in result.stderr and not out.exists()


def test_module_figure_needing_absent_data(make_run: MakeRun, tmp_path: Path) -> None:
    out = tmp_path / "x.png"
    result = _run_module("shock-wave", make_run(events=False), "-o", out)
    assert result.returncode == 2
    assert "no /events, needed by shock-wave" in _error_line(result.stderr)
    assert not out.exists()


# ------------------------------------------------------------------------ in-process


@pytest.mark.parametrize(
    ("figure", "options"),
    [
        ("space-amplitude", ["--cycles", "5", "--periods", "none"]),
        ("space-time-amplitude", ["--panel-cycles", "10", "--panels", "2"]),
        ("shock-wave", ["--panel-cycles", "10", "--max-wait", "0.5"]),
        ("poincare", ["--site", "2", "--cycles", "10"]),
        ("spectrum", []),
    ],
)
def test_run_figures(figure: str, options: list[str], run_file: Path, tmp_path: Path) -> None:
    out = tmp_path / f"{figure}.png"
    assert main([figure, str(run_file), "-o", str(out), *options]) == 0
    assert out.stat().st_size > 0


@pytest.mark.parametrize(
    ("figure", "options"),
    [
        ("bifurcation", ["--sites", "1,3"]),
        ("lyapunov", ["--k", "3", "--with-bifurcation"]),
        ("ky-dimension", []),
    ],
)
def test_sweep_figures(figure: str, options: list[str], sweep_file: Path, tmp_path: Path) -> None:
    out = tmp_path / f"{figure}.pdf"
    assert main([figure, str(sweep_file), "-o", str(out), *options]) == 0
    assert out.read_bytes()[:5] == b"%PDF-"


def _captured(monkeypatch: pytest.MonkeyPatch) -> dict[str, Figure]:
    """Figures the CLI would write, by output name, instead of writing them."""
    figures: dict[str, Figure] = {}

    def keep(figure: Figure, out: Path, dpi: float = 150) -> None:
        del dpi
        figures[Path(out).name] = figure

    monkeypatch.setattr(cli, "_save", keep)
    return figures


def _period_labels(figure: Figure) -> list[str]:
    return [t.get_text() for t in figure.axes[0].texts if t.get_gid() == "period"]


def test_periods_shown_are_the_stored_ones(make_run: MakeRun, tmp_path: Path,
                                           monkeypatch: pytest.MonkeyPatch) -> None:
    """The strobe records of the fixture have periods 1, 2, 4 and none; the file says
    3, 0, 1, 2, and the labels of space-amplitude (alone and in `all`) must say so too."""
    path = str(make_run(n=4, records=20, periods=[3, 0, 1, 2]))
    made = _captured(monkeypatch)
    assert main(["space-amplitude", path, "-o", str(tmp_path / "sa.png"), "--cycles", "8"]) == 0
    assert main(["all", path, "-o", str(tmp_path / "r")]) == 0
    assert _period_labels(made["sa.png"]) == ["P3", "ap", "P1", "P2"]
    assert _period_labels(made["r_space_amplitude.png"]) == ["P3", "ap", "P1", "P2"]


def test_ky_dimension_shown_is_the_stored_one(sweep_file: Path, tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    """The fixture's /sweep/ky_dimension is not the dimension of its /sweep/exponents."""
    made = _captured(monkeypatch)
    assert main(["ky-dimension", str(sweep_file), "-o", str(tmp_path / "ky.png")]) == 0
    assert main(["all", str(sweep_file), "-o", str(tmp_path / "s")]) == 0
    stored = read_run(sweep_file).sweep
    assert stored is not None and stored.ky_dimension is not None
    for name in ("ky.png", "s_ky_dimension.png"):
        (line,) = [ln for ln in made[name].axes[0].get_lines() if ln.get_gid() == "ky"]
        np.testing.assert_array_equal(line.get_ydata(), stored.ky_dimension)


def test_overlay_of_several_files(make_run: MakeRun, tmp_path: Path) -> None:
    files = [str(make_run("red.h5")), str(make_run("green.h5"))]
    out = tmp_path / "multi.png"
    assert main(["space-amplitude", *files, "-o", str(out)]) == 0
    assert out.exists()


def test_output_directory_is_created(run_file: Path, tmp_path: Path) -> None:
    out = tmp_path / "new" / "dir" / "fig.png"
    assert main(["poincare", str(run_file), "-o", str(out)]) == 0
    assert out.exists()
    assert [p.name for p in out.parent.iterdir()] == ["fig.png"]


def test_all_writes_every_supported_figure(run_file: Path, tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    prefix = tmp_path / "figs" / "run"
    assert main(["all", str(run_file), "-o", str(prefix), "--panel-cycles", "15"]) == 0
    names = sorted(p.name for p in prefix.parent.iterdir())
    assert names == ["run_poincare.png", "run_shock_wave.png", "run_space_amplitude.png",
                     "run_space_time_amplitude.png", "run_spectrum.png"]
    assert len(capsys.readouterr().out.splitlines()) == 5


def test_all_skips_shock_wave_without_events(make_run: MakeRun, tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    path = make_run(events=False)
    assert main(["all", str(path), "-o", str(tmp_path / "r.pdf")]) == 0
    assert "skipped shock-wave" in capsys.readouterr().err
    assert (tmp_path / "r_space_amplitude.pdf").exists()
    assert not (tmp_path / "r_shock_wave.pdf").exists()


def _expect_error(argv: list[str], message: str, out: Path,
                  capsys: pytest.CaptureFixture[str]) -> None:
    assert main([*argv, "-o", str(out)]) == 2
    assert message in _error_line(capsys.readouterr().err)
    assert not out.exists()


def test_error_not_hdf5(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "notes.h5"
    path.write_text("hello\n")
    _expect_error(["space-amplitude", str(path)], "not an HDF5 file", tmp_path / "o.png", capsys)


def test_error_wrong_schema(make_run: MakeRun, tmp_path: Path,
                            capsys: pytest.CaptureFixture[str]) -> None:
    path = make_run(schema_version=7)
    _expect_error(["space-amplitude", str(path)], "schema_version 7 is not supported",
                  tmp_path / "o.png", capsys)


def test_error_bifurcation_without_sweep(run_file: Path, tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    _expect_error(["bifurcation", str(run_file)], "no /sweep, needed by bifurcation",
                  tmp_path / "o.png", capsys)


def test_error_lyapunov_without_exponents(make_run: MakeRun, tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    path = make_run(sweep={"exponents": 0})
    _expect_error(["lyapunov", str(path)], "no /sweep/exponents", tmp_path / "o.png", capsys)


def test_error_ky_dimension_without_stored_dimensions(make_run: MakeRun, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    """The exponents alone are not enough: the dimension is never computed from them."""
    path = make_run(sweep={"ky_dimension": False})
    _expect_error(["ky-dimension", str(path)], "no /sweep/ky_dimension", tmp_path / "o.png",
                  capsys)
    assert main(["all", str(path), "-o", str(tmp_path / "r")]) == 0
    assert not (tmp_path / "r_ky_dimension.png").exists()
    assert (tmp_path / "r_lyapunov.png").exists()


def test_error_spectrum_without_lyapunov(make_run: MakeRun, tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    _expect_error(["spectrum", str(make_run())], "no /lyapunov", tmp_path / "o.png", capsys)


def test_error_site_out_of_range(run_file: Path, tmp_path: Path,
                                 capsys: pytest.CaptureFixture[str]) -> None:
    _expect_error(["poincare", str(run_file), "--site", "9"], "site 9 is outside 1..4",
                  tmp_path / "o.png", capsys)


def test_error_unknown_output_format(run_file: Path, tmp_path: Path,
                                     capsys: pytest.CaptureFixture[str]) -> None:
    _expect_error(["poincare", str(run_file)], "must end in .png", tmp_path / "o.jpg", capsys)


def test_error_in_one_of_several_files(make_run: MakeRun, tmp_path: Path,
                                       capsys: pytest.CaptureFixture[str]) -> None:
    good = make_run("good.h5")
    _expect_error(["space-amplitude", str(good), str(tmp_path / "bad.h5")], "no such file",
                  tmp_path / "o.png", capsys)


def test_bad_option_is_a_usage_error(run_file: Path, tmp_path: Path) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["space-time-amplitude", str(run_file), "-o", str(tmp_path / "o.png"),
              "--panels", "0"])
    assert exit_info.value.code == 2


def test_periods_are_never_detected(run_file: Path, tmp_path: Path) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["space-amplitude", str(run_file), "-o", str(tmp_path / "o.png"),
              "--periods", "detect"])
    assert exit_info.value.code == 2


def test_single_file_figures_take_one_file(run_file: Path, tmp_path: Path) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["poincare", str(run_file), str(run_file), "-o", str(tmp_path / "o.png")])
    assert exit_info.value.code == 2


# ------------------------------------------------------------------ resolution, formats


def test_png_has_the_resolution_and_the_metadata(make_run: MakeRun, tmp_path: Path) -> None:
    from PIL import Image

    path = make_run(n=4, seed=4)
    default, sharp = tmp_path / "default.png", tmp_path / "sharp.png"
    assert main(["poincare", str(path), "-o", str(default)]) == 0
    assert main(["poincare", str(path), "-o", str(sharp), "--dpi", "300"]) == 0
    with Image.open(default) as image:
        assert image.info["dpi"] == pytest.approx((150, 150), abs=0.05)
        assert image.size == (6 * 150, 5 * 150)
        text = dict(image.text)
    with Image.open(sharp) as image:
        assert image.info["dpi"] == pytest.approx((300, 300), abs=0.05)
    assert text["Software"].startswith("impactchain 0.1.0; impactchain.figures ")
    assert text["Source"] == str(path)
    assert text["Description"].startswith(f"! source: {path}\n&chain")
    assert "seed = 4" in text["Description"]
    assert not list(tmp_path.glob(".*partial"))


def test_format_option_writes_pdf(run_file: Path, tmp_path: Path) -> None:
    assert main(["spectrum", str(run_file), "-o", str(tmp_path / "spec"), "--format",
                 "pdf"]) == 0
    pdf = (tmp_path / "spec.pdf").read_bytes()
    assert pdf.startswith(b"%PDF-") and b"/Creator (impactchain 0.1.0" in pdf
    assert main(["poincare", str(run_file), "-o", str(tmp_path / "p.pdf"), "--format",
                 "pdf"]) == 0
    assert (tmp_path / "p.pdf").read_bytes().startswith(b"%PDF-")
    assert main(["all", str(run_file), "-o", str(tmp_path / "all" / "r"), "--format",
                 "pdf"]) == 0
    assert sorted(p.suffix for p in (tmp_path / "all").iterdir()) == [".pdf"] * 5


def test_format_and_extension_must_agree(run_file: Path, tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    _expect_error(["poincare", str(run_file), "--format", "pdf"],
                  "does not end in .pdf (--format pdf)", tmp_path / "o.png", capsys)
    with pytest.raises(SystemExit):
        main(["poincare", str(run_file), "-o", str(tmp_path / "o.png"), "--dpi", "0"])


def test_ylim_option(run_file: Path, sweep_file: Path, tmp_path: Path,
                     monkeypatch: pytest.MonkeyPatch) -> None:
    made = _captured(monkeypatch)
    assert main(["space-amplitude", str(run_file), "-o", str(tmp_path / "sa.png"),
                 "--ylim=-2.5,1.5"]) == 0
    assert main(["ky-dimension", str(sweep_file), "-o", str(tmp_path / "ky.png"),
                 "--ylim", "0,11"]) == 0
    assert made["sa.png"].axes[0].get_ylim() == (-2.5, 1.5)
    assert made["ky.png"].axes[0].get_ylim() == (0.0, 11.0)
    with pytest.raises(SystemExit):
        main(["ky-dimension", str(sweep_file), "-o", str(tmp_path / "x.png"), "--ylim", "3,1"])


# -------------------------------------------------------------- covariant vectors


def test_clv_figures(make_run: MakeRun, tmp_path: Path,
                     monkeypatch: pytest.MonkeyPatch) -> None:
    path = str(make_run(n=4, records=40, clv={"transient": 10, "store": 3}))
    made = _captured(monkeypatch)
    assert main(["clv-space-time", path, "-o", str(tmp_path / "st.png"), "--vector", "1,3",
                 "--start", "105", "--cycles", "12"]) == 0
    assert main(["clv-ipr", path, "-o", str(tmp_path / "ipr.png")]) == 0
    assert main(["clv-angles", path, "-o", str(tmp_path / "a.png"), "--bins", "9",
                 "--near", "0.2"]) == 0
    left, right = [ax for ax in made["st.png"].axes if ax.get_label() != "<colorbar>"]
    assert left.get_title().startswith("vector 1:") and right.get_title().startswith("vector 3:")
    assert left.get_ylim() == pytest.approx((104.5, 116.5))
    assert "below 0.2 rad" in made["a.png"].axes[0].get_title()
    assert len(made["a.png"].axes[0].patches) == 9
    assert main(["all", path, "-o", str(tmp_path / "r")]) == 0
    assert {"r_clv_space_time.png", "r_clv_ipr.png", "r_clv_angles.png"} <= set(made)


def test_clv_errors(make_run: MakeRun, run_file: Path, tmp_path: Path,
                    capsys: pytest.CaptureFixture[str]) -> None:
    _expect_error(["clv-ipr", str(run_file)], "no /clv, needed by clv-ipr", tmp_path / "o.png",
                  capsys)
    bare = str(make_run("bare.h5", clv={"store": 0}))
    _expect_error(["clv-space-time", bare], "no /clv/site_weight, needed by clv-space-time",
                  tmp_path / "o.png", capsys)
    path = str(make_run("clv.h5", clv=True))
    _expect_error(["clv-space-time", path, "--vector", "4"], "vector 4 is outside 1..2",
                  tmp_path / "o.png", capsys)
    assert main(["all", bare, "-o", str(tmp_path / "b")]) == 0
    assert "skipped clv-space-time" in capsys.readouterr().err
    assert (tmp_path / "b_clv_ipr.png").exists()
    assert not (tmp_path / "b_clv_space_time.png").exists()


def test_examples_are_copied_out_and_never_over_a_users_file(tmp_path: Path) -> None:
    """Issue 32, 6: `python -m impactchain examples DIR` copies the installed recipes of the
    paper's figures, the example scripts and the tutorial notebooks; a second time it
    refuses, naming a file that exists and copying nothing, unless --overwrite."""
    root = Path(__file__).resolve().parents[3]
    target = tmp_path / "mine"
    done = subprocess.run([sys.executable, "-m", "impactchain", "examples", str(target)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    recipes = sorted(p.name for p in (root / "namelists").glob("*.nml"))
    assert sorted(p.name for p in (target / "namelists").glob("*.nml")) == recipes
    assert ((target / "namelists" / "default.nml").read_text()
            == (root / "namelists" / "default.nml").read_text())
    assert (target / "fig1c_space_amplitude.py").exists()
    tutorials = sorted(p.name for p in (root / "docs" / "tutorials").glob("*.ipynb"))
    assert len(tutorials) >= 4
    assert sorted(p.name for p in (target / "tutorials").glob("*.ipynb")) == tutorials
    assert ((target / "tutorials" / tutorials[0]).read_bytes()
            == (root / "docs" / "tutorials" / tutorials[0]).read_bytes())
    (target / "namelists" / "default.nml").write_text("! my own\n")
    again = subprocess.run([sys.executable, "-m", "impactchain", "examples", str(target)],
                           capture_output=True, text=True, timeout=120)
    assert again.returncode == 2 and "nothing was copied (--overwrite" in again.stderr
    assert (target / "namelists" / "default.nml").read_text() == "! my own\n"
    forced = subprocess.run([sys.executable, "-m", "impactchain", "examples", str(target),
                             "--overwrite"], capture_output=True, text=True, timeout=120)
    assert forced.returncode == 0, forced.stderr
    assert ((target / "namelists" / "default.nml").read_text()
            == (root / "namelists" / "default.nml").read_text())
