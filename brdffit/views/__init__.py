"""What a person looks at: figures of fits (``plots.py`` gathers them: slices, polar plots, residual maps, lit
spheres, the corner plot) and the self-contained HTML report (``report.py``). Imports every layer below it, never
the command line."""
