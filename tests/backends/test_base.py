"""The shared backend machinery: conic data, crash and time-out handling, status mapping."""

from __future__ import annotations

import time

import numpy as np
import pytest
import scipy.sparse as sp

from lmic.backends.base import Backend, SolveOptions, conic_data, full_vec_map, problem_kinds
from lmic.backends.clarabel import clarabel_unvec, clarabel_vec
from lmic.backends.scs import scs_unvec, scs_vec
from lmic.ir.problem import LinearConstraints, Objective, Problem, Variable
from lmic.ir.svec import tril_vec
from lmic.solution import Solution
from lmic.testing.conformance import CASES, dense_lmi


class _Crash(Backend):
    name = "crash"
    STATUS_MAP = {"done": "optimal"}

    def _solve(self, problem, options):
        raise RuntimeError("segment the fault")


class _Sleepy(Backend):
    name = "sleepy"
    STATUS_MAP = {"done": "optimal"}

    def _solve(self, problem, options):
        time.sleep(30)
        return Solution("optimal", x=np.zeros(problem.n))


class _Weird(Backend):
    name = "weird"
    STATUS_MAP = {"done": "optimal"}

    def _solve(self, problem, options):
        return Solution(self.map_status("SOMETHING_NEW"), native_status="SOMETHING_NEW")


def test_crash_is_an_error_status_not_a_traceback():
    sol = _Crash().solve(CASES["max_sense"].build())
    assert sol.status == "error" and "RuntimeError: segment the fault" in sol.message


def test_time_limit_without_native_support_stops_the_child():
    t0 = time.perf_counter()
    sol = _Sleepy().solve(CASES["max_sense"].build(), SolveOptions(time_limit=0.5))
    assert time.perf_counter() - t0 < 10
    assert sol.status == "error" and "time limit" in sol.message


def test_unknown_native_status_is_error():
    sol = _Weird().solve(CASES["max_sense"].build())
    assert sol.status == "error"


def test_supports_explains_missing_capability():
    class _LmiOnly(_Crash):
        capabilities = frozenset({"lmi"})

    prob = CASES["linear_equalities"].build()
    assert problem_kinds(prob) == {"lmi", "eq"}
    ok, why = _LmiOnly().supports(prob, explain=True)
    assert not ok and "cannot take eq constraints" in why


@pytest.mark.parametrize("vec,unvec", [(clarabel_vec, clarabel_unvec), (scs_vec, scs_unvec)])
def test_psd_vectorisations_are_isometric_and_invertible(vec, unvec):
    rng = np.random.default_rng(1)
    d = 4
    A, B = rng.standard_normal((d, d)), rng.standard_normal((d, d))
    A, B = A + A.T, B + B.T
    perm, scale = vec(d)
    va, vb = scale * tril_vec(A)[perm], scale * tril_vec(B)[perm]
    assert np.isclose(va @ vb, np.trace(A @ B))
    assert np.allclose(unvec(va, d), A)


def test_clarabel_order_is_upper_triangle_by_columns():
    M = np.arange(9.0).reshape(3, 3)
    M = M + M.T
    perm, scale = clarabel_vec(3)
    v = tril_vec(M)[perm]
    assert np.allclose(v, [M[0, 0], M[0, 1], M[1, 1], M[0, 2], M[1, 2], M[2, 2]])


def test_conic_data_stacks_rows_then_lmis():
    prob = CASES["linear_equalities"].build()
    data = conic_data(prob, scs_vec)
    assert (data.n_eq, data.n_ge, data.psd) == (1, 0, [3])
    x = np.random.default_rng(0).standard_normal(prob.n)
    s = data.b - data.A @ x
    assert np.isclose(s[0], prob.linear.residuals(x)[0])
    assert np.allclose(scs_unvec(s[1:], 3), prob.lmis[0].matrix(x))


def test_full_vec_map_expands_symmetric_storage():
    M = np.array([[1.0, 2.0], [2.0, 5.0]])
    assert np.allclose(full_vec_map(2) @ tril_vec(M), M.reshape(-1, order="F"))


def test_max_objective_is_minimised_with_sign():
    t = Variable("t", "scalar", (1, 1))
    lmi = dense_lmi("1 - t >= 0", np.eye(1), [-np.eye(1)], False)
    prob = Problem([t], [lmi], LinearConstraints.empty(1), Objective("max", np.array([0.5, 2.0])))
    data = conic_data(prob, scs_vec)
    assert data.sign == -1.0 and np.allclose(data.c, [-2.0]) and data.c0 == -0.5
    assert isinstance(data.A, sp.csc_matrix)
