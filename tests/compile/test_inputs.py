"""lmic.compile.inputs: parameters and data-derived constants of the wrong kind are one-line errors."""

from __future__ import annotations

import numpy as np
import pytest

from lmic.compile import analyse, bind
from lmic.errors import DataError, TemplateError
from lmic.template import theorem

DATA = {"data": {"A": [[-1.0, 0.5], [0.0, -2.0]]}}


def _with_constant(fn, shape=None):
    @theorem(id="test.const", title="t", citation="c", kind="analysis")
    def thm(t):
        (n,) = t.dims("n")
        A = t.data("A", n, n)
        k = t.const("k", fn, shape=None if shape is None else (n, n))
        P = t.symmetric("P", n, pd=True)
        t.lmi("L", A.T * P + P * A + (k * P if shape is None else k) < 0)

    return thm


@pytest.mark.parametrize(
    ("fn", "shape", "pattern"),
    [
        (lambda v: 1j, None, r"constant 'k' is complex \(1j\): an LMI needs real numbers"),
        (lambda v: np.linalg.eigvals(np.array([[0.0, 1.0], [-1.0, 0.0]]))[0], None, "constant 'k' is complex"),
        (lambda v: v["A"] * (1 + 1j), "matrix", "constant 'k' is complex"),
        (lambda v: "abc", None, r"constant 'k' is not a number or a matrix of numbers: 'abc'"),
        (lambda v: None, None, "constant 'k' is not a number"),
        (lambda v: {"a": 1}, "matrix", "constant 'k' is not a number"),
    ],
)
def test_a_constant_that_is_not_real_is_a_template_error(fn, shape, pattern):
    with pytest.raises(TemplateError, match=rf"test.const: {pattern}"):
        bind(analyse(_with_constant(fn, shape)), DATA)


def test_a_complex_constant_with_zero_imaginary_part_is_its_real_part():
    lam = np.linalg.eigvals(np.array([[2.0, 0.0], [0.0, 3.0]]).astype(complex))  # complex dtype, real values
    real = bind(analyse(_with_constant(lambda v: float(np.max(lam.real)))), DATA)
    cplx = bind(analyse(_with_constant(lambda v: np.max(lam))), DATA)
    assert (real.lmis[0].coeffs != cplx.lmis[0].coeffs).nnz == 0


@pytest.mark.parametrize("value", [1j, None, [1, 2], np.array([0.1]), True, np.bool_(False), {"a": 1}])
def test_a_parameter_override_that_is_not_a_real_number_is_a_data_error(value):
    @theorem(id="test.param", title="t", citation="c", kind="analysis")
    def thm(t):
        (n,) = t.dims("n")
        A = t.data("A", n, n)
        a = t.param("a")
        P = t.symmetric("P", n, pd=True)
        t.lmi("L", A.T * P + P * A + a * P < 0)

    with pytest.raises(DataError, match=r"parameter 'a' = .* is not a number"):
        bind(analyse(thm), DATA, {"a": value})
    for fine in (np.float32(0.5), 1, np.array(0.5)):  # numpy scalars and 0-d arrays are numbers
        bind(analyse(thm), DATA, {"a": fine})


def test_a_projector_computed_in_floating_point_gets_a_note():
    """uio_dt.thm4_1 computes V = I - X X^+ numerically: on random data its zero eigenvalues are
    1e-17, so the compiled problem reads it as regular (docs/writing-a-theorem.md); the shipped
    example's projector is exact and gets no note."""
    import sys
    import warnings
    from pathlib import Path

    from lmic.compile import compile_theorem
    from lmic.system import RoundingNote

    root = Path(__file__).resolve().parents[2]
    sys.path.insert(0, str(root / "tests" / "plugins"))
    import optimisation_instances as oi

    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        compile_theorem("uio_dt.thm4_1", oi.instance("uio_dt.thm4_1", 1, 3))
        notes = [str(w.message) for w in seen if issubclass(w.category, RoundingNote)]
    assert any("constant 'V' is singular only up to rounding" in n for n in notes), notes
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        compile_theorem("uio_dt.thm4_1", root / "examples" / "uio_dt.thm4_1.flexible_joint.yaml")
        assert not [w for w in seen if issubclass(w.category, RoundingNote)]
