"""Fix some variables to given values (a reduction pass: audits of published points and gains).

:func:`fix_variables` substitutes the values into every LMI, row and the objective and returns
the problem in the remaining variables; :func:`apply` is the ``apply -> (problem, inverse)``
form (the inverse puts a solution of the restricted problem back into the full ``x``).

:func:`with_fixed_gains` is the same idea one level up, for a gain that is not a decision
variable: the ``fixed_<gain>`` convention of the theorem plugins (``t.derive(..., fixes=V)``,
:mod:`lmic.template.sugar`) -- the system with the printed gain as data and ``fixed_<gain>: 1``.

Examples
--------
>>> import scipy.sparse as sp
>>> from lmic.ir.problem import LMI
>>> p = Problem([Variable("a", "scalar", (1, 1)), Variable("b", "scalar", (1, 1), offset=1)],
...             [LMI("a + b - 1 > 0", 1, sp.csc_matrix([[-1., 1., 1.]]))],
...             LinearConstraints.empty(2), Objective("feasibility", [0, 0, 0]))
>>> q, inverse = apply(p, {"a": 3.0})
>>> inverse(Solution("feasible", x=np.array([0.5]))).x.tolist()
[3.0, 0.5]
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.errors import IRError
from lmic.ir.problem import LinearConstraints, Objective, Problem, Variable
from lmic.solution import Solution
from lmic.system import System

__all__ = ["apply", "fix_variables", "fixed_gain_flag", "with_fixed_gains"]


def fix_variables(problem: Problem, values: Mapping[str, Any]) -> tuple[Problem, np.ndarray, np.ndarray]:
    """The problem in the remaining variables, with ``values`` substituted for some of them.

    The fixed variables' values are added to the problem's ``data`` (so derived quantities and
    checks still evaluate). Returns ``(restricted, x_fixed, free)``: ``x_fixed`` is the full-length
    vector with the fixed entries filled in, ``free`` the indices of the remaining entries; a point
    ``z`` of the restricted problem is ``x = x_fixed; x[free] = z`` in the original.

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI
    >>> p = Problem([Variable("a", "scalar", (1, 1)), Variable("b", "scalar", (1, 1), offset=1)],
    ...             [LMI("a + b - 1 > 0", 1, sp.csc_matrix([[-1., 1., 1.]]))],
    ...             LinearConstraints.empty(2), Objective("feasibility", [0, 0, 0]))
    >>> q, x0, free = fix_variables(p, {"a": 3.0})
    >>> [v.name for v in q.variables], q.lmis[0].matrix([0.5]), [int(i) for i in free]
    (['b'], array([[2.5]]), [1])
    """
    x_fixed = np.zeros(problem.n)
    mask = np.zeros(problem.n, dtype=bool)
    names = {v.name for v in problem.variables}
    for name, value in values.items():
        if name not in names:
            raise IRError(f"no variable named '{name}'")
        var = problem.variable(name)
        x_fixed[var.slice] = var.pack(value)
        mask[var.slice] = True
    free = np.flatnonzero(~mask)
    fixed = np.flatnonzero(mask)
    variables, offset = [], 0
    for v in problem.variables:
        if v.name in values:
            continue
        variables.append(Variable(v.name, v.kind, v.shape, offset, v.blocks, v.sign))
        offset += v.size

    def cut(M: sp.spmatrix) -> sp.spmatrix:
        M = sp.csc_matrix(M)
        c0 = M[:, [0]] + M[:, (1 + fixed).tolist()] @ sp.csc_matrix(x_fixed[fixed].reshape(-1, 1))
        return sp.hstack([c0, M[:, (1 + free).tolist()]], format="csc")

    lmis = [replace(lmi, coeffs=cut(lmi.coeffs)) for lmi in problem.lmis]
    lin = problem.linear
    linear = LinearConstraints(sp.csr_matrix(cut(lin.A)), list(lin.kinds), list(lin.strict), list(lin.names))
    c = problem.objective.c
    obj = Objective(problem.objective.sense, np.concatenate([[c[0] + c[1 + fixed] @ x_fixed[fixed]], c[1 + free]]))
    data = dict(problem.data)
    for name in values:
        data[name] = problem.variable(name).value(x_fixed)
    meta = dict(problem.meta)
    meta["fixed_variables"] = sorted(values)
    restricted = Problem(variables, lmis, linear, obj, data, list(problem.derived), list(problem.checks), meta)
    return restricted, x_fixed, free


def apply(problem: Problem, values: Mapping[str, Any]) -> tuple[Problem, Callable[[Solution], Solution]]:
    """The pass: the restricted problem and the inverse (``x = x_fixed; x[free] = z``)."""
    restricted, x_fixed, free = fix_variables(problem, values)

    def inverse(sol: Solution) -> Solution:
        if sol.x is not None and len(sol.x) == len(free):
            x = x_fixed.copy()
            x[free] = sol.x
            sol.x = x
        return sol

    return restricted, inverse


def fixed_gain_flag(gain: str) -> str:
    """The option a theorem declares for the audit variant of ``gain`` (``fixed_<gain>``).

    >>> fixed_gain_flag("L")
    'fixed_L'
    """
    return f"fixed_{gain}"


def with_fixed_gains(
    system: System,
    gains: Mapping[str, Any],
    params: Mapping[str, Any] | None = None,
    *,
    keep_published: bool = True,
) -> System:
    """``system`` with each gain ``K`` of ``gains`` as a data matrix and the flag ``fixed_K: 1``.

    ``params`` override the system's parameters (the flags are set after them). The result is
    what a theorem's audit variant (``fixed_K = 1``: ``K`` is data, the variable it came from is
    eliminated) is compiled with.

    Examples
    --------
    >>> s = with_fixed_gains(System({"A": np.eye(2)}, {"beta": 1.0}), {"L": [[1.0], [2.0]]})
    >>> s.params, s.data["L"].shape
    ({'beta': 1.0, 'fixed_L': '1'}, (2, 1))
    """
    data = dict(system.data)
    for k, v in gains.items():
        data[k] = np.atleast_2d(np.asarray(v, dtype=float))
    merged: dict[str, Any] = dict(system.params)
    merged.update(params or {})
    merged.update({fixed_gain_flag(k): "1" for k in gains})
    published = dict(system.published) if keep_published else {}
    return System(data, merged, published, system.name, system.source, system.path, system.raw)
