"""The IR's JSON format: exact round trip, schema, canonical hash, one-line errors."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lmic import schemas
from lmic.errors import IRError, LmicError
from lmic.ir import (
    LMI,
    Check,
    LinearConstraints,
    NamedExpr,
    Objective,
    Problem,
    Variable,
    load_problem,
    problem_from_dict,
    problem_hash,
    problem_to_dict,
    read_sdpa,
    save_problem,
)
from lmic.ir.jsonio import dump_problem, load_problem_json, problem_from_json, problem_to_json
from lmic.ir.problem import CHECK_KINDS
from lmic.ir.svec import tril_size

REPO = Path(__file__).resolve().parents[2]
SCHEMA_FILE = REPO / "schemas" / "ir.schema.json"
SDPLIB = REPO.parent / "shared" / "sdplib"

AWKWARD = [
    0.1,
    1e-300,
    -0.0,
    0.0,
    5e-324,
    -2.2250738585072014e-308,
    1.7976931348623157e308,
    1 / 3,
    -1e300,
    123456789.123456789,
    2.0**-1074,
    1e16 + 2,
]


# ---------------------------------------------------------------- strategies

finite = st.floats(allow_nan=False, allow_infinity=False) | st.sampled_from(AWKWARD)
nonzero = finite.filter(lambda v: v != 0)
names_st = st.text(min_size=1, max_size=8)


@st.composite
def variables_st(draw):
    out, offset = [], 0
    specs = draw(st.lists(st.sampled_from(["scalar", "full", "symmetric", "diagonal", "blockdiag"]), max_size=4))
    for k, kind in enumerate(specs):
        blocks: tuple[int, ...] = ()
        if kind == "scalar":
            shape = (1, 1)
        elif kind == "full":
            shape = (draw(st.integers(1, 3)), draw(st.integers(1, 3)))
        elif kind == "blockdiag":
            blocks = tuple(draw(st.lists(st.integers(1, 3), min_size=1, max_size=3)))
            shape = (sum(blocks), sum(blocks))
        else:
            d = draw(st.integers(1, 3))
            shape = (d, d)
        sign = draw(st.sampled_from(["free", "positive", "nonnegative", "negative", "nonpositive"]))
        v = Variable(f"v{k}", kind, shape, offset=offset, blocks=blocks, sign=sign)
        out.append(v)
        offset += v.size
    return out


@st.composite
def sparse_st(draw, rows, cols):
    if rows == 0 or cols == 0:
        return sp.csc_matrix((rows, cols))
    entries = draw(
        st.lists(
            st.tuples(st.integers(0, rows - 1), st.integers(0, cols - 1), nonzero),
            max_size=12,
            unique_by=lambda t: (t[0], t[1]),
        )
    )
    if not entries:
        return sp.csc_matrix((rows, cols))
    r, c, v = zip(*entries, strict=True)
    # deliberately non-canonical input order and format
    return sp.coo_matrix((v, (r, c)), shape=(rows, cols))


def expr_st(known):
    leaf = st.one_of(
        st.sampled_from(sorted(known)).map(lambda s: {"name": s}) if known else st.nothing(),
        finite.map(lambda v: {"num": v}),
        st.integers(0, 3).map(lambda k: {"eye": k}),
        st.tuples(st.integers(0, 3), st.integers(0, 3)).map(lambda t: {"zeros": list(t)}),
    )
    return st.recursive(
        leaf,
        lambda kids: st.one_of(
            st.tuples(
                st.sampled_from(["add", "mul", "inv", "transpose", "lambda_max"]), st.lists(kids, max_size=2)
            ).map(lambda t: {"op": t[0], "args": t[1]}),
            st.lists(st.lists(kids, min_size=1, max_size=2), min_size=1, max_size=2).map(lambda b: {"block": b}),
        ),
        max_leaves=5,
    )


json_leaf = st.none() | st.booleans() | st.integers(-(10**6), 10**6) | finite | st.text(max_size=6)
json_st = st.recursive(
    json_leaf,
    lambda kids: st.lists(kids, max_size=3) | st.dictionaries(st.text(max_size=5), kids, max_size=3),
    max_leaves=8,
)


@st.composite
def problems(draw):
    variables = draw(variables_st())
    n = sum(v.size for v in variables)
    lmis = []
    for k in range(draw(st.integers(0, 3))):
        sizes = tuple(draw(st.lists(st.integers(1, 3), min_size=1, max_size=2)))
        dim = sum(sizes)
        strict = draw(st.booleans())
        lmis.append(
            LMI(
                f"lmi {k}",
                dim,
                draw(sparse_st(tril_size(dim), 1 + n)),
                strict=strict,
                relation=draw(st.sampled_from(["<", "<=", ">", ">="])),
                block_sizes=sizes,
            )
        )
    rows = draw(st.integers(0, 3))
    linear = LinearConstraints(
        sp.csr_matrix(draw(sparse_st(rows, 1 + n))),
        draw(st.lists(st.sampled_from(["eq", "ge"]), min_size=rows, max_size=rows)),
        draw(st.lists(st.booleans(), min_size=rows, max_size=rows)),
        draw(st.lists(names_st, min_size=rows, max_size=rows)),
    )
    c = np.array(draw(st.lists(finite, min_size=1 + n, max_size=1 + n)))
    objective = Objective(draw(st.sampled_from(["min", "max", "feasibility"])), c)
    data = {}
    for key in draw(st.lists(st.sampled_from(["A", "B", "gamma", "Q", "x0"]), unique=True)):
        if draw(st.booleans()):
            data[key] = draw(finite)
        else:
            shape = tuple(draw(st.lists(st.integers(1, 3), min_size=1, max_size=2)))
            size = int(np.prod(shape))
            vals = draw(st.lists(finite, min_size=size, max_size=size))
            data[key] = np.array(vals, dtype=float).reshape(shape)
    known = set(data) | {v.name for v in variables}
    derived = []
    for k in range(draw(st.integers(0, 2))):
        derived.append(NamedExpr(f"d{k}", draw(expr_st(known)), draw(st.text(max_size=10))))
        known.add(f"d{k}")
    checks = []
    for k in range(draw(st.integers(0, 2))):
        kind = draw(st.sampled_from(CHECK_KINDS))
        bound = draw(finite) if kind in ("less_than", "greater_than") else draw(st.none() | finite)
        checks.append(Check(f"c{k}", kind, draw(expr_st(known)), bound, draw(st.text(max_size=5))))
    meta = draw(st.dictionaries(st.text(max_size=6), json_st, max_size=4))
    meta["params"] = {"printed": "yes", "beta": draw(finite)}
    return Problem(variables, lmis, linear, objective, data, derived, checks, meta)


# ---------------------------------------------------------------- helpers


def _bits(a) -> np.ndarray:
    return np.ascontiguousarray(np.asarray(a, dtype=float)).view(np.int64)


def _same_bits(a, b) -> bool:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return a.shape == b.shape and np.array_equal(_bits(a), _bits(b))


def assert_same_problem(p: Problem, q: Problem) -> None:
    """Bitwise equality of everything an IR holds."""
    assert p.variables == q.variables
    assert len(p.lmis) == len(q.lmis)
    for a, b in zip(p.lmis, q.lmis, strict=True):
        assert (a.name, a.dim, a.strict, a.relation, tuple(a.block_sizes)) == (
            b.name,
            b.dim,
            b.strict,
            b.relation,
            tuple(b.block_sizes),
        )
        assert _same_bits(a.coeffs.toarray() + 0.0, b.coeffs.toarray())  # + 0.0: -0.0 -> 0.0
    assert _same_bits(p.linear.A.toarray() + 0.0, q.linear.A.toarray())
    assert (p.linear.kinds, p.linear.strict, p.linear.names) == (q.linear.kinds, q.linear.strict, q.linear.names)
    assert p.objective.sense == q.objective.sense
    assert _same_bits(p.objective.c, q.objective.c)  # -0.0 survives
    assert p.data.keys() == q.data.keys()
    for k, v in p.data.items():
        w = q.data[k]
        if isinstance(v, np.ndarray):
            assert isinstance(w, np.ndarray) and w.dtype == float and _same_bits(v, w)
        else:
            assert type(w) is float and _same_bits(v, w)
    # expression trees, checks and meta: compare through repr so that -0.0 != 0.0
    assert repr([(d.name, d.expr, d.doc) for d in p.derived]) == repr([(d.name, d.expr, d.doc) for d in q.derived])
    assert repr([(c.name, c.kind, c.expr, c.bound, c.doc) for c in p.checks]) == repr(
        [(c.name, c.kind, c.expr, c.bound, c.doc) for c in q.checks]
    )
    assert json.dumps(p.meta, sort_keys=True) == json.dumps(q.meta, sort_keys=True)
    assert problem_hash(p) == problem_hash(q)


def small_problem(**overrides) -> Problem:
    P = Variable("P", "symmetric", (2, 2), offset=0)
    g = Variable("gamma", "scalar", (1, 1), offset=3, sign="positive")
    coeffs = sp.csc_matrix(([1.0, 1.0, 1.0, 0.1], ([0, 1, 2, 0], [1, 2, 3, 0])), shape=(3, 5))
    args = dict(
        variables=[P, g],
        lmis=[LMI("P > 0", 2, coeffs, strict=True, relation=">")],
        linear=LinearConstraints(sp.csr_matrix([[-1e-300, 0, 0, 0, 1.0]]), ["ge"], [True], ["gamma > 1e-300"]),
        objective=Objective("min", [-0.0, 0.0, 0.0, 0.0, 1.0]),
        data={"A": np.array([[0.1, -0.0], [1e-300, 2.0]]), "beta": 0.1},
        derived=[NamedExpr("L", {"op": "inv", "args": [{"name": "P"}]}, "L = P^-1")],
        checks=[
            Check("L stable", "schur_stable", {"name": "L"}),
            Check("gamma small", "less_than", {"name": "gamma"}, 0.1),
        ],
        meta={"theorem": "test.small", "params": {"beta": 0.1, "variant": "printed"}},
    )
    args.update(overrides)
    return Problem(**args)


# ---------------------------------------------------------------- round trip


@given(problems())
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_random_problems_round_trip_exactly(p):
    d = problem_to_dict(p)
    assert_same_problem(p, problem_from_dict(d))
    assert_same_problem(p, problem_from_json(problem_to_json(p)))
    assert_same_problem(p, problem_from_json(problem_to_json(p, indent=False)))
    # the dict is plain JSON and it is canonical: a second trip gives the same text
    assert problem_to_json(problem_from_dict(json.loads(json.dumps(d)))) == problem_to_json(p)


@given(problems())
@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_random_problems_validate_against_the_schema(p):
    jsonschema.Draft202012Validator(json.loads(SCHEMA_FILE.read_text())).validate(json.loads(problem_to_json(p)))


def test_awkward_floats_survive_a_file_round_trip(tmp_path):
    p = small_problem()
    f = tmp_path / "ir.json"
    dump_problem(p, f)
    q = load_problem_json(f)
    assert_same_problem(p, q)
    assert np.signbit(q.objective.c[0]) and q.objective.c[0] == 0.0
    assert q.data["A"][0, 1] == 0.0 and np.signbit(q.data["A"][0, 1])
    assert q.data["A"][0, 0] == 0.1 and q.data["A"][1, 0] == 1e-300
    assert q.linear.A[0, 0] == -1e-300
    assert type(q.data["beta"]) is float and q.data["beta"] == 0.1
    assert q.meta["params"]["variant"] == "printed"


def test_every_float_repr_round_trips():
    vals = np.array(AWKWARD + list(np.random.default_rng(0).standard_normal(200) * 1e-200))
    p = small_problem(data={"v": vals})
    q = problem_from_json(problem_to_json(p))
    assert _same_bits(q.data["v"], vals)


def test_data_shapes_and_types():
    data = {
        "vec": np.arange(3.0),
        "col": np.ones((3, 1)),
        "cube": np.zeros((2, 2, 2)),
        "ints": np.array([[1, 2]]),
        "lst": [[1, 2], [3, 4]],
        "k": 3,
        "f": np.float64(2.5),
    }
    q = problem_from_dict(problem_to_dict(small_problem(data=data)))
    assert q.data["vec"].shape == (3,) and q.data["col"].shape == (3, 1)
    assert q.data["cube"].shape == (2, 2, 2)
    assert q.data["ints"].dtype == float and np.array_equal(q.data["ints"], [[1.0, 2.0]])
    assert isinstance(q.data["lst"], np.ndarray) and q.data["lst"].shape == (2, 2)
    assert type(q.data["k"]) is float and q.data["k"] == 3.0
    assert type(q.data["f"]) is float and q.data["f"] == 2.5


def test_triplets_are_canonical():
    A = sp.coo_matrix(([3.0, 0.0, 1.0, 2.0, 5.0], ([2, 1, 0, 0, 2], [1, 1, 2, 1, 1])), shape=(3, 5))
    p = small_problem(lmis=[LMI("F", 2, A)])
    coeffs = problem_to_dict(p)["lmis"][0]["coeffs"]
    # sorted by col then row, the zero dropped, the duplicate (2, 1) summed
    assert coeffs == {"row": [0, 2, 0], "col": [1, 1, 2], "val": [2.0, 8.0, 1.0]}


def test_hash_is_canonical_and_sensitive():
    p = small_problem()
    csr = small_problem(lmis=[LMI("P > 0", 2, p.lmis[0].coeffs.tocsr(), relation=">")])
    assert problem_hash(p) == problem_hash(csr)
    assert problem_hash(p) == problem_hash(problem_from_json(problem_to_json(p)))
    changed = small_problem(objective=Objective("min", [0.0, 0.0, 0.0, 0.0, 1.0 + 2**-52]))
    assert problem_hash(changed) != problem_hash(p)
    signed = small_problem(objective=Objective("min", [0.0, 0.0, 0.0, 0.0, 1.0]))
    assert problem_hash(signed) != problem_hash(p)  # -0.0 and 0.0 are different bits


def test_hash_is_pinned():
    # certificates store this hash: a change of the canonical serialisation must be deliberate
    t = Variable("t", "scalar", (1, 1))
    p = Problem(
        [t], [LMI("t > 0", 1, sp.csc_matrix([[0.0, 1.0]]))], LinearConstraints.empty(1), Objective("min", [0.0, 1.0])
    )
    canonical = (
        '{"checks":[],"data":{},"derived":[],"linear":{"col":[],"kinds":[],"names":[],"row":[],'
        '"strict":[],"val":[]},"lmic_ir":1,"lmis":[{"block_sizes":[1],"coeffs":{"col":[1],'
        '"row":[0],"val":[1.0]},"dim":1,"name":"t > 0","relation":">","strict":true}],"meta":{},'
        '"objective":{"c":{"idx":[1],"val":[1.0]},"sense":"min"},"variables":[{"blocks":[],'
        '"kind":"scalar","name":"t","offset":0,"shape":[1,1],"sign":"free"}]}'
    )
    import hashlib

    assert problem_hash(p) == hashlib.sha256(canonical.encode()).hexdigest()


def test_io_dispatch(tmp_path):
    p = small_problem()
    save_problem(p, tmp_path / "p.json")
    assert_same_problem(p, load_problem(tmp_path / "p.json"))
    assert_same_problem(p, load_problem(str(tmp_path / "p.json")))
    with pytest.raises(IRError, match=r"p\.txt: unknown problem file type"):
        load_problem(tmp_path / "p.txt")
    with pytest.raises(IRError, match=r"p\.yaml: unknown problem file type"):
        save_problem(p, tmp_path / "p.yaml")
    assert not (tmp_path / "p.yaml").exists()


@pytest.mark.skipif(not SDPLIB.is_dir(), reason="SDPLIB test data not found")
@pytest.mark.parametrize("name", ["control1", "arch0", "qap5", "truss1"])
def test_sdplib_problems_round_trip_through_json(name, tmp_path):
    p = read_sdpa(SDPLIB / f"{name}.dat-s")
    save_problem(p, tmp_path / "p.json")
    assert_same_problem(p, load_problem(tmp_path / "p.json"))


def test_unwritable_values_are_refused(tmp_path):
    with pytest.raises(IRError, match=r"data\.A: has a non-finite entry"):
        problem_to_dict(small_problem(data={"A": np.array([1.0, np.nan])}))
    with pytest.raises(IRError, match=r"data\.s: str is not a number or an array"):
        problem_to_dict(small_problem(data={"s": "text"}))
    with pytest.raises(IRError, match=r"data\.z: not a numeric array"):
        problem_to_dict(small_problem(data={"z": np.array([1j])}))
    with pytest.raises(IRError, match=r"meta\.when: a object cannot be written|meta\.when"):
        problem_to_dict(small_problem(meta={"when": object()}))
    with pytest.raises(IRError, match=r"meta\.x: inf is not a finite number"):
        problem_to_dict(small_problem(meta={"x": float("inf")}))
    f = tmp_path / "bad.json"
    with pytest.raises(IRError):
        dump_problem(small_problem(data={"A": np.array([np.inf])}), f)
    assert not f.exists()


# ---------------------------------------------------------------- the schema


def test_schema_helper_finds_the_checkout_schema():
    assert schemas.load_schema("ir") == json.loads(SCHEMA_FILE.read_text())
    assert schemas.load_schema("ir.schema.json")["title"] == "lmic IR"
    assert Path(schemas.schema_path("ir")) == SCHEMA_FILE
    jsonschema.Draft202012Validator.check_schema(schemas.load_schema("ir"))
    # a copy: callers cannot corrupt the cache
    s = schemas.load_schema("ir")
    s["title"] = "changed"
    assert schemas.load_schema("ir")["title"] == "lmic IR"


def test_schema_helper_prefers_the_installed_copy(tmp_path, monkeypatch):
    installed = tmp_path / "lmic"
    (installed / "_schemas").mkdir(parents=True)
    (installed / "_schemas" / "ir.schema.json").write_text('{"title": "installed"}')
    monkeypatch.setattr(schemas.resources, "files", lambda pkg: installed)
    schemas._load.cache_clear()
    try:
        assert schemas.load_schema("ir") == {"title": "installed"}
        monkeypatch.setattr(schemas, "_CHECKOUT_DIR", tmp_path / "nowhere")
        with pytest.raises(LmicError, match="schema 'nothing.schema.json' not found"):
            schemas.load_schema("nothing")
    finally:
        schemas._load.cache_clear()


def test_schema_describes_the_convention():
    text = json.loads(SCHEMA_FILE.read_text())["description"]
    for phrase in ("lower triangle", "column-major", "unscaled", "col = 0 for F0", "1 + k"):
        assert phrase in text


def _valid_dicts():
    yield problem_to_dict(small_problem())
    yield problem_to_dict(small_problem(derived=[], checks=[], data={}, meta={}))
    minimal = {
        "lmic_ir": 1,
        "variables": [{"name": "t", "kind": "scalar", "shape": [1, 1], "offset": 0}],
        "lmis": [{"name": "t > 0", "dim": 1, "coeffs": {"row": [0], "col": [1], "val": [1]}}],
        "linear": {"row": [], "col": [], "val": [], "kinds": [], "strict": [], "names": []},
        "objective": {"sense": "feasibility", "c": {"idx": [], "val": []}},
    }
    yield minimal
    if SDPLIB.is_dir():
        yield problem_to_dict(read_sdpa(SDPLIB / "arch0.dat-s"))


def test_valid_dicts_pass_the_schema_and_load():
    validator = jsonschema.Draft202012Validator(json.loads(SCHEMA_FILE.read_text()))
    for d in _valid_dicts():
        validator.validate(d)
        problem_from_dict(d)


def _mutate(path, value):
    def apply(d):
        node = d
        for key in path[:-1]:
            node = node[key]
        if value is KeyError:
            del node[path[-1]]
        else:
            node[path[-1]] = value
        return d

    return apply


SCHEMA_VIOLATIONS = {
    "missing variables": _mutate(["variables"], KeyError),
    "version as string": _mutate(["lmic_ir"], "1"),
    "unknown top-level key": _mutate(["extra"], 1),
    "bad kind": _mutate(["variables", 0, "kind"], "hermitian"),
    "shape of 3": _mutate(["variables", 0, "shape"], [2, 2, 1]),
    "dim as string": _mutate(["lmis", 0, "dim"], "2"),
    "negative row": _mutate(["lmis", 0, "coeffs", "row", 0], -1),
    "string value": _mutate(["lmis", 0, "coeffs", "val", 0], "1.0"),
    "bad relation": _mutate(["lmis", 0, "relation"], "=="),
    "bad linear kind": _mutate(["linear", "kinds", 0], "le"),
    "bad sense": _mutate(["objective", "sense"], "minimize"),
    "string data": _mutate(["data", "beta"], "0.1"),
    "bad operator": _mutate(["derived", 0, "expr"], {"op": "det", "args": []}),
    "bad check kind": _mutate(["checks", 0, "kind"], "stable"),
    "missing coeffs": _mutate(["lmis", 0, "coeffs"], KeyError),
    "extra variable key": _mutate(["variables", 0, "value"], 1.0),
}


@pytest.mark.parametrize("case", sorted(SCHEMA_VIOLATIONS))
def test_invalid_dicts_fail_the_schema_and_the_loader(case):
    d = SCHEMA_VIOLATIONS[case](copy.deepcopy(problem_to_dict(small_problem())))
    validator = jsonschema.Draft202012Validator(json.loads(SCHEMA_FILE.read_text()))
    assert not validator.is_valid(d)
    with pytest.raises(IRError, match=r"^ir\.json: "):
        problem_from_dict(d, "ir.json")


# ---------------------------------------------------------------- malformed files


def _write(tmp_path, text) -> Path:
    f = tmp_path / "ir.json"
    f.write_text(text) if isinstance(text, str) else f.write_bytes(text)
    return f


def _text(mutate=None) -> str:
    d = problem_to_dict(small_problem())
    if mutate:
        mutate(d)
    return json.dumps(d)


def _err(tmp_path, text) -> str:
    f = _write(tmp_path, text)
    with pytest.raises(IRError) as info:
        load_problem_json(f)
    msg = str(info.value)
    assert msg.startswith(f"{f}: ")
    assert "\n" not in msg
    return msg[len(str(f)) + 2 :]


def test_bad_json(tmp_path):
    assert _err(tmp_path, "{").startswith("not valid JSON (line 1, column 2)")
    assert _err(tmp_path, "").startswith("not valid JSON (line 1, column 1)")
    assert _err(tmp_path, "[]") == "an IR must be a JSON object, not list"
    assert _err(tmp_path, b"\xff\xfe{}") == "not UTF-8 text (byte 0)"
    text = _text()
    assert _err(tmp_path, text[: len(text) // 2]).startswith("not valid JSON")
    assert _err(tmp_path, '{"lmic_ir": 1, "lmic_ir": 1}') == "duplicate key 'lmic_ir'"


def test_missing_file(tmp_path):
    with pytest.raises(IRError, match=r"nope\.json: cannot read: No such file"):
        load_problem_json(tmp_path / "nope.json")


def test_version(tmp_path):
    assert _err(tmp_path, _text(_mutate(["lmic_ir"], 2))) == ("lmic_ir: unsupported IR version 2 (this lmic reads 1)")
    assert _err(tmp_path, _text(_mutate(["lmic_ir"], KeyError))).startswith("lmic_ir: missing format version")


@pytest.mark.parametrize(
    ("mutate", "expected"),
    [
        (_mutate(["variables"], KeyError), "(top level): 'variables' is a required property"),
        (_mutate(["lmis", 0, "dim"], "2"), "lmis[0].dim: '2' is not of type 'integer'"),
        (_mutate(["lmis", 0, "coeffs", "row"], KeyError), "lmis[0].coeffs: 'row' is a required property"),
        (_mutate(["variables", 1, "kind"], "hermitian"), "variables[1].kind: 'hermitian' is not one of"),
        (_mutate(["lmis", 0, "coeffs", "row", 2], 17), "lmis[0].coeffs: row index 17 out of range for dimension 2"),
        (_mutate(["lmis", 0, "coeffs", "col", 2], 9), "lmis[0].coeffs: col index 9 out of range for 1 + n = 5 columns"),
        (
            _mutate(["lmis", 0, "coeffs", "val"], [1.0]),
            "lmis[0].coeffs: row, col and val have different lengths (4, 4, 1)",
        ),
        (
            _mutate(["lmis", 0, "coeffs"], {"row": [0, 0], "col": [1, 1], "val": [1.0, 2.0]}),
            "lmis[0].coeffs: duplicate entry (row 0, col 1)",
        ),
        (_mutate(["lmis", 0, "block_sizes"], [1, 2]), "lmis[0].block_sizes: [1, 2] do not add up to dimension 2"),
        (_mutate(["variables", 1, "offset"], 4), "variables[1].offset: 4, expected 3"),
        (_mutate(["variables", 1, "name"], "P"), "variables[1].name: duplicate variable name 'P'"),
        (_mutate(["variables", 0, "shape"], [2, 3]), "variables[0]: variable 'P': a symmetric variable is square"),
        (_mutate(["variables", 0, "blocks"], [1, 1]), "variables[0].blocks: only a blockdiag variable has blocks"),
        (_mutate(["linear", "names"], []), "linear: kinds, strict and names have different lengths (1, 1, 0)"),
        (_mutate(["linear", "row", 0], 1), "linear: row index 1 out of range for 1 rows"),
        (_mutate(["objective", "c", "idx", 0], 5), "objective.c: index 5 out of range for 1 + n = 5 entries"),
        (_mutate(["objective", "c", "idx"], [0]), "objective.c: idx and val have different lengths (1, 2)"),
        (_mutate(["data", "A"], [[1.0, 2.0], [3.0]]), "data.A: ragged or non-numeric nested list"),
        (
            _mutate(["derived", 0, "expr"], {"name": "Q"}),
            "derived[0].expr: uses 'Q', which is not data, a variable or an earlier derived quantity",
        ),
        (_mutate(["checks", 1, "bound"], None), "checks[1].bound: a 'less_than' check needs a bound"),
        (_mutate(["checks", 0, "kind"], "stable"), "checks[0].kind: 'stable' is not one of"),
    ],
    ids=lambda v: v if isinstance(v, str) else "",
)
def test_field_errors(tmp_path, mutate, expected):
    assert _err(tmp_path, _text(mutate)).startswith(expected)


@pytest.mark.parametrize(
    ("literal", "where"),
    [
        ("NaN", "lmis[0].coeffs.val[1]"),
        ("Infinity", "data.A[1][0]"),
        ("-Infinity", "meta.x"),
        ("1e400", "objective.c.val[1]"),
    ],
)
def test_non_finite_numbers(tmp_path, literal, where):
    d = problem_to_dict(small_problem())
    d["meta"]["x"] = 1.0
    text = json.dumps(d)
    target = {
        "lmis[0].coeffs.val[1]": '"val": [0.1, 1.0,',
        "data.A[1][0]": "[1e-300, 2.0]",
        "meta.x": '"x": 1.0',
        "objective.c.val[1]": '"val": [-0.0, 1.0]',
    }[where]
    replacement = {
        "lmis[0].coeffs.val[1]": f'"val": [0.1, {literal},',
        "data.A[1][0]": f"[{literal}, 2.0]",
        "meta.x": f'"x": {literal}',
        "objective.c.val[1]": f'"val": [-0.0, {literal}]',
    }[where]
    assert target in text
    assert _err(tmp_path, text.replace(target, replacement)) == f"{where}: NaN or infinite number"


def test_long_arrays_are_checked_beyond_the_schema_prefix(tmp_path):
    n = 50
    x = Variable("x", "full", (n, 1))
    lin = LinearConstraints(
        sp.csr_matrix(np.hstack([np.zeros((n, 1)), np.eye(n)])),
        ["ge"] * n,
        [False] * n,
        [f"x{i} >= 0" for i in range(n)],
    )
    p = Problem([x], [], lin, Objective("min", np.ones(1 + n)), data={"M": np.ones((30, 30))})
    for path, value, expected in [
        (["linear", "row", 40], 1.5, "linear.row: expected a list of integers"),
        (["linear", "val", 40], "1", "linear.val: expected a list of numbers"),
        (["linear", "kinds", 40], "le", "linear.kinds[40]: 'le' is not 'eq' or 'ge'"),
        (["linear", "strict", 40], 0, "linear.strict[40]: 0 is not a boolean"),
        (["linear", "names", 40], 7, "linear.names[40]: 7 is not a string"),
        (["data", "M", 20, 20], "x", "data.M: ragged or non-numeric nested list"),
        (["objective", "c", "val", 40], None, "objective.c.val: expected a list of numbers"),
    ]:
        assert _err(tmp_path, _text_of(p, _mutate(path, value))).startswith(expected), path


def _text_of(p, mutate):
    d = problem_to_dict(p)
    mutate(d)
    return json.dumps(d)


def test_constructor_errors_are_prefixed_with_the_source():
    d = problem_to_dict(small_problem())
    d["variables"][0]["kind"] = "blockdiag"
    d["variables"][0]["blocks"] = [1]
    with pytest.raises(IRError, match=r"^x\.json: variables\[0\]: variable 'P': block sizes"):
        problem_from_dict(d, "x.json")
