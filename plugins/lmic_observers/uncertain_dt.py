"""Theorem plugins of the uncertain_dt family (being written)."""

THEOREMS: list = []
