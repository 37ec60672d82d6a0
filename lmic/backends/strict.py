"""Deprecated alias of :mod:`lmic.reductions.strict` (the strict reductions left ``backends/``).

>>> from lmic.backends.strict import plan
>>> plan.__module__
'lmic.reductions.strict'
"""

from lmic.reductions.strict import *  # noqa: F403
from lmic.reductions.strict import (  # noqa: F401 - private names some callers used
    _choose,
    _decided,
    _fixed_margin,
    _max_margin,
    _restrict,
    _shift,
)
