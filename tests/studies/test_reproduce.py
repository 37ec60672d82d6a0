"""lmic.studies.reproduce: the expectations file, a subset run, and the committed docs/reproduction.md."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

from lmic.errors import DataError
from lmic.present.reproduction import render_markdown
from lmic.studies.reproduce import Row, load_expectations, reproduce, theorem_of

ROOT = Path(__file__).resolve().parents[2]
EX = ROOT / "examples"
SPEC = load_expectations(EX / "reproduction.yaml")
FILES = sorted(p.name for p in EX.glob("*.yaml") if p.name != "reproduction.yaml")


def test_theorem_of_parses_family_item_name():
    assert theorem_of("thesis.thm3_2_1.ex3_2_1.yaml") == "thesis.thm3_2_1"
    assert theorem_of("nonuniform.thm1.chua-gamma2.95.yaml") == "nonuniform.thm1"
    with pytest.raises(DataError):
        theorem_of("reproduction.yaml")


def test_every_example_has_expectations_and_every_expectation_an_example():
    assert sorted(SPEC) == FILES


def _covered(rows: list[Row]) -> set[str]:
    words: set[str] = set()
    for r in rows:
        for v in r.compute.values():
            if isinstance(v, str):
                words.add(v)
        words.update(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", r.quantity))
    return words


@pytest.mark.parametrize("file", FILES)
def test_every_published_key_has_a_row_with_a_catalogue_reference(file):
    raw = yaml.safe_load((EX / file).read_text())
    published = set(raw.get("published") or {})
    rows = SPEC[file]
    missing = published - _covered(rows)
    assert not missing, f"{file}: published {sorted(missing)} not covered by examples/reproduction.yaml"
    for r in rows:
        assert r.catalogue, f"{file}: {r.quantity!r} has no catalogue reference"
        assert re.search(r"lines? \d+", r.catalogue), f"{file}: {r.quantity!r}: cite the catalogue line"
        if r.reference is not None and not isinstance(r.reference, str):
            assert r.tol is not None and r.tol > 0, f"{file}: {r.quantity!r}: a numeric reference needs tol"
        agrees = r.verdict == "infeasible" and "infeasible" in str(r.published)
        if r.published not in (None, "-") and r.verdict in ("infeasible", "differs", "rejected") and not agrees:
            assert r.explanation, f"{file}: {r.quantity!r}: explain why the published value is not reproduced"


def test_expectation_file_errors(tmp_path):
    bad = tmp_path / "r.yaml"
    bad.write_text("examples: {a.b.c.yaml: [{quantity: q}]}\n")
    with pytest.raises(DataError, match="needs 'quantity' and 'compute'"):
        load_expectations(bad)
    bad.write_text("examples: {a.b.c.yaml: [{quantity: q, compute: {solve: {}}, verdict: maybe}]}\n")
    with pytest.raises(DataError, match="verdict 'maybe'"):
        load_expectations(bad)
    bad.write_text("examples: {a.b.c.yaml: [{quantity: q, compute: {guess: 1}}]}\n")
    with pytest.raises(DataError, match="compute needs one of"):
        load_expectations(bad)
    bad.write_text("nothing: 1\n")
    with pytest.raises(DataError, match="'examples' section"):
        load_expectations(bad)


def test_reproduce_subset_agrees_with_the_catalogues():
    only = ["qib.thm1.*", "thesis.lyapunov.*", "sampled_euler.thm4.*", "uncertain_dt.thm1.*", "delay_a.*"]
    rep = reproduce(EX, only=only)
    files = {r.row.file for r in rep.results}
    assert files == {
        f
        for f in FILES
        if f.startswith(("qib.thm1", "thesis.lyapunov", "sampled_euler.thm4", "uncertain_dt.thm1", "delay_a"))
    }
    bad = [(r.row.file, r.row.quantity, r.finding, r.value, r.detail) for r in rep.results if not r.ok]
    assert not bad
    by = {(r.row.file, r.row.quantity): r for r in rep.results}
    assert by[("qib.thm1.flexible-joint.yaml", "published (P, R, omega) in LMI (7), lambda_max")].value == (
        pytest.approx(-0.05581, abs=1e-4)
    )
    assert by[("sampled_euler.thm4.example.yaml", "published L as a Theorem-1 gain (gamma_d = 0.06109)")].finding == (
        "certified"
    )
    assert by[("sampled_euler.thm4.example.yaml", "gamma_d* of Theorem 2 at the published L (fixed_L)")].value == (
        pytest.approx(0.066211, abs=1e-5)
    )
    assert rep.exit_code() == 0 and not rep.missing and not rep.unlisted
    md = render_markdown(rep)
    assert md.count("| yes |") == len(rep.results) and "### `qib.thm1.flexible-joint.yaml`" in md


def test_a_wrong_expectation_is_reported(tmp_path):
    spec = {
        "examples": {
            "thesis.lyapunov.ex2_3_2.yaml": [
                {
                    "quantity": "P",
                    "compute": {"claim": "P", "lmi": "(2.9)"},
                    "reference": -5.0,
                    "tol": 1e-3,
                    "verdict": "certified",
                    "catalogue": "T1.1 line 79",
                },
                {"quantity": "status", "compute": {"solve": {}}, "verdict": "infeasible", "catalogue": "x line 1"},
                {"quantity": "no such LMI", "compute": {"claim": "P", "lmi": "(9.9)"}, "catalogue": "x line 1"},
            ]
        }
    }
    f = tmp_path / "r.yaml"
    f.write_text(yaml.safe_dump(spec))
    rep = reproduce(EX, f, only=["thesis.lyapunov.*"])
    value, status, error = rep.results
    assert (value.verdict_ok, value.value_ok) == (True, False) and value.value == pytest.approx(-1.229, abs=1e-3)
    assert (status.finding, status.verdict_ok) == ("certified", False)
    assert error.finding == "error" and "(9.9)" in error.detail
    assert rep.exit_code() == 1


def test_committed_docs_reproduction_md_is_current():
    """docs/reproduction.md is generated from the expectations: one row per expectation, all agreeing."""
    text = (ROOT / "docs" / "reproduction.md").read_text()
    rows = [ln for ln in text.splitlines() if ln.startswith("| ") and not ln.startswith("| quantity")]
    assert len(rows) == sum(len(v) for v in SPEC.values())
    assert all(ln.rstrip().split(" | ")[-2] == "yes" for ln in rows)
    for file, spec_rows in SPEC.items():
        assert f"### `{file}`" in text
        for r in spec_rows:
            assert r.quantity.replace("|", "\\|") in text, (file, r.quantity)
