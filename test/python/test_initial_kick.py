"""&initial kick: a velocity given to oscillator 1 at t = 0 on top of any start but a file's
(an impulse at the left end, the classic way to send a wave down a chain)."""
from __future__ import annotations

import h5py
import numpy as np

from simulator import impactchain_exe, run_namelist  # noqa: F401 (fixture)

TEXT = """&chain n = 4, amplitude = 0.2, omega = 1.5 /
&initial {initial} /
&run cycles = 20 /
&output file = '{name}.h5' /
"""


def run(exe, tmp_path, initial, name):
    run_namelist(exe, TEXT.format(initial=initial, name=name), tmp_path, f"{name}.nml")
    with h5py.File(tmp_path / f"{name}.h5") as f:
        return f["initial/v"][()], f["strobe/x"][()]


def test_kick_starts_oscillator_1_moving(impactchain_exe, tmp_path):  # noqa: F811
    v_rest, x_rest = run(impactchain_exe, tmp_path, "kind = 'rest'", "rest")
    v_kick, x_kick = run(impactchain_exe, tmp_path, "kind = 'rest', kick = 0.5", "kick")
    np.testing.assert_array_equal(v_rest, [0, 0, 0, 0])
    np.testing.assert_array_equal(v_kick, [0.5, 0, 0, 0])
    assert not np.array_equal(x_rest, x_kick)
    # on top of an explicit start
    v_both, _ = run(impactchain_exe, tmp_path,
                    "kind = 'explicit', x0 = 0, 0, 0, 0, v0 = 0.1, 0.2, 0.3, 0.4, kick = -0.5",
                    "both")
    np.testing.assert_array_equal(v_both, [0.1 - 0.5, 0.2, 0.3, 0.4])


def test_kick_out_of_range_is_refused(impactchain_exe, tmp_path):  # noqa: F811
    result = run_namelist(impactchain_exe, TEXT.format(initial="kick = 2e6", name="bad"),
                          tmp_path, check=False)
    assert result.returncode != 0
    assert "&initial: kick = " in result.stderr
    assert "is outside [-1e6, 1e6]" in result.stderr
