"""The notebook route (inline theorems) and system files with extra / mistyped data keys."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import lmic
from lmic.errors import DataError
from lmic.registry import REGISTRY, register
from lmic.system import UnusedDataNote
from lmic.template import theorem

A = [[-1.0, 2.0, 0.0], [0.0, -3.0, 1.0], [0.5, 0.0, -2.0]]


def _lyapunov(tid="nb.lyap", extra_lmi=False):
    @theorem(id=tid, title="Lyapunov", citation="Lyapunov (1892)", kind="analysis")
    def build(t):
        (n,) = t.dims("n")
        A = t.data("A", n, n)
        P = t.symmetric("P", n, pd=True)
        t.lmi("stability", A.T * P + P * A < 0)

    return build


def test_solve_takes_an_inline_theorem_object_without_registration():
    thm = _lyapunov("nb.inline")
    r = lmic.solve(thm, {"data": {"A": A}})
    assert r.verdict == "certified" and r.theorem == "nb.inline" and r.target == "nb.inline"
    P = r.values["P"]
    # independent look at the point: A^T P + P A < 0 and P > 0 by eigenvalues
    assert np.linalg.eigvalsh(np.array(A).T @ P + P @ np.array(A)).max() < 0 < np.linalg.eigvalsh(P).min()
    assert r.problem.meta["provider"]["distribution"] is None  # not installed: recorded as inline


def test_registering_the_same_theorem_again_is_fine():
    thm = _lyapunov("nb.again")
    try:
        assert register(thm) is thm and register(thm) is thm
        newer = _lyapunov("nb.again")  # the notebook cell is run again
        register(newer)
        assert lmic.theorem("nb.again") is newer
        assert lmic.solve("nb.again", {"data": {"A": A}}).verdict == "certified"
    finally:
        REGISTRY._theorems.pop("nb.again", None)


def test_an_inline_theorem_may_not_take_an_installed_id():
    with pytest.raises(lmic.errors.LmicError, match="ambiguous.*lmic 0.1.0"):
        register(_lyapunov("thesis.lyapunov"))
    assert lmic.theorem("thesis.lyapunov").provider.distribution == "lmic"


def test_extra_data_keys_are_a_note_not_an_error():
    plant = {"data": {"A": A, "B": [[1.0], [0.0], [0.0]], "C": [[1.0, 0.0, 0.0]], "D": [[0.0]]}}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = lmic.solve("thesis.lyapunov", plant)
    assert r.verdict == "certified"
    notes = [str(w.message) for w in caught if issubclass(w.category, UnusedDataNote)]
    assert len(notes) == 1 and "'B', 'C', 'D' not used" in notes[0]


def test_a_near_miss_of_an_optional_or_missing_key_stays_an_error():
    sysd = {"data": {"A": [[0.5, 0.1], [0.0, 0.4]], "Cx": [[1.0, 0.0]]}, "params": {"beta": 0.01}}
    with pytest.raises(DataError, match=r"unknown data key 'Cx' \(did you mean 'C'\?"):
        lmic.compile_theorem("qib.thm1", sysd)


def test_cli_prints_the_note_on_one_line(tmp_path, capsys):
    from lmic.cli import main

    f = tmp_path / "plant.yaml"
    f.write_text("lmic: 1\ndata:\n  A: [[-1, 0], [0, -2]]\n  B: [[1], [1]]\n")
    assert main(["solve", "thesis.lyapunov", str(f)]) == 0
    err = capsys.readouterr().err
    assert "lmic: note: theorem thesis.lyapunov, plant.yaml: data 'B' not used" in err
    assert "UserWarning" not in err


def test_uncertain_dt_cor1_weights_default_to_ones():
    from lmic.system import load_system

    path = "examples/uncertain_dt.cor1.example-plant.yaml"
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    system = load_system(root / path)
    assert np.array_equal(system.data["Cw"], np.ones((3, 3)))  # the file spells the default out
    without = {"data": {k: v for k, v in system.data.items() if k != "Cw"}, "params": system.params}
    a = lmic.compile_theorem("uncertain_dt.cor1", without)
    b = lmic.compile_theorem("uncertain_dt.cor1", {"data": dict(system.data), "params": system.params})
    assert np.array_equal(a.data["Cw"], np.ones((3, 3)))
    for la, lb in zip(a.lmis, b.lmis, strict=True):
        assert (la.coeffs != lb.coeffs).nnz == 0
