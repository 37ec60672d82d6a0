"""Theorem plugins of the delay_b family (being written)."""

THEOREMS: list = []
