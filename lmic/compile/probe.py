"""A plugin's derived quantities and checks evaluated once on a bound problem, before any solve.

A derived gain of the wrong shape (``K = Q^-1 Y`` for ``K = Y Q^-1``) or a stability check
of a non-square matrix (``hurwitz(A + B)``) is a bug of the plugin: ``lmic check`` finds it
from the template alone, but ``lmic solve`` used to find it only after every solve, as a
``rejected`` verdict with a certificate written (exit 1), or not at all when the LMIs were
infeasible (exit 3). :func:`probe_shapes` evaluates every derived quantity and check of the
bound problem at a random point (a random symmetric matrix is invertible), where only the shapes
can fail, and raises :class:`~lmic.errors.TemplateError` (bad input: one line, exit 2) naming
the quantity and the shapes. Values are not judged here (the certifier does that at the
solver's point); errors that depend on values (a singular matrix) are left to it.

Examples
--------
>>> from lmic.compile.bind import bind
>>> from lmic.compile.plan import analyse
>>> from lmic.template import block, theorem
>>> @theorem(id="demo.gain", title="t", citation="c")
... def demo(t):
...     n, m = t.dims("n m")
...     A, B = t.data("A", n, n), t.data("B", n, m)
...     Q, Y = t.symmetric("Q", n), t.full("Y", m, n)
...     t.lmi("closed loop", block(A * Q + Q * A.T + B * Y + Y.T * B.T) < 0)
...     t.derive("K", Q.inv() * Y)                     # K = Y Q^-1 meant
>>> bind(analyse(demo), {"data": {"A": [[-1.0, 0.0], [0.0, -2.0]], "B": [[1.0], [0.0]]}})
Traceback (most recent call last):
...
lmic.errors.TemplateError: theorem demo.gain: derived 'K': expression multiplies shapes (2, 2) and (1, 2) (the \
plugin's expression does not fit the system's dimensions: m = 1, n = 2)
"""

from __future__ import annotations

import numpy as np

from lmic.errors import IRError, TemplateError
from lmic.ir.problem import Problem

__all__ = ["probe_shapes", "SQUARE_CHECKS"]

#: check kinds whose expression must be a square matrix
SQUARE_CHECKS = frozenset(
    {
        "hurwitz",
        "schur_stable",
        "positive_definite",
        "negative_definite",
        "positive_semidefinite",
        "negative_semidefinite",
    }
)

#: the parts of an expression error that are about shapes, not values
_SHAPE_ERRORS = ("shapes", "scalar to a matrix", "inconsistent sizes", "which has no value", "non-integer power")


def probe_shapes(problem: Problem, seed: int = 0) -> None:
    """Raise :class:`TemplateError` when a derived quantity or a check of ``problem`` cannot be
    evaluated for its shapes (module docstring); return ``None`` otherwise."""
    from lmic.ir.expr import evaluate

    if not problem.derived and not problem.checks:
        return
    tid = (problem.meta or {}).get("theorem") or "the problem"
    dims = ", ".join(f"{k} = {v}" for k, v in sorted((problem.meta or {}).get("dims", {}).items()))
    where = f" (the plugin's expression does not fit the system's dimensions{': ' + dims if dims else ''})"
    env = problem.inputs(np.random.default_rng(seed).standard_normal(problem.n))
    for what, name, expr in [("derived", d.name, d.expr) for d in problem.derived] + [
        ("check", c.name, c.expr) for c in problem.checks
    ]:
        try:
            with np.errstate(all="ignore"):
                value = evaluate(expr, env)
        except IRError as err:
            if any(s in str(err) for s in _SHAPE_ERRORS):
                raise TemplateError(f"theorem {tid}: {what} '{name}': {err}{where}") from None
            return  # a value error at a random point: the certifier judges the real one
        except Exception:  # noqa: BLE001 - any other failure depends on the values (a complex
            return  # root, a singular matrix): the certifier judges them at the solver's point
        if what == "derived":
            env[name] = value
            continue
        kind = next(c.kind for c in problem.checks if c.name == name)
        shape = np.shape(value)
        if kind in SQUARE_CHECKS and len(shape) == 2 and shape[0] != shape[1]:
            raise TemplateError(
                f"theorem {tid}: check '{name}' ({kind}) needs a square matrix, got {shape[0]}x{shape[1]}{where}"
            )
