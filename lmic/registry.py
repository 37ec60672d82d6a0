"""Theorem plugins, discovered through the entry-point group ``lmic.theorems``.

Built-in theorems (``plugins/lmic_observers``) register through the same group as any
third-party package. An entry point names a module (its module-level :class:`Theorem` objects,
or a ``THEOREMS`` list, are registered), a :class:`Theorem`, a list of them, or a callable
returning a list. Duplicate ids are rejected and a broken plugin is reported by name without
breaking the others. ``LMIC_DISABLE_PLUGIN_AUTOLOAD=1`` turns discovery off (then register
theorems with :func:`register`).

Examples
--------
>>> ids = [t.id for t in list_theorems()]
>>> "qib.thm1" in ids
True
"""

from __future__ import annotations

import difflib
import os
import types
from dataclasses import dataclass
from importlib.metadata import entry_points
from typing import Any

from lmic.errors import DataError, LmicError
from lmic.template.theorem import Theorem

__all__ = ["Registry", "BrokenPlugin", "get_theorem", "list_theorems", "broken_plugins", "register", "REGISTRY"]

GROUP = "lmic.theorems"


@dataclass
class BrokenPlugin:
    """A plugin that failed to load (or clashed), with the reason."""

    name: str
    reason: str


class Registry:
    """Theorems by id, loaded lazily from entry points."""

    def __init__(self) -> None:
        self._theorems: dict[str, Theorem] = {}
        self._broken: list[BrokenPlugin] = []
        self._loaded = False

    def register(self, thm: Theorem, plugin: str = "<api>") -> None:
        """Add a theorem; a duplicate id raises :class:`LmicError` naming both plugins."""
        if not isinstance(thm, Theorem):
            raise LmicError(f"plugin {plugin}: {thm!r} is not a Theorem")
        if thm.id in self._theorems:
            other = self._theorems[thm.id].plugin
            raise LmicError(f"theorem id '{thm.id}' is registered by both {other} and {plugin}")
        thm.plugin = plugin
        self._theorems[thm.id] = thm

    def _collect(self, obj: Any, plugin: str) -> list[Theorem]:
        if isinstance(obj, Theorem):
            return [obj]
        if isinstance(obj, types.ModuleType):
            if hasattr(obj, "THEOREMS"):
                return list(obj.THEOREMS)
            return [v for v in vars(obj).values() if isinstance(v, Theorem)]
        if isinstance(obj, list | tuple):
            return list(obj)
        if callable(obj):
            return list(obj())
        raise LmicError(f"entry point does not give theorems ({type(obj).__name__})")

    def load(self) -> None:
        """Discover plugins once (unless disabled by ``LMIC_DISABLE_PLUGIN_AUTOLOAD``)."""
        if self._loaded:
            return
        self._loaded = True
        if os.environ.get("LMIC_DISABLE_PLUGIN_AUTOLOAD"):
            return
        for ep in sorted(entry_points(group=GROUP), key=lambda e: e.name):
            name = f"{ep.name} ({ep.value})"
            try:
                thms = self._collect(ep.load(), name)
                for thm in thms:
                    if not isinstance(thm, Theorem):
                        raise LmicError(f"{thm!r} is not a Theorem")
            except Exception as err:  # a broken plugin must not break the others
                self._broken.append(BrokenPlugin(name, f"{type(err).__name__}: {err}"))
                continue
            for thm in thms:
                try:
                    self.register(thm, name)
                except LmicError as err:
                    self._broken.append(BrokenPlugin(name, str(err)))

    def get(self, theorem_id: str) -> Theorem:
        """The theorem with this id; an unknown id raises :class:`DataError` with suggestions."""
        self.load()
        if theorem_id in self._theorems:
            return self._theorems[theorem_id]
        close = difflib.get_close_matches(theorem_id, list(self._theorems), n=3)
        hint = f" (did you mean {', '.join(close)}?)" if close else " (see 'lmic theorems')"
        raise DataError(f"unknown theorem '{theorem_id}'{hint}")

    def all(self) -> list[Theorem]:
        """Every registered theorem, sorted by id."""
        self.load()
        return [self._theorems[k] for k in sorted(self._theorems)]

    def broken(self) -> list[BrokenPlugin]:
        """Plugins that failed to load."""
        self.load()
        return list(self._broken)


REGISTRY = Registry()


def get_theorem(theorem_id: str) -> Theorem:
    """The registered theorem ``theorem_id``."""
    return REGISTRY.get(theorem_id)


def list_theorems() -> list[Theorem]:
    """Every registered theorem."""
    return REGISTRY.all()


def broken_plugins() -> list[BrokenPlugin]:
    """Plugins that failed to load, with reasons."""
    return REGISTRY.broken()


def register(thm: Theorem) -> Theorem:
    """Register a theorem from Python (e.g. in a notebook); returns it."""
    REGISTRY.load()
    REGISTRY.register(thm)
    return thm
