"""Figures of the paper, built from :mod:`impactchain.io` runs.

Every figure function takes its data as a :class:`impactchain.io.Run`, a path to an impactchain
HDF5 file, or an in-memory result of :mod:`impactchain.api` (anything with a ``to_run()`` method
returning a Run: ``api.Simulation``, ``api.Lyapunov``), and returns a
:class:`matplotlib.figure.Figure`, without pyplot or global state. With ``ax=None`` the
function makes its own figure (a :class:`ProvenanceFigure`); with ``ax=`` (one Axes, or a
sequence of them for a multi-panel figure, in the order each function documents) it draws
there and returns the root figure of those axes, leaving that figure's title to the caller.

Conventions, the same in every figure:

- Axis labels read ``name $symbol$ [unit]``: a short name, the symbol where the quantity has
  one, and the unit in brackets, ``[1]`` for a dimensionless quantity. Units are the
  ``units`` attributes of the datasets shown (:data:`impactchain.io.FILE_UNITS` for a run made in
  memory); the model parameters, which the file stores without units, are in the model's
  reduced units (docs/model.md section 1.5): ``A`` and the spacing ``a`` in [length], ``w``
  in [1/time], ``b`` and ``K`` in [1].
- Colour that encodes a number has a colour bar; colour that tells runs apart has a legend
  naming the parameter or the seed that differs (:func:`run_labels`), never a file name.
- Panels that show the same quantity share their limits (y, or z in 3-D).
- Lyapunov exponents are drawn with their stored standard errors (bands, or bars for a
  sweep that goes back and forth).
- Saving a figure with :func:`save` (or ``savefig`` of a figure made here) writes the code
  version, the input namelists and the source file names into the file's metadata
  (:func:`metadata`).

Time in the space-time-amplitude and shock-wave figures is in drive cycles, t/T, so that
the strobe record of cycle c sits at c + phase/(2 pi) and both figures share panel ranges
for the same options.

The figures by topic, one module each: :mod:`~impactchain.figures.timeseries`
(space-amplitude, space-time-amplitude, Poincare section), :mod:`~impactchain.figures.shockwave`,
:mod:`~impactchain.figures.sweeps` (bifurcation, Lyapunov exponents, Kaplan-Yorke dimension),
:mod:`~impactchain.figures.spectra` (spectrum, finite-time exponents),
:mod:`~impactchain.figures.clv` (covariant vectors), :mod:`~impactchain.figures.orbits`
(continued orbits and their branches), :mod:`~impactchain.figures.charts` (curves in two
parameters over a two-parameter sweep) and :mod:`~impactchain.figures.census` (attractor
censuses). ``_style`` holds what they share (colours, labels, titles), ``_canvas`` where they
draw and how a figure is saved, ``_data`` what they take. Every public name is reachable as
``impactchain.figures.NAME``; ``__all__`` lists the figures, their error and how to save them.
"""

# every public name of the topic modules, reachable as impactchain.figures.NAME
from impactchain.figures._canvas import ProvenanceFigure, metadata, save
from impactchain.figures._data import RunLike, SupportsRun, as_run, run_labels
from impactchain.figures._style import (BAND_ALPHA, LEFT_COLOUR, OVERLAY_COLOURS, RIGHT_COLOUR,
                                        TIME_LABEL_UNIT, WALL_STYLE, FigureError)
from impactchain.figures.census import (ATTRACTOR_COLOURS, MIRROR_BLEND, SAMPLE_ALPHA,
                                        basin_fractions, basin_plane, ensemble_spectra)
from impactchain.figures.charts import (APERIODIC_COLOUR, CODIM2_STYLE, EXPONENT_CMAP,
                                        EXPONENT_SCALE, IMPACTS_CAP, QUANTITIES, chain_period,
                                        chart, map_grid)
from impactchain.figures.clv import (CLV_CMAP, IMPACT_COLOUR, NEAR_TANGENCY, clv_angles, clv_ipr,
                                     clv_space_time)
from impactchain.figures.orbits import (BRANCH_COLOURS, LOG_SPAN, OVER_COLOUR, SPECIAL_STYLES,
                                        branches, multipliers)
from impactchain.figures.shockwave import shock_wave, wave_points
from impactchain.figures.spectra import FINITE_TIME_BINS, FINITE_TIME_FILL, finite_time, spectrum
from impactchain.figures.sweeps import bifurcation, ky_dimension, lyapunov
from impactchain.figures.timeseries import poincare, space_amplitude, space_time_amplitude

__all__ = [
    # one run's record
    "space_amplitude", "space_time_amplitude", "poincare", "shock_wave",
    # sweeps
    "bifurcation", "lyapunov", "ky_dimension",
    # spectra and covariant vectors
    "spectrum", "finite_time", "clv_space_time", "clv_ipr", "clv_angles",
    # orbits and branches
    "branches", "multipliers",
    # curves in two parameters
    "chart",
    # censuses
    "basin_fractions", "basin_plane", "ensemble_spectra",
    # errors and saving with provenance
    "FigureError", "save", "metadata",
]
