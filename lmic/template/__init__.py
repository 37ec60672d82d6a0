"""The authoring layer: theorems as sympy block-matrix templates.

Examples
--------
>>> from lmic.template import theorem, block, STAR, I, schur_stable
>>> @theorem(id="demo.obs", title="DT observer", citation="textbook")
... def demo(t):
...     n, p = t.dims("n p")
...     A, C = t.data("A", n, n), t.data("C", p, n)
...     P, G = t.symmetric("P", n), t.full("G", n, p)
...     t.lmi("stability", block([[-P, A.T * P - C.T * G.T], [STAR, -P]]) < 0)
...     L = t.derive("L", P.inv() * G)
...     t.check("A - L C Schur stable", schur_stable(A - L * C))
>>> demo.template().derived[0].name
'L'
"""

from lmic.template.blocks import STAR, Block, I, LmiSpec, block
from lmic.template.builder import Template
from lmic.template.checks import (
    CheckSpec,
    finite,
    greater_than,
    hurwitz,
    less_than,
    negative_definite,
    negative_semidefinite,
    positive_definite,
    positive_semidefinite,
    schur_stable,
)
from lmic.template.theorem import Theorem, theorem
from lmic.template.totree import lambda_max, lambda_min, norm2, pinv, spectral_radius, trace

__all__ = [
    "STAR",
    "Block",
    "LmiSpec",
    "I",
    "block",
    "Template",
    "CheckSpec",
    "finite",
    "greater_than",
    "hurwitz",
    "less_than",
    "negative_definite",
    "negative_semidefinite",
    "positive_definite",
    "positive_semidefinite",
    "schur_stable",
    "Theorem",
    "theorem",
    "lambda_max",
    "lambda_min",
    "norm2",
    "pinv",
    "spectral_radius",
    "trace",
]
