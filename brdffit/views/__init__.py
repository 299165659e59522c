"""Figures of fits and their uncertainty (``corner.py``). Imports every layer below it, never the command line."""
