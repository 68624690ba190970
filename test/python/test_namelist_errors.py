"""Input mistakes reported so a person can act on them (file:line, the key, the valid keys, a
"did you mean"), and the command line's overrides, output options and --check."""
from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import h5py
import numpy as np
import pytest

from simulator import ROOT, impactchain_exe, run_namelist  # noqa: F401 (fixture)

GOOD = """&chain n = 4, amplitude = 1.7, omega = 1.5 /
&initial kind = 'random', seed = 3, x_amp = 0.2, v_amp = 0.2 /
&run transient = 5, cycles = 8 /
&output file = 'run.h5' /
"""

MISTAKES = {
    "misspelt key": ("&chain n = 4, omgea = 1.5, amplitude = 1 /",
                     ["input.nml:1:", "&chain", "unknown key 'omgea'", "did you mean 'omega'",
                      "n, spacing, damping, restitution, amplitude, omega, boundary"]),
    "integer given a fraction": ("! a comment\n&chain\n  n = 4.5, omega = 1.5, amplitude = 1 /",
                                 ["input.nml:3:", "n = 4.5 is not an integer"]),
    "key of another group": ("&chain n = 4, omega = 1.5, amplitude = 1 /\n&run damping = 0.1 /",
                             ["input.nml:2:", "&run", "'damping' is a key of &chain",
                              "transient, cycles"]),
    "logical": ("&chain n = 4, omega = 1.5, amplitude = 1 /\n&run record_events = yes /",
                ["input.nml:2:", "record_events = yes is not a logical"]),
    "number": ("&chain n = 4, omega = fast, amplitude = 1 /", ["omega = fast is not a number"]),
    "unknown group": ("&chain n = 4, omega = 1.5, amplitude = 1 /\n\n&chian n = 3 /",
                      ["input.nml:3:", "unknown group &chian", "did you mean &chain"]),
    "repeated group": ("&chain n = 4, omega = 1.5, amplitude = 1 /\n&chain n = 3 /",
                       ["input.nml:2:", "more than once (first at line 1)"]),
    "two values": ("&chain n = 4, omega = 1.5 1.6, amplitude = 1 /",
                   ["omega has 2 values; it takes one"]),
    "unclosed group": ("&chain n = 4, omega = 1.5, amplitude = 1\n", ["input.nml:1:",
                                                                      "no closing '/'"]),
    "integer beyond 32 bits": ("&chain n = 4, omega = 1.5, amplitude = 1 /\n"
                               "&initial kind = 'random', seed = 123456789012 /",
                               ["input.nml:2:", "&initial", "seed = 123456789012 is beyond the "
                                "range of 32-bit integers [-2147483648, 2147483647]"]),
    "integer beyond 64 bits": ("&chain n = 4, omega = 1.5, amplitude = 1 /\n"
                               "&run cycles = 99999999999999999999 /",
                               ["input.nml:2:", "cycles = 99999999999999999999 is beyond the "
                                "range of 64-bit integers"]),
    "number beyond double": ("&chain n = 4, omega = 1.5, amplitude = 1e400 /",
                             ["input.nml:1:", "amplitude = 1e400 is beyond double precision"]),
    "list too long": ("&chain n = 4, omega = 1.5, amplitude = 1, spacing = 100002*1.0 /",
                      ["input.nml:1:", "spacing has 100002 values; an input takes at most "
                       "100001"]),
    "repeat count beyond any list": ("&chain n = 4, omega = 3000000000*1.5, amplitude = 1 /",
                                     ["input.nml:1:", "omega has 2147483647 values; it takes "
                                      "one"]),
    "plane range of five": ("&chain n = 4, omega = 1.5, amplitude = 1 /\n&census samples = 4,"
                            " plane = 'x1', 'v1', plane_range = 0, 1, 0, 1, 2 /",
                            ["input.nml:2:", "plane_range has 5 values; an input takes at most "
                             "4"]),
    "integer one past 32 bits": ("&chain n = 4, omega = 1.5, amplitude = 1 /\n"
                                 "&initial kind = 'random', seed = 2147483648 /",
                                 ["input.nml:2:", "seed = 2147483648 is beyond the range of "
                                  "32-bit integers [-2147483648, 2147483647]"]),
    # issue 30, 7: nothing in the file is silently dropped or replaced
    "text after a group": ("&chain n = 4, omega = 1.5, amplitude = 1 / n = 8\n",
                           ["input.nml:1:", "'n' is outside any group"]),
    "text between groups": ("&chain n = 4, omega = 1.5, amplitude = 1 /\nrun cycles = 9\n"
                            "&run cycles = 8 /", ["input.nml:2:", "'run' is outside any group"]),
    "text before the first group": ("omega = 2\n&chain n = 4, omega = 1.5, amplitude = 1 /",
                                    ["input.nml:1:", "'omega' is outside any group"]),
    "value without a key": ("&chain 7, n = 4, omega = 1.5, amplitude = 1 /",
                            ["input.nml:1:", "&chain: '7' is not a value of any key"]),
    "key given twice": ("&chain n = 4, omega = 1.5,\n amplitude = 1, omega = 2 /",
                        ["input.nml:2:", "&chain: omega is given twice (first at line 1)"]),
    "comment before a value": ("&chain n = 4, omega = ! the drive\n 1.5, amplitude = 1 /",
                               ["input.nml:1:", "&chain: omega = is followed by a comment",
                                "put the comment after the value"]),
}

# values at the edges of what a key holds: read, not refused
HELD = ["&initial kind = 'random', seed = -2147483648, v_amp = 0.1 /",
        "&initial kind = 'random', seed = 2147483647, v_amp = 0.1 /",
        "&run cycles = 9223372036854775807, transient = 0 /",
        "&chain n = 4, omega = 1.5, amplitude = 0e400 /",
        "&chain n = 4, omega = 1.5, amplitude = 0.001e299 /",
        "&chain n = 4, omega = 1.5, amplitude = 1e000000001 /"]


@pytest.mark.parametrize("line", HELD)
def test_values_a_key_holds_are_read(impactchain_exe, tmp_path, line):
    group = line.split()[0]
    text = "\n".join(line if l.startswith(group) else l for l in GOOD.splitlines())
    (tmp_path / "in.nml").write_text(text)
    result = subprocess.run([str(impactchain_exe), "--quiet", "--check", "--set",
                             "output.max_size_mb=1e9", "in.nml"], cwd=tmp_path,
                            capture_output=True, text=True, timeout=60)
    assert "beyond" not in result.stderr and "overflow" not in result.stderr, result.stderr


def test_check_refuses_an_overlapping_start(impactchain_exe, tmp_path):
    """--check builds a single run's initial state, as the run does before it writes."""
    (tmp_path / "in.nml").write_text("&chain n = 2, amplitude = 1, omega = 1.5 /\n"
                                     "&initial kind = 'explicit', x0 = 0.9, -0.9 /\n"
                                     "&output file = 'o.h5' /\n")
    for check in (["--check"], []):
        result = subprocess.run([str(impactchain_exe), "--quiet", *check, "in.nml"],
                                cwd=tmp_path, capture_output=True, text=True, timeout=60)
        assert result.returncode == 1 and "the gap of bond 1 is" in result.stderr, result.stderr
        assert sorted(p.name for p in tmp_path.iterdir()) == ["in.nml"]


@pytest.mark.parametrize("case", sorted(MISTAKES))
def test_mistake_is_reported_where_and_how(impactchain_exe, tmp_path, case):
    text, needles = MISTAKES[case]
    result = run_namelist(impactchain_exe, text + "\n&output file = 'bad.h5' /\n", tmp_path,
                          check=False)
    assert result.returncode == 1
    for needle in needles:
        assert needle in result.stderr, result.stderr
    assert "Cannot match" not in result.stderr      # never the compiler's own words
    assert not list(tmp_path.glob("*.h5*"))


def run(exe, args, cwd, check=True):
    result = subprocess.run([str(exe), "--quiet", *args], cwd=cwd, capture_output=True,
                            text=True, timeout=120)
    if check:
        assert result.returncode == 0, result.stderr
    return result


def test_set_overrides_keys_and_the_echo_shows_them(impactchain_exe, tmp_path):
    (tmp_path / "in.nml").write_text(GOOD)
    run(impactchain_exe, ["--set", "chain.amplitude=2.2", "--set", "run.cycles=12",
                          "--set", "chain.spacing=1,1,0.8,1,1", "in.nml"], tmp_path)
    with h5py.File(tmp_path / "run.h5") as f:
        assert f["strobe/x"].shape == (12, 4)
        assert float(np.ravel(f["params"].attrs["amplitude"])[0]) == 2.2
        np.testing.assert_array_equal(f["params/spacing"][()], [1, 1, 0.8, 1, 1])
        text = f.attrs["input_namelist"]
        text = text.decode() if isinstance(text, bytes) else str(text)
    assert "amplitude = 2.2" in text and "amplitude = 1.7" not in text


def test_output_option_and_overwrite_protection(impactchain_exe, tmp_path):
    (tmp_path / "in.nml").write_text(GOOD)
    run(impactchain_exe, ["-o", "other.h5", "in.nml"], tmp_path)
    assert h5py.is_hdf5(tmp_path / "other.h5") and not (tmp_path / "run.h5").exists()
    refused = run(impactchain_exe, ["--output", "other.h5", "in.nml"], tmp_path, check=False)
    assert refused.returncode == 1 and "exists" in refused.stderr
    before = (tmp_path / "other.h5").read_bytes()
    run(impactchain_exe, ["-o", "other.h5", "--overwrite", "--set", "run.cycles=9",
                          "in.nml"], tmp_path)
    assert (tmp_path / "other.h5").read_bytes() != before
    with h5py.File(tmp_path / "other.h5") as f:
        assert f["strobe/x"].shape == (9, 4)


def test_check_validates_prints_resolved_and_runs_nothing(impactchain_exe, tmp_path):
    (tmp_path / "in.nml").write_text(GOOD)
    result = run(impactchain_exe, ["--check", "--set", "chain.damping=0.1", "in.nml"],
                 tmp_path)
    assert not list(tmp_path.glob("*.h5*"))
    assert "damping = 0.1," in result.stdout and "&lyapunov" in result.stdout
    (tmp_path / "resolved.nml").write_text(result.stdout)
    again = run(impactchain_exe, ["--check", "resolved.nml"], tmp_path)
    assert again.stdout == result.stdout            # the resolved input is a fixed point
    bad = run(impactchain_exe, ["--check", "--set", "chain.damping=1.5", "in.nml"], tmp_path,
              check=False)
    assert bad.returncode == 1 and "damping" in bad.stderr and not bad.stdout


# Single runs --check must refuse as the run does before it starts: (arguments, message)
REFUSED_RUNS = {
    "size": (["--set", "run.cycles=10000000", "--set", "output.max_size_mb=1", "-o", "big.h5"],
             "&output: the strobe records of this run need about 720.00000 MB"),
    "missing directory": (["-o", "nodir/run.h5"],
                          "&output: cannot create 'nodir/run.h5': the directory 'nodir' does "
                          "not exist"),
    "output is a file's child": (["-o", "in.nml/run.h5"],
                                 "&output: cannot create 'in.nml/run.h5': the directory "
                                 "'in.nml' does not exist"),
    "max_size_mb = 0": (["--set", "output.max_size_mb=0"],
                        "&output: max_size_mb = 0.0000000 is outside (0, 1e9]"),
}


@pytest.mark.parametrize("case", sorted(REFUSED_RUNS))
def test_check_refuses_what_the_run_refuses(impactchain_exe, tmp_path, case):
    """--check and the run give the same one line and exit status 1, creating nothing."""
    args, message = REFUSED_RUNS[case]
    (tmp_path / "in.nml").write_text(GOOD)
    lines = set()
    for check in (["--check"], []):
        result = run(impactchain_exe, [*check, *args, "in.nml"], tmp_path, check=False)
        assert result.returncode == 1 and not result.stdout, (check, result.stderr)
        assert result.stderr.startswith("impactchain: error: " + message), result.stderr
        assert result.stderr.count("\n") == 1
        lines.add(result.stderr)
        assert sorted(p.name for p in tmp_path.iterdir()) == ["in.nml"]
    assert len(lines) == 1


# Random starts with both amplitudes 0 (&initial's defaults) are all one start, rest: a
# study that changes only the seed would get identical runs. (input, the whole message)
DEGENERATE_STARTS = {
    "initial without amplitudes": (
        "&initial kind = 'random', seed = 5 /",
        "&initial: kind = 'random' needs x_amp or v_amp above 0 (both are 0: every seed "
        "would start from rest); x_amp in [0, half the smallest spacing = 0.50000000), "
        "v_amp in [0, 1e6]"),
    "initial with amplitudes 0": (
        "&initial kind = 'random', seed = 5, x_amp = 0, v_amp = 0.0 /",
        "&initial: kind = 'random' needs x_amp or v_amp above 0 (both are 0: every seed "
        "would start from rest); x_amp in [0, half the smallest spacing = 0.50000000), "
        "v_amp in [0, 1e6]"),
    "census with amplitudes 0": (
        "&census samples = 3, x_amp = 0, v_amp = 0 /",
        "&census: x_amp or v_amp must be above 0 (both are 0: every sample would start "
        "from rest); x_amp in [0, half the smallest spacing = 0.50000000), v_amp in [0, 1e6]"),
}


@pytest.mark.parametrize("case", sorted(DEGENERATE_STARTS))
def test_random_starts_without_amplitudes_are_refused(impactchain_exe, tmp_path, case):
    line, message = DEGENERATE_STARTS[case]
    group = line.split()[0]
    text = "\n".join(l for l in GOOD.splitlines() if not l.startswith(group)) + "\n" + line
    (tmp_path / "in.nml").write_text(text + "\n")
    for check in (["--check"], []):
        result = run(impactchain_exe, [*check, "in.nml"], tmp_path, check=False)
        assert result.returncode == 1 and not result.stdout, (check, result.stderr)
        assert result.stderr == "impactchain: error: " + message + "\n"
        assert sorted(p.name for p in tmp_path.iterdir()) == ["in.nml"]


def test_a_census_plane_needs_no_amplitudes(impactchain_exe, tmp_path):
    """A plane's starts vary its two coordinates and take the others from &initial: its
    &census x_amp and v_amp are not used, and may be 0."""
    (tmp_path / "in.nml").write_text(GOOD + "&census samples = 4, x_amp = 0, v_amp = 0, "
                                     "plane = 'x1', 'v1', plane_range = -0.1, 0.1, -0.1, 0.1, "
                                     "plane_points = 2 /\n")
    result = run(impactchain_exe, ["--check", "in.nml"], tmp_path)
    assert "plane = 'x1', 'v1'" in result.stdout, result.stdout


def test_one_amplitude_makes_seeds_differ(impactchain_exe, tmp_path):
    starts = []
    for seed in (1, 2):
        (tmp_path / "in.nml").write_text(GOOD.replace(
            "seed = 3, x_amp = 0.2, v_amp = 0.2", f"seed = {seed}, v_amp = 0.2"))
        run(impactchain_exe, ["--overwrite", "in.nml"], tmp_path)
        with h5py.File(tmp_path / "run.h5") as f:
            starts.append((f["initial/x"][()], f["initial/v"][()]))
    (x1, v1), (x2, v2) = starts
    assert not x1.any() and not x2.any() and (v1 != v2).all()


def test_check_refuses_an_existing_output(impactchain_exe, tmp_path):
    (tmp_path / "in.nml").write_text(GOOD)
    (tmp_path / "run.h5").write_bytes(b"precious")
    refused = run(impactchain_exe, ["--check", "in.nml"], tmp_path, check=False)
    assert refused.returncode == 1 and not refused.stdout
    assert refused.stderr == ("impactchain: error: &output: file = 'run.h5' exists; choose "
                              "another name or set overwrite = .true.\n")
    run(impactchain_exe, ["--check", "--overwrite", "in.nml"], tmp_path)
    assert (tmp_path / "run.h5").read_bytes() == b"precious"


def unknown_key_lines(stderr: str) -> list[str]:
    return [line.strip() for line in stderr.splitlines() if "unknown key '" in line]


def test_the_papers_symbols_are_named_with_their_keys(impactchain_exe, tmp_path):
    """Issue 32, 8: a namelist in the paper's symbols is refused with every symbol named at
    once, each with the key it stands for; A is also the paper's a (keys are case-blind), and
    the message says so."""
    result = run_namelist(impactchain_exe, "&chain n = 4, A = 1.7, w = 1.5, K = 0.7, "
                          "b = 0.05 /\n&output file = 'paper.h5' /\n", tmp_path, check=False)
    assert result.returncode == 1
    assert "input.nml: 4 unknown keys:" in result.stderr, result.stderr
    assert unknown_key_lines(result.stderr) == [
        "input.nml:1: &chain: unknown key 'A' (did you mean 'amplitude'? A is the paper's "
        "drive amplitude; keys are case-blind, so A and a (the paper's spacing) are one name "
        "here: write 'amplitude' or 'spacing')",
        "input.nml:1: &chain: unknown key 'w' (did you mean 'omega'? w is the paper's drive "
        "frequency)",
        "input.nml:1: &chain: unknown key 'K' (did you mean 'restitution'? K is the paper's "
        "coefficient of restitution)",
        "input.nml:1: &chain: unknown key 'b' (did you mean 'damping'? b is the paper's "
        "damping coefficient)"]
    assert "The keys of &chain are n, spacing, damping, restitution, amplitude, omega, " \
           "boundary" in result.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["input.nml"]


@pytest.mark.parametrize("written, key, other", [("a", "spacing", "amplitude"),
                                                 ("A", "amplitude", "spacing"),
                                                 ("W", "omega", None),
                                                 ("k", "restitution", None)])
def test_a_symbol_of_either_case_names_its_key(impactchain_exe, tmp_path, written, key, other):
    """The symbol written in the paper's case is the first guess; the other case of a symbol
    that has one (a, A) is named as well, since the reader cannot tell them apart."""
    result = run_namelist(impactchain_exe, f"&chain n = 4, omega = 1.5, amplitude = 1, "
                          f"{written}(1) = 1 /", tmp_path, check=False)
    assert result.returncode == 1
    (line,) = unknown_key_lines(result.stderr)
    assert f"unknown key '{written}' (did you mean '{key}'?" in line, line
    assert ("case-blind" in line) == (other is not None), line
    if other:
        assert f"write '{key}' or '{other}'" in line, line
    assert not list(tmp_path.glob("*.h5*"))


def test_every_unknown_key_is_named_at_once(impactchain_exe, tmp_path):
    """Misspelt keys in two groups: all of them, each with the nearest key by edit distance,
    then the keys of both groups; a key of another group says which."""
    text = ("&chain n = 4, amplitud = 1,\n omgea = 1.5, dampign = 0.1 /\n"
            "&run cycels = 3, damping = 0.2, xyzzy = 1 /\n&output file = 'bad.h5' /\n")
    result = run_namelist(impactchain_exe, text, tmp_path, check=False)
    assert result.returncode == 1
    assert "input.nml: 6 unknown keys:" in result.stderr, result.stderr
    assert unknown_key_lines(result.stderr) == [
        "input.nml:1: &chain: unknown key 'amplitud' (did you mean 'amplitude'?)",
        "input.nml:2: &chain: unknown key 'omgea' (did you mean 'omega'?)",
        "input.nml:2: &chain: unknown key 'dampign' (did you mean 'damping'?)",
        "input.nml:3: &run: unknown key 'cycels' (did you mean 'cycles'?)",
        "input.nml:3: &run: unknown key 'damping' ('damping' is a key of &chain)",
        "input.nml:3: &run: unknown key 'xyzzy'"]
    assert "The keys of &chain are n, spacing" in result.stderr
    assert "The keys of &run are transient, cycles" in result.stderr
    assert not list(tmp_path.glob("*.h5*"))


@pytest.mark.parametrize("args, needle, code", [
    (["--set", "chain.amplitud=3"], "did you mean 'amplitude'", 1),
    (["--set", "chain.n=4.5"], "n = 4.5 is not an integer", 1),
    (["--set", "chain"], "group.key=value", 1),
    (["--set", "chian.n=3"], "did you mean &chain", 1),
    (["--set", "chain.A=3"], "unknown key 'A' (did you mean 'amplitude'? A is the paper's "
     "drive amplitude", 1),
    # issue 31, 2: several unknown keys are named at once, each with its "did you mean"
    (["--set", "chain.w=1.5", "--set", "run.cycle=5", "--set", "chain.n=4"],
     "2 unknown keys:\n  in.nml (overrides):1: &chain: unknown key 'w' (did you mean "
     "'omega'? w is the paper's drive frequency)\n  in.nml (overrides):2: &run: unknown key "
     "'cycle' (did you mean 'cycles'?)", 1),
    # issue 30, 7: a value cannot close its group and open another, or comment out the rest
    (["--set", "chain.n=4 / &run cycles=5"], "--set chain.n=4 / &run cycles=5: the value", 1),
    (["--set", "chain.n=4 ! x"], "--set chain.n=4 ! x: the value", 1),
    (["-o"], "needs a value", 2),  # a mistake in the command line itself
])
def test_bad_override_is_refused(impactchain_exe, tmp_path, args, needle, code):
    (tmp_path / "in.nml").write_text(GOOD)
    result = run(impactchain_exe, [*args, "in.nml"] if args != ["-o"] else args, tmp_path,
                 check=False)
    assert result.returncode == code
    assert needle in result.stderr, result.stderr
    assert not list(tmp_path.glob("*.h5*"))


# A run that is over in milliseconds: IMPACTCHAIN_PROGRESS_AFTER = 0 shows its progress from the
# first record (not after two quiet seconds), so what is shown does not depend on the machine.
PROGRESS_RUN = """&chain n = 8, amplitude = 3.5, omega = 1.9 /
&initial kind = 'random', seed = 2, x_amp = 0.3, v_amp = 0.3 /
&run cycles = 1000, record_events = .false. /
&output file = 'long.h5' /
"""
SHOWN_AT_ONCE = {"IMPACTCHAIN_PROGRESS_AFTER": "0"}


def progress_lines(stream: str) -> list[str]:
    return [line for line in stream.replace("\r", "\n").splitlines() if "impactchain: cycle" in line]


def test_progress_on_a_log_is_a_line_per_tenth(impactchain_exe, tmp_path):
    """stderr not a terminal: a line at each tenth of the run (or each minute: never in a run
    of milliseconds), no carriage returns; the first update is shown when the delay is 0."""
    (tmp_path / "long.nml").write_text(PROGRESS_RUN)
    result = subprocess.run([str(impactchain_exe), "long.nml"], cwd=tmp_path,
                            capture_output=True, text=True, timeout=300,
                            env={**os.environ, **SHOWN_AT_ONCE})
    assert result.returncode == 0, result.stderr
    assert "\r" not in result.stderr
    lines = progress_lines(result.stderr)
    assert lines[0].startswith("impactchain: cycle 1 / 1000 (0.1 %)"), result.stderr
    assert lines[-1].startswith("impactchain: cycle 1000 / 1000 (100.0 %)"), result.stderr
    percents = [float(re.search(r"\(([\d.]+) %\)", line).group(1)) for line in lines]
    assert percents == [0.1] + [10.0 * k for k in range(1, 11)], result.stderr


def test_progress_on_a_terminal_is_one_updating_line(impactchain_exe, tmp_path):
    """stderr a terminal (a pseudo-terminal here): one line rewritten in place with carriage
    returns (the first update and the last at least), a single newline at the end."""
    import pty

    (tmp_path / "long.nml").write_text(PROGRESS_RUN)
    leader, follower = pty.openpty()
    proc = subprocess.Popen([str(impactchain_exe), "long.nml"], cwd=tmp_path,
                            stdout=subprocess.DEVNULL, stderr=follower,
                            env={**os.environ, **SHOWN_AT_ONCE})
    os.close(follower)
    chunks = []
    while True:
        try:
            chunk = os.read(leader, 4096)
        except OSError:
            break
        if not chunk:
            break
        chunks.append(chunk)
    assert proc.wait(timeout=300) == 0
    os.close(leader)
    shown = b"".join(chunks).decode()
    assert shown.count("\r") >= 2 and shown.count("\n") == 1, repr(shown[:400])
    lines = progress_lines(shown)
    assert lines[0].startswith("impactchain: cycle 1 / 1000"), repr(shown[:400])
    assert lines[-1].startswith("impactchain: cycle 1000 / 1000"), repr(shown[:400])


def test_no_progress_in_the_quiet_start(impactchain_exe, tmp_path):
    """Nothing within the first IMPACTCHAIN_PROGRESS_AFTER seconds (an hour here: longer than
    any run of the tests), and the delay must be a number of seconds."""
    (tmp_path / "long.nml").write_text(PROGRESS_RUN)
    result = subprocess.run([str(impactchain_exe), "long.nml"], cwd=tmp_path,
                            capture_output=True, text=True, timeout=300,
                            env={**os.environ, "IMPACTCHAIN_PROGRESS_AFTER": "3600"})
    assert result.returncode == 0 and result.stderr == "", result.stderr
    for bad in ("soon", "-1", "nan", "inf", "1e7", "1e400"):
        result = subprocess.run([str(impactchain_exe), "--overwrite", "long.nml"],
                                cwd=tmp_path, capture_output=True, text=True, timeout=60,
                                env={**os.environ, "IMPACTCHAIN_PROGRESS_AFTER": bad})
        assert result.returncode == 1 and not result.stdout, result.stderr
        assert result.stderr == (f"impactchain: error: IMPACTCHAIN_PROGRESS_AFTER = {bad} is "
                                 "not a number of seconds in [0, 1e6]\n")


def test_a_long_list_is_read_and_echoed_in_full(impactchain_exe, tmp_path):
    """10^5 start positions (the longest list a namelist may hold is 100001): every value is
    checked and comes back, in order, in the resolved input (lists and echo grow by doubling)."""
    n = 100000
    values = [f"{0.25 * (i % 7) / 7:.6f}" for i in range(n)]
    (tmp_path / "long.nml").write_text(
        f"&chain n = {n}, amplitude = 1, omega = 1.5 /\n"
        f"&initial kind = 'explicit', x0 = {', '.join(values)} /\n&output file = 'x.h5' /\n")
    result = run(impactchain_exe, ["--check", "long.nml"], tmp_path)
    line = next(text for text in result.stdout.splitlines() if text.startswith("&initial"))
    echoed = line.split("x0 = ", 1)[1].rstrip(" /").split(", ")
    assert len(echoed) == n
    np.testing.assert_array_equal(np.array(echoed, dtype=float), np.array(values, dtype=float))
