"""The backend interface every solver plugin implements.

A backend is a class with class attributes ``name``, ``requires`` (importable module names),
``STATUS_MAP`` (native status -> :data:`lmic.solution.STATUSES`), and the methods
:meth:`Backend.is_available`, :meth:`Backend.supports` and :meth:`Backend.solve`. Native solver
modules are imported inside methods, never at import time.

Examples
--------
>>> SolveOptions(tol=1e-9).tol
1e-09
"""

from __future__ import annotations

import importlib.util
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, ClassVar

from lmic.ir.problem import Problem
from lmic.solution import Solution

__all__ = ["SolveOptions", "Backend"]


@dataclass
class SolveOptions:
    """Options every backend understands (each maps them onto its solver's own names).

    Parameters
    ----------
    tol : float
        Relative accuracy (gap and feasibility) asked of the solver.
    max_iter : int or None
    time_limit : float or None
        Seconds.
    verbose : bool
    margin : float
        Margin imposed on strict inequalities of optimisation problems (``F(x) >= margin I``).
    extra : dict
        Solver-specific settings passed through unchanged.
    """

    tol: float = 1e-8
    max_iter: int | None = None
    time_limit: float | None = None
    verbose: bool = False
    margin: float = 1e-7
    extra: dict[str, Any] = field(default_factory=dict)


class Backend(ABC):
    """Base class of every backend plugin."""

    name: ClassVar[str] = ""
    #: importable module names the backend needs, and the pip package that provides each
    requires: ClassVar[dict[str, str]] = {}
    STATUS_MAP: ClassVar[dict[str, str]] = {}
    #: constraint kinds the backend takes: subset of {"lmi", "eq", "ge"}
    capabilities: ClassVar[frozenset[str]] = frozenset({"lmi", "eq", "ge"})

    @classmethod
    def missing_packages(cls) -> list[str]:
        """The pip packages whose modules cannot be imported here."""
        return [pkg for mod, pkg in cls.requires.items() if importlib.util.find_spec(mod) is None]

    @classmethod
    def is_available(cls) -> bool:
        """True when every required module is importable."""
        return not cls.missing_packages()

    def supports(self, problem: Problem, explain: bool = False) -> bool | tuple[bool, str]:
        """Whether this backend can take ``problem``; with ``explain``, also why not."""
        return (True, "") if explain else True

    @abstractmethod
    def solve(self, problem: Problem, options: SolveOptions | None = None) -> Solution:
        """Solve ``problem``; map every outcome (crashes included) into a :class:`Solution`."""

    def map_status(self, native: str) -> str:
        """Map a native status into the shared vocabulary (unknown -> ``error``)."""
        return self.STATUS_MAP.get(str(native), "error")
