"""The Python API: lmic.solve / lmic.theorem / lmic.compile, numpy gains, StateSpace plants,
rich display in Jupyter (tests/present/test_jupyter.py)."""

from __future__ import annotations

import numpy as np
import pytest

import lmic
from lmic.errors import DataError

QIB_FILE = "examples/qib.thm1.flexible-joint.yaml"


def test_solve_from_a_file_gives_numpy_gains_and_a_certificate(monkeypatch):
    from pathlib import Path

    monkeypatch.chdir(Path(__file__).resolve().parents[2])
    r = lmic.solve("qib.thm1", QIB_FILE)
    assert r.verdict == "certified" and r.status == "feasible"
    L = r.gains["L"]
    assert isinstance(L, np.ndarray) and L.shape == (4, 2)
    A = r.problem.data["A"]
    C = r.problem.data["C"]
    assert max(abs(np.linalg.eigvals(A - L @ C))) < 1
    np.testing.assert_allclose(L, np.linalg.solve(r.values["P"], r.values["R"].T), rtol=1e-9, atol=1e-12)


def test_solve_from_a_dict_with_numpy_arrays():
    r = lmic.solve("thesis.lyapunov", {"data": {"A": np.array([[-1.0, 2.0], [0.0, -3.0]])}})
    assert r.verdict == "certified"
    assert np.all(np.linalg.eigvalsh(r.values["P"]) > 0)


def test_statespace_plant_fills_the_theorems_data():
    control = pytest.importorskip("control")
    ss = control.ss([[0, 1], [-2, -0.5]], [[0], [1]], [[1, 0]], [[0]])
    r = lmic.solve("tutorial.bounded_real", ss) if _has_tutorial() else None
    if r is not None:
        assert r.verdict == "certified"
        assert r.objective == pytest.approx(1 / (0.5 * np.sqrt(1.9375)), rel=1e-4)
    # a dict with a plant and extra parameters
    r2 = lmic.solve(
        "qib.thm1",
        {"plant": control.ss(np.diag([0.5, 0.2]), np.zeros((2, 1)), [[1, 0]], 0, True), "params": {"beta": 0.01}},
    )
    assert r2.verdict == "certified"
    assert sorted(r2.problem.data) >= ["A", "C"]


def test_a_plant_of_the_other_time_base_is_noted():
    """A continuous-time python-control plant given to a discrete-time theorem (and the other
    way round) is taken as given, with a note naming both: the matrices would mean something else."""
    import warnings

    from lmic.plant import TimebaseNote

    control = pytest.importorskip("control")
    with pytest.warns(TimebaseNote, match=r"continuous-time \(dt = 0\) but theorem qib.thm1 is for discrete time"):
        lmic.compile_theorem(
            "qib.thm1",
            {"plant": control.ss(np.diag([0.5, 0.2]), np.zeros((2, 1)), [[1, 0]], 0), "params": {"beta": 0.01}},
        )
    with pytest.warns(
        TimebaseNote, match=r"discrete-time \(dt = 0.1\) but theorem tutorial.bounded_real is for continuous"
    ):
        lmic.compile_theorem("tutorial.bounded_real", control.ss([[0.5]], [[1.0]], [[1.0]], [[0.0]], 0.1))
    with warnings.catch_warnings():
        warnings.simplefilter("error", TimebaseNote)  # the right time base: no note
        lmic.compile_theorem(
            "qib.thm1",
            {"plant": control.ss(np.diag([0.5, 0.2]), np.zeros((2, 1)), [[1, 0]], 0, True), "params": {"beta": 0.01}},
        )


def test_a_plant_without_the_theorems_matrices_is_a_clear_error():
    class Plant:
        A = np.eye(2)
        B = np.zeros((2, 1))
        C = np.eye(1, 2)
        D = np.zeros((1, 1))

    with pytest.raises(DataError, match="missing parameter 'beta'"):
        lmic.solve("qib.thm1", Plant())


def test_compile_without_solving_and_theorem_listing():
    prob = lmic.compile_theorem("thesis.lyapunov", {"data": {"A": [[-1.0, 0.0], [0.0, -2.0]]}})
    assert [lmi.name for lmi in prob.lmis] == ["P > 0", "(2.9)"]
    assert "qib.thm1" in {t.id for t in lmic.theorems()}


def _has_tutorial() -> bool:
    return any(t.id == "tutorial.bounded_real" for t in lmic.theorems())
