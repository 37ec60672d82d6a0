"""Theorem discovery through entry points: ambiguous ids refused, broken plugins reported."""

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


class _Dist:
    def __init__(self, name, version):
        self.name, self.version = name, version


class _EP:
    def __init__(self, name, obj=None, error=None, dist=("pkg", "1.0")):
        self.name, self.value, self._obj, self._error = name, f"pkg.{name}", obj, error
        self.dist = _Dist(*dist)

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


def test_duplicate_id_is_ambiguous_and_refused_naming_both_providers(monkeypatch):
    reg = _registry_with(
        monkeypatch,
        [
            _EP("a", [_make("fam.x"), _make("fam.y")], dist=("alpha", "1.2")),
            _EP("b", [_make("fam.x")], dist=("beta", "0.3")),
        ],
    )
    assert [t.id for t in reg.all()] == ["fam.y"]  # the other id keeps working
    with pytest.raises(DataError) as err:
        reg.get("fam.x")
    msg = str(err.value)
    assert (
        "ambiguous" in msg and "alpha 1.2 (entry point a = pkg.a)" in msg and "beta 0.3 (entry point b = pkg.b)" in msg
    )
    assert [c.id for c in reg.conflicts()] == ["fam.x"]
    # the verdict does not depend on the order the entry points come in
    reg2 = _registry_with(
        monkeypatch,
        [_EP("b", [_make("fam.x")], dist=("beta", "0.3")), _EP("a", [_make("fam.x")], dist=("alpha", "1.2"))],
    )
    with pytest.raises(DataError, match="ambiguous"):
        reg2.get("fam.x")


def test_the_same_theorem_object_from_two_entry_points_is_not_a_conflict(monkeypatch):
    thm = _make("fam.same")
    reg = _registry_with(monkeypatch, [_EP("a", [thm]), _EP("b", [thm])])
    assert reg.get("fam.same") is thm and reg.conflicts() == []


def test_provider_is_recorded(monkeypatch):
    reg = _registry_with(monkeypatch, [_EP("a", [_make("fam.p")], dist=("alpha", "1.2"))])
    p = reg.get("fam.p").provider
    assert (p.distribution, p.version, p.entry_point) == ("alpha", "1.2", "a = pkg.a")
    assert get_theorem("qib.thm1").provider.distribution == "lmic"


@pytest.mark.parametrize("exc", [SystemExit(0), SystemExit(3), GeneratorExit(), RuntimeError("boom")])
def test_plugin_raising_anything_but_keyboardinterrupt_is_broken_not_fatal(monkeypatch, exc):
    good = types.ModuleType("good")
    good.THEOREMS = [_make("fam.ok")]
    reg = _registry_with(monkeypatch, [_EP("aaa", error=exc), _EP("good", good)])
    assert [t.id for t in reg.all()] == ["fam.ok"]
    (broken,) = reg.broken()
    assert broken.name == "aaa (pkg.aaa)" and type(exc).__name__ in broken.reason


def test_keyboardinterrupt_while_loading_passes(monkeypatch):
    reg = _registry_with(monkeypatch, [_EP("aaa", error=KeyboardInterrupt())])
    with pytest.raises(KeyboardInterrupt):
        reg.all()


def test_unknown_theorem_names_the_plugins_that_failed_to_load(monkeypatch):
    reg = _registry_with(monkeypatch, [_EP("bad", error=ImportError("no module named scipyy"))])
    with pytest.raises(DataError, match=r"unknown theorem 'bad.thm1'.*failed to load: bad \(pkg.bad\): ImportError"):
        reg.get("bad.thm1")


def test_undecorated_function_is_named_with_a_hint(monkeypatch):
    def build(t):
        pass

    reg = _registry_with(monkeypatch, [_EP("plain", [build])])
    reg.all()
    reason = reg.broken()[0].reason
    assert "'build'" in reason and "plain function" in reason and "@theorem(" in reason


def test_entry_point_giving_non_theorems_is_broken(monkeypatch):
    reg = _registry_with(monkeypatch, [_EP("junk", [42])])
    assert reg.all() == []
    assert "is not a Theorem" in reg.broken()[0].reason


def test_autoload_can_be_disabled(monkeypatch):
    monkeypatch.setenv("LMIC_DISABLE_PLUGIN_AUTOLOAD", "1")
    reg = Registry()
    assert reg.all() == []
    thm = _make("fam.manual")
    reg.register(thm)
    assert [t.id for t in reg.all()] == ["fam.manual"]
    reg.register(thm)  # the same object again (a notebook) is fine
    again = _make("fam.manual")  # a re-run notebook cell replaces its own earlier theorem
    reg.register(again)
    assert reg.get("fam.manual") is again


def test_api_registration_never_replaces_an_installed_theorem(monkeypatch):
    reg = _registry_with(monkeypatch, [_EP("a", [_make("fam.x")], dist=("alpha", "1.2"))])
    with pytest.raises(LmicError, match="ambiguous.*alpha 1.2.*inline theorem"):
        reg.register(_make("fam.x"))
    assert reg.get("fam.x").provider.distribution == "alpha"
