"""Writing output files safely: every ``-o`` of lmic goes through :func:`write_output`.

Rules (checked by :func:`check_output_path` *before* any work, and again when writing):

* A new path, or an existing **regular file**, is written atomically: the content goes to a
  hidden temporary file ``.NAME.<random>.tmp`` in the same folder, is flushed and ``fsync``-ed,
  then renamed over the target. Ctrl-C, a full disk, a file-size limit or any error removes the
  temporary file; a crash or ``kill -9`` may leave it, never a partial target. Two runs
  writing the same path leave one complete file (the last rename wins). An existing file keeps
  its permission bits; a new one gets ``0666 & ~umask``.
* A **character device or a FIFO** (``/dev/null``, ``/dev/stdout``, a named pipe) is written
  directly, never replaced: ``-o /dev/null`` does not turn the device into a regular file.
  Block devices, sockets and other special files are refused.
* A **symbolic link** is written through only when its target is a regular file owned by the
  user running lmic (or a character device / FIFO, written directly); the link itself stays.
  A dangling link, or one to a file owned by someone else (the ``/tmp`` symlink attack), is
  refused.
* A directory, a missing folder, a folder the user cannot write to, or a read-only target is
  refused with one line (:class:`OutputError`, exit code 2).

Any error while writing gives one line and leaves no file behind.

Examples
--------
>>> import tempfile, os
>>> d = tempfile.mkdtemp()
>>> write_output(os.path.join(d, "a.txt"), "hello\\n")
>>> open(os.path.join(d, "a.txt")).read()
'hello\\n'
>>> write_output(d, "x")
Traceback (most recent call last):
...
lmic.output.OutputError: ... is a directory
"""

from __future__ import annotations

import errno
import math
import os
import secrets
import stat
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

from lmic.errors import LmicError

__all__ = ["OutputError", "check_output_path", "write_output", "json_text"]


class OutputError(LmicError):
    """An output path that cannot (or must not) be written; one line, exit code 2."""


def _why(err: OSError) -> str:
    if err.errno in (errno.ENOSPC, errno.EDQUOT):
        return "no space left on the device"
    if err.errno == errno.EFBIG:
        return "file too large (file-size limit reached)"
    return err.strerror or str(err)


def check_output_path(path: str | os.PathLike[str]) -> tuple[Path, str]:
    """Check an output path before any work; return ``(target, how)``.

    ``how`` is ``"atomic"`` (new path or regular file, written by rename; ``target`` is the
    symlink's target when ``path`` is an allowed symlink) or ``"direct"`` (a character device
    or a FIFO).

    Raises
    ------
    OutputError
        One line naming the path and the rule it breaks.

    Examples
    --------
    >>> check_output_path("/dev/null")
    (PosixPath('/dev/null'), 'direct')
    >>> check_output_path("/nonexistent-folder/x.json")
    Traceback (most recent call last):
    ...
    lmic.output.OutputError: /nonexistent-folder/x.json: folder /nonexistent-folder does not exist
    """
    given = os.fspath(path)
    if not given:
        raise OutputError("empty output path")
    p = Path(given)
    try:
        lst = os.lstat(p)
    except FileNotFoundError:
        lst = None
    except OSError as err:
        raise OutputError(f"{given}: cannot be written: {_why(err)}") from None
    target = p
    if lst is not None and stat.S_ISLNK(lst.st_mode):
        try:
            st = os.stat(p)
        except OSError:
            raise OutputError(f"{given}: is a dangling symbolic link; lmic does not write through it") from None
        if stat.S_ISREG(st.st_mode):
            if hasattr(os, "geteuid") and st.st_uid != os.geteuid():
                raise OutputError(
                    f"{given}: is a symbolic link to a file owned by another user; lmic does not write through it"
                )
            target = Path(os.path.realpath(p))
        elif stat.S_ISCHR(st.st_mode) or stat.S_ISFIFO(st.st_mode):
            return p, "direct"
        elif stat.S_ISDIR(st.st_mode):
            raise OutputError(f"{given}: is a directory")
        else:
            raise OutputError(f"{given}: is a symbolic link to a special file; lmic does not write through it")
        lst = os.lstat(target)
    if lst is not None:
        mode = lst.st_mode
        if stat.S_ISDIR(mode):
            raise OutputError(f"{given}: is a directory")
        if stat.S_ISCHR(mode) or stat.S_ISFIFO(mode):
            return p, "direct"
        if not stat.S_ISREG(mode):
            raise OutputError(f"{given}: is a special file (not a regular file, a character device or a FIFO)")
        if not os.access(target, os.W_OK):
            raise OutputError(f"{given}: is read-only")
    folder = target.parent if str(target.parent) else Path(".")
    if not folder.is_dir():
        raise OutputError(f"{given}: folder {folder} does not exist")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise OutputError(f"{given}: folder {folder} is not writable")
    return target, "atomic"


def _write_all(fh: IO[Any], data: Any) -> None:
    if callable(data):
        data(fh)
    else:
        fh.write(data)


def _atomic(target: Path, data: Any, binary: bool, given: str) -> None:
    folder = target.parent if str(target.parent) else Path(".")
    try:
        mode = stat.S_IMODE(os.stat(target).st_mode)
    except FileNotFoundError:
        umask = os.umask(0)
        os.umask(umask)
        mode = 0o666 & ~umask
    tmp_name: str | None = None
    fd = -1
    try:
        tmp_name = str(folder / f".{target.name}.{secrets.token_hex(6)}.tmp")
        fd = os.open(tmp_name, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0), 0o600)
        fh: IO[Any] = os.fdopen(fd, "wb") if binary else os.fdopen(fd, "w", encoding="utf-8")
        fd = -1  # owned by fh now
        with fh:
            _write_all(fh, data)
            fh.flush()
            os.fsync(fh.fileno())
            os.fchmod(fh.fileno(), mode)
        os.replace(tmp_name, target)
        tmp_name = None
        try:  # make the rename itself durable
            dfd = os.open(folder, os.O_RDONLY)
            try:
                os.fsync(dfd)
            finally:
                os.close(dfd)
        except OSError:
            pass
    except OSError as err:
        raise OutputError(f"{given}: cannot write: {_why(err)}") from None
    finally:
        if fd >= 0:
            os.close(fd)
        if tmp_name is not None:
            try:
                os.unlink(tmp_name)
            except OSError:
                pass


def _direct(target: Path, data: Any, binary: bool, given: str) -> None:
    try:
        fh: IO[Any] = open(target, "wb") if binary else open(target, "w", encoding="utf-8")  # noqa: SIM115
        with fh:
            _write_all(fh, data)
            fh.flush()
    except OSError as err:
        raise OutputError(f"{given}: cannot write: {_why(err)}") from None


def write_output(
    path: str | os.PathLike[str],
    data: str | bytes | Callable[[IO[Any]], None],
    *,
    binary: bool | None = None,
) -> None:
    """Write ``data`` (text, bytes, or a function writing to a file object) to ``path`` safely.

    See the module docstring for the rules. ``binary`` defaults to ``isinstance(data, bytes)``.

    Raises
    ------
    OutputError
        The path breaks a rule, or writing failed (nothing is left behind).

    Examples
    --------
    >>> import tempfile, os
    >>> f = os.path.join(tempfile.mkdtemp(), "b.bin")
    >>> write_output(f, b"\\x00\\x01")
    >>> os.path.getsize(f)
    2
    """
    given = os.fspath(path)
    if binary is None:
        binary = isinstance(data, bytes)
    target, how = check_output_path(path)
    if how == "direct":
        _direct(target, data, binary, given)
    else:
        _atomic(target, data, binary, given)


# -- JSON text ------------------------------------------------------------------------------------
class _Unusual(Exception):
    """A value :func:`json_text` leaves to :func:`json.dumps` (its output or its error)."""


def json_text(obj: Any, indent: int = 2) -> str:
    """``json.dumps(obj, indent=indent, allow_nan=False)``, character for character, faster.

    With an indent, :func:`json.dumps` runs the pure-Python encoder: one generator step per
    number, ~25-50 ms for the variables and certificate of a 40-state ``lmic solve --json``.
    Here a list of plain floats (a matrix row) is one :meth:`str.join` over ``float.__repr__``
    (what :mod:`json` writes for a finite float). Anything but dicts with string keys, lists,
    tuples, strings, ints, finite floats, booleans and ``None`` (a non-finite float, another
    key type, a numpy scalar, a cycle) is left to :func:`json.dumps` itself, which writes it
    or raises exactly as before.

    >>> json_text({"a": [1.5, 2.0], "b": {"c": None, "d": "é"}, "e": []})
    '{\\n  "a": [\\n    1.5,\\n    2.0\\n  ],\\n  "b": {\\n    "c": null,\\n    "d": "\\\\u00e9"\\n  },\\n  "e": []\\n}'
    """
    import json

    parts: list[str] = []
    try:
        _encode(obj, parts, "\n", " " * indent, 0)
    except (_Unusual, RecursionError):
        return json.dumps(obj, indent=indent, allow_nan=False)
    return "".join(parts)


def _encode(obj: Any, out: list[str], nl: str, step: str, depth: int) -> None:
    """Append the indented JSON of ``obj`` (``nl``: newline plus the current indent)."""
    from json.encoder import encode_basestring_ascii

    if depth > 200:
        raise _Unusual  # deep or cyclic: json.dumps decides
    if isinstance(obj, str):
        out.append(encode_basestring_ascii(obj))
    elif obj is None:
        out.append("null")
    elif obj is True:
        out.append("true")
    elif obj is False:
        out.append("false")
    elif isinstance(obj, int):
        out.append(int.__repr__(obj))
    elif isinstance(obj, float):
        if not math.isfinite(obj):
            raise _Unusual
        out.append(float.__repr__(obj))
    elif isinstance(obj, list | tuple):
        if not obj:
            out.append("[]")
            return
        inner = nl + step
        if all(type(v) is float for v in obj):
            text = ("," + inner).join(map(float.__repr__, obj))
            if "n" in text:  # 'nan' or 'inf': json.dumps raises
                raise _Unusual
            out += ("[", inner, text, nl, "]")
            return
        out.append("[")
        for k, v in enumerate(obj):
            out.append(inner if k == 0 else "," + inner)
            _encode(v, out, inner, step, depth + 1)
        out += (nl, "]")
    elif isinstance(obj, dict):
        if not obj:
            out.append("{}")
            return
        inner = nl + step
        out.append("{")
        for k, (key, v) in enumerate(obj.items()):
            if not isinstance(key, str):
                raise _Unusual  # json.dumps converts numbers, booleans and None to strings
            out += (inner if k == 0 else "," + inner, encode_basestring_ascii(key), ": ")
            _encode(v, out, inner, step, depth + 1)
        out += (nl, "}")
    else:
        raise _Unusual
