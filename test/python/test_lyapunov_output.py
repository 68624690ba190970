"""/lyapunov/running holds a bounded selection of the running estimates (every d-th QR step, d
a power of two, and the last step; at most 4097 rows), /lyapunov/running_cycle the drive cycle
of each, and its last row is the final spectrum, bit for bit. /finite_time's windows average to
the exponents; bad windows are named."""
from __future__ import annotations

import h5py
import numpy as np
import pytest

from impactchain.io import read_run
from simulator import impactchain_exe, run_namelist  # noqa: F401 (fixture)

CAPACITY = 4096


def _rows(steps: int) -> tuple[int, int]:
    """(stride, rows) of a run of `steps` QR steps."""
    stride = 1
    while steps // stride > CAPACITY:
        stride *= 2
    return stride, steps // stride + (steps % stride != 0)


@pytest.mark.parametrize("cycles, qr_every", [(10000, 1), (9001, 1), (1000, 3)])
def test_running_estimates_are_bounded(impactchain_exe, tmp_path, cycles, qr_every):
    run_namelist(impactchain_exe,
                 "&chain n = 2, amplitude = 2.5, omega = 1.2 /\n"
                 "&initial kind = 'random', seed = 3, x_amp = 0.3, v_amp = 0.5 /\n"
                 f"&run transient = 7, cycles = {cycles}, record_events = .false. /\n"
                 f"&lyapunov qr_every = {qr_every} /\n&output file = 'l.h5' /\n", tmp_path)
    steps = cycles // qr_every
    stride, rows = _rows(steps)
    with h5py.File(tmp_path / "l.h5") as f:
        running = f["lyapunov/running"][:]
        assert running.shape == (rows, 4)
        kept = np.arange(1, steps // stride + 1) * stride
        if steps % stride:
            kept = np.append(kept, steps)
        records = kept * qr_every
        assert f["lyapunov/running_cycle"].dtype == np.int64
        np.testing.assert_array_equal(f["lyapunov/running_cycle"][:],
                                      f["strobe/cycle"][:][records - 1])
        np.testing.assert_array_equal(running[-1], f["lyapunov/exponents"][:])


WINDOWED = """&chain n = 4, amplitude = 1.7, omega = 1.5 /
&initial kind = 'random', seed = 3, x_amp = 0.3, v_amp = 0.5 /
&run transient = 50, cycles = 600, record_events = .false. /
&lyapunov vectors = 3, window = 100{extra} /
&output file = 'w.h5' /
"""


def test_finite_time_windows_and_block_sizes(impactchain_exe, tmp_path):
    """/finite_time: 6 windows of 100 cycles whose mean is the exponents (of the frame's
    columns: on this chain the first two, -0.0221 and -0.0226 bits per cycle, cross, and
    /lyapunov/exponents sorts them); /lyapunov/stderr_block: block sizes within the run."""
    run_namelist(impactchain_exe, WINDOWED.format(extra=""), tmp_path)
    with h5py.File(tmp_path / "w.h5") as f:
        windows = f["finite_time/exponents"][()]
        assert windows.shape == (6, 3) and int(f["finite_time"].attrs["window"]) == 100
        assert np.all(np.diff(f["finite_time/cycle"][()]) == 100)
        means = windows.mean(axis=0)
        assert means[0] < means[1]
        np.testing.assert_allclose(np.sort(means)[::-1], f["lyapunov/exponents"][()],
                                   rtol=0, atol=1e-12)
        block = f["lyapunov/stderr_block"][()]
        assert block.dtype == np.int64 and np.all(block >= 1) and np.all(block <= 600)
        assert np.all(f["lyapunov/stderr"][()] > 0)
    ft = read_run(tmp_path / "w.h5").finite_time
    np.testing.assert_array_equal(ft.descending, windows[:, [1, 0, 2]])


@pytest.mark.parametrize("extra, needle", [
    (", window = 601", "&lyapunov: window = 601 is outside [0, cycles = 600]"),
    (", window = -1", "&lyapunov: window = -1 is outside [0, cycles = 600]"),
    (", qr_every = 3", "&lyapunov: window = 100 must be a multiple of qr_every = 3"),
    (", enabled = .false.", "&lyapunov: window = 100 needs enabled = .true."),
])
def test_bad_windows_are_named(impactchain_exe, tmp_path, extra, needle):
    text = WINDOWED.format(extra=extra)
    if "window = 601" in extra or "window = -1" in extra:
        text = text.replace("window = 100, ", "")
    result = run_namelist(impactchain_exe, text, tmp_path, check=False)
    assert result.returncode == 1
    assert needle in result.stderr, result.stderr
    assert not list(tmp_path.glob("*.h5*"))


def test_windows_are_for_single_runs(impactchain_exe, tmp_path):
    text = WINDOWED.format(extra="") + ("&sweep parameter = 'amplitude', start = 1.7, "
                                        "stop = 1.8, step = 0.1 /\n")
    result = run_namelist(impactchain_exe, text, tmp_path, check=False)
    assert result.returncode == 1
    assert "window = 100 is for a single run, not a &sweep or a &census" in result.stderr
