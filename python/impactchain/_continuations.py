"""Periodic orbits followed in a parameter: :func:`continuation` and :func:`periodic_orbit`,
and the xarray dataset they return, the command line's ``/continuation`` group (public
through :mod:`impactchain.api`)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from impactchain import schema
from impactchain._calls import (
    _CONTINUATION_STAGES,
    _STATUS_CAPACITY,
    CONTINUATION_OUTPUTS,
    _config,
    _extension,
    _float,
    _frozen,
    _int32,
    _name,
    _raise_for,
    _text,
    _watched,
)
from impactchain._runs import PeriodicOrbit
from impactchain.schema import SCHEMA_DEFAULT, with_schema_defaults

#: ic_continuation's sizes: points, special points, longest period, length of end_reason,
#: start converged, start residuals, start impacts, length of start_reason, of end_kind,
#: branches
_CONTINUATION_SIZES = ("npcap", "nscap", "nlong", "ntext", None, "nrcap", "nbcap", "ntext",
                       "ntext", "nocap")
_FIRST_CONTINUATION_BYTES = 64 << 20  # memory of the first guess of a continuation's points


@with_schema_defaults
def continuation(
    n: int,
    amplitude: float,
    omega: float,
    *,
    parameter: str,
    stop: float,
    step: float,
    period: int = SCHEMA_DEFAULT,
    max_points: int = SCHEMA_DEFAULT,
    doublings: int = SCHEMA_DEFAULT,
    progress: bool = False,
    **keys: Any,
) -> Any:
    """Branches of periodic orbits followed in one parameter: the CLI's ``&continuation``.

    Newton finds the period-``period`` orbit from the state on the section (drive phase
    ``phase``) after ``transient`` cycles from ``x0``, ``v0``; pseudo-arclength continuation
    then follows its branch in ``parameter`` (``'amplitude'``, ``'omega'``, ``'damping'``,
    ``'restitution'`` or ``'spacing'``, whose value among the arguments is the start) towards
    ``stop``, first step ``step`` (its sign: the direction), at most ``max_points`` orbits per
    branch, and ``doublings`` levels of the period-doubled branches born at its period
    doublings (docs/model.md section 12). Folds, period doublings, Neimark-Sacker points,
    branch points, grazings and corners (one oscillator hit by both neighbours at once) are
    located, and a branch goes on through them where an orbit on the other side is found; it
    ends there when none is, at an impact at the section, at a bound of the parameter, after
    ``max_points`` or when Newton fails, and says why (``end_reason``) and which
    (``end_kind``). ``**keys`` (any key of the input table) as :func:`simulate`'s,
    and the ``&continuation`` keys not named here (``branch_points``: levels of switching
    onto the branches crossing at branch points).
    Ctrl-C stops the work at its next transient cycle or orbit (:class:`KeyboardInterrupt`);
    ``progress=True`` shows a tqdm bar of them.

    Returns:
        An :class:`xarray.Dataset`, identical to the CLI file's ``/continuation`` group
        (``xarray.open_dataset(path, engine="h5netcdf", group="continuation")``) for the
        same input: dimensions ``point`` (the orbits, branch after branch), ``oscillator``,
        ``multiplier``, ``iterate`` (section crossings of the longest period), ``special``,
        ``branch_index``;
        variables ``values`` (the parameter), ``x``, ``v``, ``strobe_x`` (NaN beyond a
        point's period), ``period``, ``branch``, ``multipliers_re``, ``multipliers_im``,
        ``stable``, ``symmetric`` (its own mirror image half a drive period later),
        ``min_gap``, ``min_impact_speed`` (inf: none), ``impacts_per_period``,
        ``residual``, ``iterations``, ``special_index`` (0-based point), ``special_kind``,
        ``special_value``, per branch ``parent`` (-1: none), ``origin_point`` (0-based, the
        parent's special point it began at; -1: none) and ``origin_kind`` ('': none);
        attributes ``parameter``, ``phase``, ``start``, ``stop``,
        ``step``, ``end_reason``, ``end_kind``. A failure of Newton at the start is a
        result: no point, and ``end_reason`` says why.

    Raises:
        ImportError: xarray is missing. ValueError: a bad argument, with the CLI's message.
        TypeError: an argument of the wrong type. RuntimeError: the engine failed.
        KeyboardInterrupt: Ctrl-C.
    """
    try:
        import xarray as xr
    except ImportError:
        raise ImportError("api.continuation returns an xarray.Dataset: pip install xarray"
                          ) from None
    cfg, args = _continuation_args(n, amplitude, omega, keys, parameter, stop, step, period,
                                   max_points, doublings)
    out = _continue(args, progress)
    return _continuation_dataset(xr, out, cfg, args)


@with_schema_defaults(period=("continuation", "period"))
def periodic_orbit(
    n: int,
    amplitude: float,
    omega: float,
    *,
    period: int = SCHEMA_DEFAULT,
    progress: bool = False,
    **keys: Any,
) -> PeriodicOrbit:
    """The period-``period`` orbit (p in 1..10000 drive cycles) that Newton shooting finds
    from the state on the section (drive phase ``phase``) after ``transient`` cycles from
    ``x0``, ``v0``: the CLI's ``&continuation max_points = 1`` run (the same Fortran call;
    the orbit is that file's one point). ``**keys`` as :func:`simulate`'s.

    Returns:
        A :class:`PeriodicOrbit`. Newton's failure is a result, not an exception:
        ``converged`` False and ``reason`` (an orbit that rests on a wall, no decrease of the
        residual at a grazing, ...), with the last iterate's state, Jacobian and impacts.

    Raises:
        ValueError: a bad argument, with the CLI's message. TypeError: an argument of the
        wrong type. RuntimeError: the engine failed. KeyboardInterrupt: Ctrl-C.
    """
    cfg, args = _continuation_args(n, amplitude, omega, keys, "amplitude", 0.0, 0.0, period,
                                   1, 0)
    out = _continue(args, progress)

    def file_group() -> Any:
        try:
            import xarray as xr
        except ImportError:
            raise ImportError("to_xarray() needs xarray: pip install xarray") from None
        return _continuation_dataset(xr, out, cfg, args)

    converged = bool(out["sizes"][4])
    multipliers = out["start_mult_re"] + 1j * out["start_mult_im"]
    return PeriodicOrbit(
        converged=converged,
        reason=_text(out["start_reason"]),
        residuals=_frozen(out["start_residuals"]),
        x=_frozen(out["start_x"]),
        v=_frozen(out["start_v"]),
        multipliers=_frozen(multipliers if converged else np.zeros(0, dtype=np.complex128)),
        impacts=int(out["start_bonds"].size),
        impact_bonds=_frozen(out["start_bonds"]),
        min_impact_speed=float(out["start_min_impact_speed"]),
        min_gap=float(out["start_min_gap"]),
        stable=bool(out["stable"][0]) if out["values"].size else False,
        jacobian=_frozen(out["start_jac"]),
        file_group=file_group,
    )


def _continuation_args(n: Any, amplitude: Any, omega: Any, keys: Mapping[str, Any],
                       parameter: Any, stop: Any, step: Any, period: Any, max_points: Any,
                       doublings: Any) -> tuple[dict[str, Any], dict[str, Any]]:
    """The run's arguments (as :func:`_config`) and those of ``ic_continuation``."""
    # (the &continuation keys this function does not name, e.g. branch_points, as overrides)
    cfg = _config(n, amplitude, omega, 1, keys, home=("continuation",))
    args = {key: cfg[key] for key in ("n", "spacing", "damping", "restitution", "amplitude",
                                      "omega", "boundary", "explicit", "x0", "v0",
                                      "transient", "phase", "stick_speed", "overrides")}
    args.update(
        parameter=_name(parameter, "parameter"),
        stop=_float(stop, "stop"),
        step=_float(step, "step"),
        period=_int32(period, "&continuation: period", "1..10000 (drive cycles)"),
        max_points=_int32(max_points, "&continuation: max_points", ">= 1"),
        doublings=_int32(doublings, "&continuation: doublings", "0..8"),
    )
    return cfg, args


def _continue(args: dict[str, Any], progress: bool) -> dict[str, Any]:
    """Validate, then run ``ic_continuation`` with room for the results guessed; once more
    with the exact room if a guess was short (the run repeats itself bit for bit). The
    outputs come back cut to their sizes."""
    kernels = _extension()
    no_control = np.zeros(4, dtype=np.int64)
    out = dict(zip(CONTINUATION_OUTPUTS, kernels.ic_continuation(
        **args, dry_run=1, nscap=1, ntext=1, nrcap=1, nbcap=1, nocap=1,
        strobe_x=np.empty((1, 1, 1), order="F"), control=no_control), strict=True))
    _raise_for(out["status"], out["msg_len"], out["message"])
    room = _first_room(args)
    for _ in range(2):
        strobe = np.empty((args["n"], room["nlong"], room["npcap"]), order="F")
        call = dict(args, dry_run=0, strobe_x=strobe,
                    **{k: room[k] for k in ("nscap", "ntext", "nrcap", "nbcap", "nocap")})
        result = _watched(kernels.ic_continuation, call, progress, _CONTINUATION_STAGES)
        out = dict(zip(CONTINUATION_OUTPUTS, result, strict=True), strobe_x=strobe)
        if out["status"] != _STATUS_CAPACITY:
            break
        for key, size in zip(_CONTINUATION_SIZES, out["sizes"]):
            if key is not None:
                room[key] = max(room[key], int(size))
    _raise_for(out["status"], out["msg_len"], out["message"])
    points, specials, longest, reason, _, residuals, impacts, start_reason, kind, branches = (
        int(i) for i in out["sizes"])
    cut = {"strobe_x": (slice(None), slice(longest), slice(points)),
           "x": (slice(None), slice(points)), "v": (slice(None), slice(points)),
           "mult_re": (slice(None), slice(points)), "mult_im": (slice(None), slice(points)),
           "special_kind": (slice(None), slice(specials)),
           "origin_kind": (slice(None), slice(branches)),
           "end_reason": slice(reason), "end_kind": slice(kind),
           "start_reason": slice(start_reason),
           "start_residuals": slice(residuals), "start_bonds": slice(impacts)}
    for key in ("values", "periods", "branch", "stable", "symmetric", "min_gap",
                "min_impact_speed", "impacts", "residual", "iterations"):
        cut[key] = slice(points)
    for key in ("special_index", "special_value"):
        cut[key] = slice(specials)
    for key in ("parent", "origin_point"):
        cut[key] = slice(branches)
    return {key: value[cut[key]] if key in cut else value for key, value in out.items()}


def _first_room(args: dict[str, Any]) -> dict[str, int]:
    """ic_continuation's capacities for a first call: every crossing of the longest period
    the branches can have, the points of max_points per branch and a few special points and
    branches (within about 64 MB), and ample room for texts, Newton's residuals and impacts."""
    n, period = args["n"], args["period"]
    nlong = period * 2 ** args["doublings"]
    per_point = 8 * (n * nlong + 6 * n + 8)
    return dict(npcap=min(args["max_points"] * (1 + args["doublings"]) + 16,
                          max(16, _FIRST_CONTINUATION_BYTES // per_point)),
                nlong=nlong, nscap=64, nocap=64, ntext=4096, nrcap=64,
                nbcap=min(max(1024, 16 * (n + 1) * period), 1 << 20))


def _continuation_dataset(xr: Any, out: dict[str, Any], cfg: dict[str, Any],
                          args: dict[str, Any]) -> Any:
    """ic_continuation's arrays (Fortran order) as the file's /continuation group: the same
    dimensions, coordinates, variables, their attributes (the file schema's)
    and the group's attributes."""
    parameter = _text(args["parameter"])
    points = out["values"].size
    n = cfg["n"]

    def described(name: str, values: Any) -> tuple[Any, ...]:
        return schema.variable(f"/continuation/{name}", np.ascontiguousarray(values),
                               parameter)

    def index(name: str, first: int, count: int) -> tuple[Any, ...]:
        return described(name, np.arange(first, first + count, dtype=np.int32))

    def names(byte_columns: Any) -> list[str]:
        return [bytes(np.asarray(k).astype(np.uint8)).split(b"\0")[0].decode()
                for k in np.asarray(byte_columns).T]

    kinds = names(out["special_kind"])
    origin_kinds = names(out["origin_kind"])
    coords = {
        "point": index("point", 0, points),
        "oscillator": index("oscillator", 1, n),
        "multiplier": index("multiplier", 1, 2 * n),
        "iterate": index("iterate", 1, out["strobe_x"].shape[1]),
        "special": index("special", 0, len(kinds)),
        "branch_index": index("branch_index", 0, len(origin_kinds)),
    }
    data = {
        "values": described("values", out["values"]),
        "x": described("x", out["x"].T),
        "v": described("v", out["v"].T),
        "strobe_x": described("strobe_x", out["strobe_x"].transpose(2, 1, 0)),
        "period": described("period", out["periods"]),
        "branch": described("branch", out["branch"]),
        "multipliers_re": described("multipliers_re", out["mult_re"].T),
        "multipliers_im": described("multipliers_im", out["mult_im"].T),
        "stable": described("stable", out["stable"]),
        "symmetric": described("symmetric", out["symmetric"]),
        "min_gap": described("min_gap", out["min_gap"]),
        "min_impact_speed": described("min_impact_speed", out["min_impact_speed"]),
        "impacts_per_period": described("impacts_per_period", out["impacts"]),
        "residual": described("residual", out["residual"]),
        "iterations": described("iterations", out["iterations"]),
        "special_index": described("special_index", out["special_index"]),
        "special_kind": described("special_kind", np.array(kinds, dtype=str)),
        "special_value": described("special_value", out["special_value"]),
        "parent": described("parent", out["parent"]),
        "origin_point": described("origin_point", out["origin_point"]),
        "origin_kind": described("origin_kind", np.array(origin_kinds, dtype=str)),
    }
    spacing = np.asarray(cfg["spacing"])
    start = float(spacing[0]) if parameter == "spacing" else cfg[parameter]
    attrs = dict(parameter=parameter, phase=cfg["phase"], start=start, stop=args["stop"],
                 step=args["step"], end_reason=_text(out["end_reason"]),
                 end_kind=_text(out["end_kind"]))
    return xr.Dataset(data, coords=coords, attrs=attrs)
