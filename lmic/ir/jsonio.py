"""The IR as JSON: an exact, schema-validated round trip (the format; the code is split by job).

Format (version 1, described by ``schemas/ir.schema.json``)::

    {"lmic_ir": 1,
     "meta": {...},
     "variables": [{"name", "kind", "shape", "offset", "blocks", "sign"}, ...],
     "lmis": [{"name", "dim", "strict", "relation", "block_sizes",
               "coeffs": {"row": [...], "col": [...], "val": [...]}}, ...],
     "linear": {"row": [...], "col": [...], "val": [...], "kinds", "strict", "names"},
     "objective": {"sense", "c": {"idx": [...], "val": [...]}},
     "data": {name: number or nested list},
     "derived": [{"name", "expr", "doc"}, ...],
     "checks": [{"name", "kind", "expr", "bound", "doc"}, ...]}

* LMI coefficients use the storage convention of :mod:`lmic.ir.svec`: ``row`` is the storage
  index of the lower triangle (column-major, unscaled), ``col`` is 0 for ``F0`` and ``1 + k``
  for ``F_k``. Linear rows use column 0 for the constant ``a0``.
* Sparse triplets are canonical: sorted by ``col`` then ``row``, no duplicates, no zeros. The
  objective vector keeps ``-0.0`` entries (only ``+0.0`` is left out) so that every float of the
  IR survives bitwise.
* Floats are written with ``repr`` (Python's shortest round-tripping form), so a load gives back
  bitwise equal numbers. NaN and infinities are rejected, on writing and on reading.
* Numpy arrays in ``data`` are written as nested lists and load as float arrays; scalars load
  as floats. ``meta`` is free-form JSON (strings allowed, e.g. ``meta["params"]``).

Writing is :mod:`lmic.ir.jsonwrite` (dict, text, file, hash), reading :mod:`lmic.ir.jsonread`,
validation :mod:`lmic.ir.jsonvalid` (schema, non-finite numbers); this module re-exports them.

Every malformed input raises :class:`~lmic.errors.IRError` with one line naming the source and
the field, e.g. ``ir.json: lmis[2].coeffs: row index 17 out of range for dimension 5``.

Examples
--------
>>> import scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> t = Variable("t", "scalar", (1, 1))
>>> lmi = LMI("t > 0", 1, sp.csc_matrix([[0.0, 1.0]]), strict=True)
>>> prob = Problem([t], [lmi], LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
>>> d = problem_to_dict(prob)
>>> d["lmis"][0]["coeffs"]
{'row': [0], 'col': [1], 'val': [1.0]}
>>> problem_hash(problem_from_dict(d)) == problem_hash(prob)
True
"""

from __future__ import annotations

from lmic.ir.jsonread import load_problem_json, problem_from_dict, problem_from_json
from lmic.ir.jsonvalid import IR_VERSION, validate_ir_dict
from lmic.ir.jsonwrite import dump_problem, problem_hash, problem_to_dict, problem_to_json

__all__ = [
    "IR_VERSION",
    "problem_to_dict",
    "problem_from_dict",
    "problem_to_json",
    "problem_from_json",
    "dump_problem",
    "load_problem_json",
    "problem_hash",
    "validate_ir_dict",
]
