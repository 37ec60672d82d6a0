"""System files and data validation: bad input is one clear DataError."""

from __future__ import annotations

import numpy as np
import pytest

from lmic.compile import compile_theorem
from lmic.errors import DataError
from lmic.system import load_system, parse_matrix

QIB = {"lmic": 1, "data": {"A": np.eye(3).tolist(), "C": [[1.0, 0.0, 0.0]]}, "params": {"beta": 0.01}}


def test_yaml_and_json_files_load_and_hash_stably(tmp_path):
    y = tmp_path / "s.yaml"
    y.write_text("lmic: 1\ndata:\n  A: [[1, 2], [3, 4]]\n  B: [[1e-5], [2]]\nparams: {beta: 0.5, psi1: printed}\n")
    j = tmp_path / "s.json"
    j.write_text(
        '{"lmic": 1, "data": {"A": [[1, 2], [3, 4]], "B": [[1e-5], [2]]}, "params": {"beta": 0.5, "psi1": "printed"}}'
    )
    a, b = load_system(y), load_system(j)
    np.testing.assert_array_equal(a.data["B"], [[1e-5], [2.0]])  # YAML's '1e-5' string is a number
    assert a.params == {"beta": 0.5, "psi1": "printed"}
    assert a.data_hash() == b.data_hash()
    assert a.with_params({"beta": 0.6}).data_hash() != a.data_hash()


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("lmic: 1\ndata: {A: [[1, 2], [3]]}\n", r"data 'A': row 2 has 1 entries, row 1 has 2"),
        ("lmic: 1\ndata: {A: [[1, .nan]]}\n", r"data 'A': entry \(1,2\) is nan"),
        ("lmic: 1\ndata: {A: [[1, .inf]]}\n", r"entry \(1,2\) is inf"),
        ("lmic: 1\ndata: {A: [[1, x]]}\n", r"data 'A': entry \(1,2\) is 'x', not a number"),
        ("lmic: 1\ndata: {A: [1, 2]}\n", r"data 'A': is a flat list"),
        ("lmic: 1\ndata: {A: [[1, 2]]\n", r"malformed YAML at line"),
        ("lmic: 7\ndata: {A: [[1]]}\n", r"not a supported system-file version"),
        ("lmic: 1\nparams: {beta: 1}\n", r"has no 'data' section"),
        ("- 1\n- 2\n", r"a system file is a mapping"),
        ("lmic: 1\ndata: {A: [[1]]}\nparams: {beta: [1, 2]}\n", r"parameter 'beta' is \[1, 2\]"),
    ],
)
def test_malformed_system_files_name_the_key(tmp_path, text, message):
    f = tmp_path / "bad.yaml"
    f.write_text(text)
    with pytest.raises(DataError, match=message):
        load_system(f)


def test_missing_file_and_malformed_json(tmp_path):
    with pytest.raises(DataError, match="no such file"):
        load_system(tmp_path / "nope.yaml")
    f = tmp_path / "bad.json"
    f.write_text('{"lmic": 1, "data": ')
    with pytest.raises(DataError, match="bad.json: malformed JSON at line 1"):
        load_system(f)


def test_parse_matrix_scalars_become_1x1():
    assert parse_matrix(2.5, "x").shape == (1, 1)


def test_wrong_shape_names_matrix_expected_and_given_shape():
    bad = {**QIB, "data": {"A": np.eye(3).tolist(), "C": [[1.0, 0.0]]}}
    with pytest.raises(DataError, match=r"data 'C' has shape 1x2, expected p x n = 1x3 \(n = 3 from rows of A, p = 1"):
        compile_theorem("qib.thm1", bad)


def test_missing_and_unknown_data_and_parameters():
    with pytest.raises(DataError, match=r"theorem qib.thm1, <system>: missing data 'C' \(p x n\)"):
        compile_theorem("qib.thm1", {"data": {"A": [[1.0]]}, "params": {"beta": 0.1}})
    with pytest.warns(UserWarning, match=r"data 'Z' not used by the theorem \(it takes: A, C\)"):
        compile_theorem("qib.thm1", {**QIB, "data": {**QIB["data"], "Z": [[1.0]]}})
    with pytest.raises(DataError, match="missing parameter 'beta'"):
        compile_theorem("qib.thm1", {"data": QIB["data"]})
    with pytest.raises(DataError, match=r"unknown parameter 'betta' \(the theorem takes: beta, .*gamma"):
        compile_theorem("qib.thm1", QIB, {"betta": 1.0})


def test_parameter_outside_its_domain_and_non_numeric_values():
    with pytest.raises(DataError, match=r"parameter nonstrict = .* is not one of 0, 1|option nonstrict"):
        compile_theorem("thesis.lyapunov", {"data": {"A": [[-1.0]]}}, {"nonstrict": 3})
    with pytest.raises(DataError, match="parameter 'beta' = 'abc' is not a number"):
        compile_theorem("qib.thm1", QIB, {"beta": "abc"})


def test_plain_float_rows_take_the_fast_path_with_the_same_result_and_errors():
    """A list of lists of floats/ints is converted at once; anything else goes entry by entry,
    and both give the same array (numpy's own conversion of the nested list is the truth) or
    the same one-line error."""
    import numpy as np

    from lmic.errors import DataError
    from lmic.system import _plain_rows, parse_matrix

    rng = np.random.default_rng(0)
    M = rng.standard_normal((7, 5)).tolist()
    M[2][3] = 4  # an int among floats
    assert _plain_rows(M) is not None
    assert np.array_equal(parse_matrix(M, "A"), np.array(M, dtype=float))
    for bad, fragment in [
        ([[1.0, True]], "is True, not a number"),
        ([[1.0, "x"]], "'x', not a number"),
        ([[1.0], [2.0, 3.0]], "row 2 has 2 entries"),
        ([[float("nan"), 1.0]], "is nan"),
        ([[10**400, 1.0]], "too large for a float64"),
    ]:
        assert _plain_rows(bad) is None or fragment == "is nan"
        try:
            parse_matrix(bad, "A")
        except DataError as err:
            assert fragment in str(err)
        else:
            raise AssertionError(f"{bad!r} was accepted")
