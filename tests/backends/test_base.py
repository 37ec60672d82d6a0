"""lmic.backends.base is a deprecated alias module: every old public name still resolves, to the
object of the module it moved to."""

from __future__ import annotations

import importlib

import pytest

MOVED = {
    "SolveOptions": "lmic.options",
    "Backend": "lmic.backends.backend",
    "ConicData": "lmic.backends.lowering",
    "conic_data": "lmic.backends.lowering",
    "problem_kinds": "lmic.backends.lowering",
    "full_vec_map": "lmic.backends.lowering",
    "full_vec_coo": "lmic.backends.lowering",
    "quiet_native": "lmic.backends.quiet",
    "eliminate_unused": "lmic.reductions.eliminate",
    "independent_columns": "lmic.reductions.eliminate",
    "restore_eliminated": "lmic.reductions.eliminate",
}


@pytest.mark.parametrize("name", sorted(MOVED))
def test_old_names_resolve_to_the_moved_objects(name):
    base = importlib.import_module("lmic.backends.base")
    assert getattr(base, name) is getattr(importlib.import_module(MOVED[name]), name)


def test_other_alias_modules():
    from lmic.backends import outcomes, strict
    from lmic.reductions import pipeline
    from lmic.reductions import strict as reductions_strict

    assert strict.plan is reductions_strict.plan and strict._max_margin is reductions_strict._max_margin
    assert outcomes.settle_inexact_infeasible is pipeline.settle_inexact_infeasible
    with pytest.raises(AttributeError):
        _ = strict.no_such_name
