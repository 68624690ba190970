"""Call the impactchain kernels on numpy arrays, without namelists or files.

The functions here run the very same Fortran code as the command line
(``fpm run --profile release -- input.nml``), through the f2py extension
``impactchain._kernels`` (built when the package is installed: ``pip install .``, which
``make`` runs). Results are bit-identical to the CLI's on the equivalent namelist, and every
bad argument raises a :class:`ValueError` carrying the CLI's own message (``"&chain:
damping = 1.2000000 is outside [0, 1)"``): the checks are the library's
``validate_config``, not a copy of them.

Python and the equivalent namelist / CLI output:

- ``simulate(n, amplitude, omega, ...)``: ``&chain``, ``&initial``, ``&run``; the file's
  ``/strobe``, ``/events``, ``/final``, ``/stats``.
- ``lyapunov(..., vectors=k, qr_every=q)``: ``&lyapunov enabled=T, vectors=k,
  qr_every=q``; ``/lyapunov``.
- ``floquet(..., period=p)``: ``&lyapunov enabled=F, jacobian=T, jacobian_cycles=p``;
  ``/floquet``.
- ``poincare_jacobian(x, v, ...)``: the same kernel at any state (the CLI evaluates it
  only at the final state of a run).
- ``random_start(n, seed, x_amp, v_amp)``: ``&initial kind='random'``.
- ``sweep(..., parameter='amplitude', start, stop, step, ...)``: ``&sweep``; the file's
  ``/sweep`` as an :class:`xarray.Dataset` with the same names (needs xarray).
- ``continuation(..., parameter='amplitude', stop, step, ...)``: ``&continuation``; the
  file's ``/continuation`` as an :class:`xarray.Dataset`, identical to the file's as xarray
  reads it (needs xarray).
- ``periodic_orbit(..., period=p)``: ``&continuation max_points = 1`` (Newton only): the
  orbit of that file's one point, with Newton's history and the Jacobian.
- ``curve(..., follow='fold', parameter2, stop2, step2, ...)``: ``&continuation follow``;
  the file's ``/continuation`` and ``/curve`` as an :class:`xarray.DataTree`, identical to
  the file's as ``xarray.open_datatree`` reads them (needs xarray).
- ``census(..., samples=m)``: ``&census``; the whole census file as an
  :class:`xarray.DataTree` (the installed program's run on a temporary input).

Every function takes any other key of the input table (``impactchain --schema``) as a
keyword, by its name or, where several groups have it, as ``group.key`` (``**{'initial.seed':
3}``), as the CLI's ``--set group.key=value`` (``simulate(16, 1.7, 1.5, kick=0.5)``); unknown
keys are all named at once with the reader's "did you mean". Results are xarray objects or
convert with one call: ``simulate``, ``lyapunov`` and ``floquet`` results' ``to_xarray()``
gives the :class:`xarray.DataTree` of the CLI's file (``xarray.open_datatree(path)``), with
the file's names, dimensions and units; a ``periodic_orbit``'s, its file's ``/continuation``.

Long calls (:func:`simulate`, :func:`lyapunov`, :func:`floquet`, :func:`sweep`,
:func:`continuation`, :func:`periodic_orbit`, :func:`curve`) run the Fortran in a worker
thread with the GIL released while this thread watches it: Ctrl-C stops the computation at its next transient
cycle, strobe record, sweep point or orbit, or within a cycle of millions of events (within a
second unless one orbit alone takes longer) and raises :class:`KeyboardInterrupt`; nothing is
returned from a stopped call. The same holds for calls running in worker threads (a
``ThreadPoolExecutor``'s): importing this module in the main thread lets Ctrl-C stop every
running kernel, unless a program or notebook has put its own SIGINT handler in place.
``progress=True`` shows a tqdm progress bar (needs tqdm).

Argument names are the namelist keys. No ``x0``, ``v0`` is a start at rest
(``kind='rest'``); arrays are ``kind='explicit'`` (no ``v0`` then means v = 0).
``spacing`` is one number (uniform) or the n+1 bond spacings, bond 0 (left wall) first.

Units are the model's reduced ones (docs/model.md section 1.5): time in units of 1/(natural angular
frequency), so one drive cycle lasts ``T = 2 pi / omega``; lengths in the unit of
``spacing``; velocities in length/time. A run starts at t = 0 at drive phase 0; strobe
record j (j = 1..cycles) is taken at t = (transient + j) T + phase/omega.

Example::

    from impactchain import api
    sim = api.simulate(16, amplitude=1.7, omega=1.5, transient=500, cycles=200)
    sim.x.shape                           # (200, 16)
    lyap = api.lyapunov(16, 1.7, 1.5, transient=100, cycles=300)
    lyap.exponents[:3], lyap.stderr[:3]   # bits per drive cycle, descending
    api.floquet(15, 2.16, 1.5, transient=2000, period=2).multipliers  # (30,) complex

The code lives in private modules, a room per topic: ``_calls`` (the extension, argument
conversion, watched calls and Ctrl-C, errors), ``_runs`` (one run and its results),
``_sweeps``, ``_continuations`` and ``_censuses``, ``_xarray`` (results as trees); this module
is their public face.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from impactchain._calls import (
    CONTINUATION_OUTPUTS,
    CURVE_OUTPUTS,
    RUN_OUTPUTS,
    SWEEP_OUTPUTS,
    extension_available,
    provenance,
)
from impactchain._censuses import census
from impactchain._continuations import continuation, periodic_orbit
from impactchain._curves import curve
from impactchain._runs import (
    IMPACT,
    RELEASE,
    STICK,
    TOUCH,
    Floquet,
    Lyapunov,
    PeriodicOrbit,
    Simulation,
    floquet,
    lyapunov,
    poincare_jacobian,
    random_start,
    simulate,
)
from impactchain._sweeps import sweep

__all__ = [
    "Simulation",
    "Lyapunov",
    "Floquet",
    "PeriodicOrbit",
    "simulate",
    "lyapunov",
    "floquet",
    "poincare_jacobian",
    "random_start",
    "sweep",
    "continuation",
    "periodic_orbit",
    "curve",
    "census",
    "extension_available",
    "provenance",
    "IMPACT",
    "STICK",
    "RELEASE",
    "TOUCH",
]

if TYPE_CHECKING:  # the names in the functions' annotations, resolved here by pdoc
    from collections.abc import Mapping

for _name in __all__:
    _public = globals()[_name]
    # help() and reprs name the module users import; the result classes keep their own, where
    # their fields and annotations are written
    if callable(_public) and not isinstance(_public, type):
        _public.__module__ = __name__
del _name, _public
