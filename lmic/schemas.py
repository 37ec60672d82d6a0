"""Locate and load the JSON Schemas lmic ships (``ir``, ``system``, ``certificate``).

The schemas live in ``<repo>/schemas/`` in a source checkout and in ``lmic/_schemas/`` inside an
installed wheel (``pyproject.toml`` force-includes ``schemas`` as ``lmic/_schemas``).
:func:`load_schema` tries the installed location first (through :mod:`importlib.resources`),
then the checkout, and caches what it read.

Examples
--------
>>> schema = load_schema("ir")
>>> schema["$schema"]
'https://json-schema.org/draft/2020-12/schema'
"""

from __future__ import annotations

import copy
import json
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

from lmic.errors import LmicError

__all__ = ["load_schema", "schema_path"]

_CHECKOUT_DIR = Path(__file__).resolve().parent.parent / "schemas"


def _file_name(name: str) -> str:
    return name if name.endswith(".json") else f"{name}.schema.json"


def schema_path(name: str) -> str:
    """Where the schema ``name`` was found (a path, or a resource description).

    Parameters
    ----------
    name : str
        ``"ir"``, ``"system"``, ``"certificate"`` or a full file name such as
        ``"ir.schema.json"``.

    Raises
    ------
    LmicError
        If the schema is in neither location.

    Examples
    --------
    >>> schema_path("ir").endswith("ir.schema.json")
    True
    """
    return _locate(_file_name(name))[0]


def _locate(fname: str) -> tuple[str, str]:
    """``(where, text)`` of a schema file."""
    try:
        res = resources.files("lmic").joinpath("_schemas", fname)
        if res.is_file():
            return str(res), res.read_text(encoding="utf-8")
    except (ModuleNotFoundError, FileNotFoundError, NotADirectoryError, OSError):
        pass
    path = _CHECKOUT_DIR / fname
    if path.is_file():
        return str(path), path.read_text(encoding="utf-8")
    raise LmicError(f"schema '{fname}' not found (looked in the lmic/_schemas package data and {_CHECKOUT_DIR})")


@cache
def _load(fname: str) -> dict[str, Any]:
    where, text = _locate(fname)
    try:
        schema = json.loads(text)
    except json.JSONDecodeError as err:
        raise LmicError(f"{where}: not valid JSON: {err}") from None
    if not isinstance(schema, dict):
        raise LmicError(f"{where}: a schema must be a JSON object")
    return schema


def load_schema(name: str) -> dict[str, Any]:
    """The JSON Schema ``name`` as a dict (a fresh copy; the file is read once).

    Parameters
    ----------
    name : str
        ``"ir"``, ``"system"``, ``"certificate"`` or a full file name such as
        ``"ir.schema.json"``.

    Returns
    -------
    dict

    Raises
    ------
    LmicError
        If the schema cannot be found or is not valid JSON.

    Examples
    --------
    >>> load_schema("ir.schema.json")["title"]
    'lmic IR'
    """
    return copy.deepcopy(_load(_file_name(name)))
