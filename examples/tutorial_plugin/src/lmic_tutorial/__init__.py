"""The lmic tutorial plugin (see docs/writing-a-theorem.md in the lmic repository).

The entry point ``tutorial = "lmic_tutorial"`` registers :data:`THEOREMS`.
"""

from lmic_tutorial.bounded_real import bounded_real
from lmic_tutorial.observer import observer

THEOREMS = [bounded_real, observer]
