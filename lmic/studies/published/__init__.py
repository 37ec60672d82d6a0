"""Audit what a paper prints: is the published result certified, rejected, or not reproducible?

A system file may list, under ``published:``, what the paper prints for it. :func:`audit_published`
turns every entry into a *claim* and decides it with the theorem's own LMIs and the certifier:

``point``  (route a)
    Every decision variable is given (directly, or recovered from a printed gain, below): the point
    is packed into ``x`` (:meth:`~lmic.ir.problem.Problem.pack`) and certified as it stands, no
    solver involved. Published numbers are rounded, so a point on the boundary may be rejected.
``partial point``  (route c)
    Some decision variables are given: they are fixed (:func:`fix_variables`, an IR-level
    substitution) and the theorem's problem is solved in the others, then certified. ``X_star``
    names the variable ``X`` (``eps1_star`` -> ``eps1``) when ``X`` is a scalar variable.
``gain``  (route b)
    A printed gain ``K`` that is not a decision variable, for a theorem that declares the
    audit variant: an option ``fixed_K`` (a flag) under which ``K`` is a data matrix and the LMIs
    are in the remaining variables (``R = L^T P`` substituted, ``G = P L``...). This is the
    convention the plugins follow (``sampled_euler``, ``uncertain_dt``, ``qib``, ``nonuniform``).
    The variant is solved (objective kept, e.g. the best ``gamma*`` the printed gain certifies).
``status``
    ``status: feasible | infeasible``: the theorem is solved for the file's parameters.
``param``
    A published number named like a parameter: feasibility at that value.
``value``
    A derived quantity (``L``, ``gamma_star``) or data-derived constant (``U``, ``V``) of the
    theorem: compared with the value computed at the best point available (the published point,
    else its completion, else the theorem's own solution). Informational when the theorem's
    answer is not unique (feasibility problems).

The code: :mod:`~lmic.studies.published.claims` (the claim and report types),
:mod:`~lmic.studies.published.transforms` (IR helpers), :mod:`~lmic.studies.published.context`
(the compiled problem and the claims so far), :mod:`~lmic.studies.published.routes` (one
public function per route) and :mod:`~lmic.studies.published.audit` (:func:`audit_published`).
Their text form is :mod:`lmic.present.published`.

Recovering variables from gains: a derived quantity printed together with the matrix it is
divided by (``L = P^-1 Lbar`` with ``P`` and ``L`` printed) gives the variable back
(``Lbar = P L``). :func:`recover_variables` reads the IR's expression trees for the forms
``inv(A) B``, ``inv(A) B^T`` and ``B inv(A)``.

Exit code (:meth:`AuditReport.exit_code`): over the decisive claims (point, partial point, gain,
status, param), 1 if one is rejected, else 3 if one is proven infeasible, else 1 if one is not
reproducible, else 0; with value claims only, 0 if every one matches, else 1.

Examples
--------
>>> rep = audit_published("qib.thm1", "examples/qib.thm1.flexible-joint.yaml")   # doctest: +SKIP
>>> [(c.kind, c.finding) for c in rep.claims][:2]                                   # doctest: +SKIP
[('point', 'certified'), ('gain', 'certified')]
"""

from __future__ import annotations

from lmic.studies.published.audit import audit_published
from lmic.studies.published.claims import DECISIVE, AuditReport, Claim
from lmic.studies.published.context import AuditContext
from lmic.studies.published.routes import (
    compare_value,
    derived_at_published,
    gain_claims,
    param_claim,
    point_claims,
    published_environment,
    status_claim,
    value_claims,
)
from lmic.studies.published.transforms import fix_variables, lmi_extremes, recover_variables

__all__ = [
    "Claim",
    "AuditReport",
    "AuditContext",
    "audit_published",
    "fix_variables",
    "recover_variables",
    "lmi_extremes",
    "DECISIVE",
    "point_claims",
    "gain_claims",
    "status_claim",
    "param_claim",
    "value_claims",
    "compare_value",
    "published_environment",
    "derived_at_published",
]
