"""lmic batch --status on a study folder whose files were edited or damaged: one line, exit 2."""

from __future__ import annotations

import json

import pytest

from lmic.cli import main
from lmic.studies.report import status

GOOD = {"name": "s", "task": "solve", "total": 2, "jobs": [{"hash": "a" * 64}, {"hash": "b" * 64}]}
RECORD = {"hash": "a" * 64, "outcome": "certified", "finished_at": "2026-01-01T00:00:00Z"}


def _folder(tmp_path, manifest, records):
    (tmp_path / "study.json").write_text(json.dumps(manifest))
    (tmp_path / "results.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))
    return str(tmp_path)


def test_a_good_folder_is_summarised(tmp_path):
    st = status(_folder(tmp_path, GOOD, [RECORD, {"x": 1}, {"hash": "c" * 64, "outcome": "error"}]))
    assert (st["total"], st["done"], st["counts"]["certified"]) == (2, 1, 1)  # unknown jobs and junk ignored


@pytest.mark.parametrize(
    "damage", [{"outcome": ["weird"]}, {"outcome": "great"}, {"finished_at": None}, {"params": "x"}]
)
def test_a_damaged_record_counts_as_not_done(tmp_path, damage):
    good_b = {**RECORD, "hash": "b" * 64}
    st = status(_folder(tmp_path, GOOD, [{**RECORD, **damage}, good_b]))
    assert st["done"] == 1 and [r["hash"] for r in st["records"]] == ["b" * 64]


@pytest.mark.parametrize(
    ("manifest", "records", "fragment"),
    [
        ([], [], "study.json is not a study manifest"),
        ({**GOOD, "jobs": 5}, [], "study.json is not a study manifest"),
        ({**GOOD, "jobs": [{"hash": 3}]}, [], "study.json is not a study manifest"),
    ],
)
def test_a_damaged_folder_is_one_line_exit_2(tmp_path, capsys, manifest, records, fragment):
    assert main(["batch", "--status", _folder(tmp_path, manifest, records)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("lmic: error:") and fragment in err
