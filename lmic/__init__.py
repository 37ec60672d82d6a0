"""lmic: a plugin-based, solver-agnostic compiler for linear matrix inequalities.

Theorems are written once, symbolically (:mod:`lmic.template`); they compile with a system's
numbers into an intermediate representation (:mod:`lmic.ir`), solve on interchangeable
backends (:mod:`lmic.backends`) and are checked by an independent certifier
(:mod:`lmic.certify`).

Examples
--------
>>> import lmic
>>> result = lmic.solve("thesis.lyapunov", {"data": {"A": [[-1.0, 2.0], [0.0, -3.0]]}})
>>> result.verdict
'certified'
>>> result.values["P"].shape
(2, 2)
>>> lmic.theorem("qib.thm1").citation
'Wang, Song & Zhang (2015), Adv. Difference Equ. 2015:307, Theorem 1'
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any, cast

from lmic._version import __version__

__all__ = [
    "__version__",
    "solve",
    "theorem",
    "theorems",
    "compile_theorem",
    "register",
    "Theorem",
    "Result",
    "SolveOptions",
]

if TYPE_CHECKING:  # pragma: no cover
    from lmic.api import Result
    from lmic.ir.problem import Problem
    from lmic.options import SolveOptions
    from lmic.registry import register
    from lmic.template.theorem import Theorem

# Importing lmic is cheap (``lmic --version`` loads neither numpy nor sympy): the names below and
# the sub-packages (``lmic.api``, ``lmic.compile``, ...) are imported on first access (PEP 562).
_LAZY: dict[str, tuple[str, str]] = {
    "register": ("lmic.registry", "register"),
    "Theorem": ("lmic.template.theorem", "Theorem"),
    "Result": ("lmic.api", "Result"),
    "SolveOptions": ("lmic.options", "SolveOptions"),
}
_SUBMODULES = frozenset(
    {
        "api",
        "backends",
        "cache",
        "certify",
        "compile",
        "errors",
        "ir",
        "options",
        "outcome",
        "output",
        "plugin_index",
        "registry",
        "system",
        "template",
    }
)


def __getattr__(name: str) -> Any:
    """``lmic.Theorem``, ``lmic.register``, ... and ``lmic.compile``, ...: imported on first use.

    >>> import lmic
    >>> lmic.Theorem.__name__, lmic.registry.__name__
    ('Theorem', 'lmic.registry')
    """
    if name in _LAZY:
        module, attr = _LAZY[name]
        value = getattr(importlib.import_module(module), attr)
        globals()[name] = value
        return value
    if name in _SUBMODULES:
        return importlib.import_module(f"lmic.{name}")
    raise AttributeError(f"module 'lmic' has no attribute {name!r}")


def __dir__() -> list[str]:
    """The public names, the lazily imported ones included."""
    return sorted(set(globals()) | set(_LAZY) | _SUBMODULES)


def solve(
    theorem: str | Theorem,
    system: Any,
    params: dict[str, Any] | None = None,
    backend: str | None = None,
    *,
    exact: bool = False,
    options: Any = None,
) -> Result:
    """Compile, solve and certify ``theorem`` for ``system``.

    Parameters
    ----------
    theorem : str or Theorem
        A theorem id (``lmic.theorems()`` lists them), a :class:`~lmic.template.Theorem`
        object written in a notebook (``@theorem``-decorated; no packaging or registration
        needed), or an ``.json`` IR / ``.dat-s`` file (then ``system`` is ``None``).
    system : path, dict, System or StateSpace
        A system file, a dict with its keys (``data``, ``params``; numpy arrays allowed), a
        python-control ``StateSpace`` (its ``A, B, C, D`` fill the theorem's data of those names),
        or ``{"plant": ss, "data": {...}, "params": {...}}``.
    params : dict, optional
        Parameter overrides.
    backend : str
        ``clarabel`` (the default; ``auto`` when a PSD block is too large for Clarabel), ``scs``,
        ``cvxopt``, ``sdpa``, ``cvxpy[:SOLVER]``, ``picos``, ``auto``.
    exact : bool
        Also prove strict LMIs in exact rational arithmetic.

    Returns
    -------
    lmic.api.Result
        ``.status``, ``.verdict``, ``.certificate``, ``.gains`` and ``.values`` (numpy arrays);
        displays as a table in Jupyter.
    """
    from lmic.api import solve as _solve

    # api.solve takes Theorem objects too (its annotation names str, path and Problem only)
    return _solve(cast(Any, theorem), system, params, backend, options=options, exact=exact)


def theorem(theorem_id: str) -> Theorem:
    """The registered theorem ``theorem_id`` (``.latex()``, ``.template()``, ``.citation``)."""
    from lmic.registry import get_theorem

    return get_theorem(theorem_id)


def theorems() -> list[Theorem]:
    """Every registered theorem."""
    from lmic.registry import list_theorems

    return list_theorems()


def compile_theorem(theorem_id: str, system: Any, params: dict[str, Any] | None = None) -> Problem:
    """Compile a theorem for a system into the IR (:class:`lmic.ir.Problem`) without solving."""
    from lmic.compile import compile_theorem
    from lmic.plant import as_system

    return compile_theorem(theorem_id, as_system(theorem_id, system), params)
