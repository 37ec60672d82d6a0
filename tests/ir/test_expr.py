"""Expression trees for derived quantities and checks."""

from __future__ import annotations

import numpy as np
import pytest

from lmic.errors import IRError
from lmic.ir.expr import OPS, evaluate, names, validate


def N(name):
    return {"name": name}


def op(name, *args):
    return {"op": name, "args": list(args)}


ENV = {
    "A": np.array([[0.5, 0.1], [0.0, 0.3]]),
    "P": np.array([[2.0, 0.0], [0.0, 4.0]]),
    "G": np.array([[1.0], [2.0]]),
    "a": 4.0,
}


def test_leaves():
    assert evaluate({"num": 2.5}, {}) == 2.5
    assert np.array_equal(evaluate({"eye": 3}, {}), np.eye(3))
    assert np.array_equal(evaluate({"zeros": [2, 1]}, {}), np.zeros((2, 1)))
    assert evaluate(N("a"), ENV) == 4.0 and isinstance(evaluate(N("a"), ENV), float)
    assert evaluate(N("P"), ENV) is ENV["P"]


def test_back_substitution_gain():
    L = evaluate(op("mul", op("inv", N("P")), N("G")), ENV)
    assert np.allclose(L, [[0.5], [0.5]])


@pytest.mark.parametrize(
    ("tree", "expected"),
    [
        (op("add", N("a"), {"num": 1.0}), 5.0),
        (op("neg", N("a")), -4.0),
        (op("mul", {"num": 2.0}, N("a")), 8.0),
        (op("pow", N("a"), {"num": 0.5}), 2.0),
        (op("sqrt", N("a")), 2.0),
        (op("inv", N("a")), 0.25),
        (op("abs", op("neg", N("a"))), 4.0),
        (op("log", op("exp", N("a"))), 4.0),
        (op("trace", N("P")), 6.0),
        (op("lambda_max", N("P")), 4.0),
        (op("lambda_min", N("P")), 2.0),
        (op("spectral_radius", N("A")), 0.5),
        (op("spectral_abscissa", N("A")), 0.5),
        (op("norm2", N("P")), 4.0),
        (op("max", N("a"), {"num": 7.0}), 7.0),
        (op("min", N("a"), {"num": 7.0}), 4.0),
        (op("mul", op("transpose", N("G")), N("G")), np.array([[5.0]])),
    ],
)
def test_scalar_results(tree, expected):
    got = evaluate(tree, ENV)
    assert np.allclose(got, expected)


def test_matrix_operators():
    A, P = ENV["A"], ENV["P"]
    assert np.allclose(evaluate(op("add", N("A"), N("P")), ENV), A + P)
    assert np.allclose(evaluate(op("mul", N("A"), N("P")), ENV), A @ P)
    assert np.allclose(evaluate(op("hadamard", N("A"), N("P")), ENV), A * P)
    assert np.allclose(evaluate(op("transpose", N("A")), ENV), A.T)
    assert np.allclose(evaluate(op("pow", N("A"), {"num": 2}), ENV), A @ A)
    assert np.allclose(evaluate(op("pow", N("P"), {"num": -1}), ENV), np.linalg.inv(P))
    assert np.allclose(evaluate(op("pinv", N("G")), ENV), np.linalg.pinv(ENV["G"]))
    assert np.allclose(evaluate(op("sym", N("A")), ENV), (A + A.T) / 2)
    assert np.allclose(evaluate(op("kron", {"eye": 2}, N("A")), ENV), np.kron(np.eye(2), A))
    # adding a zero scalar to a matrix is allowed (e.g. a parameter set to 0)
    assert np.allclose(evaluate(op("add", N("A"), {"num": 0.0}), ENV), A)


def test_block():
    tree = {"block": [[N("P"), N("G")], [op("transpose", N("G")), {"num": 1.0}]]}
    M = evaluate(tree, ENV)
    assert M.shape == (3, 3)
    assert np.array_equal(M[:2, :2], ENV["P"]) and M[2, 2] == 1.0 and M[0, 2] == 1.0


@pytest.mark.parametrize(
    ("tree", "match"),
    [
        (N("Q"), "uses 'Q', which has no value"),
        (op("nope", N("a")), "unknown expression operator 'nope'"),
        (op("add", N("A"), N("G")), r"adds matrices of shapes \(2, 2\) and \(2, 1\)"),
        (op("add", N("A"), {"num": 1.0}), "adds a non-zero scalar to a matrix"),
        (op("mul", N("G"), N("A")), r"multiplies shapes \(2, 1\) and \(2, 2\)"),
        (op("pow", N("A"), {"num": 0.5}), "non-integer power of a matrix"),
        (op("inv", {"zeros": [2, 2]}), "'inv' failed"),
        ({"block": [[N("P"), N("a")]]}, "block expression has inconsistent sizes"),
        ({"what": 1}, "malformed expression node"),
    ],
)
def test_evaluation_errors(tree, match):
    with pytest.raises(IRError, match=match):
        evaluate(tree, ENV)


def test_names():
    tree = {"block": [[op("mul", N("P"), N("G"))], [op("neg", N("a"))]]}
    assert names(tree) == {"P", "G", "a"}
    assert names({"num": 1.0}) == set()


def test_validate_accepts_the_grammar():
    for tree in [
        N("P"),
        {"num": 1},
        {"eye": 2},
        {"zeros": [1, 2]},
        {"block": [[N("P")]]},
        op("mul", op("inv", N("P")), N("G")),
    ]:
        validate(tree)
    assert set(OPS) >= {"add", "mul", "inv", "lambda_max", "spectral_radius"}


@pytest.mark.parametrize(
    ("tree", "match"),
    [
        ([1, 2], "derived L: expression node is not an object"),
        ({"op": "nope"}, "derived L: unknown operator 'nope'"),
        ({"name": 3}, "derived L: malformed expression node"),
        ({"name": "P", "num": 1.0}, "derived L: malformed expression node"),
        ({"zeros": [1]}, "derived L: malformed expression node"),
        (op("add", {"bad": 1}), "derived L: malformed expression node"),
    ],
)
def test_validate_rejects(tree, match):
    with pytest.raises(IRError, match=match):
        validate(tree, "derived L")
