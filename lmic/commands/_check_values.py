"""Small random dimensions and data for ``lmic check`` (split from :mod:`lmic.commands.check`).

numpy, sympy and the template layer are imported by the functions that use them, so that the
``lmic`` parser stays light.

Examples
--------
>>> import numpy as np
>>> _random_matrix(np.random.default_rng(0), 2, 2, "pd").shape
(2, 2)
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np
    import sympy

    from lmic.template.builder import Template

__all__ = ["choose_dims"]


# ---- dimensions and random values ------------------------------------------------------------


def _shapes(t: Template) -> list[Any]:
    from lmic.template.convert import as_expr

    out: list[Any] = []
    for d in t.data_decls + t.variables:
        out += [as_expr(s) for s in d.shape]
    for v in t.variables:
        out += [as_expr(b) for b in v.blocks]
    for c in t.consts:
        if c.shape is not None:
            out += [as_expr(s) for s in c.shape]
    return out


def choose_dims(t: Template, seed: int = 0, tries: int = 400) -> dict[sympy.Symbol, int] | None:
    """Small random dimensions making every declared shape a positive integer.

    >>> from lmic.template.builder import Template
    >>> t = Template("x"); n, p = t.dims("n p"); _ = t.data("H", n - p, n)
    >>> d = choose_dims(t); d[n] > d[p] >= 1
    True
    """
    import numpy as np

    from lmic.template.convert import as_expr

    rng = np.random.default_rng(seed)
    shapes = _shapes(t)
    k = len(t.dimensions)
    if k == 0:
        return {}
    for attempt in range(tries):
        hi = 2 + k + 3 + attempt // 50
        pool = np.arange(1 if attempt >= tries // 2 else 2, hi)
        if len(pool) >= k and attempt < tries // 2:
            vals = rng.choice(pool, size=k, replace=False)
        else:
            vals = rng.choice(pool, size=k, replace=True)
        dims = {s: int(v) for s, v in zip(t.dimensions, vals, strict=True)}
        ok = True
        for s in shapes:
            v = as_expr(s.xreplace(dims))
            if not (v.is_Integer and int(v) >= 1):
                ok = False
                break
        if ok:
            return dims
    return None


def _dim(s: Any, dims: dict) -> int:
    from lmic.template.convert import as_expr

    return int(as_expr(s).xreplace(dims))


def _random_matrix(rng: np.random.Generator, r: int, c: int, kind: str = "full") -> np.ndarray:
    import numpy as np

    M = rng.standard_normal((r, c))
    if kind in ("symmetric", "pd") and r == c:
        M = M + M.T
        if kind == "pd":
            M = M @ M.T / max(r, 1) + np.eye(r)
    if kind == "diagonal":
        M = np.diag(rng.standard_normal(r))
    return M


def _param_value(p: Any) -> float:
    import sympy

    if p.default is not None:
        return float(p.default)
    for v in (0.5, 2.0, 1.0, -0.5, 0.0):
        if sympy.Float(v) in p.domain or sympy.Integer(int(v)) == v and sympy.Integer(int(v)) in p.domain:
            return v
    return 1.0


def _environment(t: Template, dims: dict, rng: np.random.Generator) -> dict[str, Any]:
    import numpy as np

    env: dict[str, Any] = {}
    for d in t.data_decls:
        kind = "pd" if d.positive_definite else ("symmetric" if d.symmetric else "full")
        env[d.name] = _random_matrix(rng, _dim(d.shape[0], dims), _dim(d.shape[1], dims), kind)
    for p in t.params:
        env[p.name] = _param_value(p)
    for c in t.consts:
        if c.shape is None:
            env[c.name] = 0.7
        else:  # a square constant is taken symmetric: its symmetry is unknown without data
            env[c.name] = _random_matrix(rng, _dim(c.shape[0], dims), _dim(c.shape[1], dims), "symmetric")
    for v in t.variables:
        r, cols = _dim(v.shape[0], dims), _dim(v.shape[1], dims)
        if v.kind == "scalar":
            env[v.name] = 0.3
        elif v.kind == "blockdiag":
            sizes = [_dim(b, dims) for b in v.blocks]
            M = np.zeros((r, r))
            k = 0
            for s in sizes:
                M[k : k + s, k : k + s] = _random_matrix(rng, s, s, "pd")
                k += s
            env[v.name] = M
        else:
            env[v.name] = _random_matrix(rng, r, cols, {"symmetric": "pd"}.get(v.kind, v.kind))
    return env
