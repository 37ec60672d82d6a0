"""Theorem discovery through entry points: duplicates rejected, broken plugins reported."""

from __future__ import annotations

import types

import pytest

from lmic.errors import DataError, LmicError
from lmic.registry import Registry, get_theorem, list_theorems
from lmic.template import block, theorem


def _make(tid):
    @theorem(id=tid, title="t", citation="c")
    def build(t):
        (n,) = t.dims("n")
        P = t.symmetric("P", n)
        t.lmi("P", block(P) > 0)

    return build


class _EP:
    def __init__(self, name, obj=None, error=None):
        self.name, self.value, self._obj, self._error = name, f"pkg.{name}", obj, error

    def load(self):
        if self._error:
            raise self._error
        return self._obj


def _registry_with(monkeypatch, eps):
    import lmic.registry as reg

    monkeypatch.setattr(reg, "entry_points", lambda group: eps)
    return Registry()


def test_builtin_plugins_are_discovered_through_entry_points():
    ids = [t.id for t in list_theorems()]
    assert {"qib.thm1", "thesis.lyapunov"} <= set(ids)
    assert get_theorem("qib.thm1").plugin.startswith("qib (lmic_observers.qib)")


def test_unknown_theorem_suggests_close_ids():
    with pytest.raises(DataError, match=r"unknown theorem 'qib.thm9' \(did you mean .*qib.thm1"):
        get_theorem("qib.thm9")


def test_broken_plugin_is_reported_by_name_without_breaking_others(monkeypatch):
    good = types.ModuleType("good")
    good.THEOREMS = [_make("fam.ok")]
    reg = _registry_with(monkeypatch, [_EP("good", good), _EP("bad", error=ImportError("no module named x"))])
    assert [t.id for t in reg.all()] == ["fam.ok"]
    (broken,) = reg.broken()
    assert broken.name == "bad (pkg.bad)" and "ImportError: no module named x" in broken.reason


def test_duplicate_ids_are_rejected_naming_both_plugins(monkeypatch):
    reg = _registry_with(monkeypatch, [_EP("a", [_make("fam.x")]), _EP("b", [_make("fam.x")])])
    assert [t.id for t in reg.all()] == ["fam.x"]
    assert "registered by both a (pkg.a) and b (pkg.b)" in reg.broken()[0].reason


def test_entry_point_giving_non_theorems_is_broken(monkeypatch):
    reg = _registry_with(monkeypatch, [_EP("junk", [42])])
    assert reg.all() == []
    assert "is not a Theorem" in reg.broken()[0].reason


def test_autoload_can_be_disabled(monkeypatch):
    monkeypatch.setenv("LMIC_DISABLE_PLUGIN_AUTOLOAD", "1")
    reg = Registry()
    assert reg.all() == []
    reg.register(_make("fam.manual"))
    assert [t.id for t in reg.all()] == ["fam.manual"]
    with pytest.raises(LmicError, match="registered by both"):
        reg.register(_make("fam.manual"))
