"""Forged certificates: written through lmic's own writer with loosened tolerances, and mutated.

The three forgeries of the hardening issue, each produced the way an attacker would (lmic's
certifier run with a loosened tolerance, the result written by :func:`write_certificate`):

* an infeasibility claim for a *feasible* ``qib.thm1`` example (Farkas tolerance raised);
* an "optimal" point of SDPLIB truss1 at ``x = -1000`` everywhere (``rel`` raised);
* a ``uio_dt.thm4_1`` objective claimed 1000 times better than the true one (``objective_rel``).

Each must be rejected by ``lmic audit``, naming the loosened tolerance; and when the forger
also resets the recorded tolerances (and recomputes the integrity hashes), naming the
recomputed field that differs. Then every single-field mutation of a certificate is rejected,
except the declared informational fields.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest

from lmic.certify import certify
from lmic.certify.certificate import (
    INFORMATIONAL,
    _schema,
    audit_certificate,
    integrity_of,
    write_certificate,
)
from lmic.cli import main
from lmic.errors import CertificateError, LmicError
from lmic.solution import Solution

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
TRUSS1 = Path("/work/shared/sdplib/truss1.dat-s")
if not TRUSS1.is_file():
    TRUSS1 = ROOT.parent / "shared" / "sdplib" / "truss1.dat-s"


def _audit_json(path: Path, capsys, *extra: str) -> tuple[int, dict]:
    code = main(["audit", str(path), "--json", *extra])
    return code, json.loads(capsys.readouterr().out)


def _reset_tolerances(path: Path) -> None:
    """The forger's second move: record lmic's default tolerances, recompute the hashes."""
    doc = json.loads(path.read_text())
    for key in doc["tolerances"]:
        doc["tolerances"][key] = {"rel": 1e-8, "farkas_rel": 1e-6, "objective_rel": 1e-6}.get(
            key, doc["tolerances"][key]
        )
    doc["certificate"]["tolerances"] = dict(doc["tolerances"])
    doc["integrity"] = integrity_of(doc)
    path.write_text(json.dumps(doc))


@pytest.fixture(scope="module")
def qib():
    from lmic.compile import compile_theorem
    from lmic.system import load_system

    system = load_system(EXAMPLES / "qib.thm1.flexible-joint.yaml")
    return system, compile_theorem("qib.thm1", system)


def test_forged_infeasibility_of_a_feasible_qib_example(qib, tmp_path, capsys):
    from lmic.api import solve

    system, prob = qib
    # the truth, independently of the forgery: a solver finds a point the certifier accepts
    truth = solve("qib.thm1", system=str(EXAMPLES / "qib.thm1.flexible-joint.yaml"))
    assert truth.certificate.verdict == "certified"
    # the forgery: identity multipliers, verified with farkas_rel raised from 1e-6 to 0.5
    farkas = {"lmis": [np.eye(lmi.dim) for lmi in prob.lmis], "linear": np.ones(prob.linear.A.shape[0])}
    sol = Solution("infeasible", farkas=farkas, backend="clarabel")
    forged = certify(prob, sol, tol={"farkas_rel": 0.5})
    assert forged.verdict == "infeasible-bounded"  # what the loosened certifier says (scale-free: bounded)
    path = tmp_path / "forged.json"
    write_certificate(path, prob, sol, forged, system=system)
    code, out = _audit_json(path, capsys)
    assert code == 1 and out["ok"] is False
    assert out["field"] == "tolerances.farkas_rel"
    assert "looser" in out["message"]
    _reset_tolerances(path)
    code, out = _audit_json(path, capsys)
    assert code == 1 and out["ok"] is False
    assert out["field"].startswith("certificate.farkas")


def test_forged_truss1_point_at_minus_1000(tmp_path, capsys):
    from lmic.ir.sdpa import read_sdpa

    prob = read_sdpa(TRUSS1)
    x = -1000.0 * np.ones(prob.n)
    c = np.asarray(prob.objective.c, dtype=float)
    sol = Solution("optimal", x=x, objective=float(c[0] + c[1:] @ x), backend="sdpa")
    # the truth, without the certifier: some block F(x) has no Cholesky factor (not PSD)
    from lmic.ir.svec import tril_unvec

    def psd(lmi) -> bool:
        F = tril_unvec((lmi.coeffs @ np.concatenate([[1.0], x])).ravel(), lmi.dim)
        try:
            np.linalg.cholesky(F + 1e-9 * np.eye(lmi.dim))
        except np.linalg.LinAlgError:
            return False
        return True

    assert not all(psd(lmi) for lmi in prob.lmis)
    forged = certify(prob, sol, tol={"rel": 1e300})
    assert forged.verdict == "rejected"  # even an absurd tolerance certifies nothing: only proofs do
    forged.verdict, forged.reason = "certified", "every constraint and check holds"  # the forger's edit
    for entry in forged.lmis:
        entry["ok"] = True
    path = tmp_path / "truss1.json"
    write_certificate(path, prob, sol, forged)
    code, out = _audit_json(path, capsys)
    assert code == 1 and out["field"] == "tolerances.rel"
    _reset_tolerances(path)
    code, out = _audit_json(path, capsys)
    assert code == 1 and out["field"].startswith("certificate.lmis[0]")


def test_forged_uio_dt_objective_1000_times_better(tmp_path, capsys):
    from lmic.api import solve
    from lmic.system import load_system

    sysfile = EXAMPLES / "uio_dt.thm4_1.flexible_joint.yaml"
    real = solve("uio_dt.thm4_1", system=str(sysfile))  # the default route certifies it
    assert real.certificate.verdict == "certified"
    prob, honest = real.problem, real.solution
    true_obj = float(prob.objective.c[0] + prob.objective.c[1:] @ honest.x)  # min: smaller is better
    sol = Solution("optimal", x=honest.x, objective=true_obj / 1000.0, backend=honest.backend)
    # the optimum is an infimum on the boundary: the point's margins (~1e-7) are proven exactly,
    # as the default route did (exact rescue), so the forger certifies exactly too
    exact = bool((real.certificate.exact or {}).get("proven"))
    forged = certify(prob, sol, tol={"objective_rel": 1e300}, exact=exact)
    assert forged.verdict == "certified"
    path = tmp_path / "uio.json"
    write_certificate(path, prob, sol, forged, system=load_system(sysfile))
    code, out = _audit_json(path, capsys)
    assert code == 1 and out["field"] == "tolerances.objective_rel"
    _reset_tolerances(path)
    code, out = _audit_json(path, capsys)
    assert code == 1 and out["field"].startswith("certificate.objective")


def test_auditor_tolerances_stricter_only(qib, tmp_path, capsys):
    from lmic.api import solve

    system, prob = qib
    r = solve("qib.thm1", system=str(EXAMPLES / "qib.thm1.flexible-joint.yaml"))
    path = tmp_path / "q.json"
    write_certificate(path, r.problem, r.solution, r.certificate, system=system)
    code, out = _audit_json(path, capsys)
    assert code == 0 and out["ok"] and "created" in out["informational"]
    # the certificate's own smallest relative margin, from the file
    margin = min(e["rel_margin"] for e in json.loads(path.read_text())["certificate"]["lmis"])
    code, out = _audit_json(path, capsys, "--tol", f"strict_rel={margin * 10}")
    assert code == 1 and out["field"] == "certificate.verdict" and out["tolerances"]["strict_rel"] == margin * 10
    code, out = _audit_json(path, capsys, "--tol", f"strict_rel={margin / 10}")
    assert code == 0
    assert main(["audit", str(path), "--tol", "rel=1e-3"]) == 2  # looser than the default
    assert "looser" in capsys.readouterr().err
    with pytest.raises(LmicError, match="looser"):
        audit_certificate(path, tol={"farkas_rel": 1.0})


# -- single-field mutations ---------------------------------------------------------------------


def _leaves(value, keys=()):
    """(keys, value) of every node (keys: a tuple of dict keys and list indices)."""
    yield keys, value
    if isinstance(value, dict):
        for k, v in value.items():
            yield from _leaves(v, (*keys, k))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from _leaves(v, (*keys, i))


def _dotted(keys) -> str:
    out = ""
    for k in keys:
        out += f"[{k}]" if isinstance(k, int) else (f".{k}" if out else str(k))
    return out


def _locate(doc, keys):
    """Parent container and key of a node."""
    obj = doc
    for k in keys[:-1]:
        obj = obj[k]
    return obj, keys[-1]


def _mutate(value):
    if isinstance(value, bool):
        return not value
    if isinstance(value, int):
        return value + 1
    if isinstance(value, float):
        return value + 1.0 + abs(value)
    if isinstance(value, str):
        return value + "0" if value else "x"
    if value is None:
        return 1.0
    if isinstance(value, list):
        return value[:-1] if value else [0.0]
    return {**value, "zz_added": 1} if isinstance(value, dict) else value


def _mutants(doc):
    for keys, value in list(_leaves(doc)):
        if not keys:
            continue
        yield keys, "change", _mutate(value)
        if isinstance(value, dict):
            yield keys, "delete", None


def _is_informational(keys) -> bool:
    from lmic.certify.certificate import _matches

    return _matches(".".join(str(k) for k in keys if not isinstance(k, int)), INFORMATIONAL)


def _run_sweep(path: Path, doc: dict, sample_every: int = 1, only: tuple = ()) -> tuple[int, list[str]]:
    """Audit single-field mutants: every ``sample_every``-th one, and all under the ``only`` sections."""
    validator = jsonschema.Draft202012Validator(_schema())
    bad: list[str] = []
    n = 0
    for i, (keys, how, new) in enumerate(_mutants(doc)):
        if i % sample_every and keys[0] not in only:
            continue
        mpath = _dotted(keys)
        m = copy.deepcopy(doc)
        parent, key = _locate(m, keys)
        if how == "delete":
            if isinstance(parent, dict):
                del parent[key]
            else:
                continue
        else:
            parent[key] = new
        path.write_text(json.dumps(m))
        n += 1
        schema_ok = not list(validator.iter_errors(m))
        try:
            r = audit_certificate(path)
        except CertificateError:
            if schema_ok and not mpath.startswith(("ir.embedded", "system.path")):
                bad.append(f"{how} {mpath}: CertificateError on a schema-valid mutant")
            continue
        if _is_informational(keys) and how == "change":
            if not r.ok:
                bad.append(f"{how} {mpath}: informational field rejected ({r.field})")
        elif r.ok:
            bad.append(f"{how} {mpath}: accepted")
        elif not r.field:
            bad.append(f"{how} {mpath}: rejected without naming a field")
    return n, bad


def test_every_single_field_mutation_of_a_small_certificate_is_rejected(tmp_path):
    import scipy.sparse as sp

    from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable

    # min t s.t. [[t, 1], [1, p]] >= 0, p > 0, 2 - p >= 0 and t - 0.1 >= 0 (a linear row)
    prob = Problem(
        [Variable("p", "scalar", (1, 1)), Variable("t", "scalar", (1, 1), offset=1)],
        [
            LMI("[[t,1],[1,p]] >= 0", 2, sp.csc_matrix(np.array([[0, 0, 1.0], [1, 0, 0], [0, 1, 0]])), strict=False),
            LMI("p > 0", 1, sp.csc_matrix([[0.0, 1.0, 0.0]])),
        ],
        LinearConstraints(
            sp.csr_matrix([[-0.1, 0.0, 1.0], [2.0, -1.0, 0.0]]), ["ge", "ge"], [False, False], ["t >= 0.1", "p <= 2"]
        ),
        Objective("min", np.array([0.0, 0.0, 1.0])),
    )
    sol = Solution("optimal", x=np.array([2.0, 0.5]), objective=0.5, backend="clarabel")
    cert = certify(prob, sol)
    assert cert.verdict == "certified"
    path = tmp_path / "c.json"
    write_certificate(path, prob, sol, cert)
    assert audit_certificate(path).ok
    n, bad = _run_sweep(path, json.loads(path.read_text()))
    assert n > 150
    assert not bad, f"{len(bad)} of {n} mutants: " + "; ".join(bad[:8])


def test_sampled_mutations_of_a_real_theorem_certificate_are_rejected(qib, tmp_path):
    from lmic.api import solve

    system, _ = qib
    r = solve("qib.thm1", system=str(EXAMPLES / "qib.thm1.flexible-joint.yaml"))
    path = tmp_path / "q.json"
    write_certificate(path, r.problem, r.solution, r.certificate, system=system)
    doc = json.loads(path.read_text())
    total = sum(1 for _ in _mutants(doc))
    n, bad = _run_sweep(path, doc, sample_every=max(1, total // 60))
    assert n >= 50
    assert not bad, f"{len(bad)} of {n} mutants: " + "; ".join(bad[:8])


def test_sampled_mutations_of_a_certificate_with_an_enclosure_are_rejected(tmp_path):
    from lmic.api import solve

    control1 = TRUSS1.parent / "control1.dat-s"
    r = solve(str(control1), backend="clarabel")
    assert r.enclosure is not None
    path = tmp_path / "c.json"
    write_certificate(path, r.problem, r.solution, r.certificate, enclosure=r.enclosure)
    assert audit_certificate(path).ok
    doc = json.loads(path.read_text())
    assert doc["enclosure"]["lower"] is not None
    # every mutant of the enclosure section, and a sample of the rest
    mutants = list(_mutants(doc))
    enclosure = sum(1 for keys, _, _ in mutants if keys[0] == "enclosure")
    n, bad = _run_sweep(path, doc, sample_every=max(1, (len(mutants) - enclosure) // 30), only=("enclosure",))
    assert n >= enclosure
    assert not bad, f"{len(bad)} of {n} mutants: " + "; ".join(bad[:8])
