"""Theorem plugins of the descriptor family (being written)."""

THEOREMS: list = []
