"""Runs made in memory: the :class:`impactchain.results.Run` of results of
:mod:`impactchain.api` (:func:`run_from_api`, :func:`run_from_sweep`,
:func:`run_from_continuation`, :func:`run_from_curve`) and of xarray trees of a file
(:func:`run_from_tree`), as if
read from the command line's file, so that every figure draws them.
"""

from __future__ import annotations

import dataclasses
import math
import os
import tempfile
from collections.abc import Mapping
from typing import Any

import numpy as np

from impactchain._hdf5 import _flat_points, _frozen, _point_values
from impactchain.namelist import equivalent_namelist
from impactchain.results import (FILE_UNITS, SCHEMA_VERSION, Continuation, Curve, Events,
                                 FinalState, Lyapunov, Params, Run, State, Stats, Strobe, Sweep)

__all__ = ["IN_MEMORY", "run_from_api", "run_from_sweep", "is_sweep_dataset",
           "run_from_continuation", "is_continuation_dataset", "run_from_curve", "is_curve_tree",
           "run_from_tree", "is_tree"]


IN_MEMORY = "(in memory, impactchain.api)"
"""``Run.path`` of a run made by :func:`run_from_api`."""


def run_from_api(simulation: Any = None, lyapunov: Any = None) -> Run:
    """A :class:`Run` from the in-memory results of :mod:`impactchain.api`, for the figures.

    ``simulation``: a ``impactchain.api.Simulation`` (strobe records, events, statistics, final
    state); ``lyapunov``: a ``impactchain.api.Lyapunov`` (exponents and their standard errors;
    no running estimates). Either or both; with both they must come from the same
    parameters. Their ``params`` (the arguments as used) give ``Run.params``, and the
    equivalent namelist becomes ``Run.input_namelist``; units are the simulator's
    (:data:`impactchain.results.FILE_UNITS`). ``api.Simulation.to_run()`` and
    ``api.Lyapunov.to_run()`` call this.
    """
    if simulation is None and lyapunov is None:
        raise ValueError("run_from_api needs a simulation, a Lyapunov result or both")
    sources = [r for r in (simulation, lyapunov) if r is not None]
    settings = [dict(getattr(r, "params", None) or {}) for r in sources]
    if not settings[0]:
        raise ValueError(f"{type(sources[0]).__name__} has no params: "
                         "not an impactchain.api result")
    config = settings[0]
    if len(settings) == 2:
        model = ("n", "amplitude", "omega", "damping", "restitution", "boundary", "phase")
        differ = [k for k in model if settings[0].get(k) != settings[1].get(k)]
        if differ:
            raise ValueError("the simulation and the Lyapunov result differ in "
                             + ", ".join(differ))
    n = int(config["n"])
    spacing = np.broadcast_to(np.asarray(config["spacing"], dtype=float), (n + 1,))
    omega = float(config["omega"])
    params = Params(
        n=n, damping=float(config["damping"]), restitution=float(config["restitution"]),
        amplitude=float(config["amplitude"]), omega=omega, boundary=str(config["boundary"]),
        drive_period=2 * math.pi / omega, phase=float(config["phase"]),
        transient=int(config["transient"]), cycles=int(config["cycles"]),
        spacing=_frozen(spacing),
    )
    parts: dict[str, Any] = {}
    x0, v0 = config.get("x0"), config.get("v0")
    if x0 is not None and v0 is not None:
        parts["initial"] = State(x=_frozen(x0), v=_frozen(v0))
    if simulation is not None:
        parts.update(_simulation_parts(simulation, params, bool(config.get("events", True))))
    if lyapunov is not None:
        exponents = _frozen(lyapunov.exponents)
        parts["lyapunov"] = Lyapunov(
            exponents=exponents,
            exponents_per_time=_frozen(lyapunov.exponents_per_time),
            stderr=_frozen(lyapunov.stderr),
            running=_frozen(np.empty((0, exponents.size))),
            ky_dimension=float(lyapunov.ky_dimension),
            positive_sum=math.nan,  # not returned by impactchain.api
            collisions_per_cycle=float(lyapunov.collisions_per_cycle),
            stderr_block=getattr(lyapunov, "stderr_block", None),
        )
        if getattr(lyapunov, "finite_time", None) is not None:
            parts["finite_time"] = lyapunov.finite_time
        if "final" not in parts:
            parts["final"] = FinalState(
                x=_frozen(lyapunov.final_x), v=_frozen(lyapunov.final_v),
                cycle=params.transient + params.cycles, phase=params.phase)
    merged = {**settings[-1], **config}
    return Run(
        path=IN_MEMORY,
        schema_version=SCHEMA_VERSION,
        code_version=str(config.get("code_version", "")),
        input_namelist=equivalent_namelist(merged, lyapunov is not None),
        complete=True,
        params=params,
        units=FILE_UNITS,
        **parts,
    )


def is_sweep_dataset(data: Any) -> bool:
    """Is ``data`` an :func:`impactchain.api.sweep` result (an xarray Dataset of /sweep)?"""
    attrs = getattr(data, "attrs", None)
    return (hasattr(data, "data_vars") and isinstance(attrs, Mapping)
            and "parameter" in attrs and "input_namelist" in attrs)


def run_from_sweep(ds: Any) -> Run:
    """A :class:`Run` holding the sweep of :func:`impactchain.api.sweep` (an xarray Dataset),
    for the figures: ``Run.sweep`` with its points in the file's order (version 1's flat
    list, p = i + n1 j), ``Run.params`` from the Dataset's attributes (NaN for the swept
    parameters, as in a sweep file)."""
    if not is_sweep_dataset(ds):
        raise TypeError(f"{type(ds).__name__} is not a sweep of impactchain.api.sweep")
    attrs = ds.attrs
    two_d = bool(attrs["parameter2"])

    def flat(name: str) -> np.ndarray | None:
        return _frozen(_flat_points(np.asarray(ds[name].values), two_d)) if name in ds else None

    values = _point_values(np.asarray(ds["point"].values),
                           np.asarray(ds["point2"].values) if two_d else None)
    drive_period = None
    if "drive_period" in ds:
        axis = 0 if attrs["parameter"] == "omega" else 1
        drive_period = _frozen(2 * math.pi / np.atleast_2d(values.T)[axis])
    sweep = Sweep(parameter=str(attrs["parameter"]), parameter2=str(attrs["parameter2"]),
                  mode=str(attrs["mode"]), values=_frozen(values), x=flat("x"),
                  collisions_per_cycle=flat("collisions_per_cycle"), period=flat("period"),
                  exponents=flat("exponents"), stderr=flat("stderr"),
                  ky_dimension=flat("ky_dimension"), drive_period=drive_period)
    n = int(attrs["n"])
    nan = math.nan
    omega = float(attrs.get("omega", nan))
    params = Params(
        n=n, damping=float(attrs.get("damping", nan)),
        restitution=float(attrs.get("restitution", nan)),
        amplitude=float(attrs.get("amplitude", nan)), omega=omega,
        boundary=str(attrs["boundary"]), drive_period=2 * math.pi / omega,
        phase=float(attrs["phase"]), transient=int(attrs["transient"]),
        cycles=int(attrs["cycles"]),
        spacing=_frozen(np.asarray(attrs.get("spacing", np.full(n + 1, nan)), dtype=float)),
    )
    return Run(path=IN_MEMORY, schema_version=SCHEMA_VERSION,
               code_version=str(attrs["code_version"]),
               input_namelist=str(attrs["input_namelist"]), complete=True, params=params,
               units=FILE_UNITS, sweep=sweep)


def _simulation_parts(sim: Any, params: Params, events: bool) -> dict[str, Any]:
    parts: dict[str, Any] = {
        "strobe": Strobe(x=_frozen(sim.x), v=_frozen(sim.v),
                         cycle=_frozen(np.asarray(sim.cycle, dtype=np.int64)),
                         period=_frozen(np.asarray(sim.periods, dtype=np.int64))),
        "stats": Stats(collisions_per_cycle=float(sim.collisions_per_cycle),
                       impacts=int(sim.impacts), sticks=int(sim.sticks),
                       releases=int(sim.releases),
                       site_counts=_frozen(np.asarray(sim.site_counts, dtype=np.int64)),
                       cycles_done=int(sim.x.shape[0]), touches=int(sim.touches)),
        "final": FinalState(x=_frozen(sim.final_x), v=_frozen(sim.final_v),
                            cycle=params.transient + params.cycles, phase=params.phase),
    }
    if events:
        parts["events"] = Events(
            time=_frozen(sim.event_time),
            site=_frozen(np.asarray(sim.event_site, dtype=np.int64)),
            speed=_frozen(sim.event_speed),
            kind=_frozen(np.asarray(sim.event_kind, dtype=np.int64)))
    return parts


def is_continuation_dataset(data: Any) -> bool:
    """Is ``data`` an :func:`impactchain.api.continuation` result (an xarray Dataset of
    /continuation, as the file's group)?"""
    attrs = getattr(data, "attrs", None)
    return (hasattr(data, "data_vars") and isinstance(attrs, Mapping)
            and "end_reason" in attrs and "special_kind" in data)


def run_from_continuation(ds: Any) -> Run:
    """A :class:`Run` holding the continuation of :func:`impactchain.api.continuation` (an
    xarray Dataset, the file's /continuation group), for the figures. The group does not
    hold the chain's parameters: ``Run.params`` has n, the section's phase and NaN (the
    figures leave unknown parameters out of their titles)."""
    if not is_continuation_dataset(ds):
        raise TypeError(f"{type(ds).__name__} is not a continuation of "
                        "impactchain.api.continuation")
    fields = {name: _frozen(np.asarray(ds[name].values)) for name in Continuation.__annotations__
              if name in ds}
    fields["stable"] = _frozen(fields["stable"] == 1)
    for name in ("special_kind", "origin_kind"):
        if name in ds:
            fields[name] = _frozen(np.asarray([str(k) for k in ds[name].values]))
    cont = Continuation(parameter=str(ds.attrs["parameter"]), phase=float(ds.attrs["phase"]),
                        end_reason=str(ds.attrs["end_reason"]), **fields)
    n = int(ds.sizes["oscillator"])
    nan = math.nan
    params = Params(n=n, damping=nan, restitution=nan, amplitude=nan, omega=nan, boundary="",
                    drive_period=nan, phase=float(ds.attrs["phase"]), transient=0, cycles=0,
                    spacing=_frozen(np.full(n + 1, nan)))
    return Run(path=IN_MEMORY, schema_version=SCHEMA_VERSION, code_version="",
               input_namelist="", complete=True, params=params, units=FILE_UNITS,
               continuation=cont)


def is_curve_tree(data: Any) -> bool:
    """Is ``data`` an :func:`impactchain.api.curve` result (an xarray tree of /continuation and
    /curve without a file's attributes), or a group of one?"""
    return (is_tree(data) and "curve" in data.root.children
            and "schema_version" not in data.root.attrs)


def run_from_curve(tree: Any) -> Run:
    """A :class:`Run` holding the continuation and the curve of :func:`impactchain.api.curve`
    (an xarray tree, or a group of one), for the figures: ``Run.params`` as
    :func:`run_from_continuation` gives them."""
    if not is_curve_tree(tree):
        raise TypeError(f"{type(tree).__name__} is not a curve of impactchain.api.curve")
    root = tree.root
    ds = root["curve"].to_dataset()
    fields = {name: _frozen(np.asarray(ds[name].values)) for name in Curve.__annotations__
              if name in ds}
    fields["codim2_kind"] = _frozen(np.asarray([str(k) for k in ds["codim2_kind"].values]))
    curve = Curve(**{key: str(ds.attrs[key]) for key in ("follow", "parameter", "parameter2",
                                                         "end_reason")}, **fields)
    run = run_from_continuation(root["continuation"].to_dataset())
    return dataclasses.replace(run, curve=curve)


def is_tree(data: Any) -> bool:
    """Is ``data`` an :class:`xarray.DataTree` (``xarray.open_datatree(file)``, or the
    ``to_xarray()`` of an :mod:`impactchain.api` result)?"""
    return type(data).__name__ == "DataTree" and hasattr(data, "to_netcdf")


def run_from_tree(tree: Any, require: Any = (), purpose: str | None = None) -> Run:
    """The :class:`Run` of an xarray tree of an impactchain file: xarray writes it as the
    netCDF-4 file it mirrors, which :func:`impactchain.io.read_run` reads (with ``require``
    and ``purpose``); ``Run.path`` is the tree's source file, if it was read from one. A group
    of a tree (``tree["sweep"]``) stands for its whole tree."""
    from impactchain.io import read_run

    tree = tree.root

    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "tree.h5")
        tree.to_netcdf(path, engine="h5netcdf")
        run = read_run(path, require=require, purpose=purpose)
    source = tree.encoding.get("source", IN_MEMORY)
    return dataclasses.replace(run, path=str(source))
