"""Theorem plugins of the uio_dt family (being written)."""

THEOREMS: list = []
