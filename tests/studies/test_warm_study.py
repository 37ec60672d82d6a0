"""Loading a study without sympy when an earlier process analysed its theorem (lmic.compile.warm).

The truth is the same study loaded by a cold process (an empty cache: the plugin imported, the
template built with sympy): the warm load must expand the same jobs (hashes cover the theorem's
template hash, the random plants' data and the parameters), refuse the same bad values, and
import no sympy. A batch run on a warm cache is checked through the runners' certifier (its
outcomes) against the cold run's.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

from study_helpers import REPO, env, lines

STUDY = REPO / "examples" / "studies" / "qib_monte_carlo.yaml"

LOAD = textwrap.dedent(
    """
    import json, sys
    from lmic.errors import DataError
    from lmic.studies.spec import load_study
    study = load_study(sys.argv[1])
    try:
        load_study({"theorem": "qib.cor1", "task": "solve", "params": {"lambda": -0.5},
                    "systems": {"random": {"count": 1, "seed": 1, "dims": {"n": 2, "p": 1}}}})
        bad = None
    except DataError as err:
        bad = str(err)
    jsonschema = "jsonschema" in sys.modules
    try:
        load_study({"theorem": "qib.thm1", "task": "solve", "systems": {"random": {"count": 0}}, "colour": 1})
        invalid = None
    except DataError as err:
        invalid = str(err)
    print(json.dumps({"hashes": [j.hash for j in study.jobs], "systems": [j.system for j in study.jobs[:3]],
                      "bad": bad, "invalid": invalid, "sympy": "sympy" in sys.modules, "jsonschema": jsonschema}))
    """
)


def _load(cache: Path) -> dict:
    e = {**env(), "LMIC_CACHE_DIR": str(cache)}
    e.pop("LMIC_NO_CACHE", None)
    out = subprocess.run([sys.executable, "-c", LOAD, str(STUDY)], env=e, capture_output=True, text=True, cwd=REPO)
    assert out.returncode == 0, out.stderr[-1500:]
    return json.loads(out.stdout)


def test_a_warm_study_load_imports_no_sympy_and_expands_the_same_jobs(tmp_path):
    cache = tmp_path / "cache"
    cold = _load(cache)
    warm = _load(cache)
    assert cold["sympy"] is True and warm["sympy"] is False
    assert len(cold["hashes"]) == 200 and warm["hashes"] == cold["hashes"]
    assert warm["systems"] == cold["systems"]
    # a parameter outside its declared domain (lambda > 0): the same one line
    assert "outside its domain" in cold["bad"] and warm["bad"] == cold["bad"]
    # a document that passed the schema once is not validated again (jsonschema not imported);
    # one that fails is never remembered: the same one line every time
    assert cold["jsonschema"] is True and warm["jsonschema"] is False
    assert cold["invalid"] and warm["invalid"] == cold["invalid"]


def test_a_warm_batch_gives_the_cold_outcomes(tmp_path):
    cache = tmp_path / "cache"
    e = {**env(), "LMIC_CACHE_DIR": str(cache)}
    e.pop("LMIC_NO_CACHE", None)
    study = tmp_path / "s.yaml"
    study.write_text(STUDY.read_text().replace("count: 200", "count: 12"))
    runs = []
    for k in range(2):
        out = tmp_path / f"out{k}"
        cmd = [sys.executable, "-m", "lmic.cli", "batch", str(study), "-o", str(out), "--workers", "2", "--no-progress"]
        proc = subprocess.run(cmd, env=e, capture_output=True, text=True, cwd=REPO)
        assert proc.returncode == 0, proc.stderr[-1500:]
        runs.append({r["hash"]: r["outcome"] for r in lines(out)})
    assert len(runs[0]) == 12 and runs[1] == runs[0]
    assert set(runs[0].values()) <= {"certified", "infeasible-certified"}  # each decided by the certifier
    assert any(p.name == "frozen" for p in cache.iterdir()) and os.listdir(cache / "frozen")
