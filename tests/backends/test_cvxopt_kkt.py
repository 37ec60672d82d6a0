"""The structured KKT solver for CVXOPT (:mod:`lmic.backends.cvxopt_kkt`).

The Schur complement is checked against ``tr(F_i Q F_j Q)`` computed entry by entry, the KKT
solve against CVXOPT's own ``misc.kkt_chol`` for the same scaling (built by CVXOPT's
``misc.compute_scaling`` from random interior points), and whole solves through the certifier,
against the H-infinity norm of a Hamiltonian bisection (no LMI solver).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from certify_helpers import hinf_norm, stable_system

cvxopt = pytest.importorskip("cvxopt")
from cvxopt import misc  # noqa: E402

import lmic.backends.cvxopt as cvxopt_backend  # noqa: E402
import lmic.backends.cvxopt_kkt as kkt_module  # noqa: E402
from lmic.backends.cvxopt_kkt import StructuredKKT, cover_sizes, structured_cost  # noqa: E402
from lmic.backends.lowering import LMIForm  # noqa: E402


def vec(F: np.ndarray) -> np.ndarray:
    return F.ravel(order="F")


def lyapunov_columns(A: np.ndarray, extra: int, rng: np.random.Generator) -> tuple[sp.csc_matrix, int]:
    """Columns ``vec([[A'E + E A, E B], [B'E, 0]])`` for every symmetric unit ``E``, one dense
    symmetric column and one ``-I`` on the last ``extra`` rows (``gamma I``): crosses, a wide
    dense variable and a narrow diagonal."""
    n = len(A)
    d = n + extra
    B = rng.standard_normal((n, extra))
    cols = []
    for a in range(n):
        for b in range(a + 1):
            E = np.zeros((n, n))
            E[a, b] = E[b, a] = 1.0
            F = np.zeros((d, d))
            F[:n, :n] = A.T @ E + E @ A
            F[:n, n:] = E @ B
            F[n:, :n] = B.T @ E
            cols.append(vec(F))
    M = rng.standard_normal((d, d))
    cols.append(vec(M + M.T))
    F = np.zeros((d, d))
    F[n:, n:] = -np.eye(extra)
    cols.append(vec(F))
    return sp.csc_matrix(np.array(cols).T), d


def sym_from_lower(v: np.ndarray, d: int) -> np.ndarray:
    M = v.reshape(d, d, order="F")
    return np.tril(M) + np.tril(M, -1).T


def schur_reference(G: sp.spmatrix, d: int, Q: np.ndarray) -> np.ndarray:
    Fs = [sym_from_lower(c, d) for c in G.toarray().T]
    return np.array([[np.trace(Fi @ Q @ Fj @ Q) for Fj in Fs] for Fi in Fs])


def test_a_cross_has_a_cover_of_one_row_and_a_dense_matrix_is_wide():
    d = 5
    cross = np.zeros((d, d))
    cross[2, :] = cross[:, 2] = 1.0
    dense = np.ones((d, d))
    cover, size = cover_sizes(sp.csc_matrix(np.array([vec(cross), vec(dense)]).T), d, 2)
    assert cover[0].nonzero()[0].tolist() == [2]
    assert size.tolist() == [1, d]  # a full graph needs every row but one; greedy takes d


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_schur_complement_is_tr_Fi_Q_Fj_Q(seed):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((6, 6))
    G1, d1 = lyapunov_columns(A, 3, rng)
    n = G1.shape[1]
    # a second block: a random sparse symmetric coefficient per variable (various covers)
    d2 = 7
    cols = []
    for _ in range(n):
        M = sp.random(d2, d2, density=rng.uniform(0.02, 0.3), random_state=rng).toarray()
        cols.append(vec(M + M.T))
    G2 = sp.csc_matrix(np.array(cols).T)
    _, _, blocks = structured_cost([G1, G2], [d1, d2], n)
    assert blocks[0].s >= 1 and len(blocks[0].wide) >= 1  # both kinds are exercised
    kkt = StructuredKKT([G1, G2], sp.csc_matrix((0, n)), sp.csc_matrix((0, n)), [d1, d2], blocks)
    H = np.zeros((n, n))
    Qs = []
    for b, d in zip(kkt.blocks, [d1, d2], strict=True):
        L = rng.standard_normal((d, d)) + 2 * np.eye(d)  # CVXOPT's rti: Q = L L'
        Qs.append(L @ L.T)
        b.schur(b.scaled(L), H)
    ref = schur_reference(G1, d1, Qs[0]) + schur_reference(G2, d2, Qs[1])
    np.testing.assert_allclose(H, ref, rtol=1e-11, atol=1e-11 * np.abs(ref).max())


def random_scaling(dims: dict, rng: np.random.Generator):
    """CVXOPT's Nesterov-Todd scaling of random interior points ``s`` and ``z``."""
    parts_s, parts_z = [], []
    for _ in range(2):
        vals = [rng.uniform(0.5, 2.0, dims["l"])]
        for d in dims["s"]:
            M = rng.standard_normal((d, d))
            vals.append(vec(M @ M.T + 0.5 * np.eye(d)))
        (parts_s if not parts_s else parts_z).append(np.concatenate(vals))
    s, z = cvxopt.matrix(parts_s[0]), cvxopt.matrix(parts_z[0])
    lmbda = cvxopt.matrix(0.0, (dims["l"] + sum(dims["s"]), 1))
    return misc.compute_scaling(s, z, lmbda, dims)


@pytest.mark.parametrize("with_rows", [False, True])
def test_the_kkt_solve_matches_cvxopts_own_solver(with_rows):
    rng = np.random.default_rng(5)
    A = rng.standard_normal((4, 4))
    Gs, d = lyapunov_columns(A, 2, rng)
    n = Gs.shape[1]
    ml, p = (3, 2) if with_rows else (0, 0)
    Gl = sp.csc_matrix(rng.standard_normal((ml, n)))
    Aeq = sp.csc_matrix(rng.standard_normal((p, n)))
    dims = {"l": ml, "q": [], "s": [d]}
    W = random_scaling(dims, rng)
    ours = StructuredKKT([Gs], Gl, Aeq, [d])(W)
    G_dense = cvxopt.matrix(np.vstack([Gl.toarray(), Gs.toarray()]))
    theirs = misc.kkt_chol(G_dense, dims, cvxopt.matrix(Aeq.toarray() if p else np.zeros((0, n))))(W)
    bx, by = rng.standard_normal(n), rng.standard_normal(p)
    S = rng.standard_normal((d, d))
    bz = np.concatenate([rng.standard_normal(ml), vec(S + S.T)])
    out = []
    for f in (ours, theirs):
        y = cvxopt.matrix(by.copy()) if p else cvxopt.matrix(0.0, (0, 1))
        x, z = cvxopt.matrix(bx.copy()), cvxopt.matrix(bz.copy())
        f(x, y, z)
        zs = np.array(z).ravel()
        out.append((np.array(x).ravel(), np.array(y).ravel(), zs[:ml], sym_from_lower(zs[ml:], d)))
    for mine, ref in zip(out[0], out[1], strict=True):
        np.testing.assert_allclose(mine, ref, rtol=1e-7, atol=1e-9 * max(1.0, np.abs(ref).max(initial=0.0)))


def brl_system(n, seed):
    A, B, C = stable_system(n, seed, margin=1.0)
    return A, B, C, {"lmic": 1, "data": {"A": A.tolist(), "B": B.tolist(), "C": C.tolist()}}


@pytest.fixture
def small_problems_too(monkeypatch):
    """The structured solver on problems below its work threshold (kept small for speed)."""
    monkeypatch.setattr(kkt_module, "STRUCTURED_MIN_WORK", 0.0)


def test_small_problems_keep_cvxopts_own_solver():
    from lmic.api import load_target, solve_problem

    problem = load_target("tutorial.bounded_real", brl_system(8, 0)[3])[0]
    assert not kkt_module.worth_it(problem)  # 'chol''s estimate is below STRUCTURED_MIN_WORK
    assert kkt_module.analyse(problem)[1] < kkt_module.STRUCTURED_MIN_WORK
    assert solve_problem(problem, "cvxopt").info["kktsolver"] in ("chol", "qr")


@pytest.mark.parametrize("seed", [0, 1])
def test_cvxopt_with_the_structured_solver_reaches_the_hinf_norm(seed, small_problems_too):
    from lmic.api import load_target, solve_problem
    from lmic.certify import certify

    A, B, C, system = brl_system(12, seed)
    problem = load_target("tutorial.bounded_real", system)[0]
    solution = solve_problem(problem, "cvxopt")
    assert solution.info["kktsolver"] == "structured"
    assert solution.status == "optimal"
    certificate = certify(problem, solution)
    assert certificate.verdict == "certified"
    lo, hi = hinf_norm(A, B, C)
    gamma = solution.objective
    assert lo * (1 - 1e-9) <= gamma <= hi * (1 + 1e-6)


def test_a_failed_cholesky_hands_over_to_cvxopts_qr_solver(monkeypatch, small_problems_too):
    """After the structured factorisation fails (forced from the 6th), CVXOPT's QR solver
    finishes the same run: the answer is still the norm, and the hand-over is recorded."""
    from lmic.api import load_target, solve_problem
    from lmic.certify import certify

    A, B, C, system = brl_system(8, 3)
    problem = load_target("tutorial.bounded_real", system)[0]
    made: list[StructuredKKT] = []
    real_cholesky = kkt_module._cholesky
    calls = {"n": 0}

    def failing(K):
        calls["n"] += 1
        if calls["n"] > 5:
            raise ArithmeticError("forced")
        return real_cholesky(K)

    real_factory = cvxopt_backend._structured_kkt

    def recording(data, prob):
        kkt = real_factory(data, prob)
        made.append(kkt)
        return kkt

    monkeypatch.setattr(kkt_module, "_cholesky", failing)
    monkeypatch.setattr(cvxopt_backend, "_structured_kkt", recording)
    solution = solve_problem(problem, "cvxopt")
    assert made and made[0] is not None and made[0].fallback_from == 5
    assert solution.info["kktsolver"] == "structured" and solution.status == "optimal"
    assert certify(problem, solution).verdict == "certified"
    lo, hi = hinf_norm(A, B, C)
    assert lo * (1 - 1e-9) <= solution.objective <= hi * (1 + 1e-6)


def test_dense_coefficients_keep_cvxopts_own_solver():
    """Every coefficient dense (no cross structure): the estimate says no, 'chol' solves."""
    from lmic.ir.problem import LinearConstraints, Objective, Problem, Variable
    from lmic.testing.conformance import dense_lmi

    rng = np.random.default_rng(0)
    d, n = 6, 5
    Fs = []
    for _ in range(n):
        M = rng.standard_normal((d, d))
        Fs.append(M + M.T)
    lmi = dense_lmi("dense", np.eye(d), Fs, strict=True)  # x = 0 is strictly feasible
    problem = Problem(
        [Variable(f"x{i}", "scalar", (1, 1), offset=i) for i in range(n)],
        [lmi],
        LinearConstraints.empty(n),
        Objective("min", np.concatenate([[0.0], rng.standard_normal(n)])),
    )
    data = LMIForm.apply(problem)
    assert cvxopt_backend._structured_kkt(data, problem) is None
    # the entry count alone rules it out: no cover is searched
    ours, theirs, blocks = structured_cost([-g for g in data.G], data.dims, problem.n)
    assert ours == float("inf") and theirs > 0 and blocks == []


def test_an_inaccurate_solve_hands_over_to_cvxopts_qr_solver(monkeypatch, small_problems_too):
    """A refined solve whose residual stays above INACCURATE (forced: 0) hands the next
    factorisations to CVXOPT's QR solver; the run still reaches the norm, certified."""
    from lmic.api import load_target, solve_problem
    from lmic.certify import certify

    A, B, C, system = brl_system(10, 4)
    problem = load_target("tutorial.bounded_real", system)[0]
    made: list[StructuredKKT] = []
    real_factory = cvxopt_backend._structured_kkt

    def recording(data, prob):
        kkt = real_factory(data, prob)
        made.append(kkt)
        return kkt

    monkeypatch.setattr(kkt_module, "INACCURATE", 0.0)
    monkeypatch.setattr(cvxopt_backend, "_structured_kkt", recording)
    solution = solve_problem(problem, "cvxopt")
    assert made and made[0] is not None and made[0].fallback_from == 1  # after the first factorisation
    assert solution.status == "optimal" and certify(problem, solution).verdict == "certified"
    lo, hi = hinf_norm(A, B, C)
    assert lo * (1 - 1e-9) <= solution.objective <= hi * (1 + 1e-6)


def test_refinement_makes_the_solve_exact_for_the_true_operator(small_problems_too):
    """With the formed Schur complement perturbed (a wrong H), the refined solve still solves
    the KKT system of the true operator: it matches CVXOPT's own solver."""
    rng = np.random.default_rng(7)
    A = rng.standard_normal((4, 4))
    Gs, d = lyapunov_columns(A, 2, rng)
    n = Gs.shape[1]
    dims = {"l": 0, "q": [], "s": [d]}
    W = random_scaling(dims, rng)
    kkt = StructuredKKT([Gs], sp.csc_matrix((0, n)), sp.csc_matrix((0, n)), [d])
    real_schur = kkt.blocks[0].schur

    def perturbed(sc, H, work=None):
        real_schur(sc, H, work)
        H *= 1.0 + 1e-4  # a relative error far above rounding
        H[np.diag_indices_from(H)] *= 1.0 + 1e-4

    kkt.blocks[0].schur = perturbed
    ours = kkt(W)
    theirs = misc.kkt_chol(cvxopt.matrix(Gs.toarray()), dims, cvxopt.matrix(np.zeros((0, n))))(W)
    bx = rng.standard_normal(n)
    S = rng.standard_normal((d, d))
    bz = vec(S + S.T)
    out = []
    for f in (ours, theirs):
        x, y, z = cvxopt.matrix(bx.copy()), cvxopt.matrix(0.0, (0, 1)), cvxopt.matrix(bz.copy())
        f(x, y, z)
        out.append(np.array(x).ravel())
    np.testing.assert_allclose(out[0], out[1], rtol=1e-7, atol=1e-9 * np.abs(out[1]).max())


@pytest.mark.parametrize("structured_iterations, runs, answer", [(1, 1, "structured"), (8, 2, "qr")])
def test_a_run_that_stalled_in_qr_is_not_run_again_with_qr(
    monkeypatch, small_problems_too, structured_iterations, runs, answer
):
    """A structured run stopped 'unknown' (here by the iteration limit, 12) after
    QR_TAIL_TRIED or more iterations of CVXOPT's 'qr' is the answer: a second run with 'qr'
    from the start is not made (on the near-unstable bounded-real lemma it stalls alike and
    costs as much). After a shorter 'qr' tail (4 iterations) the second run is made."""
    from cvxopt import solvers

    from lmic.api import load_target, solve_problem
    from lmic.options import SolveOptions

    problem = load_target("tutorial.bounded_real", brl_system(10, 4)[3])[0]
    calls = {"n": 0}
    real_sdp = solvers.sdp

    def counting(*args, **kwargs):
        calls["n"] += 1
        return real_sdp(*args, **kwargs)

    monkeypatch.setattr(solvers, "sdp", counting)
    monkeypatch.setattr(kkt_module, "MAX_STRUCTURED_ITERATIONS", structured_iterations)
    solution = solve_problem(problem, "cvxopt", SolveOptions(max_iter=12))
    qr_tail = 12 - structured_iterations + 1
    assert (qr_tail >= cvxopt_backend.QR_TAIL_TRIED) == (runs == 1)
    assert calls["n"] == runs and solution.info["kktsolver"] == answer
    assert solution.status == "inaccurate" and solution.native_status == "unknown"
