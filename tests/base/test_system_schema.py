"""schemas/system.schema.json describes every shipped system file, and rejects bad ones."""

from __future__ import annotations

from pathlib import Path

import jsonschema
import pytest
import yaml
from referencing import Registry, Resource

from lmic.schemas import load_schema

ROOT = Path(__file__).resolve().parents[2]


def _validator():
    system = load_schema("system")
    simulation = load_schema("simulation")
    registry = Registry().with_resources(
        [(s["$id"], Resource.from_contents(s)) for s in (system, simulation)]
        + [("simulation.schema.json", Resource.from_contents(simulation))]
    )
    return jsonschema.Draft202012Validator(system, registry=registry)


@pytest.mark.parametrize("path", sorted((ROOT / "examples").glob("*.yaml")), ids=lambda p: p.name)
def test_every_shipped_example_follows_the_schema(path):
    doc = yaml.safe_load(path.read_text())
    if "data" not in doc:  # examples/reproduction.yaml is not a system file
        pytest.skip("not a system file")
    errors = sorted(_validator().iter_errors(doc), key=str)
    assert not errors, f"{path.name}: {errors[0].message}"


@pytest.mark.parametrize(
    "doc",
    [
        {"lmic": 1},
        {"lmic": 2, "data": {"A": [[1]]}},
        {"data": {"A": [1, 2]}},
        {"data": {"A": [[1, "x"]]}},
        {"data": {"A": [[1]]}, "params": {"beta": [1, 2]}},
    ],
)
def test_bad_system_files_fail_the_schema(doc):
    assert list(_validator().iter_errors(doc))
