"""The one progress bar of lmic's long commands (rich, on standard error).

``lmic crosscheck``, ``lmic reproduce``, ``lmic solve --maximize/--sweep`` and ``lmic batch``
draw their progress with :class:`ProgressBar`: a bold label, the bar, ``done/total``, the elapsed
time and a free text (``info``), optionally a spinner, a rate (``2.00 jobs/s``) and the time
remaining. The bar is drawn only when standard error is a terminal; elsewhere (a pipe, a log
file, a notebook cell's captured stderr) it is silent, or with ``log=True`` writes the ``line``
of each update as one plain line (a log a person can read afterwards), or with ``summary=True``
prints its final state once, when the work ends.

(The one-line display of a single long solve, :mod:`lmic.backends.progress`, is a different
thing: a line rewritten by a thread with ``os.write``, safe around forked solver children.)

Examples
--------
>>> with ProgressBar("reproduce", total=2) as bar:
...     bar.update(completed=1, info="qib.thm1: ok")
...     bar.update(advance=1, line="[2/2] done")
>>> bar.drawn  # doctest runs are not on a terminal
False
"""

from __future__ import annotations

import sys
from typing import Any

__all__ = ["ProgressBar"]


class ProgressBar:
    """A rich progress bar on standard error (a context manager).

    Parameters
    ----------
    label : str
        The description shown first (bold); :meth:`update` may change it.
    total : int, optional
        The number of steps (``None``: unknown until an update gives it).
    enabled : bool
        ``False`` draws and writes nothing.
    completed : int
        Steps already done (a resumed study).
    spinner : bool
        A spinner before the label.
    rate : str, optional
        Show the speed as ``"<x.xx> <rate>/s"`` (e.g. ``rate="jobs"``).
    eta : bool
        Show the time remaining.
    transient : bool
        Erase the bar when the block ends.
    log : bool
        When standard error is not a terminal, write the ``line`` of each update on a line of its own.
    summary : bool
        When standard error is not a terminal, print the bar's final state once, when the block ends.

    Examples
    --------
    >>> bar = ProgressBar("batch", total=10, rate="jobs", eta=True)
    >>> [type(c).__name__ for c in bar.columns()][:3]
    ['TextColumn', 'BarColumn', 'MofNCompleteColumn']
    """

    def __init__(
        self,
        label: str,
        total: int | None = None,
        *,
        enabled: bool = True,
        completed: int = 0,
        spinner: bool = False,
        rate: str | None = None,
        eta: bool = False,
        transient: bool = False,
        log: bool = False,
        summary: bool = False,
    ) -> None:
        from rich.console import Console

        self.label = label
        self.total = total
        self.completed = completed
        self.spinner, self.rate, self.eta = spinner, rate, eta
        self.console = Console(stderr=True)
        #: whether rich draws the bar (always on a terminal; elsewhere only its final state, with ``summary``)
        self.drawn = enabled and (self.console.is_terminal or (summary and not transient))
        self.log = enabled and log and not self.drawn
        self._progress: Any = None
        self._task: Any = None
        self.transient = transient

    def columns(self) -> list[Any]:
        """The rich columns of this bar, in order."""
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            SpinnerColumn,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        cols: list[Any] = [SpinnerColumn()] if self.spinner else []
        cols += [TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn()]
        if self.rate:
            cols.append(_RateColumn(self.rate))
        cols.append(TimeElapsedColumn())
        if self.eta:
            cols += [TextColumn("ETA"), TimeRemainingColumn()]
        cols.append(TextColumn("{task.fields[info]}"))
        return cols

    def __enter__(self) -> ProgressBar:
        if self.drawn:
            from rich.progress import Progress

            self._progress = Progress(*self.columns(), console=self.console, transient=self.transient)
            self._progress.start()
            self._task = self._progress.add_task(self.label, total=self.total, completed=self.completed, info="")
        return self

    def __exit__(self, *exc: Any) -> None:
        if self._progress is not None:
            self._progress.stop()
            self._progress = None

    def update(
        self,
        *,
        completed: int | None = None,
        total: int | None = None,
        advance: int | None = None,
        description: str | None = None,
        info: str | None = None,
        line: str | None = None,
    ) -> None:
        """Move the bar; change its label (``description``) or text (``info``); log ``line`` (``log=True``)."""
        if self._progress is not None:
            fields = {} if info is None else {"info": info}
            self._progress.update(
                self._task, total=total, completed=completed, advance=advance, description=description, **fields
            )
        elif self.log and line is not None:
            sys.stderr.write(line + "\n")
            sys.stderr.flush()


def _RateColumn(unit: str) -> Any:  # noqa: N802 - a column factory (rich is imported lazily)
    from rich.progress import ProgressColumn
    from rich.text import Text

    class RateColumn(ProgressColumn):
        """``<x.xx> <unit>/s`` (``--`` before the first step)."""

        def render(self, task: Any) -> Text:
            speed = task.finished_speed or task.speed
            return Text(f"-- {unit}/s" if speed is None else f"{speed:.2f} {unit}/s", style="cyan")

    return RateColumn()
