"""Backend discovery: entry points, validation, broken and duplicate plugins, autoload switch."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from lmic.backends import registry
from lmic.backends.base import Backend
from lmic.backends.clarabel import ClarabelBackend
from lmic.errors import BackendUnavailable

BUILTINS = {"clarabel", "scs", "cvxopt", "sdpa", "cvxpy", "picos", "auto"}


@pytest.fixture(autouse=True)
def _fresh_registry():
    registry.reset()
    yield
    registry.reset()


def _fake_eps(monkeypatch, extra):
    real = registry.entry_points

    def fake(group):
        eps = list(real(group=group))
        eps += [SimpleNamespace(name=n, value=v) for n, v in extra]
        return eps

    monkeypatch.setattr(registry, "entry_points", fake)


def test_builtins_are_discovered_through_entry_points():
    from importlib.metadata import entry_points

    names = {ep.name for ep in entry_points(group=registry.ENTRY_POINT_GROUP)}
    assert BUILTINS <= names
    assert BUILTINS <= set(registry.backend_classes())
    assert registry.broken_backends() == {}


def test_get_backend_and_variants():
    assert isinstance(registry.get_backend("clarabel"), ClarabelBackend)
    assert registry.get_backend("cvxpy").label == "cvxpy:CLARABEL"
    assert registry.get_backend("cvxpy:scs").label == "cvxpy:SCS"
    assert "cvxpy:CVXOPT" in registry.available_backend_names(expand_variants=True)


def test_unknown_backend_names_the_available_ones():
    with pytest.raises(BackendUnavailable, match="unknown backend 'mosek'.*clarabel.*scs"):
        registry.get_backend("mosek")
    with pytest.raises(BackendUnavailable, match="no ':FOO' variant|takes no"):
        registry.get_backend("clarabel:FOO")
    with pytest.raises(BackendUnavailable, match="sub-solver"):
        registry.get_backend("cvxpy:MOSEK")


class _Missing(Backend):
    name = "missingsolver"
    requires = {"no_such_module_lmic_test": "no-such-solver-pkg"}
    STATUS_MAP = {"ok": "optimal"}

    def _solve(self, problem, options):  # pragma: no cover - never reached
        raise AssertionError


class _BadStatus(Backend):
    name = "badstatus"
    STATUS_MAP = {"ok": "great"}

    def _solve(self, problem, options):  # pragma: no cover
        raise AssertionError


def test_missing_package_is_named(monkeypatch):
    _fake_eps(monkeypatch, [("missingsolver", "tests.backends.test_registry:_Missing")])
    with pytest.raises(BackendUnavailable, match="pip install no-such-solver-pkg"):
        registry.get_backend("missingsolver")
    info = {i.name: i for i in registry.backend_infos()}["missingsolver"]
    assert not info.available and info.missing == ["no-such-solver-pkg"]


def test_broken_plugin_is_reported_and_others_still_work(monkeypatch):
    _fake_eps(
        monkeypatch,
        [
            ("ghost", "no_such_package_lmic.mod:Backend"),
            ("badstatus", "tests.backends.test_registry:_BadStatus"),
        ],
    )
    broken = registry.broken_backends()
    assert "ghost" in broken and "ModuleNotFoundError" in broken["ghost"]
    assert "unknown words" in broken["badstatus"]
    assert "clarabel" in registry.backend_classes()
    with pytest.raises(BackendUnavailable, match="ghost.*failed to load"):
        registry.get_backend("ghost")


def test_duplicate_name_is_rejected(monkeypatch):
    _fake_eps(monkeypatch, [("clarabel", "tests.backends.test_registry:_Missing")])
    assert registry.backend_classes()["clarabel"] is ClarabelBackend
    assert any("duplicate backend name 'clarabel'" in m for m in registry.broken_backends().values())


def test_autoload_can_be_disabled(monkeypatch):
    _fake_eps(monkeypatch, [("missingsolver", "tests.backends.test_registry:_Missing")])
    monkeypatch.setenv(registry.DISABLE_AUTOLOAD_ENV, "1")
    classes = registry.backend_classes()
    assert "missingsolver" not in classes and BUILTINS <= set(classes)


def test_explicit_register_validates():
    registry.register(_Missing)
    assert registry.backend_classes()["missingsolver"] is _Missing
    with pytest.raises(BackendUnavailable, match="duplicate"):
        registry.register(type("Other", (_Missing,), {}))
    with pytest.raises(TypeError, match="unknown words"):
        registry.register(_BadStatus)
