"""The extension and how it is called: its import, the conversion of Python arguments to
the kernels' types, the calls watched from another thread (progress, Ctrl-C) and the errors
they report (the plumbing of :mod:`impactchain.api`)."""

from __future__ import annotations

import difflib
import operator
import signal
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from impactchain.schema import default as schema_default
from impactchain.schema import inputs as schema_inputs
from impactchain.schema import key as schema_key


try:
    from impactchain import _kernels
except ImportError as _exc:  # not built yet: say how to build it when a function is called
    _kernels = None
    _IMPORT_ERROR: ImportError | None = _exc
else:
    _IMPORT_ERROR = None

_STATUS_OK, _STATUS_INVALID, _STATUS_FAILED, _STATUS_CAPACITY = 0, 1, 2, 3
_STATUS_STOPPED = 5
_POLL_SECONDS = 0.05  # how often the calling thread looks at a running kernel
#: chain_monitor's stages, as (description, unit) of a progress bar
_STAGES = {1: ("transient", "cycle"), 2: ("records", "cycle"), 3: ("sweep", "point")}
#: The same for a continuation, whose unit of progress is an orbit found on a branch
_CONTINUATION_STAGES = {**_STAGES, 3: ("orbits", "orbit")}
_INT32 = (-(2**31), 2**31 - 1)
_INT64 = (-(2**63), 2**63 - 1)

#: Outputs of ``_kernels.ic_run``, in f2py's order (checked by test/python/package/test_api.py).
RUN_OUTPUTS = (
    "final_x", "final_v", "periods", "site_counts", "counts", "collisions_per_cycle", "nev",
    "k", "exponents", "stderr_bits", "stderr_cycles", "per_time", "ky", "jac", "mult_re",
    "mult_im", "status", "msg_len", "message",
)
#: Outputs of ``_kernels.ic_sweep``, in f2py's order (checked by test/python/package/test_api.py).
SWEEP_OUTPUTS = (
    "sizes", "values", "collisions", "period", "exponents", "stderr_bits", "stderr_cycles",
    "ky", "status", "msg_len", "message",
)
#: Outputs of ``_kernels.ic_continuation``, in f2py's order (checked by
#: test/python/package/test_api.py).
CONTINUATION_OUTPUTS = (
    "sizes", "values", "x", "v", "periods", "branch", "mult_re", "mult_im", "stable",
    "symmetric", "min_gap", "min_impact_speed", "impacts", "residual", "iterations",
    "special_index", "special_kind", "special_value", "end_reason", "end_kind", "parent",
    "origin_point", "origin_kind", "start_x", "start_v", "start_jac",
    "start_mult_re", "start_mult_im", "start_residuals", "start_bonds", "start_min_gap",
    "start_min_impact_speed", "start_reason", "status", "msg_len", "message",
)

#: Outputs of ``_kernels.ic_curve``, in f2py's order (checked by
#: test/python/package/test_api.py).
CURVE_OUTPUTS = (
    "sizes", "values", "values2", "x", "v", "mult_re", "mult_im", "codim2_index",
    "codim2_kind", "end_reason", "status", "msg_len", "message",
)


def extension_available() -> bool:
    """Whether the compiled extension ``impactchain._kernels`` could be imported."""
    return _kernels is not None


def _extension() -> Any:
    if _kernels is None:
        raise ImportError(
            "the compiled extension impactchain._kernels is missing: install the package "
            "with `pip install .` (or `make`) from the repository; an import of "
            f"impactchain from the source tree has no extension ({_IMPORT_ERROR})")
    return _kernels


#: The keys of the input table that the run functions hand the bridge as arguments of its
#: own, by name and group; every other key goes as an override (``group.key=value``)
_ARGUMENT_KEYS = {"damping": "chain", "restitution": "chain", "spacing": "chain",
                  "boundary": "chain", "x0": "initial", "v0": "initial", "transient": "run",
                  "phase": "run", "stick_speed": "run", "max_size_mb": "output"}
#: Keys a function sets from its own parameters or its kind of run, never from ``**keys``
_FUNCTION_KEYS = {("chain", "n"), ("chain", "amplitude"), ("chain", "omega"),
                  ("run", "cycles"), ("run", "record_events"), ("lyapunov", "enabled"),
                  ("lyapunov", "vectors"), ("lyapunov", "qr_every"), ("lyapunov", "window"),
                  ("lyapunov", "jacobian"), ("lyapunov", "jacobian_cycles"),
                  ("output", "file")}
#: Groups of a kind of run whose keys are the parameters of its own function
_RUN_KINDS = ("sweep", "continuation", "census")


def _keys(keys: Mapping[str, Any], home: Sequence[str] = ()) -> dict[tuple[str, str], Any]:
    """Each keyword of ``**keys`` as ``(group, key)`` of the input table: ``group.key`` as
    written, a bare name in the one group that has it (in the first of ``home`` when several
    do; the groups of sweeps, continuations and censuses only when in ``home``). A name of no
    group is kept as written under the group of the nearest key (else &chain, the model's,
    where the paper's symbols live), so that the reader's "did you mean" names it, with
    every other unknown key at once."""
    groups: dict[str, list[str]] = {}
    for entry in schema_inputs():  # (a kind of run's keys are its function's arguments)
        if entry["group"] not in _RUN_KINDS or entry["group"] in home:
            groups.setdefault(entry["name"], []).append(entry["group"])
    resolved: dict[tuple[str, str], Any] = {}
    for written, value in keys.items():
        group, dot, name = written.rpartition(".")
        if dot:
            group = group.lower()
        elif name.lower() in groups:
            found = groups[name.lower()]
            group = next((g for g in home if g in found), found[0])
            if len(found) > 1 and group not in home:
                raise TypeError(f"{name} is a key of " + " and ".join(f"&{g}" for g in found)
                                + f": name one, e.g. **{{'{found[0]}.{name}': ...}}")
        else:
            near = difflib.get_close_matches(name.lower(), list(groups), n=1)
            group = groups[near[0]][0] if near else "chain"
        if name.lower() in groups and group in groups[name.lower()]:
            name = name.lower()
        if (group, name) in _FUNCTION_KEYS or (group in _RUN_KINDS and group not in home):
            raise TypeError(f"&{group} {name} is not set through **keys here: it is an "
                            "argument of this function, or of the function of its kind of run")
        resolved[(group, name)] = value
    return resolved


def _namelist_value(value: Any) -> str:
    """A Python value as namelist text (reals to every bit: repr round-trips a double)."""
    if isinstance(value, (bool, np.bool_)):
        return ".true." if value else ".false."
    if isinstance(value, str):
        return "'" + value.replace("'", "''") + "'"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    if np.ndim(value) == 1:
        return ", ".join(_namelist_value(v) for v in np.asarray(value).tolist())
    raise TypeError(f"{value!r}: a key's value is a number, a string, a bool or a list")


def _overrides(given: Mapping[tuple[str, str], Any]) -> NDArray[np.int32]:
    """The bridge's ``overrides``: a ``group.key=value`` line per key, as byte values."""
    lines = "".join(f"{group}.{key}={_namelist_value(value)}\n"
                    for (group, key), value in given.items())
    return np.frombuffer(lines.encode(), dtype=np.uint8).astype(np.int32)


def _argument(given: dict[tuple[str, str], Any], name: str) -> Any:
    """A key the bridge takes as an argument: given (and taken out of ``given``), else the
    table's default (x0, v0: None, a start at rest)."""
    key = (_ARGUMENT_KEYS[name], name)
    if key in given:
        return given.pop(key)
    return None if name in ("x0", "v0") else schema_default(*key)


def _config(n: Any, amplitude: Any, omega: Any, cycles: Any, keys: Mapping[str, Any],
            home: Sequence[str] = ()) -> dict[str, Any]:
    """The arguments of ``ic_run`` describing one run (Python types converted only): those
    the bridge takes, from ``keys`` or the table's defaults, and every other key of ``keys``
    as ``overrides``."""
    given = _keys(keys, home)
    arg = {name: _argument(given, name) for name in _ARGUMENT_KEYS}
    nn = _n(n)
    x0, v0 = arg["x0"], arg["v0"]
    explicit = x0 is not None or v0 is not None
    xs = np.zeros(max(nn, 0)) if x0 is None and explicit else _vector(x0, "&initial: x0")
    return dict(
        n=nn,
        spacing=_spacing(arg["spacing"]),
        damping=_float(arg["damping"], "damping"),
        restitution=_float(arg["restitution"], "restitution"),
        amplitude=_float(amplitude, "amplitude"),
        omega=_float(omega, "omega"),
        boundary=_name(arg["boundary"], "boundary"),
        explicit=int(explicit),
        x0=xs,
        v0=_vector(v0, "&initial: v0"),
        transient=_int64(arg["transient"], "&run: transient", "[0, 1e12]"),
        cycles=_int64(cycles, "&run: cycles", "[1, 1e12]"),
        phase=_float(arg["phase"], "phase"),
        stick_speed=_float(arg["stick_speed"], "stick_speed"),
        max_size_mb=_float(arg["max_size_mb"], "max_size_mb"),
        record_events=0,
        lyapunov=0,
        vectors=0,
        qr_every=1,
        jacobian=0,
        jacobian_cycles=1,
        overrides=_overrides(given),
    )


def _used(cfg: dict[str, Any], **extra: Any) -> Mapping[str, Any]:
    """The arguments of a run as used, read-only (``Simulation.params``); ``overrides``:
    the other keys given, as ``group.key=value`` lines."""
    n = cfg["n"]
    start = bool(cfg["explicit"])
    x0 = cfg["x0"] if start else None
    v0 = (cfg["v0"] if cfg["v0"].size else np.zeros(n)) if start else None
    used = dict(
        n=n, amplitude=cfg["amplitude"], omega=cfg["omega"], damping=cfg["damping"],
        restitution=cfg["restitution"],
        spacing=_frozen(np.broadcast_to(cfg["spacing"], (n + 1,)).copy()),
        boundary=_text(cfg["boundary"]), x0=None if x0 is None else _frozen(x0.copy()),
        v0=None if v0 is None else _frozen(np.array(v0, dtype=np.float64)),
        transient=cfg["transient"], cycles=cfg["cycles"], phase=cfg["phase"],
        stick_speed=cfg["stick_speed"], overrides=tuple(_text(cfg["overrides"]).splitlines()),
        code_version=_code_version(), **extra)
    return MappingProxyType(used)


def provenance() -> Mapping[str, str]:
    """Where the extension runs: ``code_version``, ``compiler``, ``compiler_options``, ``blas``
    (name, version, build), ``blas_kernel`` (the kernels the BLAS selected on this CPU) and
    ``cpu_model``; the root attributes of the files the command line writes on this machine
    and the lines of ``impactchain --version`` (one table: src/base/chain_provenance.f90).
    (``compiler_options`` are the extension's own, which name other build directories.)"""
    text_len, text = _extension().ic_provenance()
    lines = bytes(np.asarray(text[:text_len]).astype(np.uint8)).decode().splitlines()
    return MappingProxyType(dict(line.split(": ", 1) for line in lines))


def _code_version() -> str:
    from impactchain import __version__

    return f"impactchain.api {__version__}"


class _RunningKernels:
    """The control arrays of the kernels running now, in any thread, so that Ctrl-C stops
    them all: Python delivers SIGINT to the main thread only, and a kernel running in a
    worker (a ``ThreadPoolExecutor``'s) would otherwise go on to its end while the executor
    waits for it. A kernel that a worker starts within a second after Ctrl-C (the next task
    an executor had queued) is stopped at once too, so that the executor's wait ends."""

    _AFTER_INTERRUPT = 1.0  # seconds after Ctrl-C in which new kernels of workers stop

    def __init__(self) -> None:
        # (reentrant: the handler runs in the main thread, which may hold it then)
        self._lock = threading.RLock()
        self._controls: dict[int, NDArray[np.int64]] = {}
        self._interrupted_at = -float("inf")

    def __len__(self) -> int:
        with self._lock:
            return len(self._controls)

    def add(self, control: NDArray[np.int64]) -> None:
        with self._lock:
            self._controls[id(control)] = control
            if (threading.current_thread() is not threading.main_thread()
                    and time.monotonic() - self._interrupted_at < self._AFTER_INTERRUPT):
                control[0] = 1

    def remove(self, control: NDArray[np.int64]) -> None:
        with self._lock:
            self._controls.pop(id(control), None)

    def on_interrupt(self, signum: int, frame: Any) -> None:
        """SIGINT: every kernel asked to stop, then Python's KeyboardInterrupt as always."""
        with self._lock:
            self._interrupted_at = time.monotonic()
            for control in self._controls.values():
                control[0] = 1
        signal.default_int_handler(signum, frame)


_RUNNING = _RunningKernels()


def _stop_kernels_on_interrupt() -> None:
    """Let Ctrl-C reach kernels in worker threads: Python's own SIGINT handler, if it is the
    one in place, is replaced by one that also stops them (a program's or a notebook's own
    handler is left alone). Only the main thread can set a handler: done at import there."""
    if threading.current_thread() is not threading.main_thread():
        return
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, _RUNNING.on_interrupt)


_stop_kernels_on_interrupt()


def _watched(kernel: Callable[..., Any], args: dict[str, Any], progress: bool,
             stages: Mapping[int, tuple[str, str]] = _STAGES) -> Any:
    """``kernel(**args, control=...)`` in a worker thread, watched from this one.

    The kernel releases the GIL and polls ``control`` (int64, 4 values: chain_bridge's
    shared_monitor_t) at every transient cycle, record and sweep point, and every few
    thousand events within a cycle: control[0] set here asks it to stop; it keeps
    control[1:4] = stage, done, total. Ctrl-C here (this thread gets Python's signals) sets
    the flag, waits for the kernel to stop, and re-raises; Ctrl-C while this runs in another
    thread sets it too (_RUNNING), and the kernel's stop is raised here.
    """
    control = np.zeros(4, dtype=np.int64)
    outcome: dict[str, Any] = {}

    def work() -> None:
        try:
            outcome["result"] = kernel(**args, control=control)
        except BaseException as exc:  # handed to the calling thread
            outcome["error"] = exc

    bar = _ProgressBar(stages) if progress else None
    worker = threading.Thread(target=work, name="impactchain-kernel", daemon=True)
    _RUNNING.add(control)
    worker.start()
    try:
        while worker.is_alive():
            worker.join(_POLL_SECONDS)
            if bar is not None:
                bar.show(control)
    except KeyboardInterrupt:
        control[0] = 1
        worker.join()
        raise
    finally:
        _RUNNING.remove(control)
        if bar is not None:
            bar.close()
    if "error" in outcome:
        raise outcome["error"]
    return outcome["result"]


class _ProgressBar:
    """A tqdm bar per stage of a watched kernel (a new one when the stage changes)."""

    def __init__(self, stages: Mapping[int, tuple[str, str]] = _STAGES) -> None:
        try:
            from tqdm.auto import tqdm
        except ImportError:
            raise ImportError("progress=True needs tqdm: pip install tqdm") from None
        self._tqdm = tqdm
        self._stages = stages
        self._bar: Any = None
        self._stage = 0

    def show(self, control: NDArray[np.int64]) -> None:
        stage, done, total = (int(c) for c in control[1:4])
        if stage not in self._stages:
            return
        if stage != self._stage:
            self.close()
            description, unit = self._stages[stage]
            self._bar = self._tqdm(total=total, desc=description, unit=unit, leave=False)
            self._stage = stage
        self._bar.total = total
        self._bar.update(done - self._bar.n)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None


def _raise_for(status: int, msg_len: int, message: NDArray[np.int32]) -> None:
    if status == _STATUS_OK:
        return
    text = bytes(np.asarray(message[:msg_len]).astype(np.uint8)).decode("utf-8", "replace")
    if status == _STATUS_INVALID:
        raise ValueError(text)
    if status == _STATUS_FAILED:
        raise RuntimeError(text)
    if status == _STATUS_STOPPED:  # (Ctrl-C while the call ran in another thread)
        raise KeyboardInterrupt(text)
    raise RuntimeError(f"impactchain extension (status {status}): {text}")


def _frozen(a: NDArray[Any]) -> NDArray[Any]:
    a = np.asarray(a)
    a.setflags(write=False)
    return a


def _float(value: Any, name: str) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(
            value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a real number, not {type(value).__name__}")
    return float(value)


def _integer(value: Any, name: str) -> int:
    if isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be an integer, not bool")
    try:
        return operator.index(value)
    except TypeError:
        raise TypeError(f"{name} must be an integer, not {type(value).__name__}") from None


def _int32(value: Any, key: str, allowed: str) -> int:
    """An integer argument; one beyond 32 bits gets the CLI's message for that key."""
    i = _integer(value, key.split(": ")[-1])
    if not _INT32[0] <= i <= _INT32[1]:
        raise ValueError(f"{key} = {i} is outside {allowed}")
    return i


def _n(value: Any) -> int:
    """n, refused outside the CLI's range before anything of size n is made (the kernels
    check it too, but only after their arguments, sized by n, exist)."""
    n = _integer(value, "n")
    # (refused here, before any allocation, as the reader would: the table's range)
    most = int(schema_key("chain", "n")["max"])
    if not 1 <= n <= most:
        raise ValueError(f"&chain: n = {n} is outside [1, {most}]")
    return n


def _int64(value: Any, key: str, allowed: str) -> int:
    i = _integer(value, key.split(": ")[-1])
    if not _INT64[0] <= i <= _INT64[1]:
        raise ValueError(f"{key} = {i} is outside {allowed}")
    return i


def _vector(value: Any, key: str, length: str = "n") -> NDArray[np.float64]:
    """A 1-D float64 array (empty for None); lengths are checked by the library."""
    if value is None:
        return np.zeros(0)
    name = key.split(": ")[-1]
    if np.iscomplexobj(value):  # (a cast would drop the imaginary part with a warning)
        raise TypeError(f"{name} must be an array of real numbers, not complex")
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be an array of real numbers") from None
    if a.ndim != 1:
        raise ValueError(f"{key} must be a 1-D array of {length} values, got shape {a.shape}")
    return np.ascontiguousarray(a)


def _spacing(value: Any) -> NDArray[np.float64]:
    """One value (uniform) or n+1 values, as the namelist's ``spacing``."""
    if np.ndim(value) == 0:
        return np.array([_float(value, "spacing")])
    return _vector(value, "&chain: spacing", "n+1")


def _name(value: Any, name: str) -> NDArray[np.int32]:
    """A keyword value as the namelist reader sees it (trimmed, lower case), as bytes."""
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a string, not {type(value).__name__}")
    return np.frombuffer(value.strip().lower().encode(), dtype=np.uint8).astype(np.int32)


def _text(name: NDArray[np.int32]) -> str:
    """A name passed to the kernels as byte values (:func:`_name`), as text."""
    return bytes(np.asarray(name).astype(np.uint8)).decode()
