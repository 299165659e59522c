"""The data-driven model: a linear basis of mapped, tabulated BRDFs learned from a library of measurements.

Matusik, Pfister, Brand and McMillan ("A data-driven reflectance model", SIGGRAPH 2003) reduced a library of
dense MERL tables by principal components; Nielsen, Jensen and Ramamoorthi ("On optimal, minimal BRDF sampling
for reflectance acquisition", SIGGRAPH Asia 2015) made it practical: map each table so that every bin weighs
alike, keep a few components, and fit a new material's coefficients from a handful of measured directions,
chosen to condition that fit. One idea per module:

* ``tabulation.py``: where a direction pair falls in the table (MERL's Rusinkiewicz bins, ``physics/merl_table.py``)
  and the trilinear weights that interpolate it;
* ``mapping.py``: the maps between BRDF values and the space the basis is linear in;
* ``basis.py``: the basis file (``.npz``) and the basis evaluated at direction pairs;
* ``directions.py``: the direction pairs that best condition a fit (Nielsen's greedy selection), and their file;
* ``model.py``: the ``pca`` model, whose parameters are the coefficients;
* ``build.py``: a basis learned from a library of MERL files (streamed, bounded memory);
* ``fit.py``: the coefficients fitted to samples (a ridge start, then Levenberg-Marquardt with the ridge prior).

The one folder that spans layers: each module sits in the layer of what it does (``tests/test_layout.py``): the
basis and the model with the physics, ``build.py`` with the data, ``fit.py`` with the fitting.
"""
