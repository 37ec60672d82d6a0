"""Hostile output paths and faults (#12 section 3, #17 items 1-3 and 5), without privileges.

Device nodes are made with ``mknod`` only when the tests run as root (skipped otherwise); the
other cases use a symlink or a FIFO in a temporary folder, ``ulimit -f`` (RLIMIT_FSIZE) in a
subprocess, ``kill -9`` and SIGINT sent to a real ``lmic`` process.
"""

from __future__ import annotations

import json
import os
import resource
import signal
import stat
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from lmic.cli import main

ROOT = Path(__file__).resolve().parents[2]
SYSTEM = str(ROOT / "examples" / "qib.thm1.flexible-joint.yaml")
ENV = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), str(ROOT / "plugins")]))
IS_ROOT = hasattr(os, "geteuid") and os.geteuid() == 0


def _lmic(*args: str, preexec=None, **kw) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "lmic.cli", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=ENV,
        preexec_fn=preexec,
        **kw,
    )


def _one_line_exit_2(code: int, err: str) -> None:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2, err
    assert len(lines) == 1 and lines[0].startswith("lmic: error:") and "Traceback" not in err, err


# -- symlinks, directories, special files --------------------------------------------------------


def test_symlink_to_own_regular_file_is_written_through(tmp_path, capsys):
    real = tmp_path / "real.json"
    real.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(real)
    assert main(["compile", "qib.thm1", SYSTEM, "-o", str(link)]) == 0
    assert link.is_symlink() and json.loads(real.read_text())["lmic_ir"] == 1


def test_dangling_symlink_is_refused(tmp_path, capsys):
    link = tmp_path / "link.json"
    link.symlink_to(tmp_path / "nowhere" / "x.json")
    code = main(["compile", "qib.thm1", SYSTEM, "-o", str(link)])
    _one_line_exit_2(code, capsys.readouterr().err)
    assert not (tmp_path / "nowhere").exists() and link.is_symlink()


@pytest.mark.skipif(not IS_ROOT, reason="chown to another user needs root")
def test_symlink_to_another_users_file_is_refused(tmp_path, capsys):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    os.chown(victim, 65534, 65534)  # nobody
    link = tmp_path / "out.json"
    link.symlink_to(victim)
    code = main(["compile", "qib.thm1", SYSTEM, "-o", str(link)])
    _one_line_exit_2(code, capsys.readouterr().err)
    assert victim.read_text() == "precious"


def test_directory_and_missing_folder_are_refused_before_any_work(tmp_path, capsys):
    for target in (tmp_path, tmp_path / "missing" / "c.json"):
        # the system file does not exist either: the output path is checked first
        code = main(["solve", "qib.thm1", str(tmp_path / "no-such-system.yaml"), "-o", str(target)])
        err = capsys.readouterr().err
        _one_line_exit_2(code, err)
        assert "no-such-system" not in err


@pytest.mark.skipif(IS_ROOT, reason="root may write into a read-only folder")
def test_read_only_folder_is_refused(tmp_path, capsys):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        code = main(["compile", "qib.thm1", SYSTEM, "-o", str(folder / "ir.json")])
        _one_line_exit_2(code, capsys.readouterr().err)
        assert os.listdir(folder) == []
    finally:
        folder.chmod(0o700)


def test_fifo_is_written_directly_and_stays_a_fifo(tmp_path):
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    got: list[bytes] = []
    reader = threading.Thread(target=lambda: got.append(open(fifo, "rb").read()))
    reader.start()
    assert main(["compile", "qib.thm1", SYSTEM, "-o", str(fifo)]) == 0
    reader.join(30)
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert json.loads(got[0])["lmic_ir"] == 1


def test_dev_full_gives_one_line_and_stays_a_device(capsys):
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full")
    code = main(["compile", "qib.thm1", SYSTEM, "-o", "/dev/full"])
    _one_line_exit_2(code, capsys.readouterr().err)
    assert stat.S_ISCHR(os.stat("/dev/full").st_mode)


@pytest.mark.skipif(not IS_ROOT, reason="mknod needs root")
@pytest.mark.parametrize(("name", "major_minor", "ok"), [("null", (1, 3), True), ("full", (1, 7), False)])
def test_private_device_copies_are_never_replaced(tmp_path, capsys, name, major_minor, ok):
    dev = tmp_path / f"{name}.json"
    try:
        os.mknod(dev, 0o666 | stat.S_IFCHR, os.makedev(*major_minor))
    except PermissionError:
        pytest.skip("mknod not permitted here")
    for argv in (
        ["compile", "qib.thm1", SYSTEM, "-o", str(dev)],
        ["solve", "qib.thm1", SYSTEM, "-o", str(dev)],
    ):
        code = main(argv)
        err = capsys.readouterr().err
        if ok:
            assert code == 0, err
        else:
            _one_line_exit_2(code, err)
        assert stat.S_ISCHR(os.lstat(dev).st_mode)  # still the device, not a regular file


# -- full disk, kill -9, concurrency, Ctrl-C -------------------------------------------------------


@pytest.mark.parametrize("suffix", [".json", ".dat-s"])
def test_file_size_limit_leaves_no_file(tmp_path, suffix):
    out = tmp_path / f"ir{suffix}"

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (1024, 1024))  # ulimit -f 2

    proc = _lmic("compile", "qib.thm1", SYSTEM, "-o", str(out), preexec=limit)
    _, err = proc.communicate(timeout=120)
    _one_line_exit_2(proc.returncode, err)
    assert os.listdir(tmp_path) == []


def test_kill_9_during_solve_never_leaves_a_partial_file(tmp_path):
    out = tmp_path / "cert.json"
    seen_complete = 0
    for delay in (0.5, 1.0, 1.5, 2.0, 2.5, 3.0):
        if out.exists():
            out.unlink()
        proc = _lmic("solve", "qib.thm1", SYSTEM, "-o", str(out))
        time.sleep(delay)
        proc.send_signal(signal.SIGKILL)
        proc.communicate(timeout=60)
        if out.exists():  # present means complete
            json.loads(out.read_text())
            seen_complete += 1
        leftovers = [p for p in os.listdir(tmp_path) if p != "cert.json" and not p.endswith(".tmp")]
        assert leftovers == []
    proc = _lmic("solve", "qib.thm1", SYSTEM, "-o", str(out))
    proc.communicate(timeout=120)
    assert proc.returncode == 0 and json.loads(out.read_text())["certificate"]["verdict"] == "certified"


def test_two_concurrent_runs_leave_one_complete_file(tmp_path, capsys):
    out = tmp_path / "cert.json"
    procs = [_lmic("solve", "qib.thm1", SYSTEM, "-o", str(out)) for _ in range(2)]
    for p in procs:
        p.communicate(timeout=180)
        assert p.returncode == 0
    assert os.listdir(tmp_path) == ["cert.json"]
    assert main(["audit", str(out)]) == 0


def test_ctrl_c_exits_130_with_one_line(tmp_path):
    proc = _lmic("solve", "qib.thm1", SYSTEM, "--sweep", "beta=0:0.01:4000")  # far longer than 5 s
    time.sleep(5.0)  # well inside the sweep (imports take ~1-2 s)
    proc.send_signal(signal.SIGINT)
    stdout, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert err.strip().splitlines()[-1] == "lmic: interrupted" and "Traceback" not in err


def test_ctrl_c_during_compile_to_a_file_leaves_nothing(tmp_path, monkeypatch, capsys):
    import lmic.output as output

    def interrupted(fh, data):  # Ctrl-C arrives while the file is being written
        fh.write("{")
        raise KeyboardInterrupt

    monkeypatch.setattr(output, "_write_all", interrupted)
    code = main(["compile", "qib.thm1", SYSTEM, "-o", str(tmp_path / "ir.json")])
    assert code == 130 and capsys.readouterr().err == "lmic: interrupted\n"
    assert os.listdir(tmp_path) == []
