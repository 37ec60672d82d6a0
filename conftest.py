"""Test-session settings shared by every test folder (tests/, doctests in lmic/ and plugins/).

lmic's on-disk cache (:mod:`lmic.cache`) goes to a temporary folder for the session, so that
tests never read or write the user's real cache folder (subprocesses inherit the variable).

BLAS runs single-threaded (unless the environment says otherwise), as every benchmark and
measurement in docs/ does: multi-threaded BLAS sums in another order, and an enclosure at the
edge of its 1e-6 target moves with it (uir.thm4_1 at 12 states, seed 1, Clarabel: relative gap
4.8e-7 single-threaded, 1.1e-6 with two BLAS threads); its worker threads also spend the
enclosure's processor-time budget. This file is read before any test imports numpy.
"""

from __future__ import annotations

import os
import shutil
import tempfile

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

_SESSION_CACHE = tempfile.mkdtemp(prefix="lmic-test-cache-")
os.environ["LMIC_CACHE_DIR"] = _SESSION_CACHE
os.environ.pop("LMIC_NO_CACHE", None)


def pytest_unconfigure(config: object) -> None:
    shutil.rmtree(_SESSION_CACHE, ignore_errors=True)
