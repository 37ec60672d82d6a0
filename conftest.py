"""Test-session settings shared by every test folder (tests/, doctests in lmic/ and plugins/).

lmic's on-disk cache (:mod:`lmic.cache`) goes to a temporary folder for the session, so that
tests never read or write the user's real cache folder (subprocesses inherit the variable).
"""

from __future__ import annotations

import os
import shutil
import tempfile

_SESSION_CACHE = tempfile.mkdtemp(prefix="lmic-test-cache-")
os.environ["LMIC_CACHE_DIR"] = _SESSION_CACHE
os.environ.pop("LMIC_NO_CACHE", None)


def pytest_unconfigure(config: object) -> None:
    shutil.rmtree(_SESSION_CACHE, ignore_errors=True)
