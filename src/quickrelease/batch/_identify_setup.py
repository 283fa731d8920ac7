"""The per-observation setup of the friction identification (Eq. 11-13), written once for every back-end.

:func:`identify_setup` is pure arithmetic on its arguments plus three library calls, ``sin``, ``cos`` and ``sqrt``,
looked up as globals of this module (``math``'s here). The three back-ends of the identification run this one
source:

* the compiled kernel ``_fast._identify_one`` (numba, one case at a time) calls :data:`_fast._identify_setup`,
  this function compiled by ``_fast._jit`` with ``math``'s functions (``_fast`` stamps its cache with this file:
  an edit here recompiles the kernels that inline it);
* the numpy reference ``batch._identify_chunk`` and the GPU back-end ``_gpu._identify_chunk`` (CuPy, or numpy on a
  machine without a GPU) call :func:`for_arrays` ``(xp)``, the same code object with ``sin``, ``cos`` and ``sqrt``
  bound to the array module's ufuncs, so that it works elementwise on arrays.

Each back-end gets the bits it had when it wrote the setup itself (the same operations in the same order, the same
library functions). A Python float in gives Python floats out (a division by zero raises there, where the compiled
and array forms give inf or NaN, as numpy does): that is how tests check it against the paper's formulas in mpmath.
"""

from __future__ import annotations

import math
import types

sin = math.sin
cos = math.cos
sqrt = math.sqrt


def identify_setup(a0, aF, E, k, m2, L1):
    """The per-observation constants of the identification on the line of Eq. 13.

    Parameters
    ----------
    a0, aF : float
        alpha0 and alpha_F, the release and stop angles, 0 < alpha0 < alpha_F < pi/2 [rad].
    E : float
        E_S, the strain energy stored before release (Eq. 2) [J].
    k : float
        The mass ratio c m1 / m2 [-].
    m2 : float
        The head mass [kg].
    L1 : float
        The bar length [m].

    Returns
    -------
    sA, cA : float
        sin alpha_F, cos alpha_F [-].
    sm : float
        sigma_m = sin((alpha_F - alpha0) / 2) [-].
    c1, c2 : float
        cos and sin of (alpha_F + alpha0) / 2, written from those of alpha_F and of the half sweep (the normalisers
        of the remaining energies: sin alpha_F - sin alpha0 = 2 c1 sigma_m, cos alpha0 - cos alpha_F = 2 c2 sigma_m)
        [-].
    F1max, F2max : float
        F1* = E_S / (2 L1 (sin alpha_F - sin alpha0)) (Eq. 11) and F2* = E_S / (4 L1 (cos alpha0 - cos alpha_F))
        (Eq. 12), by sum to product [N].
    ratio : float
        cos alpha_F / c1, the remaining energy of pure hinge friction at the stop (the tier ratio that vanishes as
        alpha_F -> pi/2) [-].
    msq : float
        (k + sin^2 alpha0) / (alpha_F - alpha0)^2, the mass factor at the start over the squared sweep (the tier
        ratio of a small mass factor near the start) [-].
    pref : float
        4 sigma_m L1 sqrt(m2 / E_S), the prefactor of the node sums: t_F = pref x sum [s].
    """
    sA = sin(aF)
    cA = cos(aF)
    half = 0.5 * (aF - a0)
    sm = sin(half)
    ch = cos(half)
    # cos and sin of (aF + a0)/2 = aF - half
    c1 = cA * ch + sA * sm
    c2 = sA * ch - cA * sm
    F1max = E / (4.0 * L1 * c1 * sm)  # Eq. 11: E_S / (2 L1 (sin aF - sin a0))
    F2max = E / (8.0 * L1 * c2 * sm)  # Eq. 12: E_S / (4 L1 (cos a0 - cos aF))
    # the tiers' ratios (as for the stop-time kernel): the pure-hinge remaining energy at the stop, which vanishes
    # as aF -> pi/2, and the mass factor at the start over the squared sweep
    ratio = cA / c1
    sa0 = sin(a0)
    msq = (k + sa0 * sa0) / (aF - a0) ** 2
    pref = 4.0 * sm * L1 * sqrt(m2 / E)
    return sA, cA, sm, c1, c2, F1max, F2max, ratio, msq, pref


def for_arrays(xp):
    """:func:`identify_setup` elementwise on ``xp`` arrays (numpy or CuPy): the same code, its ``sin``, ``cos`` and
    ``sqrt`` bound to ``xp``'s (any object with those three functions: a module, or a test's stand-in for one)."""
    fn = identify_setup
    env = {**fn.__globals__, "sin": xp.sin, "cos": xp.cos, "sqrt": xp.sqrt}
    return types.FunctionType(fn.__code__, env, fn.__name__, fn.__defaults__)
