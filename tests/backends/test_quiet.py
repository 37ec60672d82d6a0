"""quiet_native (lmic/backends/quiet.py) silences what native code writes to fds 1 and 2."""

from __future__ import annotations

import os

from lmic.backends.quiet import quiet_native


def test_native_writes_are_silenced_and_the_descriptors_restored(capfd):
    with quiet_native():
        os.write(1, b"native stdout\n")
        os.write(2, b"native stderr\n")
    os.write(1, b"after\n")
    with quiet_native(active=False):
        os.write(1, b"shown\n")
    out, err = capfd.readouterr()
    assert out == "after\nshown\n" and err == ""
