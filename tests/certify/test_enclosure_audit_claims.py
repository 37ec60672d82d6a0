"""Every claim of a recorded enclosure is checked by the audit, not only its two ends.

A forger recomputes the integrity hashes (they are not a signature), so a field the audit does
not re-derive is a claim nobody checks. Before: ``dual.lower_exact`` (the exact rational lower
end) could be set to any value, ``rel_gap`` to 0 and ``kind`` from ``infimum`` to ``minimum``
(the optimum attained), and ``lmic audit`` accepted the file. The truth is closed form:
``min t s.t. [[t, 1], [1, t]] >= 0`` is 1.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import scipy.sparse as sp

from lmic.certify.enclosure import enclosure
from lmic.certify.enclosure_audit import audit_enclosure
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable


def _problem(strict: bool) -> Problem:
    C = sp.csc_matrix(np.array([[0.0, 1.0], [1.0, 0.0], [0.0, 1.0]]))
    return Problem(
        [Variable("t", "scalar", (1, 1))],
        [LMI("[[t, 1], [1, t]]", 2, C, strict=strict)],
        LinearConstraints.empty(1),
        Objective("min", [0.0, 1.0]),
    )


def _record(strict: bool = False):
    p = _problem(strict)
    x = np.array([1.0 + 1e-6]) if strict else np.array([1.0])
    e = enclosure(p, {"lmis": [np.array([[0.5, -0.5], [-0.5, 0.5]])], "linear": []}, x, exact=True)
    assert e["lower"] is not None and e["lower"] <= 1.0  # the optimum is 1
    return p, e, SimpleNamespace(x=x)  # the certificate's point, the primal end's


def test_the_genuine_record_passes():
    for strict in (False, True):
        p, e, c = _record(strict)
        assert audit_enclosure(p, e, c)["ok"], e


def test_a_forged_exact_lower_end_is_rejected():
    p, e, c = _record()
    assert e["dual"].get("lower_exact") is not None
    forged = dict(e, dual=dict(e["dual"], lower_exact="2"))  # above the optimum 1
    r = audit_enclosure(p, forged, c)
    assert not r["ok"] and r["field"] == "enclosure.dual"
    # an exact end added to a float proof is unsupported
    p, e, c = _record()
    float_only = {k: v for k, v in e["dual"].items() if k not in ("lower_exact", "exact")}
    forged = dict(e, dual=dict(float_only, method="rigorous-float", lower_exact="1"))
    assert not audit_enclosure(p, forged, c)["ok"]


def test_a_forged_relative_gap_is_rejected():
    p, e, c = _record(strict=True)
    assert e["rel_gap"] is not None and e["rel_gap"] > 0
    r = audit_enclosure(p, dict(e, rel_gap=0.0), c)
    assert not r["ok"] and r["field"] == "enclosure.rel_gap"


def test_an_infimum_relabelled_minimum_is_rejected():
    p, e, c = _record(strict=True)
    assert e["kind"] == "infimum"
    r = audit_enclosure(p, dict(e, kind="minimum"), c)
    assert not r["ok"] and r["field"] == "enclosure.kind"
