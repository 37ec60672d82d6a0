"""Compile a theorem template plus a system's numbers into the IR.

:func:`compile_theorem` analyses a theorem once per set of structural options (cached in memory,
and on disk across processes by :mod:`lmic.compile.cache`) and binds numbers to the cached plan;
a parameter sweep re-binds, it does not re-analyse. A one-shot process whose plan an earlier
process analysed binds the frozen plan read from the cache, without sympy or the plugin module
(:mod:`lmic.compile.frozen`).

Importing this package does not import sympy: ``analyse`` and ``Plan`` are imported on first use.

Examples
--------
>>> from lmic.compile import compile_theorem
>>> prob = compile_theorem("thesis.lyapunov", {"data": {"A": [[-1.0, 2.0], [0.0, -3.0]]}})
>>> [l.name for l in prob.lmis]
['P > 0', '(2.9)']
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

# bind is sympy-free (and a submodule of the same name: imported here, so that the package
# attribute is the function, whatever imports lmic.compile.bind later)
from lmic.compile.bind import bind

if TYPE_CHECKING:
    from lmic.compile.plan import Plan, analyse
    from lmic.ir.problem import Problem
    from lmic.system import System
    from lmic.template.theorem import Theorem

__all__ = ["compile_theorem", "plan_for", "analyse", "bind", "Plan"]

_PLANS: dict[tuple[str, int, tuple[tuple[str, str], ...]], Plan] = {}
#: per theorem: its structural options and their defaults (learnt at the first analysis)
_OPTION_DEFAULTS: dict[tuple[str, int], dict[str, str]] = {}
_LAZY = {"analyse": "lmic.compile.plan", "Plan": "lmic.compile.plan"}


def __getattr__(name: str) -> Any:
    """``analyse`` and ``Plan`` (sympy) are imported on first use (PEP 562)."""
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'lmic.compile' has no attribute {name!r}")


def _resolve(theorem: Theorem | str) -> Theorem:
    from lmic.template.theorem import Theorem

    if isinstance(theorem, Theorem):
        return theorem
    from lmic.registry import get_theorem

    return get_theorem(theorem)


def plan_for(theorem: Theorem | str, params: Mapping[str, Any] | None = None) -> Plan:
    """The (cached) plan of ``theorem`` for the structural options found in ``params``.

    The cache key is the theorem and the values of its options (defaults filled in).
    """
    from lmic.compile.cache import cached_analyse
    from lmic.template.builder import normalise_option

    thm = _resolve(theorem)
    params = dict(params or {})
    tkey = (thm.id, id(thm.build))
    defaults = _OPTION_DEFAULTS.get(tkey)
    if defaults is not None:
        chosen = {k: normalise_option(params.get(k, d)) for k, d in defaults.items()}
        plan = _PLANS.get((*tkey, tuple(sorted(chosen.items()))))
        if plan is not None:
            return plan
    plan = cached_analyse(thm, params)
    _OPTION_DEFAULTS[tkey] = {o.name: o.default for o in plan.template.options}
    _PLANS[(*tkey, tuple(sorted(plan.options.items())))] = plan
    return plan


def compile_theorem(
    theorem: Theorem | str,
    system: str | os.PathLike[str] | dict[str, Any] | System,
    params: Mapping[str, Any] | None = None,
) -> Problem:
    """Compile ``theorem`` for ``system`` (path, dict or System) with parameter overrides.

    Returns
    -------
    Problem
        The IR; ``meta`` records the theorem, parameters and data hash (no timings, so that
        compiling the same inputs twice gives the same IR and the same hash).
    """
    from lmic.system import load_system

    sysobj = load_system(system)
    merged = dict(sysobj.params)
    merged.update(params or {})
    if isinstance(theorem, str):  # by id: the warm path when an earlier process analysed it
        from lmic.compile.warm import warm_plan

        frozen = warm_plan(theorem, merged)
        if frozen is not None:
            return bind(frozen, sysobj, params)
    plan = plan_for(theorem, merged)
    if isinstance(theorem, str):
        from lmic.compile.freeze import remember

        remember(plan)
    return bind(plan, sysobj, params)
