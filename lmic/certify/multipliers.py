"""Reading a dual point or a Farkas certificate: ``{'lmis': [Z_i], 'linear': y}`` as arrays.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> mats, y = parse_multipliers(p, {"lmis": [[[2.0]]]}, "dual point")
>>> mats[0].tolist(), y.shape
([[2.0]], (0,))
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lmic.errors import CertificateError
from lmic.ir.problem import Problem

__all__ = ["parse_multipliers"]


def parse_multipliers(
    problem: Problem, record: Any, what: str, missing_is_zero: bool = False
) -> tuple[list[np.ndarray], np.ndarray]:
    """The symmetrised LMI multipliers ``Z_i`` and the row multipliers ``y`` of ``record``.

    ``what`` names the record in messages (``"Farkas certificate"``, ``"dual point"``). With
    ``missing_is_zero``, fewer (or ``None``) LMI multipliers than LMIs stand for zeros;
    otherwise there must be one per LMI. Raises :class:`CertificateError` on a wrong count or
    shape and on non-finite entries.

    >>> parse_multipliers(None, 1, "dual point")
    Traceback (most recent call last):
    ...
    lmic.errors.CertificateError: a dual point is a dict {'lmis': [Z_i], 'linear': y}
    """
    if not isinstance(record, dict):
        raise CertificateError(f"a {what} is a dict {{'lmis': [Z_i], 'linear': y}}")
    mats_in: Any = record.get("lmis")  # untrusted: a list of matrices, None or anything else
    n_in = 0 if mats_in is None else len(mats_in)
    if n_in > len(problem.lmis) or (not missing_is_zero and n_in != len(problem.lmis)):
        raise CertificateError(f"the {what} has {n_in} LMI multipliers, the problem {len(problem.lmis)} LMIs")
    mats = []
    for i, lmi in enumerate(problem.lmis):
        Z = mats_in[i] if i < n_in else None
        if Z is None or lmi.dim == 0:
            mats.append(np.zeros((lmi.dim, lmi.dim)))
            continue
        Z = np.atleast_2d(np.asarray(Z, dtype=float))
        if Z.shape != (lmi.dim, lmi.dim):
            raise CertificateError(
                f"{what}: multiplier of LMI '{lmi.name}' has shape {Z.shape}, expected {(lmi.dim,) * 2}"
            )
        mats.append(0.5 * (Z + Z.T))
    m = len(problem.linear)
    y_in = record.get("linear")
    y = np.zeros(m) if y_in is None or len(y_in) == 0 else np.asarray(y_in, dtype=float).ravel()
    if y.shape != (m,):
        raise CertificateError(f"the {what} has {y.size} row multipliers, the problem {m} rows")
    if not (all(np.all(np.isfinite(Z)) for Z in mats) and np.all(np.isfinite(y))):
        raise CertificateError(f"the {what} has non-finite entries")
    return mats, y
