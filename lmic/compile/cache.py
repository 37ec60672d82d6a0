"""Analysed plans on disk: a one-shot ``lmic solve`` skips the template analysis when warm.

:func:`cached_analyse` builds the theorem's template (cheap; it is needed to bind numbers
anyway), hashes its declarations (:meth:`~lmic.template.builder.Template.fingerprint`, the hash a
certificate records) and looks the analysis up in lmic's on-disk cache (:mod:`lmic.cache`, kind
``plans``). The key is the template hash, the theorem id, its option values, lmic's version, the
sympy version and a hash of the analyser's own source (an edited checkout never reuses an old
plan). On a miss the template is analysed (:func:`lmic.compile.plan.analyse_template`) and the
result stored.

Plans are serialised to JSON, never pickled: every sympy expression becomes a node of a shared
table -- ``["Symbol", name, assumptions]``, ``["Integer", k]``, ``["Rational", p, q]``,
``["Float", sign, mantissa, exponent, bits, precision]``, ``["Str", s]``, ``["S", name]`` for a
few constants, or ``[class, child, ...]`` for a class of a fixed list of sympy classes, rebuilt
as ``class(*children)`` (sympy's ``expr.func(*expr.args) == expr`` invariant). Nothing is parsed
or evaluated from text. A plan that uses anything else is simply not cached; a plan is stored
only when decoding its encoding gives an equal plan, and a stored entry that fails any check
(:mod:`lmic.cache` checksum, shapes, names, unknown classes) is a miss and is replaced.

Examples
--------
>>> from lmic.registry import get_theorem
>>> thm = get_theorem("thesis.lyapunov")
>>> plan = cached_analyse(thm)  # analysed (or read from the cache)
>>> again = cached_analyse(thm)  # read from the cache
>>> [lp.entries for lp in again.lmis] == [lp.entries for lp in plan.lmis]
True
"""

from __future__ import annotations

import functools
import hashlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import sympy
from sympy.core.symbol import Str
from sympy.matrices.expressions import (
    Identity,
    Inverse,
    MatAdd,
    MatMul,
    MatPow,
    MatrixSymbol,
    OneMatrix,
    Trace,
    Transpose,
    ZeroMatrix,
)
from sympy.matrices.expressions.matexpr import MatrixElement

from lmic import cache
from lmic._version import __version__
from lmic.compile.plan import EntryPlan, LinearForm, LmiPlan, Plan, Term, analyse_template
from lmic.template.builder import Template, template_hash
from lmic.template.theorem import Theorem

__all__ = ["cached_analyse", "plan_key", "encode_plan", "decode_plan", "KIND", "Unsupported"]

#: the cache kind of analysed plans
KIND = "plans"

#: the sympy classes a cached plan may contain, rebuilt as ``cls(*args)``
_CLASSES: dict[str, Any] = {
    c.__name__: c
    for c in (
        sympy.Add,
        sympy.Mul,
        sympy.Pow,
        sympy.exp,
        sympy.log,
        sympy.sin,
        sympy.cos,
        sympy.tan,
        sympy.Abs,
        sympy.Max,
        sympy.Min,
        MatAdd,
        MatMul,
        MatPow,
        MatrixSymbol,
        Identity,
        ZeroMatrix,
        OneMatrix,
        Transpose,
        Inverse,
        Trace,
        MatrixElement,
    )
}
#: sympy's singleton constants a plan may contain
_SINGLETONS: dict[str, Any] = {"pi": sympy.pi, "E": sympy.E, "I": sympy.I, "oo": sympy.oo, "-oo": -sympy.oo}


class Unsupported(ValueError):
    """The plan holds something the JSON encoding does not cover (the plan is not cached)."""


@functools.lru_cache(maxsize=1)
def _code_stamp() -> str:
    """A hash of the analyser and of this module: a changed analyser never reuses old plans."""
    here = Path(__file__).resolve().parent
    h = hashlib.sha256()
    try:
        for name in ("plan.py", "cache.py"):
            h.update((here / name).read_bytes())
    except OSError:  # installed without sources: lmic's version alone tells analysers apart
        return "no-source"
    return h.hexdigest()[:16]


def plan_key(theorem: Theorem, t: Template, parts: Mapping[str, str]) -> dict[str, Any]:
    """The cache key of the plan of ``theorem`` built as ``t`` (``parts``: its fingerprint).

    >>> from lmic.registry import get_theorem
    >>> thm = get_theorem("qib.thm1"); t = thm.template()
    >>> sorted(plan_key(thm, t, t.fingerprint()))
    ['analyser', 'lmic', 'objective', 'options', 'sympy', 'template', 'theorem']
    """
    sense, expr = t.objective
    return {
        "lmic": __version__,
        "sympy": sympy.__version__,
        "analyser": _code_stamp(),
        "theorem": theorem.id,
        "options": sorted([k, str(v)] for k, v in t.option_values().items()),
        "template": template_hash(parts),
        "objective": [sense, sympy.srepr(expr) if isinstance(expr, sympy.Basic) else repr(expr)],
    }


# -- encoding --------------------------------------------------------------------------------------
class _Encoder:
    def __init__(self) -> None:
        self.nodes: list[list[Any]] = []
        self.index: dict[Any, int] = {}

    def __call__(self, e: Any) -> int:
        if isinstance(e, int) and not isinstance(e, bool):
            e = sympy.Integer(e)
        if not isinstance(e, sympy.Basic):
            raise Unsupported(f"{type(e).__name__} {e!r:.40}")
        key = (type(e), e)
        found = self.index.get(key)
        if found is not None:
            return found
        node = self._node(e)
        self.nodes.append(node)
        self.index[key] = len(self.nodes) - 1
        return len(self.nodes) - 1

    def _node(self, e: sympy.Basic) -> list[Any]:
        if isinstance(e, sympy.Dummy | sympy.Wild):
            raise Unsupported(f"dummy symbol {e}")
        if isinstance(e, sympy.Symbol):
            orig = getattr(e, "_assumptions_orig", None)
            assumptions = dict(orig) if orig is not None else dict(e.assumptions0)
            return ["Symbol", e.name, sorted([k, bool(v)] for k, v in assumptions.items() if v is not None)]
        if isinstance(e, sympy.Integer):
            return ["Integer", int(e)]
        if isinstance(e, sympy.Rational):
            return ["Rational", int(e.p), int(e.q)]
        if isinstance(e, sympy.Float):
            sign, man, exp, bits = e._mpf_
            return ["Float", int(sign), hex(int(man)), int(exp), int(bits), int(e._prec)]
        if isinstance(e, Str):
            return ["Str", e.name]
        for name, value in _SINGLETONS.items():
            if e is value:
                return ["S", name]
        cls = type(e)
        if _CLASSES.get(cls.__name__) is not cls:
            raise Unsupported(f"sympy class {cls.__name__}")
        return [cls.__name__] + [self(a) for a in e.args]

    def term(self, t: Term) -> list[Any]:
        return [self(t.coef), t.var, t.transposed, [self(f) for f in t.left], [self(f) for f in t.right], t.text]

    def form(self, f: LinearForm) -> list[Any]:
        terms = [[self(c), list(atom)] for c, atom in f.terms]
        traces = [[self(c), [self.term(t) for t in ts]] for c, ts in f.traces]
        return [self(f.const), terms, traces]


def encode_plan(plan: Plan) -> dict[str, Any]:
    """The JSON form of a plan's analysis (template and theorem excluded: rebuilt, not stored).

    Raises :class:`Unsupported` for anything outside the encoding.
    """
    enc = _Encoder()
    lmis = []
    for lp in plan.lmis:
        entries = [
            [i, j, [enc.term(t) for t in ep.terms], ep.scalar, ep.text] for (i, j), ep in sorted(lp.entries.items())
        ]
        lmis.append(
            {
                "name": lp.name,
                "relation": lp.relation,
                "k": lp.k,
                "entries": entries,
                "zeros": sorted([i, j] for i, j in lp.zeros),
                "stars": sorted([i, j] for i, j in lp.stars),
                "sizes": [enc(s) for s in lp.sizes],
            }
        )
    constraints = [[name, kind, strict, enc.form(form)] for name, kind, strict, form in plan.constraints]
    objective = [plan.objective[0], enc.form(plan.objective[1])]
    return {"nodes": enc.nodes, "lmis": lmis, "constraints": constraints, "objective": objective}


# -- decoding --------------------------------------------------------------------------------------
def _decode_nodes(nodes: Any) -> list[Any]:
    if not isinstance(nodes, list):
        raise Unsupported("nodes")
    out: list[Any] = []
    for node in nodes:
        if not isinstance(node, list) or not node or not isinstance(node[0], str):
            raise Unsupported("node")
        tag, args = node[0], node[1:]
        if tag == "Symbol":
            name, assumptions = args
            if not isinstance(name, str) or not all(isinstance(k, str) and isinstance(v, bool) for k, v in assumptions):
                raise Unsupported("symbol")
            out.append(sympy.Symbol(name, **dict(assumptions)))
        elif tag == "Integer":
            (k,) = args
            out.append(sympy.Integer(_int(k)))
        elif tag == "Rational":
            p, q = args
            out.append(sympy.Rational(_int(p), _int(q)))
        elif tag == "Float":
            sign, man, exp, bits, prec = args
            if not (isinstance(man, str) and man.startswith("0x")):
                raise Unsupported("float")
            if len(man) > 40:
                raise Unsupported("float mantissa")
            mpf = (_int(sign), int(man, 16), _int(exp), _int(bits))
            out.append(sympy.Float((mpf[0], hex(mpf[1])[2:], mpf[2], mpf[3]), precision=_int(prec)))
        elif tag == "Str":
            (s,) = args
            if not isinstance(s, str):
                raise Unsupported("str")
            out.append(Str(s))
        elif tag == "S":
            (name,) = args
            if name not in _SINGLETONS:
                raise Unsupported("singleton")
            out.append(_SINGLETONS[name])
        elif tag in _CLASSES:
            if not all(isinstance(a, int) and not isinstance(a, bool) and 0 <= a < len(out) for a in args):
                raise Unsupported("child index")
            out.append(_CLASSES[tag](*(out[a] for a in args)))
        else:
            raise Unsupported(f"tag {tag}")
    return out


def _int(v: Any) -> int:
    # bounded: a damaged entry must not make sympy evaluate a huge power
    if not isinstance(v, int) or isinstance(v, bool) or abs(v) > 10**30:
        raise Unsupported("integer")
    return v


class _Decoder:
    def __init__(self, nodes: list[Any], variables: set[str]) -> None:
        self.nodes = nodes
        self.variables = variables  # the template's decision variables: a term names one of them

    def __call__(self, i: Any) -> Any:
        if not isinstance(i, int) or isinstance(i, bool) or not 0 <= i < len(self.nodes):
            raise Unsupported("node index")
        return self.nodes[i]

    def term(self, rec: Any) -> Term:
        coef, var, transposed, left, right, text = rec
        if not (var is None or var in self.variables) or not isinstance(transposed, bool) or not isinstance(text, str):
            raise Unsupported("term")
        return Term(self(coef), var, transposed, tuple(self(f) for f in left), tuple(self(f) for f in right), text)

    def form(self, rec: Any) -> LinearForm:
        const, terms, traces = rec
        out = LinearForm(self(const))
        for c, atom in terms:
            var, kind, i, j = atom
            if not (var in self.variables and kind in ("scalar", "entry", "trace")):
                raise Unsupported("atom")
            out.terms.append((self(c), (var, kind, _int(i), _int(j))))
        for c, ts in traces:
            out.traces.append((self(c), [self.term(t) for t in ts]))
        return out


def decode_plan(payload: Any, theorem: Theorem, t: Template) -> Plan:
    """Rebuild the plan of ``theorem`` built as ``t`` from :func:`encode_plan`'s JSON.

    Raises :class:`Unsupported` (or ``ValueError``/``TypeError``) for anything malformed.
    """
    if not isinstance(payload, dict) or set(payload) != {"nodes", "lmis", "constraints", "objective"}:
        raise Unsupported("payload")
    dec = _Decoder(_decode_nodes(payload["nodes"]), {v.name for v in t.variables})
    recs = payload["lmis"]
    if not isinstance(recs, list) or [r.get("name") for r in recs] != [d.name for d in t.lmis]:
        raise Unsupported("LMI names")
    lmis = []
    for rec, decl in zip(recs, t.lmis, strict=True):
        k = _int(rec["k"])
        if rec["relation"] != decl.spec.relation or k != decl.spec.block.shape[0]:
            raise Unsupported("LMI shape")
        entries: dict[tuple[int, int], EntryPlan] = {}
        for i, j, terms, scalar, text in rec["entries"]:
            if not (0 <= _int(i) < k and 0 <= _int(j) < k) or not isinstance(scalar, bool):
                raise Unsupported("entry")
            entries[(i, j)] = EntryPlan([dec.term(x) for x in terms], scalar, str(text))
        zeros = {(_int(i), _int(j)) for i, j in rec["zeros"]}
        stars = {(_int(i), _int(j)) for i, j in rec["stars"]}
        sizes = [dec(s) for s in rec["sizes"]]
        if len(sizes) != k:
            raise Unsupported("sizes")
        lmis.append(LmiPlan(decl.name, decl.spec.relation, k, entries, zeros, stars, sizes, decl.spec.block))
    constraints = []
    for name, kind, strict, form in payload["constraints"]:
        if not (isinstance(name, str) and kind in ("eq", "ge") and isinstance(strict, bool)):
            raise Unsupported("constraint")
        constraints.append((name, kind, strict, dec.form(form)))
    sense, form = payload["objective"]
    if sense != t.objective[0]:
        raise Unsupported("objective")
    coef_symbols = [p.symbol for p in t.params] + [c.symbol for c in t.consts if c.shape is None]
    return Plan(theorem, t, t.option_values(), lmis, constraints, (sense, dec.form(form)), coef_symbols)


# -- the cached analysis ---------------------------------------------------------------------------
def cached_analyse(theorem: Theorem, options: Mapping[str, Any] | None = None) -> Plan:
    """:func:`lmic.compile.plan.analyse`, with the analysis read from / written to the disk cache.

    The template is always built (and checked) afresh; only its expansion is cached. With the
    cache off (``LMIC_NO_CACHE=1``) this is :func:`~lmic.compile.plan.analyse`.
    """
    t = theorem.template(options)
    if cache.cache_dir() is None:
        return analyse_template(theorem, t)
    parts = t.fingerprint()
    key = plan_key(theorem, t, parts)
    payload = cache.load(KIND, key)
    if payload is not None:
        try:
            plan = decode_plan(payload, theorem, t)
        except Exception:  # noqa: BLE001 - a damaged or foreign entry: analyse and replace it
            plan = None
        if plan is not None:
            plan.cache["template_parts"] = parts
            return plan
    plan = analyse_template(theorem, t)
    plan.cache["template_parts"] = parts
    try:
        encoded = encode_plan(plan)
        again = decode_plan(encoded, theorem, t)
    except Exception:  # noqa: BLE001 - outside the encoding: not cached
        return plan
    if again.lmis == plan.lmis and again.constraints == plan.constraints and again.objective == plan.objective:
        cache.store(KIND, key, encoded)
    return plan
