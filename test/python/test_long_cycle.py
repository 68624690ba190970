"""Issue 30, 4: a drive cycle can hold millions of events (a dense elastic chain), and a run
then shows its progress and takes a stop request within that cycle, not only at records.
A stop within a cycle ends the run at its last record, as a stop there would: the file keeps
every finished record and the same command continues it to the uninterrupted run's file, bit
for bit. A stop within the cycle of the first record has nothing to keep and says so."""
from __future__ import annotations

import signal
import subprocess
from pathlib import Path

import h5py
import numpy as np

from simulator import impactchain_exe, run_namelist, start_until_progress  # noqa: F401
from test_continue_run import _contents, _same

# Undamped, elastic, nearly touching: about 2.6 million impacts per drive cycle (seconds of
# work per cycle on any machine; the tests wait for what the run says, not for a time).
DENSE = """&chain n = 60, spacing = 1.0e-5, damping = 0.0, restitution = 1.0,
       amplitude = 1.7, omega = 1.5 /
&initial kind = 'random', seed = 1, x_amp = 1.0e-6, v_amp = 0.3 /
&run transient = 0, cycles = {cycles}, record_events = .false. /
&output file = 'dense.h5' /
"""


def test_progress_and_a_stop_within_the_first_cycle(impactchain_exe, tmp_path):
    """Progress shows within the first cycle (after IMPACTCHAIN_PROGRESS_AFTER = 0 seconds,
    on a pipe at once and then once a minute); SIGINT there ends the run at once, before any
    record: an error saying so, and no file. Before, nothing was shown and the signal waited
    for the cycle's end."""
    (tmp_path / "dense.nml").write_text(DENSE.format(cycles=2))
    proc, shown = start_until_progress(impactchain_exe, ["dense.nml"], tmp_path,
                                       label="the first cycle under way,")
    assert " events so far (" in shown
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 1, err
    assert ("run stopped during the drive cycle of its first record, before that record: "
            "nothing was recorded") in err
    assert not list(tmp_path.glob("dense.h5*"))


def test_a_stop_within_a_cycle_keeps_the_records_before_it(impactchain_exe, tmp_path):
    """SIGTERM during the second cycle (just after the first record is shown) ends the run
    at the first record, not at the end of the cycle; the same command then continues it to
    the uninterrupted run's file."""
    whole = tmp_path / "whole"
    whole.mkdir()
    run_namelist(impactchain_exe, DENSE.format(cycles=2), whole, "dense.nml")
    (tmp_path / "dense.nml").write_text(DENSE.format(cycles=2))
    proc, _ = start_until_progress(impactchain_exe, ["dense.nml"], tmp_path,
                                   label="cycle 1 / 2")
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 3, err
    with h5py.File(tmp_path / "dense.h5") as f:
        assert int(np.ravel(f.attrs["complete"])[0]) == 0
        assert int(f["stats/cycles_done"][()]) == 1
        with h5py.File(whole / "dense.h5") as g:
            assert np.array_equal(f["strobe/x"][()], g["strobe/x"][:1])
    result = run_namelist(impactchain_exe, DENSE.format(cycles=2), tmp_path, "dense.nml")
    assert "continued a run stopped early after 1 records" in result.stdout
    a, b = _contents(whole / "dense.h5"), _contents(tmp_path / "dense.h5")
    assert sorted(a) == sorted(b)
    assert not [name for name in a if not _same(a[name], b[name])]
