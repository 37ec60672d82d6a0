"""Re-verification of a certificate file from scratch (:func:`audit_certificate`).

The audit trusts nothing in the file: it recompiles (or loads) the IR, checks the hashes,
re-runs the certifier with the recorded tolerances and compares every recorded number with the
recomputed one (the rules are in the docstring of :mod:`lmic.certify.certificate`). Split out
of it; it re-exports every public name.

Examples
--------
>>> from lmic.certify.check import Tolerances
>>> strictest(Tolerances(rel=1e-6), Tolerances()).rel
1e-08
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from lmic.certify.certificate_format import read_certificate
from lmic.certify.certificate_hash import CLAIMED, INFORMATIONAL, _integrity_finding, _matches, ir_hash
from lmic.certify.certificate_write import _json, certificate_document, theorem_changes
from lmic.certify.check import Certificate, Tolerances, certified_solution, certify
from lmic.errors import CertificateError, LmicError
from lmic.ir.problem import Problem
from lmic.solution import STATUSES, Solution

__all__ = ["audit_certificate", "AuditResult", "looser_tolerances", "strictest"]

#: free text and bit sizes inside recomputed sections: covered by the hash, not compared
#: (a reason quotes numbers whose last digits may vary between BLAS builds; the exact Farkas
#: multipliers come out of a float least-squares repair)
_TEXT_KEYS = ("reason", "note", "detail", "statement", "denominator_bits")

#: tolerances that are looser when larger / when smaller (strict_rel is a required margin,
#: zero_rel the fraction below which a point counts as ~0 and is rejected)
_LOOSER_IF_LARGER = ("rel", "objective_rel", "farkas_rel")
_LOOSER_IF_SMALLER = ("strict_rel", "zero_rel")


def looser_tolerances(recorded: dict[str, Any], than: Tolerances) -> list[tuple[str, Any, float]]:
    """Tolerances of ``recorded`` that are looser than ``than`` (or unknown): ``(name, value, bound)``.

    Examples
    --------
    >>> looser_tolerances({"rel": 1e300, "strict_rel": 1e-12}, Tolerances())
    [('rel', 1e+300, 1e-08)]
    >>> looser_tolerances({"strict_rel": 0.0}, Tolerances())
    [('strict_rel', 0.0, 1e-12)]
    """
    ref = than.to_dict()
    out: list[tuple[str, Any, float]] = []
    for key, value in recorded.items():
        num = _num(value)
        if key not in ref or num is None or not math.isfinite(num):
            out.append((key, value, float("nan") if key not in ref else ref[key]))
        elif key in _LOOSER_IF_LARGER and num > ref[key]:
            out.append((key, value, ref[key]))
        elif key in _LOOSER_IF_SMALLER and num < ref[key]:
            out.append((key, value, ref[key]))
        elif key not in _LOOSER_IF_LARGER and key not in _LOOSER_IF_SMALLER and num != ref[key]:
            out.append((key, value, ref[key]))
    return out


def strictest(a: Tolerances, b: Tolerances) -> Tolerances:
    """Key by key, the stricter of two tolerance sets.

    >>> strictest(Tolerances(rel=1e-6), Tolerances(rel=1e-9, strict_rel=0.0)).to_dict()["rel"]
    1e-09
    """
    da, db = a.to_dict(), b.to_dict()
    out = {}
    for k in da:
        out[k] = max(da[k], db[k]) if k in _LOOSER_IF_SMALLER else min(da[k], db[k])
    return Tolerances(**out)


@dataclass
class AuditResult:
    """The outcome of :func:`audit_certificate`.

    Attributes
    ----------
    ok : bool
        Every hash and number matches the recomputation.
    verdict : str
        The recomputed verdict when ``ok``; ``"rejected"`` otherwise.
    recorded_verdict : str
    field : str or None
        The first field that differs.
    message : str
        One line.
    certificate : Certificate or None
        The recomputed certificate (``None`` when the audit stopped before certifying).
    exact : bool
        Whether an exact proof was run (always when the certificate records one).
    theorem : str or None
    checked : list of str
        What was checked, in order.
    label : str
        The verdict as displayed: ``certified (exact)`` when an exact proof backs it.
    tolerances : dict
        The tolerances the audit decided with (lmic's defaults or stricter).
    informational : list of str
        The fields left unchecked (:data:`INFORMATIONAL`).
    """

    ok: bool
    verdict: str
    recorded_verdict: str
    field: str | None = None
    message: str = ""
    certificate: Certificate | None = None
    exact: bool = False
    theorem: str | None = None
    checked: list[str] = dataclasses.field(default_factory=list)
    label: str = ""
    tolerances: dict[str, float] = dataclasses.field(default_factory=lambda: Tolerances().to_dict())
    informational: list[str] = dataclasses.field(default_factory=lambda: list(INFORMATIONAL))

    def __post_init__(self) -> None:
        if not self.label:
            self.label = self.verdict

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        return _json(
            {
                "ok": self.ok,
                "verdict": self.verdict,
                "recorded_verdict": self.recorded_verdict,
                "field": self.field,
                "message": self.message,
                "theorem": self.theorem,
                "exact": self.exact,
                "label": self.label,
                "checked": self.checked,
                "tolerances": self.tolerances,
                "informational": self.informational,
                "certificate": None if self.certificate is None else self.certificate.to_dict(),
            }
        )


def _fail(doc: dict, fld: str, message: str, cert: Certificate | None = None, **kw: Any) -> AuditResult:
    rec = doc.get("certificate")
    return AuditResult(
        ok=False,
        verdict="rejected",
        recorded_verdict=str(rec.get("verdict")) if isinstance(rec, dict) else "?",
        field=fld,
        message=message,
        certificate=cert,
        **kw,
    )


def _provider_hint(theorem: dict[str, Any]) -> str:
    """What to install to audit a certificate of a theorem that is not installed here.

    >>> _provider_hint({"provider": {"distribution": "lmic-nb3", "version": "0.1.0"}})
    ' (the certificate was written with lmic-nb3 0.1.0: pip install lmic-nb3==0.1.0)'
    >>> _provider_hint({"provider": {"distribution": None, "module": "mine"}})
    ' (an inline theorem of module mine: install it as a plugin, or write its certificates with embed_ir=True)'
    """
    provider = theorem.get("provider") or {}
    dist, version = provider.get("distribution"), provider.get("version")
    if dist:
        pin = f"=={version}" if version else ""
        return f" (the certificate was written with {dist} {version or ''}".rstrip() + f": pip install {dist}{pin})"
    if provider.get("module"):
        return (
            f" (an inline theorem of module {provider['module']}: install it as a plugin, "
            "or write its certificates with embed_ir=True)"
        )
    return ""


def _rebuild(doc: dict[str, Any], base: Path) -> tuple[Problem, str, Any]:
    """The problem to audit against, a label, and the loaded system (None for an embedded IR)."""
    embedded = doc["ir"]["embedded"]
    theorem = doc["theorem"]
    if embedded is not None:
        from lmic.ir.jsonio import problem_from_dict

        try:
            problem = problem_from_dict(embedded, source="certificate ir.embedded")
        except LmicError as err:
            raise CertificateError(f"embedded IR is malformed: {err}") from None
        return problem, "embedded IR", None
    if theorem is None or doc["system"] is None or not doc["system"].get("path"):
        raise CertificateError("the certificate neither embeds its IR nor records a theorem and a system file")
    from lmic.compile import compile_theorem
    from lmic.registry import get_theorem
    from lmic.system import load_system

    try:
        thm = get_theorem(theorem["id"])
    except LmicError as err:
        if "ambiguous" in str(err):  # two plugins offer the id: refuse rather than guess
            raise CertificateError(str(err)) from None
        raise CertificateError(f"theorem '{theorem['id']}' is not installed here{_provider_hint(theorem)}") from None
    sys_path = Path(doc["system"]["path"])
    if not sys_path.is_absolute():
        sys_path = base / sys_path
    if not sys_path.is_file():
        raise CertificateError(f"system file {sys_path} (recorded in the certificate) not found")
    system = load_system(sys_path)
    if system.data_hash() != doc["system"]["sha256"]:
        why = f"system.sha256 differs: the data of {sys_path.name} changed since the certificate was written"
        return None, why, system  # type: ignore[return-value]
    params = doc["params"] or {}
    problem = compile_theorem(thm, system, params=params)
    return problem, f"theorem {theorem['id']} on {sys_path.name}", system


def _num(v: Any) -> float | None:
    if isinstance(v, bool):
        return None
    if isinstance(v, int | float):
        return float(v)
    if v in ("nan", "inf", "-inf"):
        return float(v)
    return None


def _close(a: float, b: float, atol: float) -> bool:
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    if math.isinf(a) or math.isinf(b):
        return a == b
    return abs(a - b) <= 1e-9 * max(abs(a), abs(b)) + atol


def _first_diff(rec: Any, new: Any, where: str, atol: float = 1e-300) -> tuple[str, Any, Any] | None:
    """The first leaf where the recorded and the recomputed value differ (numbers to 1e-9 rel)."""
    ra, na = _num(rec), _num(new)
    if ra is not None and na is not None and type(rec) is not str and type(new) is not str:
        if isinstance(rec, int) != isinstance(new, int) and (isinstance(rec, int) or isinstance(new, int)):
            if float(rec) != float(new):
                return (where, rec, new)
        return None if _close(ra, na, atol) else (where, rec, new)
    if isinstance(rec, dict) and isinstance(new, dict):
        scale = _num(new.get("scale")) if "min_eig" in new else None
        sub_atol = 1e-12 * scale if scale and math.isfinite(scale) else atol
        keys = [k for k in rec if k not in ("verdict", "label")] + [k for k in new if k not in rec]
        keys += [k for k in ("verdict", "label") if k in rec or k in new]
        for key in keys:
            sub = f"{where}.{key}"
            if key in _TEXT_KEYS or _matches(sub, INFORMATIONAL):
                continue
            if key not in rec or key not in new:
                return (sub, rec.get(key, "<missing>"), new.get(key, "<missing>"))
            d = _first_diff(rec[key], new[key], sub, sub_atol)
            if d:
                return d
        return None
    if isinstance(rec, list) and isinstance(new, list):
        if len(rec) != len(new):
            return (f"{where} (length)", len(rec), len(new))
        for i, (a, b) in enumerate(zip(rec, new, strict=True)):
            d = _first_diff(a, b, f"{where}[{i}]", atol)
            if d:
                return d
        return None
    if type(rec) is not type(new):
        return (where, rec, new)
    return None if rec == new else (where, rec, new)


def _short(v: Any) -> str:
    s = json.dumps(v) if not isinstance(v, str) else v
    return s if len(s) <= 60 else s[:57] + "..."


def _recomputed_diff(doc: dict[str, Any], new: dict[str, Any], infeasible: bool) -> tuple[str, Any, Any] | None:
    """First difference between the file and the regenerated document, on recomputed fields."""
    keys = [k for k in doc if k != "integrity"] + [k for k in new if k not in doc and k != "integrity"]
    for key in keys:
        if _matches(key, INFORMATIONAL) or _matches(key, CLAIMED):
            continue
        if key not in new or (new[key] is None and doc.get(key) is not None):
            continue  # a claim this lmic cannot recompute (e.g. the system of an embedded IR): hashed
        if key not in doc:
            return (key, "<missing>", new[key])
        rec, fresh = doc[key], new[key]
        if isinstance(rec, dict) and isinstance(fresh, dict):
            sub_keys = [k for k in rec if k not in ("verdict", "label")] + [k for k in fresh if k not in rec]
            sub_keys += [k for k in ("verdict", "label") if k in rec or k in fresh]
            for sk in sub_keys:
                path = f"{key}.{sk}"
                if _matches(path, INFORMATIONAL) or _matches(path, CLAIMED) or sk in _TEXT_KEYS:
                    continue
                if sk not in fresh or (fresh[sk] is None and rec.get(sk) is not None):
                    continue  # not recomputable here: hash-covered
                if sk not in rec:
                    return (path, "<missing>", fresh[sk])
                # a Farkas verification is normalised to sum tr Z_i + sum |y_r| = 1 and a repaired
                # certificate comes out of least squares: its round-off-level entries may differ
                # in the last bits between BLAS builds, so they compare with an absolute 1e-12
                atol = 1e-12 if path == "certificate.farkas" or (path == "certificate.exact" and infeasible) else 1e-300
                d = _first_diff(rec[sk], fresh[sk], path, atol)
                if d:
                    return d
            continue
        d = _first_diff(rec, fresh, key)
        if d:
            return d
    return None


def audit_certificate(
    path: str | os.PathLike[str],
    exact: bool = False,
    tol: Tolerances | float | dict | None = None,
) -> AuditResult:
    """Recompute a certificate from scratch and compare it with the file.

    The audit trusts nothing in the file but the data it recomputes from: it decides with its
    own tolerances (``tol``: lmic's defaults, or stricter), and a file that records looser ones
    is rejected, naming the tolerance. It rebuilds the IR (recompiling the theorem on the system
    file, or loading the embedded IR, both checked against ``ir.sha256``), re-runs the certifier
    on the recorded point (or Farkas ray), regenerates the whole document with
    :func:`certificate_document` and compares it field by field; the fields it cannot recompute
    (:data:`CLAIMED`, free text) are checked against the ``integrity`` hashes. Only the
    :data:`INFORMATIONAL` fields may differ.

    Parameters
    ----------
    path : path
        The certificate file.
    exact : bool
        Also run the exact rational proof when the file does not record one (it is reported,
        not compared). A recorded exact proof is always re-run and compared: the recorded
        verdict may rest on it.
    tol : Tolerances, float or dict, optional
        The auditor's tolerances; looser than lmic's defaults is refused (``LmicError``).

    Returns
    -------
    AuditResult
        ``ok`` is False (verdict ``rejected``) when any hash or number differs; ``field`` names
        the first one.

    Raises
    ------
    CertificateError
        Malformed, truncated or unknown-version file; theorem not installed; system file
        missing (one line each).

    Examples
    --------
    >>> import tempfile, os, json, numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> from lmic.certify.check import certify
    >>> from lmic.certify.certificate_write import write_certificate
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p>0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> s = Solution("optimal", x=np.array([2.0]))
    >>> f = os.path.join(tempfile.mkdtemp(), "c.json")
    >>> doc = write_certificate(f, p, s, certify(p, s))
    >>> doc["solution"]["x"] = [-1.0]; _ = open(f, "w").write(json.dumps(doc))
    >>> r = audit_certificate(f)
    >>> r.ok, r.field
    (False, 'solution.variables.p')
    """
    auditor = Tolerances.coerce(tol)
    too_loose = looser_tolerances(auditor.to_dict(), Tolerances())
    if too_loose:
        k, v, b = too_loose[0]
        raise LmicError(f"audit tolerance {k}={v} is looser than lmic's default {b}: an audit may only be stricter")
    p = Path(path)
    doc = read_certificate(p)
    theorem_id = (doc["theorem"] or {}).get("id")
    common: dict[str, Any] = {"theorem": theorem_id, "tolerances": auditor.to_dict()}
    recorded = doc["certificate"]
    # 1. the file may not ask for tolerances looser than the audit's
    # (looser than lmic's defaults; between those and stricter ones the auditor asked for, the
    # file's numbers are checked with its own tolerances and the verdict with the auditor's)
    for key, value, bound in looser_tolerances(doc["tolerances"], Tolerances()):
        what = "an unknown tolerance" if math.isnan(bound) else f"looser than lmic's default {bound:g}"
        return _fail(doc, f"tolerances.{key}", f"tolerances.{key} = {_short(value)} is {what}", **common)
    file_tol = strictest(Tolerances.coerce(dict(doc["tolerances"])), Tolerances())
    hashed = _integrity_finding(doc)
    # 2. the IR: recompiled from the theorem and the system file, or the embedded one
    try:
        problem, label, system = _rebuild(doc, p.resolve().parent)
    except LmicError as err:
        if hashed is not None:  # e.g. a modified system.path or params: name the modified field
            return _fail(doc, hashed[0], hashed[1], **common)
        if isinstance(err, CertificateError):
            raise
        raise CertificateError(f"cannot rebuild the IR the certificate records: {err}") from None
    if problem is None:
        return _fail(doc, "system.sha256", label, **common)
    checked = ["schema", "tolerances", "system.sha256" if doc["ir"]["embedded"] is None else "embedded IR"]
    if doc["ir"]["embedded"] is None:  # recompiled from the installed theorem: is it the same theorem?
        changed, note = theorem_changes(doc["theorem"], problem)
        if changed:
            return _fail(doc, "theorem.template_hash", changed, checked=checked, **common)
        if doc["theorem"] and doc["theorem"].get("template_hash"):
            checked.append("theorem.template_hash" + (f" ({note})" if note else ""))
    if ir_hash(problem) != doc["ir"]["sha256"]:
        why = (
            "the embedded IR was modified"
            if doc["ir"]["embedded"] is not None
            else "recompiling gives a different IR (the theorem plugin, the compiler or the parameters changed)"
        )
        recorded, now = (doc.get("system") or {}).get("name"), (problem.meta or {}).get("system")
        if doc["ir"]["embedded"] is None and recorded is not None and now is not None and recorded != now:
            # the data are the same (system.sha256 held): the IR records the system's name too
            why = f"the system file's name changed ({recorded!r} -> {now!r}), and the IR records it"
        return _fail(doc, "ir.sha256", f"ir.sha256 differs: {why}", checked=checked, **common)
    checked.append("ir.sha256")
    # 3. the solver's claims, as recorded, re-certified
    sol = doc["solution"]
    x = None if sol["x"] is None else np.asarray(sol["x"], dtype=float)
    if x is not None and x.shape != (problem.n,):
        why = f"solution.x has {x.size} entries, the IR {problem.n} variables"
        return _fail(doc, "solution.x", why, checked=checked, **common)
    backend = doc["backend"]
    status = backend["status"] if backend["status"] in STATUSES else "error"
    solution = Solution(
        status=status,
        x=x,
        objective=sol["objective"],
        backend=backend["name"] or "",
        native_status=backend.get("native_status") or "",
        farkas=sol.get("farkas"),
        margin=backend.get("margin"),
        strategy=backend.get("strategy") or "none",
        iterations=backend.get("iterations"),
        solve_s=float(backend.get("solve_s") or 0.0),
    )
    # recompute in the recorded mode: a certificate that records an exact proof may rest on it
    # (a strict LMI below the float threshold, proved exactly), so the proof is re-run
    recorded_exact = recorded.get("exact") is not None
    cert = certify(problem, solution, exact=recorded_exact, tol=file_tol)
    moved, _ = certified_solution(problem, solution, cert)
    if moved is not solution:
        # the proof holds at another point (snapped or rounded): the file's point is not proved
        why = "solution.x is not the proven point: the certifier proves a point moved from it"
        dist = float(np.max(np.abs(np.asarray(moved.x) - np.asarray(x))))
        return _fail(doc, "solution.x", f"{why} (max |x_q - x| = {dist:.3g})", cert, checked=checked, **common)
    fresh = certificate_document(
        problem, solution, cert, system=system, path=p, embed_ir=doc["ir"]["embedded"] is not None
    )
    # 4. every recomputed field, in document order; then the hashes of the rest
    d = _recomputed_diff(doc, fresh, backend["status"] == "infeasible")
    kw = {"theorem": theorem_id, "exact": recorded_exact, "checked": checked, "tolerances": auditor.to_dict()}
    if d:
        fld, a, b = d
        if fld.startswith("solution.variables."):
            fld = ".".join(fld.split(".")[:3]).split("[")[0]  # name the variable
            msg = f"{fld} differs from the value solution.x gives"
        else:
            msg = f"{fld} differs: recorded {_short(a)}, recomputed {_short(b)}"
        return _fail(doc, fld, msg, cert, **kw)
    checked.append("recomputed fields")
    # the sections that other modules re-verify (before the hashes: they name what is wrong)
    # -- optimal-value enclosure (lmic.certify.enclosure): both ends re-verified --
    if doc.get("enclosure") is not None:
        from lmic.certify.enclosure_audit import audit_enclosure

        try:
            enc = audit_enclosure(problem, doc["enclosure"], cert, doc.get("backoff"))
        except (ValueError, TypeError, KeyError, IndexError, AttributeError) as err:
            # a malformed section (the enclosure audit expects what lmic writes)
            fld, why = hashed if hashed is not None else ("enclosure", f"enclosure is malformed: {err}")
            return _fail(doc, fld, " ".join(why.split())[:200], cert, **kw)
        if not enc["ok"]:
            return _fail(doc, enc["field"], enc["message"], cert, **kw)
        checked.append("enclosure")
    if doc.get("backoff") is not None and doc["backoff"].get("x") is not None:  # -- lmic.backoff --
        rec_b = doc["backoff"]
        try:
            xb = np.asarray(rec_b["x"], dtype=float)
        except (ValueError, TypeError):
            xb = np.zeros(0)
        if xb.shape != (problem.n,):
            return _fail(doc, "backoff.x", "backoff.x has the wrong length", cert, **kw)
        sol_b = Solution(status=rec_b.get("status") or "optimal", x=xb)
        cb = certify(problem, sol_b, tol=file_tol)
        if cb.verdict == "rejected" and rec_b.get("verdict") == "certified":
            # margins below the float threshold (a point near an infimum, lmic.backoff's given
            # point): the exact proof at the point decides, as it did when the file was written
            cb = certify(problem, sol_b, tol=file_tol, exact=True)
        if cb.verdict != rec_b.get("verdict") or problem.objective.value(xb) != rec_b.get("objective"):
            return _fail(
                doc, "backoff", f"backoff differs: recorded {rec_b.get('verdict')}, recomputed {cb.verdict}", cert, **kw
            )
        checked.append("backoff")
    if doc.get("unbounded") is not None:  # -- unbounded-certified: the exact ray (lmic.route_unbounded) --
        from lmic.certify.farkas_unbounded import audit_unbounded

        unb = audit_unbounded(problem, doc["unbounded"])
        if not unb["ok"]:
            return _fail(doc, unb["field"], unb["message"], cert, **kw)
        # the ray proves "unbounded" only with a point that is feasible, not feasible within
        # the certifier's tolerance (lmic.route_unbounded._certified_point)
        from lmic.certify.enclosure_float import primal_end
        from lmic.certify.snap import exact_primal_end

        if x is None or not exact_primal_end(problem, x, primal_end(problem, x))["proven"]:
            why = "the point is not proved feasible with rigorous rounding or exactly: no proof of unboundedness"
            return _fail(doc, "unbounded", f"unbounded: {why}", cert, **kw)
        checked.append("unbounded (exact ray)")
    if hashed is not None:
        return _fail(doc, hashed[0], hashed[1], cert, **kw)
    checked.append("integrity")
    # 5. the verdict under the auditor's tolerances, when stricter than the file's
    final = strictest(file_tol, auditor)
    if final != file_tol:
        cert = certify(problem, solution, exact=recorded_exact, tol=final)
        checked.append("auditor tolerances")
        if cert.verdict != recorded["verdict"]:
            return _fail(
                doc,
                "certificate.verdict",
                f"under the audit's tolerances the verdict is {cert.verdict}, not {recorded['verdict']}: {cert.reason}",
                cert,
                **kw,
            )
    shown = cert
    msg = f"every hash and number matches ({label}); verdict {cert.label}"
    if doc.get("unbounded") is not None:
        word = "below" if problem.objective.sense == "min" else "above"
        msg += f"; unbounded {word} (exact improving ray re-proved): no optimum"
    if exact and not recorded_exact:
        # asked for a proof the file does not record: run it, report it, compare nothing new
        shown = certify(problem, solution, exact=True, tol=final)
        assert shown.exact is not None
        if shown.exact["proven"]:
            msg += "; exact proof (not recorded) holds: " + shown.exact.get("statement", shown.exact["reason"])
            if shown.verdict != cert.verdict:
                msg += f" (with it the verdict would be {shown.label}; re-certify with --exact)"
        else:
            msg += "; exact proof (not recorded) not obtained: " + shown.exact["reason"]
    elif recorded_exact and cert.exact is not None:
        msg += "; exact proof re-run: " + ("holds" if cert.exact["proven"] else "not obtained: " + cert.exact["reason"])
    label_out = cert.label
    if shown is not cert and shown.verdict == cert.verdict:
        label_out = shown.label  # e.g. 'certified (exact)' from the proof run on request
    verdict = cert.verdict
    if doc.get("unbounded") is not None and cert.verdict == "certified":
        # the certified point and the re-proved improving ray: lmic solve's verdict (exit 5)
        verdict = "unbounded-certified"
        label_out = label_out.replace("certified", "unbounded-certified", 1)
    return AuditResult(
        ok=True,
        verdict=verdict,
        recorded_verdict=recorded["verdict"],
        message=msg,
        certificate=shown,
        exact=exact or recorded_exact,
        theorem=theorem_id,
        checked=checked,
        label=label_out,
        tolerances=auditor.to_dict(),
    )
