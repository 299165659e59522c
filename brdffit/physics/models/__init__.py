"""The reflectance models: what a model is (``model.py``: a diffuse term plus lobes of one family, ``lobe.py``), its
parameters in each form (``params.py``, ``dictionary.py``, ``coordinates.py``), one module per family (``lambert``,
``ward``, ``cook_torrance``, ``phong``, ``lafortune``), the shapes fits start from (``grids.py``), and the registry
that names them all (``registry.py``: ``MODELS``, ``get_model``) with their specs (``specs.py``).

Nothing is imported here: the registry also names the data-driven model (``brdffit/datadriven/model.py``), which is
built on ``model.py``, so importing a module of this package must not import the registry.
"""
