"""Theorem plugins of the delay_a family (being written)."""

THEOREMS: list = []
