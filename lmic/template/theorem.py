"""Theorem objects: metadata plus a ``build(t)`` function that declares the template.

Examples
--------
>>> from lmic.template import theorem, block
>>> @theorem(id="demo.lyap", title="Lyapunov", citation="Lyapunov (1892)")
... def demo(t):
...     n, = t.dims("n")
...     A = t.data("A", n, n)
...     P = t.symmetric("P", n)
...     t.lmi("stability", block(A.T * P + P * A) < 0)
...     t.lmi("P > 0", block(P) > 0)
>>> demo.id, demo.template().variables[0].name
('demo.lyap', 'P')
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from lmic.errors import LmicError, TemplateError
from lmic.template.builder import Template

__all__ = ["Theorem", "theorem"]

KINDS = {"S": "synthesis", "A": "analysis"}


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
    kind : {"S", "A"}
        Synthesis (gains computed) or analysis (gains given as data).
    objective : str
        One line describing the objective / output.
    system_class : str
    notes : str
        Typo resolutions, caveats (shown by ``lmic show``).
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

    def __post_init__(self) -> None:
        if not isinstance(self.id, str) or "." not in self.id:
            raise TemplateError(f"theorem id {self.id!r} must look like '<family>.<item>'")
        if self.kind not in KINDS:
            raise TemplateError(f"theorem {self.id}: kind must be 'S' or 'A'")
        if not callable(self.build):
            raise TemplateError(f"theorem {self.id}: build is not callable")

    def template(self, options: Mapping[str, Any] | None = None) -> Template:
        """Run ``build`` and return the declarations (structural options from ``options``)."""
        t = Template(self.id, options)
        try:
            self.build(t)
        except LmicError:
            raise
        except Exception as err:  # a plugin bug: name the theorem, keep one line
            raise TemplateError(f"theorem {self.id}: template failed to build: {type(err).__name__}: {err}") from err
        return t

    def latex(self, options: Mapping[str, Any] | None = None) -> str:
        """The LMIs as LaTeX (see :func:`lmic.template.render.latex`)."""
        from lmic.template.render import theorem_latex

        return theorem_latex(self, self.template(options))

    def _repr_html_(self) -> str:
        from lmic.display import theorem_html

        return theorem_html(self)

    def _repr_latex_(self) -> str:
        from lmic.display import theorem_latex_block

        return theorem_latex_block(self)

    @property
    def doc(self) -> str:
        """The build function's docstring (source, result and references)."""
        return (self.build.__doc__ or "").strip()


def theorem(**meta: Any) -> Callable[[Callable[[Template], None]], Theorem]:
    """Decorator turning a ``build(t)`` function into a :class:`Theorem`.

    Keyword arguments are the :class:`Theorem` fields other than ``build``.
    """

    def wrap(fn: Callable[[Template], None]) -> Theorem:
        return Theorem(build=fn, **meta)

    return wrap
