"""Fitted models in the forms renderers read (``merl.py``: a MERL table). Imports every layer below it."""
