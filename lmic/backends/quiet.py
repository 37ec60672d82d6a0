"""Silence a native library's own prints (file descriptors 1 and 2, and Python's streams).

Examples
--------
>>> with quiet_native():
...     pass
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator

__all__ = ["quiet_native"]


@contextlib.contextmanager
def quiet_native(active: bool = True) -> Iterator[None]:
    """Silence a native library's own prints (file descriptors 1 and 2) while ``active``.

    >>> with quiet_native(False):
    ...     print("shown")
    shown
    """
    if not active:
        yield
        return
    try:
        saved = [os.dup(1), os.dup(2)]
    except OSError:  # no real file descriptors (embedded interpreters)
        yield
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    sink = open(os.devnull, "w")  # noqa: SIM115 -- closed in the finally clause
    try:
        sys.stdout.flush()
        sys.stderr.flush()
        os.dup2(devnull, 1)
        os.dup2(devnull, 2)
        # bindings that print through Python (SCS's scs_printf is PySys_WriteStdout) write to
        # sys.stdout, which need not be file descriptor 1 (a captured or redirected stream)
        with contextlib.redirect_stdout(sink), contextlib.redirect_stderr(sink):
            yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, devnull):
            os.close(fd)
        sink.close()
