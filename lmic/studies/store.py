"""A study's output folder: results that survive crashes, the manifest, certificates, a lock.

``DIR/results.jsonl`` gets one JSON line per finished job, appended by the driver process only,
each with a single ``write`` of the whole line on a descriptor opened with ``O_APPEND``: once
``write`` returns, the line is in the kernel, so a killed run (or a killed worker) leaves every
finished line whole. ``fsync`` -- which only matters if the *machine* fails -- is grouped: at most
one every ``sync_interval`` seconds (default 1 s) and one at :meth:`Store.close`, so a power
failure can lose at most the last second of lines (those jobs simply run again at resume; a torn
last line is ignored and fenced off by a newline at the next run). One ``fsync`` per line cost
the driver about 4 ms a job, a fifth of a short job's time. Certificates are written
(atomically, ``fsync``-ed) under ``DIR/certificates/<hash>.json`` before their result line -- by
the job runner itself when it shares the driver's file system (the local executor), else by the
driver -- so a line always has its certificate. ``DIR/study.json`` lists the jobs of the last run; ``DIR/.lock``
keeps two drivers off one folder.

Examples
--------
>>> import tempfile
>>> d = tempfile.mkdtemp()
>>> store = Store(d)
>>> store.append({"hash": "a", "outcome": "certified"})
>>> sorted(store.done())
['a']
"""

from __future__ import annotations

import fcntl
import json
import os
import time
from pathlib import Path
from typing import Any

from lmic.errors import DataError

__all__ = ["Store", "read_results", "write_atomic", "write_json_atomic"]


def write_atomic(path: str | os.PathLike[str], write: Any, mode: str = "w") -> None:
    """Write through a temporary file in the same folder, then rename: nothing half-written.

    >>> import tempfile
    >>> p = os.path.join(tempfile.mkdtemp(), "x.txt")
    >>> write_atomic(p, lambda fh: fh.write("ok"))
    >>> open(p).read()
    'ok'
    """
    import tempfile

    target = Path(path)
    folder = target.parent if str(target.parent) else Path(".")
    if not folder.is_dir():
        raise DataError(f"{target}: folder {folder} does not exist")
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", dir=folder)
    try:
        with os.fdopen(fd, mode) as fh:
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, target)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_json_atomic(path: str | os.PathLike[str], document: Any) -> None:
    """``document`` as one JSON text, written atomically (:func:`write_atomic`).

    The text is encoded in one ``json.dumps`` call (C-accelerated; ``json.dump`` to a file runs
    the pure-Python encoder, five times slower on a certificate).

    >>> import tempfile
    >>> p = os.path.join(tempfile.mkdtemp(), "d.json")
    >>> write_json_atomic(p, {"a": [1.5]})
    >>> open(p).read()
    '{"a": [1.5]}'
    """
    text = json.dumps(document, allow_nan=False)
    write_atomic(path, lambda fh: fh.write(text))


def _whole_record(rec: Any) -> bool:
    """A job record as the runners write it (a damaged one means: the job is not done)."""
    from lmic.studies.tasks import OUTCOMES

    return (
        isinstance(rec, dict)
        and isinstance(rec.get("hash"), str)
        and rec.get("outcome", "error") in OUTCOMES
        and isinstance(rec.get("finished_at", ""), str)
        and isinstance(rec.get("params") or {}, dict)
    )


def read_results(path: str | os.PathLike[str]) -> list[dict[str, Any]]:
    """Every whole, parseable line of a ``results.jsonl`` (first line per job hash wins; a
    damaged record, e.g. an edited outcome, counts as not done: a resumed study runs it again).

    >>> read_results("/nonexistent/results.jsonl")
    []
    """
    p = Path(path)
    if not p.is_file():
        return []
    out: list[dict[str, Any]] = []
    seen: set[str] = set()
    with p.open("rb") as fh:
        for raw in fh:
            if not raw.endswith(b"\n"):
                break  # a torn last line
            try:
                rec = json.loads(raw)
            except (json.JSONDecodeError, UnicodeDecodeError):
                continue
            if _whole_record(rec) and rec["hash"] not in seen:
                seen.add(rec["hash"])
                out.append(rec)
    return out


class Store:
    """The output folder ``root`` of a study (created if missing)."""

    def __init__(self, root: str | os.PathLike[str], *, sync_interval: float = 1.0) -> None:
        self.root = Path(root)
        self.sync_interval = float(sync_interval)
        self._synced_at = time.monotonic()
        self._unsynced = False
        try:
            (self.root / "certificates").mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise DataError(f"{self.root}: cannot create the output folder ({err.strerror})") from None
        self.results_path = self.root / "results.jsonl"
        self._fd: int | None = None
        self._lock_fd: int | None = None

    # -- lock -------------------------------------------------------------------------------------
    def lock(self) -> None:
        """Take ``DIR/.lock`` (one driver per folder); raises :class:`DataError` if taken."""
        fd = os.open(self.root / ".lock", os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            other = os.read(fd, 64).decode(errors="replace").strip() or "?"
            os.close(fd)
            raise DataError(f"{self.root}: another lmic batch (pid {other}) is running on this folder") from None
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        self._lock_fd = fd

    def running_pid(self) -> int | None:
        """The pid of the driver holding the lock, or ``None`` when no driver runs."""
        path = self.root / ".lock"
        if not path.exists():
            return None
        fd = os.open(path, os.O_RDONLY)
        try:
            try:
                fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
            except BlockingIOError:
                text = os.read(fd, 64).decode(errors="replace").strip()
                return int(text) if text.isdigit() else -1
            fcntl.flock(fd, fcntl.LOCK_UN)
            return None
        finally:
            os.close(fd)

    # -- results ----------------------------------------------------------------------------------
    def _open(self) -> int:
        if self._fd is None:
            fd = os.open(self.results_path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
            size = os.fstat(fd).st_size
            if size:
                with open(self.results_path, "rb") as fh:
                    fh.seek(size - 1)
                    if fh.read(1) != b"\n":
                        os.write(fd, b"\n")  # fence off a torn line
            self._fd = fd
        return self._fd

    def append(self, record: dict[str, Any]) -> None:
        """Append one record as one line: a single ``write`` with ``O_APPEND``.

        The file is ``fsync``-ed when ``sync_interval`` seconds have passed since the last
        ``fsync`` (``sync_interval=0``: after every line) and at :meth:`sync` / :meth:`close`.
        """
        line = (json.dumps(record, allow_nan=False, separators=(",", ":")) + "\n").encode()
        fd = self._open()
        written = os.write(fd, line)
        if written != len(line):  # regular files do not short-write short of a full disk
            raise OSError(f"{self.results_path}: short write ({written} of {len(line)} bytes)")
        self._unsynced = True
        if time.monotonic() - self._synced_at >= self.sync_interval:
            self.sync()

    def sync(self) -> None:
        """``fsync`` the results file if lines were appended since the last one."""
        if self._fd is not None and self._unsynced:
            os.fsync(self._fd)
            self._unsynced = False
        self._synced_at = time.monotonic()

    def done(self) -> dict[str, dict[str, Any]]:
        """``hash -> record`` of the jobs already finished."""
        return {r["hash"]: r for r in read_results(self.results_path)}

    def write_certificate(self, job_hash: str, document: dict[str, Any]) -> str:
        """Write ``certificates/<hash>.json`` atomically; return its path relative to the folder."""
        rel = f"certificates/{job_hash}.json"
        write_json_atomic(self.root / rel, document)
        return rel

    def certificate_path(self, job_hash: str) -> str:
        """The absolute path of ``certificates/<hash>.json`` (where a local runner writes it)."""
        return str((self.root / "certificates" / f"{job_hash}.json").resolve())

    # -- manifest ---------------------------------------------------------------------------------
    def write_manifest(self, manifest: dict[str, Any]) -> None:
        """``DIR/study.json``: the study's name, settings and jobs (atomically)."""
        manifest = {**manifest, "written_at": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}
        write_atomic(self.root / "study.json", lambda fh: json.dump(manifest, fh, indent=1, allow_nan=False))

    def manifest(self) -> dict[str, Any] | None:
        """The manifest, or ``None`` if this folder has none."""
        path = self.root / "study.json"
        if not path.is_file():
            return None
        try:
            return json.loads(path.read_text(encoding="utf-8"))
        except (json.JSONDecodeError, OSError):
            raise DataError(f"{path}: not a readable study manifest") from None

    def close(self) -> None:
        """``fsync`` and close the results file, and release the lock."""
        if self._fd is not None:
            self.sync()
            os.close(self._fd)
            self._fd = None
        if self._lock_fd is not None:
            os.close(self._lock_fd)
            self._lock_fd = None
