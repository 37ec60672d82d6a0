"""The ``lmic`` command line.

Every sub-command lives in its own module under :mod:`lmic.commands`, exposing
``register(subparsers)`` (which adds its parser and sets ``func``) and a ``run(args) -> int``.
Exit codes (DESIGN section 7): 0 certified, 3 infeasible, 1 rejected / inaccurate / failed
solve, 2 bad usage or bad input (one line on stderr, no traceback).

Examples
--------
>>> main(["--version"])  # doctest: +SKIP
lmic 0.1.0
"""

from __future__ import annotations

import argparse
import importlib
import sys
import traceback
from collections.abc import Sequence
from typing import Any

from lmic import __version__
from lmic.errors import LmicError

__all__ = ["main", "COMMANDS", "EXIT_OK", "EXIT_FAILED", "EXIT_USAGE", "EXIT_INFEASIBLE", "EXIT_INTERRUPTED"]

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_USAGE = 2
EXIT_INFEASIBLE = 3
#: Ctrl-C (128 + SIGINT, the shell convention)
EXIT_INTERRUPTED = 130

#: sub-command modules, in the order ``lmic --help`` lists them
COMMANDS = [
    "theorems",
    "backends",
    "show",
    "check",
    "compile",
    "solve",
    "crosscheck",
    "audit",
    "audit_published",
    "reproduce",
    "batch",
    "simulate",
    "report",
]


#: one or two examples per command, shown at the end of ``lmic COMMAND --help`` (a command
#: that sets its own epilog keeps it)
EXAMPLES = {
    "theorems": ["lmic theorems", "lmic theorems --json"],
    "backends": ["lmic backends", "lmic backends --json"],
    "show": ["lmic show qib.thm1", "lmic show qib.thm1 -p fixed_L=1 --latex"],
    "check": ["lmic check qib.thm1", "lmic check my_theorems.py --strict"],
    "compile": ["lmic compile qib.thm1 examples/qib.thm1.flexible-joint.yaml -o qib.json"],
    "solve": [
        "lmic solve qib.thm1 examples/qib.thm1.flexible-joint.yaml -o cert.json",
        "lmic solve thesis.thm3_2_2 examples/thesis.thm3_2_2.ex3_2_2.yaml --maximize gamma",
    ],
    "crosscheck": [
        "lmic crosscheck qib.thm1 examples/qib.thm1.flexible-joint.yaml",
        "lmic crosscheck control1.dat-s --backends clarabel,scs,cvxopt --executor local --workers 2",
        "lmic crosscheck qib.thm1 examples/qib.thm1.flexible-joint.yaml --executor dask",
    ],
    "audit": ["lmic audit cert.json", "lmic audit cert.json --exact"],
    "audit-published": ["lmic audit-published qib.thm1 examples/qib.thm1.flexible-joint.yaml"],
    "reproduce": ["lmic reproduce --only 'qib.*'"],
    "simulate": ["lmic simulate qib.thm1 examples/qib.thm1.flexible-joint.yaml -o sim.png"],
    "report": ["lmic report qib.thm1 examples/qib.thm1.flexible-joint.yaml -o report.html"],
    "batch": [
        "lmic batch examples/studies/qib_monte_carlo.yaml -o runs/qib-mc",
        "lmic batch examples/studies/obs_control_map.yaml -o runs/map --executor dask",
        "lmic batch --status runs/qib-mc",
    ],
}


def _add_examples(sub: argparse._SubParsersAction) -> None:
    for name, parser in sub.choices.items():
        if parser.epilog or name not in EXAMPLES:
            continue
        parser.epilog = "examples:\n" + "\n".join(f"  {line}" for line in EXAMPLES[name])
        parser.formatter_class = argparse.RawDescriptionHelpFormatter


class _Parser(argparse.ArgumentParser):
    """argparse that reports usage errors as one line and exit code 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        sys.stderr.write(f"lmic: error: {message}\n")
        raise SystemExit(EXIT_USAGE)


def _wanted(argv: Sequence[str]) -> list[str] | None:
    """The one command module ``argv`` runs (its first word names it), ``[]`` for a bare
    ``--version``, or ``None`` (help, no command, an unknown word: every command is needed)."""
    if list(argv) == ["--version"]:
        return []
    first = next((a for a in argv if not a.startswith("-")), None)
    if first is None or any(a in ("-h", "--help") for a in argv[: argv.index(first)]):
        return None
    module = first.replace("-", "_")
    return [module] if module in COMMANDS else None


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The argument parser: every available sub-command, or (``argv`` given) only the one
    ``argv`` runs, so that a one-shot process imports no other command's module.

    >>> sorted(build_parser(["backends"])._subparsers._group_actions[0].choices)
    ['backends']
    """
    only = None if argv is None else _wanted(argv)
    if only:
        parser, sub = _build(only)
        if {only[0], only[0].replace("_", "-")} & set(sub.choices):
            return parser
        only = None  # the module registers another name: build them all
    return _build(COMMANDS if only is None else only)[0]


def _build(names: Sequence[str]) -> tuple[argparse.ArgumentParser, argparse._SubParsersAction]:
    parser = _Parser(prog="lmic", description="Compile, solve and certify linear matrix inequalities.")
    parser.add_argument("--version", action="version", version=f"lmic {__version__}")
    parser.add_argument("--debug", action="store_true", help="show the traceback of an error (any command)")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name in names:
        try:
            module = importlib.import_module(f"lmic.commands.{name}")
        except ModuleNotFoundError as err:
            if err.name == f"lmic.commands.{name}":
                continue  # command not built yet
            raise
        module.register(sub)
    _add_examples(sub)
    return parser, sub


def _notes_as_lines() -> None:
    """Show lmic's notes (e.g. unused data keys) as ``lmic: note: ...`` lines on stderr."""
    import warnings

    default = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):  # noqa: ANN001
        # lmic.system (numpy, sympy) is not imported for this: a note can only have been issued
        # once it is loaded
        system = sys.modules.get("lmic.system")
        if system is not None and issubclass(category, system.Note):
            sys.stderr.write(f"lmic: note: {message}\n")
        else:
            default(message, category, filename, lineno, file, line)

    if getattr(warnings.showwarning, "__name__", "") != "show":
        warnings.showwarning = show


#: numpy's lazily imported submodules that SciPy's array-API shim imports only to copy them into its
#: own namespace (``scipy._lib.array_api_compat.numpy`` runs ``from numpy import *`` and
#: ``getattr(numpy, name)`` for every name of ``dir(numpy)``): ``numpy.f2py`` (and through it
#: ``charset_normalizer``), ``numpy.testing`` (``unittest``, ``importlib.metadata``) and
#: ``numpy.ma``. No lmic code path uses them; SciPy's namespace reads them only for CuPy and
#: PyTorch arrays. Measured: 60-120 ms of every ``lmic solve`` process (``python -X importtime``).
_UNUSED_NUMPY_SUBMODULES = frozenset({"f2py", "testing", "ma"})
_SHIM = "scipy._lib.array_api_compat.numpy"


class _LeanNumpyNames:
    """While a command runs: the first import of SciPy's array-API shim sees ``numpy.__all__``
    and ``dir(numpy)`` without :data:`_UNUSED_NUMPY_SUBMODULES`, so it does not import them.
    Nothing else changes: ``numpy.f2py`` etc. still import on first use, and both names lists
    are whole again when the command returns.

    >>> with _LeanNumpyNames():
    ...     pass
    """

    def __enter__(self) -> _LeanNumpyNames:
        self._saved: tuple[Any, Any, Any] | None = None
        if _SHIM not in sys.modules:
            sys.meta_path.insert(0, self)
        return self

    def find_spec(self, name: str, path: Any = None, target: Any = None) -> None:
        """Before the shim is imported (numpy is by then): hide the unused names."""
        if name == _SHIM and self._saved is None:
            numpy: Any = sys.modules.get("numpy")
            full_dir, full_all = getattr(numpy, "__dir__", None), getattr(numpy, "__all__", None)
            if numpy is not None and callable(full_dir) and isinstance(full_all, list):
                self._saved = (numpy, full_dir, full_all)
                numpy.__all__ = [n for n in full_all if n not in _UNUSED_NUMPY_SUBMODULES]
                numpy.__dir__ = lambda: [n for n in full_dir() if n not in _UNUSED_NUMPY_SUBMODULES]
        return None  # the ordinary finders import it

    def __exit__(self, *exc: object) -> None:
        if self in sys.meta_path:
            sys.meta_path.remove(self)
        if self._saved is not None:
            numpy, full_dir, full_all = self._saved
            numpy.__dir__, numpy.__all__ = full_dir, full_all  # the module's own functions and list


class OutputLost(OSError):
    """Standard output could not be written (a full disk, a lost terminal): the command's answer
    did not reach the user, which :func:`main` reports as a failure (exit 1), never as a crash."""


class _ClosedPipeSafeStdout:
    """Standard output that a closed pipe cannot break (``lmic solve ... | head -1``).

    When the reader has gone, the rest of the output is discarded (the stream's descriptor is
    pointed at ``os.devnull``, the recipe of Python's ``signal`` documentation) and the command
    finishes as it would have: its exit code is still its verdict's. Any other write error is
    :class:`OutputLost`. Everything else is the wrapped stream's.

    >>> import io
    >>> out = _ClosedPipeSafeStdout(io.StringIO())
    >>> out.write("certified"), out.closed_pipe
    (9, False)
    """

    def __init__(self, stream: Any) -> None:
        self._stream = stream
        self.closed_pipe = False

    def write(self, text: str) -> int:
        if not self.closed_pipe:
            self._guarded(self._stream.write, text)
        return len(text)

    def flush(self) -> None:
        if not self.closed_pipe:
            self._guarded(self._stream.flush)

    def _guarded(self, op: Any, *args: Any) -> None:
        try:
            op(*args)
        except BrokenPipeError:
            self._discard_the_rest()
        except OSError as err:
            raise OutputLost(err.errno, f"cannot write the output: {err.strerror or err}") from None

    def _discard_the_rest(self) -> None:
        import os

        self.closed_pipe = True
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, self._stream.fileno())  # the buffered rest then flushes into it
            os.close(devnull)
        except (OSError, ValueError, AttributeError):  # no real descriptor (a captured stream)
            pass

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit code.

    Examples
    --------
    >>> main(["--version"])  # doctest: +SKIP
    lmic 0.1.0
    0
    """
    stdout = sys.stdout
    safe = _ClosedPipeSafeStdout(stdout) if stdout is not None else None
    if safe is not None:
        sys.stdout = safe
    try:
        with _LeanNumpyNames():
            return _main(argv)
    finally:
        if safe is not None and sys.stdout is safe:
            try:
                safe.flush()
            except OutputLost:
                pass  # already reported, or the answer was written and only the last flush failed
            sys.stdout = stdout


def _main(argv: Sequence[str] | None = None) -> int:
    _notes_as_lines()
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in argv  # accepted anywhere: lmic --debug solve ..., lmic solve ... --debug
    argv = [a for a in argv if a != "--debug"]
    try:
        parser = build_parser(argv)
        args = parser.parse_args(argv)
        args.debug = debug
        if not getattr(args, "func", None):
            parser.print_help()
            return EXIT_USAGE
        return int(args.func(args))
    except LmicError as err:
        if debug:
            traceback.print_exception(err)
        msg = " ".join(str(err).split())
        sys.stderr.write(f"lmic: error: {msg}\n")
        return EXIT_USAGE
    except OutputLost as err:
        sys.stderr.write(f"lmic: error: {err.strerror}\n")
        return EXIT_FAILED
    except Exception as err:  # a bug (lmic's or a plugin's): one line; the traceback with --debug
        if debug:
            traceback.print_exception(err)
        msg = " ".join(str(err).split())
        sys.stderr.write(
            f"lmic: internal error: {type(err).__name__}: {msg}"
            + ("" if debug else " (run with --debug for the traceback)")
            + "\n"
        )
        return EXIT_FAILED
    except KeyboardInterrupt:
        sys.stderr.write("lmic: interrupted\n")
        return EXIT_INTERRUPTED  # lmic.outcome.EXIT_CODES["interrupted"]


#: commands after which the process ends without the interpreter's teardown (:func:`exit_now`)
QUICK_EXIT_COMMANDS = frozenset({"solve", "theorems", "backends", "show", "--version"})


def exit_now(code: int) -> None:
    """End a one-shot process as the interpreter would, minus the teardown of every module.

    Python's exit waits for non-daemon threads, runs the ``atexit`` handlers (``weakref.finalize``
    and ``multiprocessing`` included), flushes the standard streams, then frees every module:
    with numpy and SciPy loaded that last step alone is ~0.1 s (a third of ``python -c "import
    numpy, scipy.sparse"``). Here the first three run and the process ends (``os._exit``).
    Anything unusual -- a non-daemon thread still running, an ``atexit`` handler or a flush that
    fails (a closed pipe) -- takes the ordinary ``SystemExit`` path, so the exit code and the
    messages are exactly the ordinary ones.

    >>> exit_now(0)
    Traceback (most recent call last):
    ...
    SystemExit: 0
    """
    import atexit
    import os
    import threading

    quick = os.environ.get("LMIC_QUICK_EXIT", "1") != "0" and "pytest" not in sys.modules  # tests keep running
    if not quick or threading.active_count() > 1 or threading.current_thread() is not threading.main_thread():
        raise SystemExit(code)
    try:
        atexit._run_exitfuncs()
        for stream in (sys.stdout, sys.stderr):
            if stream is not None:
                stream.flush()
    except BaseException:  # noqa: BLE001 - the ordinary exit reports it as it always did
        raise SystemExit(code) from None
    os._exit(code)


#: BLAS thread counts a one-shot ``lmic`` process sets when the environment does not (see
#: :func:`single_threaded_blas`)
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def single_threaded_blas(environ: Any = None) -> list[str]:
    """Ask for single-threaded BLAS, for every variable of :data:`BLAS_THREAD_VARIABLES` the
    environment leaves unset; return the ones set.

    The ``lmic`` command calls it before numpy is imported (BLAS reads them once, at load). Every
    measurement in docs/ runs this way: multi-threaded BLAS sums in another order, so an
    enclosure at the edge of its target moves with the thread count (uir.thm4_1, 12 states,
    seed 1, Clarabel: relative gap 4.8e-7 single-threaded, 1.1e-6 with two threads), its
    spinning worker threads spend the processor-time budgets of the route, and on a busy
    machine they slow the many small dense solves of the proofs ten-fold. A variable the user
    sets (e.g. ``OPENBLAS_NUM_THREADS=2``) is kept; subprocesses (batch workers) inherit them.

    >>> env = {"OMP_NUM_THREADS": "4"}
    >>> single_threaded_blas(env), env["OMP_NUM_THREADS"], env["OPENBLAS_NUM_THREADS"]
    (['OPENBLAS_NUM_THREADS', 'MKL_NUM_THREADS'], '4', '1')
    """
    import os

    env = os.environ if environ is None else environ
    chosen = [v for v in BLAS_THREAD_VARIABLES if v not in env]
    for var in chosen:
        env[var] = "1"
    return chosen


def _entry() -> None:
    argv = sys.argv[1:]
    if "numpy" not in sys.modules:  # the console script: nothing has loaded BLAS yet
        single_threaded_blas()
    try:
        code = main()
    except SystemExit as done:  # argparse: --version, --help, a usage error
        if done.code is not None and not isinstance(done.code, int):
            raise
        code = done.code or 0
    first = next((a for a in argv if a.startswith("--version") or not a.startswith("-")), None)
    if first in QUICK_EXIT_COMMANDS and "--debug" not in argv:
        exit_now(code)
    raise SystemExit(code)


if __name__ == "__main__":
    _entry()
