"""Clarabel's dense PSD scaling blocks grow as d^4: too large ones are refused with a reason,
and the default backend then takes the auto route instead of exhausting the memory."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import lmic.backends.clarabel as clarabel_module
from lmic.api import solve
from lmic.backends.clarabel import ClarabelBackend, kkt_bytes
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.ir.svec import tril_index, tril_size


def maxcut_dual(d: int) -> Problem:
    """min sum x_i  s.t.  diag(x) - W/4 >= 0 (the SDP relaxation of max-cut, dual form)."""
    rng = np.random.default_rng(d)
    W = np.triu((rng.random((d, d)) < 0.1).astype(float), 1)
    W = W + W.T
    lap = np.diag(W.sum(1)) - W
    i, j = np.nonzero(np.tril(lap))
    rows = list(tril_index(i, j, d)) + list(tril_index(np.arange(d), np.arange(d), d))
    cols = [0] * len(i) + list(range(1, d + 1))
    vals = list(-lap[i, j] / 4) + [1.0] * d
    coeffs = sp.csc_matrix((vals, (rows, cols)), shape=(tril_size(d), 1 + d))
    return Problem(
        [Variable("x", "full", (d, 1))],
        [LMI("block 1", d, coeffs, strict=False, relation=">=")],
        LinearConstraints.empty(d),
        Objective("min", np.r_[0.0, np.ones(d)]),
    )


def test_memory_estimate_grows_as_d_to_the_fourth():
    def psd_part(d):
        return (
            kkt_bytes(maxcut_dual(d)) - clarabel_module.KKT_CONSTANT_BYTES - clarabel_module.BYTES_PER_FILL_ENTRY * d**2
        )

    small, big = psd_part(10), psd_part(20)
    assert 14 < big / small < 18  # (210/55)^2 = 14.6


@pytest.mark.parametrize("kind,d", [("maxcut", 60), ("lyapunov", 50)])
def test_memory_estimate_covers_the_measured_peak(kind, d):
    """The guard's estimate is at least the peak RSS a Clarabel solve adds (measured in a fresh
    process by benchmarks/clarabel_memory.py), and not wildly above it."""
    script = Path(__file__).resolve().parents[2] / "benchmarks" / "clarabel_memory.py"
    rows = []
    for _ in range(2):  # the peak of the two runs (a busy machine can make one read low)
        out = subprocess.run(
            [sys.executable, str(script), "--child", kind, str(d)], capture_output=True, text=True, check=True
        )
        rows.append(json.loads(out.stdout.strip().splitlines()[-1]))
    row = max(rows, key=lambda r: r["measured"])
    assert row["measured"] > 0
    assert row["measured"] <= row["estimate"] <= 3 * row["measured"], row


def test_a_block_too_large_for_memory_is_refused_with_a_reason(monkeypatch):
    monkeypatch.setattr(clarabel_module, "_physical_memory", lambda: 1 << 20)  # a 1 MiB machine
    ok, why = ClarabelBackend().supports(maxcut_dual(30), explain=True)
    assert not ok
    assert "LMI 'block 1' (30x30)" in why and "--backend sdpa" in why


def test_the_default_backend_falls_back_to_the_auto_route(monkeypatch):
    monkeypatch.setattr(clarabel_module, "_physical_memory", lambda: 1 << 20)
    prob = maxcut_dual(30)
    result = solve(prob)
    assert result.backend != "clarabel"
    assert result.verdict == "certified"
    reference = solve(maxcut_dual(30), backend="cvxopt").objective
    assert abs(result.objective - reference) <= 1e-6 * abs(reference)
