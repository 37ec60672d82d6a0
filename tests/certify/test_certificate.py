"""Certificate files: schema, atomic writing, strict reading, audits that catch tampering."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from certify_helpers import lyapunov
from scipy.linalg import solve_continuous_lyapunov

from lmic.certify import certify
from lmic.certify.certificate import (
    SCHEMA_VERSION,
    audit_certificate,
    integrity_of,
    ir_hash,
    read_certificate,
    write_certificate,
)
from lmic.errors import CertificateError
from lmic.solution import Solution

A3 = [[-1.0, 2.0, -1.0], [-4.0, -2.0, 0.0], [1.0, 1.0, -2.0]]


@pytest.fixture
def raw_cert(tmp_path, lyapunov_point):
    """A certificate of a raw IR problem (embedded IR)."""
    prob, x = lyapunov_point
    sol = Solution("optimal", x=x, backend="clarabel", native_status="Solved", margin=0.1, strategy="max-margin")
    path = tmp_path / "raw.json"
    doc = write_certificate(path, prob, sol, certify(prob, sol))
    return path, doc


def _rewrite(path: Path, doc: dict) -> None:
    path.write_text(json.dumps(doc))


def test_written_file_follows_the_schema_and_records_everything(raw_cert, lyapunov_point):
    import jsonschema

    from lmic.schemas import load_schema

    path, doc = raw_cert
    on_disk = json.loads(path.read_text())
    jsonschema.validate(on_disk, load_schema("certificate"))
    assert on_disk == doc
    assert on_disk["lmic_certificate"] == SCHEMA_VERSION
    assert on_disk["theorem"] is None and on_disk["system"] is None
    assert on_disk["ir"]["embedded"] is not None
    assert on_disk["ir"]["sha256"] == ir_hash(lyapunov_point[0])
    assert on_disk["backend"]["versions"]["lmic"] and "clarabel" in on_disk["backend"]["versions"]
    assert on_disk["solution"]["variables"]["P"] == lyapunov_point[0].unpack(lyapunov_point[1])["P"].tolist()
    assert on_disk["certificate"]["verdict"] == "certified"
    assert on_disk["tolerances"]["rel"] == 1e-8
    assert [p.name for p in path.parent.iterdir()] == ["raw.json"]  # no temporary file left


def test_audit_of_an_untouched_certificate_passes(raw_cert):
    path, _ = raw_cert
    r = audit_certificate(path)
    assert r.ok and r.verdict == "certified" and r.field is None
    assert r.checked == ["schema", "tolerances", "embedded IR", "ir.sha256", "recomputed fields", "integrity"]
    exact = audit_certificate(path, exact=True)
    assert exact.ok and exact.certificate.exact["proven"]


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (lambda d: d["solution"]["x"].__setitem__(0, d["solution"]["x"][0] * 1.001), "solution.variables.P"),
        (lambda d: d["certificate"]["lmis"][1].__setitem__("min_eig", 2.0), "certificate.lmis[1].min_eig"),
        (lambda d: d["certificate"].__setitem__("verdict", "infeasible-certified"), "certificate.verdict"),
        (lambda d: d["certificate"]["checks"][0].__setitem__("ok", False), "certificate.checks[0].ok"),
        (lambda d: d["ir"]["embedded"]["data"].__setitem__("A", [[-2.0, 2.0, -1.0], *A3[1:]]), "ir.sha256"),
        (lambda d: d["ir"].__setitem__("sha256", "0" * 64), "ir.sha256"),
    ],
)
def test_tampering_is_caught_and_named(raw_cert, edit, field):
    path, doc = raw_cert
    edit(doc)
    _rewrite(path, doc)
    r = audit_certificate(path)
    assert not r.ok and r.verdict == "rejected"
    assert r.field == field
    assert field in r.message


def test_consistent_but_forged_point_changes_the_numbers(raw_cert):
    # change x AND the variables consistently: the recomputed margins then differ
    path, doc = raw_cert
    doc["solution"]["x"] = [v * 2 for v in doc["solution"]["x"]]
    doc["solution"]["variables"]["P"] = [[v * 2 for v in row] for row in doc["solution"]["variables"]["P"]]
    _rewrite(path, doc)
    r = audit_certificate(path)
    assert r.field == "certificate.lmis[0].min_eig"
    assert "recorded" in r.message and "recomputed" in r.message


@pytest.mark.parametrize(
    ("content", "needle"),
    [
        ("", "empty certificate file"),
        ('{"lmic_certificate": 1, "lmic": "0.1.0", "crea', "not valid JSON (truncated or corrupted?)"),
        ('{"lmic_certificate": 2}', "unknown certificate schema version 2"),
        ("[1, 2]", "not an lmic certificate"),
        ('{"lmic_certificate": 1, "x": NaN}', "NaN is not allowed"),
    ],
)
def test_malformed_files_raise_one_line(tmp_path, content, needle):
    p = tmp_path / "bad.json"
    p.write_text(content)
    with pytest.raises(CertificateError) as err:
        read_certificate(p)
    assert needle in str(err.value)
    assert "\n" not in str(err.value)


def test_schema_violation_names_the_field(raw_cert):
    path, doc = raw_cert
    doc["certificate"]["lmis"][0]["dim"] = "three"
    _rewrite(path, doc)
    with pytest.raises(CertificateError, match=r"certificate\.lmis\[0\]\.dim"):
        audit_certificate(path)
    with pytest.raises(CertificateError, match="no such certificate file"):
        read_certificate(path.parent / "missing.json")


def test_truncated_real_certificate(raw_cert):
    path, _ = raw_cert
    text = path.read_text()
    path.write_text(text[: len(text) // 2])
    with pytest.raises(CertificateError, match="truncated"):
        audit_certificate(path)


def test_failed_write_leaves_the_old_file_intact(raw_cert, lyapunov_point, monkeypatch):
    path, _ = raw_cert
    before = path.read_text()

    def boom(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", boom)
    prob, x = lyapunov_point
    sol = Solution("optimal", x=2 * x)
    from lmic.output import OutputError

    with pytest.raises(OutputError, match="disk full"):  # one line, exit code 2 on the command line
        write_certificate(path, prob, sol, certify(prob, sol))
    assert path.read_text() == before
    assert sorted(p.name for p in path.parent.iterdir()) == ["raw.json"]


def test_infeasibility_certificate_roundtrip(tmp_path):
    A = np.array([[0.5, 1.0], [0.0, -1.0]])
    prob = lyapunov(A)
    v = np.array([1.0, 0.0])  # A v = 0.5 v
    Z = np.outer(v, v)
    sol = Solution("infeasible", farkas={"lmis": [Z, Z], "linear": []}, backend="test")
    path = tmp_path / "inf.json"
    # the exact proof makes it global (a scale-free problem's float ray only bounds the margin)
    write_certificate(path, prob, sol, certify(prob, sol, exact=True))
    r = audit_certificate(path)
    assert r.ok and r.verdict == "infeasible-certified"
    doc = json.loads(path.read_text())
    doc["solution"]["farkas"]["lmis"][0] = [[1.0, 0.0], [0.0, 1.0]]
    _rewrite(path, doc)
    bad = audit_certificate(path)
    assert not bad.ok and bad.field.startswith("certificate.exact")  # the recomputed exact proof differs first


# ---- certificates of compiled theorems (recompiled from the theorem and the system file)


@pytest.fixture
def theorem_cert(tmp_path):
    from lmic.compile import compile_theorem
    from lmic.system import load_system

    sysfile = tmp_path / "lyap.yaml"
    sysfile.write_text("lmic: 1\nname: test\ndata:\n  A: " + json.dumps(A3) + "\nparams: {}\n")
    system = load_system(sysfile)
    prob = compile_theorem("thesis.lyapunov", system)
    P = solve_continuous_lyapunov(np.array(A3).T, -np.eye(3))
    x = prob.pack({"P": P})
    sol = Solution("feasible", x=x, backend="scs")
    path = tmp_path / "thm.json"
    doc = write_certificate(path, prob, sol, certify(prob, sol), system=system)
    return path, doc, sysfile


def test_theorem_certificate_recompiles(theorem_cert):
    path, doc, _ = theorem_cert
    assert doc["theorem"]["id"] == "thesis.lyapunov" and doc["theorem"]["citation"]
    assert doc["system"]["path"] == "lyap.yaml"  # relative to the certificate
    assert doc["ir"]["embedded"] is None
    r = audit_certificate(path)
    assert r.ok, r.message
    assert r.checked[:5] == ["schema", "tolerances", "system.sha256", "theorem.template_hash", "ir.sha256"]
    assert "theorem thesis.lyapunov on lyap.yaml" in r.message


def test_changed_system_file_is_caught(theorem_cert):
    path, _, sysfile = theorem_cert
    sysfile.write_text(sysfile.read_text().replace("-4.0", "-4.5"))
    r = audit_certificate(path)
    assert not r.ok and r.field == "system.sha256"


def test_a_renamed_system_file_is_named_as_the_cause(theorem_cert):
    """Only the system's ``name:`` changed (same data, system.sha256 holds): the IR records the
    name, so the certificate no longer matches; the audit says that, not "the plugin changed"."""
    path, _, sysfile = theorem_cert
    sysfile.write_text(sysfile.read_text().replace("name: test", "name: renamed"))
    r = audit_certificate(path)
    assert not r.ok and r.field == "ir.sha256"
    assert "the system file's name changed ('test' -> 'renamed'), and the IR records it" in r.message


def test_changed_compilation_is_caught_by_the_ir_hash(theorem_cert):
    # a different compilation (here: other parameters; equally a changed plugin) -> other IR
    path, doc, _ = theorem_cert
    doc["params"] = {"nonstrict": "1"}
    _rewrite(path, doc)
    r = audit_certificate(path)
    assert not r.ok and r.field == "theorem.template_hash"
    assert "option nonstrict differs; LMI (2.9) removed; LMI (2.14) added" in r.message
    # a certificate predating template hashes still meets the IR hash
    for key in ("template_hash", "template_parts"):
        doc["theorem"].pop(key)
    _rewrite(path, doc)
    r = audit_certificate(path)
    assert not r.ok and r.field == "ir.sha256"
    assert "recompiling gives a different IR" in r.message


def test_certificate_records_provider_and_template_hash(theorem_cert):
    _, doc, _ = theorem_cert
    thm = doc["theorem"]
    assert thm["provider"]["distribution"] == "lmic" and thm["provider"]["version"]
    assert thm["provider"]["entry_point"] == "thesis = lmic_observers.thesis"
    assert len(thm["template_hash"]) == 64 and "LMI (2.9)" in thm["template_parts"]


def test_audit_rejects_a_certificate_whose_theorem_changed(tmp_path):
    """The same id, now with a different LMI (e.g. a plugin upgrade): the audit names the change."""
    from lmic.compile import compile_theorem
    from lmic.registry import REGISTRY, register
    from lmic.system import load_system
    from lmic.template import theorem

    def make(scale):
        @theorem(id="tst.changed", title="t", citation="c", kind="analysis")
        def build(t):
            (n,) = t.dims("n")
            A = t.data("A", n, n)
            P = t.symmetric("P", n, pd=True)
            t.lmi("(1)", A.T * P + P * A + scale * P < 0)

        return build

    sysfile = tmp_path / "s.yaml"
    sysfile.write_text("lmic: 1\ndata:\n  A: " + json.dumps(A3) + "\n")
    system = load_system(sysfile)
    try:
        register(make(0))
        prob = compile_theorem("tst.changed", system)
        P = solve_continuous_lyapunov(np.array(A3).T, -np.eye(3))
        sol = Solution("feasible", x=prob.pack({"P": P}), backend="scs")
        path = tmp_path / "c.json"
        write_certificate(path, prob, sol, certify(prob, sol), system=system)
        assert audit_certificate(path).ok
        register(make(1))  # the theorem changes under the same id
        r = audit_certificate(path)
        assert not r.ok and r.field == "theorem.template_hash"
        assert "LMI (1) differs" in r.message and "P > 0" not in r.message
    finally:
        REGISTRY._theorems.pop("tst.changed", None)


def test_theorem_not_installed_and_missing_system(theorem_cert):
    path, doc, sysfile = theorem_cert
    doc["theorem"]["id"] = "nobody.thm9"
    _rewrite(path, doc)  # a modified theorem id: rejected, named
    r = audit_certificate(path)
    assert not r.ok and r.field == "theorem.id"
    doc["integrity"] = integrity_of(doc)  # as written by an lmic with that theorem installed
    _rewrite(path, doc)
    with pytest.raises(CertificateError, match="theorem 'nobody.thm9' is not installed"):
        audit_certificate(path)
    doc["theorem"]["id"] = "thesis.lyapunov"
    doc["integrity"] = integrity_of(doc)
    _rewrite(path, doc)
    sysfile.unlink()
    with pytest.raises(CertificateError, match="not found"):
        audit_certificate(path)


def test_compiled_ir_without_its_system_is_embedded(tmp_path):
    from lmic.compile import compile_theorem

    prob = compile_theorem("thesis.lyapunov", {"lmic": 1, "data": {"A": A3}})
    x = prob.pack({"P": solve_continuous_lyapunov(np.array(A3).T, -np.eye(3))})
    sol = Solution("optimal", x=x)
    path = tmp_path / "ir.json"
    doc = write_certificate(path, prob, sol, certify(prob, sol))
    assert doc["theorem"]["id"] == "thesis.lyapunov"
    assert doc["ir"]["embedded"] is not None
    r = audit_certificate(path)
    assert r.ok and "embedded IR" in r.checked


def test_repaired_farkas_certificate_is_recorded_and_audited(tmp_path):
    from test_farkas import _uir_sdpa

    prob, farkas = _uir_sdpa()
    sol = Solution("infeasible", farkas=farkas, backend="sdpa")
    path = tmp_path / "uir.json"
    doc = write_certificate(path, prob, sol, certify(prob, sol))
    rec = doc["certificate"]["farkas"]
    # a float ray of an inhomogeneous problem: bounded (no solution with ||x||_inf <= R), not global
    assert doc["certificate"]["verdict"] == "infeasible-bounded" and rec["repaired"]
    assert rec["original"]["rel_residual"] > 1e-5 and len(rec["certificate"]["lmis"]) == 3
    r = audit_certificate(path)
    assert r.ok and r.verdict == "infeasible-bounded", r.message
    doc["certificate"]["farkas"]["certificate"]["linear"][0] *= 1.01
    _rewrite(path, doc)
    bad = audit_certificate(path)
    assert not bad.ok and bad.field == "certificate.farkas.certificate.linear[0]"


def test_exact_infeasibility_certificate_is_audited(tmp_path):
    from test_farkas import _uir_sdpa

    prob, farkas = _uir_sdpa()
    sol = Solution("infeasible", farkas=farkas, backend="sdpa")
    plain = tmp_path / "plain.json"
    write_certificate(plain, prob, sol, certify(prob, sol))
    asked = audit_certificate(plain, exact=True)  # not recorded: run, reported, not compared
    # the file claims only the bounded verdict of its float ray; the proof run on request is
    # reported (it would make the verdict global), the file's claim is what is audited
    assert asked.ok and asked.verdict == "infeasible-bounded", asked.message
    assert "with it the verdict would be infeasible-certified (exact)" in asked.message
    path = tmp_path / "exact.json"
    doc = write_certificate(path, prob, sol, certify(prob, sol, exact=True))
    assert doc["certificate"]["label"] == "infeasible-certified (exact)"
    r = audit_certificate(path)
    assert r.ok and r.label == "infeasible-certified (exact)", r.message
    doc["certificate"]["exact"]["proven"] = False
    _rewrite(path, doc)
    assert audit_certificate(path).field == "certificate.exact.proven"
