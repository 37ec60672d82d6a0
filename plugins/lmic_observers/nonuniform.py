"""Theorem plugins of the nonuniform family (being written)."""

THEOREMS: list = []
