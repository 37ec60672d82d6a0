"""Standard output that goes away: a reader that closes the pipe, a full disk.

``lmic solve ... | head -1`` must end with the verdict's exit code and no message (the reader
chose to stop reading); a write that fails for any other reason is one line and exit 1, never
"internal error". Each case runs the real entry point (``lmic.cli._entry``, the console script)
in a subprocess, since only a process of its own has a standard output to lose.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SDPLIB = Path("/work/shared/sdplib")
if not SDPLIB.exists():  # a checkout next to shared/ elsewhere
    SDPLIB = ROOT.parent / "shared" / "sdplib"
ENTRY = "from lmic.cli import _entry; _entry()"


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), str(ROOT / "plugins"), env.get("PYTHONPATH", "")])
    env["OPENBLAS_NUM_THREADS"] = "1"
    return env


def _sdplib(name: str) -> Path:
    path = SDPLIB / name
    if not path.exists():
        pytest.skip(f"{path} is not on this machine")
    return path


def _with_closed_reader(*args: str) -> tuple[int, str]:
    """Run ``lmic ARGS`` with a standard output whose reader has already gone."""
    proc = subprocess.Popen(
        [sys.executable, "-c", ENTRY, *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=_env(),
        cwd=ROOT,
    )
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()  # every write of the process now meets EPIPE
    err = proc.stderr.read().decode()
    return proc.wait(timeout=300), err


@pytest.mark.parametrize(
    ("problem", "verdict_code"),
    [("truss1.dat-s", 0), ("infp1.dat-s", 3)],  # SDPLIB: truss1 has an optimum, infp1 is infeasible
)
@pytest.mark.parametrize("fmt", [[], ["--json"]])
def test_a_closed_pipe_keeps_the_verdicts_exit_code_and_says_nothing(problem, verdict_code, fmt):
    code, err = _with_closed_reader("solve", str(_sdplib(problem)), *fmt)
    assert code == verdict_code, err
    assert err == ""


def test_a_closed_pipe_during_a_listing_is_quiet():
    code, err = _with_closed_reader("theorems")
    assert (code, err) == (0, "")


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full (Linux)")
def test_a_full_disk_is_one_line_and_exit_1():
    with open("/dev/full", "w") as full:
        proc = subprocess.run(
            [sys.executable, "-c", ENTRY, "solve", str(_sdplib("truss1.dat-s"))],
            stdout=full,
            stderr=subprocess.PIPE,
            text=True,
            env=_env(),
            cwd=ROOT,
            timeout=300,
        )
    assert proc.returncode == 1
    lines = proc.stderr.strip().splitlines()
    assert lines == ["lmic: error: cannot write the output: No space left on device"]


_SHOW_BLAS = (
    "import atexit, os, sys\n"
    "atexit.register(lambda: sys.stderr.write('BLAS ' + ' '.join(os.environ.get(v, '-') for v in "
    "('OPENBLAS_NUM_THREADS', 'OMP_NUM_THREADS', 'MKL_NUM_THREADS')) + '\\n'))\n"
    "from lmic.cli import _entry\n"
    "_entry()\n"
)


@pytest.mark.parametrize(
    ("given", "seen"),
    [({}, "BLAS 1 1 1"), ({"OPENBLAS_NUM_THREADS": "2"}, "BLAS 2 1 1")],
)
def test_the_command_runs_blas_single_threaded_unless_told_otherwise(given, seen):
    env = _env()
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        env.pop(var, None)
    env.update(given)
    proc = subprocess.run(
        [sys.executable, "-c", _SHOW_BLAS, "solve", str(_sdplib("truss1.dat-s"))],
        capture_output=True,
        text=True,
        env=env,
        cwd=ROOT,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.strip().splitlines()[-1] == seen
