"""lmic's on-disk cache: small JSON entries in the user cache directory, never trusted blindly.

Two things are cached, so that a one-shot ``lmic`` process does not redo work whose inputs did
not change: analysed theorem plans (:mod:`lmic.compile.cache`, keyed by the template hash and
lmic's version) and the list of installed theorems that ``lmic theorems`` prints
(:mod:`lmic.plugin_index`, keyed by the installed plugins' versions and files).

Where: ``$LMIC_CACHE_DIR`` if set, else the platform's user cache folder (``platformdirs``:
``~/.cache/lmic`` on Linux, ``~/Library/Caches/lmic`` on macOS, ``%LOCALAPPDATA%\\lmic\\Cache``
on Windows). ``LMIC_NO_CACHE=1`` turns the cache off (nothing read, nothing written). Deleting
the folder (or ``lmic.cache.clear()``) is always safe.

Safety rules:

* entries are JSON only (never pickle): a document ``{"format", "kind", "key", "sha256",
  "payload"}`` whose ``sha256`` covers the canonical JSON of the payload;
* a write goes to a temporary file in the same folder and is renamed over the entry
  (:func:`lmic.output.write_output`), so concurrent writers leave one complete entry;
* a read returns ``None`` (a miss) for a missing, unreadable, truncated, corrupt, oversized or
  mismatched entry (other format, kind or key, wrong checksum), and for a file owned by another
  user; the caller recomputes and writes the entry again;
* any error while reading or writing is a miss or a skipped write, never an error of lmic.

Examples
--------
>>> import os, tempfile
>>> old = os.environ.get("LMIC_CACHE_DIR"); os.environ["LMIC_CACHE_DIR"] = tempfile.mkdtemp()
>>> store("demo", {"id": "a.b"}, {"answer": [1, 2]})
True
>>> load("demo", {"id": "a.b"})
{'answer': [1, 2]}
>>> load("demo", {"id": "other"}) is None
True
>>> clear(); cache_dir().exists()
False
>>> os.environ.pop("LMIC_CACHE_DIR"); os.environ.update({"LMIC_CACHE_DIR": old} if old else {})  # doctest: +ELLIPSIS
'...'
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from pathlib import Path
from typing import Any

__all__ = ["CACHE_DIR_ENV", "NO_CACHE_ENV", "FORMAT", "cache_dir", "entry_path", "load", "store", "clear"]

#: the folder of the cache (overrides the platform's user cache folder)
CACHE_DIR_ENV = "LMIC_CACHE_DIR"
#: set to a non-empty value other than ``0`` to turn the cache off
NO_CACHE_ENV = "LMIC_NO_CACHE"
#: the version of the entry layout (entries of another layout are misses)
FORMAT = "lmic-cache/1"
#: entries larger than this are not read (a corrupt or foreign file)
MAX_BYTES = 64 * 1024 * 1024


def _canonical(obj: Any) -> bytes:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=False).encode()


def cache_dir() -> Path | None:
    """The cache folder, or ``None`` when the cache is turned off (``LMIC_NO_CACHE``).

    >>> os.environ["LMIC_NO_CACHE"] = "1"; cache_dir() is None
    True
    >>> os.environ["LMIC_NO_CACHE"] = "0"; cache_dir() is None
    False
    >>> del os.environ["LMIC_NO_CACHE"]
    """
    if os.environ.get(NO_CACHE_ENV, "").strip() not in ("", "0"):
        return None
    given = os.environ.get(CACHE_DIR_ENV, "").strip()
    if given:
        return Path(given).expanduser()
    try:
        import platformdirs

        return Path(platformdirs.user_cache_dir("lmic", appauthor=False))
    except ImportError:  # a dependency, but an install without it still runs (XDG layout)
        try:
            return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "lmic"
        except RuntimeError:  # no home folder: no cache
            return None


def entry_path(kind: str, key: Any) -> Path | None:
    """Where the entry of ``kind`` for ``key`` (any JSON value) lives; ``None`` if off.

    >>> entry_path("plans", {"x": 1}).name.endswith(".json")
    True
    """
    return _entry_path(kind, _canonical(key))


def _entry_path(kind: str, canonical_key: bytes) -> Path | None:
    root = cache_dir()
    if root is None:
        return None
    digest = hashlib.sha256(kind.encode() + b"\0" + canonical_key).hexdigest()[:40]
    return root / kind / f"{digest}.json"


def load(kind: str, key: Any) -> Any:
    """The payload stored for ``(kind, key)``, or ``None`` (missing, corrupt or mismatched).

    >>> load("demo", {"never": "stored"}) is None
    True
    """
    try:
        canonical_key = _canonical(key)  # once: the file name and the stored key's check
    except (ValueError, TypeError, RecursionError):
        return None
    path = _entry_path(kind, canonical_key)
    if path is None:
        return None
    try:
        with open(path, "rb") as fh:
            if hasattr(os, "geteuid") and os.fstat(fh.fileno()).st_uid != os.geteuid():
                return None  # planted by another user (a shared LMIC_CACHE_DIR): never trusted
            raw = fh.read(MAX_BYTES + 1)
        if len(raw) > MAX_BYTES:
            return None
        doc = json.loads(raw)
        if not isinstance(doc, dict) or doc.get("format") != FORMAT or doc.get("kind") != kind:
            return None
        if _canonical(doc.get("key")) != canonical_key:
            return None
        payload = doc.get("payload")
        if doc.get("sha256") != hashlib.sha256(_canonical(payload)).hexdigest():
            return None
        return payload
    except (OSError, ValueError, TypeError, RecursionError):
        return None


def store(kind: str, key: Any, payload: Any) -> bool:
    """Write ``payload`` (JSON-serialisable) for ``(kind, key)`` atomically; ``True`` if written.

    Never raises for an I/O problem (read-only or full disk, missing permissions): the entry is
    simply not written.

    >>> store("demo", {"id": 1}, {"nan": float("nan")})  # not JSON: not written
    False
    """
    path = entry_path(kind, key)
    if path is None:
        return False
    try:
        body = _canonical(payload)
        doc = {"format": FORMAT, "kind": kind, "key": key, "sha256": hashlib.sha256(body).hexdigest()}
        text = _canonical(doc)[:-1] + b',"payload":' + body + b"}"
    except (ValueError, TypeError, RecursionError):
        return False
    from lmic.errors import LmicError
    from lmic.output import write_output

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_output(path, text, binary=True)
    except (OSError, LmicError):
        return False
    return True


def clear() -> None:
    """Delete the whole cache folder (a no-op when it is off or missing); see the module example."""
    root = cache_dir()
    if root is not None:
        shutil.rmtree(root, ignore_errors=True)
