"""lmic's built-in theorem plugins: observer and filter LMIs from the source papers.

One module per paper family; each registers through the ``lmic.theorems`` entry-point group
exactly like a third-party plugin.
"""
