"""The progress line of long solves: drawn on a terminal (a pseudo-terminal here), with the
route, the current step and the elapsed seconds, erased at the end; nothing on a pipe."""

from __future__ import annotations

import os
import select
import time

import numpy as np
import pytest

from lmic.backends.base import Backend
from lmic.backends.progress import solve_progress
from lmic.solution import Solution
from lmic.testing.conformance import CASES

pty = pytest.importorskip("pty")


def _read_all(fd: int) -> str:
    out = b""
    while select.select([fd], [], [], 0.2)[0]:
        try:
            chunk = os.read(fd, 4096)
        except OSError:
            break
        if not chunk:
            break
        out += chunk
    return out.decode()


class _Slow(Backend):
    name = "slow"
    STATUS_MAP = {"done": "optimal"}

    def _solve(self, problem, options):
        time.sleep(1.3)
        return Solution("optimal", x=np.zeros(problem.n), native_status="done")


def test_a_long_solve_shows_route_step_and_seconds_on_a_terminal(monkeypatch):
    master, slave = pty.openpty()
    stream = os.fdopen(slave, "w")
    monkeypatch.delenv("LMIC_PROGRESS", raising=False)
    try:
        with solve_progress("route slow -> cvxopt", stream=stream, delay=0.1, interval=0.2):
            sol = _Slow().solve(CASES["max_sense"].build())
        text = _read_all(master)
    finally:
        stream.close()
        os.close(master)
    assert sol.status == "optimal"
    assert "lmic: route slow -> cvxopt | slow | 1 s" in text
    assert text.endswith("\r\x1b[K")  # the line is erased when the solve ends


def test_nothing_is_drawn_when_stderr_is_not_a_terminal():
    r, w = os.pipe()
    stream = os.fdopen(w, "w")
    try:
        with solve_progress("route sdpa", stream=stream, delay=0.0, interval=0.05) as show:
            time.sleep(0.2)
        stream.flush()
        assert not show.enabled
        assert _read_all(r) == ""
    finally:
        stream.close()
        os.close(r)


def test_lmic_progress_0_turns_it_off(monkeypatch):
    master, slave = pty.openpty()
    stream = os.fdopen(slave, "w")
    monkeypatch.setenv("LMIC_PROGRESS", "0")
    try:
        with solve_progress("route sdpa", stream=stream, delay=0.0, interval=0.05) as show:
            time.sleep(0.2)
        assert not show.enabled and _read_all(master) == ""
    finally:
        stream.close()
        os.close(master)
