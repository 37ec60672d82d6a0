"""The error hierarchy of lmic: one root, a small flat set of classes.

Every error a user can provoke with bad input is an :class:`LmicError`; the command line
prints its message on one line and exits with code 2. Infeasibility is a *status*, never an
exception.

Examples
--------
>>> try:
...     raise DataError("system.yaml: data 'A' has shape 3x4, expected n x n")
... except LmicError as err:
...     print(err)
system.yaml: data 'A' has shape 3x4, expected n x n
"""

from __future__ import annotations

__all__ = [
    "LmicError",
    "TemplateError",
    "DataError",
    "BackendUnavailable",
    "BackendError",
    "CertificateError",
    "IRError",
]


class LmicError(Exception):
    """Root of every error raised by lmic."""


class TemplateError(LmicError):
    """A theorem template is not a valid LMI (names the block and the term at fault)."""


class DataError(LmicError):
    """System data or parameters do not fit the theorem (names file, key and shape)."""


class IRError(LmicError):
    """An IR or SDPA file is malformed (names the file, field or line)."""


class BackendUnavailable(LmicError):
    """A backend is unknown, or its solver package is not installed (names the package)."""


class BackendError(LmicError):
    """A backend cannot take a problem, or failed in a way that is not a solver status."""


class CertificateError(LmicError):
    """A certificate file is malformed, truncated, of an unknown version, or unusable."""
