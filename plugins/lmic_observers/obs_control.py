"""Theorem plugins of the obs_control family (being written)."""

THEOREMS: list = []
