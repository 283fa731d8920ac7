"""The compiled integrator of the isolation layer's free vibration where no closed form exists (SI units).

One degree of freedom x(t), the isolation layer, under

    m x_ddot + k x + f_h + d (f_f(s) + f_d(s)) = 0,     s = d x_dot >= 0, d = sign(x_dot) over a piece,

with the hysteretic force ``f_h`` of a Bouc-Wen element (``q z``, ``dy z_dot = x_dot (1 - |z|^n (beta sgn(x_dot
z) + gamma))``, beta = gamma = 1/2) or an elastic-perfectly-plastic element (``z``, ``z_dot = k_p x_dot`` until
``|z|`` reaches ``f_p``), the sliders' friction ``f_f(s) = f_fast - (f_fast - f_slow) exp(-rate s)``
(Constantinou's law; constant where f_fast = f_slow) and the damper's ``f_d(s) = C s^alpha``.

Between events the equation is smooth and is integrated by the 8th-order Dormand-Prince tableau (DOP853's) on a
fixed step ``h`` per piece, a continuous function of the parameters (so that the solution is a smooth function
of them and central differences see no step-size noise). Every event is located on the tableau's own map
``theta -> step(y, theta)`` by a safeguarded Newton iteration to machine precision and the piece restarts there:
the reversals (x_dot = 0: the sliders stick for good where ``|k x + f_h| <= f_slow``, else the motion turns),
the yields of the plastic element, and the Bouc-Wen element's zero crossings of z and its saturations.
The Bouc-Wen element's law is a property of the piece (its ``mode``), never switched inside a step: unloading
(``z x_dot < 0``: ``dy z_dot = x_dot``, linear in x), loading (``dy z_dot = x_dot (1 - |z|^n)``: the transition
to full yield over a displacement ~dy / n, the only stiff part of the motion) and saturated: once ``1 - |z|``
falls below :data:`SATURATION` (``1 - |z|`` decays as ``exp(-n |x - x_0| / dy)`` while loading), z is set to
``sign(x_dot)`` (a change of the force of Qd 1e-13) and held there to the next reversal, on the steps of the
post-yield stiffness. The steps over the transition are sized by the largest velocity the loading piece can
reach before it saturates (not the release's: the force that drives a piece on only falls along it), so a sharp
element (n = 25) of a small dy costs a few hundred steps a half-cycle, not millions. With a power-law damper
(alpha != 1) the force ``C s^alpha`` is not smooth where the velocity vanishes: the steps next to a reversal are
graded geometrically towards it (:data:`GRADES` halvings where alpha < 1, :data:`ZERO_GRADES` where alpha > 1),
so that its error stays at rounding. So are the steps after z's zero crossing where |z|^n is not smooth (a
fractional n): ratio 2 where n > 1, finer and longer where n < 1 (:data:`FINE_RATIO`). No smoothed sign
function anywhere.

A damper of alpha < 1 dominates the sliders at low speed: where the layer is pushed on past the sliders' holding
limit (``push = -d (k x + f_h) > f_slow``) its speed relaxes towards the slow manifold ``g(s) = push``
(``g(s) = f_f(s) + C s^alpha``) at the rate ``g'(s) / m``, which grows without bound as s falls (a creep of 1e-6 m/s:
hundreds of times the layer's frequency). There the explicit steps span at most STEP_RELAX of the relaxation time
while the speed relaxes (and the speed at most halves in a step while it slows down onto the manifold), STEP_STABLE
once it is on it, and where the relaxation is CREEP_RATIO times faster than the layer's oscillation the piece
creeps (mode bit :data:`CREEPING`): it moves at ``S0 + S1 + S2``, the quasi-static speed and its first two
corrections for inertia (:func:`_slow`; the neglected terms are (omega / lambda)^6 of the speed), on steps of a
fraction of its own slow time (:func:`_creep_step`), until a yield or zero crossing of z, or its end at rest
(:data:`EV_REST`, located as the other events).

The integration records every step's start state (a grid); any time is evaluated by a partial step from the
grid point before it (the tableau's own continuous extension of the same order: a step of a shorter length).
The dissipated energies (friction, damper, hysteresis) are integrated with the state, so the energy balance is
closed to the integrator's accuracy.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy.integrate._ivp import dop853_coefficients as _dop

# the 12-stage 8th-order Dormand-Prince tableau (scipy's, the one of DOP853)
_S = 12
_A = np.ascontiguousarray(_dop.A[:_S, :_S], dtype=np.float64)
_B = np.ascontiguousarray(_dop.B, dtype=np.float64)
_C = np.ascontiguousarray(_dop.C[:_S], dtype=np.float64)
# its 7th-order continuous extension (three more stages; Hairer, Norsett and Wanner's dense output)
_AX = np.ascontiguousarray(_dop.A, dtype=np.float64)
_D = np.ascontiguousarray(_dop.D, dtype=np.float64)

#: The state: x [m], x_dot [m/s], z (Bouc-Wen: [-]; plastic element: [N]), and the work so far [J] of the
#: sliders' friction, of the damper and of the hysteresis.
NY = 6
#: The parameter vector's slots (COARSE: the steps' lengths times this where it is above 1, e.g. 2 for half as
#: many steps in a fit's search on a thinned record; 0, the default, is 1).
(M, K, HKIND, Q, DY, N, KP, FP, FSLOW, FFAST, RATE, C, ALPHA, COARSE) = range(14)
NP = 14
#: Hysteretic element: none, Bouc-Wen, elastic-perfectly-plastic.
H_NONE, H_BOUCWEN, H_PLASTIC = 0, 1, 2
#: A piece's mode (its grid points' flag): the plastic element elastic (0) or yielding (1); the Bouc-Wen element
#: unloading (0, ``z x_dot < 0``: elastic), saturated (1, ``z = sign(x_dot)``) or loading (2).
ELASTIC, YIELDING, LOADING = 0, 1, 2
#: The Bouc-Wen element is saturated where ``1 - |z|`` falls below this (then z = +-1 exactly, and the force
#: changes by Qd times this).
SATURATION = 1e-13
#: Steps a period of the (initial) stiffness; steps over the Bouc-Wen element's transition (dy / (n v));
#: steps over the friction law's velocity scale (1 / (rate a)).
STEPS_PERIOD = 32.0
STEPS_TRANSITION = 1.5
STEPS_RATE = 2.0
#: Halvings of the steps next to a reversal with a power-law damper (the last substep is 2^-GRADES of a step).
#: The tableau's error on the last substep towards the reversal, where the damper's s^alpha is not smooth, falls as
#: its length to the 1 + alpha, and the reversal's instant, the root of the velocity there, is off by that error
#: over the deceleration, which at a stick near the sliders' holding limit, (f_slow - |k x + f_h|) / m, can be small:
#: a Bouc-Wen layer (n 1.5, alpha 0.2, sliders) stuck at 3.2e-3 m/s^2 came to rest 3.9e-8 s after the reference
#: (converged to 1e-13 s) with 14 halvings, 4.3e-9 with 17, 2.3e-9 with 18 (x 4.3e-10 -> 0.9e-10 of d0; on four
#: other power-law layers the reversals and x as close or closer); 18 cost 0-19% more grid points. (Graded towards
#: the reversal by 18 and after it by 14, the errors of the other layers grew, a pendulum's reversals from 2.5e-10
#: to 3.7e-9 s: the two sides' errors had cancelled.) On coarse steps (a fit's search), and after z's zero crossing
#: of a fractional n < 1 on them, SEARCH_GRADES, as before.
GRADES = 18
SEARCH_GRADES = 14
#: Halvings after z's zero crossing with a fractional n >= 1 where there is no power-law damper (default steps,
#: and coarse steps: a fit's search on a thinned record). The graded substeps [s, 2 s] of a term t^n each err in
#: proportion to s^(n + 1), the same at every scale: the largest ones (h / 2, h / 4) rule the error, and past a few
#: halvings the first substep's own error is below theirs. Measured against the solve_ivp reference (rtol 1e-12;
#: 40 s of a 0.2 m release, viscous 2 %, no sliders), the largest error of x over d0 with 14 / 8 / 6 halvings:
#: n 1.0007 1.5e-11 / 1.5e-11 / 1.5e-11, n 1.3 3.6e-11 / 3.7e-11 / 7.9e-11, n 2.5 2.6e-11 for all three; n 1.0007
#: evaluated in 4.9 / 3.6 / 3.2 ms (the 14 halvings after each crossing were 1 100 of its 2 800 grid points). A
#: power-law damper's grading towards the reversals, where the velocity's s^alpha is not smooth, keeps GRADES:
#: with 6 the error of alpha 0.2 grew from 7.9e-9 to 5.2e-6 of d0. On coarse steps (n 1.0007): the motion within
#: 1.3e-9 of d0 of the reference, 2.1 ms against 4.1 ms with GRADES. A damper of alpha > 1 (|t|^alpha smooth to
#: first order, as z^n) is graded towards its turns on ZERO_GRADES, on coarse steps too (with COARSE_GRADES one of
#: twelve layers of alpha 1.2-1.6 erred 2.3e-9 of d0 instead of 3.3e-10): twelve random layers of alpha 1.02-1.98
#: (Bouc-Wen, linear, pendulum) erred as with GRADES to two digits, on 25-35 % fewer points.
ZERO_GRADES = 8
COARSE_GRADES = 4
#: After z's zero crossing with n below 1 (a term t^n whose derivatives are unbounded there) the default steps'
#: grading is finer and longer: one step of FINE_SPAN of the piece's steps (``1 / (FINE_RATIO - 1)``, so that the
#: plain steps after it are at most FINE_RATIO - 1 of their distance from the crossing, as the graded substeps) on
#: the mesh of ratio FINE_RATIO, the points ``FINE_RATIO^-j`` of it for j = FINE_GRADES .. 0 (the first substep
#: 2^-14 of it); the push's z from 0 (:func:`boucwen_push`) likewise. Coarse steps keep the ratio-2 grading of
#: SEARCH_GRADES. Measured against the solve_ivp reference (rtol 1e-12; 40 s of a 0.2 m release of 800 t on Kd 3.5 MN/m,
#: Qd 400 kN, dy 25 mm, viscous 2 %, no sliders), the largest error of x / a over d0 / d0 omega^2, grid points and
#: time of a motion (load ~2):
#:   n     ratio 2, 14 halvings, pushed on equal steps   ratio 2, graded push      FINE (ratio sqrt 2, 28), graded push
#:   0.5   1.3e-6 / 3.3e-6, 1 913 points, 2.5 ms         7.5e-10 / 2.9e-8          1.8e-10 / 6.1e-10, 2 660, 3.4 ms
#:   0.6   3.2e-7 / 7.9e-7, 1 927                        6.2e-10 / 2.6e-8          4.2e-11 / 1.5e-10, 2 690, 3.1 ms
#:   0.7   7.6e-8 / 1.9e-7                               -                         1.1e-11 / 1.6e-10
#:   0.8   1.6e-8 / 4.0e-8                               2.8e-10 / 1.3e-8          3.6e-12 / 1.0e-10
#:   0.9   2.6e-9 / 6.4e-9                               -                         1.6e-12 / 2.7e-11
#: (the push's equal steps were the main error: 1.4e-6 of z at n 0.6, against 1.9e-12 graded). The first substep
#: rules the rest: with 20 substeps of ratio sqrt 2 (the first 2^-10 of the span) n 0.5 erred 1.1e-8 / 3.7e-8, with
#: 30 of ratio 2^(1/3) (2^-10) 2.2e-8 / 7.5e-8, with 42 of ratio 2^(1/3) (2^-14, span 3.8 steps, 3 418 points)
#: 3.4e-10 / 1.2e-9. On coarse steps (ratio 2, 14 halvings, the graded push) n 0.5-0.9 hold x to 4e-9 and a to
#: 6.5e-8 on 1 401-1 418 points.
FINE_RATIO = 2.0 ** 0.5
FINE_GRADES = 28
FINE_SPAN = 1.0 / (FINE_RATIO - 1.0)
#: The kinds of grading at a step's start: none, towards a reversal or zero crossing (ratio 2), FINE.
FINE = 2
#: Events in a row located at the start of their step (the motion does not advance) after which the integration
#: gives up with status 3 rather than loop to MAX_STEPS (minutes).
MAX_STALLED = 1000
#: A creep into the sliders' holding limit is at rest below this fraction of the release's largest speed.
CREEP = 1e-8
#: A piece's mode bit: creeping (added to the element's mode): the damper (alpha < 1) holds the layer on its slow
#: manifold, inertia a small correction (see :func:`_creep`).
CREEPING = 4
#: A piece creeps where the damper's relaxation rate at the quasi-static speed, g'(S0) / m, is at least this many
#: times the layer's circular frequency sqrt(k_t / m), once its speed is within CREEP_TOL of the slow manifold's.
#: The neglected terms are (omega / lambda)^6 = 1.4e-9 of the creep's speed at 30 (measured against the reference
#: at the creep's start, lead-rubber bearings with fluid dampers of alpha 0.4 and 0.2: 2.7e-8 and 3.7e-8 of it;
#: S0 + S1 alone 4.3e-6 and 5.0e-6). With S0 + S1 the creep began at 100 (the neglected (omega / lambda)^4 1e-8):
#: the explicit steps before it, STEP_STABLE of the relaxation time, grow in number as the ratio squared (their
#: minute of 3 624 grid points came down to 466, 4.5 -> 0.95 ms, the same motion to 1e-11 of d0).
CREEP_RATIO = 30.0
CREEP_TOL = 1e-6
#: A creeping piece's step, this fraction of its slow time g'(S0) / k_t at its start (see :func:`_creep_step`; 4
#: erred 4e-6 of d0 against the reference, 0.25 as the swing's steps did).
STEP_CREEP = 0.25
#: Where the damper dominates (alpha < 1, the layer pushed on past the sliders), an explicit step spans at most this
#: many of the damper's relaxation times m / g'(s) while the speed relaxes towards the slow manifold (resolved:
#: the tableau's e^-z to 1e-10 at z = 0.5), and STEP_STABLE of them once it is within BAND_TOL of it (the
#: relaxation then only needs to be damped: the tableau's amplification at z = -3 is 0.050 against e^-3 = 0.0498;
#: it is unstable beyond z = -6.2).
STEP_RELAX = 0.5
STEP_STABLE = 3.0
BAND_TOL = 1e-3
#: End codes of a record's grid points: the step goes on, or the point starts a piece after an event.
EV_NONE, EV_RELEASE, EV_REVERSAL, EV_YIELD, EV_ZERO, EV_STICK = 0, 1, 2, 3, 4, 5
#: The event that ends a creep: the force pushing the layer on falls to what the sliders and the damper resist at
#: the creep's lowest speed (the quasi-static speed reaches CREEP of the release's: at rest, as :func:`_held`).
EV_REST = 6


@njit(cache=True, nogil=True)
def _net(P, y):
    """The force the sliders must hold at rest: k x + f_h [N]."""
    fh = 0.0
    if P[HKIND] == H_BOUCWEN:
        fh = P[Q] * y[2]
    elif P[HKIND] == H_PLASTIC:
        fh = y[2]
    return P[K] * y[0] + fh


@njit(cache=True, nogil=True)
def _resist(P, s):
    """The sliders' friction and the damper's force against a speed s > 0 [m/s], g(s) = f_f(s) + C s^alpha [N],
    and its first two derivatives [N s/m], [N s^2/m^2]."""
    rate = P[RATE]
    df = P[FFAST] - P[FSLOW]
    if rate > 0.0 and df != 0.0:
        e = math.exp(-rate * s)
        f, f1, f2 = P[FFAST] - df * e, df * rate * e, -df * rate * rate * e
    else:
        f, f1, f2 = P[FSLOW], 0.0, 0.0
    a = P[ALPHA]
    p = P[C] * s ** a
    return f + p, f1 + a * (p / s), f2 + a * (a - 1.0) * (p / s / s)  # (no underflow of s * s to 0)


@njit(cache=True, nogil=True)
def _quasi(P, push, cs=0.0):
    """The quasi-static speed S0 [m/s] at which the sliders and the damper (and ``cs`` [N s/m], a viscous slope in
    parallel: the flexible superstructure's storey damper, which the base drags) balance the force ``push`` [N] that
    drives the layer on, g(S0) + cs S0 = push (0 where the sliders hold it, push <= f_slow). Closed form for
    constant friction without cs, ((push - f_slow) / C)^(1 / alpha); else a safeguarded Newton iteration on ln S0
    within a bracket, to a residual of rounding."""
    excess = push - P[FSLOW]
    if excess <= 0.0 or (P[C] <= 0.0 and cs <= 0.0):
        return 0.0
    if cs <= 0.0 and (P[RATE] <= 0.0 or P[FFAST] == P[FSLOW]):
        return (excess / P[C]) ** (1.0 / P[ALPHA])
    # g(hi) + cs hi >= push: the friction is at least the smaller of its two levels (a friction that weakens with
    # the speed makes g rise, fall and rise again: the bracket's iteration finds one of its roots)
    fmin = min(P[FSLOW], P[FFAST])
    hi = math.inf
    if P[C] > 0.0:
        hi = ((push - fmin) / P[C]) ** (1.0 / P[ALPHA])
    if cs > 0.0:
        hi = min(hi, (push - fmin) / cs)
    u_hi = math.log(hi)
    u_lo = u_hi
    for _ in range(40):  # g -> f_slow < push as the speed vanishes
        u_lo -= 20.0
        s = math.exp(u_lo)
        if _resist(P, s)[0] + cs * s < push:
            break
    u = u_hi
    for _ in range(200):
        s = math.exp(u)
        g, g1, _g2 = _resist(P, s)
        g += cs * s
        g1 += cs
        if abs(g - push) <= 4e-16 * push:
            return s
        if g > push:
            u_hi = u
        else:
            u_lo = u
        new = u - (g - push) / s / g1 if g1 > 0.0 else 0.5 * (u_lo + u_hi)
        if not (u_lo < new < u_hi):
            new = 0.5 * (u_lo + u_hi)
        if abs(new - u) <= 1e-15 or u_hi - u_lo <= 1e-15:
            return math.exp(new)
        u = new
    return math.exp(u)


@njit(cache=True, nogil=True)
def _slope(P, z, mode):
    """dz/dx of the hysteretic element in a piece of this mode, and the layer's tangent stiffness k_t [N/m]."""
    base = mode & 3
    if P[HKIND] == H_BOUCWEN:
        if base == YIELDING:
            return 0.0, P[K]
        zx = 1.0 / P[DY]
        if base == LOADING:
            az = abs(z)
            zx *= 1.0 - (az if P[N] == 1.0 else az ** P[N])
        return zx, P[K] + P[Q] * zx
    if P[HKIND] == H_PLASTIC and base == ELASTIC:
        return P[KP], P[K] + P[KP]
    return 0.0, P[K]


@njit(cache=True, nogil=True)
def _slow(P, y, d, mode):
    """The slow manifold at the state y of a piece pushed on past the sliders by ``push = -d (k x + f_h)``:
    returns (S, dS/dt, g'(S0), k_t, dz/dx), the speed S = S0 + S1 + S2 [m/s] and its rate [m/s^2].

    From m dS/dt = push - g(S) and dpush/dt = -k_t S, expanded in eps = m k_t / g'(S0)^2 = (omega / lambda)^2:
    S0 the quasi-static speed (g(S0) = push, :func:`_quasi`), S1 = m k_t S0 / g'^2 its first correction for
    inertia, S2 = (m k_t S1 / g' - m dS1/dt - g'' S1^2 / 2) / g' the second (dS1/dt at first order, with
    dS0/dt = -k_t S0 / g' and, while the Bouc-Wen element loads, dk_t/dt = -Q n |z|^(n-1) sgn(z) z_dot / dy); the
    neglected terms are eps^3 of S. The rate is dS0/dt (at the speed S) + dS1/dt, to eps^2 of itself."""
    zx, kt = _slope(P, y[2], mode)
    s0 = _quasi(P, -d * _net(P, y))
    if s0 <= 0.0:
        return 0.0, 0.0, 0.0, kt, zx
    m = P[M]
    _g, g1, g2 = _resist(P, s0)
    s1 = m * kt * s0 / g1 / g1
    dkt = _stiffening(P, y, d, mode, s0, zx)
    ds0 = -kt * s0 / g1
    ds1 = m * (dkt * s0 + kt * ds0) / g1 / g1 - 2.0 * m * kt * s0 * g2 * ds0 / g1 / g1 / g1
    s2 = (m * kt * s1 / g1 - m * ds1 - 0.5 * g2 * s1 * s1) / g1
    s = s0 + s1 + s2
    return s, -kt * s / g1 + ds1, g1, kt, zx


@njit(cache=True, nogil=True)
def _stiffening(P, y, d, mode, s, zx):
    """dk_t/dt [N/(m s)] of a piece moving at the speed s [m/s] in direction d: while the Bouc-Wen element loads,
    ``-Q n |z|^(n-1) sgn(z) z_dot / dy`` with z_dot = d s dz/dx (``zx``); 0 otherwise."""
    if P[HKIND] == H_BOUCWEN and (mode & 3) == LOADING and P[N] > 0.0:
        z = y[2]
        az = abs(z)
        if az > 0.0:
            return -P[Q] * P[N] * az ** (P[N] - 1.0) * (1.0 if z > 0.0 else -1.0) * d * s * zx / P[DY]
    return 0.0


@njit(cache=True, nogil=True)
def _creep(P, y, d, mode, out):
    """The right-hand side on the slow manifold (:func:`_slow`): the layer moves at its speed S, the velocity's
    state at its rate, z and the works with it."""
    for j in range(NY):
        out[j] = 0.0
    s, ds, _g1, _kt, zx = _slow(P, y, d, mode)
    if s <= 0.0:
        return
    v = d * s
    out[0] = v
    out[1] = d * ds
    out[2] = v * zx
    _creep_works(P, y, mode, s, v, out)


@njit(cache=True, nogil=True)
def _creep_works(P, y, mode, s, v, out):
    """The works' rates (out[3:6], [W]) of a piece creeping at the speed s > 0 [m/s], velocity v = d s: the sliders'
    friction, the damper and the hysteresis (as :func:`_rhs`'s)."""
    base = mode & 3
    g, _g1, _g2 = _resist(P, s)
    fd = P[C] * s ** P[ALPHA]
    out[3] = (g - fd) * s
    out[4] = fd * s
    if P[HKIND] == H_BOUCWEN:
        if base == LOADING:
            az = abs(y[2])
            out[5] = P[Q] * (az if P[N] == 1.0 else az ** P[N]) * y[2] * v
        elif base == YIELDING:
            out[5] = P[Q] * y[2] * v
    elif P[HKIND] == H_PLASTIC and base == YIELDING:
        out[5] = P[FP] * s


@njit(cache=True, nogil=True)
def _rhs_any(P, y, d, mode, out):
    """The right-hand side of a piece of any mode: on the slow manifold (:func:`_creep`) or the equation of motion
    (:func:`_rhs`)."""
    if mode & CREEPING:
        _creep(P, y, d, mode, out)
    else:
        _rhs(P, y, d, mode, out)


@njit(cache=True, nogil=True)
def _rhs(P, y, d, mode, out):
    """The equation of motion's right-hand side (a piece that does not creep). (The creeping pieces' law is kept
    out of it and of the tableau's loops: a branch to it here made every free vibration twice as slow.)"""
    x, v, z = y[0], y[1], y[2]
    s = d * v
    if s < 0.0:
        s = 0.0
    rate = P[RATE]
    if rate > 0.0:
        ff = P[FFAST] - (P[FFAST] - P[FSLOW]) * math.exp(-rate * s)
    else:
        ff = P[FSLOW]
    alpha = P[ALPHA]
    if alpha == 1.0:
        fd = P[C] * s
    elif s > 0.0:
        fd = P[C] * s ** alpha
    else:
        fd = 0.0
    hk = P[HKIND]
    fh = 0.0
    zdot = 0.0
    dh = 0.0
    if hk == H_BOUCWEN:
        q, dy = P[Q], P[DY]
        fh = q * z
        if mode == LOADING:
            az = abs(z)
            zn = az if P[N] == 1.0 else az ** P[N]
            zdot = v / dy * (1.0 - zn)
            dh = q * zn * z * v
        elif mode == YIELDING:  # saturated: z = d, all of the element's work dissipated
            dh = q * z * v
        else:
            zdot = v / dy
    elif hk == H_PLASTIC:
        fh = z
        if mode == YIELDING:
            dh = P[FP] * s
        else:
            zdot = P[KP] * v
    out[0] = v
    out[1] = -(P[K] * x + fh + d * (ff + fd)) / P[M]
    out[2] = zdot
    out[3] = ff * s
    out[4] = fd * s
    out[5] = dh


@njit(cache=True, nogil=True)
def _step(P, y, h, d, mode, k, tmp, out):
    """One step of length h of the tableau from y (stages in k, scratch tmp) into out."""
    if mode & CREEPING:
        _tableau_creep(P, y, h, d, mode, k, tmp, out)
    else:
        _tableau(P, y, h, d, mode, k, tmp, out)


@njit(cache=True, nogil=True)
def _tableau(P, y, h, d, mode, k, tmp, out):
    """One step of the tableau on the equation of motion."""
    for i in range(_S):
        for j in range(NY):
            acc = 0.0
            for m in range(i):
                acc += _A[i, m] * k[m, j]
            tmp[j] = y[j] + h * acc
        _rhs(P, tmp, d, mode, k[i])
    for j in range(NY):
        acc = 0.0
        for i in range(_S):
            acc += _B[i] * k[i, j]
        out[j] = y[j] + h * acc


# The helpers that integrate calls with literal flags are compiled for one signature each (numba compiled a
# version per literal argument: five of _locate, each inlining the tableau's step).
@njit(cache=True, nogil=True)
def _tableau_creep(P, y, h, d, mode, k, tmp, out):
    """One step of the tableau on the slow manifold (:func:`_tableau`, a copy: numba cannot cache a function
    that takes another as an argument)."""
    for i in range(_S):
        for j in range(NY):
            acc = 0.0
            for m in range(i):
                acc += _A[i, m] * k[m, j]
            tmp[j] = y[j] + h * acc
        _creep(P, tmp, d, mode, k[i])
    for j in range(NY):
        acc = 0.0
        for i in range(_S):
            acc += _B[i] * k[i, j]
        out[j] = y[j] + h * acc


# The helpers that integrate calls with literal flags are compiled for one signature each (numba compiled a
# version per literal argument: five of _locate, each inlining the tableau's step).
@njit("float64[::1](float64[::1], int64, boolean)", cache=True, nogil=True)
def _fractions(P, graded_start, graded_end):
    """The substeps of a step, as fractions of it: one, or graded towards a reversal at its start or end
    (:data:`GRADES` halvings, :data:`SEARCH_GRADES` on coarse steps, ``P[COARSE]`` above 1; where the grading
    only follows z's zero crossing with a fractional n above 1, no power-law damper, :data:`ZERO_GRADES`, or
    :data:`COARSE_GRADES` on coarse steps; a damper of alpha > 1, ZERO_GRADES), or
    (``graded_start`` :data:`FINE`: the step after z's zero crossing with n below 1) on the finer mesh of ratio
    :data:`FINE_RATIO` (:data:`FINE_GRADES` substeps after the first)."""
    if not graded_start and not graded_end:
        return np.ones(1)
    if graded_start == FINE:
        g = np.empty(FINE_GRADES + 1)
        g[0] = FINE_RATIO ** -FINE_GRADES
        for i in range(1, FINE_GRADES + 1):
            g[i] = FINE_RATIO ** -(FINE_GRADES - i) * (1.0 - 1.0 / FINE_RATIO)
        if not graded_end:
            return g
        grades = GRADES  # (a power-law damper's reversal in the step after the fine one: both halves graded)
        out = np.empty(FINE_GRADES + 1 + grades + 1)
        for i in range(FINE_GRADES + 1):
            out[i] = 0.5 * g[i]
        out[FINE_GRADES + 1 + grades] = 0.5 * 0.5 ** grades
        for i in range(1, grades + 1):
            out[FINE_GRADES + 1 + grades - i] = 0.5 * 0.5 ** (grades + 1 - i)
        return out
    grades = GRADES
    if P[ALPHA] >= 1.0 and (P[HKIND] != H_BOUCWEN or P[N] >= 1.0):  # (see ZERO_GRADES)
        if P[ALPHA] > 1.0:
            grades = ZERO_GRADES
        else:  # no power-law damper: the grading follows z's zero crossing only
            grades = COARSE_GRADES if P[COARSE] > 1.0 else ZERO_GRADES
    elif P[COARSE] > 1.0:  # a fit's search (a power-law damper's reversals, n < 1's zero crossings)
        grades = SEARCH_GRADES
    g = np.empty(grades + 1)
    g[0] = 0.5 ** grades
    for i in range(1, grades + 1):
        g[i] = 0.5 ** (grades + 1 - i)
    if graded_start and graded_end:
        out = np.empty(2 * (grades + 1))
        for i in range(grades + 1):
            out[i] = 0.5 * g[i]
            out[2 * grades + 1 - i] = 0.5 * g[i]
        return out
    if graded_start:
        return g
    return g[::-1].copy()


@njit("void(float64[::1], float64[::1], float64, float64, int64, int64, boolean, float64[:, ::1], float64[::1], "
      "float64[::1], float64[::1])", cache=True, nogil=True)
def _advance(P, y, h, d, mode, graded_start, graded_end, k, tmp, a, out):
    """y advanced by h (substeps graded as asked) into out; a is scratch."""
    fr = _fractions(P, graded_start, graded_end)
    for j in range(NY):
        a[j] = y[j]
    for f in fr:
        _step(P, a, f * h, d, mode, k, tmp, out)
        for j in range(NY):
            a[j] = out[j]


@njit("float64(float64[::1], float64[::1], int64, float64, float64)", cache=True, nogil=True)
def _event_value(P, y, kind, d, level):
    if kind == EV_REST:  # the push -d (k x + f_h) above ``level``
        return -d * _net(P, y) - level
    if kind == EV_REVERSAL:
        return d * y[1]
    if kind == EV_YIELD:  # the plastic element's yield; the Bouc-Wen element's saturation
        return (1.0 - SATURATION if P[HKIND] == H_BOUCWEN else P[FP]) - d * y[2]
    return y[2]  # EV_ZERO


@njit("float64(float64[::1], float64[::1], float64, float64, int64, int64, int64, boolean, float64[:, ::1], "
      "float64[::1], float64[::1], float64[::1], float64[::1], float64)", cache=True, nogil=True)
def _locate(P, y, h, d, mode, kind, graded_start, graded_end, k, tmp, a, out, r, level):
    """The fraction theta in (0, h] of a step where the event's function (:func:`_event_value`) vanishes,
    bracketed by [0, h]; a safeguarded Newton iteration on the tableau's map (derivative from the equation)."""
    lo, hi = 0.0, h
    # the event's function is positive before the event (the velocity's d x_dot, the plastic element's margin
    # f_p - d z), or has the sign of z (a zero crossing of z): taken so even where it starts at 0 (a reversal's
    # velocity at the piece's start)
    glo = abs(_event_value(P, y, kind, d, level)) * (1.0 if kind != EV_ZERO or y[2] > 0.0 else -1.0)
    _advance(P, y, h, d, mode, graded_start, graded_end, k, tmp, a, out)
    ghi = _event_value(P, out, kind, d, level)
    if ghi == 0.0:
        return h
    theta = h * glo / (glo - ghi)
    for _ in range(100):
        if not (lo < theta < hi):
            theta = 0.5 * (lo + hi)
        _advance(P, y, theta, d, mode, graded_start, graded_end, k, tmp, a, out)
        g = _event_value(P, out, kind, d, level)
        if g == 0.0:
            return theta
        if (g > 0.0) == (glo > 0.0 or (glo == 0.0 and kind != EV_ZERO)):
            lo, glo = theta, g
        else:
            hi, ghi = theta, g
        _rhs_any(P, out, d, mode, r)
        if kind == EV_REVERSAL:
            dg = d * r[1]
        elif kind == EV_YIELD:
            dg = -d * r[2]
        elif kind == EV_REST:
            dg = -d * (P[K] * r[0] + (P[Q] * r[2] if P[HKIND] == H_BOUCWEN else
                                      (r[2] if P[HKIND] == H_PLASTIC else 0.0)))
        else:
            dg = r[2]
        new = theta - g / dg if dg != 0.0 else 0.5 * (lo + hi)
        if not (lo < new < hi):
            new = 0.5 * (lo + hi)
        if abs(new - theta) <= 4e-16 * abs(theta) or hi - lo <= 4e-16 * hi:
            return new if lo < new <= hi else hi
        theta = new
    return theta


@njit(cache=True, nogil=True)
def _stored(P, y):
    e = 0.5 * P[K] * y[0] * y[0]
    if P[HKIND] == H_BOUCWEN:
        e += 0.5 * P[Q] * P[DY] * y[2] * y[2]
    elif P[HKIND] == H_PLASTIC:
        e += 0.5 * y[2] * y[2] / P[KP]
    return e


@njit(cache=True, nogil=True)
def _step_size(P, y, d, mode):
    """The piece's step [s]: a fraction of the period of its stiffness (the initial one, or the post-yield one where
    the Bouc-Wen element is saturated), of the Bouc-Wen transition while loading, and of the friction law's
    velocity scale; times ``P[COARSE]`` where that is above 1.

    The transition: ``dy / (n v)`` over :data:`STEPS_TRANSITION`, v the largest velocity the piece can reach
    before it saturates: from the piece's start ``v0``, driven on by at most the force at its start,
    ``push = -d (k x + Q z)`` (along the piece the spring's force grows and z moves towards d, so the driving force
    falls by at least k u over a displacement u; the sliders and the damper only brake), over the displacement to
    saturation, ``dy G_n(1 - SATURATION)`` with ``G_n(z) = int_0^z du / (1 - u^n) <= 1 + ln(1 / SATURATION) / n``
    (``v^2 <= v0^2 + 2 push reach / m``, and ``<= v0^2 + push^2 / (k m)``), and at most the energy's own bound.
    (A layer the element held off centre, ringing on its elastic stiffness, took 3.7 times the grid points on the
    bound of the acceleration the release's energy allows.)"""
    mode = mode & 3
    k1 = P[K]
    if P[HKIND] == H_BOUCWEN and mode != YIELDING:
        k1 += P[Q] / P[DY]
    elif P[HKIND] == H_PLASTIC:  # (the plastic element's steps: its initial stiffness's throughout)
        k1 += P[KP]
    coarse = max(P[COARSE], 1.0)
    h = 2.0 * math.pi * math.sqrt(P[M] / k1) * coarse / STEPS_PERIOD
    energy = 0.5 * P[M] * y[1] * y[1] + _stored(P, y)
    vmax = math.sqrt(2.0 * energy / P[M])
    xmax = math.sqrt(2.0 * energy / P[K])
    amax = (P[K] * xmax + P[Q] + P[FP] + max(P[FFAST], P[FSLOW])) / P[M] + 1e-300
    if P[HKIND] == H_BOUCWEN and mode == LOADING and vmax > 0.0:
        reach = P[DY] * (1.0 - d * y[2] + math.log(1.0 / SATURATION) / P[N])
        # the force that drives the piece on, -d (k x + Q z), only falls along it (the spring's grows, and z moves
        # towards d), by at least k u over a displacement u, and the sliders and the damper only brake it: the
        # kinetic energy gains at most push * reach, and push^2 / (2 k)
        push = max(-d * _net(P, y), 0.0)
        gain = 2.0 * push * reach / P[M]
        if P[K] > 0.0:
            gain = min(gain, push * push / (P[K] * P[M]))
        v = min(vmax, math.sqrt(y[1] * y[1] + gain))
        h = min(h, coarse * P[DY] / (max(P[N], 1.0) * v * STEPS_TRANSITION))
    if P[RATE] > 0.0 and P[FFAST] != P[FSLOW]:
        h = min(h, coarse / (P[RATE] * amax * STEPS_RATE))
    return h


@njit(cache=True, nogil=True)
def _relax_step(P, y, d, mode, h):
    """The step [s] of a piece whose layer the sliders do not hold (push = -d (k x + f_h) > f_slow) and a damper of
    alpha < 1 resists: at most STEP_RELAX of the damper's relaxation time m / g'(s) at the speed s the layer has
    (the quasi-static speed at a turn), h otherwise; and whether the piece is on its slow manifold and may creep
    (the relaxation at least CREEP_RATIO times faster than the layer's oscillation, the speed within CREEP_TOL of
    S0 + S1). Where the layer slows down onto the manifold, the speed at most halves in a step (a pendulum slowing
    from 4e-4 to 3e-6 m/s in one step of its period's, the relaxation rate 50 times larger at its end than at its
    start, came out 8e-8 m off). Returns (step, creep, S)."""
    push = -d * _net(P, y)
    if push <= P[FSLOW]:
        return h, False, 0.0
    s0 = _quasi(P, push)
    if not (0.0 < s0 < math.inf):
        return h, False, 0.0
    m = P[M]
    _g, g1, _g2 = _resist(P, s0)
    if not (0.0 < g1 < math.inf):  # (a damper too weak to matter at that speed)
        return h, False, 0.0
    _zx, kt = _slope(P, y[2], mode)
    s = d * y[1]
    target = _slow(P, y, d, mode)[0]
    off = abs(s - target)
    if g1 >= CREEP_RATIO * math.sqrt(kt * m) and off <= CREEP_TOL * target:
        return h, True, target
    if s > 0.0:
        g, g1, _g2 = _resist(P, s)
        if not (0.0 < g1 < math.inf):
            return h, False, 0.0
        if g > push:  # slowing down towards the slow manifold: the speed at most halves in a step (so the
            # relaxation rate, which grows as s^(alpha - 1), at most doubles over it)
            h = min(h, 0.5 * s * m / (g - push))
    return min(h, (STEP_STABLE if off <= BAND_TOL * target else STEP_RELAX) * m / g1), False, 0.0


@njit(cache=True, nogil=True)
def _creep_step(P, y, d, mode, h):
    """The step [s] of a creeping piece: STEP_CREEP of its slow time g'(S0) / k_t (the time over which the push,
    and with it the speed, change by their own size) at its start, or the piece's step h where that is longer; while
    the Bouc-Wen element loads, at most the transition's steps at the creep's speed (dy / (n S))."""
    s, _ds, g1, kt, _zx = _slow(P, y, d, mode)
    if not (s > 0.0 and g1 > 0.0 and kt > 0.0):
        return h
    hc = STEP_CREEP * g1 / kt
    if P[HKIND] == H_BOUCWEN and (mode & 3) == LOADING:
        hc = min(hc, P[DY] / (max(P[N], 1.0) * s * STEPS_TRANSITION))
    return max(h, hc)


@njit(cache=True, nogil=True)
def _mode(P, y, d):
    """The mode of a piece that starts at rest or after an event at y, moving in direction d: the plastic element
    yields where ``d z`` has reached its strength; the Bouc-Wen element loads where ``d z >= 0`` (saturated where
    ``d z >= 1 - SATURATION``), else unloads."""
    if P[HKIND] == H_PLASTIC:
        return YIELDING if d * y[2] >= P[FP] else ELASTIC
    if P[HKIND] == H_BOUCWEN:
        if d * y[2] >= 1.0 - SATURATION:
            return YIELDING
        return LOADING if d * y[2] >= 0.0 else ELASTIC
    return ELASTIC


@njit(cache=True, nogil=True)
def _held(P, net, creep):
    """Whether the layer at rest under the net force ``net`` [N] stays there: the sliders hold it
    (``|net| <= f_slow``), or a power-law damper (alpha < 1) holds its creep below ``creep`` [m/s]: with inertia
    neglected the damper balances the excess, ``C s^alpha = |net| - f_slow``, and the speed never exceeds
    ``((|net| - f_slow) / C)^(1 / alpha)`` since the excess only falls as the layer moves towards the holding limit.
    (A record of a linear layer, alpha 0.32, turning 0.8 % past the holding limit crept at 1e-11 m/s, a damper
    so stiff there, alpha C s^(alpha - 1), that the explicit steps shrank to 1e-7 s: 350 000 steps a second.)
    Likewise a friction that grows with the speed, with a viscous damper or none, where its quasi-static speed is
    below ``creep``."""
    excess = abs(net) - P[FSLOW]
    if excess <= 0.0:
        return True
    if P[ALPHA] < 1.0 and P[C] > 0.0:
        return (excess / P[C]) ** (1.0 / P[ALPHA]) < creep
    # a friction that grows with the speed (Constantinou's law, f_fast > f_slow) and a viscous damper balance the
    # excess at the quasi-static speed excess / g'(0) (to 1 + rate s of itself): at rest where that is below
    # ``creep`` (a pendulum turning 4e-9 of f_slow past its holding limit, its slow friction 3.5e-10, crept at
    # 3e-18 m/s, and the integration turned there without end, each step of length 0)
    slope = _creep_slope(P)
    return slope > 0.0 and excess < slope * creep and P[RATE] * excess < 0.1 * slope


@njit(cache=True, nogil=True)
def _creep_slope(P):
    """g'(0) [N s/m]: how fast the sliders' friction (Constantinou's law, f_fast > f_slow) and a viscous damper grow
    with the speed from rest, the slope of the quasi-static creep ``excess / g'(0)`` (0 where neither grows)."""
    slope = P[C] if P[ALPHA] == 1.0 else 0.0
    if P[RATE] > 0.0 and P[FFAST] > P[FSLOW]:
        slope += (P[FFAST] - P[FSLOW]) * P[RATE]
    return slope


@njit(cache=True, nogil=True)
def _finish(P, y, h, d, mode, k, K, tmp, F, ynew):
    """The coefficients F (7 x NY) of the continuous extension over the step of length h from y whose 12 stages
    are ``k`` (the step just taken), without computing those again (stages 12-15 only)."""
    for i in range(_S):
        for j in range(NY):
            K[i, j] = k[i, j]
    for i in range(_S, 16):
        if i == _S:  # the stage at the step's end
            for j in range(NY):
                acc = 0.0
                for m in range(_S):
                    acc += _B[m] * K[m, j]
                ynew[j] = y[j] + h * acc
            if mode & CREEPING:
                _creep(P, ynew, d, mode, K[_S])
            else:
                _rhs(P, ynew, d, mode, K[_S])
            continue
        for j in range(NY):
            acc = 0.0
            for m in range(i):
                acc += _AX[i, m] * K[m, j]
            tmp[j] = y[j] + h * acc
        if mode & CREEPING:
            _creep(P, tmp, d, mode, K[i])
        else:
            _rhs(P, tmp, d, mode, K[i])
    coefficients(y, ynew, h, K, F)


@njit(cache=True, nogil=True)
def coefficients(y, ynew, h, K, F):
    """The 7 coefficient rows F of the tableau's continuous extension (Hairer, Norsett and Wanner's dense output of
    DOP853) over a step of length h from y to ynew whose 16 stages are K (any state size)."""
    for j in range(y.size):
        dy = ynew[j] - y[j]
        F[0, j] = dy
        F[1, j] = h * K[0, j] - dy
        F[2, j] = 2.0 * dy - h * (K[_S, j] + K[0, j])
        for i in range(4):
            acc = 0.0
            for m in range(16):
                acc += _D[i, m] * K[m, j]
            F[3 + i, j] = h * acc


@njit("int64(float64[::1], float64[:, ::1], float64[::1], int64[::1], int64, float64, float64[::1], float64, int64)",
      cache=True, nogil=True)
def _put(gt, gy, gd, gf, n, t, y, d, mode):
    gt[n] = t
    for j in range(NY):
        gy[n, j] = y[j]
    gd[n] = d
    gf[n] = mode
    return n + 1


@njit("int64(float64[::1], float64[::1], float64, float64, int64, int64, boolean, float64, float64[::1], "
      "float64[:, ::1], float64[::1], int64[::1], int64, float64[:, ::1], float64[::1], float64[::1], "
      "float64[:, :, ::1], float64[:, ::1], float64[::1])", cache=True, nogil=True)
def _walk(P, y, span, d, mode, graded_start, graded_end, t, gt, gy, gd, gf, n, k, tmp, out, gF, K, ynew):
    """Advance y by span through its (graded) substeps, recording each substep's start after the first as a grid
    point and each substep's continuous extension (``gF`` at its start's index, the grid point n - 1 on entry for
    the first); the end state in out. Returns the grid's count."""
    fr = _fractions(P, graded_start, graded_end)
    a = y.copy()
    tt = t
    for i in range(fr.size):
        if i > 0:
            n = _put(gt, gy, gd, gf, n, tt, a, d, mode)
        _step(P, a, fr[i] * span, d, mode, k, tmp, out)
        _finish(P, a, fr[i] * span, d, mode, k, K, tmp, gF[n - 1], ynew)
        tt += fr[i] * span
        for j in range(NY):
            a[j] = out[j]
    return n


@njit(cache=True, nogil=True)
def integrate(P, y0, t_end, capacity, max_steps):
    """The free vibration from the state y0 at rest (t = 0) to t_end [s] (inf: until the sliders stick).

    Returns (grid_t, grid_y, grid_d, grid_flags, grid_dense, n, stop_time, status): the grid's times [s], states,
    the direction d of the piece each point starts a step of (0 at rest), the piece's mode (:data:`ELASTIC`,
    :data:`YIELDING`, :data:`LOADING`, plus :data:`CREEPING` on the slow manifold), the continuous extension's
    coefficients of the step each point starts (7 x NY, from the step's own stages: evaluating the record does not
    take the steps again), the count of points, the stop time (inf if it never sticks) and a status (0 done, 1 the
    grid's capacity is too small, 2 more than max_steps steps, 3 more than MAX_STALLED events in a row without
    progress).

    With a power-law damper the steps next to a reversal are graded towards it: the step after it from the
    reversal on, the one before it from the start of the step before the one that holds it (so that every
    plain step lies at least its own length away from where the velocity vanishes)."""
    gt = np.empty(capacity)
    gy = np.empty((capacity, NY))
    gd = np.empty(capacity)
    gf = np.empty(capacity, dtype=np.int64)
    gF = np.empty((capacity, 7, NY))  # each grid step's continuous extension (evaluate, motion)
    K = np.empty((16, NY))
    ynew = np.empty(NY)
    k = np.empty((_S, NY))
    tmp = np.empty(NY)
    a = np.empty(NY)
    out = np.empty(NY)
    y1 = np.empty(NY)
    r = np.empty(NY)
    y = y0.copy()
    t = 0.0
    n = 0
    stop = math.inf
    net = _net(P, y)
    creep = CREEP * math.sqrt(2.0 * _stored(P, y) / P[M])
    rest = _resist(P, creep)[0] if creep > 0.0 and P[ALPHA] < 1.0 and P[C] > 0.0 else 0.0  # a creep's end (EV_REST)
    if _held(P, net, creep):  # held where it was pushed
        n = _put(gt, gy, gd, gf, n, 0.0, y, 0.0, ELASTIC)
        return gt, gy, gd, gf, gF, n, 0.0, 0
    d = -1.0 if net > 0.0 else 1.0
    mode = _mode(P, y, d)
    if P[HKIND] == H_BOUCWEN and mode == YIELDING:
        y[2] = d
    powered = P[ALPHA] != 1.0
    stiff = P[ALPHA] < 1.0 and P[C] > 0.0  # a damper that can dominate the sliders at low speed
    graded = 1 if powered else 0  # the release starts at rest: graded like a reversal (FINE: after a crossing)
    h_plain = 0.0  # the piece's step after a FINE one
    hp = _step_size(P, y, d, mode)  # the piece's step
    h = _relax_step(P, y, d, mode, hp)[0] if stiff else hp
    steps = 0
    stalled = 0  # events in a row at the step's start (no progress)
    # the grid index, time and gradedness of the start of the step before the current one in this piece (-1: none)
    prev, t_prev, graded_prev = -1, 0.0, 0
    margin = 4 * GRADES + 8 + (2 * FINE_GRADES if P[N] < 1.0 else 0)  # the most grid points a step may take
    n = _put(gt, gy, gd, gf, n, t, y, d, mode)
    while True:
        if n + margin >= capacity:
            return gt, gy, gd, gf, gF, n, stop, 1
        steps += 1
        if steps > max_steps:
            return gt, gy, gd, gf, gF, n, stop, 2
        here = n - 1  # the grid point the step starts from (at t, state y)
        if graded:  # its substeps recorded at once (a grid point and an extension each); taken back where an
            # event falls in the step (the grid from here + 1 is written again from the event's walk)
            n = _walk(P, y, h, d, mode, graded, False, t, gt, gy, gd, gf, n, k, tmp, y1, gF, K, ynew)
        else:
            _step(P, y, h, d, mode, k, tmp, y1)
        # the first event in the step (if any)
        kind = EV_NONE
        theta = h
        if not (mode & CREEPING) and d * y1[1] <= 0.0:
            kind = EV_REVERSAL
        first = EV_NONE  # the first event other than a reversal (a yield, a saturation, z's zero crossing)
        base = mode & 3
        if ((P[HKIND] == H_PLASTIC and base == ELASTIC and d * y1[2] >= P[FP])
                or (P[HKIND] == H_BOUCWEN and base == LOADING and d * y1[2] >= 1.0 - SATURATION)):
            first = EV_YIELD
        if P[HKIND] == H_BOUCWEN and base == ELASTIC and (y1[2] == 0.0 or (y1[2] > 0.0) != (y[2] > 0.0)):
            first = EV_ZERO
        if first != EV_NONE:
            th = _locate(P, y, h, d, mode, first, graded, False, k, tmp, a, out, r, rest)
            if kind == EV_NONE or th < theta:
                kind, theta = first, th
        if mode & CREEPING and -d * _net(P, y1) <= rest:  # the creep ends in this step
            th = _locate(P, y, h, d, mode, EV_REST, graded, False, k, tmp, a, out, r, rest)
            if kind == EV_NONE or th < theta:
                kind, theta = EV_REST, th
        if kind == EV_REVERSAL:
            if powered and prev >= 0 and not graded:
                # graded from the start of the step before: back to that point
                th = _locate(P, gy[prev], t - t_prev + h, d, mode, EV_REVERSAL, graded_prev, True, k, tmp, a,
                             out, r, rest)
                reversal_at = t_prev + th
            else:
                th = _locate(P, y, h, d, mode, EV_REVERSAL, graded, powered, k, tmp, a, out, r, rest)
                reversal_at = t + th
            # a yield or zero crossing of z before it comes first
            if theta < h and t + theta < reversal_at:
                kind = first
            else:
                theta = th
        if kind == EV_NONE:
            if not graded:  # the step's stages are still in k (no event was located in it; a graded step's
                # substeps are recorded already)
                _finish(P, y, h, d, mode, k, K, tmp, gF[here], ynew)
            prev, t_prev, graded_prev = here, t, graded
            t += h
            for j in range(NY):
                y[j] = y1[j]
            if graded == FINE:  # back to the piece's steps
                h = h_plain
            graded = 0
            n = _put(gt, gy, gd, gf, n, t, y, d, mode)
            if d * y[1] < creep and abs(_net(P, y)) <= P[FSLOW] * (1.0 + 1e-9):
                # creeping into the sliders' holding limit (a velocity-strengthening friction, an overdamped
                # piece): the velocity only tends to 0; at rest once below CREEP of the release's scale
                y[1] = 0.0
                gy[n - 1, 1] = 0.0
                gd[n - 1] = 0.0
                stop = t
                break
            if stiff and not (mode & CREEPING):
                h, creeps, speed = _relax_step(P, y, d, mode, hp)
                if creeps:  # on the slow manifold: on it from here, on its own slow steps
                    mode |= CREEPING
                    y[1] = d * speed
                    gy[n - 1, 1] = y[1]
                    gf[n - 1] = mode
                    h = _creep_step(P, y, d, mode, hp)
            if t >= t_end:  # the horizon's step was the last
                break
            continue
        # the event's instant
        stalled = stalled + 1 if t + theta <= t else 0
        if stalled > MAX_STALLED:  # events without progress: a degenerate turn the tests above do not settle
            return gt, gy, gd, gf, gF, n, stop, 3
        n = here + 1  # (a graded step's substeps, recorded above, taken back)
        if kind == EV_REVERSAL and powered and prev >= 0 and not graded:
            n = prev + 1
            for j in range(NY):
                a[j] = gy[prev, j]
            n = _walk(P, a, theta, d, mode, graded_prev, True, t_prev, gt, gy, gd, gf, n, k, tmp, out, gF, K, ynew)
            t = t_prev + theta
        else:
            n = _walk(P, y, theta, d, mode, graded, kind == EV_REVERSAL and powered, t, gt, gy, gd, gf, n, k,
                      tmp, out, gF, K, ynew)
            t += theta
        for j in range(NY):
            y[j] = out[j]
        graded = 0
        creeping = mode & CREEPING
        if kind == EV_REST:  # the creep's speed down to CREEP of the release's: at rest (as _held)
            y[1] = 0.0
            stop = t
            n = _put(gt, gy, gd, gf, n, t, y, 0.0, mode)
            break
        if kind == EV_YIELD and P[HKIND] == H_PLASTIC:
            y[2] = d * P[FP]
            mode = YIELDING | creeping
        elif kind == EV_YIELD:  # the Bouc-Wen element saturates: on the post-yield stiffness's steps
            y[2] = d
            mode = YIELDING | creeping
            hp = _step_size(P, y, d, mode)
        elif kind == EV_ZERO:  # the Bouc-Wen element starts loading: on the transition's steps
            y[2] = 0.0
            mode = LOADING | creeping
            # |z|^n with a fractional n is not smooth where z leaves 0: the next step is graded from it
            # (n below 1, default steps: FINE)
            graded = FINE if P[N] < 1.0 and P[COARSE] <= 1.0 else (1 if P[N] != math.floor(P[N]) else 0)
            hp = _step_size(P, y, d, mode)
        else:  # a reversal: stick, or turn
            y[1] = 0.0
            net = _net(P, y)
            if _held(P, net, creep):
                stop = t
                n = _put(gt, gy, gd, gf, n, t, y, 0.0, mode)
                break
            d = -1.0 if net > 0.0 else 1.0
            mode = _mode(P, y, d)
            if P[HKIND] == H_BOUCWEN and mode == YIELDING:
                y[2] = d
            graded = 1 if powered else 0
            hp = _step_size(P, y, d, mode)
        if mode & CREEPING:
            h = _creep_step(P, y, d, mode, hp)
        else:
            h = _relax_step(P, y, d, mode, hp)[0] if stiff else hp
        if graded == FINE:
            h_plain = h
            h *= FINE_SPAN
        prev = -1
        n = _put(gt, gy, gd, gf, n, t, y, d, mode)
        if t >= t_end:
            break
    return gt, gy, gd, gf, gF, n, stop, 0


@njit(cache=True, nogil=True)
def evaluate(P, gt, gy, gd, gf, gF, n, stop, y_push, t):
    """The state (x, v, z and the three works) and the acceleration at times t [s] (any order; sorted is
    fastest): the continuous extension of the grid step that holds each time (``gF``, stored by the integration), the
    acceleration from the equation at that state; before the release the pushed state at rest, after the stop
    the last point at rest (the value after an instant where the acceleration jumps); past the last step of a
    motion that has not stopped, NaN (the horizon's step ends at or after the horizon)."""
    m = t.size
    ys = np.empty((m, NY))
    acc = np.empty(m)
    out = np.empty(NY)
    r = np.empty(NY)
    for i in range(m):
        ti = t[i]
        if ti < 0.0 or n == 1:
            src = y_push if ti < 0.0 else gy[0]
            for j in range(NY):
                ys[i, j] = src[j]
            acc[i] = 0.0
            continue
        if ti >= stop:
            for j in range(NY):
                ys[i, j] = gy[n - 1, j]
            acc[i] = 0.0
            continue
        if ti > gt[n - 1]:  # past the last step of a motion still moving there: not computed (its extension
            # would extrapolate, 0.5 m where the layer was at -0.014 m)
            for j in range(NY):
                ys[i, j] = math.nan
            acc[i] = math.nan
            continue
        p = np.searchsorted(gt[:n], ti, side="right") - 1
        if p >= n - 1:
            p = n - 2
        mode = gf[p]
        h = gt[p + 1] - gt[p]
        tau = ti - gt[p]
        if tau == 0.0 or h <= 0.0:
            for j in range(NY):
                out[j] = gy[p, j]
        else:
            F = gF[p]
            x = tau / h
            for j in range(NY):
                out[j] = 0.0
            for q in range(7):
                for j in range(NY):
                    out[j] += F[6 - q, j]
                    out[j] *= x if q % 2 == 0 else 1.0 - x
            for j in range(NY):
                out[j] += gy[p, j]
        _rhs_any(P, out, gd[p], mode, r)
        for j in range(NY):
            ys[i, j] = out[j]
        acc[i] = r[1]
    return ys, acc


@njit(cache=True, nogil=True)
def _accel(P, x, v, z, d):
    """The acceleration at a state [m/s^2] (the equation's second component alone)."""
    s = d * v
    if s < 0.0:
        s = 0.0
    rate = P[RATE]
    ff = P[FFAST] - (P[FFAST] - P[FSLOW]) * math.exp(-rate * s) if rate > 0.0 else P[FSLOW]
    alpha = P[ALPHA]
    fd = P[C] * s if alpha == 1.0 else (P[C] * s ** alpha if s > 0.0 else 0.0)
    fh = P[Q] * z if P[HKIND] == H_BOUCWEN else (z if P[HKIND] == H_PLASTIC else 0.0)
    return -(P[K] * x + fh + d * (ff + fd)) / P[M]


@njit(cache=True, nogil=True)
def motion(P, gt, gy, gd, gf, gF, n, stop, y_push, t):
    """x [m], x_dot [m/s] and x_ddot [m/s^2] at sorted times t [s]: what a record's channels need, as
    :func:`evaluate` gives them (the same continuous extension; NaN past the last step of a motion that has not
    stopped), without the works, the grid walked once."""
    m = t.size
    out = np.empty((3, m))
    ynew = np.empty(NY)
    p = 0
    for i in range(m):
        ti = t[i]
        if ti < 0.0 or n == 1:
            out[0, i] = y_push[0] if ti < 0.0 else gy[0, 0]
            out[1, i] = 0.0
            out[2, i] = 0.0
            continue
        if ti >= stop:
            out[0, i] = gy[n - 1, 0]
            out[1, i] = 0.0
            out[2, i] = 0.0
            continue
        if ti > gt[n - 1]:  # past the last step of a motion still moving there (as evaluate)
            out[0, i] = math.nan
            out[1, i] = math.nan
            out[2, i] = math.nan
            continue
        while p < n - 2 and gt[p + 1] <= ti:
            p += 1
        h = gt[p + 1] - gt[p]
        tau = ti - gt[p]
        if tau <= 0.0 or h <= 0.0:
            x, v, z = gy[p, 0], gy[p, 1], gy[p, 2]
        else:
            F = gF[p]
            u = tau / h
            w = 1.0 - u
            x = 0.0
            v = 0.0
            z = 0.0
            for q in range(7):
                x += F[6 - q, 0]
                v += F[6 - q, 1]
                z += F[6 - q, 2]
                f = u if q % 2 == 0 else w
                x *= f
                v *= f
                z *= f
            x += gy[p, 0]
            v += gy[p, 1]
            z += gy[p, 2]
        out[0, i] = x
        out[1, i] = v
        if gf[p] & CREEPING:  # the slow manifold's rate (as _creep's, without the works)
            ynew[0], ynew[1], ynew[2] = x, v, z
            speed, rate, _g1, _kt, _zx = _slow(P, ynew, gd[p], gf[p])
            out[2, i] = gd[p] * rate if speed > 0.0 else 0.0
        else:
            out[2, i] = _accel(P, x, v, z, gd[p])
    return out


@njit(cache=True, nogil=True)
def boucwen_push(n, dy, d0, steps):
    """z after a monotonic push from x = 0, z = 0 to |d0| [m] (dz/dx = (1 - z^n) / dy), with the tableau on
    ``steps`` equal steps in x; its sign is d0's. With n below 1 (z^n not smooth where z leaves 0) the first
    FINE_SPAN of those steps are one step on the mesh of ratio FINE_RATIO from 0 (as the integrator's step after
    z's zero crossing)."""
    h = abs(d0) / steps
    z = 0.0
    k = np.empty(_S)
    if n < 1.0:
        span = min(abs(d0), FINE_SPAN * h)
        for j in range(FINE_GRADES + 1):
            z = _push_step(n, dy, z, (FINE_RATIO ** -FINE_GRADES if j == 0 else
                                      FINE_RATIO ** -(FINE_GRADES - j) * (1.0 - 1.0 / FINE_RATIO)) * span, k)
        rest = abs(d0) - span
        steps = int(math.ceil(rest / h - 1e-9)) if rest > 0.0 else 0
        h = rest / steps if steps > 0 else 0.0
    for _ in range(steps):
        znew = _push_step(n, dy, z, h, k)
        if znew == z:  # saturated to rounding: the step (a function of z alone here) gives z again every time
            break
        z = znew
    return z if d0 > 0.0 else -z


@njit(cache=True, nogil=True)
def _push_step(n, dy, z, h, k):
    """One step of the tableau of length h in x on dz/dx = (1 - z^n) / dy (z >= 0); k is scratch."""
    for i in range(_S):
        acc = 0.0
        for m in range(i):
            acc += _A[i, m] * k[m]
        zz = z + h * acc
        k[i] = (1.0 - (zz if n == 1.0 else abs(zz) ** n)) / dy
    acc = 0.0
    for i in range(_S):
        acc += _B[i] * k[i]
    return z + h * acc


@njit(cache=True, nogil=True)
def boucwen_path(x, dy, n, z0):
    """The Bouc-Wen element's z along a prescribed displacement path x [m] (samples, in order), from z0 at
    x[0]: ``dy dz = dx (1 - |z|^n (sgn(dx z) + 1) / 2)`` (beta = gamma = 1/2, as the model): unloading
    (dx z < 0) exactly, z moving at the rate 1 to 0, and loading by the classical Runge-Kutta scheme in steps of
    at most 0.05 dy between samples. Returns z at each sample."""
    z = np.empty(x.size)
    zc = z0
    if x.size:
        z[0] = zc
    for i in range(1, x.size):
        du = (x[i] - x[i - 1]) / dy
        m = max(1, int(math.ceil(abs(du) / 0.05)))
        h = du / m
        for _ in range(m):
            step = h
            if step * zc < 0.0:  # unloading: z moves at the rate 1, exactly, to 0 and then loads
                if abs(step) <= abs(zc):
                    zc += step
                    continue
                step += zc
                zc = 0.0
            k1 = 1.0 - abs(zc) ** n
            z2 = zc + 0.5 * step * k1
            k2 = 1.0 - abs(z2) ** n
            z3 = zc + 0.5 * step * k2
            k3 = 1.0 - abs(z3) ** n
            z4 = zc + step * k3
            k4 = 1.0 - abs(z4) ** n
            zc += step * (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0
        z[i] = zc
    return z
