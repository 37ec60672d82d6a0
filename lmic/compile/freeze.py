"""A :class:`~lmic.compile.plan.Plan` as plain JSON that binds without sympy (the warm path).

:func:`freeze` writes everything :func:`lmic.compile.bind.bind` and
:func:`lmic.compile.inputs.resolve_inputs` read from a plan and its template -- declarations,
parameter domains, expanded LMIs and linear forms, the template hash -- with every sympy
expression turned into an IR expression tree (:mod:`lmic.ir.expr`, evaluated with numpy):

* a dimension (``n``, ``n + p``) is the tree of its expression in the dimension names;
* a coefficient is the tree of a scalar expression of parameters and scalar constants;
* a constant factor is ``["eye"]``, ``["name", A]``, ``["nameT", A]`` (``A^T``) or
  ``["tree", tree]``, where sizes of identities and zeros are ``{"dim": tree}`` placeholders
  replaced by integers at bind time;
* a parameter domain is an interval with exact rational ends (``None``: infinite) or one of
  ``integers``, ``naturals``, ``naturals0``.

:mod:`lmic.compile.warm` reads it back (without sympy). A template that runs plugin code at
bind time (data-derived constants, requirements, callable data defaults) or holds anything
outside the encoding raises :class:`Unsupported`: it is simply not frozen, and its one-shot runs
take the full path.

Examples
--------
>>> from lmic.compile.plan import analyse
>>> from lmic.registry import get_theorem
>>> payload = freeze(analyse(get_theorem("thesis.lyapunov")))
>>> payload["theorem"]["id"], [d[0] for d in payload["data"]]
('thesis.lyapunov', ['A'])
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import sympy
from sympy.matrices.expressions import Identity, MatrixSymbol, Transpose

from lmic.compile.frozen import FORMAT
from lmic.compile.plan import LinearForm, Plan, Term
from lmic.errors import LmicError
from lmic.template.builder import template_hash
from lmic.template.convert import as_expr
from lmic.template.totree import to_tree

__all__ = ["freeze", "remember", "Unsupported", "FORMAT"]


class Unsupported(ValueError):
    """The plan cannot be frozen (plugin code at bind time, or outside the encoding)."""


class _SymbolicDims(dict[Any, Any]):
    """The ``dims`` of :func:`~lmic.template.totree.to_tree` that keeps sizes symbolic."""

    def symbolic_dim(self, v: Any) -> dict[str, Any]:
        return {"dim": _dim(v)}


def _tree(e: Any) -> dict[str, Any]:
    try:
        return to_tree(e, _SymbolicDims())
    except (LmicError, TypeError, ValueError) as err:
        raise Unsupported(f"expression {e}: {err}") from None


def _dim(v: Any) -> dict[str, Any]:
    """The tree of a dimension expression (integers and dimension names, ``+``, ``*``)."""
    e = as_expr(v)
    if e.is_Integer:
        return {"num": int(e)}
    if not e.free_symbols or not all(s.is_integer for s in e.free_symbols):
        raise Unsupported(f"dimension {v}")
    return to_tree(e, {})


def _coef(e: Any, names: set[str]) -> dict[str, Any]:
    tree = _tree(e)
    if not _names(tree) <= names:
        raise Unsupported(f"coefficient {e}")
    return tree


def _names(tree: Any) -> set[str]:
    if isinstance(tree, dict):
        out = {tree["name"]} if "name" in tree else set()
        for v in tree.values():
            out |= _names(v)
        return out
    if isinstance(tree, list):
        out = set()
        for v in tree:
            out |= _names(v)
        return out
    return set()


def _factor(f: Any) -> list[Any]:
    if isinstance(f, Identity):
        return ["eye"]
    if isinstance(f, MatrixSymbol):
        return ["name", f.name]
    if isinstance(f, Transpose) and isinstance(f.arg, MatrixSymbol):
        return ["nameT", f.arg.name]
    return ["tree", _tree(f)]


def _term(t: Term, names: set[str]) -> list[Any]:
    return [
        _coef(t.coef, names),
        t.var,
        t.transposed,
        [_factor(f) for f in t.left],
        [_factor(f) for f in t.right],
        t.text,
    ]


def _form(f: LinearForm, names: set[str]) -> list[Any]:
    terms = [[_coef(c, names), list(atom)] for c, atom in f.terms]
    traces = [[_coef(c, names), [_term(t, names) for t in ts]] for c, ts in f.traces]
    return [_coef(f.const, names), terms, traces]


def _bound(b: Any) -> list[int] | None:
    if b in (sympy.oo, -sympy.oo):
        return None
    if not isinstance(b, sympy.Rational):
        raise Unsupported(f"domain bound {b}")
    return [int(b.p), int(b.q)]


def _domain(d: Any) -> list[Any]:
    for name, s in (("integers", sympy.S.Integers), ("naturals", sympy.S.Naturals), ("naturals0", sympy.S.Naturals0)):
        if d == s:
            return [name]
    if isinstance(d, sympy.Interval):
        return ["interval", _bound(d.start), _bound(d.end), bool(d.left_open), bool(d.right_open)]
    raise Unsupported(f"domain {d}")


def _number(v: Any) -> float | None:
    if v is None:
        return None
    if callable(v) or not isinstance(v, int | float | sympy.Number):
        raise Unsupported("a data default that is not a number")
    return float(v)


def freeze(plan: Plan, parts: Mapping[str, str] | None = None) -> dict[str, Any]:
    """The JSON form of ``plan`` (see the module docstring); ``parts``: its template fingerprint.

    Raises :class:`Unsupported` when the plan cannot be bound without the plugin's code.
    """
    t = plan.template
    if t.consts or t.requirements:
        raise Unsupported("data-derived constants or requirements (plugin code at bind time)")
    parts = dict(parts if parts is not None else plan.cache.get("template_parts") or t.fingerprint())
    names = {s.name for s in plan.coef_symbols}
    thm = plan.theorem
    lmis = []
    for lp in plan.lmis:
        entries = [
            [i, j, [_term(x, names) for x in ep.terms], ep.scalar, ep.text] for (i, j), ep in sorted(lp.entries.items())
        ]
        lmis.append(
            {
                "name": lp.name,
                "relation": lp.relation,
                "k": lp.k,
                "entries": entries,
                "zeros": sorted([i, j] for i, j in lp.zeros),
                "stars": sorted([i, j] for i, j in lp.stars),
                "sizes": [_dim(s) for s in lp.sizes],
            }
        )
    observer = None
    if t.observer_decl is not None:
        ob = t.observer_decl
        observer = [ob.model, ob.time, dict(ob.roles), ob.doc]
    return {
        "format": FORMAT,
        "theorem": {"id": thm.id, "title": thm.title, "citation": thm.citation},
        "template": {"sha256": template_hash(parts), "parts": parts},
        "dimensions": [s.name for s in t.dimensions],
        "options": [[o.name, list(o.choices), o.default, o.value, o.doc] for o in t.options],
        "params": [[p.name, p.default, _domain(p.domain), str(p.domain), p.doc] for p in t.params],
        "data": [
            [
                d.name,
                [_dim(s) for s in d.shape],
                bool(d.symmetric),
                bool(d.positive_definite),
                _number(d.default),
                d.doc,
            ]
            for d in t.data_decls
        ],
        "variables": [
            [v.name, v.kind, [_dim(s) for s in v.shape], [_dim(b) for b in v.blocks], v.sign, v.doc]
            for v in t.variables
        ],
        "coef_names": [s.name for s in plan.coef_symbols],
        "lmis": lmis,
        "constraints": [[name, kind, strict, _form(form, names)] for name, kind, strict, form in plan.constraints],
        "objective": [plan.objective[0], _form(plan.objective[1], names)],
        "derived": [[d.name, _tree(d.expr), d.doc] for d in t.derived],
        "checks": [
            [c.name, c.spec.kind, _tree(c.spec.expr), None if c.spec.bound is None else float(c.spec.bound), c.doc]
            for c in t.checks
        ],
        "observer": observer,
    }


def remember(plan: Plan) -> bool:
    """Store the frozen form of ``plan`` for the next process's :func:`~lmic.compile.warm.warm_plan`.

    Only for a theorem installed through an entry point, never ambiguous, and only when no
    plugin or lmic file changed since this process computed its fingerprint (before importing
    any plugin). Returns ``True`` when written.
    """
    from lmic import cache
    from lmic.compile import warm
    from lmic.registry import conflicts

    if plan.cache.get("frozen_stored") is not None:
        return bool(plan.cache["frozen_stored"])
    plan.cache["frozen_stored"] = False  # tried once per plan and process
    provider = plan.theorem.provider
    if provider is None or provider.is_api or any(c.id == plan.id for c in conflicts()):
        return False
    after = warm.stable_fingerprint()
    if after is None:
        return False
    try:
        payload = freeze(plan)
        # what the next process reads must be what this one would bind
        check = warm.from_payload(payload, provider.to_dict())
    except (Unsupported, LmicError, ValueError, TypeError, KeyError):
        return False
    if check.options != plan.options:
        return False
    options = [[o.name, o.default] for o in plan.template.options]
    cache.store(warm.OPTIONS_KIND, {"fingerprint": after, "theorem": plan.id}, {"options": options})
    stored = cache.store(
        warm.KIND, warm.plan_key(after, plan.id, plan.options), {"plan": payload, "provider": provider.to_dict()}
    )
    plan.cache["frozen_stored"] = stored
    return stored
