"""The certifier: decide from the IR alone whether a solver's answer is what it claims.

A solver's ``optimal`` is a claim. :func:`certify` re-evaluates everything from the IR
(:class:`~lmic.ir.problem.Problem`), never from a backend's model:

* every LMI ``F(x)`` (sparse, from the IR coefficients) and its extreme eigenvalues;
* every linear row, the objective, the derived quantities (gains) and the theorem's checks;
* for an ``infeasible`` status, the dual (Farkas) certificate (:mod:`lmic.certify.farkas`);
* optionally (``exact=True``) an exact rational proof of every LMI (:mod:`lmic.certify.exact`).

Margins are relative to the *term scale*
----------------------------------------
For an LMI ``F(x) = F0 + sum_k x_k F_k`` the certifier computes the term scale

    ``T = || |F0| + sum_k |x_k| |F_k| ||_2``      (entrywise absolute values, spectral norm)

which bounds ``||F(x)||`` and is what the floating-point error of evaluating ``F(x)`` is
proportional to: the computed ``lambda_min`` is within ``(k + d + 2) u T`` of the exact one
(``k`` terms per entry, dimension ``d``, unit round-off ``u``). The relative margin is
``lambda_min / T``. It is scale-free, so a homogeneous LMI (``F0 = 0``) evaluated at a
near-zero point is judged at its own scale: the near-zero points SCS returns on homogeneous
LMIs (``omega ~ 1.7e-7``), whose tiny absolute violations would pass an absolute tolerance,
have a relative margin of order ``-1e-2`` and are rejected.

Acceptance rules (defaults in :class:`Tolerances`)
--------------------------------------------------
strict LMI (``F(x) > 0``)
    ``lambda_min > max(strict_rel, 10 (k + d + 2) u) * T``: positive beyond any doubt from
    floating-point evaluation (``strict_rel = 1e-12``; the second term is ~1e-13 for d = 180).
    A point at which every term of the LMI vanishes (``T == 0``, or ``T`` below ``zero_rel``
    times the coefficient scale ``|| |F0| + sum_k |F_k| ||``) is "~0" and rejected: a
    homogeneous LMI says nothing at ``x = 0``.
non-strict LMI (``F(x) >= 0``)
    ``lambda_min >= -rel * T`` (``rel = 1e-8``, a typical solver tolerance). When the solver
    itself reported ``inaccurate`` no tolerance is granted: ``lambda_min`` must be ``>= 0`` up
    to the floating-point error bound. A marginally infeasible problem comes back as
    ``inaccurate`` with a small violation (Clarabel, +1.6e-7 at ``||P|| ~ 7.5``); it must not
    pass as a certificate.
linear rows
    ``eq``: ``|r| <= rel * s``; ``ge``: ``r >= -rel * s``; strict ``ge``:
    ``r > max(strict_rel, 10 (k + 2) u) * s``, with ``s = |a0| + sum_k |a_k x_k|``.
objective
    The IR's ``c0 + c . x`` must agree with the solver's claim to ``objective_rel`` (relative to
    ``max(1, |value|)``); a disagreement rejects the answer.
derived quantities and checks
    Derived quantities are evaluated in order (``Problem.environment``); a failure (singular
    ``P``) or a non-finite value fails every check that uses it. Checks follow
    :data:`lmic.ir.problem.CHECK_KINDS` (``schur_stable``: spectral radius ``< 1``;
    ``hurwitz``: spectral abscissa ``< 0``; definiteness of the symmetric part with a
    ``strict_rel`` margin relative to its norm; ...). A failed check rejects the answer even
    when every LMI holds (e.g. an SCS "success" whose gain leaves ``A - L C`` unstable).

Exact mode (``exact=True``)
---------------------------
The float rules above are a test; an exact proof (:func:`lmic.certify.exact.prove`) is a
theorem, so in exact mode it decides the LMIs and the linear rows:

* when the whole proof holds (every LMI and inequality row exactly, every equality row exactly
  or within ``rel``), every LMI and row is accepted, whatever its float margin: a strict LMI
  whose relative margin is below ``strict_rel`` (e.g. ``uio_dt.thm3_2`` near its supremum,
  ~2e-13) is certified. The proof holds at the *recorded* rational point ``x_q``
  (``exact.point``), which is the solver's float point itself whenever that can be proved
  (``exact.at_x``), and otherwise a rounding or an exact projection onto the equality rows,
  at distance ``exact.distance`` from ``x``;
* otherwise, if ``x_q`` is the float point, each LMI or row proved on its own is accepted and
  a strict LMI disproved exactly is rejected; elsewhere the float rules stay;
* a non-strict LMI accepted within the float tolerance stays accepted when exactly disproved.

Every LMI and row entry reports both: ``float_ok`` (the float rule), ``exact`` (``proved``,
``disproved``, ``not proven``; ``within tolerance`` for equality rows; ``None`` outside exact
mode), ``ok`` (the decision) and ``decided_by`` (``float`` or ``exact``). Derived quantities,
checks and the objective are evaluated in float64 at ``x`` in either mode, and must hold; the
exact objective at ``x_q`` is reported in ``exact.objective``. The label is
``certified (exact)`` when the verdict is ``certified`` and the whole proof holds.

Verdicts
--------
``certified``            every criterion above holds at ``x`` (the solver status does not matter).
``rejected``             some criterion fails; ``reason`` names the first violated constraint
                         (LMIs, then linear rows, then derived quantities and checks, then the
                         objective) and by how much.
``infeasible-certified`` the status is ``infeasible`` and the Farkas certificate is a GLOBAL proof
                         (exact, or homogeneous problem: :func:`lmic.certify.farkas.scope`).
``infeasible-bounded``   the Farkas certificate verifies in float but only excludes solutions with
                         ``||x||_inf <= R`` (never called infeasible).
``unverified``           nothing to check: ``infeasible`` without a verifiable certificate,
                         ``unbounded``, or an ``error`` without a point.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> from lmic.solution import Solution
>>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> certify(p, Solution("optimal", x=np.array([2.0]))).verdict
'certified'
>>> c = certify(p, Solution("optimal", x=np.array([-1e-9])))
>>> c.verdict, c.reason
('rejected', "LMI 'p > 0' violated: lambda_min = -1e-09 (relative -1), needs > 0 (strict)")

A strict LMI below the float threshold, decided by the exact proof:

>>> q = Problem([Variable("p", "scalar", (1, 1))],
...             [LMI("M > 0", 2, sp.csc_matrix([[1e6, 0.], [0., 0.], [1e-7, 0.]]))],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> certify(q, Solution("optimal", x=np.array([0.0]))).verdict
'rejected'
>>> c = certify(q, Solution("optimal", x=np.array([0.0])), exact=True)
>>> c.label, c.lmis[0]["float_ok"], c.lmis[0]["exact"], c.lmis[0]["decided_by"]
('certified (exact)', False, 'proved', 'exact')
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field, fields
from typing import Any

import numpy as np

from lmic.errors import IRError, LmicError
from lmic.ir.expr import evaluate
from lmic.ir.problem import LMI, Check, Problem
from lmic.ir.svec import tril_unvec
from lmic.solution import Solution

__all__ = ["VERDICTS", "Tolerances", "Certificate", "certify", "lmi_report", "evaluate_checks"]

#: The verdicts of the certifier (``infeasible-bounded``: only "no solution with ||x||_inf <= R").
VERDICTS = ("certified", "rejected", "infeasible-certified", "infeasible-bounded", "unverified")

_U = float(np.finfo(float).eps) / 2.0  # unit round-off of float64


@dataclass(frozen=True)
class Tolerances:
    """Thresholds of the certifier (all relative; see the module docstring).

    Parameters
    ----------
    rel : float
        Tolerance for non-strict LMIs, equality rows and non-strict ``ge`` rows.
    strict_rel : float
        Minimum relative margin of a strict LMI or a strict row (never below the float64
        error bound of the evaluation).
    zero_rel : float
        A point whose term scale is below this fraction of the coefficient scale is "~0".
    objective_rel : float
        Allowed relative disagreement between the recomputed and the claimed objective.
    farkas_rel : float
        Relative residual allowed in a Farkas certificate (:mod:`lmic.certify.farkas`).

    Examples
    --------
    >>> Tolerances().rel
    1e-08
    >>> Tolerances.coerce(1e-6).rel, Tolerances.coerce({"strict_rel": 1e-9}).strict_rel
    (1e-06, 1e-09)
    """

    rel: float = 1e-8
    strict_rel: float = 1e-12
    zero_rel: float = 1e-12
    objective_rel: float = 1e-6
    farkas_rel: float = 1e-6

    @classmethod
    def coerce(cls, tol: Tolerances | float | dict | None) -> Tolerances:
        """A :class:`Tolerances` from ``None`` (defaults), a float (``rel``) or a dict."""
        if tol is None:
            return cls()
        if isinstance(tol, Tolerances):
            return tol
        if isinstance(tol, int | float) and not isinstance(tol, bool):
            if not (math.isfinite(tol) and tol >= 0):
                raise LmicError(f"tolerance must be a finite non-negative number, got {tol}")
            return cls(rel=float(tol))
        if isinstance(tol, dict):
            known = {f.name for f in fields(cls)}
            bad = set(tol) - known
            if bad:
                raise LmicError(f"unknown tolerance(s) {sorted(bad)}; known: {sorted(known)}")
            return cls(**{k: float(v) for k, v in tol.items()})
        raise LmicError(f"tolerance must be a number or a dict, got {type(tol).__name__}")

    def to_dict(self) -> dict[str, float]:
        """JSON-able form."""
        return asdict(self)


@dataclass
class Certificate:
    """What the certifier found (JSON-able through :meth:`to_dict`).

    Attributes
    ----------
    verdict : str
        One of :data:`VERDICTS`.
    reason : str
        One line: why (the violated constraint and by how much, or what could not be verified).
    status : str
        The solver's status (a claim, reported for reference).
    lmis : list of dict
        Per LMI: ``name, dim, strict, min_eig, max_eig, max_abs, scale, min_margin,
        rel_margin, threshold, ok`` (``min_margin`` is ``lambda_min``, the absolute distance
        to the boundary of the cone; ``rel_margin = lambda_min / scale``).
    linear : list of dict
        Per row: ``name, kind, strict, residual, scale, rel_residual, ok``.
    objective : dict or None
        ``sense, value`` (recomputed), ``claimed``, ``rel_diff``, ``ok``.
    derived : list of dict
        ``name, value`` (JSON-able), ``ok`` (computable and finite), ``error``.
    checks : list of dict
        ``name, kind, value, bound, ok`` (and ``error``).
    exact : dict or None
        The exact proof, when requested: of every LMI at a rational point
        (:func:`lmic.certify.exact.prove`), or for an ``infeasible`` answer of an exact Farkas
        certificate (:func:`lmic.certify.farkas.prove_infeasible`).
    farkas : dict or None
        The verification of an infeasibility certificate (:mod:`lmic.certify.farkas`).
    margin : dict or None
        The strict-inequality margin the backend claims and the smallest one found.
    tolerances : dict
    x : list of float or None
    time_s : float

    Examples
    --------
    >>> c = Certificate("certified", exact={"proven": True})
    >>> c.ok, c.label, c.min_margin
    (True, 'certified (exact)', None)
    """

    verdict: str
    reason: str = ""
    status: str = ""
    backend: str = ""
    lmis: list[dict[str, Any]] = field(default_factory=list)
    linear: list[dict[str, Any]] = field(default_factory=list)
    objective: dict[str, Any] | None = None
    derived: list[dict[str, Any]] = field(default_factory=list)
    checks: list[dict[str, Any]] = field(default_factory=list)
    exact: dict[str, Any] | None = None
    farkas: dict[str, Any] | None = None
    margin: dict[str, Any] | None = None
    tolerances: dict[str, float] = field(default_factory=dict)
    x: list[float] | None = None
    time_s: float = 0.0

    @property
    def ok(self) -> bool:
        """True for ``certified`` and ``infeasible-certified``."""
        return self.verdict in ("certified", "infeasible-certified")

    @property
    def min_margin(self) -> float | None:
        """The smallest ``lambda_min`` over the LMIs (``None`` without a point)."""
        vals = [e["min_eig"] for e in self.lmis if e.get("min_eig") is not None]
        return min(vals) if vals else None

    @property
    def label(self) -> str:
        """The verdict, with ``(exact)`` when an exact proof backs it (``certified (exact)``,
        ``infeasible-certified (exact)``)."""
        if self.verdict in ("certified", "infeasible-certified") and self.exact and self.exact.get("proven"):
            return f"{self.verdict} (exact)"
        return self.verdict

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form (floats, lists, dicts; non-finite floats become strings).

        Besides the fields it holds ``label`` (the verdict as displayed, e.g.
        ``certified (exact)``).

        >>> Certificate("certified", exact={"proven": True}).to_dict()["label"]
        'certified (exact)'
        """
        d = asdict(self)
        d["label"] = self.label
        return _jsonable(d)


# --------------------------------------------------------------------------------------------
# helpers


def _jsonable(v: Any) -> Any:
    if isinstance(v, dict):
        return {str(k): _jsonable(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_jsonable(x) for x in v]
    if isinstance(v, np.ndarray):
        return _jsonable(v.tolist())
    if isinstance(v, bool | np.bool_):
        return bool(v)
    if isinstance(v, int | np.integer):
        return int(v)
    if isinstance(v, float | np.floating):
        f = float(v)
        if math.isfinite(f):
            return f
        return "nan" if math.isnan(f) else ("inf" if f > 0 else "-inf")
    return v


def _g(v: float) -> str:
    return f"{v:.3g}"


def _spectral_norm_nonneg(M: np.ndarray) -> float:
    """Spectral norm of a symmetric entrywise non-negative matrix (its Perron root)."""
    if M.size == 0:
        return 0.0
    if M.shape[0] == 1:
        return float(M[0, 0])
    return float(max(np.linalg.eigvalsh(M)[-1], 0.0))


def _below_coefficient_scale(T: float, absC: Any, xx: np.ndarray, d: int, zero_rel: float) -> bool:
    """``T <= zero_rel * ||sum_i |C_i|||`` (the point is ~0 for this LMI); the coefficient
    scale is only computed when its cheap upper bound (the largest row sum) allows it."""
    M = tril_unvec(absC @ np.ones_like(xx), d)
    if T > zero_rel * float(M.sum(axis=1).max(initial=0.0)):
        return False  # the Perron root is at most the largest row sum
    coef_scale = _spectral_norm_nonneg(M)
    return coef_scale > 0 and T <= zero_rel * coef_scale


def lmi_report(lmi: LMI, x: np.ndarray, tol: Tolerances, *, inaccurate: bool = False) -> dict:
    """Evaluate one LMI at ``x`` and judge it (the rules of the module docstring).

    Parameters
    ----------
    lmi : LMI
    x : numpy.ndarray
    tol : Tolerances
    inaccurate : bool
        The solver reported ``inaccurate``: no tolerance for non-strict LMIs.

    Returns
    -------
    dict
        ``name, dim, strict, min_eig, max_eig, max_abs, scale, min_margin, rel_margin,
        float_err`` (the float64 error bound of ``lambda_min``), ``threshold, ok`` and ``note``.

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> r = lmi_report(LMI("p > 0", 1, sp.csc_matrix([[0., 1.]])), np.array([3.0]), Tolerances())
    >>> r["min_eig"], r["rel_margin"], r["ok"]
    (3.0, 1.0, True)
    """
    from lmic.certify.spectra import block_spectrum, perron_root

    C = lmi.coeffs.tocsr()
    xx = np.concatenate([[1.0], np.asarray(x, dtype=float)])
    d = lmi.dim
    F, eig = block_spectrum(lmi, x)  # one eigen-decomposition per block and point (shared)
    absC = abs(C)
    T = perron_root(tril_unvec(absC @ np.abs(xx), d))  # no second decomposition
    k = int(np.max(np.diff(C.indptr))) if C.nnz else 0
    err_rel = 10.0 * (k + d + 2) * _U
    out: dict[str, Any] = {"name": lmi.name, "dim": d, "strict": bool(lmi.strict)}
    if d == 0:  # an empty LMI holds vacuously
        inf = float("inf")
        out.update(
            min_eig=inf,
            max_eig=-inf,
            max_abs=0.0,
            scale=0.0,
            min_margin=inf,
            rel_margin=inf,
            float_err=0.0,
            threshold=None,
            ok=True,
            note="empty LMI",
        )
        return _decided_by_float(out)
    if not np.all(np.isfinite(F)):
        out.update(
            min_eig=float("nan"),
            max_eig=float("nan"),
            max_abs=float("nan"),
            scale=T,
            min_margin=float("nan"),
            rel_margin=float("nan"),
            float_err=float("nan"),
            threshold=None,
            ok=False,
            note="F(x) is not finite",
        )
        return _decided_by_float(out)
    lmin, lmax = float(eig[0]), float(eig[-1])
    rel = lmin / T if T > 0 else float("-inf") if lmin < 0 else 0.0
    out.update(
        min_eig=lmin,
        max_eig=lmax,
        max_abs=float(max(abs(lmin), abs(lmax))),
        scale=T,
        min_margin=lmin,
        rel_margin=rel,
        float_err=err_rel * T,
    )
    zero = T == 0.0 or _below_coefficient_scale(T, absC, xx, d, tol.zero_rel)
    if lmi.strict:
        thr = max(tol.strict_rel, err_rel) * T
        ok = (not zero) and lmin > thr
        note = "the point is ~0 for this LMI (every term vanishes)" if zero else ""
    elif inaccurate:
        thr = -err_rel * T
        ok = lmin >= thr
        note = "solver status 'inaccurate': no tolerance granted"
    else:
        thr = -tol.rel * T
        ok = lmin >= thr
        note = "" if lmin >= 0 else "holds within tolerance"
    out.update(threshold=thr, ok=bool(ok), note=note)
    return _decided_by_float(out)


def _decided_by_float(entry: dict[str, Any]) -> dict[str, Any]:
    """Record the float decision (``float_ok``); the exact proof may decide later."""
    entry.update(float_ok=bool(entry["ok"]), exact=None, decided_by="float")
    return entry


def _lmi_reason(r: dict, optimisation: bool = False) -> str:
    if r["note"].startswith("the point is ~0"):
        return (
            f"LMI '{r['name']}' is not certified: the point is ~0 for it "
            f"(term scale {_g(r['scale'])}), a homogeneous LMI says nothing there"
        )
    if not math.isfinite(r["min_eig"]):
        return f"LMI '{r['name']}' could not be evaluated: F(x) is not finite"
    if r["strict"] and abs(r["min_eig"]) <= r["float_err"]:
        return (
            f"LMI '{r['name']}' not certified: lambda_min = {_g(r['min_eig'])} "
            f"(relative {_g(r['rel_margin'])}) is zero to float64 accuracy, needs > 0 (strict)"
        )
    need = "> 0 (strict)" if r["strict"] else f">= {_g(r['threshold'])}"
    if r["strict"] and r["min_eig"] > 0:
        # a positive margin the float evaluation cannot vouch for: not a violation
        return (
            f"LMI '{r['name']}' holds with margin {r['min_eig']:.1e} (relative {_g(r['rel_margin'])}), below the "
            f"certification threshold {_g(r['threshold'])} (relative {_g(r['threshold'] / r['scale'])}): "
            + _margin_hint(r, optimisation)
        )
    return f"LMI '{r['name']}' violated: lambda_min = {_g(r['min_eig'])} (relative {_g(r['rel_margin'])}), needs {need}"


def _margin_hint(r: dict, optimisation: bool) -> str:
    """The likely cause of a positive margin below the threshold, and the option that helps."""
    if optimisation:
        return (
            "the optimum of a strict problem is an infimum on the boundary (unattained infimum or "
            "degenerate optimum); --backoff gives a certified point inside, within a relative "
            "objective tolerance; --exact may prove the margin exactly"
        )
    if r["rel_margin"] < 1e-9:
        return (
            f"scaling: the margin is {_g(r['rel_margin'])} of the matrix scale {_g(r['scale'])}; "
            "impose a larger one with --margin, prove it with --exact, or try another backend"
        )
    return "impose a larger margin with --margin, prove it with --exact, or try another backend"


def _linear_reports(problem: Problem, x: np.ndarray, tol: Tolerances, inaccurate: bool) -> list:
    lin = problem.linear
    if len(lin) == 0:
        return []
    A = lin.A.tocsr()
    xx = np.concatenate([[1.0], x])
    res = np.asarray(A @ xx).ravel()
    scale = np.asarray(abs(A) @ np.abs(xx)).ravel()
    k = np.diff(A.indptr)
    out = []
    for i in range(len(lin)):
        r, s = float(res[i]), float(scale[i])
        err = 10.0 * (int(k[i]) + 2) * _U * s
        kind, strict = lin.kinds[i], bool(lin.strict[i])
        allowed = err if inaccurate else max(tol.rel * s, err)
        if kind == "eq":
            ok, thr = abs(r) <= allowed, allowed
        elif strict:
            thr = max(tol.strict_rel * s, err)
            ok = r > thr and s > 0
        else:
            thr = -allowed
            ok = r >= thr
        out.append(
            {
                "name": lin.names[i],
                "kind": kind,
                "strict": strict,
                "residual": r,
                "scale": s,
                "rel_residual": (r / s if s > 0 else 0.0),
                "threshold": thr,
                "ok": bool(ok and math.isfinite(r)),
            }
        )
        _decided_by_float(out[-1])
    return out


def _linear_reason(r: dict) -> str:
    if r["kind"] == "eq":
        res, allowed = _g(r["residual"]), _g(r["threshold"])
        return f"equality '{r['name']}' violated: residual {res} (allowed {allowed})"
    rel = "> " + _g(r["threshold"]) if r["strict"] else ">= " + _g(r["threshold"])
    return f"inequality '{r['name']}' violated: value {_g(r['residual'])}, needs {rel}"


def _value_json(v: Any) -> Any:
    if isinstance(v, np.ndarray):
        return v.tolist()
    return float(v)


def _finite(v: Any) -> bool:
    return bool(np.all(np.isfinite(np.asarray(v, dtype=float))))


def _environment(problem: Problem, x: np.ndarray) -> tuple[dict, list[dict]]:
    """Environment for expression trees and the per-quantity derived report."""
    try:
        env = problem.environment(x)
        failed: dict[str, str] = {}
    except (IRError, ValueError, TypeError, ZeroDivisionError, FloatingPointError):
        # locate the failure: evaluate quantity by quantity (same order as environment())
        env = {}
        for k, v in problem.data.items():
            env[k] = np.asarray(v, dtype=float) if isinstance(v, list | np.ndarray) else float(v)
        env.update(problem.unpack(x))
        failed = {}
        for d in problem.derived:
            try:
                env[d.name] = evaluate(d.expr, env)
            except (IRError, ValueError, TypeError, ZeroDivisionError) as err:
                failed[d.name] = str(err) or type(err).__name__
    report = []
    for d in problem.derived:
        if d.name in failed:
            report.append({"name": d.name, "value": None, "ok": False, "error": failed[d.name]})
            continue
        v = env[d.name]
        ok = _finite(v)
        report.append({"name": d.name, "value": _value_json(v), "ok": ok, "error": "" if ok else "not finite"})
    return env, report


def evaluate_checks(checks: list[Check], env: dict, tol: Tolerances) -> list[dict]:
    """Evaluate theorem checks (kinds :data:`lmic.ir.problem.CHECK_KINDS`) in ``env``.

    Examples
    --------
    >>> from lmic.ir.problem import Check
    >>> c = Check("A - L C Schur", "schur_stable", {"name": "M"})
    >>> evaluate_checks([c], {"M": np.diag([0.5, 1.2])}, Tolerances())[0]["ok"]
    False
    """
    out = []
    for c in checks:
        entry: dict[str, Any] = {
            "name": c.name,
            "kind": c.kind,
            "value": None,
            "bound": c.bound,
            "ok": False,
            "error": "",
        }
        try:
            with np.errstate(all="ignore"):
                v = evaluate(c.expr, env)
            entry["value"], entry["ok"] = _judge(c, v, tol)
        except (IRError, ValueError, TypeError, ZeroDivisionError, np.linalg.LinAlgError) as err:
            entry["error"] = str(err) or type(err).__name__
        out.append(entry)
    return out


def _judge(c: Check, v: Any, tol: Tolerances) -> tuple[float, bool]:
    M = np.atleast_2d(np.asarray(v, dtype=float))
    if c.kind == "finite":
        finite = bool(np.all(np.isfinite(M)))
        return (float(np.max(np.abs(M))) if finite and M.size else (0.0 if finite else float("inf"))), finite
    if not np.all(np.isfinite(M)):
        raise ValueError("the checked quantity is not finite")
    if c.kind in ("less_than", "greater_than"):
        if M.size != 1:
            raise ValueError(f"'{c.kind}' needs a scalar, got shape {M.shape}")
        val = float(M.ravel()[0])
        bound = 0.0 if c.bound is None else float(c.bound)
        return val, (val < bound) if c.kind == "less_than" else (val > bound)
    if M.shape[0] != M.shape[1]:
        raise ValueError(f"'{c.kind}' needs a square matrix, got shape {M.shape}")
    if c.kind == "schur_stable":
        rho = float(np.max(np.abs(np.linalg.eigvals(M))))
        return rho, rho < 1.0
    if c.kind == "hurwitz":
        a = float(np.max(np.real(np.linalg.eigvals(M))))
        return a, a < 0.0
    S = 0.5 * (M + M.T)
    eig = np.linalg.eigvalsh(S)
    norm = float(np.max(np.abs(eig)))
    err = max(tol.strict_rel, 10.0 * (S.shape[0] + 2) * _U) * norm
    if c.kind == "negative_definite":
        return float(eig[-1]), bool(eig[-1] < -err)
    if c.kind == "positive_definite":
        return float(eig[0]), bool(eig[0] > err)
    if c.kind == "negative_semidefinite":
        return float(eig[-1]), bool(eig[-1] <= tol.rel * norm)
    if c.kind == "positive_semidefinite":
        return float(eig[0]), bool(eig[0] >= -tol.rel * norm)
    raise ValueError(f"unknown check kind '{c.kind}'")  # pragma: no cover - Check validates


def _check_reason(r: dict) -> str:
    if r["error"]:
        return f"check '{r['name']}' ({r['kind']}) failed: {r['error']}"
    what = {
        "schur_stable": "spectral radius {v}, needs < 1",
        "hurwitz": "spectral abscissa {v}, needs < 0",
        "negative_definite": "lambda_max {v}, needs < 0",
        "positive_definite": "lambda_min {v}, needs > 0",
        "negative_semidefinite": "lambda_max {v}, needs <= 0",
        "positive_semidefinite": "lambda_min {v}, needs >= 0",
        "less_than": "value {v}, needs < {b}",
        "greater_than": "value {v}, needs > {b}",
        "finite": "value is not finite",
    }[r["kind"]]
    b = 0.0 if r["bound"] is None else r["bound"]
    return f"check '{r['name']}' failed: " + what.format(v=_g(r["value"]), b=_g(b))


def _objective_report(problem: Problem, solution: Solution, x: np.ndarray, tol: Tolerances):
    obj = problem.objective
    if obj.sense == "feasibility":
        return None
    val = obj.value(x)
    claimed = solution.objective
    entry: dict[str, Any] = {
        "sense": obj.sense,
        "value": val,
        "claimed": claimed,
        "rel_diff": None,
        "ok": math.isfinite(val),
    }
    if claimed is not None:
        claimed = float(claimed)
        diff = abs(val - claimed) / max(1.0, abs(val), abs(claimed))
        entry.update(claimed=claimed, rel_diff=diff, ok=bool(diff <= tol.objective_rel))
    return entry


def _reasons(cert: Certificate) -> list[str]:
    """Every failed criterion, in the documented order (LMIs, rows, derived, checks, objective)."""
    reasons: list[str] = []
    failing = [r for r in cert.lmis if not r["ok"]]
    if failing:
        worst = min(failing, key=lambda r: r["rel_margin"] if math.isfinite(r["rel_margin"]) else -math.inf)
        if worst["decided_by"] == "exact":
            reasons.append(f"exact: LMI '{worst['name']}' {worst['note']}")
        else:
            reasons.append(_lmi_reason(worst, cert.objective is not None))
        if len(failing) > 1:
            reasons[-1] += f" (and {len(failing) - 1} more LMI(s))"
    reasons += [_linear_reason(r) for r in cert.linear if not r["ok"]]
    reasons += [f"derived '{r['name']}' failed: {r['error']}" for r in cert.derived if not r["ok"]]
    reasons += [_check_reason(r) for r in cert.checks if not r["ok"]]
    if cert.objective is not None and not cert.objective["ok"]:
        o = cert.objective
        reasons.append(f"objective: the solver reports {o['claimed']!r}, the point gives {o['value']!r}")
    return reasons


def _apply_exact(cert: Certificate, ex: dict[str, Any]) -> None:
    """Let the exact proof decide the LMIs and linear rows (rules of the module docstring).

    * the whole proof holds (at ``x_q``, recorded): every LMI and row is accepted, whatever its
      float margin;
    * otherwise, when ``x_q`` is the float point itself, each LMI or row proved exactly is
      accepted, and a strict LMI disproved exactly is rejected;
    * a non-strict LMI accepted by the float tolerance stays accepted even when exactly
      disproved (the tolerance is documented; the label then stays ``certified``).
    """
    whole, at_x = bool(ex["proven"]), bool(ex["at_x"])
    for r, e in zip(cert.lmis, ex.get("lmis", []), strict=True):
        r["exact"] = "proved" if e["proven"] else ("disproved" if e["disproved"] else "not proven")
        if (whole or (at_x and e["proven"])) and not r["ok"]:
            r["ok"], r["decided_by"] = True, "exact"
            what = "positive definite" if r["strict"] else "positive semidefinite"
            r["note"] = (
                f"below the float threshold (relative margin {_g(r['rel_margin'])}); {what} by the exact proof at x_q"
            )
        elif e["disproved"] and r["strict"] and r["ok"]:
            r["ok"], r["decided_by"] = False, "exact"
            r["note"] = f"is not positive definite at the solver's point ({e['detail']})"
    for r, e in zip(cert.linear, ex.get("linear", []), strict=True):
        r["exact"] = "proved" if e["proven"] else ("within tolerance" if e["within_tolerance"] else "not proven")
        if (whole or (at_x and e["proven"])) and not r["ok"]:
            r["ok"], r["decided_by"] = True, "exact"


# --------------------------------------------------------------------------------------------
# the certifier


def certify(
    problem: Problem,
    solution: Solution,
    *,
    exact: bool = False,
    tol: Tolerances | float | dict | None = None,
) -> Certificate:
    """Certify (or reject) a solver's answer from the IR alone.

    Parameters
    ----------
    problem : Problem
        The IR the answer is for.
    solution : Solution
        The backend's answer (its status and objective are claims to check).
    exact : bool
        Also prove every LMI in exact rational arithmetic (:func:`lmic.certify.exact.prove`).
    tol : Tolerances, float or dict, optional
        Tolerances (a float sets :attr:`Tolerances.rel`).

    Returns
    -------
    Certificate

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> from lmic.solution import Solution
    >>> p = Problem([Variable("p", "scalar", (1, 1))],
    ...             [LMI("1 - p >= 0", 1, sp.csc_matrix([[1., -1.]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("max", [0, 1]))
    >>> c = certify(p, Solution("optimal", x=np.array([1.0]), objective=1.0), exact=True)
    >>> c.verdict, c.objective["ok"], c.exact["proven"]
    ('certified', True, True)
    """
    t0 = time.perf_counter()
    tolr = Tolerances.coerce(tol)
    cert = Certificate(
        verdict="unverified",
        status=solution.status,
        backend=solution.backend,
        tolerances=tolr.to_dict(),
    )
    if solution.status == "infeasible":
        from lmic.certify.farkas import verify_farkas

        if solution.farkas is None:
            cert.reason = "the solver reports infeasible but gave no dual (Farkas) certificate"
        else:
            cert.farkas = verify_farkas(problem, solution.farkas, tol=tolr.farkas_rel)
            if exact:
                from lmic.certify.farkas import prove_infeasible

                cert.exact = prove_infeasible(problem, solution.farkas, cert.farkas)
            # global (exact, or homogeneous) or bounded ("no solution with ||x|| <= R"): farkas.scope
            from lmic.certify.farkas import scope

            cert.farkas["scope"] = scope(problem, cert.farkas, cert.exact)
            kind = cert.farkas["scope"]["scope"]
            if kind == "global" and cert.farkas["verified"]:
                cert.verdict = "infeasible-certified"
                cert.reason = cert.farkas["reason"]
                if cert.exact is not None:
                    cert.reason += "; exact proof: " + cert.exact["reason"]
            elif kind == "global":
                # the float tolerances failed but an exact certificate exists: a theorem
                cert.verdict = "infeasible-certified"
                cert.reason = cert.exact["reason"] + " (the float verification failed: " + cert.farkas["reason"] + ")"
            elif kind == "bounded":
                cert.verdict = "infeasible-bounded"
                cert.reason = cert.farkas["scope"]["statement"]
                if cert.exact is not None:
                    cert.reason += "; exact proof failed: " + cert.exact["reason"]
            else:
                cert.reason = "infeasibility not verified: " + (
                    cert.farkas["reason"] if not cert.farkas["verified"] else cert.farkas["scope"]["statement"]
                )
        cert.time_s = time.perf_counter() - t0
        return cert
    if solution.x is None:
        cert.reason = f"the solver reports '{solution.status}' and returned no point to check"
        if solution.message:
            cert.reason += f" ({' '.join(solution.message.split())})"
        cert.time_s = time.perf_counter() - t0
        return cert

    x = np.asarray(solution.x, dtype=float).ravel()
    if x.shape != (problem.n,):
        raise LmicError(f"the solution has {x.size} entries, the problem {problem.n} variables")
    cert.x = x.tolist()
    if not np.all(np.isfinite(x)):
        cert.verdict = "rejected"
        cert.reason = "the point has non-finite entries"
        cert.time_s = time.perf_counter() - t0
        return cert

    inaccurate = solution.status == "inaccurate"
    cert.lmis = [lmi_report(lmi, x, tolr, inaccurate=inaccurate) for lmi in problem.lmis]
    cert.linear = _linear_reports(problem, x, tolr, inaccurate)
    cert.objective = _objective_report(problem, solution, x, tolr)
    env, cert.derived = _environment(problem, x)
    cert.checks = evaluate_checks(problem.checks, env, tolr)
    strict_eigs = [r["min_eig"] for r in cert.lmis if r["strict"]]
    if solution.margin is not None or strict_eigs:
        cert.margin = {
            "strategy": solution.strategy,
            "claimed": solution.margin,
            "achieved": min(strict_eigs) if strict_eigs else None,
        }

    if exact:
        from lmic.certify.exact import prove

        cert.exact = prove(problem, x, inaccurate=inaccurate, tol=tolr, min_eigs=[r["min_eig"] for r in cert.lmis])
        _apply_exact(cert, cert.exact)
    reasons = _reasons(cert)

    if reasons:
        cert.verdict, cert.reason = "rejected", reasons[0]
    else:
        cert.verdict = "certified"
        worst = min(cert.lmis, key=lambda r: r["rel_margin"], default=None)
        cert.reason = "every constraint and check holds"
        if worst is not None:
            cert.reason += (
                f"; smallest margin {_g(worst['min_eig'])} (relative {_g(worst['rel_margin'])}) on '{worst['name']}'"
            )
        if inaccurate:
            cert.reason += " (despite the solver's 'inaccurate' status)"
        if cert.exact is not None:
            rescued = [r["name"] for r in cert.lmis + cert.linear if r["decided_by"] == "exact"]
            if cert.exact["proven"]:
                cert.reason += "; exact proof: " + cert.exact["statement"]
            else:
                cert.reason += "; exact proof: " + cert.exact["reason"]
            if rescued:
                cert.reason += f"; below the float threshold but proved exactly: {', '.join(repr(n) for n in rescued)}"
    cert.time_s = time.perf_counter() - t0
    return cert
