"""Parameter sweeps: :func:`sweep` and the xarray dataset it returns, the command line's
``/sweep`` group (public through :mod:`impactchain.api`)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from impactchain import schema
from impactchain._calls import (
    SWEEP_OUTPUTS,
    _config,
    _extension,
    _float,
    _int32,
    _name,
    _raise_for,
    _text,
    _used,
    _watched,
)
from impactchain.schema import SCHEMA_DEFAULT, with_schema_defaults


@with_schema_defaults
def sweep(
    n: int,
    amplitude: float,
    omega: float,
    *,
    cycles: int = 100,
    parameter: str,
    start: float,
    stop: float,
    step: float,
    mode: str = SCHEMA_DEFAULT,
    parameter2: str | None = None,
    start2: float | None = None,
    stop2: float | None = None,
    step2: float | None = None,
    lyapunov: bool = False,
    vectors: int = SCHEMA_DEFAULT,
    qr_every: int = SCHEMA_DEFAULT,
    threads: int = 0,
    progress: bool = False,
    **keys: Any,
) -> Any:
    """A parameter sweep (bifurcation diagram, Lyapunov scan): the CLI's ``&sweep``.

    ``parameter`` (``'amplitude'``, ``'omega'``, ``'damping'``, ``'restitution'`` or
    ``'spacing'``) runs from ``start`` to ``stop`` in steps of ``step``; its value among the
    run's arguments is replaced at each point. ``mode='continuation'`` starts each point from
    the final state of the one before (the paper's procedure), ``'independent'`` every point
    from ``x0``, ``v0``. ``parameter2``, ``start2``, ``stop2``, ``step2``: a second axis, each
    of its values a branch of its own (a 2-D grid). Each point runs ``transient`` cycles and
    records ``cycles`` strobe records; with ``lyapunov=True`` also ``vectors`` exponents (0:
    all 2n). Branches run on ``threads`` OpenMP threads (0: ``OMP_NUM_THREADS``, else every
    core); the numbers are the same for any count, and the CLI's on the same namelist.
    Ctrl-C stops the sweep once the points running finish (:class:`KeyboardInterrupt`);
    ``progress=True`` shows a tqdm bar of the points. Other arguments and ``**keys`` (any
    key of the input table) as :func:`simulate`.

    Returns:
        An :class:`xarray.Dataset`, the CLI file's ``/sweep`` group
        (``xarray.open_dataset(path, engine="h5netcdf", group="sweep")``) with the same
        names: dimensions ``point`` (the values of ``parameter``; ``point2`` for
        ``parameter2``), ``record``, ``oscillator``, ``exponent``; variables ``x``
        (point, [point2,] record, oscillator), ``collisions_per_cycle``, ``period``
        (0: aperiodic), with ``lyapunov`` also ``exponents``, ``stderr`` (bits per drive
        cycle) and ``ky_dimension``, and ``drive_period`` in an ``omega`` sweep;
        attributes ``parameter``, ``parameter2`` ('' for 1-D), ``mode`` and the run's
        other arguments.

    Raises:
        ImportError: xarray is missing. ValueError, TypeError, RuntimeError: as
        :func:`simulate` (a point outside its range names the point).
    """
    try:
        import xarray as xr
    except ImportError:
        raise ImportError("api.sweep returns an xarray.Dataset: pip install xarray") from None
    cfg, args = _sweep_args(n, amplitude, omega, cycles, keys, lyapunov, vectors, qr_every,
                            parameter, start, stop, step, mode, parameter2, start2, stop2,
                            step2, threads)
    kernels = _extension()
    no_control = np.zeros(4, dtype=np.int64)
    out = dict(zip(SWEEP_OUTPUTS, kernels.ic_sweep(**args, dry_run=1, nf=1, nc=1, npts=1,
                                                   kcap=0, x=np.empty((1, 1, 1), order="F"),
                                                   control=no_control), strict=True))
    _raise_for(out["status"], out["msg_len"], out["message"])
    n1, n2, k = (int(i) for i in out["sizes"])
    sizes = dict(nf=cfg["n"], nc=cfg["cycles"], npts=n1 * n2, kcap=k)
    x = np.empty((cfg["n"], cfg["cycles"], n1 * n2), order="F")
    result = _watched(kernels.ic_sweep, dict(args, dry_run=0, x=x, **sizes), progress)
    out = dict(zip(SWEEP_OUTPUTS, result, strict=True), x=x)
    _raise_for(out["status"], out["msg_len"], out["message"])
    return _sweep_dataset(xr, out, cfg, args, n1, n2, k)


def _sweep_args(n: Any, amplitude: Any, omega: Any, cycles: Any, keys: Mapping[str, Any],
                lyapunov: Any, vectors: Any, qr_every: Any, parameter: Any, start: Any,
                stop: Any, step: Any, mode: Any, parameter2: Any, start2: Any, stop2: Any,
                step2: Any, threads: Any) -> tuple[dict[str, Any], dict[str, Any]]:
    """The run's arguments (as :func:`_config`) and those of ``ic_sweep``."""
    cfg = _config(n, amplitude, omega, cycles, keys)
    for name in ("record_events", "jacobian", "jacobian_cycles"):
        del cfg[name]
    cfg["lyapunov"] = int(bool(lyapunov))
    cfg["vectors"] = _int32(vectors, "&lyapunov: vectors", "[0, 2n] (0 means all 2n)")
    cfg["qr_every"] = _int32(qr_every, "&lyapunov: qr_every", "[0, cycles] (0: adaptive)")
    two_d = parameter2 is not None
    if two_d and (start2 is None or stop2 is None or step2 is None):
        raise ValueError("&sweep: parameter2 needs start2, stop2 and step2")
    args = dict(
        cfg,
        parameter=_name(parameter, "parameter"),
        start=_float(start, "start"),
        stop=_float(stop, "stop"),
        step=_float(step, "step"),
        mode=_name(mode, "mode"),
        parameter2=_name(parameter2 if two_d else "", "parameter2"),
        start2=_float(start2, "start2") if two_d else 0.0,
        stop2=_float(stop2, "stop2") if two_d else 0.0,
        step2=_float(step2, "step2") if two_d else 0.0,
        threads=_int32(threads, "threads", "the non-negative 32-bit integers"),
    )
    if args["threads"] < 0:
        raise ValueError(f"threads = {args['threads']} is outside [0, 2**31) (0: the default)")
    return cfg, args


def _sweep_dataset(xr: Any, out: dict[str, Any], cfg: dict[str, Any], args: dict[str, Any],
                   n1: int, n2: int, k: int) -> Any:
    """ic_sweep's arrays (point p = i + n1 j, Fortran order) as the file's /sweep group:
    the same dimensions, coordinates, variables and variable attributes (``units`` UDUNITS'
    as in the file, ``model_units`` the reduced ones)."""
    parameter = _text(args["parameter"])
    parameter2 = _text(args["parameter2"])
    two_d = len(parameter2) > 0

    def grid(a: Any) -> NDArray[Any]:
        """(..., n1 n2) in Fortran order -> (n1, [n2,] ...), the file's layout."""
        a = np.moveaxis(np.asarray(a), -1, 0)           # [p, ...], p = i + n1 j
        a = np.swapaxes(a.reshape((n2, n1) + a.shape[1:]), 0, 1)  # [i, j, ...]
        return np.ascontiguousarray(a if two_d else a[:, 0])

    axes = 2 if two_d else 1

    def described(name: str, values: Any, parameter: str | None = None,
                  along: int = 1) -> tuple[Any, ...]:
        return schema.variable(f"/sweep/{name}", values, parameter, axes, along)

    values = np.asarray(out["values"])
    coords = {
        "point": described("point", values[0, :n1].copy(), parameter),
        "oscillator": described("oscillator", np.arange(1, cfg["n"] + 1, dtype=np.int32)),
    }
    if two_d:
        coords["point2"] = described("point2", values[1, ::n1].copy(), parameter2)
    data = {
        "x": described("x", grid(np.asarray(out["x"]).transpose(1, 0, 2))),
        "collisions_per_cycle": described("collisions_per_cycle", grid(out["collisions"])),
        "period": described("period", grid(out["period"])),
    }
    if k > 0:
        coords["exponent"] = described("exponent", np.arange(1, k + 1, dtype=np.int32))
        data["exponents"] = described("exponents", grid(out["exponents"]))
        data["stderr"] = described("stderr", grid(out["stderr_bits"]))
        data["stderr_block"] = described("stderr_block", grid(out["stderr_cycles"]))
        data["ky_dimension"] = described("ky_dimension", grid(out["ky"]))
    if "omega" in (parameter, parameter2):
        along = 1 if parameter == "omega" else 2
        axis = ("point", "point2")[along - 1]
        data["drive_period"] = described("drive_period", 2 * np.pi / coords[axis][1],
                                         along=along)
    attrs: dict[str, Any] = dict(parameter=parameter, parameter2=parameter2,
                                 mode=_text(args["mode"]))
    attrs.update({key: cfg[key] for key in ("n", "amplitude", "omega", "damping",
                                             "restitution", "transient", "cycles", "phase")
                  if key not in (parameter, parameter2)})
    used = _used(cfg, events=False, vectors=cfg["vectors"], qr_every=cfg["qr_every"])
    if parameter != "spacing" and parameter2 != "spacing":
        attrs["spacing"] = np.asarray(used["spacing"])
    attrs.update(boundary=used["boundary"], stick_speed=cfg["stick_speed"],
                 code_version=used["code_version"],
                 input_namelist=_sweep_namelist(used, k > 0, attrs, args))
    return xr.Dataset(data, coords=coords, attrs=attrs)


def _sweep_namelist(used: Mapping[str, Any], lyapunov: bool, attrs: Mapping[str, Any],
                    args: Mapping[str, Any]) -> str:
    """The command-line input equal to this sweep (io's equivalent namelist + &sweep)."""
    from impactchain.io import _equivalent_namelist

    text = _equivalent_namelist(used, lyapunov)
    group = (f"&sweep parameter = '{attrs['parameter']}', start = {args['start']!r}, "
             f"stop = {args['stop']!r}, step = {args['step']!r}, mode = '{attrs['mode']}'")
    if attrs["parameter2"]:
        group += (f", parameter2 = '{attrs['parameter2']}', start2 = {args['start2']!r}, "
                  f"stop2 = {args['stop2']!r}, step2 = {args['step2']!r}")
    return text + group + " /\n"
