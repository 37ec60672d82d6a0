"""Theorem plugins, discovered through the entry-point group ``lmic.theorems``.

Built-in theorems (``plugins/lmic_observers``) register through the same group as any
third-party package. An entry point names a module (its module-level :class:`Theorem` objects,
or a ``THEOREMS`` list, are registered), a :class:`Theorem`, a list of them, or a callable
returning a list. ``LMIC_DISABLE_PLUGIN_AUTOLOAD=1`` turns discovery off (then register
theorems with :func:`register`).

Integrity rules (a certificate must say which theorem it certifies):

* every theorem records its :class:`Provider` (distribution, version, entry point);
* an id offered by two providers is **ambiguous**: every use of it is refused (one line naming
  both providers and versions), other ids keep working; nothing is decided by load order;
* plugin code that fails while loading (any exception, including ``SystemExit``; only
  ``KeyboardInterrupt`` passes) is recorded as a :class:`BrokenPlugin` by name and never ends
  the process; ``unknown theorem`` errors name the plugins that failed to load;
* :func:`register` (the notebook route) accepts the same object twice and replaces a theorem it
  registered itself earlier, but never an installed plugin's theorem.

Examples
--------
>>> ids = [t.id for t in list_theorems()]
>>> "qib.thm1" in ids
True
>>> get_theorem("qib.thm1").provider.distribution
'lmic'
"""

from __future__ import annotations

import contextlib
import difflib
import os
import sys
import types
from dataclasses import dataclass, field
from importlib.metadata import entry_points
from typing import Any

from lmic.errors import DataError, LmicError
from lmic.template.theorem import Provider, Theorem

__all__ = [
    "Registry",
    "BrokenPlugin",
    "Conflict",
    "Provider",
    "get_theorem",
    "list_theorems",
    "broken_plugins",
    "conflicts",
    "register",
    "REGISTRY",
]

GROUP = "lmic.theorems"


@dataclass
class BrokenPlugin:
    """A plugin that failed to load, with the reason (one line)."""

    name: str
    reason: str


@dataclass
class Conflict:
    """A theorem id offered by several providers: refused until one is uninstalled."""

    id: str
    providers: list[Provider] = field(default_factory=list)

    def message(self) -> str:
        """One line naming every provider.

        >>> print(Conflict("a.b", [Provider("p", "1.0", "x = p"), Provider("q", "2", "y = q")]).message())
        ... # doctest: +NORMALIZE_WHITESPACE
        theorem id 'a.b' is ambiguous: provided by p 1.0 (entry point x = p) and q 2 (entry point y = q);
        uninstall one of them
        """
        who = " and ".join(p.describe() for p in self.providers)
        return f"theorem id '{self.id}' is ambiguous: provided by {who}; uninstall one of them"


def _one_line(err: BaseException) -> str:
    text = " ".join(str(err).split())
    if isinstance(err, SystemExit):
        return f"SystemExit({err.code!r}) raised while loading"
    return f"{type(err).__name__}: {text}" if text else type(err).__name__


def _not_a_theorem(obj: Any) -> str:
    if isinstance(obj, types.FunctionType):
        where = f" ({obj.__code__.co_filename}:{obj.__code__.co_firstlineno})"
        return (
            f"'{obj.__name__}'{where} is a plain function, not a Theorem: "
            "decorate it with @theorem(id=..., title=..., citation=...)"
        )
    return f"{type(obj).__name__} {obj!r:.60} is not a Theorem"


def _provider(ep: Any) -> Provider:
    dist = getattr(ep, "dist", None)
    name = getattr(dist, "name", None) or getattr(getattr(dist, "metadata", None) or {}, "get", lambda k: None)("Name")
    return Provider(str(name or "unknown"), str(getattr(dist, "version", None) or "unknown"), f"{ep.name} = {ep.value}")


class Registry:
    """Theorems by id, loaded lazily from entry points."""

    def __init__(self) -> None:
        self._theorems: dict[str, Theorem] = {}
        self._conflicts: dict[str, Conflict] = {}
        self._broken: list[BrokenPlugin] = []
        self._loaded = False

    def register(self, thm: Theorem, plugin: str = "<api>", provider: Provider | None = None) -> None:
        """Add a theorem.

        The same object twice is a no-op; a theorem registered from the API replaces an earlier
        API registration of the same id (re-running a notebook cell). Otherwise a duplicate id
        raises :class:`LmicError` naming both providers.
        """
        self.load()
        if not isinstance(thm, Theorem):
            raise LmicError(f"plugin {plugin}: {_not_a_theorem(thm)}")
        provider = provider or Provider.api(thm)
        old = self._theorems.get(thm.id)
        if old is thm:
            return
        if old is not None and not (provider.is_api and old.provider is not None and old.provider.is_api):
            assert old.provider is not None
            raise LmicError(Conflict(thm.id, [old.provider, provider]).message())
        if thm.id in self._conflicts:
            raise LmicError(self._conflicts[thm.id].message())
        thm.plugin = plugin
        thm.provider = provider
        self._theorems[thm.id] = thm

    def _collect(self, obj: Any) -> list[Any]:
        if isinstance(obj, Theorem):
            return [obj]
        if isinstance(obj, types.ModuleType):
            if hasattr(obj, "THEOREMS"):
                return list(obj.THEOREMS)
            return [v for v in vars(obj).values() if isinstance(v, Theorem)]
        if isinstance(obj, list | tuple):
            return list(obj)
        if callable(obj) and not isinstance(obj, types.FunctionType | type):
            return list(obj())
        if isinstance(obj, types.FunctionType) and obj.__code__.co_argcount == 0:
            return list(obj())
        raise LmicError(_not_a_theorem(obj))

    def load(self) -> None:
        """Discover plugins once (unless disabled by ``LMIC_DISABLE_PLUGIN_AUTOLOAD``).

        Plugin code runs here: anything it raises (``SystemExit`` included, ``KeyboardInterrupt``
        excepted) marks that plugin broken and loading goes on.
        """
        if self._loaded:
            return
        self._loaded = True
        if os.environ.get("LMIC_DISABLE_PLUGIN_AUTOLOAD"):
            return
        offers: dict[str, list[tuple[Theorem, str, Provider]]] = {}
        seen: set[tuple[str, str]] = set()
        for ep in sorted(entry_points(group=GROUP), key=lambda e: (e.name, e.value)):
            if (ep.name, ep.value) in seen:  # the same entry point twice (two installs of one dist)
                continue
            seen.add((ep.name, ep.value))
            name = f"{ep.name} ({ep.value})"
            provider = _provider(ep)
            try:
                with contextlib.redirect_stdout(sys.stderr):  # plugin code never prints into lmic's output
                    thms = self._collect(ep.load())
                for thm in thms:
                    if not isinstance(thm, Theorem):
                        raise LmicError(_not_a_theorem(thm))
            except KeyboardInterrupt:
                raise
            except BaseException as err:  # noqa: BLE001 - plugin code never decides lmic's fate
                self._broken.append(BrokenPlugin(name, _one_line(err)))
                continue
            for thm in thms:
                offers.setdefault(thm.id, [])
                if not any(o[0] is thm for o in offers[thm.id]):
                    offers[thm.id].append((thm, name, provider))
        for tid, offered in offers.items():
            if len(offered) == 1:
                thm, name, provider = offered[0]
                thm.plugin, thm.provider = name, provider
                self._theorems[tid] = thm
            else:
                self._conflicts[tid] = Conflict(tid, [o[2] for o in offered])

    def get(self, theorem_id: str) -> Theorem:
        """The theorem with this id.

        Raises :class:`DataError` for an ambiguous id (naming the providers) and for an unknown
        id (with suggestions and the plugins that failed to load).
        """
        self.load()
        if theorem_id in self._conflicts:
            raise DataError(self._conflicts[theorem_id].message())
        if theorem_id in self._theorems:
            return self._theorems[theorem_id]
        close = difflib.get_close_matches(theorem_id, list(self._theorems), n=3)
        hint = f" (did you mean {', '.join(close)}?)" if close else " (see 'lmic theorems')"
        broken = ""
        if self._broken:
            broken = "; plugins that failed to load: " + "; ".join(f"{b.name}: {b.reason}" for b in self._broken)
        raise DataError(f"unknown theorem '{theorem_id}'{hint}{broken}")

    def all(self) -> list[Theorem]:
        """Every usable theorem (ambiguous ids left out), sorted by id."""
        self.load()
        return [self._theorems[k] for k in sorted(self._theorems)]

    def broken(self) -> list[BrokenPlugin]:
        """Plugins that failed to load."""
        self.load()
        return list(self._broken)

    def conflicts(self) -> list[Conflict]:
        """Ids offered by several providers (each refused)."""
        self.load()
        return [self._conflicts[k] for k in sorted(self._conflicts)]


REGISTRY = Registry()


def get_theorem(theorem_id: str) -> Theorem:
    """The registered theorem ``theorem_id``.

    >>> get_theorem("thesis.lyapunov").id
    'thesis.lyapunov'
    """
    return REGISTRY.get(theorem_id)


def list_theorems() -> list[Theorem]:
    """Every registered theorem (ambiguous ids left out).

    >>> len(list_theorems()) > 10
    True
    """
    return REGISTRY.all()


def broken_plugins() -> list[BrokenPlugin]:
    """Plugins that failed to load, with reasons.

    >>> isinstance(broken_plugins(), list)
    True
    """
    return REGISTRY.broken()


def conflicts() -> list[Conflict]:
    """Theorem ids offered by several providers (refused by every command).

    >>> isinstance(conflicts(), list)
    True
    """
    return REGISTRY.conflicts()


def register(thm: Theorem) -> Theorem:
    """Register a theorem from Python (e.g. in a notebook); returns it.

    Registering the same object again, or a new version of a theorem registered this way (a
    re-run notebook cell), is fine; an id an installed plugin provides is refused.

    >>> from lmic.template import theorem
    >>> @theorem(id="nb.demo", title="t", citation="c")
    ... def demo(t):
    ...     (n,) = t.dims("n")
    ...     t.symmetric("P", n, pd=True)
    >>> register(demo) is register(demo)
    True
    """
    REGISTRY.load()
    REGISTRY.register(thm)
    return thm
