"""Templates that are not LMIs are TemplateErrors naming the LMI, the block and the term."""

from __future__ import annotations

import pytest

from lmic.compile import analyse, bind
from lmic.errors import TemplateError
from lmic.template import STAR, I, block, theorem

DATA = {"data": {"A": [[1.0, 2.0], [0.0, 3.0]], "C": [[1.0, 0.0]]}}


def _thm(build):
    return theorem(id="test.bad", title="bad", citation="tests")(build)


def test_product_of_two_matrix_variables_names_block_and_term():
    def build(t):
        n, p = t.dims("n p")
        A = t.data("A", n, n)
        t.data("C", p, n)
        P = t.symmetric("P", n)
        Q = t.symmetric("Q", n)
        t.lmi("bilinear", block([[A.T * P + P * A, P * Q], [STAR, -P]]) < 0)

    msg = r"LMI 'bilinear' block \(1,2\).*product of decision variables P and Q.*P\*Q"
    with pytest.raises(TemplateError, match=msg):
        analyse(_thm(build))


def test_scalar_variable_times_matrix_variable_is_rejected():
    def build(t):
        n, p = t.dims("n p")
        t.data("A", n, n)
        t.data("C", p, n)
        P = t.symmetric("P", n)
        w = t.scalar("w")
        t.lmi("L", block([[w * P]]) < 0)

    with pytest.raises(TemplateError, match=r"block \(1,1\).*product of decision variables w and P"):
        analyse(_thm(build))


def test_nonlinear_scalar_function_of_a_variable_is_rejected():
    def build(t):
        n, p = t.dims("n p")
        t.data("A", n, n)
        t.data("C", p, n)
        w = t.scalar("w")
        t.lmi("L", block([[w**2 * I(n)]]) < 0)

    with pytest.raises(TemplateError, match="not linear in the decision variable w"):
        analyse(_thm(build))


def test_non_symmetric_diagonal_block_is_rejected_at_bind():
    def build(t):
        n, p = t.dims("n p")
        A = t.data("A", n, n)
        t.data("C", p, n)
        P = t.symmetric("P", n)
        t.lmi("skew", block([[A * P]]) < 0)

    with pytest.raises(TemplateError, match=r"LMI 'skew' block \(1,1\) is not symmetric"):
        bind(analyse(_thm(build)), DATA)


def test_explicit_lower_block_that_disagrees_is_rejected():
    def build(t):
        n, p = t.dims("n p")
        A = t.data("A", n, n)
        t.data("C", p, n)
        P = t.symmetric("P", n)
        t.lmi("mirror", block([[-P, A * P], [A * P, -P]]) < 0)

    with pytest.raises(TemplateError, match=r"block \(1,2\) is not the transpose of block \(2,1\)"):
        bind(analyse(_thm(build)), DATA)


def test_explicit_zero_lower_with_nonzero_upper_is_rejected():
    def build(t):
        n, p = t.dims("n p")
        A = t.data("A", n, n)
        t.data("C", p, n)
        P = t.symmetric("P", n)
        t.lmi("half", block([[-P, A.T * P], [0, -P]]) < 0)

    with pytest.raises(TemplateError, match="not the transpose"):
        bind(analyse(_thm(build)), DATA)


def test_star_on_both_sides_is_rejected():
    def build(t):
        n, p = t.dims("n p")
        t.data("A", n, n)
        t.data("C", p, n)
        P = t.symmetric("P", n)
        t.lmi("stars", block([[-P, STAR], [STAR, -P]]) < 0)

    with pytest.raises(TemplateError, match="both"):
        analyse(_thm(build))


def test_lmi_without_relation_and_with_nonzero_rhs_are_rejected():
    def no_rel(t):
        (n,) = t.dims("n")
        P = t.symmetric("P", n)
        t.lmi("x", block(P))

    with pytest.raises(TemplateError, match="no relation"):
        analyse(_thm(no_rel))

    def rhs(t):
        (n,) = t.dims("n")
        P = t.symmetric("P", n)
        t.lmi("x", block(P) < 1)

    with pytest.raises(TemplateError, match="compared with 0"):
        analyse(_thm(rhs))


def test_derived_quantity_inside_an_lmi_is_rejected():
    def build(t):
        (n,) = t.dims("n")
        A = t.data("A", n, n)
        P = t.symmetric("P", n)
        L = t.derive("L", P.inv())
        t.lmi("x", block(A.T * L) < 0)

    with pytest.raises(TemplateError, match="derived quantity 'L'"):
        analyse(_thm(build))


def test_a_buggy_build_function_is_reported_with_the_theorem_id():
    def build(t):
        raise KeyError("oops")

    where = r"at test_template_errors.py:\d+"  # the file and line of the bug in the plugin
    with pytest.raises(TemplateError, match=rf"theorem test.bad: template failed to build {where}: KeyError"):
        analyse(_thm(build))


def test_build_function_without_the_template_argument_points_at_its_definition():
    def build():  # a newcomer forgets ``t``: the error is raised calling build, not inside it
        pass

    line = build.__code__.co_firstlineno
    with pytest.raises(TemplateError, match=rf"at test_template_errors.py:{line}: TypeError: .*0 positional"):
        analyse(_thm(build))


def test_term_with_inconsistent_shapes_names_them_once():
    def build(t):
        n, p = t.dims("n p")
        t.data("A", n, n)
        C = t.data("C", p, n)
        P = t.symmetric("P", n)
        t.lmi("L", block([[P * C]]) < 0)  # P is n x n, C is p x n

    with pytest.raises(TemplateError) as err:
        bind(analyse(_thm(build)), DATA)
    msg = str(err.value)
    assert msg.count("theorem test.bad") == 1
    assert "LMI 'L' block (1,1): term" in msg and "inconsistent shapes (2x2 * 1x2)" in msg


@pytest.mark.parametrize(
    ("meta", "pattern"),
    [
        ({"title": None}, "title must be a string, not NoneType"),
        ({"title": 3}, "title must be a string, not int"),
        ({"citation": ["a"]}, "citation must be a string, not list"),
        ({"title": "  "}, "title is empty"),
        ({"citation": ""}, "citation is empty"),
        ({"objective": None}, "objective must be a string"),
    ],
)
def test_theorem_metadata_of_the_wrong_type_is_one_line(meta, pattern):
    full = {"id": "test.meta", "title": "t", "citation": "c", **meta}
    with pytest.raises(TemplateError, match=rf"^theorem test.meta: {pattern}"):
        theorem(**full)(lambda t: None)


@pytest.mark.parametrize(
    ("default", "domain"), [(-1, "positive"), (0.5, "natural"), (float("nan"), "real"), ("1", "real"), (True, "real")]
)
def test_parameter_default_outside_its_domain_is_rejected(default, domain):
    def build(t):
        (n,) = t.dims("n")
        A = t.data("A", n, n)
        a = t.param("a", default=default, domain=domain)
        P = t.symmetric("P", n)
        t.lmi("L", A.T * P + P * A + a * P < 0)

    with pytest.raises(TemplateError, match=r"test.bad: the default .* of parameter 'a' is not a number in its domain"):
        analyse(_thm(build))


def test_matrix_objective_is_a_template_error():
    def build(t):
        (n,) = t.dims("n")
        A = t.data("A", n, n)
        P = t.symmetric("P", n)
        t.lmi("L", A.T * P + P * A < 0)
        t.minimize(P)

    with pytest.raises(TemplateError, match=r"test.bad.*the objective 'P' is a matrix"):
        analyse(_thm(build))


def test_a_dims_tuple_used_as_a_dimension_names_the_theorem_and_the_fix():
    def build(t):
        n = t.dims("n")  # a tuple: the newcomer meant ``n, = t.dims("n")``
        t.data("A", n, n)

    with pytest.raises(TemplateError, match=r"^theorem test.bad: the shape of 'A': \(n,\) .*write n, = t.dims"):
        analyse(_thm(build))


def test_matrix_relations_in_a_scalar_constraint_name_the_fix():
    """A newcomer's ``t.constraint("mat", Eq(P, I(n)))`` was an internal TypeError; ``P <= I(n)``
    suggested ``P - I(n) <= 0``, which t.constraint then called "not a relation"."""
    import sympy

    def equality(t):
        (n,) = t.dims("n")
        t.data("A", n, n)
        P = t.symmetric("P", n)
        t.constraint("mat", sympy.Eq(P, I(n)))

    with pytest.raises(TemplateError, match=r"constraint 'mat' relates matrices.*write the entries"):
        analyse(_thm(equality))

    def inequality(t):
        (n,) = t.dims("n")
        t.data("A", n, n)
        P = t.symmetric("P", n)
        t.constraint("b", P - I(n) <= 0)

    with pytest.raises(TemplateError, match=r"constraint 'b' is a matrix inequality: declare it with t.lmi\('b'"):
        analyse(_thm(inequality))

    def compared(t):
        (n,) = t.dims("n")
        t.data("A", n, n)
        P = t.symmetric("P", n)
        t.constraint("b", P <= I(n))

    with pytest.raises(TemplateError, match=r"write 'M - N <= 0' instead of 'M <= N', declared with t.lmi"):
        analyse(_thm(compared))


def test_a_method_trace_points_at_the_trace_function():
    def build(t):
        (n,) = t.dims("n")
        Z = t.symmetric("Z", n)
        t.lmi("Z", Z > 0)
        t.minimize(Z.trace())  # sympy's matrix symbols have no .trace(): a newcomer's first guess

    with pytest.raises(
        TemplateError, match=r"no attribute 'trace' \(write trace\(Z\), with trace from lmic.template\)"
    ):
        analyse(_thm(build))


def _trace_of_a_non_square_matrix(t):
    from lmic.template import trace

    n, q = t.dims("n q")
    C = t.data("C", q, n)
    P = t.symmetric("P", n)
    t.lmi("P", P > 0)
    t.minimize(trace(C * P))  # rejected where it is written


def _scalar_subtracted_from_a_block(t):
    n, m = t.dims("n m")
    B = t.data("B", n, m)
    P = t.symmetric("P", n)
    gamma = t.scalar("gamma")
    t.lmi("gain", block([[B.T * P * B - gamma]]) < 0)  # as a paper prints it; sympy refuses


def _entry_of_a_matrix_product(t):
    import sympy

    (n,) = t.dims("n")
    A = t.data("A", n, n)
    P = t.symmetric("P", n, pd=True)
    t.constraint("entry", sympy.Eq((A.T * P + P * A)[0, 0], 0))  # linear, but sympy writes a Sum


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (_trace_of_a_non_square_matrix, r"trace of a matrix that is not square: C\*P is q x n"),
        (
            _scalar_subtracted_from_a_block,
            r"Mix of Matrix and Scalar symbols \(a matrix plus or minus a scalar: write gamma \* I\(m\)",
        ),
        (_entry_of_a_matrix_product, r"is an entry of a matrix product; write entries of a variable"),
    ],
)
def test_a_newcomers_mistake_says_how_to_write_it(build, message):
    with pytest.raises(TemplateError, match=message):
        analyse(_thm(build))
