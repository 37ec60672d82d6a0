"""Helpers for the tests of the seed-paper plugins (sampled_euler, uncertain_dt, qib, nonuniform).

* ``system``: a shipped example as a dict, with data/param overrides (e.g. a published gain
  moved into ``data`` for a ``fixed_L`` audit).
* ``solve``: the pipeline (compile -> solve -> certify) of :func:`lmic.api.solve`.
* ``fix_variables`` / ``certify_point``: audits of published (partial) points through the IR.
* ``compare_lmi``: the plugin's compiled LMI against an independent numpy assembly of the
  catalogue's block matrix at the same point (catches any block, sign or transposition slip).
* ``cvx_feasible`` / ``cvx_min``: the independent CVXPY formulations (written from the
  catalogue, not from the plugins) the random-system tests compare with.
"""

from __future__ import annotations

import copy
import dataclasses
from pathlib import Path

import cvxpy as cp
import numpy as np
import scipy.sparse as sp
import yaml

from lmic.api import solve as _solve
from lmic.certify import certify
from lmic.ir.problem import LinearConstraints, Problem
from lmic.solution import Solution

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
MARGIN = 1e-7
#: reference solvers (CVXPY) and lmic backends of the random-system tests
REF_SOLVERS = ("CLARABEL", "SCS")
BACKENDS = ("clarabel", "cvxopt")


def system(name: str, data: dict | None = None, params: dict | None = None) -> dict:
    """The example ``examples/<name>.yaml`` as a dict, with data and parameter overrides."""
    path = EXAMPLES / f"{name}.yaml"
    assert path.is_file(), path
    d = yaml.safe_load(path.read_text())
    d = copy.deepcopy(d)
    d["data"].update(data or {})
    d.setdefault("params", {}).update(params or {})
    return d


def solve(theorem: str, sysdict, params: dict | None = None, backend: str = "clarabel"):
    """``lmic.api.solve`` (compile, solve, certify)."""
    return _solve(theorem, sysdict, params, backend=backend)


def certify_point(prob: Problem, values: dict):
    """Certify a given point (e.g. a published solution) as if a solver had returned it."""
    return certify(prob, Solution("feasible", x=prob.pack(values)))


def fix_variables(prob: Problem, **values) -> Problem:
    """The same problem with the given variables fixed by equality rows."""
    rows, names = [], []
    for name, value in values.items():
        var = prob.variable(name)
        for k, val in enumerate(var.pack(value)):
            row = np.zeros(1 + prob.n)
            row[0] = -val
            row[1 + var.offset + k] = 1.0
            rows.append(row)
            names.append(f"{name} fixed")
    lin = prob.linear
    linear = LinearConstraints(
        sp.vstack([lin.A, sp.csr_matrix(np.array(rows))], format="csr"),
        list(lin.kinds) + ["eq"] * len(rows),
        list(lin.strict) + [False] * len(rows),
        list(lin.names) + names,
    )
    return dataclasses.replace(prob, linear=linear)


def random_point(prob: Problem, rng: np.random.Generator) -> tuple[np.ndarray, dict]:
    """A random ``x`` and the variable values it holds."""
    x = rng.standard_normal(prob.n)
    return x, prob.unpack(x)


def lmi_matrix(prob: Problem, name: str, x: np.ndarray) -> np.ndarray:
    """The LMI as the author wrote it (``M`` of ``M < 0`` or ``M > 0``) at ``x``."""
    lmi = next(item for item in prob.lmis if item.name == name)
    F = lmi.matrix(x)
    return -F if lmi.relation in ("<", "<=") else F


def compare_lmi(prob: Problem, name: str, x: np.ndarray, expected: np.ndarray) -> None:
    """The compiled LMI ``name`` at ``x`` equals the independently assembled ``expected``."""
    got = lmi_matrix(prob, name, x)
    assert got.shape == expected.shape, (name, got.shape, expected.shape)
    scale = max(1.0, float(np.max(np.abs(expected))))
    assert np.max(np.abs(got - expected)) <= 1e-10 * scale, name


def sym(M):
    """Symmetric part (cvxpy or numpy)."""
    return (M + M.T) / 2


def cvx_feasible(
    neg_strict: list, pos_strict: list = (), scalars: list = (), solver: str = "CLARABEL", box: list = ()
) -> bool | None:
    """Is there a point with every ``M < 0`` (``neg_strict``), ``M > 0`` (``pos_strict``) and
    scalar ``> 0``? Phase 1: ``max t`` with ``M + t I <= 0``, ``t <= 1``, variables in ``box``
    bounded by 1e4 (homogeneous LMIs); feasible iff ``t* > 1e-6``, infeasible iff ``t* < 1e-9``.
    ``None`` when the solver fails or the answer is too close to call.
    """
    t = cp.Variable()
    cons = [t <= 1]
    for M in neg_strict:
        cons.append(sym(M) + t * np.eye(M.shape[0]) << 0)
    for M in pos_strict:
        cons.append(sym(M) - t * np.eye(M.shape[0]) >> 0)
    for s in scalars:
        cons.append(s >= t)
    for v in box:
        cons.append(cp.abs(v) <= 1e4)
    prob = cp.Problem(cp.Maximize(t), cons)
    prob.solve(solver=solver)
    if prob.status not in ("optimal", "optimal_inaccurate") or t.value is None:
        return None
    if t.value > 1e-6:
        return True
    if t.value < 1e-9:
        return False
    return None


def cvx_min(
    objective, neg_strict: list, pos_strict: list = (), scalars: list = (), extra: list = (), solver: str = "CLARABEL"
) -> tuple[str, float | None]:
    """``min objective`` with every strict ``M < 0`` as ``M <= -1e-7 I`` (``M > 0``: ``>= 1e-7 I``)
    and every strictly positive scalar ``>= 1e-7`` (lmic's fixed-margin convention)."""
    cons = list(extra)
    for M in neg_strict:
        cons.append(sym(M) + MARGIN * np.eye(M.shape[0]) << 0)
    for M in pos_strict:
        cons.append(sym(M) - MARGIN * np.eye(M.shape[0]) >> 0)
    for s in scalars:
        cons.append(s >= MARGIN)
    prob = cp.Problem(cp.Minimize(objective), cons)
    prob.solve(solver=solver)
    return prob.status, (None if prob.value is None else float(prob.value))


def lmic_feasible(result) -> bool | None:
    """A pipeline result as feasible (certified) / infeasible / undecided (``None``)."""
    if result.verdict == "certified":
        return True
    if result.status == "infeasible":
        return False
    return None
