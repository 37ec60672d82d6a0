"""The state an audit of published results shares between its routes.

:class:`AuditContext` loads the system, compiles the theorem once and keeps what the routes find
(the published variables, the best point to evaluate values at, the theorem's own solution).

Examples
--------
>>> ctx = AuditContext("qib.thm1", "examples/qib.thm1.flexible-joint.yaml")  # doctest: +SKIP
>>> ctx.var_names                                                           # doctest: +SKIP
['P', 'R', 'omega']
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from lmic.errors import DataError
from lmic.ir.problem import Problem
from lmic.studies.published.claims import Claim
from lmic.studies.published.transforms import checks_of, lmi_extremes, min_margin

__all__ = ["AuditContext"]


class AuditContext:
    """One system file's ``published:`` section against one theorem: the compiled problem and the claims so far.

    Parameters
    ----------
    theorem : str
    system : path, dict or System
        With a ``published:`` section (else :class:`~lmic.errors.DataError`).
    params : mapping, optional
        Parameter overrides.
    backend, options
        For every solve (:func:`lmic.studies.sweep.decide`).
    rtol : float
        Relative tolerance of value claims.
    """

    def __init__(
        self,
        theorem: str,
        system: Any,
        params: Mapping[str, Any] | None = None,
        backend: Any = None,
        options: Any = None,
        rtol: float = 0.05,
    ) -> None:
        from lmic.compile import bind, plan_for
        from lmic.system import load_system

        self.sysobj = load_system(system)
        if not self.sysobj.published:
            raise DataError(f"{self.sysobj.label}: has no 'published:' section to audit")
        self.theorem = theorem
        self.params = dict(params or {})
        merged = dict(self.sysobj.params)
        merged.update(self.params)
        self.plan = plan_for(theorem, merged)
        self.problem = bind(self.plan, self.sysobj, self.params)
        self.backend, self.options, self.rtol = backend, options, rtol
        t = self.plan.template
        self.var_names = [v.name for v in self.problem.variables]
        self.derived_names = [d.name for d in self.problem.derived]
        self.const_names = [c.name for c in t.consts]
        self.data_names = [d.name for d in t.data_decls]
        self.param_names = [p.name for p in t.params]
        self.option_names = [o.name for o in t.options]
        self.claims: list[Claim] = []
        self.value_point: tuple[str, Problem, np.ndarray] | None = None  # (where, problem, x)
        self.given: dict[str, Any] = {}  # published (and recovered) variable values
        self._synthesis: Any = None

    def decide(self, problem: Problem, keep_objective: bool = True) -> Any:
        from lmic.studies.sweep import decide

        return decide(problem, self.backend, self.options, keep_objective=keep_objective)

    def synthesis(self) -> Any:
        """The theorem's own problem, decided once (for status and value claims)."""
        if self._synthesis is None:
            self._synthesis = self.decide(self.problem)
        return self._synthesis

    def fill_from_point(self, claim: Claim, problem: Problem, pt: Any) -> None:
        """Copy a decided point (verdict, proof, margins, checks, objective, derived) into ``claim``."""
        cert = pt.certificate
        claim.verdict = pt.verdict
        claim.proof = pt.proof
        claim.lmis = lmi_extremes(problem, cert) if cert is not None and cert.lmis else []
        claim.margin = min_margin(cert) if cert is not None else None
        claim.checks = checks_of(cert) if cert is not None else []
        claim.objective = pt.objective
        claim.derived = dict(pt.derived)
        claim.solve_s = pt.solve_s
        claim.reason = (cert.reason if cert is not None else "") or pt.proof
