"""A one-line progress display for long solves: the route, the current step, elapsed seconds.

:func:`solve_progress` is a context manager. While its block runs longer than ``delay`` seconds
(2 s by default: quick solves print nothing) it rewrites one line on standard error once a
second, e.g. ``lmic: route scs -> cvxopt | scs | 14 s``, and erases it when the block ends.
It is silent unless standard error is a terminal (pipes, files, notebooks, batch workers see
nothing) and when ``LMIC_PROGRESS=0`` is set.

Nested uses share one line: the outermost call (e.g. the solve policy, with the whole route as
its label) owns the display and inner calls (each backend's :meth:`Backend.solve`) only name
the current step. The display thread writes with ``os.write`` on file descriptor 2, never
through Python's buffered ``sys.stderr``, so a solver child forked meanwhile (the time-limit
sandbox) cannot inherit a held stream lock.

Examples
--------
>>> with solve_progress("route clarabel") as show:
...     with solve_progress("clarabel"):
...         pass
>>> show.enabled  # doctest runs are not on a terminal
False
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
import time
from collections.abc import Iterator
from typing import TextIO

__all__ = ["solve_progress", "Progress"]

_ACTIVE: list[Progress] = []
_LOCK = threading.Lock()


class Progress:
    """State of one display: its label, the current step and the thread that draws it."""

    def __init__(self, label: str, stream: TextIO | None, delay: float, interval: float, enabled: bool) -> None:
        self.label = label
        self.steps: list[str] = []
        self.stream = stream
        self.delay = delay
        self.interval = interval
        self.enabled = enabled
        self.start = time.monotonic()
        self.drawn = False
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def line(self) -> str:
        """The text shown now (without the carriage return).

        >>> p = Progress("route sdpa", None, 0.0, 1.0, False)
        >>> p.steps.append("sdpa")
        >>> p.line().rsplit("|", 1)[0]
        'lmic: route sdpa | sdpa '
        """
        parts = [f"lmic: {self.label}"] + [s for s in self.steps[-1:] if s and s != self.label]
        return " | ".join(parts) + f" | {time.monotonic() - self.start:.0f} s"

    def _fd(self) -> int | None:
        try:
            return self.stream.fileno() if self.stream is not None else None
        except (AttributeError, OSError, ValueError):
            return None

    def _write(self, text: str) -> None:
        fd = self._fd()
        if fd is None:
            return
        with contextlib.suppress(OSError):
            os.write(fd, text.encode("utf-8", "replace"))

    def _run(self) -> None:
        if self._stop.wait(self.delay):
            return
        while True:
            self._write("\r\x1b[K" + self.line())
            self.drawn = True
            if self._stop.wait(self.interval):
                return

    def begin(self) -> None:
        """Start the drawing thread (when enabled)."""
        if self.enabled:
            self._thread = threading.Thread(target=self._run, name="lmic-progress", daemon=True)
            self._thread.start()

    def end(self) -> None:
        """Stop drawing and erase the line."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(2 * self.interval)
        if self.drawn:
            self._write("\r\x1b[K")


def _enabled(stream: TextIO | None) -> bool:
    if os.environ.get("LMIC_PROGRESS", "1").strip().lower() in ("0", "no", "false", "off"):
        return False
    try:
        return bool(stream is not None and stream.isatty())
    except (AttributeError, ValueError, OSError):
        return False


@contextlib.contextmanager
def solve_progress(
    label: str,
    *,
    stream: TextIO | None = None,
    delay: float = 2.0,
    interval: float = 1.0,
    enabled: bool | None = None,
) -> Iterator[Progress]:
    """Show ``label`` and the elapsed seconds on standard error while the block runs.

    Parameters
    ----------
    label : str
        What runs: the route for the outermost call (``"route scs -> cvxopt"``), the backend for
        an inner one (``"scs"``).
    stream : file, optional
        Where to draw (default ``sys.stderr``); must be a terminal unless ``enabled=True``.
    delay, interval : float
        Seconds before the first draw, and between draws.
    enabled : bool, optional
        Force the display on or off (default: on when ``stream`` is a terminal and
        ``LMIC_PROGRESS`` is not ``0``).

    Examples
    --------
    >>> with solve_progress("route sdpa", enabled=False) as p:
    ...     p.label
    'route sdpa'
    """
    stream = sys.stderr if stream is None else stream
    with _LOCK:
        outer = _ACTIVE[0] if _ACTIVE else None
    if outer is not None:  # nested: name the step on the outer display
        outer.steps.append(label)
        try:
            yield outer
        finally:
            with contextlib.suppress(ValueError):
                outer.steps.remove(label)
        return
    show = Progress(label, stream, delay, interval, _enabled(stream) if enabled is None else enabled)
    with _LOCK:
        _ACTIVE.append(show)
    show.begin()
    try:
        yield show
    finally:
        show.end()
        with _LOCK:
            _ACTIVE.remove(show)
