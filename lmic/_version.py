"""The version of lmic, in the lowest layer so that any module may record it without importing the package root.

Examples
--------
>>> from lmic._version import __version__
>>> isinstance(__version__, str)
True
"""

__version__ = "0.1.0"
