"""A variable that exposes a face of the dual on its own (lmic.certify.enclosure_facial.obvious_face):
SDPLIB's graph-partitioning layout (gpp: ``x_0 J + Diag(x) + L / 4 >= 0``, ``c_0 = 0``, so
every dual ``Y`` has ``<J, Y> = 0`` and no interior). The enclosure goes to the facial route
first; its bound is checked against the closed form of the cycle's bisection relaxation."""

from __future__ import annotations

import math

import pytest

import lmic.api
import lmic.certify.enclosure as enc_mod
from lmic.certify import certify
from lmic.certify.enclosure_facial import obvious_face
from lmic.ir.sdpa import read_sdpa


def _gpp_cycle_text(n: int, cost0: float = 0.0) -> str:
    """SDPLIB's gpp layout for the cycle ``C_n`` (written here, not by lmic): ``min sum_i
    x_i`` s.t. ``x_0 J + Diag(x) - F_0 >= 0``, ``F_0 = -L / 4``."""
    lines = [str(n + 1), "1", str(n), " ".join([repr(cost0)] + ["1"] * n)]
    for i in range(n):
        a, b = sorted((i, (i + 1) % n))
        lines.append(f"0 1 {i + 1} {i + 1} -0.5")
        lines.append(f"0 1 {a + 1} {b + 1} 0.25")
    lines += [f"1 1 {i + 1} {j + 1} 1.0" for i in range(n) for j in range(i, n)]
    lines += [f"{i + 2} 1 {i + 1} {i + 1} 1.0" for i in range(n)]
    return "\n".join(lines) + "\n"


def _gpp_cycle_value(n: int) -> float:
    """``-min <L/4, Y>`` over ``diag Y = 1``, ``Y e = 0``, ``Y >= 0``: ``-n lambda_2(L) / 4``
    (``<L, Y> >= lambda_2 tr Y`` on ``Y e = 0``, attained by ``Y_ij = cos(2 pi (i - j) / n)``)."""
    return -n * (2.0 - 2.0 * math.cos(2.0 * math.pi / n)) / 4.0


def test_obvious_face_detects_the_partition_constraint_only():
    assert obvious_face(read_sdpa(_gpp_cycle_text(8))) is not None
    # a cost on x_0: <J, Y> = c_0 != 0, the dual has an interior
    assert obvious_face(read_sdpa(_gpp_cycle_text(8, cost0=1.0))) is None
    # an indefinite coefficient of cost 0 (max-cut's L/4 as x_0's coefficient) is no exposing direction
    text = _gpp_cycle_text(4).splitlines()
    text = text[:4] + [ln for ln in text[4:] if not ln.startswith("1 ")]
    text += ["1 1 1 1 0.5", "1 1 1 2 -0.25"]
    assert obvious_face(read_sdpa("\n".join(text) + "\n")) is None


@pytest.mark.parametrize("n", [6, 9, 16])
def test_gpp_cycle_enclosure_by_the_facial_route_first(n, monkeypatch):
    p = read_sdpa(_gpp_cycle_text(n))
    shifted = []
    real = enc_mod.dual_bound
    monkeypatch.setattr(enc_mod, "dual_bound", lambda *a, **k: shifted.append(1) or real(*a, **k))
    r = lmic.api.solve(p, backend="sdpa", backoff=0)
    cert = certify(p, r.solution)
    assert cert.verdict == "certified", cert.reason
    enc = r.enclosure
    truth = _gpp_cycle_value(n)
    assert enc["lower"] <= truth <= enc["upper"], (enc["lower"], truth, enc["upper"])
    assert enc["rel_gap"] <= 1e-6, enc["reason"]
    assert enc["dual"]["route"] == "facial"
    assert not shifted, "the shifted repairs ran before the facial route"
