"""Template mistakes: one line naming the theorem, the LMI / derive / check and the symbol.

``lmic check`` finds bilinear terms, asymmetric blocks, shape mismatches and unused
declarations without a data file; ``--debug`` alone shows tracebacks.
"""

from __future__ import annotations

import textwrap

import pytest

from lmic.cli import main
from lmic.errors import TemplateError
from lmic.template import STAR, block, theorem

HEAD = """
import numpy as np
import sympy
from lmic.template import theorem, block, STAR, I, schur_stable
"""


def _module(tmp_path, body: str, name: str = "mine.py"):
    f = tmp_path / name
    f.write_text(HEAD + textwrap.dedent(body))
    return f


def _check(capsys, path, *extra):
    code = main(["check", str(path), *extra])
    out = capsys.readouterr()
    return code, out.out, out.err


def _one_error_line(err: str) -> str:
    lines = [x for x in err.splitlines() if x.strip()]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


def test_undeclared_symbol_in_an_lmi(tmp_path, capsys):
    f = _module(
        tmp_path,
        """
        @theorem(id="my.thm", title="t", citation="c")
        def build(t):
            (n,) = t.dims("n")
            A = t.data("A", n, n)
            P = t.symmetric("P", n, pd=True)
            t.lmi("decay", A.T * P + P * A + 2 * sympy.Symbol("gamma") * P < 0)
        """,
    )
    code, _, err = _check(capsys, f)
    line = _one_error_line(err)
    assert code == 2
    assert "my.thm" in line and "LMI 'decay'" in line and "Symbol 'gamma'" in line and "not declared" in line


def test_undeclared_matrix_symbol_in_a_derive(tmp_path, capsys):
    f = _module(
        tmp_path,
        """
        @theorem(id="my.thm", title="t", citation="c")
        def build(t):
            (n,) = t.dims("n")
            A = t.data("A", n, n)
            P = t.symmetric("P", n, pd=True)
            t.lmi("(1)", A.T * P + P * A < 0)
            t.derive("K", P.inv() * sympy.MatrixSymbol("B", n, n))
        """,
    )
    code, _, err = _check(capsys, f)
    line = _one_error_line(err)
    assert code == 2 and "derive 'K'" in line and "MatrixSymbol 'B'" in line and "my.thm" in line


def test_a_single_matrix_compares_with_zero_without_block():
    @theorem(id="my.single", title="t", citation="c", kind="analysis")
    def build(t):
        (n,) = t.dims("n")
        A = t.data("A", n, n)
        P = t.symmetric("P", n)
        t.lmi("P > 0", P > 0)
        t.lmi("(1)", A.T * P + P * A < 0)

    t = build.template()
    assert [(d.name, d.spec.relation) for d in t.lmis] == [("P > 0", ">"), ("(1)", "<")]
    assert build.kind == "A"
    with pytest.raises(TemplateError, match="compared with 0"):

        @theorem(id="my.bad", title="t", citation="c")
        def bad(t):
            (n,) = t.dims("n")
            P = t.symmetric("P", n)
            t.lmi("P > I", P > t.data("B", n, n))

        bad.template()


def test_numpy_inside_a_block_names_file_line_and_the_fix(tmp_path, capsys):
    f = _module(
        tmp_path,
        """
        @theorem(id="my.np", title="t", citation="c")
        def build(t):
            (n,) = t.dims("n")
            P = t.symmetric("P", n)
            t.lmi("(1)", block([[P - np.eye(n)]]) > 0)
        """,
    )
    code, _, err = _check(capsys, f)
    line = _one_error_line(err)
    assert code == 2 and "my.np" in line and "mine.py:10" in line and "use I(n)" in line


def test_python_bug_in_build_gives_file_and_line(tmp_path, capsys):
    f = _module(
        tmp_path,
        """
        @theorem(id="my.bug", title="t", citation="c")
        def build(t):
            (n,) = t.dims("n")
            P = t.symmetric("P", n)
            t.lmi("(1)", P + Q > 0)
        """,
    )
    code, _, err = _check(capsys, f)
    line = _one_error_line(err)
    assert code == 2 and "my.bug" in line and "mine.py:10" in line and "NameError" in line and "'Q'" in line
    # --debug (anywhere on the line) shows the traceback, nothing else does
    assert main(["check", str(f), "--debug"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" in err and 'mine.py", line 10' in err


def test_undecorated_function_is_named(tmp_path, capsys):
    f = _module(
        tmp_path,
        """
        def build(t):
            (n,) = t.dims("n")
        """,
    )
    code, _, err = _check(capsys, f)
    line = _one_error_line(err)
    assert code == 2 and "function 'build'" in line and "@theorem(" in line and "mine.py:6" in line


def test_check_reports_every_bilinear_term_and_asymmetric_block(tmp_path, capsys):
    f = _module(
        tmp_path,
        """
        @theorem(id="my.bil", title="t", citation="c")
        def build(t):
            n, p = t.dims("n p")
            A, C = t.data("A", n, n), t.data("C", p, n)
            P = t.symmetric("P", n, pd=True)
            L = t.full("L", n, p)
            w = t.scalar("w")
            t.lmi("(1)", block([[-P, A.T * P - C.T * L.T * P], [STAR, w * w * I(n) - P]]) < 0)
            t.lmi("(2)", A.T * P - P < 0)
            t.lmi("(3)", block([[-P, w * P * A], [STAR, -I(n)]]) < 0)
        """,
    )
    code, _, err = _check(capsys, f)
    lines = err.strip().splitlines()
    assert code == 2
    assert any("LMI '(1)' block (1,2): product of decision variables L and P in term" in x for x in lines)
    assert any("LMI '(1)' block (2,2): product of decision variables w^2" in x for x in lines)
    assert any("LMI '(2)' block (1,1) is not symmetric" in x for x in lines)
    assert any("LMI '(3)' block (1,2): product of decision variables P and w" in x for x in lines)
    assert all(x.startswith("lmic check: my.bil: ") for x in lines) and len(lines) == 4


def test_check_finds_a_derived_gain_of_the_wrong_shape(tmp_path, capsys):
    # the example: L = R P^-1 instead of P^-1 R^T; solve only 'rejected' it before
    f = _module(
        tmp_path,
        """
        @theorem(id="my.shape", title="t", citation="c")
        def build(t):
            n, p = t.dims("n p")
            A, C = t.data("A", n, n), t.data("C", p, n)
            P = t.symmetric("P", n, pd=True)
            R = t.full("R", p, n)
            t.lmi("(1)", block([[-P, A.T * P - C.T * R], [STAR, -P]]) < 0)
            L = t.derive("L", R * P.inv())
            t.check("A - L C Schur stable", schur_stable(A - L * C))
        """,
    )
    code, _, err = _check(capsys, f)
    assert code == 2
    assert "check 'A - L C Schur stable': expression multiplies shapes" in err


def test_unused_declarations_are_warnings_and_fail_with_strict(tmp_path, capsys):
    f = _module(
        tmp_path,
        """
        @theorem(id="my.unused", title="t", citation="c", kind="analysis")
        def build(t):
            (n,) = t.dims("n")
            A = t.data("A", n, n)
            t.data("B", n, n)
            t.param("beta", default=1.0)
            P = t.symmetric("P", n, pd=True)
            t.scalar("s")
            t.lmi("(1)", A.T * P + P * A < 0)
        """,
    )
    code, out, err = _check(capsys, f)
    assert code == 0 and "my.unused: ok" in out
    for needle in ("data 'B' is declared but not used", "parameter 'beta'", "decision variable 's' appears in no LMI"):
        assert needle in err
    code, _, _ = _check(capsys, f, "--strict")
    assert code == 2


def test_every_shipped_theorem_passes_check(capsys):
    from lmic.registry import list_theorems

    for thm in list_theorems():
        assert main(["check", thm.id]) == 0, capsys.readouterr().err
    capsys.readouterr()


def test_show_runs_the_same_checks(capsys):
    from lmic.registry import REGISTRY, register

    @theorem(id="my.showbad", title="t", citation="c")
    def bad(t):
        (n,) = t.dims("n")
        A = t.data("A", n, n)
        P = t.symmetric("P", n, pd=True)
        t.lmi("(1)", A.T * P < 0)

    try:
        register(bad)
        assert main(["show", "my.showbad"]) == 2
        assert "block (1,1) is not symmetric" in capsys.readouterr().err
    finally:
        REGISTRY._theorems.pop("my.showbad", None)
    assert main(["show", "qib.thm1"]) == 0


def test_undeclared_symbol_is_an_error_at_template_time():
    import sympy

    @theorem(id="my.sym", title="t", citation="c")
    def build(t):
        (n,) = t.dims("n")
        P = t.symmetric("P", n)
        t.lmi("(1)", block([[P, 0], [STAR, sympy.Symbol("g") * P]]) > 0)

    with pytest.raises(TemplateError, match=r"theorem my.sym: LMI '\(1\)' uses Symbol 'g', which is not declared"):
        build.template()


def test_check_json(tmp_path, capsys):
    import json

    f = _module(
        tmp_path,
        """
        @theorem(id="my.js", title="t", citation="c", kind="analysis")
        def build(t):
            (n,) = t.dims("n")
            A = t.data("A", n, n)
            P = t.symmetric("P", n, pd=True)
            t.lmi("(1)", A.T * P < 0)
        """,
    )
    assert main(["check", str(f), "--json"]) == 2
    doc = json.loads(capsys.readouterr().out)
    (rep,) = doc["theorems"]
    assert rep["id"] == "my.js" and doc["exit_code"] == 2
    assert rep["findings"] == ["LMI '(1)' block (1,1) is not symmetric: A.T*P"]
