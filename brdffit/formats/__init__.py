"""Readers and writers of measurement formats beyond the CSV samples file (SPEC section 4)."""
