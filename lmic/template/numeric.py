"""Numerical helpers for data-derived constants (computed before compiling).

Projectors are built from an orthonormal basis given by the SVD with a rank decided by a
relative tolerance, so ``I - X X^+`` is an exact orthogonal projector (idempotent and
symmetric to machine precision), not ``I - X pinv(X)`` assembled from a noisy inverse.

Examples
--------
>>> import numpy as np
>>> X = np.array([[1.0], [1.0]])
>>> V = null_projector(X)
>>> np.allclose(V @ V, V), np.allclose(V @ X, 0)
(True, True)
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "lambda_max",
    "lambda_min",
    "spectral_radius",
    "pinv",
    "rank",
    "range_basis",
    "null_basis",
    "range_projector",
    "null_projector",
    "left_null_basis",
]


def _rank_from_singular(s: np.ndarray, shape: tuple[int, int], rtol: float | None) -> int:
    if s.size == 0:
        return 0
    tol = (rtol if rtol is not None else max(shape) * np.finfo(float).eps) * s[0]
    return int(np.sum(s > tol))


def lambda_max(M: np.ndarray) -> float:
    """Largest eigenvalue of the symmetric part of ``M``.

    >>> lambda_max(np.diag([1.0, 3.0]))
    3.0
    """
    M = np.atleast_2d(np.asarray(M, dtype=float))
    return float(np.linalg.eigvalsh(0.5 * (M + M.T))[-1])


def lambda_min(M: np.ndarray) -> float:
    """Smallest eigenvalue of the symmetric part of ``M``.

    >>> lambda_min(np.diag([1.0, 3.0]))
    1.0
    """
    M = np.atleast_2d(np.asarray(M, dtype=float))
    return float(np.linalg.eigvalsh(0.5 * (M + M.T))[0])


def spectral_radius(M: np.ndarray) -> float:
    """Largest eigenvalue modulus.

    >>> spectral_radius(np.array([[0.0, 1.0], [-1.0, 0.0]]))
    1.0
    """
    return float(np.max(np.abs(np.linalg.eigvals(np.atleast_2d(M)))))


def rank(X: np.ndarray, rtol: float | None = None) -> int:
    """Numerical rank from the SVD (relative tolerance ``rtol``).

    >>> rank(np.ones((3, 3)))
    1
    """
    X = np.atleast_2d(np.asarray(X, dtype=float))
    return _rank_from_singular(np.linalg.svd(X, compute_uv=False), X.shape, rtol)


def range_basis(X: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthonormal basis of the column space of ``X`` (columns).

    >>> range_basis(np.array([[2.0], [0.0]]))
    array([[1.],
           [0.]])
    """
    X = np.atleast_2d(np.asarray(X, dtype=float))
    U, s, _ = np.linalg.svd(X, full_matrices=True)
    r = _rank_from_singular(s, X.shape, rtol)
    Ur = U[:, :r]
    # fix the sign so the basis is deterministic: largest entry of each column positive
    if r:
        idx = np.argmax(np.abs(Ur), axis=0)
        Ur = Ur * np.sign(Ur[idx, np.arange(r)])
    return Ur


def null_basis(X: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthonormal basis of the null space of ``X`` (columns).

    >>> null_basis(np.array([[1.0, 0.0]]))
    array([[0.],
           [1.]])
    """
    X = np.atleast_2d(np.asarray(X, dtype=float))
    _, s, Vt = np.linalg.svd(X, full_matrices=True)
    r = _rank_from_singular(s, X.shape, rtol)
    N = Vt[r:].T
    if N.shape[1]:
        idx = np.argmax(np.abs(N), axis=0)
        N = N * np.sign(N[idx, np.arange(N.shape[1])])
    return N


def left_null_basis(X: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthonormal basis (columns) of the null space of ``X^T``.

    >>> left_null_basis(np.array([[1.0], [0.0]]))
    array([[0.],
           [1.]])
    """
    return null_basis(np.atleast_2d(np.asarray(X, dtype=float)).T, rtol)


def range_projector(X: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthogonal projector ``X X^+`` onto the column space of ``X``, from an SVD basis.

    >>> range_projector(np.array([[1.0], [1.0]]))
    array([[0.5, 0.5],
           [0.5, 0.5]])
    """
    U = range_basis(X, rtol)
    return U @ U.T


def null_projector(X: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthogonal projector ``I - X X^+`` onto the orthogonal complement of range(X).

    >>> null_projector(np.eye(2))
    array([[0., 0.],
           [0., 0.]])
    """
    X = np.atleast_2d(np.asarray(X, dtype=float))
    W = left_null_basis(X, rtol)
    return W @ W.T if W.shape[1] else np.zeros((X.shape[0], X.shape[0]))


def pinv(X: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Moore-Penrose pseudo-inverse with an explicit SVD rank decision.

    >>> pinv(np.array([[2.0, 0.0]]))
    array([[0.5],
           [0. ]])
    """
    X = np.atleast_2d(np.asarray(X, dtype=float))
    U, s, Vt = np.linalg.svd(X, full_matrices=False)
    r = _rank_from_singular(s, X.shape, rtol)
    return (Vt[:r].T / s[:r]) @ U[:, :r].T
