"""Property-based and mutation tests of every reader (hypothesis; about 30 s in all).

* Round trips: a random IR survives JSON and SDPA export unchanged (same hash / same data).
* Mutants: random byte edits of real files (a system file, an SDPA file, an IR, a certificate)
  are either read or rejected with an :class:`~lmic.errors.LmicError` (one line on the command
  line), never any other exception.
* Arbitrary text to the limited YAML and JSON loaders, and to the simulation expression parser.

The long campaign (subprocesses under memory and time limits, thousands of runs) is
``benchmarks/fuzz.py``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lmic.errors import LmicError

ROOT = Path(__file__).resolve().parents[2]
SYSTEM_TEXT = (ROOT / "examples" / "qib.thm1.flexible-joint.yaml").read_text()
SDPA_TEXT = "2\n2\n2 -1\n1.0 -2.5\n0 1 1 1 1.0\n1 1 1 1 1.0\n1 1 1 2 0.5\n2 1 2 2 1.0\n2 2 1 1 3.0\n"

FAST = settings(max_examples=50, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)


def _mutate(data: bytes, edits: list[tuple[int, int, bytes]]) -> bytes:
    out = bytearray(data)
    for pos, kind, chunk in edits:
        if not out:
            out += chunk
            continue
        i = pos % len(out)
        if kind == 0:
            out[i : i + 1] = chunk  # replace one byte by a chunk
        elif kind == 1:
            del out[i : i + len(chunk) + 1]  # delete
        elif kind == 2:
            out[i:i] = chunk * 50  # insert a repeated chunk (digits, brackets, anchors...)
        else:
            out[i:i] = out[max(0, i - 40) : i]  # duplicate a span
    return bytes(out)


CHUNKS = st.sampled_from(
    [b"9", b"99999999999999999999", b"[", b"{", b"]", b"-", b".nan", b"&a ", b"*a", b"\x00", b"\xff", b"e999",
     b"\n", b": ", b"'", b"1e-400", b"\xd9\xa1", b"!!python/object ", b"<<: *a\n"]
)  # fmt: skip
EDITS = st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 3), CHUNKS), min_size=1, max_size=4)


def _reads_or_rejects(fn, *args) -> None:
    try:
        fn(*args)
    except LmicError as err:
        assert "\n" not in " ".join(str(err).split()) and str(err)


@FAST
@given(EDITS)
def test_system_file_mutants(tmp_path_factory, edits):
    from lmic.system import load_system

    path = tmp_path_factory.mktemp("sys") / "s.yaml"
    path.write_bytes(_mutate(SYSTEM_TEXT.encode(), edits))
    _reads_or_rejects(load_system, path)


@FAST
@given(EDITS)
def test_simulation_section_mutants(tmp_path_factory, edits):
    from lmic.simulate.run import check_section
    from lmic.system import load_system

    path = tmp_path_factory.mktemp("sim") / "s.yaml"
    path.write_bytes(_mutate(SYSTEM_TEXT.encode(), edits))

    def read(p):
        s = load_system(p)
        if "simulation" in s.raw:
            check_section(s.raw["simulation"], "simulation")

    _reads_or_rejects(read, path)


@FAST
@given(EDITS)
def test_sdpa_mutants(edits):
    from lmic.ir.sdpa import read_sdpa

    text = _mutate(SDPA_TEXT.encode(), edits).decode("latin-1")
    _reads_or_rejects(read_sdpa, text + "\n")


@pytest.fixture(scope="module")
def ir_text() -> str:
    from lmic.compile import compile_theorem
    from lmic.ir.jsonio import problem_to_json

    return problem_to_json(compile_theorem("qib.thm1", ROOT / "examples" / "qib.thm1.flexible-joint.yaml"))


@FAST
@given(edits=EDITS)
def test_ir_json_mutants(ir_text, edits):
    from lmic.ir.jsonio import problem_from_json

    text = _mutate(ir_text.encode(), edits).decode("utf-8", errors="replace")
    _reads_or_rejects(problem_from_json, text, "ir.json")


@pytest.fixture(scope="module")
def cert_text(tmp_path_factory) -> str:
    from lmic.certify import certify, write_certificate
    from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    from lmic.solution import Solution

    prob = Problem(
        [Variable("p", "scalar", (1, 1))],
        [LMI("p > 0", 1, sp.csc_matrix([[0.0, 1.0]]))],
        LinearConstraints.empty(1),
        Objective("feasibility", np.zeros(2)),
    )
    sol = Solution("optimal", x=np.array([1.0]), backend="clarabel")
    path = tmp_path_factory.mktemp("cert") / "c.json"
    write_certificate(path, prob, sol, certify(prob, sol))
    return path.read_text()


@FAST
@given(edits=EDITS)
def test_certificate_mutants_are_read_and_audited_or_rejected(tmp_path_factory, cert_text, edits):
    from lmic.certify.certificate import audit_certificate

    path = tmp_path_factory.mktemp("c") / "c.json"
    data = _mutate(cert_text.encode(), edits)
    path.write_bytes(data)
    try:
        r = audit_certificate(path)
    except LmicError:
        return
    # read and audited: a mutant that still parses passes only if nothing but informational
    # fields changed
    if r.ok:
        a, b = json.loads(cert_text), json.loads(data)
        a.pop("created"), b.pop("created")
        a["certificate"].pop("time_s"), b["certificate"].pop("time_s", None)
        assert a == b


@FAST
@given(st.text(max_size=300))
def test_yaml_and_json_loaders_on_arbitrary_text(text):
    from lmic.limits import load_json_text, load_yaml_text

    _reads_or_rejects(load_yaml_text, text, "t.yaml")
    _reads_or_rejects(load_json_text, text, "t.json")


@FAST
@given(st.text(alphabet="x1u t0.5e+-*/()sincoexplgqrtabmhd,^", max_size=120))
def test_expression_parser_never_crashes(text):
    from lmic.simulate.parser import parse

    _reads_or_rejects(parse, text, {"x1", "u", "t"}, "f")


# -- round trips ---------------------------------------------------------------------------------


@st.composite
def problems(draw):
    from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable

    n = draw(st.integers(1, 4))
    variables = [Variable(f"v{i}", "scalar", (1, 1), offset=i) for i in range(n)]
    finite = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False, width=64)
    lmis = []
    for k in range(draw(st.integers(1, 3))):
        d = draw(st.integers(1, 3))
        dense = np.array(
            draw(st.lists(finite, min_size=d * (d + 1) // 2 * (n + 1), max_size=d * (d + 1) // 2 * (n + 1)))
        )
        lmis.append(LMI(f"L{k}", d, sp.csc_matrix(dense.reshape(d * (d + 1) // 2, n + 1)), strict=False, relation=">="))
    c = np.array(draw(st.lists(finite, min_size=n + 1, max_size=n + 1)))
    return Problem(variables, lmis, LinearConstraints.empty(n), Objective(draw(st.sampled_from(["min", "max"])), c))


@FAST
@given(problems())
def test_ir_json_round_trip(prob):
    from lmic.ir.jsonio import problem_from_json, problem_hash, problem_to_json

    back = problem_from_json(problem_to_json(prob), "rt.json")
    assert problem_hash(back) == problem_hash(prob)


@FAST
@given(problems())
def test_sdpa_round_trip(prob):
    from lmic.ir.sdpa import read_sdpa, sdpa_text

    back = read_sdpa(sdpa_text(prob))
    assert [lmi.dim for lmi in back.lmis] == [lmi.dim for lmi in prob.lmis]
    for a, b in zip(prob.lmis, back.lmis, strict=True):
        assert (a.coeffs != b.coeffs).nnz == 0
    assert back.objective.sense == prob.objective.sense
    assert np.array_equal(back.objective.c, prob.objective.c)
