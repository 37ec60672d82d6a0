"""The row kinds of ``lmic reproduce`` are registered handlers, and reproduce uses only public audit routes."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from lmic.errors import DataError
from lmic.studies.reproduce import HANDLERS, Row, register
from lmic.studies.reproduce.handlers import compute_row

ROOT = Path(__file__).resolve().parents[2]


def test_the_shipped_kinds_are_registered_in_precedence_order():
    # the if-chain this replaced tested these keys in this order (maximize before gain: a
    # maximize row with gain: bisects on the fixed-gain variant)
    assert list(HANDLERS)[:6] == ["claim", "solve", "at_published", "maximize", "sweep", "gain"]


def test_a_new_kind_is_one_registered_function(tmp_path):
    seen = []

    @register("constant_for_test")
    def _constant(runner, row):
        seen.append((runner, row.quantity))
        return "certified", float(row.compute["constant_for_test"]), "2.5", "made up"

    try:
        row = Row.from_dict("thesis.lyapunov.x.yaml", {"quantity": "q", "compute": {"constant_for_test": 2.5}})
        assert compute_row("RUNNER", row) == ("certified", 2.5, "2.5", "made up")
        assert seen == [("RUNNER", "q")]
        with pytest.raises(ValueError, match="already registered"):
            register("constant_for_test")(_constant)
    finally:
        del HANDLERS["constant_for_test"]
    with pytest.raises(DataError, match="compute needs one of"):
        Row.from_dict("thesis.lyapunov.x.yaml", {"quantity": "q", "compute": {"constant_for_test": 2.5}})


def test_reproduce_imports_no_private_name_of_the_audit():
    audit_modules = ("lmic.studies.published", "lmic.published")
    imported: set[str] = set()
    for path in (ROOT / "lmic" / "studies" / "reproduce").glob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith(audit_modules):
                imported |= {a.name for a in node.names}
                private = [a.name for a in node.names if a.name.startswith("_")]
                assert not private, f"{path.name} imports {private} from {node.module}"
            if isinstance(node, ast.Attribute) and node.attr in ("_compare", "_Auditor"):
                pytest.fail(f"{path.name} uses {node.attr}")
    # the audit is used (claim and at_published rows), through its public names
    assert {"audit_published", "AuditContext", "compare_value", "point_claims"} <= imported
