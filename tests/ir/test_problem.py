"""Variables, LMIs, linear constraints, objectives and the Problem container."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from lmic.errors import IRError
from lmic.ir.problem import (
    LMI,
    Check,
    LinearConstraints,
    NamedExpr,
    Objective,
    Problem,
    Variable,
)
from lmic.ir.svec import tril_size, tril_vec


def _value_for(v: Variable, rng: np.random.Generator) -> np.ndarray:
    r, c = v.shape
    if v.kind == "scalar":
        return np.array([[rng.standard_normal()]])
    if v.kind == "full":
        return rng.standard_normal((r, c))
    if v.kind == "diagonal":
        return np.diag(rng.standard_normal(r))
    if v.kind == "symmetric":
        M = rng.standard_normal((r, r))
        return M + M.T
    out = np.zeros((r, r))
    start = 0
    for b in v.blocks:
        M = rng.standard_normal((b, b))
        out[start : start + b, start : start + b] = M + M.T
        start += b
    return out


KINDS = [
    ("scalar", (1, 1), ()),
    ("full", (2, 3), ()),
    ("symmetric", (3, 3), ()),
    ("diagonal", (4, 4), ()),
    ("blockdiag", (5, 5), (2, 3)),
]


@pytest.mark.parametrize(("kind", "shape", "blocks"), KINDS)
def test_variable_sizes(kind, shape, blocks):
    v = Variable("V", kind, shape, offset=0, blocks=blocks)
    expected = {"scalar": 1, "full": 6, "symmetric": 6, "diagonal": 4, "blockdiag": 3 + 6}[kind]
    assert v.size == expected
    assert v.slice == slice(0, expected)
    assert Variable("V", kind, shape, offset=7, blocks=blocks).slice == slice(7, 7 + expected)


@pytest.mark.parametrize(("kind", "shape", "blocks"), KINDS)
@given(seed=st.integers(0, 2**31))
@settings(max_examples=25)
def test_pack_value_basis_agree(kind, shape, blocks, seed):
    rng = np.random.default_rng(seed)
    offset = 3
    v = Variable("V", kind, shape, offset=offset, blocks=blocks)
    V = _value_for(v, rng)
    packed = v.pack(V)
    assert packed.shape == (v.size,)
    x = np.concatenate([rng.standard_normal(offset), packed, rng.standard_normal(2)])
    got = v.value(x)
    if kind == "scalar":
        assert got == V[0, 0]
    else:
        assert np.allclose(got, V, atol=0, rtol=1e-15)
    # the basis maps the variable's entries to vec(V), column-major
    vecV = v.basis() @ x[v.slice]
    assert np.allclose(vecV, np.atleast_2d(V).reshape(-1, order="F"))


def test_symmetric_variable_layout_is_the_storage_convention():
    P = Variable("P", "symmetric", (3, 3))
    M = np.array([[1.0, 2.0, 3.0], [2.0, 4.0, 5.0], [3.0, 5.0, 6.0]])
    assert np.array_equal(P.pack(M), tril_vec(M))
    assert np.array_equal(P.pack(M), [1, 2, 3, 4, 5, 6])


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (("V", "tensor", (2, 2)), "unknown kind 'tensor'"),
        (("V", "scalar", (2, 1)), "a scalar has shape 1x1"),
        (("V", "symmetric", (2, 3)), "a symmetric variable is square"),
        (("V", "diagonal", (2, 3)), "a diagonal variable is square"),
    ],
)
def test_variable_errors(args, match):
    with pytest.raises(IRError, match=match):
        Variable(*args)


def test_blockdiag_blocks_must_add_up():
    with pytest.raises(IRError, match=r"block sizes \(2, 2\) do not add up to 5"):
        Variable("B", "blockdiag", (5, 5), blocks=(2, 2))


@pytest.mark.parametrize(
    ("kind", "shape", "value", "match"),
    [
        ("full", (2, 2), np.ones((2, 3)), "value of shape"),
        ("diagonal", (2, 2), np.ones((2, 2)), "not diagonal"),
        ("symmetric", (2, 2), [[1.0, 2.0], [0.0, 1.0]], "not symmetric"),
        ("blockdiag", (3, 3), np.ones((3, 3)), "not block-diagonal"),
    ],
)
def test_pack_rejects_wrong_values(kind, shape, value, match):
    v = Variable("V", kind, shape, blocks=(1, 2) if kind == "blockdiag" else ())
    with pytest.raises(IRError, match=match):
        v.pack(value)


def test_lmi_matrix_and_coefficients():
    # F(x) = [[1, 0], [0, 0]] + x0 [[0, 1], [1, 0]] + x1 I
    coeffs = sp.csc_matrix(np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]))
    L = LMI("F", 2, coeffs, strict=False, relation=">=")
    assert np.array_equal(L.matrix([2.0, 3.0]), [[4.0, 2.0], [2.0, 3.0]])
    assert np.array_equal(L.coefficient(0), [[1.0, 0.0], [0.0, 0.0]])
    assert np.array_equal(L.coefficient(1), [[0.0, 1.0], [1.0, 0.0]])
    assert np.array_equal(L.coefficient(2), np.eye(2))
    assert L.block_sizes == (2,)
    assert not L.homogeneous
    assert LMI("G", 2, sp.csc_matrix((3, 3))).homogeneous


def test_lmi_row_count_must_match_dimension():
    with pytest.raises(IRError, match="LMI 'F': 4 coefficient rows, expected 3 for dimension 2"):
        LMI("F", 2, sp.csc_matrix((4, 2)))


def test_linear_constraints():
    A = sp.csr_matrix([[-1.0, 1.0, 0.0], [0.0, 1.0, -1.0]])
    L = LinearConstraints(A, ["ge", "eq"], [True, False], ["x0 > 1", "x0 = x1"])
    assert len(L) == 2
    assert np.array_equal(L.residuals([3.0, 3.0]), [2.0, 0.0])
    assert len(LinearConstraints.empty(4)) == 0 and LinearConstraints.empty(4).A.shape == (0, 5)
    with pytest.raises(IRError, match="one entry a row"):
        LinearConstraints(A, ["ge"], [True], ["a"])
    with pytest.raises(IRError, match="unknown kind 'le'"):
        LinearConstraints(A, ["ge", "le"], [True, False], ["a", "b"])


def test_objective():
    assert Objective("min", [1.0, 2.0, -1.0]).value([3.0, 4.0]) == 3.0
    assert Objective("max", [0.0, 1.0, 0.0]).value(np.array([5.0, 0.0])) == 5.0
    assert Objective("feasibility", [0.0, 0.0]).value([1.0]) is None
    with pytest.raises(IRError, match="unknown sense 'minimise'"):
        Objective("minimise", [0.0])


def test_check_kind_is_validated():
    with pytest.raises(IRError, match="unknown kind 'stable'"):
        Check("c", "stable", {"name": "A"})


def _problem(**kw):
    P = Variable("P", "symmetric", (2, 2), offset=0)
    g = Variable("g", "scalar", (1, 1), offset=3)
    coeffs = sp.csc_matrix((np.ones(3), ([0, 1, 2], [1, 2, 3])), shape=(3, 5))
    args = dict(
        variables=[P, g],
        lmis=[LMI("P > 0", 2, coeffs)],
        linear=LinearConstraints(sp.csr_matrix([[-1.0, 0, 0, 0, 1.0]]), ["ge"], [False], ["g>=1"]),
        objective=Objective("min", [0.0, 0.0, 0.0, 0.0, 1.0]),
    )
    args.update(kw)
    return Problem(**args)


def test_problem_pack_unpack_and_environment():
    p = _problem(
        data={"A": [[2.0, 0.0], [0.0, 2.0]], "k": 3},
        derived=[
            NamedExpr("L", {"op": "mul", "args": [{"op": "inv", "args": [{"name": "P"}]}, {"name": "A"}]}),
            NamedExpr("h", {"op": "mul", "args": [{"name": "k"}, {"name": "g"}]}),
        ],
    )
    assert p.n == 4
    x = p.pack({"P": [[2.0, 0.0], [0.0, 4.0]], "g": 1.5})
    assert np.array_equal(x, [2.0, 0.0, 4.0, 1.5])
    vals = p.unpack(x)
    assert vals["g"] == 1.5 and np.array_equal(vals["P"], [[2.0, 0.0], [0.0, 4.0]])
    env = p.environment(x)
    assert np.allclose(env["L"], [[1.0, 0.0], [0.0, 0.5]])
    assert env["h"] == 4.5
    assert p.variable("g").offset == 3
    with pytest.raises(IRError, match="no variable named 'Q'"):
        p.variable("Q")
    with pytest.raises(IRError, match="no value given for variable 'g'"):
        p.pack({"P": np.eye(2)})


def test_problem_validation():
    P = Variable("P", "symmetric", (2, 2), offset=0)
    with pytest.raises(IRError, match="duplicate variable name 'P'"):
        _problem(variables=[P, Variable("P", "scalar", (1, 1), offset=3)])
    with pytest.raises(IRError, match="variable 'g' has offset 4, expected 3"):
        _problem(variables=[P, Variable("g", "scalar", (1, 1), offset=4)])
    with pytest.raises(IRError, match="LMI 'bad' has 4 coefficient columns, expected 5"):
        _problem(lmis=[LMI("bad", 1, sp.csc_matrix((1, 4)))])
    with pytest.raises(IRError, match="LMI 'nan' has a non-finite coefficient"):
        _problem(lmis=[LMI("nan", 1, sp.csc_matrix(([np.nan], ([0], [1])), shape=(1, 5)))])
    with pytest.raises(IRError, match="linear constraints have 3 columns, expected 5"):
        _problem(linear=LinearConstraints.empty(2))
    with pytest.raises(IRError, match="objective has 2 entries, expected 5"):
        _problem(objective=Objective("min", [0.0, 1.0]))
    with pytest.raises(IRError, match="objective has a non-finite coefficient"):
        _problem(objective=Objective("min", [0.0, 0.0, 0.0, 0.0, np.inf]))


def test_lmi_sizes_follow_the_convention():
    p = _problem()
    assert p.lmis[0].coeffs.shape == (tril_size(2), 1 + p.n)
    # P > 0 written as F(x) = P: F's storage vector is P's entries
    x = p.pack({"P": [[1.0, 2.0], [2.0, 5.0]], "g": 0.0})
    assert np.array_equal(p.lmis[0].matrix(x), [[1.0, 2.0], [2.0, 5.0]])
