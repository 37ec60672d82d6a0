"""Theorem objects: metadata plus a ``build(t)`` function that declares the template.

Examples
--------
>>> from lmic.template import theorem
>>> @theorem(id="demo.lyap", title="Lyapunov", citation="Lyapunov (1892)", kind="analysis")
... def demo(t):
...     n, = t.dims("n")
...     A = t.data("A", n, n)
...     P = t.symmetric("P", n, pd=True)
...     t.lmi("stability", A.T * P + P * A < 0)
>>> demo.id, demo.kind, demo.template().variables[0].name
('demo.lyap', 'A', 'P')
"""

from __future__ import annotations

import contextlib
import os
import sys
import traceback
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from lmic.errors import LmicError, TemplateError
from lmic.template.builder import Template

__all__ = ["Theorem", "theorem", "Provider", "KINDS"]

#: kind letters and the words that may be written instead
KINDS = {"S": "synthesis", "A": "analysis"}
_KIND_WORDS = {v: k for k, v in KINDS.items()}


@dataclass(frozen=True)
class Provider:
    """Who supplies a theorem: the installed distribution, its version and the entry point.

    A theorem registered from Python (a notebook) has no distribution: ``entry_point`` is empty
    and ``module`` names where it was defined.

    >>> Provider("lmic", "0.1.0", "qib = lmic_observers.qib").describe()
    'lmic 0.1.0 (entry point qib = lmic_observers.qib)'
    """

    distribution: str
    version: str
    entry_point: str = ""
    module: str = ""

    @classmethod
    def api(cls, thm: Theorem) -> Provider:
        """The provider of a theorem registered from Python."""
        return cls("", "", "", getattr(thm.build, "__module__", "") or "")

    @property
    def is_api(self) -> bool:
        """True for a theorem registered from Python, not installed through an entry point."""
        return not self.entry_point

    def describe(self) -> str:
        """One phrase naming the provider."""
        if self.is_api:
            return f"an inline theorem (module {self.module or '?'})"
        return f"{self.distribution} {self.version} (entry point {self.entry_point})"

    def to_dict(self) -> dict[str, str]:
        """What a certificate records."""
        if self.is_api:
            return {"distribution": None, "version": None, "module": self.module}  # type: ignore[dict-item]
        return {"distribution": self.distribution, "version": self.version, "entry_point": self.entry_point}


def _build_location(err: BaseException, build: Callable[..., Any]) -> str:
    """``file:line`` of the deepest frame of the error inside the theorem's source file."""
    code = getattr(build, "__code__", None)
    home = os.path.abspath(code.co_filename) if code is not None else None
    frames = traceback.extract_tb(err.__traceback__)
    mine = [f for f in frames if home and os.path.abspath(f.filename) == home]
    if not mine and code is not None and len(frames) <= 1:  # build itself could not be called
        return f"{os.path.basename(code.co_filename)}:{code.co_firstlineno}"
    frame = mine[-1] if mine else (frames[-1] if frames else None)
    if frame is None:
        return ""
    return f"{os.path.basename(frame.filename)}:{frame.lineno}"


def _hint(err: BaseException) -> str:
    text = str(err)
    if "cannot be interpreted as an integer" in text:
        return " (numpy cannot size arrays by a dimension symbol: use I(n), 0 or data inside blocks, not numpy)"
    if isinstance(err, AttributeError) and "has no attribute 'trace'" in text:
        return " (write trace(Z), with trace from lmic.template)"
    if isinstance(err, TypeError) and "Mix of Matrix and Scalar symbols" in text:
        return " (a matrix plus or minus a scalar: write gamma * I(m), or put the scalar alone as a diagonal block)"
    if isinstance(err, TypeError) and "Invalid comparison of non-real" in text:
        return " (compare a matrix with 0: write M < 0, or block([[...]]) < 0)"
    return ""


@dataclass
class Theorem:
    """A registered theorem.

    Parameters
    ----------
    id : str
        ``<family>.<item>``, e.g. ``qib.thm1``.
    title, citation : str
    build : callable
        ``build(t: Template) -> None``.
    kind : {"synthesis", "analysis"} (or "S", "A")
        Synthesis (gains computed) or analysis (gains given as data); stored as ``"S"``/``"A"``.
    objective : str
        One line describing the objective / output.
    system_class : str
    notes : str
        Typo resolutions, caveats (shown by ``lmic show``).

    Examples
    --------
    >>> Theorem("a.b", "t", "c", lambda t: None, kind="synthesis").kind_word
    'synthesis'
    """

    id: str
    title: str
    citation: str
    build: Callable[[Template], None]
    kind: str = "S"
    objective: str = "feasibility"
    system_class: str = ""
    notes: str = ""
    plugin: str = ""
    provider: Provider | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.id, str) or "." not in self.id:
            raise TemplateError(f"theorem id {self.id!r} must look like '<family>.<item>'")
        for name in ("title", "citation", "objective", "system_class", "notes"):
            value = getattr(self, name)
            if not isinstance(value, str):
                raise TemplateError(f"theorem {self.id}: {name} must be a string, not {type(value).__name__}")
            if name in ("title", "citation") and not value.strip():
                raise TemplateError(
                    f"theorem {self.id}: {name} is empty (say what the theorem is and where it is from)"
                )
        self.kind = _KIND_WORDS.get(self.kind, self.kind)
        if self.kind not in KINDS:
            raise TemplateError(f"theorem {self.id}: kind must be 'synthesis' or 'analysis' (or 'S', 'A')")
        if not callable(self.build):
            raise TemplateError(f"theorem {self.id}: build is not callable")

    @property
    def kind_word(self) -> str:
        """``synthesis`` or ``analysis``."""
        return KINDS[self.kind]

    def template(self, options: Mapping[str, Any] | None = None) -> Template:
        """Run ``build`` and return the declarations (structural options from ``options``).

        A Python error inside ``build`` becomes one :class:`TemplateError` line naming the
        theorem and the file and line of the plugin where it happened (``--debug`` shows the
        traceback: the original error is chained). What ``build`` prints goes to standard error
        (standard output is lmic's: tables, ``--json``).
        """
        t = Template(self.id, options)
        try:
            with contextlib.redirect_stdout(sys.stderr):  # a plugin's print never mixes into lmic's output
                self.build(t)
        except LmicError as err:
            if self.id in str(err):
                raise
            where = _build_location(err, self.build)
            at = f" at {where}" if where else ""
            raise type(err)(f"theorem {self.id}{at}: {err}") from err
        except KeyboardInterrupt:
            raise
        except Exception as err:  # a plugin bug: name the theorem, file and line; keep one line
            where = _build_location(err, self.build)
            at = f" at {where}" if where else ""
            msg = " ".join(str(err).split())
            raise TemplateError(
                f"theorem {self.id}: template failed to build{at}: {type(err).__name__}: {msg}{_hint(err)}"
            ) from err
        t.finish()
        return t

    def latex(self, options: Mapping[str, Any] | None = None) -> str:
        """The LMIs as LaTeX (see :func:`lmic.template.render.latex`)."""
        from lmic.template.render import theorem_latex

        return theorem_latex(self, self.template(options))

    def _repr_html_(self) -> str:
        from lmic.template.render import theorem_html

        return theorem_html(self)

    def _repr_latex_(self) -> str:
        from lmic.template.render import theorem_latex_block

        return theorem_latex_block(self)

    @property
    def doc(self) -> str:
        """The build function's docstring (source, result and references)."""
        return (self.build.__doc__ or "").strip()


def theorem(**meta: Any) -> Callable[[Callable[[Template], None]], Theorem]:
    """Decorator turning a ``build(t)`` function into a :class:`Theorem`.

    Keyword arguments are the :class:`Theorem` fields other than ``build``.

    >>> @theorem(id="demo.x", title="t", citation="c")
    ... def demo(t):
    ...     pass
    >>> demo.kind_word
    'synthesis'
    """

    def wrap(fn: Callable[[Template], None]) -> Theorem:
        if isinstance(fn, Theorem):
            raise TemplateError(f"theorem {meta.get('id')}: @theorem is applied twice")
        return Theorem(build=fn, **meta)

    return wrap
