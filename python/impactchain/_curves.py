"""A fold, period-doubling, grazing, branch-point or Neimark-Sacker curve in two parameters:
:func:`curve`, the command line's ``&continuation follow``, and the tree it returns, the file's
``/continuation`` and ``/curve`` groups (public through :mod:`impactchain.api`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from impactchain import schema
from impactchain._calls import (
    _CONTINUATION_STAGES,
    CURVE_OUTPUTS,
    _extension,
    _raise_for,
    _text,
    _watched,
)
from impactchain._continuations import _continuation_args, _continuation_dataset, _continue
from impactchain.schema import SCHEMA_DEFAULT, with_schema_defaults

_KIND_BYTES = 64  # room for the name of a codim-2 point's kind
_TEXT_BYTES = 4096  # room for end_reason


@with_schema_defaults
def curve(
    n: int,
    amplitude: float,
    omega: float,
    *,
    parameter: str,
    stop: float,
    step: float,
    follow: str,
    parameter2: str,
    stop2: float,
    step2: float,
    period: int = SCHEMA_DEFAULT,
    max_points: int = SCHEMA_DEFAULT,
    doublings: int = SCHEMA_DEFAULT,
    progress: bool = False,
    **keys: Any,
) -> Any:
    """A fold, period-doubling, grazing, branch-point or Neimark-Sacker curve in two
    parameters: the CLI's ``&continuation`` with ``follow``. The branches of
    :func:`continuation` (its arguments, the same meaning), then the first special point of
    kind ``follow`` (``'fold'``, ``'period-doubling'``, ``'grazing'``, ``'branch-point'`` or
    ``'neimark-sacker'``) on branch 0 followed in (``parameter``, ``parameter2``) towards
    ``parameter2 = stop2`` with arclength steps ``step2`` (its sign: the direction), at most
    ``max_points`` points (docs/model.md section 12.6). ``**keys`` as :func:`continuation`'s.

    Returns:
        An :class:`xarray.DataTree` with the groups ``continuation`` (as :func:`continuation`
        returns it) and ``curve``, each identical to the CLI file's group as
        ``xarray.open_datatree(path, engine="h5netcdf")`` reads it: ``curve`` has dimensions
        ``curve_point``, ``oscillator``, ``multiplier``, ``codim2``; variables ``values``,
        ``values2`` (the two parameters), ``x``, ``v``, ``multipliers_re``,
        ``multipliers_im``, ``codim2_index`` (0-based point), ``codim2_kind``; attributes
        ``follow``, ``parameter``, ``parameter2``, ``end_reason``. A branch without such a
        point is a result: no curve points, and ``end_reason`` says so.

    Raises:
        ImportError: xarray is missing. ValueError: a bad argument, with the CLI's message.
        TypeError: an argument of the wrong type. RuntimeError: the engine failed.
        KeyboardInterrupt: Ctrl-C.
    """
    try:
        import xarray as xr
    except ImportError:
        raise ImportError("api.curve returns an xarray.DataTree: pip install xarray"
                          ) from None
    given = dict(keys, follow=follow, parameter2=parameter2, stop2=stop2, step2=step2)
    cfg, args = _continuation_args(n, amplitude, omega, given, parameter, stop, step, period,
                                   max_points, doublings)
    branches = _continuation_dataset(xr, _continue(args, progress), cfg, args)
    out = _follow(args, progress)
    return xr.DataTree.from_dict({"/continuation": branches,
                                  "/curve": _curve_dataset(xr, out, cfg, args, given)})


def _follow(args: dict[str, Any], progress: bool) -> dict[str, Any]:
    """``ic_curve`` with room for max_points points, its outputs cut to their sizes."""
    points = args["max_points"]
    call = dict(args, nf=args["n"], npcap=points, nccap=points, nkind=_KIND_BYTES,
                ntext=_TEXT_BYTES)
    result = _watched(_extension().ic_curve, call, progress, _CONTINUATION_STAGES)
    out = dict(zip(CURVE_OUTPUTS, result, strict=True))
    _raise_for(out["status"], out["msg_len"], out["message"])
    points, codim2, reason = (int(i) for i in out["sizes"])
    for key in ("values", "values2", "x", "v", "mult_re", "mult_im"):
        out[key] = out[key][..., :points]
    out["codim2_index"] = out["codim2_index"][:codim2]
    out["codim2_kind"] = out["codim2_kind"][:, :codim2]
    out["end_reason"] = out["end_reason"][:reason]
    return out


def _curve_dataset(xr: Any, out: dict[str, Any], cfg: dict[str, Any], args: dict[str, Any],
                   given: dict[str, Any]) -> Any:
    """ic_curve's arrays (Fortran order) as the file's /curve group: the same dimensions,
    coordinates, variables, their attributes (the file schema's) and the group's."""
    parameter, parameter2 = _text(args["parameter"]), str(given["parameter2"]).lower()
    n = cfg["n"]

    def described(name: str, values: Any, which: str = parameter) -> tuple[Any, ...]:
        return schema.variable(f"/curve/{name}", np.ascontiguousarray(values), which)

    def index(name: str, first: int, count: int) -> tuple[Any, ...]:
        return described(name, np.arange(first, first + count, dtype=np.int32))

    kinds = [bytes(np.asarray(k).astype(np.uint8)).split(b"\0")[0].decode()
             for k in np.asarray(out["codim2_kind"]).T]
    coords = {
        "curve_point": index("curve_point", 0, out["values"].size),
        "oscillator": index("oscillator", 1, n),
        "multiplier": index("multiplier", 1, 2 * n),
        "codim2": index("codim2", 0, len(kinds)),
    }
    data = {
        "values": described("values", out["values"]),
        "values2": described("values2", out["values2"], parameter2),
        "x": described("x", out["x"].T),
        "v": described("v", out["v"].T),
        "multipliers_re": described("multipliers_re", out["mult_re"].T),
        "multipliers_im": described("multipliers_im", out["mult_im"].T),
        "codim2_index": described("codim2_index", out["codim2_index"]),
        "codim2_kind": described("codim2_kind", np.array(kinds, dtype=str)),
    }
    attrs = dict(follow=str(given["follow"]).lower(), parameter=parameter,
                 parameter2=parameter2, end_reason=_text(out["end_reason"]))
    return xr.Dataset(data, coords=coords, attrs=attrs)
