"""The warm one-shot path: a theorem's plan read from the disk cache and bound without sympy.

A one-shot ``lmic solve THEOREM SYSTEM`` whose plan was analysed by an earlier process needs
neither sympy nor the plugin module: :func:`warm_plan` reads the frozen plan
(:mod:`lmic.compile.freeze`) from lmic's cache (:mod:`lmic.cache`, kind ``frozen``) and
:func:`lmic.compile.bind.bind` binds it like an analysed plan. The cold path (any miss) is
unchanged; it stores the frozen plan for the next process (:func:`lmic.compile.freeze.remember`).

Validity: entries are keyed by the plugin fingerprint (:func:`lmic.plugin_index.fingerprint`:
lmic's version and the size and modification time of every ``.py`` file of lmic and of every
installed plugin package, the plugins' entry points and distributions, ``sys.path``), the
theorem id and its structural option values. Editing a plugin file, lmic itself, or installing
or removing a plugin changes the key: the old entry is never read again. The cache layer rejects
truncated, corrupt or foreign entries (checksum); :func:`from_payload` rejects anything
malformed; each is a miss that takes the full path. Theorems that run plugin code at bind time
(data-derived constants, requirements) are never frozen. ``LMIC_NO_CACHE=1`` turns this off, and
so does a process whose registry is already loaded (theorems may be registered from Python).

Examples
--------
>>> warm_plan("no.such.theorem") is None
True
"""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from lmic import cache
from lmic.compile.frozen import FORMAT, Coef, Dim, Domain, Factor, Tree, normalise_option

__all__ = [
    "KIND",
    "OPTIONS_KIND",
    "FrozenPlan",
    "FrozenTemplate",
    "from_payload",
    "warm_plan",
    "plan_key",
    "fingerprint",
    "stable_fingerprint",
    "load_extra",
    "store_extra",
]

#: cache kinds: frozen plans, and each theorem's structural options (to key its plans)
KIND = "frozen"
OPTIONS_KIND = "frozen-options"


# -- the plan's pieces (the attributes bind and resolve_inputs read) ------------------------------
@dataclass(frozen=True)
class Term:
    """``coef * L V R`` (as :class:`lmic.compile.plan.Term`)."""

    coef: Coef
    var: str | None
    transposed: bool
    left: tuple[Factor, ...]
    right: tuple[Factor, ...]
    text: str = ""


@dataclass
class EntryPlan:
    """One block entry's terms."""

    terms: list[Term]
    scalar: bool = False
    text: str = ""


@dataclass
class LmiPlan:
    """One LMI (as :class:`lmic.compile.plan.LmiPlan`)."""

    name: str
    relation: str
    k: int
    entries: dict[tuple[int, int], EntryPlan]
    zeros: set[tuple[int, int]]
    stars: set[tuple[int, int]]
    sizes: list[Dim]

    @property
    def strict(self) -> bool:
        return self.relation in ("<", ">")

    @property
    def negated(self) -> bool:
        return self.relation in ("<", "<=")


@dataclass
class LinearForm:
    """``const + sum coef * atom`` (as :class:`lmic.compile.plan.LinearForm`)."""

    const: Coef
    terms: list[tuple[Coef, tuple[str, str, int, int]]] = field(default_factory=list)
    traces: list[tuple[Coef, list[Term]]] = field(default_factory=list)


@dataclass
class Decl:
    """A declaration (data, parameter, option, variable, derived quantity, check, observer)."""

    name: str
    doc: str = ""
    attrs: dict[str, Any] = field(default_factory=dict)

    def __getattr__(self, item: str) -> Any:
        attrs = self.__dict__.get("attrs", {})
        if item in attrs:
            return attrs[item]
        raise AttributeError(item)


@dataclass
class FrozenTemplate:
    """The declarations :mod:`lmic.compile.inputs` and :mod:`lmic.compile.bind` read."""

    theorem_id: str
    dimensions: list[str]
    options: list[Decl]
    params: list[Decl]
    data_decls: list[Decl]
    variables: list[Decl]
    derived: list[Decl]
    checks: list[Decl]
    observer_decl: Decl | None
    objective: tuple[str, Any]
    consts: list[Any] = field(default_factory=list)
    requirements: list[Any] = field(default_factory=list)

    def option_values(self) -> dict[str, str]:
        """The option values of the analysed plan."""
        return {o.name: o.value for o in self.options}


@dataclass
class FrozenTheorem:
    """The theorem's metadata the IR records (no build function)."""

    id: str
    title: str
    citation: str
    provider: Any


@dataclass
class _Provider:
    record: dict[str, Any]

    def to_dict(self) -> dict[str, Any]:
        return dict(self.record)


@dataclass
class FrozenPlan:
    """A plan read from the cache; binds like :class:`lmic.compile.plan.Plan` (``frozen``)."""

    theorem: FrozenTheorem
    template: FrozenTemplate
    options: dict[str, str]
    lmis: list[LmiPlan]
    constraints: list[tuple[str, str, bool, LinearForm]]
    objective: tuple[str, LinearForm]
    coef_symbols: list[Decl]
    template_sha256: str
    template_parts: dict[str, str]
    cache: dict[Any, Any] = field(default_factory=dict, repr=False)
    frozen: bool = True

    @property
    def id(self) -> str:
        return self.theorem.id

    def identity(self) -> dict[str, Any]:
        """``provider`` and ``template`` of :func:`lmic.compile.bind.template_identity`."""
        return {
            "provider": self.theorem.provider.to_dict(),
            "template": {"sha256": self.template_sha256, "parts": dict(self.template_parts)},
        }


def _bool(v: Any) -> bool:
    if not isinstance(v, bool):
        raise ValueError("flag")
    return v


def _str(v: Any) -> str:
    if not isinstance(v, str):
        raise ValueError("text")
    return v


def _term(rec: Any, variables: set[str]) -> Term:
    coef, var, transposed, left, right, text = rec
    if not (var is None or var in variables):
        raise ValueError("term variable")
    return Term(
        Coef.of(coef),
        var,
        _bool(transposed),
        tuple(Factor.of(f) for f in left),
        tuple(Factor.of(f) for f in right),
        _str(text),
    )


def _form(rec: Any, variables: set[str]) -> LinearForm:
    const, terms, traces = rec
    out = LinearForm(Coef.of(const))
    for c, atom in terms:
        var, kind, i, j = atom
        if not (
            var in variables and kind in ("scalar", "entry", "trace") and isinstance(i, int) and isinstance(j, int)
        ):
            raise ValueError("atom")
        out.terms.append((Coef.of(c), (var, kind, i, j)))
    for c, ts in traces:
        out.traces.append((Coef.of(c), [_term(t, variables) for t in ts]))
    return out


def from_payload(payload: Any, provider: Mapping[str, Any]) -> FrozenPlan:
    """The :class:`FrozenPlan` of a cached payload; ``ValueError`` (or ``TypeError``,
    ``KeyError``) for anything malformed."""
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise ValueError("format")
    thm = payload["theorem"]
    theorem = FrozenTheorem(_str(thm["id"]), _str(thm["title"]), _str(thm["citation"]), _Provider(dict(provider)))
    variables = []
    for name, kind, shape, blocks, sign, doc in payload["variables"]:
        if kind not in ("symmetric", "full", "diagonal", "blockdiag", "scalar") or len(shape) != 2:
            raise ValueError("variable")
        attrs = {"kind": kind, "shape": tuple(Dim.of(s) for s in shape), "blocks": tuple(Dim.of(b) for b in blocks)}
        variables.append(Decl(_str(name), _str(doc), {**attrs, "sign": _str(sign)}))
    names = {v.name for v in variables}
    options = [
        Decl(_str(n), _str(doc), {"choices": tuple(map(_str, ch)), "default": _str(d), "value": _str(v)})
        for n, ch, d, v, doc in payload["options"]
    ]
    params = []
    for name, default, domain, text, doc in payload["params"]:
        if default is not None and not isinstance(default, int | float):
            raise ValueError("parameter default")
        params.append(Decl(_str(name), _str(doc), {"default": default, "domain": Domain.of(domain, _str(text))}))
    data = []
    for name, shape, sym, pd, default, doc in payload["data"]:
        if len(shape) != 2 or not (default is None or isinstance(default, int | float)):
            raise ValueError("data")
        attrs = {"shape": tuple(Dim.of(s) for s in shape), "symmetric": _bool(sym), "positive_definite": _bool(pd)}
        data.append(Decl(_str(name), _str(doc), {**attrs, "default": default}))
    derived = [Decl(_str(n), _str(doc), {"expr": Tree.of(tree)}) for n, tree, doc in payload["derived"]]
    checks = []
    for name, kind, tree, bound, doc in payload["checks"]:
        if not (bound is None or isinstance(bound, int | float)):
            raise ValueError("check bound")
        spec = Decl(_str(kind), "", {"kind": _str(kind), "expr": Tree.of(tree), "bound": bound})
        checks.append(Decl(_str(name), _str(doc), {"spec": spec}))
    observer = None
    if payload["observer"] is not None:
        model, time, roles, doc = payload["observer"]
        if not isinstance(roles, dict) or not all(isinstance(v, str) for v in roles.values()):
            raise ValueError("observer")
        observer = Decl(_str(model), _str(doc), {"model": _str(model), "time": _str(time), "roles": dict(roles)})
    lmis = []
    for rec in payload["lmis"]:
        k = rec["k"]
        if not isinstance(k, int) or rec["relation"] not in ("<", "<=", ">", ">="):
            raise ValueError("LMI")
        entries: dict[tuple[int, int], EntryPlan] = {}
        for i, j, terms, scalar, text in rec["entries"]:
            if not (isinstance(i, int) and isinstance(j, int) and 0 <= i < k and 0 <= j < k):
                raise ValueError("entry")
            entries[(i, j)] = EntryPlan([_term(t, names) for t in terms], _bool(scalar), _str(text))
        sizes = [Dim.of(s) for s in rec["sizes"]]
        if len(sizes) != k:
            raise ValueError("sizes")
        zeros = {(int(i), int(j)) for i, j in rec["zeros"]}
        stars = {(int(i), int(j)) for i, j in rec["stars"]}
        lmis.append(LmiPlan(_str(rec["name"]), rec["relation"], k, entries, zeros, stars, sizes))
    constraints = []
    for name, kind, strict, form in payload["constraints"]:
        if kind not in ("eq", "ge"):
            raise ValueError("constraint")
        constraints.append((_str(name), kind, _bool(strict), _form(form, names)))
    sense, form = payload["objective"]
    if sense not in ("feasibility", "min", "max"):
        raise ValueError("objective")
    template = FrozenTemplate(
        theorem.id,
        [_str(d) for d in payload["dimensions"]],
        options,
        params,
        data,
        variables,
        derived,
        checks,
        observer,
        (sense, None),
    )
    coef_symbols = [Decl(_str(n)) for n in payload["coef_names"]]
    tpl = payload["template"]
    parts = {_str(k): _str(v) for k, v in tpl["parts"].items()}
    return FrozenPlan(
        theorem,
        template,
        template.option_values(),
        lmis,
        constraints,
        (sense, _form(form, names)),
        coef_symbols,
        _str(tpl["sha256"]),
        parts,
    )


# -- the warm lookup ----------------------------------------------------------------------------
#: frozen plans read in this process: (theorem id, option values) -> plan
_MEMO: dict[tuple[str, tuple[tuple[str, str], ...]], FrozenPlan] = {}
#: the plugin fingerprint this process computed (None: not yet)
_FINGERPRINT: list[Any] = []


def _usable() -> bool:
    if cache.cache_dir() is None or os.environ.get("LMIC_DISABLE_PLUGIN_AUTOLOAD"):
        return False
    registry = sys.modules.get("lmic.registry")  # loaded: theorems may come from Python too
    return registry is None or not getattr(registry.REGISTRY, "_loaded", False)


def fingerprint() -> Any:
    """The plugin fingerprint (:func:`lmic.plugin_index.fingerprint`), computed once per process."""
    if not _FINGERPRINT:
        from lmic.plugin_index import fingerprint as compute

        _FINGERPRINT.append(compute())
    return _FINGERPRINT[0]


def stable_fingerprint() -> Any:
    """The fingerprint to store entries under, or ``None`` when storing is unsafe.

    The fingerprint this process computed before importing any plugin must still describe the
    same files and entry points (nothing was edited meanwhile); the entry goes under the state
    now (importing may have written ``__pycache__`` folders into ``sys.path``), which is what the
    next process computes first.
    """
    if not _FINGERPRINT or _FINGERPRINT[0] is None or cache.cache_dir() is None:
        return None
    from lmic.plugin_index import fingerprint as compute

    before, after = _FINGERPRINT[0], compute()
    if after is None or any(after[k] != before[k] for k in ("entry_points", "files")):
        return None
    return after


def load_extra(kind: str, theorem_id: str) -> Any:
    """Another per-theorem cache entry of the warm path (e.g. a study's template hash), or ``None``.

    Valid under the same rules as the frozen plans (the plugin fingerprint is in the key).
    """
    if not _usable():
        return None
    fp = fingerprint()
    return None if fp is None else cache.load(kind, {"fingerprint": fp, "theorem": theorem_id})


def store_extra(kind: str, theorem_id: str, payload: Any) -> bool:
    """Store what :func:`load_extra` reads (when :func:`stable_fingerprint` allows it)."""
    fp = stable_fingerprint()
    return fp is not None and cache.store(kind, {"fingerprint": fp, "theorem": theorem_id}, payload)


def plan_key(fp: Any, theorem_id: str, options: Mapping[str, str]) -> dict[str, Any]:
    """The cache key of a frozen plan."""
    return {"fingerprint": fp, "theorem": theorem_id, "options": sorted([k, v] for k, v in options.items())}


def warm_plan(theorem_id: str, params: Mapping[str, Any] | None = None) -> FrozenPlan | None:
    """The frozen plan of ``theorem_id`` for the options in ``params``, or ``None`` (a miss)."""
    if not _usable():
        return None
    fp = fingerprint()
    if fp is None:
        return None
    declared = cache.load(OPTIONS_KIND, {"fingerprint": fp, "theorem": theorem_id})
    try:
        if not isinstance(declared, dict):
            return None
        given = dict(params or {})
        options = {_str(n): normalise_option(given.get(n, _str(d))) for n, d in declared["options"]}
        memo_key = (theorem_id, tuple(sorted(options.items())))
        if memo_key in _MEMO:
            return _MEMO[memo_key]
        payload = cache.load(KIND, plan_key(fp, theorem_id, options))
        if payload is None:
            return None
        plan = from_payload(payload["plan"], payload["provider"])
        if plan.id != theorem_id or plan.options != options:
            return None
    except (ValueError, TypeError, KeyError, AttributeError, IndexError, RecursionError):
        return None  # a malformed entry: the full path (which writes it again)
    _MEMO[memo_key] = plan
    return plan
