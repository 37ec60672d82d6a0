"""``lmic solve --maximize/--minimize``: the certified end's gains, its certificate file (``-o``), audits.

The gains are recomputed here with numpy from the certified decision variables (formulas (19),
(22), (27) of the uio_dt paper), never with lmic's derive code; every certificate is checked by
``lmic audit``; tampered certificates (re-hashed, so only the recomputation can catch them) are
rejected.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from lmic.certify.certificate import integrity_of
from lmic.cli import main
from lmic.studies.sweep import maximize, minimize, write_end_certificate
from lmic.template import I, block, theorem

ROOT = Path(__file__).resolve().parents[3]
UIO = str(ROOT / "examples" / "uio_dt.thm4_1.flexible_joint.yaml")
#: a short bracket below gamma_max = 51.5 (catalogue T4.3): few solves, a certified lower end
BRACKET = ["--lo", "50", "--hi", "51.5", "--rtol", "1e-2", "--no-progress"]


@theorem(id="toy.growth", title="growth bound", citation="test")
def toy_growth(t):
    """``P > 0``, ``A^T P + P A - 2 b P < 0``: feasible iff ``b`` exceeds the spectral abscissa of ``A``."""
    (n,) = t.dims("n")
    A = t.data("A", n, n)
    b = t.param("b", default=0.0, domain="real")
    P = t.symmetric("P", n)
    t.lmi("P > 0", block(P) > 0)
    t.lmi("growth", block(A.T * P + P * A - 2 * b * P) < 0)


@theorem(id="toy.decay_gain", title="decay rate with a gain", citation="test")
def toy_decay_gain(t):
    """``P >= I``, ``A^T P + P A + 2 a P < 0``, ``s I - P >= 0``, min ``s``; derives ``Pinv = P^-1``."""
    (n,) = t.dims("n")
    A = t.data("A", n, n)
    a = t.param("a", default=0.0, domain="real")
    P = t.symmetric("P", n)
    s = t.scalar("s")
    t.lmi("P >= I", block(P - I(n)) >= 0)
    t.lmi("decay", block(A.T * P + P * A + 2 * a * P) < 0)
    t.lmi("s I - P >= 0", block(s * I(n) - P) >= 0)
    t.minimize(s)
    t.derive("Pinv", P.inv(), doc="P^-1")


def _uio_gains(system: str, v: dict) -> dict[str, np.ndarray]:
    """Gains of Theorem 4.1 from P, Ybar, Kbar, with numpy only (U, V by (19), then (22)/(27))."""
    d = {k: np.array(x, dtype=float) for k, x in yaml.safe_load(Path(system).read_text())["data"].items()}
    A, B, C, D1 = d["A"], d["B"], d["C"], d["D1"]
    n, p = A.shape[0], C.shape[0]
    CD1p = np.linalg.pinv(C @ D1)
    U, V = -D1 @ CD1p, np.eye(p) - (C @ D1) @ CD1p
    P, Ybar, Kbar = (np.array(v[k], dtype=float) for k in ("P", "Ybar", "Kbar"))
    Y, K = np.linalg.solve(P, Ybar), np.linalg.solve(P, Kbar)
    E = U + Y @ V
    M = np.eye(n) + E @ C
    return {"Y": Y, "K": K, "E": E, "M": M, "N": M @ A - K @ C, "L": K @ (np.eye(p) + C @ E) - M @ A @ E, "G": M @ B}


@pytest.fixture(scope="module")
def uio_run(tmp_path_factory):
    """One ``--maximize gamma -o CERT --json`` run on the flexible joint (shared by the tests)."""
    cert = tmp_path_factory.mktemp("maxgain") / "end.json"
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = main(["solve", "uio_dt.thm4_1", UIO, "--maximize", "gamma", *BRACKET, "-o", str(cert), "--json"])
    return code, json.loads(buf.getvalue()), cert


def test_maximize_returns_the_gains_of_the_certified_end(uio_run):
    code, d, cert = uio_run
    assert code == 0 and d["certificate_file"] == str(cert)
    lower = d["ends"]["lower"]
    assert lower["value"] == d["lower"] == d["certified"] and lower["evidence"] == "certified point"
    assert 50.0 <= d["lower"] < d["upper"] <= 51.5
    upper = d["ends"]["upper"]
    assert upper["value"] == d["upper"] and upper["evidence"] == d["upper_kind"]
    assert upper["is_bound"] == (d["upper_kind"] == "infeasible-certified")
    # the gains recomputed with numpy from the certified P, Ybar, Kbar (recorded in the file)
    doc = json.loads(cert.read_text())
    assert doc["params"]["gamma"] == d["lower"]
    want = _uio_gains(UIO, doc["solution"]["variables"])
    for name, g in want.items():
        got = np.array(lower["derived"][name], dtype=float)
        assert np.allclose(got, g, rtol=1e-6, atol=1e-6 * np.linalg.norm(g)), name
        assert lower["derived_norms"][name] == pytest.approx(np.linalg.norm(np.atleast_2d(g), 2), rel=1e-6)
    # the bound on usable gains
    assert max(lower["derived_norms"][k] for k in ("L", "K", "N", "M", "G")) < 1e4
    # gamma_max = 1/sqrt(rho) >= gamma at the certified point
    rho = float(np.array(doc["solution"]["variables"]["rho"]).ravel()[0])
    assert lower["derived"]["gamma_max"] == pytest.approx(1.0 / np.sqrt(rho), rel=1e-9)
    assert 1.0 / np.sqrt(rho) >= d["lower"] * (1 - 1e-9)


def test_the_end_certificate_audits(uio_run, capsys):
    _, d, cert = uio_run
    assert main(["audit", str(cert), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["ok"] is True and out["exit_code"] == 0


def _tampered(cert: Path, tmp: Path, change) -> Path:
    doc = json.loads(cert.read_text())
    change(doc)
    doc["integrity"] = integrity_of(doc)  # a forger re-hashes: only the recomputation can catch it
    out = tmp / "tampered.json"
    out.write_text(json.dumps(doc))
    return out


def _set_gain(doc):
    row = next(r for r in doc["certificate"]["derived"] if r["name"] == "L")
    row["value"][0][0] *= 0.5


def _raise_gamma(doc):
    doc["params"]["gamma"] = 60.0  # claim the point certifies a larger Lipschitz constant


def _move_point(doc):
    doc["solution"]["x"][0] *= 1.5


@pytest.mark.parametrize("change", [_set_gain, _raise_gamma, _move_point], ids=["gain", "gamma", "point"])
def test_a_tampered_end_certificate_is_rejected(uio_run, tmp_path, change, capsys):
    _, _, cert = uio_run
    bad = _tampered(cert, tmp_path, change)
    assert main(["audit", str(bad), "--json"]) == 1
    out = json.loads(capsys.readouterr().out)
    assert out["ok"] is False and out["exit_code"] == 1


def test_maximize_text_shows_both_ends_and_the_gains(tmp_path, capsys):
    cert = tmp_path / "c.json"
    assert main(["solve", "uio_dt.thm4_1", UIO, "--maximize", "gamma", *BRACKET, "-o", str(cert)]) == 0
    out = capsys.readouterr().out
    assert "sup gamma" in out and "(evidence: a certified point)" in out and "bisection upper" in out
    assert "L            4x2 matrix, ||.||_2 = " in out and f"written to {cert}" in out
    assert cert.exists()


def test_minimize_toy_growth_bound_is_the_spectral_abscissa(tmp_path, capsys):
    A = np.array([[-1.0, 2.0], [0.0, -3.0]])
    truth = float(np.max(np.linalg.eigvals(A).real))  # -1, independently of lmic
    sysd = {"lmic": 1, "data": {"A": A.tolist()}}
    res = minimize(toy_growth, sysd, "b", rtol=1e-4, xtol=1e-4)
    assert res.sense == "min" and res.certified == res.upper and res.end is not None
    assert res.lower <= truth <= res.upper and res.upper - res.lower <= 2e-4
    # the certified end's point, checked with numpy: P > 0 and A^T P + P A - 2 b P < 0
    P = np.array(res.end.problem.unpack(res.end.solution.x)["P"], dtype=float)
    assert np.linalg.eigvalsh(P).min() > 0
    assert np.linalg.eigvalsh(A.T @ P + P @ A - 2 * res.upper * P).max() < 0
    assert res.end.certificate.verdict == "certified" and res.exit_code() == 0
    d = res.to_dict()
    assert d["mode"] == "minimize" and d["ends"]["upper"]["evidence"] == "certified point"
    assert d["ends"]["lower"]["value"] == res.lower


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--maximize", "gamma", "--minimize", "gamma"], "give one of"),
        (["--sweep", "gamma=1:2:3", "-o", "x.json"], "-o is not available with --sweep"),
        (["--maximize", "gamma", "-o", "/nonexistent-folder/x.json"], "does not exist"),
        (["--minimize", "gamma", "--hi", "-1"], "outside the domain"),
    ],
)
def test_bad_usage_exit_2_before_any_work(extra, message, capsys):
    assert main(["solve", "uio_dt.thm4_1", UIO, *extra]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_maximize_backs_off_the_end_point_and_its_certificate_audits(tmp_path, capsys):
    """With an objective and a derived gain the end's point is the backed-off one (objective within
    1e-3 of the bisection point's, ||x||_inf minimised); checked here with numpy and by the audit."""
    A = np.array([[-1.0, 2.0], [0.0, -3.0]])
    truth = -float(np.max(np.linalg.eigvals(A).real))  # decay rate 1
    res = maximize(toy_decay_gain, {"lmic": 1, "data": {"A": A.tolist()}}, "a", lo=0.0, hi=2.0, rtol=1e-3)
    assert res.lower <= truth <= res.upper
    end = res.end
    assert end.source == "backed-off point" and end.backoff == 1e-3 and end.verdict == "certified"
    v = end.problem.unpack(end.solution.x)
    P, s = np.array(v["P"], dtype=float), float(np.array(v["s"]).ravel()[0])
    # non-strict constraints, active at the backed-off point: they hold to the solver's 1e-8
    tol = 1e-8 * max(1.0, s)
    assert np.linalg.eigvalsh(P - np.eye(2)).min() >= -tol and np.linalg.eigvalsh(s * np.eye(2) - P).min() >= -tol
    assert np.linalg.eigvalsh(A.T @ P + P @ A + 2 * res.lower * P).max() < 0
    assert np.allclose(np.array(end.derived["Pinv"], dtype=float), np.linalg.inv(P), rtol=1e-9, atol=1e-12)
    bisection_x = next(p.x for p in res.points if p.value == res.lower and p.outcome == "feasible")
    bisection_s = float(end.problem.objective.value(bisection_x))
    assert s <= bisection_s + 1e-3 * abs(bisection_s) + 1e-9
    cert = tmp_path / "decay.json"
    write_end_certificate(res, str(cert))
    assert main(["audit", str(cert), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["ok"] is True
