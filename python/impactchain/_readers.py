"""One reader per optional HDF5 group of a run file (``/initial`` ... ``/finite_time``), each
checking the shapes and values it reads and returning the group's dataclass of
:mod:`impactchain.results`; :func:`impactchain.io.read_run` calls them. Every name they read
or test for goes through the file schema (:mod:`impactchain._hdf5`), so one the table lacks
fails at once.
"""

from __future__ import annotations

import re

import h5py
import numpy as np

from impactchain._hdf5 import (SchemaError, _attr, _dataset, _flat_points, _float, _frozen, _has,
                               _has_attr, _int, _point_values, _str, _strings)
from impactchain.results import (ATTRACTOR_KINDS, IMPACT, RELEASE, SPECIAL_KINDS, STICK, TOUCH,
                                 Census, Clv, Continuation, Curve, Events, FinalState, FiniteTime,
                                 Lyapunov, State, Stats, Strobe, Sweep)


def _read_state(g: h5py.Group, path: str, n: int) -> State:
    return State(
        x=_dataset(g, path, "x", (n,), float),
        v=_dataset(g, path, "v", (n,), float),
    )


def _read_final(g: h5py.Group, path: str, n: int) -> FinalState:
    return FinalState(
        x=_dataset(g, path, "x", (n,), float),
        v=_dataset(g, path, "v", (n,), float),
        cycle=_int(_dataset(g, path, "cycle", None, int), path, f"{g.name}/cycle"),
        phase=_float(_dataset(g, path, "phase", None, float), path, f"{g.name}/phase"),
    )


def _read_strobe(g: h5py.Group, path: str, n: int) -> Strobe:
    x = _dataset(g, path, "x", (None, n), float)
    m = x.shape[0]
    period = _dataset(g, path, "period", (n,), int) if _has(g, "period") else None
    return Strobe(
        x=x,
        v=_dataset(g, path, "v", (m, n), float),
        cycle=_dataset(g, path, "cycle", (m,), int),
        period=period,
    )


def _read_events(g: h5py.Group, path: str, n: int) -> Events:
    time = _dataset(g, path, "time", (None,), float)
    m = time.shape[0]
    site = _dataset(g, path, "site", (m,), int)
    if m and (site.min() < 0 or site.max() > n):
        raise SchemaError(
            f"{path}: /events/site holds values outside 0..{n} "
            f"(found {site.min()}..{site.max()})"
        )
    kind = _dataset(g, path, "kind", (m,), int)
    if m and not np.isin(kind, (IMPACT, STICK, RELEASE, TOUCH)).all():
        raise SchemaError(f"{path}: /events/kind holds values other than 0, 1, 2, 3")
    return Events(time=time, site=site, speed=_dataset(g, path, "speed", (m,), float), kind=kind)


def _read_stats(g: h5py.Group, path: str, n: int) -> Stats:
    return Stats(
        collisions_per_cycle=_float(_attr(g, path, "collisions_per_cycle"), path,
                                    "stats/collisions_per_cycle"),
        impacts=_int(_attr(g, path, "impacts"), path, "stats/impacts"),
        sticks=_int(_attr(g, path, "sticks"), path, "stats/sticks"),
        releases=_int(_attr(g, path, "releases"), path, "stats/releases"),
        site_counts=_dataset(g, path, "site_counts", (n + 1,), int),
        cycles_done=_int(_dataset(g, path, "cycles_done", None, int), path,
                         "stats/cycles_done") if _has(g, "cycles_done") else None,
        touches=_int(_attr(g, path, "touches"), path, "stats/touches")
        if _has_attr(g, "touches") else None,
    )


def _read_lyapunov(g: h5py.Group, path: str) -> Lyapunov:
    exponents = _dataset(g, path, "exponents", (None,), float)
    k = exponents.shape[0]
    running = _dataset(g, path, "running", (None, k), float)
    return Lyapunov(
        exponents=exponents,
        exponents_per_time=_dataset(g, path, "exponents_per_time", (k,), float),
        stderr=_dataset(g, path, "stderr", (k,), float),
        running=running,
        ky_dimension=_float(_attr(g, path, "ky_dimension"), path, "lyapunov/ky_dimension"),
        positive_sum=_float(_attr(g, path, "positive_sum"), path, "lyapunov/positive_sum"),
        collisions_per_cycle=_float(_attr(g, path, "collisions_per_cycle"), path,
                                    "lyapunov/collisions_per_cycle"),
        running_cycle=_dataset(g, path, "running_cycle", (running.shape[0],), int)
        if _has(g, "running_cycle") else None,
        stderr_block=_dataset(g, path, "stderr_block", (k,), int)
        if _has(g, "stderr_block") else None,
    )


def _read_sweep(g: h5py.Group, path: str, n: int) -> Sweep:
    if _has(g, "point"):
        return _read_sweep_v2(g, path, n)
    parameter2 = _str(_attr(g, path, "parameter2"))
    values = _dataset(g, path, "values", (None, 2) if parameter2 else (None,), float)
    p = values.shape[0]
    exponents = _dataset(g, path, "exponents", (p, None), float) if _has(g, "exponents") else None
    k = None if exponents is None else exponents.shape[1]
    return Sweep(
        parameter=_str(_attr(g, path, "parameter")),
        parameter2=parameter2,
        mode=_str(_attr(g, path, "mode")),
        values=values,
        x=_dataset(g, path, "x", (p, None, n), float),
        collisions_per_cycle=_dataset(g, path, "collisions_per_cycle", (p,), float),
        period=_dataset(g, path, "period", (p, n), int),
        exponents=exponents,
        stderr=_dataset(g, path, "stderr", (p, k), float) if _has(g, "stderr") else None,
        ky_dimension=_dataset(g, path, "ky_dimension", (p,), float)
        if _has(g, "ky_dimension") else None,
    )


def _read_sweep_v2(g: h5py.Group, path: str, n: int) -> Sweep:
    """Version 2: the point axes (point, point2) first; returned flattened as version 1."""
    parameter2 = _str(_attr(g, path, "parameter2", ""))
    point = _dataset(g, path, "point", (None,), float)
    n1 = point.shape[0]
    if parameter2:
        point2 = _dataset(g, path, "point2", (None,), float)
        n2 = point2.shape[0]
        axes: tuple[int, ...] = (n1, n2)
    else:
        point2 = None
        axes = (n1,)
    values = _point_values(point, point2)

    def per_point(name: str, tail: tuple[int | None, ...], dtype: type) -> np.ndarray:
        return _frozen(_flat_points(_dataset(g, path, name, axes + tail, dtype), bool(parameter2)))

    exponents = per_point("exponents", (None,), float) if _has(g, "exponents") else None
    k = None if exponents is None else exponents.shape[1]
    drive_period = None
    if _has(g, "drive_period"):
        along = "point" if _str(_attr(g, path, "parameter")) == "omega" else "point2"
        period = _dataset(g, path, "drive_period", (n1 if along == "point" else n2,), float)
        if parameter2:
            period = np.tile(period, n2) if along == "point" else np.repeat(period, n1)
        drive_period = _frozen(period)
    return Sweep(
        parameter=_str(_attr(g, path, "parameter")),
        parameter2=parameter2,
        mode=_str(_attr(g, path, "mode")),
        values=_frozen(values),
        x=per_point("x", (None, n), float),
        collisions_per_cycle=per_point("collisions_per_cycle", (), float),
        period=per_point("period", (n,), int),
        exponents=exponents,
        stderr=per_point("stderr", (k,), float) if _has(g, "stderr") else None,
        ky_dimension=per_point("ky_dimension", (), float) if _has(g, "ky_dimension") else None,
        drive_period=drive_period,
    )


def _read_continuation(g: h5py.Group, path: str, n: int) -> Continuation:
    values = _dataset(g, path, "values", (None,), float)
    p = values.shape[0]
    period = _dataset(g, path, "period", (p,), int)
    if p and period.min() < 1:
        raise SchemaError(f"{path}: {g.name}/period holds {period.min()}; periods are >= 1")
    strobe_x = _dataset(g, path, "strobe_x", (p, None, n), float)
    if p and strobe_x.shape[1] < period.max():
        raise SchemaError(f"{path}: {g.name}/strobe_x has {strobe_x.shape[1]} iterates, "
                          f"fewer than the largest period {period.max()}")
    stable = _dataset(g, path, "stable", (p,), int)
    if not np.isin(stable, (0, 1)).all():
        raise SchemaError(f"{path}: {g.name}/stable holds values other than 0 and 1")
    special_index = _dataset(g, path, "special_index", (None,), int)
    s = special_index.shape[0]
    if s and (special_index.min() < 0 or special_index.max() >= p):
        raise SchemaError(f"{path}: {g.name}/special_index holds values outside 0..{p - 1} "
                          f"(found {special_index.min()}..{special_index.max()})")
    special_kind = _strings(g, path, "special_kind", (s,))
    unknown = sorted({str(kind) for kind in special_kind} - set(SPECIAL_KINDS))
    if unknown:
        raise SchemaError(f"{path}: {g.name}/special_kind holds {', '.join(map(repr, unknown))}"
                          f" (known: {', '.join(SPECIAL_KINDS)})")
    origins = _read_origins(g, path, p) if _has(g, "parent") else {}
    return Continuation(
        parameter=_str(_attr(g, path, "parameter")),
        phase=_float(_attr(g, path, "phase"), path, f"{g.name}/phase"),
        end_reason=_str(_attr(g, path, "end_reason")),
        values=values,
        x=_dataset(g, path, "x", (p, n), float),
        v=_dataset(g, path, "v", (p, n), float),
        strobe_x=strobe_x,
        period=period,
        branch=_dataset(g, path, "branch", (p,), int),
        multipliers_re=_dataset(g, path, "multipliers_re", (p, 2 * n), float),
        multipliers_im=_dataset(g, path, "multipliers_im", (p, 2 * n), float),
        stable=_frozen(stable == 1),
        min_gap=_dataset(g, path, "min_gap", (p,), float),
        min_impact_speed=_dataset(g, path, "min_impact_speed", (p,), float),
        impacts_per_period=_dataset(g, path, "impacts_per_period", (p,), int),
        residual=_dataset(g, path, "residual", (p,), float),
        iterations=_dataset(g, path, "iterations", (p,), int),
        special_index=special_index,
        special_kind=special_kind,
        special_value=_dataset(g, path, "special_value", (s,), float),
        **origins,
    )


def _read_origins(g: h5py.Group, path: str, p: int) -> dict[str, np.ndarray]:
    """Where each branch began (``parent``, ``origin_point``, ``origin_kind``, written since
    they were added to the schema): an earlier branch or -1, a point or -1, a special kind or
    ''."""
    parent = _dataset(g, path, "parent", (None,), int)
    b = parent.shape[0]
    if b and ((parent < -1).any() or (parent >= np.arange(b)).any()):
        raise SchemaError(f"{path}: {g.name}/parent holds a branch that is not an earlier one "
                          f"or -1 (found {parent.tolist()})")
    origin_point = _dataset(g, path, "origin_point", (b,), int)
    if b and (origin_point.min() < -1 or origin_point.max() >= p):
        raise SchemaError(f"{path}: {g.name}/origin_point holds values outside -1..{p - 1}")
    origin_kind = _strings(g, path, "origin_kind", (b,))
    unknown = sorted({str(kind) for kind in origin_kind} - set(SPECIAL_KINDS) - {""})
    if unknown:
        raise SchemaError(f"{path}: {g.name}/origin_kind holds {', '.join(map(repr, unknown))}"
                          f" (known: {', '.join(SPECIAL_KINDS)} or '')")
    return dict(parent=parent, origin_point=origin_point, origin_kind=origin_kind)


def _read_curve(g: h5py.Group, path: str, n: int) -> Curve:
    values = _dataset(g, path, "values", (None,), float)
    c = values.shape[0]
    codim2_index = _dataset(g, path, "codim2_index", (None,), int)
    k = codim2_index.shape[0]
    if k and (codim2_index.min() < 0 or codim2_index.max() >= c):
        raise SchemaError(f"{path}: {g.name}/codim2_index holds values outside 0..{c - 1}")
    return Curve(
        follow=_str(_attr(g, path, "follow")),
        parameter=_str(_attr(g, path, "parameter")),
        parameter2=_str(_attr(g, path, "parameter2")),
        end_reason=_str(_attr(g, path, "end_reason")),
        values=values,
        values2=_dataset(g, path, "values2", (c,), float),
        x=_dataset(g, path, "x", (c, n), float),
        v=_dataset(g, path, "v", (c, n), float),
        multipliers_re=_dataset(g, path, "multipliers_re", (c, 2 * n), float),
        multipliers_im=_dataset(g, path, "multipliers_im", (c, 2 * n), float),
        codim2_index=codim2_index,
        codim2_kind=_strings(g, path, "codim2_kind", (k,)),
    )


def _read_census(g: h5py.Group, path: str, n: int) -> Census:
    values = _dataset(g, path, "point", (None,), float)
    p = values.shape[0]
    x0 = _dataset(g, path, "x0", (p, None, n), float)
    s = x0.shape[1]
    samples = _int(_attr(g, path, "samples"), path, f"{g.name}/samples")
    if s != samples:
        raise SchemaError(f"{path}: {g.name}/x0 holds {s} samples, its 'samples' attribute "
                          f"{samples}")
    kinds = _strings(g, path, "attractor_kind", (None,))
    a = kinds.shape[0]
    unknown = sorted({str(kind) for kind in kinds} - set(ATTRACTOR_KINDS))
    if unknown:
        raise SchemaError(f"{path}: {g.name}/attractor_kind holds "
                          f"{', '.join(map(repr, unknown))} (known: {', '.join(ATTRACTOR_KINDS)})")
    ids = _dataset(g, path, "sample_attractor", (p, s), int)
    if ids.size and (ids.min() < 0 or ids.max() >= a):
        raise SchemaError(f"{path}: {g.name}/sample_attractor holds ids outside 0..{a - 1}")
    point = _dataset(g, path, "attractor_point", (a,), int)
    if a and (point.min() < 0 or point.max() >= p):
        raise SchemaError(f"{path}: {g.name}/attractor_point holds points outside "
                          f"0..{p - 1}")
    mirrored = _dataset(g, path, "mirrored", (p, s), int)
    if not np.isin(mirrored, (0, 1)).all():
        raise SchemaError(f"{path}: {g.name}/mirrored holds values other than 0 and 1")
    plane = None
    plane_range = None
    plane_points = 0
    if _has_attr(g, "plane"):
        names = tuple(_str(_attr(g, path, "plane")).split())
        bad = [name for name in names if not re.fullmatch(r"[xv][0-9]+", name)
               or not 1 <= int(name[1:]) <= n]
        if len(names) != 2 or bad:
            raise SchemaError(f"{path}: {g.name} attribute 'plane' = "
                              f"{_str(_attr(g, path, 'plane'))!r} is not two coordinates x<i> or "
                              f"v<i>, i in 1..{n}")
        plane = (names[0], names[1])
        plane_range = _frozen(np.asarray(_attr(g, path, "plane_range"), dtype=float))
        if plane_range.shape != (4,):
            raise SchemaError(f"{path}: {g.name} attribute 'plane_range' has "
                              f"{plane_range.size} values, expected 4")
        plane_points = _int(_attr(g, path, "plane_points"), path, f"{g.name}/plane_points")
        if plane_points**2 != s:
            raise SchemaError(f"{path}: {g.name}: plane_points = {plane_points} does not "
                              f"square to the {s} samples")
    lambda1 = _dataset(g, path, "lambda1", (p, s), float)
    stored = _has(g, "sample_exponents")
    if stored:
        exponents = _dataset(g, path, "sample_exponents", (p, s, None), float)
        k = exponents.shape[2]
        exponents_stderr = _dataset(g, path, "sample_exponents_stderr", (p, s, k), float)
        attractor_exponents = _dataset(g, path, "attractor_exponents", (a, k), float)
        spread = _dataset(g, path, "attractor_exponents_spread", (a, k), float)
    else:
        exponents = _frozen(lambda1[:, :, np.newaxis].copy())
        exponents_stderr = _frozen(np.full(exponents.shape, np.nan))
        attractor_exponents, spread = _ensembles(exponents, ids, point, a)
    return Census(
        parameter=_str(_attr(g, path, "parameter")),
        samples=samples,
        seed=_int(_attr(g, path, "seed"), path, f"{g.name}/seed"),
        x_amp=_float(_attr(g, path, "x_amp"), path, f"{g.name}/x_amp"),
        v_amp=_float(_attr(g, path, "v_amp"), path, f"{g.name}/v_amp"),
        tolerance=_float(_attr(g, path, "tolerance"), path, f"{g.name}/tolerance"),
        mirror=_str(_attr(g, path, "mirror")),
        rule=_str(_attr(g, path, "rule", "")),
        values=values,
        x0=x0,
        v0=_dataset(g, path, "v0", (p, s, n), float),
        sample_attractor=ids,
        mirrored=_frozen(mirrored == 1),
        lambda1=lambda1,
        attractor_kind=kinds,
        attractor_period=_dataset(g, path, "attractor_period", (a, n), int),
        attractor_lambda1=_dataset(g, path, "attractor_lambda1", (a,), float),
        attractor_lambda1_stderr=_dataset(g, path, "attractor_lambda1_stderr", (a,), float),
        attractor_x=_dataset(g, path, "attractor_x", (a, n), float),
        attractor_v=_dataset(g, path, "attractor_v", (a, n), float),
        attractor_point=point,
        attractor_sample=_dataset(g, path, "attractor_sample", (a,), int),
        attractor_sites=_dataset(g, path, "attractor_sites", (a, n + 1), float),
        fraction=_dataset(g, path, "fraction", (p, a), float),
        fraction_stderr=_dataset(g, path, "fraction_stderr", (p, a), float),
        sample_exponents=exponents,
        sample_exponents_stderr=exponents_stderr,
        attractor_exponents=attractor_exponents,
        attractor_exponents_spread=spread,
        ensemble_stored=stored,
        plane=plane,
        plane_range=plane_range,
        plane_points=plane_points,
    )


def _ensembles(exponents: np.ndarray, ids: np.ndarray, point: np.ndarray,
               a: int) -> tuple[np.ndarray, np.ndarray]:
    """(A, k) the mean of each attractor's samples' exponents and their standard deviation
    (n - 1; 0 for one sample), as the simulator's census defines them: -infinity in some
    member makes the mean -infinity and the spread +infinity (0 when every member's is)."""
    k = exponents.shape[2]
    mean = np.zeros((a, k))
    spread = np.zeros((a, k))
    for attractor in range(a):
        values = exponents[int(point[attractor])][ids[int(point[attractor])] == attractor]
        if values.shape[0] == 0:
            continue
        with np.errstate(invalid="ignore"):
            mean[attractor] = values.mean(axis=0)
        for j in range(k):
            column = values[:, j]
            if column.size == 1:
                continue
            if np.isfinite(column).all():
                spread[attractor, j] = column.std(ddof=1)
            elif not (column == column[0]).all():
                spread[attractor, j] = np.inf
    return _frozen(mean), _frozen(spread)


def _read_clv(g: h5py.Group, path: str, n: int) -> Clv:
    exponents = _dataset(g, path, "exponents", (None,), float)
    k = exponents.shape[0]
    cycle = _dataset(g, path, "cycle", (None,), int)
    r = cycle.shape[0]
    unstable = _int(_attr(g, path, "unstable"), path, f"{g.name}@unstable")
    if not 0 <= unstable <= k:
        raise SchemaError(f"{path}: {g.name}@unstable = {unstable} is outside 0..{k}")
    site_weight = None
    if _has(g, "site_weight"):
        site_weight = _dataset(g, path, "site_weight", (r, None, n), float)
        if site_weight.shape[1] > k:
            raise SchemaError(f"{path}: {g.name}/site_weight holds {site_weight.shape[1]} "
                              f"vectors, more than the {k} of {g.name}/exponents")
    vectors = saved_cycle = None
    if _has(g, "vectors") or _has(g, "saved_cycle"):
        saved_cycle = _dataset(g, path, "saved_cycle", (None,), int)
        vectors = _dataset(g, path, "vectors", (saved_cycle.shape[0], k, 2 * n), float)
    return Clv(
        cycle=cycle,
        exponents=exponents,
        stderr=_dataset(g, path, "stderr", (k,), float),
        stderr_block=_dataset(g, path, "stderr_block", (k,), int),
        ipr=_dataset(g, path, "ipr", (r, k), float),
        min_angle=_dataset(g, path, "min_angle", (r,), float),
        clv_transient=_int(_attr(g, path, "clv_transient"), path, f"{g.name}@clv_transient"),
        unstable=unstable,
        site_weight=site_weight,
        vectors=vectors,
        saved_cycle=saved_cycle,
    )


def _read_finite_time(g: h5py.Group, path: str) -> FiniteTime:
    window = _int(_attr(g, path, "window"), path, f"{g.name}@window")
    if window < 1:
        raise SchemaError(f"{path}: {g.name}@window = {window} must be >= 1")
    cycle = _dataset(g, path, "cycle", (None,), int)
    return FiniteTime(
        window=window,
        cycle=cycle,
        exponents=_dataset(g, path, "exponents", (cycle.shape[0], None), float),
    )
