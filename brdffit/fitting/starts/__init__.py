"""Where a fit starts: variable projection over a grid of lobe shapes, every dataset of a batch in one program
(``grid.py``), and models of several lobes placed and fitted one lobe at a time (``lobes.py``)."""
