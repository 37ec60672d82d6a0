"""Study files: validation before any job runs, grids, samples, random plants, job hashes."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from study_helpers import REPO, env, write_study

from lmic.errors import DataError
from lmic.studies.spec import expand_axis, load_study

RANDOM = {"count": 3, "seed": 1, "dims": {"n": 3, "p": 1}}


def _cli(*args: str, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "lmic.cli", *args], env=env(), capture_output=True, text=True, timeout=120, cwd=cwd
    )


@pytest.mark.parametrize(
    ("study", "message"),
    [
        ({"theorem": "no.such", "systems": {"random": RANDOM}}, "theorem 'no.such' is not registered"),
        ({"theorem": "qib.thm1", "systems": {"files": ["missing.yaml"]}}, "'missing.yaml': no such file"),
        ({"theorem": "qib.thm1", "systems": {"files": ["nothing*.yaml"]}}, "matches no file"),
        ({"theorem": "qib.thm1", "systems": {"random": RANDOM}, "grid": {"beta": {"linspace": [0, 1]}}}, "grid/beta"),
        (
            {"theorem": "qib.thm1", "systems": {"random": RANDOM}, "grid": {"beta": {"logspace": [0, 1, 3]}}},
            "logspace bounds must be positive",
        ),
        (
            {"theorem": "qib.thm1", "systems": {"random": RANDOM}, "grid": {"zeta": [1, 2]}},
            "'zeta' is not a parameter of qib.thm1",
        ),
        (
            {
                "theorem": "obs_control.thm3_2",
                "systems": {"files": [str(REPO / "examples/obs_control.thm3_2.rossler_z.yaml")]},
                "grid": {"alpha": [0.0, 0.1]},
            },
            "'alpha' = 0 is outside its domain",
        ),
        ({"theorem": "qib.thm1", "systems": {"random": {**RANDOM, "dims": {"n": 3}}}}, "needs dims p"),
        ({"theorem": "qib.thm1", "systems": {"random": RANDOM}, "backends": ["nosuchsolver"]}, "backends:"),
        ({"theorem": "qib.thm1", "systems": {"random": RANDOM}, "task": "maximize"}, "needs maximize"),
        ({"theorem": "qib.thm1", "systems": {"random": RANDOM}, "colour": 1}, "Additional properties"),
    ],
)
def test_bad_study_is_one_line_exit_2_and_nothing_runs(tmp_path, study, message):
    path = write_study(tmp_path / "bad.yaml", {"lmic": 1, **study})
    out = tmp_path / "out"
    proc = _cli("batch", str(path), "-o", str(out), "--no-progress", cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and proc.stderr.startswith("lmic: error: bad.yaml: ")
    assert message in proc.stderr
    assert not out.exists()  # validated before the output folder is even created


def test_malformed_yaml_and_usage(tmp_path):
    bad = tmp_path / "s.yaml"
    bad.write_text("theorem: [qib.thm1\n", encoding="utf-8")
    proc = _cli("batch", str(bad), "-o", str(tmp_path / "o"))
    assert proc.returncode == 2 and "malformed YAML" in proc.stderr and proc.stderr.count("\n") == 1
    proc = _cli("batch", str(bad))
    assert proc.returncode == 2 and "give the output folder" in proc.stderr
    proc = _cli("batch", "--status", str(tmp_path / "nowhere"))
    assert proc.returncode == 2 and "no such study folder" in proc.stderr


def test_axes_and_cartesian_grid():
    assert expand_axis("a", {"logspace": [1e-3, 10, 5]}, "s") == pytest.approx([10.0**k for k in range(-3, 2)])
    assert expand_axis("a", {"linspace": [0, 1, 5]}, "s") == pytest.approx([0, 0.25, 0.5, 0.75, 1])
    study = load_study(
        {
            "theorem": "qib.thm1",
            "systems": {"random": RANDOM},
            "grid": {"beta": [0.001, 0.01], "gamma": {"linspace": [-0.1, 0.1, 3]}},
        }
    )
    assert len(study.jobs) == 3 * 2 * 3
    points = {(j.system_label, j.point["beta"], j.point["gamma"]) for j in study.jobs}
    assert len(points) == 18
    assert study.map_axes == ("beta", "gamma")


def test_samples_are_seeded_and_inside_their_ranges():
    spec = {
        "theorem": "qib.thm1",
        "params": {"gamma": 0.0},
        "systems": {"random": {**RANDOM, "count": 1}},
        "samples": {"count": 50, "seed": 3, "params": {"beta": {"loguniform": [1e-4, 1e-1]}}},
    }
    a, b = load_study(spec), load_study(spec)
    betas = [j.params["beta"] for j in a.jobs]
    assert betas == [j.params["beta"] for j in b.jobs]
    assert len(set(betas)) == 50 and all(1e-4 <= v <= 1e-1 for v in betas)
    logs = np.log10(betas)  # log-uniform: both decades halves are populated
    assert (logs < -2.5).sum() > 10 and (logs > -2.5).sum() > 10


def test_random_plants_follow_the_theorem_declarations():
    spec = {
        "theorem": "qib.thm1",
        "systems": {"random": {"count": 4, "seed": 9, "dims": {"n": 5, "p": 2}, "spectral_radius": {"A": 0.7}}},
    }
    study = load_study({**spec, "params": {"beta": 0.01}})
    assert len(study.jobs) == 4
    for job in study.jobs:
        a, c = np.array(job.system["data"]["A"]), np.array(job.system["data"]["C"])
        assert a.shape == (5, 5) and c.shape == (2, 5)
        assert max(abs(np.linalg.eigvals(a))) == pytest.approx(0.7, rel=1e-9)
        assert set(job.system["data"]) == {"A", "C"}  # the optional fixed-gain L is left out
    # plant k is the same whatever the count
    more = load_study(
        {**spec, "params": {"beta": 0.01}, "systems": {"random": {**spec["systems"]["random"], "count": 6}}}
    )
    assert [j.hash for j in more.jobs[:4]] == [j.hash for j in study.jobs]


def test_job_hash_depends_on_what_the_job_computes(tmp_path):
    sysfile = REPO / "examples/qib.thm1.flexible-joint.yaml"
    copy = tmp_path / "copy.yaml"
    copy.write_text(sysfile.read_text(encoding="utf-8"), encoding="utf-8")
    base = {"theorem": "qib.thm1", "systems": {"files": [str(sysfile), str(copy)]}}
    study = load_study(base)
    assert len(study.jobs) == 1 and study.duplicates == 1  # same numbers: one job
    h = study.jobs[0].hash
    assert load_study({**base, "params": {"beta": 0.002}}).jobs[0].hash != h
    assert load_study({**base, "backends": ["scs"]}).jobs[0].hash != h
    assert load_study({**base, "task": "crosscheck", "backends": ["clarabel"]}).jobs[0].hash != h
    assert load_study({**base, "time_limit": 5}).jobs[0].hash == h  # limits do not change the question
    two = load_study({**base, "backends": ["clarabel", "scs"]})
    assert len(two.jobs) == 2 and len({j.hash for j in two.jobs}) == 2


def test_by_filename_reads_the_theorem_of_each_example():
    study = load_study({"theorem": "by-filename", "systems": {"files": [str(REPO / "examples/qib.thm*.yaml")]}})
    assert sorted((j.system_label, j.theorem) for j in study.jobs) == [
        ("qib.thm1.flexible-joint.yaml", "qib.thm1"),
        ("qib.thm2.flexible-joint.yaml", "qib.thm2"),
    ]
    with pytest.raises(DataError, match="cannot be combined"):
        load_study({"theorems": ["by-filename", "qib.thm1"], "systems": {"random": RANDOM}})


@pytest.mark.parametrize("name", sorted(p.name for p in (REPO / "examples" / "studies").glob("*.yaml")))
def test_example_studies_are_valid(name):
    study = load_study(REPO / "examples" / "studies" / name)
    assert study.jobs and len({j.hash for j in study.jobs}) == len(study.jobs)
    if name == "qib_monte_carlo.yaml":
        assert len(study.jobs) == 200
    if name == "obs_control_map.yaml":
        assert study.map_axes == ("eps", "alpha") and len(study.jobs) == 144


def test_unreachable_scheduler_is_one_line_and_writes_nothing(tmp_path):
    from study_helpers import free_port

    path = write_study(
        tmp_path / "s.yaml", {"lmic": 1, "theorem": "qib.thm1", "params": {"beta": 0.01}, "systems": {"random": RANDOM}}
    )
    out = tmp_path / "out"
    proc = _cli("batch", str(path), "-o", str(out), "--executor", f"tcp://127.0.0.1:{free_port()}", "--no-progress")
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1
    assert "cannot reach the Dask scheduler" in proc.stderr
    assert not out.exists()
