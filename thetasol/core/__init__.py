"""Numeric core: SO(3) and attitude kernels, double-double arithmetic, input validation, Fourier
series of one angle (``periodic``) and vectorized scalar root finders (``roots``).

The lowest layer: plain numeric functions on numpy arrays, no physics and no objects of the
upper layers.  Every other subpackage may import it; it imports none of them.
"""
