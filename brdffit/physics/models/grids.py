"""Starting shapes shared by the lobe families: coarse, log-spaced, spanning real materials.

Ngan et al. 2005 fit roughnesses of 0.005–0.65 and exponents of 1–10⁵ to the
MERL materials; the fit starts from the best few points of these grids (see
``brdffit/fitting/starts/grid.py``), so each grid only needs to land within the basin of
the optimum, a factor of ~2 in roughness.
"""

ROUGHNESS_GRID = (0.005, 0.01, 0.02, 0.04, 0.08, 0.15, 0.3, 0.6)
EXPONENT_GRID = (3.0, 10.0, 30.0, 100.0, 300.0, 1000.0, 3000.0, 10000.0, 30000.0)
#: The renderers' own models (``physics/renderers``): roughness in [0, 1] (``α = roughness²`` from 0.0025 to 0.64, a
#: factor of ~2 in ``α`` apart), metallic values (off the ends of [0, 1], where the solver's logistic map has no slope)
#: and grey colours (glTF's and principled's base colour, roughplastic's diffuse reflectance).
ROUGHNESS_STARTS = (0.05, 0.1, 0.15, 0.22, 0.3, 0.42, 0.6, 0.8)
METALLIC_STARTS = (0.02, 0.5, 0.98)
BASE_COLOR_STARTS = (0.05, 0.25, 0.7)
