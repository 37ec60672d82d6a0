"""lmic.output.json_text writes exactly what json.dumps(indent=2, allow_nan=False) writes.

The reference is the standard library's own encoder, run on the same value: any difference of a
character (or an error raised by one and not the other) fails.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lmic.output import json_text

scalars = (
    st.none()
    | st.booleans()
    | st.integers(-(10**20), 10**20)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=8)
)
values = st.recursive(
    scalars | st.lists(st.floats(allow_nan=False, allow_infinity=False), max_size=6),
    lambda inner: (
        st.lists(inner, max_size=5)
        | st.tuples(inner, inner)
        | st.dictionaries(st.text(max_size=6) | st.integers(-5, 5) | st.booleans() | st.none(), inner, max_size=5)
    ),
    max_leaves=40,
)


def _reference(obj):
    try:
        return json.dumps(obj, indent=2, allow_nan=False)
    except (ValueError, TypeError) as err:
        return type(err)


def _ours(obj):
    try:
        return json_text(obj)
    except (ValueError, TypeError) as err:
        return type(err)


@settings(max_examples=400, deadline=None)
@given(values)
def test_same_text_or_same_error_as_json_dumps(obj):
    assert _ours(obj) == _reference(obj)


@pytest.mark.parametrize(
    "obj",
    [
        {"P": [[1.0, -2.5e-300, 3.0], [0.1, 1e16, -0.0]], "n": 3, "ok": True, "why": 'é\n"x"'},
        [float("nan")],
        {"x": [1.0, math.inf]},
        {1: "int key", 2.5: "float key", None: "none key"},
        {"numpy": np.float64(1.5)},
        {"numpy": np.int64(3)},
        [[], {}, [[]], ""],
    ],
)
def test_the_cases_a_solve_writes_and_the_ones_left_to_json(obj):
    assert _ours(obj) == _reference(obj)


def test_a_cycle_raises_like_json_dumps():
    a: list = []
    a.append(a)
    assert _ours(a) is _reference(a) is ValueError
