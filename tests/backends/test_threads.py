"""BLAS threads during a solve (lmic.backends.threads): one thread inside CVXOPT's structured KKT
solver, the caller's setting restored afterwards."""

from __future__ import annotations

import numpy as np
import pytest

threadpoolctl = pytest.importorskip("threadpoolctl")

from lmic.backends.threads import blas_threads  # noqa: E402


def _blas_threads() -> list[int]:
    return [int(d["num_threads"]) for d in threadpoolctl.threadpool_info() if d.get("user_api") == "blas"]


def test_blas_threads_limits_every_blas_library_and_restores_them():
    np.dot(np.ones(2), np.ones(2))  # numpy's BLAS loaded
    # the test session runs on one BLAS thread (conftest.py): a caller's two threads first
    with threadpoolctl.threadpool_limits(limits=2, user_api="blas"):
        before = _blas_threads()
        assert before and max(before) == 2
        with blas_threads(1):
            assert max(_blas_threads()) == 1
        assert _blas_threads() == before


def test_the_structured_cvxopt_solve_runs_on_one_blas_thread(monkeypatch):
    """The bounded-real lemma at 24 states (a random stable system) takes the structured KKT
    solver, and every factorisation sees one BLAS thread."""
    from lmic.backends import cvxopt_kkt
    from lmic.backends.cvxopt import CVXOPTBackend
    from lmic.options import SolveOptions
    from lmic.testing.conformance import bounded_real_problem

    n = 24
    rng = np.random.default_rng(0)
    A = rng.standard_normal((n, n))
    A -= (max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)
    p = bounded_real_problem(A, rng.standard_normal((n, 2)), rng.standard_normal((2, n)))
    assert cvxopt_kkt.worth_it(p)
    seen: list[int] = []
    real = cvxopt_kkt.StructuredKKT.__call__

    def spy(self, W):
        seen.append(max(_blas_threads()))
        return real(self, W)

    monkeypatch.setattr(cvxopt_kkt.StructuredKKT, "__call__", spy)
    be = CVXOPTBackend()
    with threadpoolctl.threadpool_limits(limits=2, user_api="blas"):  # a caller's two threads
        r = be.call(p, be.settings(SolveOptions()))
    assert r.native == "optimal" and r.info["kktsolver"] == "structured"
    assert seen and set(seen) == {1}
