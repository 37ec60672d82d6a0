"""lmic: a plugin-based, solver-agnostic compiler for linear matrix inequalities.

Theorems are written once, symbolically (:mod:`lmic.template`); they compile with a system's
numbers into an intermediate representation (:mod:`lmic.ir`), solve on interchangeable
backends (:mod:`lmic.backends`) and are checked by an independent certifier
(:mod:`lmic.certify`).
"""

from __future__ import annotations

__version__ = "0.1.0"

__all__ = ["__version__"]
