"""The certificate file format: its version and the strict reader (:func:`read_certificate`).

The layout is in the docstring of :mod:`lmic.certify.certificate` and in
``schemas/certificate.schema.json``; reading rejects non-standard JSON constants, numbers that do
not fit a float, another format version and anything the schema forbids. Split out of
:mod:`lmic.certify.certificate`, which re-exports every public name.

Examples
--------
>>> SCHEMA_VERSION
1
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

from lmic.errors import CertificateError, LmicError

__all__ = ["SCHEMA_VERSION", "read_certificate"]

#: version of the certificate file format (the ``lmic_certificate`` key)
SCHEMA_VERSION = 1


def _schema() -> dict[str, Any]:
    try:
        from lmic.schemas import load_schema

        return load_schema("certificate")
    except (ImportError, LmicError):
        here = Path(__file__).resolve().parents[2] / "schemas" / "certificate.schema.json"
        return json.loads(here.read_text(encoding="utf-8"))


def _reject_constant(name: str) -> float:
    raise ValueError(f"{name} is not allowed")


def read_certificate(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read and validate a certificate file.

    Raises
    ------
    CertificateError
        One line: unreadable, not JSON (e.g. truncated), unknown schema version, or not
        following ``schemas/certificate.schema.json`` (naming the field).

    Examples
    --------
    >>> import tempfile, os
    >>> f = os.path.join(tempfile.mkdtemp(), "c.json")
    >>> _ = open(f, "w").write('{"lmic_certificate": 99}')
    >>> read_certificate(f)
    Traceback (most recent call last):
    ...
    lmic.errors.CertificateError: c.json: unknown certificate schema version 99 (this lmic reads 1)
    """
    p = Path(path)
    name = p.name
    from lmic.limits import MAX_INPUT_BYTES, MAX_INT_DIGITS, check_depth

    def parse_int(t: str) -> int:
        if len(t.lstrip("-")) > MAX_INT_DIGITS:
            raise ValueError(f"an integer of {len(t.lstrip('-'))} digits (at most {MAX_INT_DIGITS})")
        return int(t)

    def parse_float(t: str) -> float:
        value = float(t)
        if not math.isfinite(value):
            raise ValueError(f"the number {t[:24]} overflows float64")
        return value

    try:
        if p.stat().st_size > MAX_INPUT_BYTES:
            raise CertificateError(f"{p}: larger than the input limit of {MAX_INPUT_BYTES} bytes")
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise CertificateError(f"{p}: no such certificate file") from None
    except (OSError, UnicodeDecodeError) as err:
        raise CertificateError(f"{p}: cannot read: {err}") from None
    if not text.strip():
        raise CertificateError(f"{name}: empty certificate file")
    try:
        doc = json.loads(text, parse_constant=_reject_constant, parse_int=parse_int, parse_float=parse_float)
    except json.JSONDecodeError as err:
        raise CertificateError(
            f"{name}: not valid JSON (truncated or corrupted?) at line {err.lineno} column {err.colno}: {err.msg}"
        ) from None
    except ValueError as err:
        raise CertificateError(f"{name}: {err}") from None
    except RecursionError:
        raise CertificateError(f"{name}: nested too deeply") from None
    check_depth(doc, name, CertificateError)
    if not isinstance(doc, dict) or "lmic_certificate" not in doc:
        raise CertificateError(f"{name}: not an lmic certificate (no 'lmic_certificate' key)")
    version = doc["lmic_certificate"]
    if version != SCHEMA_VERSION or isinstance(version, bool):
        raise CertificateError(
            f"{name}: unknown certificate schema version {version!r} (this lmic reads {SCHEMA_VERSION})"
        )
    import jsonschema

    validator = jsonschema.Draft202012Validator(_schema())
    errors = sorted(validator.iter_errors(doc), key=lambda e: list(e.absolute_path))
    if errors:
        first = errors[0]
        where = "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in first.absolute_path).lstrip(".")
        msg = " ".join(first.message.split())
        if len(msg) > 160:
            msg = msg[:157] + "..."
        raise CertificateError(f"{name}: {where or 'top level'}: {msg}")
    return doc
