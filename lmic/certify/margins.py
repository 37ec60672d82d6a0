"""The float rules of the certifier for LMIs and linear rows: margins relative to the term scale.

:func:`lmi_report` evaluates one LMI ``F(x)`` at a point and judges it (strict, non-strict, or
non-strict after an ``inaccurate`` solver status); :func:`linear_reports` does the same for the
linear rows. The rules and their thresholds are those of :mod:`lmic.certify.check` (whose
docstring explains the term scale). Split out of :mod:`lmic.certify.check`, which re-exports
:func:`lmi_report`.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI
>>> lmi_report(LMI("p > 0", 1, sp.csc_matrix([[0., 1.]])), np.array([-1.0]), Tolerances())["ok"]
False
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from lmic.certify.result import Tolerances
from lmic.certify.spectra import block_spectrum, prepared, term_scale
from lmic.ir.problem import LMI, Problem

__all__ = ["lmi_report", "linear_reports", "lmi_reason", "linear_reason", "UNIT_ROUNDOFF"]

#: unit round-off of float64
UNIT_ROUNDOFF = float(np.finfo(float).eps) / 2.0
_U = UNIT_ROUNDOFF  # the float error bounds below read it (tests patch it)


def _g(v: float) -> str:
    return f"{v:.3g}"


def _spectral_norm_nonneg(M: np.ndarray) -> float:
    """Spectral norm of a symmetric entrywise non-negative matrix (its Perron root)."""
    if M.size == 0:
        return 0.0
    if M.shape[0] == 1:
        return float(M[0, 0])
    return float(max(np.linalg.eigvalsh(M)[-1], 0.0))


def _below_coefficient_scale(T: float, lmi: LMI, zero_rel: float) -> bool:
    """``T <= zero_rel * ||sum_i |C_i|||`` (the point is ~0 for this LMI); the coefficient
    scale is only computed when its cheap upper bound (the largest row sum) allows it."""
    rows, M = prepared(lmi).coefficient_scale
    if T > zero_rel * rows:
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
    d = lmi.dim
    F, eig = block_spectrum(lmi, x)  # one eigen-decomposition per block and point (shared)
    T = term_scale(lmi, x)  # kept with the spectrum
    k = prepared(lmi).k  # per LMI, not per point
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
    zero = T == 0.0 or _below_coefficient_scale(T, lmi, tol.zero_rel)
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
        note = ""
    # a non-strict LMI is proved positive semidefinite in float only when lambda_min exceeds its
    # error bound; between the tolerance and that bound it holds within tolerance, not proved
    within = bool(ok and not lmi.strict and lmin < err_rel * T)
    if within:
        note = (note + "; " if note else "") + "holds within tolerance, not proved"
    out.update(threshold=thr, ok=bool(ok), note=note, within_tolerance=within)
    return _decided_by_float(out)


def _decided_by_float(entry: dict[str, Any]) -> dict[str, Any]:
    """Record the float decision (``float_ok``); the exact proof may decide later."""
    entry.update(float_ok=bool(entry["ok"]), exact=None, decided_by="float")
    return entry


def _only_within_tolerance(r: dict) -> bool:
    """Rejected only because it holds within the tolerance and nothing proved it
    (:func:`lmic.certify.check.certify`)."""
    return bool(r.get("within_tolerance")) and not r["ok"] and r["decided_by"] == "float"


def lmi_reason(r: dict, optimisation: bool = False) -> str:
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
    if _only_within_tolerance(r):
        return (
            f"LMI '{r['name']}' holds only within the tolerance: lambda_min = {_g(r['min_eig'])} (relative "
            f"{_g(r['rel_margin'])}) is not above its float error bound {_g(r['float_err'])}, so the point is not "
            "proved positive semidefinite" + (" and the exact proof failed" if r.get("exact") else "")
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


def linear_reports(problem: Problem, x: np.ndarray, tol: Tolerances, inaccurate: bool) -> list:
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
            within = bool(ok)  # a float residual never proves an equality: only the exact proof does
        elif strict:
            thr = max(tol.strict_rel * s, err)
            ok = r > thr and s > 0
            within = False
        else:
            thr = -allowed
            ok = r >= thr
            within = bool(ok and r < err)  # not above its rounding error: holds within tolerance
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
                "within_tolerance": bool(within and math.isfinite(r)),
            }
        )
        _decided_by_float(out[-1])
    return out


def linear_reason(r: dict) -> str:
    if _only_within_tolerance(r):
        what = "equality" if r["kind"] == "eq" else "inequality"
        return (
            f"{what} '{r['name']}' holds only within the tolerance: value {_g(r['residual'])} "
            f"(allowed {_g(abs(r['threshold']))}) is not proved {'zero' if r['kind'] == 'eq' else 'non-negative'}"
        )
    if r["kind"] == "eq":
        res, allowed = _g(r["residual"]), _g(r["threshold"])
        return f"equality '{r['name']}' violated: residual {res} (allowed {allowed})"
    rel = "> " + _g(r["threshold"]) if r["strict"] else ">= " + _g(r["threshold"])
    return f"inequality '{r['name']}' violated: value {_g(r['residual'])}, needs {rel}"
