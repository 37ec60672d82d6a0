r"""LaTeX: numbers, matrices, a theorem's LMIs and a result's derived values.

Examples
--------
>>> number_latex(-3e12)
'-3 \\cdot 10^{12}'
>>> from lmic.registry import get_theorem
>>> "\\prec 0" in lmi_latex(get_theorem("thesis.lyapunov").template().lmis[1])
True
"""

from __future__ import annotations

from lmic.formatting import matrix_latex, number_latex, result_latex
from lmic.template.render import lmi_latex, theorem_latex, theorem_latex_block

__all__ = ["number_latex", "matrix_latex", "lmi_latex", "theorem_latex", "theorem_latex_block", "result_latex"]
