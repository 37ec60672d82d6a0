"""Theorem plugins of the uir family (being written)."""

THEOREMS: list = []
