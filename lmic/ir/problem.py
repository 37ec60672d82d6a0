"""The intermediate representation (IR): the contract between the front end and every backend.

A :class:`Problem` has a decision vector ``x`` (length :attr:`Problem.n`), made of the free
entries of its :class:`Variable` objects laid out one after the other, and

* LMIs (:class:`LMI`) ``F(x) = F0 + sum_k x_k F_k``, always normalised to ``F(x) > 0``
  (``strict``) or ``F(x) >= 0`` (not strict). The relation the author wrote (``<``, ``<=``,
  ``>``, ``>=``) is kept for display; ``<`` constraints are negated when compiled.
  Coefficients are stored as one sparse matrix of shape ``(d (d+1)/2, 1 + n)``: column 0 is
  ``F0``, column ``1 + k`` is ``F_k``, each in the storage convention of :mod:`lmic.ir.svec`
  (lower triangle, column-major, unscaled).
* linear constraints (:class:`LinearConstraints`): rows ``a0 + a . x`` that are ``== 0``
  (``eq``), ``>= 0`` (``ge``) or ``> 0`` (``ge`` with ``strict``).
* an objective (:class:`Objective`): ``minimize``/``maximize`` ``c0 + c . x``, or feasibility.
* numeric ``data`` (data matrices, parameters, data-derived constants), ``derived``
  quantities and ``checks`` as expression trees (:mod:`lmic.ir.expr`), and ``meta``.

Variable layout (how ``x`` maps to a matrix value ``V``; ``vec`` is column-major):

``scalar``     1 entry.
``full``       ``r x c`` entries, ``V = reshape(x, (r, c), order="F")``.
``symmetric``  ``d (d+1)/2`` entries, the lower triangle in storage order; ``V`` symmetric.
``diagonal``   ``d`` entries, ``V = diag(x)``.
``blockdiag``  symmetric blocks of sizes ``blocks``, one after the other, each in storage order.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> P = Variable("P", "symmetric", (2, 2), offset=0)
>>> P.size
3
>>> P.value(np.array([1.0, 0.5, 2.0]))
array([[1. , 0.5],
       [0.5, 2. ]])
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.errors import IRError
from lmic.ir.svec import tril_rows_cols, tril_size, tril_unvec

__all__ = [
    "VARIABLE_KINDS",
    "CHECK_KINDS",
    "Variable",
    "LMI",
    "LinearConstraints",
    "Objective",
    "NamedExpr",
    "Check",
    "Problem",
]

VARIABLE_KINDS = ("scalar", "full", "symmetric", "diagonal", "blockdiag")

#: Kinds of theorem checks and what they mean (``value`` is what the certifier reports):
#: ``schur_stable``: value = spectral radius of the matrix, ok iff < 1;
#: ``hurwitz``: value = max real part of the eigenvalues, ok iff < 0;
#: ``negative_definite`` / ``positive_definite``: value = lambda_max / lambda_min of the
#: symmetric part, ok iff < 0 / > 0;
#: ``negative_semidefinite`` / ``positive_semidefinite``: as above with <= / >= (tolerance);
#: ``less_than`` / ``greater_than``: a scalar expression against ``bound``;
#: ``finite``: every entry finite (e.g. a gain was computable).
CHECK_KINDS = (
    "schur_stable",
    "hurwitz",
    "negative_definite",
    "positive_definite",
    "negative_semidefinite",
    "positive_semidefinite",
    "less_than",
    "greater_than",
    "finite",
)


@dataclass(frozen=True)
class Variable:
    """A decision variable and its place in ``x``.

    Parameters
    ----------
    name : str
    kind : {"scalar", "full", "symmetric", "diagonal", "blockdiag"}
    shape : (int, int)
    offset : int
        Index of its first entry in ``x``.
    blocks : tuple of int
        Sizes of the symmetric diagonal blocks (``blockdiag`` only).
    sign : {"free", "positive", "nonnegative", "negative", "nonpositive"}
        Informational (scalars); the constraint itself is a linear row of the problem.

    Examples
    --------
    >>> Variable("R", "full", (2, 3), offset=4).size
    6
    """

    name: str
    kind: str
    shape: tuple[int, int]
    offset: int = 0
    blocks: tuple[int, ...] = ()
    sign: str = "free"

    def __post_init__(self) -> None:
        if self.kind not in VARIABLE_KINDS:
            raise IRError(f"variable '{self.name}': unknown kind '{self.kind}'")
        r, c = self.shape
        if self.kind == "scalar" and (r, c) != (1, 1):
            raise IRError(f"variable '{self.name}': a scalar has shape 1x1")
        if self.kind in ("symmetric", "diagonal", "blockdiag") and r != c:
            raise IRError(f"variable '{self.name}': a {self.kind} variable is square")
        if self.kind == "blockdiag" and sum(self.blocks) != r:
            raise IRError(f"variable '{self.name}': block sizes {self.blocks} do not add up to {r}")

    @property
    def size(self) -> int:
        """Number of entries of ``x`` this variable occupies."""
        r, c = self.shape
        if self.kind == "scalar":
            return 1
        if self.kind == "full":
            return r * c
        if self.kind == "symmetric":
            return tril_size(r)
        if self.kind == "diagonal":
            return r
        return sum(tril_size(b) for b in self.blocks)

    @property
    def slice(self) -> slice:
        """The slice of ``x`` holding this variable."""
        return slice(self.offset, self.offset + self.size)

    def basis(self) -> sp.csc_matrix:
        """Sparse ``B`` with ``vec(V) = B @ x[self.slice]`` (``vec`` column-major).

        >>> Variable("P", "symmetric", (2, 2)).basis().toarray()
        array([[1., 0., 0.],
               [0., 1., 0.],
               [0., 1., 0.],
               [0., 0., 1.]])
        """
        r, c = self.shape
        if self.kind in ("scalar", "full"):
            return sp.identity(r * c, format="csc")
        if self.kind == "diagonal":
            idx = np.arange(r)
            return sp.csc_matrix((np.ones(r), (idx * r + idx, idx)), shape=(r * r, r))
        sizes = self.blocks if self.kind == "blockdiag" else (r,)
        rows, cols = [], []
        start, col0 = 0, 0
        for b in sizes:
            i, j = tril_rows_cols(b)
            k = np.arange(len(i)) + col0
            gi, gj = i + start, j + start
            off = gi != gj
            rows += [gj * r + gi, gi[off] * r + gj[off]]  # entry (gi, gj) and its mirror
            cols += [k, k[off]]
            start += b
            col0 += len(i)
        rows_a, cols_a = np.concatenate(rows), np.concatenate(cols)
        return sp.csc_matrix((np.ones(len(rows_a)), (rows_a, cols_a)), shape=(r * r, self.size))

    def value(self, x: np.ndarray) -> float | np.ndarray:
        """The variable's value (a float for scalars) from the full vector ``x``."""
        v = np.asarray(x, dtype=float)[self.slice]
        r, c = self.shape
        if self.kind == "scalar":
            return float(v[0])
        if self.kind == "full":
            return v.reshape((r, c), order="F")
        if self.kind == "diagonal":
            return np.diag(v)
        if self.kind == "symmetric":
            return tril_unvec(v, r)
        out = np.zeros((r, r))
        start, k = 0, 0
        for b in self.blocks:
            m = tril_size(b)
            out[start : start + b, start : start + b] = tril_unvec(v[k : k + m], b)
            start += b
            k += m
        return out

    def pack(self, value: Any) -> np.ndarray:
        """Entries of ``x`` for a given value (inverse of :meth:`value`).

        Raises :class:`IRError` if the value has the wrong shape or structure.

        >>> Variable("P", "symmetric", (2, 2)).pack([[1, 2], [2, 3]])
        array([1., 2., 3.])
        """
        r, c = self.shape
        V = np.atleast_2d(np.asarray(value, dtype=float))
        if V.shape != (r, c):
            raise IRError(f"variable '{self.name}': value of shape {V.shape}, expected {(r, c)}")
        if self.kind == "scalar":
            return V.reshape(1)
        if self.kind == "full":
            return V.reshape(-1, order="F")
        if self.kind == "diagonal":
            if np.any(V - np.diag(np.diag(V))):
                raise IRError(f"variable '{self.name}': value is not diagonal")
            return np.diag(V).copy()
        scale = max(1.0, float(np.max(np.abs(V))))
        if np.max(np.abs(V - V.T)) > 1e-9 * scale:
            raise IRError(f"variable '{self.name}': value is not symmetric")
        V = 0.5 * (V + V.T)
        sizes = self.blocks if self.kind == "blockdiag" else (r,)
        parts, start = [], 0
        for b in sizes:
            i, j = tril_rows_cols(b)
            parts.append(V[i + start, j + start])
            start += b
        packed = np.concatenate(parts)
        if self.kind == "blockdiag" and not np.allclose(self.value(np.r_[np.zeros(self.offset), packed]), V):
            raise IRError(f"variable '{self.name}': value is not block-diagonal {self.blocks}")
        return packed


@dataclass
class LMI:
    """One linear matrix inequality ``F(x) > 0`` (``strict``) or ``F(x) >= 0``.

    Parameters
    ----------
    name : str
    dim : int
    coeffs : scipy.sparse matrix, shape ``(dim (dim+1)/2, 1 + n)``
        Column 0 is ``F0``, column ``1 + k`` is ``F_k`` (storage convention).
    strict : bool
    relation : str
        The relation as written by the author (display only).
    block_sizes : tuple of int
        Sizes of the diagonal blocks as written (display and error messages).

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> L = LMI("x > 0", 1, sp.csc_matrix([[0.0, 1.0]]), strict=True)
    >>> L.matrix([3.0])
    array([[3.]])
    """

    name: str
    dim: int
    coeffs: sp.spmatrix
    strict: bool = True
    relation: str = ">"
    block_sizes: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        self.coeffs = sp.csc_matrix(self.coeffs)
        if self.coeffs.shape[0] != tril_size(self.dim):
            raise IRError(
                f"LMI '{self.name}': {self.coeffs.shape[0]} coefficient rows, "
                f"expected {tril_size(self.dim)} for dimension {self.dim}"
            )
        if not self.block_sizes:
            self.block_sizes = (self.dim,)

    def matrix(self, x: np.ndarray) -> np.ndarray:
        """Dense symmetric ``F(x)``."""
        xx = np.concatenate([[1.0], np.asarray(x, dtype=float)])
        return tril_unvec(self.coeffs @ xx, self.dim)

    def coefficient(self, k: int) -> np.ndarray:
        """Dense ``F_k`` (``k = 0`` is the constant term, ``k = 1 + i`` multiplies ``x_i``)."""
        return tril_unvec(self.coeffs[:, k].toarray().ravel(), self.dim)

    @property
    def homogeneous(self) -> bool:
        """True when ``F0 = 0`` (the LMI is invariant under scaling of ``x``)."""
        return self.coeffs[:, 0].nnz == 0 or not np.any(self.coeffs[:, 0].toarray())


@dataclass
class LinearConstraints:
    """Rows ``A[:, 0] + A[:, 1:] @ x``  ``== 0`` (kind ``eq``) or ``>= 0`` / ``> 0`` (``ge``).

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> L = LinearConstraints(sp.csr_matrix([[-1.0, 1.0]]), ["ge"], [True], ["xi > 1"])
    >>> L.residuals([3.0])
    array([2.])
    """

    A: sp.spmatrix
    kinds: list[str] = field(default_factory=list)
    strict: list[bool] = field(default_factory=list)
    names: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.A = sp.csr_matrix(self.A)
        m = self.A.shape[0]
        if not (len(self.kinds) == len(self.strict) == len(self.names) == m):
            raise IRError("linear constraints: kinds, strict and names must have one entry a row")
        for k in self.kinds:
            if k not in ("eq", "ge"):
                raise IRError(f"linear constraints: unknown kind '{k}'")

    @classmethod
    def empty(cls, n: int) -> LinearConstraints:
        """No rows, for a problem with ``n`` variables."""
        return cls(sp.csr_matrix((0, 1 + n)), [], [], [])

    def __len__(self) -> int:
        return self.A.shape[0]

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """``a0 + a . x`` for every row."""
        xx = np.concatenate([[1.0], np.asarray(x, dtype=float)])
        return np.asarray(self.A @ xx).ravel()


@dataclass
class Objective:
    """``sense`` in ``{"min", "max", "feasibility"}``; value ``c[0] + c[1:] . x``.

    >>> Objective("min", np.array([1.0, 2.0])).value([3.0])
    7.0
    """

    sense: str
    c: np.ndarray

    def __post_init__(self) -> None:
        if self.sense not in ("min", "max", "feasibility"):
            raise IRError(f"objective: unknown sense '{self.sense}'")
        self.c = np.asarray(self.c, dtype=float).ravel()

    def value(self, x: np.ndarray) -> float | None:
        """The objective at ``x`` (``None`` for a feasibility problem)."""
        if self.sense == "feasibility":
            return None
        return float(self.c[0] + self.c[1:] @ np.asarray(x, dtype=float))


@dataclass
class NamedExpr:
    """A derived quantity: ``name = expr`` (an expression tree over IR names)."""

    name: str
    expr: dict
    doc: str = ""


@dataclass
class Check:
    """A theorem check on derived quantities (kinds: :data:`CHECK_KINDS`)."""

    name: str
    kind: str
    expr: dict
    bound: float | None = None
    doc: str = ""

    def __post_init__(self) -> None:
        if self.kind not in CHECK_KINDS:
            raise IRError(f"check '{self.name}': unknown kind '{self.kind}'")


def _all_finite(a: np.ndarray) -> bool:
    """``np.all(np.isfinite(a))`` without a boolean array of ``a``'s size: a finite sum means every
    entry is finite (a NaN or an infinity makes the sum NaN or infinite); only a sum that
    overflowed or is not finite is checked entry by entry.

    >>> _all_finite(np.array([1.0, 1e308, 1e308])), _all_finite(np.array([1.0, np.nan]))
    (True, False)
    """
    with np.errstate(over="ignore", invalid="ignore"):
        total = np.sum(a)
    return bool(np.isfinite(total)) or bool(np.all(np.isfinite(a)))


@dataclass
class Problem:
    """A compiled LMI problem (see the module docstring).

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> t = Variable("t", "scalar", (1, 1))
    >>> lmi = LMI("t > 0", 1, sp.csc_matrix([[0.0, 1.0]]), strict=True)
    >>> prob = Problem([t], [lmi], LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> prob.n, prob.unpack([2.0])
    (1, {'t': 2.0})
    """

    variables: list[Variable]
    lmis: list[LMI]
    linear: LinearConstraints
    objective: Objective
    data: dict[str, Any] = field(default_factory=dict)
    derived: list[NamedExpr] = field(default_factory=list)
    checks: list[Check] = field(default_factory=list)
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.validate()

    @property
    def n(self) -> int:
        """Length of the decision vector ``x``."""
        return sum(v.size for v in self.variables)

    def validate(self) -> None:
        """Check internal consistency; raise :class:`IRError` naming what is wrong."""
        offset = 0
        seen: set[str] = set()
        for v in self.variables:
            if v.name in seen:
                raise IRError(f"duplicate variable name '{v.name}'")
            seen.add(v.name)
            if v.offset != offset:
                raise IRError(f"variable '{v.name}' has offset {v.offset}, expected {offset}")
            offset += v.size
        n = offset
        for lmi in self.lmis:
            if lmi.coeffs.shape[1] != 1 + n:
                raise IRError(f"LMI '{lmi.name}' has {lmi.coeffs.shape[1]} coefficient columns, expected {1 + n}")
            if not _all_finite(lmi.coeffs.data):
                raise IRError(f"LMI '{lmi.name}' has a non-finite coefficient")
        if self.linear.A.shape[1] != 1 + n:
            raise IRError(f"linear constraints have {self.linear.A.shape[1]} columns, expected {1 + n}")
        if not _all_finite(self.linear.A.data):
            raise IRError("linear constraints have a non-finite coefficient")
        if self.objective.c.shape != (1 + n,):
            raise IRError(f"objective has {self.objective.c.shape[0]} entries, expected {1 + n}")
        if not np.all(np.isfinite(self.objective.c)):
            raise IRError("objective has a non-finite coefficient")

    def variable(self, name: str) -> Variable:
        """The variable called ``name``."""
        for v in self.variables:
            if v.name == name:
                return v
        raise IRError(f"no variable named '{name}'")

    def unpack(self, x: np.ndarray) -> dict[str, float | np.ndarray]:
        """Values of every variable at ``x``."""
        return {v.name: v.value(x) for v in self.variables}

    def pack(self, values: dict[str, Any]) -> np.ndarray:
        """``x`` from a value for every variable (inverse of :meth:`unpack`)."""
        x = np.zeros(self.n)
        for v in self.variables:
            if v.name not in values:
                raise IRError(f"no value given for variable '{v.name}'")
            x[v.slice] = v.pack(values[v.name])
        return x

    def environment(self, x: np.ndarray) -> dict[str, Any]:
        """Names -> values for expression trees: data, variables at ``x``, derived quantities.

        Derived quantities are evaluated in order, each seeing the earlier ones.
        """
        from lmic.ir.expr import evaluate

        env = self.inputs(x)
        for d in self.derived:
            env[d.name] = evaluate(d.expr, env)
        return env

    def inputs(self, x: np.ndarray) -> dict[str, Any]:
        """Names -> values of the data and of the variables at ``x`` (no derived quantity)."""
        env: dict[str, Any] = {}
        for k, v in self.data.items():
            env[k] = np.asarray(v, dtype=float) if isinstance(v, list | np.ndarray) else float(v)
        env.update(self.unpack(x))
        return env
