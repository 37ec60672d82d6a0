"""Resolve the numbers of one bind: parameters, data, dimensions and data-derived constants.

Everything a system file or a call supplies is validated here against the theorem's template
(names, shapes, symmetry, domains, requirements), before :mod:`lmic.compile.bind` turns the
numbers into an IR. Errors are :class:`~lmic.errors.DataError` naming the theorem, the source
and the key at fault.
"""

from __future__ import annotations

import contextlib
import sys
import warnings
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from lmic.compile.frozen import Dim, Domain, normalise_option
from lmic.errors import DataError, LmicError, TemplateError
from lmic.formatting import domain_text
from lmic.system import RoundingNote, System, UnusedDataNote, near_miss

if TYPE_CHECKING:  # sympy only for analysed plans (a frozen plan, lmic.compile.frozen, has none)
    from lmic.compile.plan import Plan
    from lmic.compile.warm import FrozenPlan

__all__ = ["Inputs", "dim_value", "resolve_inputs"]


class Inputs:
    """Numbers resolved for one bind: dimensions, data, parameters and constants.

    ``dims`` is keyed by the dimension symbols (sympy) of an analysed plan, by the dimension
    names of a frozen one.
    """

    def __init__(self) -> None:
        self.dims: dict[Any, int] = {}
        self.values: dict[str, Any] = {}  # data, params, consts (numbers / arrays)
        self.params: dict[str, Any] = {}  # every parameter and option value used


def dim_value(expr: Any, dims: Mapping[Any, int]) -> int | None:
    """The integer value of a dimension expression under ``dims``, or None when it is not fixed.

    Examples
    --------
    >>> import sympy
    >>> n, p = sympy.symbols("n p")
    >>> dim_value(n + 1, {n: 3}), dim_value(2, {}), dim_value(n * p, {n: 3})
    (4, 2, None)
    """
    if isinstance(expr, int):
        return expr
    if isinstance(expr, Dim):  # a frozen plan's
        return expr.value(dims)
    from lmic.template.convert import as_expr

    v = as_expr(as_expr(expr).xreplace(dict(dims)))
    return int(v) if v.is_Integer else None


def _real_array(value: Any, what: str) -> np.ndarray:
    """``value`` as a float array; a text, object or complex value (non-zero imaginary part) is a TemplateError."""
    try:
        arr = np.asarray(value)
        if np.iscomplexobj(arr):
            if np.any(arr.imag != 0):
                raise TemplateError(f"{what} is complex ({value!r:.60}): an LMI needs real numbers")
            arr = arr.real
        if arr.dtype == object and any(e is None for e in arr.flat):  # None would become nan
            raise TypeError
        return arr.astype(float)
    except (TypeError, ValueError):
        raise TemplateError(f"{what} is not a number or a matrix of numbers: {value!r:.60}") from None


def _in_domain(value: float, domain: Any) -> bool:
    """Whether ``value`` lies in ``domain``: a frozen plan's :class:`Domain` without sympy, an
    analysed plan's sympy set by :func:`lmic.template.decls.in_domain`."""
    if isinstance(domain, Domain):  # a frozen plan's
        return domain.contains_number(value)
    key = (float(value), domain)
    hit = _DOMAIN_MEMO.get(key)
    if hit is None:
        from lmic.template.decls import in_domain

        hit = _DOMAIN_MEMO[key] = bool(in_domain(value, domain))  # sympy: ~1-2 ms a call
        if len(_DOMAIN_MEMO) > 4096:
            _DOMAIN_MEMO.clear()
    return hit


#: answers of sympy's set membership for (value, domain) in this process (every bind asks again)
_DOMAIN_MEMO: dict[tuple[float, Any], bool] = {}


def resolve_inputs(plan: Plan | FrozenPlan, system: System, overrides: Mapping[str, Any] | None = None) -> Inputs:
    """Validate data and parameters against the template and compute the constants.

    Parameters
    ----------
    plan : Plan
        The analysed theorem (:func:`lmic.compile.plan.analyse`).
    system : System
        The numbers (:func:`lmic.system.load_system`).
    overrides : mapping, optional
        Parameter values that replace the system's.

    Returns
    -------
    Inputs
        Dimensions, data, parameters and data-derived constants, checked.

    Raises
    ------
    DataError
        Naming the theorem, the key and the rule broken (unknown or missing key, wrong shape,
        parameter outside its domain, failed requirement).

    Examples
    --------
    >>> from lmic.template import theorem, block
    >>> from lmic.compile.plan import analyse
    >>> from lmic.system import load_system
    >>> @theorem(id="demo.inputs", title="t", citation="c")
    ... def demo(t):
    ...     n, = t.dims("n")
    ...     A = t.data("A", n, n)
    ...     P = t.symmetric("P", n)
    ...     t.lmi("stability", block(A.T * P + P * A) < 0)
    >>> inputs = resolve_inputs(analyse(demo), load_system({"data": {"A": [[-1.0, 0.0], [0.0, -2.0]]}}))
    >>> {str(k): v for k, v in inputs.dims.items()}
    {'n': 2}
    """
    t = plan.template
    tid = t.theorem_id
    where = f"theorem {tid}, {system.label}"
    out = Inputs()
    # parameters and options: one the caller sets (-p, overrides) must exist; the system file's
    # may be another theorem's (one plant file, several theorems), as its data may, but a key
    # close to one this theorem takes is a typo
    known = {p.name for p in t.params} | {o.name for o in t.options}
    accepted = ", ".join(sorted(known)) or "none"
    for key in overrides or {}:
        if key not in known:
            raise DataError(f"{where}: unknown parameter '{key}' (the theorem takes: {accepted})")
    foreign = [key for key in system.params if key not in known and key not in (overrides or {})]
    unset = sorted(k for k in known if k not in system.params and k not in (overrides or {}))
    for key in foreign:
        close = near_miss(key, unset)
        if close is not None:
            raise DataError(
                f"{where}: unknown parameter '{key}' (did you mean '{close}'? the theorem takes: {accepted})"
            )
    if foreign:
        warnings.warn(
            f"{where}: parameter {', '.join(repr(k) for k in foreign)} not used by the theorem (it takes: {accepted})",
            UnusedDataNote,
            stacklevel=2,
        )
    params = {key: value for key, value in system.params.items() if key in known}
    params.update(overrides or {})
    for o in t.options:
        option = normalise_option(params.get(o.name, o.default))
        if option != o.value:
            raise DataError(f"{where}: option {o.name} = {option!r} does not match the analysed plan")
        out.params[o.name] = o.value
    for p in t.params:
        raw: Any
        if p.name in params:
            raw = params[p.name]
            if isinstance(raw, str):
                try:
                    raw = float(raw)
                except ValueError:
                    raise DataError(f"{where}: parameter '{p.name}' = {raw!r} is not a number") from None
            elif np.ndim(raw) != 0 or np.asarray(raw).dtype.kind not in "iuf":  # not bool, complex, text
                raise DataError(f"{where}: parameter '{p.name}' = {raw!r:.60} is not a number")
        elif p.default is not None:
            raw = p.default
        else:
            raise DataError(f"{where}: missing parameter '{p.name}'" + (f" ({p.doc})" if p.doc else ""))
        number = float(raw)
        if not np.isfinite(number):
            raise DataError(f"{where}: parameter '{p.name}' is {number}")
        if not _in_domain(number, p.domain):
            raise DataError(f"{where}: parameter {p.name} = {number:g} is outside its domain {domain_text(p.domain)}")
        out.params[p.name] = number
        out.values[p.name] = number

    # data and dimensions
    declared = {d.name for d in t.data_decls}
    unused = [key for key in system.data if key not in declared]
    absent = [d.name for d in t.data_decls if d.name not in system.data]  # missing or optional
    for key in unused:  # extra keys are fine (one plant file, several theorems); typos are not
        close = near_miss(key, absent)
        if close is not None:
            raise DataError(
                f"{where}: unknown data key '{key}' (did you mean '{close}'? the theorem takes: "
                f"{', '.join(sorted(declared))})"
            )
    if unused:
        warnings.warn(
            f"{where}: data {', '.join(repr(k) for k in unused)} not used by the theorem "
            f"(it takes: {', '.join(sorted(declared))})",
            UnusedDataNote,
            stacklevel=2,
        )
    origin: dict[Any, str] = {}
    arrays: dict[str, np.ndarray] = {}
    for d in t.data_decls:
        if d.name in system.data:
            arrays[d.name] = system.data[d.name]
    # first pass: bind plain dimension symbols from the data present
    for d in t.data_decls:
        if d.name not in arrays:
            continue
        for axis, size in enumerate(d.shape):
            dim = _dim_symbol(size)
            if dim is not None and dim not in out.dims:
                out.dims[dim] = int(arrays[d.name].shape[axis])
                origin[dim] = f"{'rows' if axis == 0 else 'columns'} of {d.name}"
    # defaults for missing data
    for d in t.data_decls:
        if d.name in arrays:
            continue
        if d.default is None:
            shape = " x ".join(str(s) for s in d.shape)
            raise DataError(f"{where}: missing data '{d.name}' ({shape})" + (f": {d.doc}" if d.doc else ""))
        for size in d.shape:  # a dimension only absent optional data would fix is 0
            dim = _dim_symbol(size)
            if dim is not None and dim not in out.dims:
                out.dims[dim] = 0
                origin[dim] = f"absent optional data {d.name}"
        n_rows, n_cols = (dim_value(size, out.dims) for size in d.shape)
        if n_rows is None or n_cols is None:
            raise DataError(f"{where}: cannot size the default of data '{d.name}' (dimensions unknown)")
        if callable(d.default):
            with contextlib.redirect_stdout(sys.stderr):  # plugin code: its prints go to stderr
                value = d.default({**out.values, **arrays}, n_rows, n_cols)
            arr = np.atleast_2d(np.asarray(value, dtype=float))
        else:
            arr = float(d.default) * np.eye(n_rows, n_cols)
        arrays[d.name] = arr
    for d in t.data_decls:
        arr = arrays[d.name]
        expected: list[int] = []
        for size in d.shape:
            val = dim_value(size, out.dims)
            if val is None:
                raise DataError(f"{where}: dimension {size} of data '{d.name}' cannot be determined")
            expected.append(val)
        if tuple(expected) != arr.shape:
            shape_sym = " x ".join(str(s) for s in d.shape)
            bound = ", ".join(
                f"{s} = {out.dims[s]} from {origin.get(s, 'defaults')}"
                for s in sorted((s for s in _shape_symbols(d.shape) if s in out.dims), key=str)
            )
            raise DataError(
                f"{where}: data '{d.name}' has shape {arr.shape[0]}x{arr.shape[1]}, expected "
                f"{shape_sym} = {expected[0]}x{expected[1]}" + (f" ({bound})" if bound else "")
            )
        if d.symmetric:
            scale = max(1.0, float(np.max(np.abs(arr))))
            if arr.shape[0] != arr.shape[1] or np.max(np.abs(arr - arr.T)) > 1e-9 * scale:
                raise DataError(f"{where}: data '{d.name}' must be symmetric")
        if d.positive_definite and np.linalg.eigvalsh(0.5 * (arr + arr.T))[0] <= 0:
            raise DataError(f"{where}: data '{d.name}' must be positive definite")
        out.values[d.name] = arr

    # data-derived constants, in order
    for c in t.consts:
        try:
            with contextlib.redirect_stdout(sys.stderr):
                computed = c.fn(dict(out.values))
        except DataError as err:
            msg = str(err)
            raise DataError(msg if msg.startswith(f"theorem {tid}") else f"{where}: {msg}") from None
        except LmicError:
            raise
        except Exception as err:
            raise DataError(f"{where}: constant '{c.name}' cannot be computed: {type(err).__name__}: {err}") from None
        arr = _real_array(computed, f"{tid}: constant '{c.name}'")
        if c.shape is None:
            if arr.size != 1:
                raise TemplateError(f"{tid}: constant '{c.name}' is declared scalar but has shape {arr.shape}")
            scalar = float(arr.reshape(-1)[0])
            if not np.isfinite(scalar):
                raise DataError(f"{where}: constant '{c.name}' is {scalar} for this data")
            out.values[c.name] = scalar
        else:
            matrix = np.atleast_2d(arr)
            exp = tuple(dim_value(size, out.dims) for size in c.shape)
            if matrix.shape != exp:
                raise TemplateError(f"{tid}: constant '{c.name}' has shape {matrix.shape}, declared {exp}")
            if not np.all(np.isfinite(matrix)):
                raise DataError(f"{where}: constant '{c.name}' is not finite for this data")
            out.values[c.name] = matrix
            ratio = rounding_singular(matrix)
            if ratio is not None:
                warnings.warn(
                    f"{where}: constant '{c.name}' is singular only up to rounding (smallest singular value "
                    f"{ratio:.1e} of the largest, not zero exactly): the compiled problem reads it as regular, "
                    "so where the theorem relies on its null space (a projector, a kernel) a certificate "
                    "holds for the compiled numbers, not for the theorem as written; compute it exactly "
                    "(left_null_basis, docs/writing-a-theorem.md)",
                    RoundingNote,
                    stacklevel=2,
                )
    for req in t.requirements:
        try:
            with contextlib.redirect_stdout(sys.stderr):
                ok = bool(req.predicate(dict(out.values)))
        except LmicError:
            raise
        except Exception as err:
            why = f"{type(err).__name__}: {err}"
            raise DataError(f"{where}: requirement '{req.name}' cannot be checked: {why}") from None
        if not ok:
            raise DataError(f"{where}: requirement '{req.name}' fails" + (f" ({req.doc})" if req.doc else ""))
    return out


#: a constant is singular to rounding when its smallest singular value is below this share of its largest
ROUNDING_SINGULAR = 1e-12


def rounding_singular(M: np.ndarray) -> float | None:
    """The relative smallest singular value of ``M`` when it is below :data:`ROUNDING_SINGULAR`
    while ``M`` has full rank exactly (its floats read as rationals), else ``None``. Full rank is
    proved by the rank modulo a prime (at most the rational rank).

    >>> X = np.array([[1.0], [3.0]]) / np.sqrt(10.0)
    >>> rounding_singular(np.eye(2) - X @ X.T) is not None  # a projector of rank 1, in floats
    True
    >>> rounding_singular(np.diag([1.0, 0.0])), rounding_singular(np.eye(2))  # exactly singular; regular
    (None, None)
    """
    k = min(M.shape)
    if k < 2 or M.size > 40_000 or not np.any(M):
        return None
    s = np.linalg.svd(M, compute_uv=False)
    if not s[-1] < ROUNDING_SINGULAR * s[0]:
        return None
    from lmic.rational_rank import full_row_rank_exactly

    if not full_row_rank_exactly(M if M.shape[0] <= M.shape[1] else M.T):
        return None  # (very probably) singular exactly: its null space is exact
    return float(s[-1] / s[0])


def _dim_symbol(size: Any) -> Any:
    """The dimension a size names when it is a bare dimension (sympy symbol or name), else ``None``."""
    if isinstance(size, Dim):  # a frozen plan's
        return size.symbol
    import sympy

    from lmic.template.convert import as_expr

    dim = as_expr(size)
    return dim if isinstance(dim, sympy.Symbol) else None


def _shape_symbols(shape: Any) -> set[Any]:
    """The dimensions a shape uses."""
    out: set[Any] = set()
    for size in shape:
        if isinstance(size, Dim):  # a frozen plan's
            out |= size.names()
        elif not isinstance(size, int):
            out |= set(size.free_symbols)
    return out
