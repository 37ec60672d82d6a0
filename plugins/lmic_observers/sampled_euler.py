"""Theorem plugins of the sampled_euler family (being written)."""

THEOREMS: list = []
