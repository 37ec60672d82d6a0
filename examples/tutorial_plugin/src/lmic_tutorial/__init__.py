"""The lmic tutorial plugin (see docs/writing-a-theorem.md in the lmic repository)."""
