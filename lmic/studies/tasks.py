"""Run one job in this process through lmic's public API; map what it found to a verdict.

:func:`run_job` takes the JSON form of a :class:`~lmic.studies.spec.Job` and returns a JSON-able
record. It calls :func:`lmic.api.solve`, :func:`lmic.crosscheck.crosscheck`,
:func:`lmic.studies.sweep.maximize`, :func:`lmic.published.audit_published` or
:func:`lmic.certify.audit_certificate`; those cache a theorem's analysed plan per process
(:func:`lmic.compile.plan_for`), so a worker analyses each theorem once and re-binds the
numbers of every later job. :func:`outcome` is the one place where results become the verdict
names of a study (``OUTCOMES``).

Examples
--------
>>> rec = run_job({"hash": "h", "task": "solve", "theorem": "thesis.lyapunov",
...                "system": {"data": {"A": [[-1.0, 0.0], [0.0, -2.0]]}}, "params": {},
...                "backend": "clarabel"})
>>> rec["outcome"], rec["status"]
('certified', 'feasible')
"""

from __future__ import annotations

import os
import socket
import time
import traceback
from typing import Any

__all__ = ["OUTCOMES", "outcome", "run_job", "run_reproduce_file", "run_crosscheck_backend"]

#: the outcomes a study counts, in display order (HELPERS vocabulary plus ``error``)
OUTCOMES = (
    "certified",
    "infeasible-certified",
    "infeasible-bounded",
    "unbounded-certified",
    "rejected",
    "undecided",
    "error",
)

_PASS = {"certified", "infeasible-certified", "infeasible-bounded", "unbounded-certified", "rejected", "undecided"}


def outcome(kind: str, obj: Any) -> str:
    """The study verdict of one task's result (swap this for ``lmic.outcome`` when it lands).

    Parameters
    ----------
    kind : {"solve", "crosscheck", "maximize", "audit-published", "audit"}
    obj : Result, CrosscheckReport, SupResult, AuditReport or AuditResult

    Returns
    -------
    str
        One of :data:`OUTCOMES` (never ``error``: that is a job that raised).

    Examples
    --------
    >>> from lmic.certify.certificate import AuditResult
    >>> outcome("audit", AuditResult(ok=False, verdict="rejected", recorded_verdict="certified"))
    'rejected'
    """
    if kind == "solve":
        verdict = obj.verdict
        if verdict == "certified":
            return "certified" if obj.exit_code() == 0 else "undecided"
        return verdict if verdict in _PASS else "undecided"
    if kind == "crosscheck":
        verdicts = {r["verdict"] for r in obj.results}
        if "rejected" in verdicts:
            return "rejected"
        if obj.agree and verdicts == {"certified"} and obj.exit_code() == 0:
            return "certified"
        if obj.agree and verdicts <= {"infeasible-certified", "infeasible-bounded"}:
            # one global proof suffices; rays that only bound it (scale-free: the relative margin)
            return "infeasible-certified" if "infeasible-certified" in verdicts else "infeasible-bounded"
        if obj.agree and verdicts == {"unbounded-certified"}:
            return "unbounded-certified"
        return "undecided"
    if kind == "maximize":
        if obj.lower is not None:
            return "certified"
        proofs = {p.proof for p in obj.points}
        if obj.points and proofs == {"infeasible-certified"}:
            return "infeasible-certified"
        return "undecided"
    if kind == "audit-published":
        code = obj.exit_code()
        if code == 0:
            return "certified"
        findings = {c.finding for c in obj.claims if c.decisive}
        if "rejected" in findings:
            return "rejected"
        if code == 3:
            return "infeasible-certified"
        return "undecided"
    if kind == "audit":
        if not obj.ok:
            return "rejected"
        return obj.verdict if obj.verdict in _PASS else "undecided"
    raise ValueError(f"unknown task {kind!r}")


def _options(time_limit: float | None) -> Any:
    from lmic.backends.base import SolveOptions

    opts = SolveOptions()
    if time_limit is not None:
        opts.time_limit = float(time_limit)
    return opts


def _finite(v: Any) -> Any:
    import math

    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


def _solve(job: dict[str, Any], sysobj: Any, opts: Any) -> dict[str, Any]:
    from lmic.api import solve

    res = solve(
        job["theorem"],
        sysobj,
        params=job["params"] or None,
        backend=job.get("backend"),
        options=opts,
        exact=bool(job.get("exact")),
    )
    rec: dict[str, Any] = {
        "outcome": outcome("solve", res),
        "status": res.status,
        "verdict": res.verdict,
        "backend_used": res.backend,
        "objective": _finite(res.objective),
        "min_margin": _finite(res.min_margin),
        "message": " ".join(str(res.solution.message or "").split())[:300],
        "timings": res.timings,
        "derived": {k: v for k, v in (res.derived or {}).items() if isinstance(v, int | float)},
    }
    if res.certificate is not None:
        from lmic.certify.certificate import certificate_document

        rec["_certificate"] = certificate_document(
            res.problem, res.solution, res.certificate, system=sysobj, embed_ir=True
        )
    return rec


def _crosscheck(job: dict[str, Any], sysobj: Any, opts: Any) -> dict[str, Any]:
    from lmic.studies.crosscheck import crosscheck

    rep = crosscheck(job["theorem"], sysobj, params=job["params"] or None, backends=job.get("backends"), options=opts)
    return {
        "outcome": outcome("crosscheck", rep),
        "status": "agree" if rep.agree else "disagree",
        "verdict": ",".join(sorted({r["verdict"] for r in rep.results})),
        "objective": None,
        "message": "; ".join(f"{r['backend']}: {r['status']}/{r['verdict']}" for r in rep.results),
        "rows": rep.results,
        "max_rel_objective_gap": rep.max_rel_objective_gap,
    }


def _maximize(job: dict[str, Any], sysobj: Any, opts: Any) -> dict[str, Any]:
    from lmic.studies.sweep import maximize

    m = dict(job["maximize"])
    kwargs = {k: m[k] for k in ("lo", "hi", "xtol", "rtol", "max_evals") if m.get(k) is not None}
    if job.get("backend"):  # else the API's own default (its decision policy)
        kwargs["backend"] = job["backend"]
    sup = maximize(
        job["theorem"],
        sysobj,
        m["param"],
        params=job["params"] or None,
        options=opts,
        exact=True,
        **kwargs,
    )
    return {
        "outcome": outcome("maximize", sup),
        "status": "converged" if sup.converged else "not converged",
        "verdict": sup.upper_kind,
        "objective": sup.lower,
        "sup_lower": sup.lower,
        "sup_upper": _finite(sup.upper),
        "sup_upper_kind": sup.upper_kind,
        "evaluations": len(sup.points),
        "message": sup.message,
    }


def _audit_published(job: dict[str, Any], sysobj: Any, opts: Any) -> dict[str, Any]:
    from lmic.studies.published import audit_published

    kwargs = {"backend": job["backend"]} if job.get("backend") else {}  # else the API's own default
    rep = audit_published(job["theorem"], sysobj, params=job["params"] or None, options=opts, **kwargs)
    return {
        "outcome": outcome("audit-published", rep),
        "status": f"exit {rep.exit_code()}",
        "verdict": ",".join(sorted({c.finding for c in rep.claims})),
        "objective": None,
        "message": "; ".join(f"{'/'.join(c.keys)}: {c.finding}" for c in rep.claims)[:500],
    }


def _audit(job: dict[str, Any]) -> dict[str, Any]:
    from lmic.certify.certificate import audit_certificate

    res = audit_certificate(job["certificate_file"], exact=bool(job.get("exact")))
    return {
        "outcome": outcome("audit", res),
        "status": "consistent" if res.ok else f"differs at {res.field}",
        "verdict": res.verdict,
        "objective": None,
        "message": " ".join(res.message.split())[:300],
    }


def run_reproduce_file(job: dict[str, Any]) -> dict[str, Any]:
    """The worker side: reproduce one example file; rows as JSON (``RowResult.to_dict``)."""
    from lmic.studies.reproduce import reproduce

    options = None
    if job.get("options"):
        from lmic.backends.base import SolveOptions

        options = SolveOptions()
        for key, value in job["options"].items():
            setattr(options, key, value)
    kwargs = {"backend": job["backend"]} if job.get("backend") else {}  # else reproduce's own default
    rep = reproduce(job["examples"], job["expectations"], only=[job["file"]], options=options, **kwargs)
    return {
        "backend": rep.backend,
        "outcome": "certified" if rep.exit_code() == 0 else "undecided",
        "rows": [r.to_dict() for r in rep.results],
        "file_times": rep.file_times,
        "status": f"exit {rep.exit_code()}",
        "message": "",
    }


def run_crosscheck_backend(job: dict[str, Any]) -> dict[str, Any]:
    """The worker side of ``lmic crosscheck --executor``: one backend's row (``lmic.crosscheck.backend_row``).

    The job names the target (theorem id or IR/SDPA file), the system (file or dict), the parameters,
    the backend and the ``SolveOptions`` fields; the problem is loaded here as the sequential
    command loads it, so the row is the one the sequential run gets.

    >>> rec = run_crosscheck_backend({"target": "thesis.lyapunov", "system": {"data": {"A": [[-2.0]]}},
    ...                               "params": {}, "backend": "clarabel", "options": {}})
    >>> rec["outcome"], rec["row"]["decision"]
    ('certified', 'certified')
    """
    from lmic.api import load_target
    from lmic.options import SolveOptions
    from lmic.studies.crosscheck import backend_row

    options = SolveOptions()
    for key, value in (job.get("options") or {}).items():
        setattr(options, key, value)
    problem, _theorem, _ = load_target(job["target"], job.get("system"), job.get("params") or None)
    row, _res = backend_row(problem, job["backend"], options)
    return {
        "outcome": row["decision"],
        "status": row["status"],
        "verdict": row["verdict"],
        "objective": row["objective"],
        "message": row["message"] or "",
        "row": row,
    }


def run_job(job: dict[str, Any], time_limit: float | None = None) -> dict[str, Any]:
    """Run one job; never raises (a job that raises is an ``error`` record with its message).

    Parameters
    ----------
    job : dict
        :meth:`lmic.studies.spec.Job.to_dict`.
    time_limit : float, optional
        Passed to the solver as ``SolveOptions.time_limit`` (the executor enforces the job's
        own limit by stopping the worker).

    Returns
    -------
    dict
        ``hash, outcome, status, verdict, objective, message, time_s, worker`` and task-specific
        fields; ``_certificate`` holds a certificate document for the driver to write.
    """
    from lmic.errors import LmicError

    t0 = time.perf_counter()
    worker = f"{socket.gethostname()}:{os.getpid()}"
    task = job["task"]
    try:
        opts = _options(time_limit)
        if task == "audit":
            rec = _audit(job)
        elif task == "reproduce-file":
            rec = run_reproduce_file(job)
        elif task == "crosscheck-backend":
            rec = run_crosscheck_backend(job)
        else:
            from lmic.system import load_system

            sysobj = load_system(job["system"], job.get("system_label"))
            run = {
                "solve": _solve,
                "crosscheck": _crosscheck,
                "maximize": _maximize,
                "audit-published": _audit_published,
            }[task]
            rec = run(job, sysobj, opts)
    except LmicError as err:
        rec = {
            "outcome": "error",
            "status": "error",
            "verdict": None,
            "objective": None,
            "message": f"{type(err).__name__}: {' '.join(str(err).split())}"[:500],
        }
    except Exception as err:  # noqa: BLE001 - a crashing job is recorded, not fatal for the study
        tb = traceback.extract_tb(err.__traceback__)
        where = f" at {os.path.basename(tb[-1].filename)}:{tb[-1].lineno}" if tb else ""
        rec = {
            "outcome": "error",
            "status": "error",
            "verdict": None,
            "objective": None,
            "message": f"{type(err).__name__}: {' '.join(str(err).split())}{where}"[:500],
        }
    rec["hash"] = job["hash"]
    rec["time_s"] = time.perf_counter() - t0
    rec["worker"] = worker
    return rec
