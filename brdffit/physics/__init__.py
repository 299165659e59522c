"""The physics: directions in the shading frame, Fresnel terms, parameter domains, the reflectance models.

Depends on nothing else in brdffit. ``geometry.py`` also serves host code (readers, ``data_synth``) with
numpy; the models compute in JAX. ``evaluate.py`` is the checked, public way to evaluate a model.
"""
