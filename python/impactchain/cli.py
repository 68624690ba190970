"""Command line: ``python -m impactchain <figure> FILE.h5 [FILE2.h5 ...] -o out.png``.

The format is the output's extension (``.png``, ``.pdf``, ``.svg``) or ``--format``
(which adds the extension when the output has none); PNG at ``--dpi`` (default 150). Every
file carries the code version, the input namelists and the source file names in its
metadata (:func:`impactchain.figures.metadata`).

``python -m impactchain examples DIR`` copies the recipes of the paper's figures
(``namelists/``), the example scripts and the tutorial notebooks (``tutorials/``) into DIR.

Errors in the input (missing file, wrong schema, data the figure needs but the run did
not record) and bad options print one line ``impactchain: error: ...`` on stderr and exit
with status 2 without writing anything.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from impactchain import figures
from impactchain.io import Run, SchemaError, read_run

__all__ = ["main", "COMMANDS"]

FORMATS = (".png", ".pdf", ".svg")
EXIT_ERROR = 2
DEFAULT_DPI = 150


class CliError(Exception):
    """An error to report as ``impactchain: error: ...`` with exit status 2."""


@dataclass(frozen=True)
class Command:
    """A figure the CLI can make."""

    name: str
    help: str
    require: tuple[str, ...]
    optional: tuple[str, ...]
    multiple: bool
    options: Callable[[argparse.ArgumentParser], None]
    build: Callable[[list[Run], argparse.Namespace], Figure]


# ------------------------------------------------------------------------------ options


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value} must be >= 1")
    return value


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not value > 0:
        raise argparse.ArgumentTypeError(f"{value} must be > 0")
    return value


def _dpi(text: str) -> float:
    value = _positive_float(text)
    if value < 10:
        raise argparse.ArgumentTypeError(f"{value:g} dots per inch is too few (>= 10)")
    return value


def _output_options(parser: argparse.ArgumentParser, output_help: str) -> None:
    parser.add_argument("-o", "--output", required=True, metavar="OUT", help=output_help)
    parser.add_argument("--format", choices=[f.lstrip(".") for f in FORMATS],
                        help="file format (default: the output's extension); added to an "
                             "output without an extension")
    parser.add_argument("--dpi", type=_dpi, default=DEFAULT_DPI,
                        help=f"resolution of PNG output and of rasterised parts of PDF/SVG "
                             f"(default: {DEFAULT_DPI})")


def _one_based_list(text: str, what: str, example: str) -> list[int]:
    """A comma-separated list of 1-based indices (`what`: their name, plural)."""
    try:
        indices = [int(item) for item in text.split(",") if item.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a comma-separated list of "
                                         f"{what}, e.g. {example}") from None
    if not indices or min(indices) < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: {what} are 1-based integers")
    return indices


def _site_list(text: str) -> list[int]:
    return _one_based_list(text, "sites", "1,3")


def _range(text: str) -> tuple[float, float]:
    try:
        low, high = (float(item) for item in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not LOW,HIGH, e.g. -2.5,1.5") from None
    if not low < high:
        raise argparse.ArgumentTypeError(f"{text!r}: LOW must be below HIGH")
    return low, high


def _ylim_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--ylim", type=_range, metavar="LOW,HIGH",
                        help="y range, to share one scale between figures that are compared "
                             "(default: the data's)")


def _cycles_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--cycles", type=_positive_int, metavar="N",
                        help="use only the last N strobe records (default: all)")


def _panel_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--panel-cycles", type=_positive_int, default=60, metavar="N",
                        help="cycles per panel (default: 60)")
    parser.add_argument("--panels", type=_positive_int, metavar="K",
                        help="number of panels (default: all that the record fills, "
                             "at most 8)")
    parser.add_argument("--start", type=int, metavar="CYCLE",
                        help="first cycle of the first panel (default: the first "
                             "recorded cycle)")


def _wait_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--max-wait", type=_positive_float, default=1.0, metavar="CYCLES",
                        help="a shock wave dies after this many drive cycles without "
                             "a collision (default: 1.0)")


def _space_amplitude_options(parser: argparse.ArgumentParser) -> None:
    _cycles_option(parser)
    _ylim_option(parser)
    parser.add_argument("--periods", choices=("file", "none"), default="file",
                        help="period labels: the simulator's, from the file's /strobe/period "
                             "(default), or none")


def _shock_wave_options(parser: argparse.ArgumentParser) -> None:
    _panel_options(parser)
    _wait_option(parser)


def _site_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--site", type=_positive_int, default=1, metavar="I",
                        help="oscillator, 1-based (default: 1)")


def _poincare_options(parser: argparse.ArgumentParser) -> None:
    _site_option(parser)
    _cycles_option(parser)


def _bifurcation_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--sites", type=_site_list, metavar="I,J,...",
                        help="oscillators to show, 1-based (default: all)")


def _lyapunov_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--k", type=_positive_int, default=10, metavar="K",
                        help="number of largest exponents to draw (default: 10)")
    parser.add_argument("--with-bifurcation", action="store_true",
                        help="add a bifurcation panel of oscillator 1 above the exponents")


def _branches_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--over", metavar="SWEEP.h5",
                        help="a 1-D sweep of the same parameter, drawn underneath in grey as "
                             "the brute-force bifurcation diagram")
    _site_option(parser)


def _chart_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--over", metavar="SWEEP.h5",
                        help="a sweep over the curves' two parameters, drawn underneath as a "
                             "map")
    parser.add_argument("--quantity", choices=figures.QUANTITIES, default="period",
                        help="what the map shows: the chain's period (default), impacts per "
                             "drive cycle, or the largest Lyapunov exponent (a sweep with "
                             "&lyapunov)")


def _plane_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--point", type=_non_negative_int, default=0, metavar="P",
                        help="the point (0-based) of a census along a swept parameter "
                             "(default: 0)")


def _non_negative_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"{value} must be >= 0")
    return value


def _clv_space_time_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--vector", type=_site_list, default=[1], metavar="J,K,...",
                        help="covariant vectors to show, 1-based, one panel each; among the "
                             "first clv_store (default: 1)")
    parser.add_argument("--start", type=int, metavar="CYCLE",
                        help="first cycle shown (default: the first record with vectors)")
    parser.add_argument("--cycles", type=_positive_int, metavar="N",
                        help="number of records shown from --start (default: all)")


def _clv_angles_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--bins", type=_positive_int, default=40, metavar="B",
                        help="logarithmically spaced bins (default: 40)")
    parser.add_argument("--near", type=_positive_float, default=figures.NEAR_TANGENCY,
                        metavar="RAD",
                        help="angles below this count as near-tangencies in the title "
                             f"(default: {figures.NEAR_TANGENCY:g})")


def _index_list(text: str) -> list[int]:
    return _one_based_list(text, "exponent indices", "1,2")


def _finite_time_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--exponents", type=_index_list, default=[1], metavar="J,K,...",
                        help="exponents to show, 1-based, one panel each (default: 1, the "
                             "largest)")
    parser.add_argument("--bins", type=_positive_int, metavar="B",
                        help=f"bins per histogram (default: numpy's choice, at most "
                             f"{figures.FINITE_TIME_BINS})")


def _all_options(parser: argparse.ArgumentParser) -> None:
    _cycles_option(parser)
    _panel_options(parser)
    _wait_option(parser)


def _no_options(parser: argparse.ArgumentParser) -> None:
    del parser


# ----------------------------------------------------------------------------- commands


def _branches(runs: list[Run], args: argparse.Namespace) -> Figure:
    """The branches of one or more continuations, over the sweep of --over if given."""
    over = None if args.over is None else _read(args.over, ("sweep",), (), "branches --over")
    return figures.branches(runs, over=over, site=args.site)


def _chart(runs: list[Run], args: argparse.Namespace) -> Figure:
    """Curves in two parameters, over the two-parameter sweep of --over if given."""
    over = None if args.over is None else _read(args.over, ("sweep",), (), "chart --over")
    return figures.chart(runs, over=over, quantity=args.quantity)


COMMANDS: dict[str, Command] = {
    c.name: c
    for c in (
        Command("space-amplitude",
                "overlaid strobe snapshots x(site); several files overlay in colours",
                ("strobe",), (), True, _space_amplitude_options,
                lambda runs, a: figures.space_amplitude(runs, a.cycles, a.periods,
                                                        ylim=a.ylim)),
        Command("space-time-amplitude",
                "3-D waterfall of strobe snapshots, in panels of cycles",
                ("strobe",), (), False, _panel_options,
                lambda runs, a: figures.space_time_amplitude(runs[0], a.panel_cycles,
                                                             a.panels, a.start)),
        Command("shock-wave",
                "collision cascades from the walls, same panels as space-time-amplitude",
                ("events",), ("strobe",), False, _shock_wave_options,
                lambda runs, a: figures.shock_wave(runs[0], a.panel_cycles, a.panels,
                                                   a.max_wait, a.start)),
        Command("poincare",
                "Poincare section (x, v) of one oscillator",
                ("strobe",), (), False, _poincare_options,
                lambda runs, a: figures.poincare(runs[0], a.site, a.cycles)),
        Command("bifurcation",
                "strobe positions against the swept parameter (sweep file)",
                ("sweep",), (), False, _bifurcation_options,
                lambda runs, a: figures.bifurcation(runs[0], a.sites)),
        Command("lyapunov",
                "largest Lyapunov exponents against the swept parameter (sweep file)",
                ("sweep", "sweep/exponents"), (), True, _lyapunov_options,
                lambda runs, a: figures.lyapunov(runs, a.k, a.with_bifurcation)),
        Command("ky-dimension",
                "Kaplan-Yorke dimension against the swept parameter (sweep files)",
                ("sweep", "sweep/ky_dimension"), (), True, _ylim_option,
                lambda runs, a: figures.ky_dimension(runs, ylim=a.ylim)),
        Command("spectrum",
                "Lyapunov spectrum of one run and convergence of the running estimates",
                ("lyapunov",), ("strobe",), False, _no_options,
                lambda runs, a: figures.spectrum(runs[0])),
        Command("branches",
                "continued periodic orbits against the parameter, stable and unstable, "
                "with their special points (continuation file)",
                ("continuation",), (), True, _branches_options, _branches),
        Command("chart",
                "fold, period-doubling, grazing and Neimark-Sacker curves in the plane of "
                "their two parameters, over a two-parameter sweep (curve files, &continuation follow)",
                ("curve",), (), True, _chart_options, _chart),
        Command("multipliers",
                "largest Floquet multiplier of the continued orbits against the parameter "
                "(continuation file)",
                ("continuation",), (), False, _no_options,
                lambda runs, a: figures.multipliers(runs[0])),
        Command("basin-fractions",
                "basin fraction of each attractor of a census, stacked against the swept "
                "parameter or as bars at one point (census file)",
                ("census",), (), False, _no_options,
                lambda runs, a: figures.basin_fractions(runs[0])),
        Command("basin-plane",
                "basin picture: the attractor each start on a census plane reached "
                "(census file with &census plane)",
                ("census",), (), False, _plane_options,
                lambda runs, a: figures.basin_plane(runs[0], a.point)),
        Command("ensemble-spectra",
                "each attractor's mean Lyapunov spectrum with the spread between its "
                "samples, over every sample's spectrum (census file; &census exponents = k)",
                ("census",), (), False, _no_options,
                lambda runs, a: figures.ensemble_spectra(runs[0])),
        Command("clv-space-time",
                "weight of covariant Lyapunov vectors along the chain against time, with "
                "the collisions",
                ("clv/site_weight",), ("events",), False, _clv_space_time_options,
                lambda runs, a: figures.clv_space_time(runs[0], a.vector, a.cycles,
                                                       a.start)),
        Command("clv-ipr",
                "inverse participation ratio of each covariant vector, with its growth rate",
                ("clv",), (), False, _no_options,
                lambda runs, a: figures.clv_ipr(runs[0])),
        Command("clv-angles",
                "histogram of the smallest angle between the unstable covariant vectors and "
                "the others",
                ("clv",), (), False, _clv_angles_options,
                lambda runs, a: figures.clv_angles(runs[0], a.bins, a.near)),
        Command("finite-time",
                "histogram of the finite-time Lyapunov exponents over windows, with the "
                "run's exponent and standard error; several files (window lengths) overlay "
                "in colours",
                ("finite_time",), ("lyapunov",), True, _finite_time_options,
                lambda runs, a: figures.finite_time(runs, a.exponents, a.bins)),
    )
}


def build_parser() -> argparse.ArgumentParser:
    """The argument parser, one sub-command per figure plus ``all``."""
    parser = argparse.ArgumentParser(
        prog="python -m impactchain",
        description="Figures from impactchain HDF5 output files.",
        epilog="example: python -m impactchain space-amplitude run.h5 -o fig.png",
    )
    sub = parser.add_subparsers(dest="figure", metavar="<figure>", required=True,
                                title="figures")
    for command in COMMANDS.values():
        p = sub.add_parser(command.name, help=command.help, description=command.help)
        p.add_argument("files", nargs="+" if command.multiple else 1, metavar="FILE.h5")
        _output_options(p, "output file, .png, .pdf or .svg")
        command.options(p)
    p = sub.add_parser("all", help="every figure one file supports, written as "
                                   "PREFIX_<figure>.png",
                       description="Write every figure the file's data supports, as "
                                   "PREFIX_space_amplitude.png etc. (PDF or SVG when "
                                   "PREFIX ends in .pdf or .svg).")
    p.add_argument("files", nargs=1, metavar="FILE.h5")
    _output_options(p, "output prefix, e.g. figs/run (figs/run.pdf: PDF files)")
    _all_options(p)
    p = sub.add_parser("examples", help="copy the recipes of the paper's figures, the "
                                        "example scripts and the tutorials into DIR",
                       description="Copy the recipes of the paper's figures (namelists/), "
                                   "the example scripts and the tutorial notebooks "
                                   "(tutorials/) into DIR; an existing file is never "
                                   "replaced without --overwrite.")
    p.add_argument("directory", metavar="DIR")
    p.add_argument("--overwrite", action="store_true", help="replace files that exist")
    return parser


# --------------------------------------------------------------------------------- main


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; return the exit status."""
    args = build_parser().parse_args(argv)
    try:
        if args.figure == "examples":
            _copy_examples(Path(args.directory), args.overwrite)
        elif args.figure == "all":
            _make_all(args)
        else:
            _make_one(COMMANDS[args.figure], args)
    except (CliError, SchemaError, figures.FigureError) as exc:
        print(f"impactchain: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    return 0


EXAMPLES = Path(__file__).resolve().parent / "examples"


def _copy_examples(target: Path, overwrite: bool) -> None:
    """The installed examples (recipes in namelists/, scripts, tutorials/) into ``target``: all or
    nothing, and nothing the user has replaced without ``overwrite``."""
    if not EXAMPLES.is_dir():
        raise CliError("this installation has no examples (the package was built without "
                       "them)")
    if target.exists() and not target.is_dir():
        raise CliError(f"{target} exists and is not a directory")
    files = sorted(p.relative_to(EXAMPLES) for p in EXAMPLES.rglob("*")
                   if p.is_file() and "__pycache__" not in p.parts)
    taken = [str(target / f) for f in files if (target / f).exists()]
    if taken and not overwrite:
        raise CliError(f"{len(taken)} file(s) exist, e.g. {taken[0]}; nothing was copied "
                       "(--overwrite replaces them)")
    for f in files:
        (target / f).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(EXAMPLES / f, target / f)
    print(f"impactchain: copied {len(files)} files into {target} (the recipes in "
          f"{target / 'namelists'}, run one with: impactchain {target / 'namelists'}"
          f"/default.nml; the tutorial notebooks in {target / 'tutorials'})")


def _make_one(command: Command, args: argparse.Namespace) -> None:
    output = _output_path(args.output, args.format)
    runs = [_read(path, command.require, command.optional, command.name)
            for path in args.files]
    figure = command.build(runs, args)
    _save(figure, output, args.dpi)


def _make_all(args: argparse.Namespace) -> None:
    prefix, suffix = _output_prefix(args.output, args.format)
    path = args.files[0]
    run = _read(path, (), None, "all")
    made = list(_all_figures(run, args))
    if not made:
        raise CliError(f"{path}: the file holds no data for any figure")
    for name, figure in made:
        out = Path(f"{prefix}_{name.replace('-', '_')}{suffix}")
        _save(figure, out, args.dpi)
        print(out)


def _all_figures(run: Run, args: argparse.Namespace) -> Iterator[tuple[str, Figure]]:
    """(name, figure) for every figure ``run`` supports; notes skipped ones on stderr."""
    if run.strobe is not None and run.strobe.n_record:
        yield "space-amplitude", figures.space_amplitude([run], args.cycles)
        yield "space-time-amplitude", figures.space_time_amplitude(
            run, args.panel_cycles, args.panels, args.start)
        if run.events is not None:
            yield "shock-wave", figures.shock_wave(run, args.panel_cycles, args.panels,
                                                   args.max_wait, args.start)
        else:
            _note(f"skipped shock-wave: {run.path} holds no events")
        yield "poincare", figures.poincare(run, 1, args.cycles)
    if run.lyapunov is not None:
        yield "spectrum", figures.spectrum(run)
    sweep = run.sweep
    if sweep is not None and sweep.values.shape[0]:
        if not sweep.is_2d:
            yield "bifurcation", figures.bifurcation(run)
            if sweep.exponents is not None:
                yield "lyapunov", figures.lyapunov([run], with_bifurcation=True)
        if sweep.ky_dimension is not None:
            yield "ky-dimension", figures.ky_dimension([run])
    if run.continuation is not None and run.continuation.n_points:
        yield "branches", figures.branches(run)
        yield "multipliers", figures.multipliers(run)
    if run.curve is not None and run.curve.values.size:
        yield "chart", figures.chart(run)
    if run.census is not None and run.census.n_attractors:
        yield "basin-fractions", figures.basin_fractions(run)
        if run.census.plane is not None:
            yield "basin-plane", figures.basin_plane(run)
        if run.census.k > 1:
            yield "ensemble-spectra", figures.ensemble_spectra(run)
    if run.clv is not None and run.clv.n_record:
        if run.clv.stored:
            # the first --panel-cycles records with vectors, as many as a shock-wave panel
            yield "clv-space-time", figures.clv_space_time(run, 1, args.panel_cycles)
        else:
            _note(f"skipped clv-space-time: {run.path} holds no site weights (clv_store = 0)")
        yield "clv-ipr", figures.clv_ipr(run)
        if np.isfinite(run.clv.min_angle).any():
            yield "clv-angles", figures.clv_angles(run)
        else:
            _note(f"skipped clv-angles: {run.path} holds no angle (no unstable-stable pair)")
    if run.finite_time is not None and run.finite_time.n_windows:
        if np.isfinite(run.finite_time.exponents[:, 0]).any():
            yield "finite-time", figures.finite_time(run)
        else:
            _note(f"skipped finite-time: {run.path}: exponent 1 is -infinity in every window")


def _read(path: str, require: tuple[str, ...], optional: tuple[str, ...] | None,
          purpose: str) -> Run:
    groups = None if optional is None else (*require, *optional)
    run = read_run(path, require=require, groups=groups, purpose=purpose)
    if not run.complete:
        _note(f"{path}: the run was interrupted; plotting the records it finished")
    return run


def _note(message: str) -> None:
    print(f"impactchain: note: {message}", file=sys.stderr)


def _output_path(text: str, fmt: str | None = None) -> Path:
    """The output file: its extension, or ``--format`` (added when it has no extension)."""
    path = Path(text)
    suffix = path.suffix.lower()
    if fmt is not None:
        if suffix in FORMATS and suffix != f".{fmt}":
            raise CliError(f"output {text!r} does not end in .{fmt} (--format {fmt})")
        return path if suffix == f".{fmt}" else Path(f"{text}.{fmt}")
    if suffix not in FORMATS:
        raise CliError(f"output {text!r} must end in {', '.join(FORMATS)} "
                       "(or give --format)")
    return path


def _output_prefix(text: str, fmt: str | None = None) -> tuple[str, str]:
    """Split ``figs/run.pdf`` into ('figs/run', '.pdf'); no known suffix means PNG, or
    ``--format``."""
    path = Path(text)
    if path.suffix.lower() in FORMATS:
        if fmt is not None and path.suffix.lower() != f".{fmt}":
            raise CliError(f"output prefix {text!r} does not end in .{fmt} (--format {fmt})")
        return str(path.with_suffix("")), path.suffix.lower()
    if not path.name:
        raise CliError(f"output prefix {text!r} has no file name part")
    return text, f".{fmt or 'png'}"


def _save(figure: Figure, out: Path, dpi: float = DEFAULT_DPI) -> None:
    """Write the figure atomically: to a hidden temporary file, then rename."""
    fmt = out.suffix.lower().lstrip(".")
    temporary = out.with_name(f".{out.name}.partial")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        figures.save(figure, temporary, dpi=dpi, format=fmt)
        os.replace(temporary, out)
    except OSError as exc:
        raise CliError(f"cannot write {out}: {exc.strerror or exc}") from exc
    finally:
        if temporary.exists():
            temporary.unlink()
