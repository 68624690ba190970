"""/lyapunov/running holds a bounded selection of the running estimates (every d-th QR step, d
a power of two, and the last step; at most 4097 rows), /lyapunov/running_cycle the drive cycle
of each, and its last row is the final spectrum, bit for bit."""
from __future__ import annotations

import h5py
import numpy as np
import pytest

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
