"""The fit's defaults, in a module of their own: the command line's help shows them without importing the solver."""

#: Levenberg-Marquardt runs from the best grid starts; the lowest cost wins.
N_STARTS = 3
#: Most solver steps per start.
MAX_STEPS = 256
