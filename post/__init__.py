"""Post-processing of impactchain HDF5 output: reading, analysis and the paper's figures.

Modules: :mod:`post.io` (the file layout), :mod:`post.shockwave` (shock-wave
construction), :mod:`post.analysis` (period labels, panels),
:mod:`post.figures` (figure functions returning ``matplotlib.figure.Figure``) and
:mod:`post.cli` (``python -m post``).
"""

__version__ = "0.1.0"
