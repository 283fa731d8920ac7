"""The compiled integrator of a flexible superstructure on a hysteretic isolation layer (2-DOF; SI units).

Two degrees of freedom: the base (isolation layer) x_b and the roof x_s, the storey drift u = x_s - x_b:

    m_b x_b'' + F_iso(x_b, x_b', z) - c_s u' - k_s u = 0,     m_s x_s'' + c_s u' + k_s u = 0,

F_iso the layer's force of :mod:`quickrelease.building._ode` (spring, hysteretic element, sliders' friction with its
law, damper), evaluated by that module's own functions (:func:`quickrelease.building._ode._rhs` on the layer's part
of the state, with ``P[M] = m_b``; ``_net``, ``_mode``, ``_slope``, ``_stored``), the storey's force added here.
The integration is the rigid kernel's: the tableau of DOP853 on a fixed step per piece, every event located on the
tableau's own step map to machine precision (a bracketed Illinois iteration), no smoothed sign function. A piece
either slides (direction d = sign(x_b') = +-1, the element's mode as in ``_ode``) or is stuck (d = 0: the sliders
hold the base, ``x_b' = 0``, the roof vibrates on the fixed base). Events:

- sliding: the reversal (``d x_b' = 0``: the base sticks where the holding force ``G = k x_b + f_h - k_s u - c_s u'``
  is within the sliders' static limit, ``|G| <= f_slow``, else it turns, d = -sign(G)); the plastic element's
  yield, the Bouc-Wen element's saturation and zero crossing of z (as ``_ode``; where the shape n is not whole, the
  steps after the crossing graded as ``_ode``'s default steps, ``_ode._fractions``, each substep a plain step of
  its own). The base's velocity is not monotone between reversals here (the storey pushes and pulls it): a step
  where ``d x_b''`` turns from negative to positive has its minimum of ``d x_b'`` located, and a reversal looked
  for before it (so a dip to zero within a step is not missed);
- stuck: the re-slip, where ``|G|`` reaches ``f_slow`` (likewise with the maxima of ``|G|`` inside a step); the
  base is held for good where ``|k x_b + f_h| + E <= f_slow``, E the envelope of the storey's force
  ``k_s u + c_s u'`` on the fixed base (a damped oscillation: it never exceeds E again). From then on the roof
  rings on in closed form (:func:`_ringing`).

A power-law damper (``C |x_b'|^alpha``, alpha != 1) is solved as ``_ode`` solves it: a slide's first step graded
from its start and the steps to a reversal towards it (:func:`integrate`); a damper of alpha < 1, whose slope is
unbounded at rest, limits the steps by the base's relaxation time (:func:`_relax_step`) and, where it holds the
base on its slow manifold, the base creeps there (mode bit CREEPING, :func:`_slow`, :func:`_creep`): the
expansion of ``_ode._slow`` with the storey's drive (:func:`drive`), whose rate carries the roof's ringing. A slide
below the creep speed whose drive is within the dampers' margin is at rest (stuck; it slips again where the drive
leaves the margin, :func:`margin`). The works of the layer's friction, damper and hysteresis are the layer's
states of ``_ode``; the storey damper's work is one more state, so the energy balance closes to the integrator's
accuracy.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import _ode
from ._ode import (
    _A,
    _AX,
    _B,
    _S,
    ALPHA,
    BAND_TOL,
    COARSE,
    CREEP_RATIO,
    CREEP_TOL,
    CREEPING,
    DY,
    FFAST,
    FINE,
    FINE_SPAN,
    FP,
    FSLOW,
    H_BOUCWEN,
    H_PLASTIC,
    HKIND,
    KP,
    LOADING,
    RATE,
    SATURATION,
    STEP_CREEP,
    STEP_RELAX,
    STEP_STABLE,
    STEPS_PERIOD,
    STEPS_RATE,
    STEPS_TRANSITION,
    YIELDING,
    C,
    K,
    M,
    N,
    Q,
)

#: The state: the layer's six of :mod:`~quickrelease.building._ode` (x_b, x_b', z and the works of friction,
#: damper and hysteresis [J]), then x_s [m], x_s' [m/s] and the storey damper's work [J].
NY = 9
XS, VS, WS = 6, 7, 8
#: The storey's vector: m_s [kg], k_s [N/m], c_s [N s/m]; inside :func:`integrate` two more slots, the holding
#: limit f_slow + :func:`margin` [N] and the drive at which a creep ends (:data:`EV_REST`) [N].
MS, KS, CS, LIMIT, REST = 0, 1, 2, 3, 4
#: Events: none, a reversal, a yield (saturation), z's zero crossing, the re-slip of a stuck base; the two
#: extrema looked for inside a step (the base's slowest speed, the holding force's largest magnitude); the re-slip
#: of a base stuck within the holding margin (|G| above f_slow, not above f_slow + :func:`margin`: where |G| leaves
#: the margin).
EV_NONE, EV_REVERSAL, EV_YIELD, EV_ZERO, EV_SLIP, EV_DIP, EV_PEAK, EV_SLIP_MARGIN = 0, 2, 3, 4, 7, 8, 9, 10
#: The end of a creep on the slow manifold: the drive (:func:`drive`) falls to ``S[REST]``, inside the holding
#: limit (the base at rest there, as the rigid kernel's ``_ode.EV_REST``).
EV_REST = 11
#: A creeping piece leaves the slow manifold (back to explicit steps) where its relaxation is no longer this many
#: times faster than the motions that move it (CREEP_RATIO on entry: the two apart, so that a piece at the
#: threshold does not enter and leave at every step); the neglected terms (1 / CREEP_EXIT)^6 = 1.6e-8 of the speed.
CREEP_EXIT = CREEP_RATIO / 1.5
#: A slide whose speed falls below this fraction of the release's scale is at rest for good where the sliders hold it
#: there against the roof's ringing too (the rigid kernel's creep into the holding limit).
CREEP = _ode.CREEP
#: Most events in a row without a plain step between them (a base that chatters without end: status 3).
MAX_CHAIN = 10_000


@njit(cache=True, nogil=True)
def holding(P, S, y):
    """The force the sliders must resist to hold the base, ``G = k x_b + f_h - k_s u - c_s u'`` [N]."""
    return _ode._net(P, y) - S[KS] * (y[XS] - y[0]) - S[CS] * (y[VS] - y[1])


@njit(cache=True, nogil=True)
def drive(P, S, y, d):
    """The force that drives a sliding base on in its direction d, less the storey damper's part that the base's
    own speed makes [N]: ``push = -d (k x_b + f_h) + d (k_s u + c_s x_s')``. The base's equation along d is
    ``m_b s' = push - G(s)``, s = d x_b' and ``G(s) = f_f(s) + C s^alpha + c_s s`` (the sliders, the layer's damper
    and the storey's damper, which the base drags)."""
    return -d * _ode._net(P, y) + d * (S[KS] * (y[XS] - y[0]) + S[CS] * y[VS])


@njit(cache=True, nogil=True)
def _resist(P, S, s):
    """``G(s) = g(s) + c_s s`` (:func:`quickrelease.building._ode._resist`'s g) and its first two derivatives."""
    g, g1, g2 = _ode._resist(P, s)
    return g + S[CS] * s, g1 + S[CS], g2


@njit(cache=True, nogil=True)
def _slow(P, S, y, d, mode):
    """The slow manifold of a sliding base whose dampers dominate (:func:`quickrelease.building._ode._slow` with the
    storey): returns (S, dS/dt, G'(S0), eps), the speed S = S0 + S1 + S2 [m/s], its rate [m/s^2], the
    resistance's slope [N s/m] and the expansion's small parameter.

    From ``m_b dS/dt = push - G(S)`` (:func:`drive`) and ``dpush/dt = A - B S`` (A = d (k_s x_s' - c_s (k_s u +
    c_s x_s') / m_s) the roof's part, B = k_t + k_s - c_s^2 / m_s; the roof ``m_s x_s'' = -(k_s u + c_s u')``):
    S0 the quasi-static speed (G(S0) = push, ``_ode._quasi`` with c_s), S1 = -m_b push' / G'^2 its first correction for
    inertia, S2 = (m_b B S1 / G' - m_b dS1/dt - G'' S1^2 / 2) / G' the second (dS1/dt with push'' = A' - k_t' S0 -
    B dS0/dt at first order); ``eps = m_b (|A| + |B| S0) / (G'^2 S0)``, the relaxation time m_b / G' over the
    time in which S0 changes by itself (the rigid kernel's (omega / lambda)^2 where A = 0), the neglected terms
    eps^3 of S. Without the storey (k_s = c_s = 0) the rigid kernel's expansion, term by term. Where the roof's
    part A does not vanish with S0 (a ringing roof that drives the base), eps grows without bound as S0 falls for
    alpha > 1/2 (``eps ~ S0^(1 - 2 alpha)``): the expansion holds only where eps is small, which the callers
    check."""
    ms, ks, cs = S[MS], S[KS], S[CS]
    zx, kt = _ode._slope(P, y[2], mode)
    u, vs = y[XS] - y[0], y[VS]
    s0 = _ode._quasi(P, drive(P, S, y, d), S[CS])
    if not (0.0 < s0 < math.inf):
        return 0.0, 0.0, 0.0, math.inf
    m = P[M]
    _g, g1, g2 = _resist(P, S, s0)
    a = d * (ks * vs - cs * (ks * u + cs * vs) / ms)
    b = kt + ks - cs * cs / ms
    p1 = a - b * s0
    ds0 = p1 / g1
    s1 = -m * p1 / g1 / g1
    dkt = _ode._stiffening(P, y, d, mode, s0, zx)
    du = vs - d * s0
    dvs = -(ks * u + cs * du) / ms
    da = d * (ks * dvs - cs * (ks * du + cs * dvs) / ms)
    p2 = da - dkt * s0 - b * ds0
    ds1 = -m * p2 / g1 / g1 + 2.0 * m * p1 * g2 * ds0 / g1 / g1 / g1
    s2 = (m * b * s1 / g1 - m * ds1 - 0.5 * g2 * s1 * s1) / g1
    sp = s0 + s1 + s2
    eps = m * (abs(a) + abs(b) * s0) / (g1 * g1 * s0)
    return sp, (a - b * sp) / g1 + ds1, g1, eps


@njit(cache=True, nogil=True)
def _creep(P, S, y, d, mode, out):
    """The right-hand side on the slow manifold (:func:`_slow`): the base moves at its speed S, the velocity's state
    at its rate, z and the works with it; the roof on the storey."""
    for j in range(NY):
        out[j] = 0.0
    sp, ds, _g1, _eps = _slow(P, S, y, d, mode)
    v = 0.0
    if sp > 0.0:
        v = d * sp
        out[0] = v
        out[1] = d * ds
        out[2] = v * _ode._slope(P, y[2], mode)[0]
        _ode._creep_works(P, y, mode, sp, v, out)
    du = y[VS] - v
    out[XS] = y[VS]
    out[VS] = -(S[KS] * (y[XS] - y[0]) + S[CS] * du) / S[MS]
    out[WS] = S[CS] * du * du


@njit(cache=True, nogil=True)
def _rhs(P, S, y, d, mode, out):
    """The right-hand side: the layer's of ``_ode`` plus the storey's force on the base (sliding, d = +-1), the base
    at rest (stuck, d = 0); the roof on the storey. On the slow manifold (mode bit CREEPING): :func:`_creep`."""
    if mode & CREEPING:
        _creep(P, S, y, d, mode, out)
        return
    fs = S[KS] * (y[XS] - y[0]) + S[CS] * (y[VS] - y[1])
    if d == 0.0:
        for j in range(6):
            out[j] = 0.0
    else:
        _ode._rhs(P, y[:6], d, mode, out[:6])
        out[1] += fs / P[M]
    out[XS] = y[VS]
    out[VS] = -fs / S[MS]
    du = y[VS] - y[1]
    out[WS] = S[CS] * du * du


@njit(cache=True, nogil=True)
def _step(P, S, y, h, d, mode, k, tmp, out):
    """One step of length h of the tableau from y (stages in k, scratch tmp) into out."""
    for i in range(_S):
        for j in range(NY):
            acc = 0.0
            for m in range(i):
                acc += _A[i, m] * k[m, j]
            tmp[j] = y[j] + h * acc
        _rhs(P, S, tmp, d, mode, k[i])
    for j in range(NY):
        acc = 0.0
        for i in range(_S):
            acc += _B[i] * k[i, j]
        out[j] = y[j] + h * acc


@njit(cache=True, nogil=True)
def _value(P, S, y, kind, d, r):
    """The event's function at y, positive before the event (r: scratch for the right-hand side)."""
    if kind == EV_REVERSAL:
        return d * y[1]
    if kind == EV_YIELD:
        return (1.0 - SATURATION if P[HKIND] == H_BOUCWEN else P[FP]) - d * y[2]
    if kind == EV_ZERO:
        return y[2]
    if kind == EV_SLIP:
        return P[FSLOW] - abs(holding(P, S, y))
    if kind == EV_SLIP_MARGIN:
        return S[LIMIT] - abs(holding(P, S, y))
    if kind == EV_REST:
        return drive(P, S, y, d) - S[REST]
    # EV_PEAK: |G| still growing: sign(G) G', G' = -(k_s u' + c_s u'') on the fixed base
    _rhs(P, S, y, 0.0, 0, r)
    g = holding(P, S, y)
    dg = -(S[KS] * (y[VS] - y[1]) + S[CS] * r[VS])
    return dg if g > 0.0 else -dg


@njit(cache=True, nogil=True)
def _advance(P, S, y, h, d, mode, fr, k, tmp, a, out):
    """y advanced by h through substeps of the fractions ``fr`` of it (one: a plain step) into out; a is scratch."""
    if fr.size == 1:
        _step(P, S, y, h, d, mode, k, tmp, out)
        return
    for j in range(NY):
        a[j] = y[j]
    for f in fr:
        _step(P, S, a, f * h, d, mode, k, tmp, out)
        for j in range(NY):
            a[j] = out[j]


@njit(cache=True, nogil=True)
def _walk(P, S, y, h, d, mode, fr, t, gt, gy, gd, gf, n, k, tmp, a, out):
    """:func:`_advance`, each substep's start after the first recorded as a grid point (the first is the grid point
    n - 1); the end state in out. Returns the grid's count."""
    for j in range(NY):
        a[j] = y[j]
    tt = t
    for i in range(fr.size):
        if i > 0:
            n = _put(gt, gy, gd, gf, n, tt, a, d, mode)
        _step(P, S, a, fr[i] * h, d, mode, k, tmp, out)
        tt += fr[i] * h
        for j in range(NY):
            a[j] = out[j]
    return n


@njit(cache=True, nogil=True)
def _locate(P, S, y, h, d, mode, kind, sign, fr, k, tmp, a, out, r):
    """The instant theta in (0, h] where the event's function (:func:`_value`, times ``sign``) falls from >= 0 at
    the step's start to <= 0 at its end, on the tableau's map (through the substeps ``fr``, :func:`_advance`), by
    the Illinois iteration to machine precision; the state there in out. (EV_DIP's function is evaluated in the
    piece's own mode.)"""
    lo, hi = 0.0, h
    flo = sign * _value_in(P, S, y, kind, d, mode, r)
    _advance(P, S, y, h, d, mode, fr, k, tmp, a, out)
    fhi = sign * _value_in(P, S, out, kind, d, mode, r)
    if flo < 0.0:
        flo = 0.0
    side = 0
    for _ in range(200):
        if flo > 0.0 and fhi < 0.0:
            theta = lo + (hi - lo) * flo / (flo - fhi)
        else:
            theta = 0.5 * (lo + hi)
        if not (lo < theta < hi):
            theta = 0.5 * (lo + hi)
        if not (lo < theta < hi):
            break
        _advance(P, S, y, theta, d, mode, fr, k, tmp, a, out)
        f = sign * _value_in(P, S, out, kind, d, mode, r)
        if f > 0.0:
            lo, flo = theta, f
            if side == 1:
                fhi *= 0.5
            side = 1
        elif f < 0.0:
            hi, fhi = theta, f
            if side == -1:
                flo *= 0.5
            side = -1
        else:
            return theta
        if hi - lo <= 4e-16 * hi:
            break
    _advance(P, S, y, hi, d, mode, fr, k, tmp, a, out)
    return hi


@njit(cache=True, nogil=True)
def _value_in(P, S, y, kind, d, mode, r):
    """:func:`_value`, EV_DIP's in the piece's mode."""
    if kind == EV_DIP:
        _rhs(P, S, y, d, mode, r)
        return -d * r[1]
    return _value(P, S, y, kind, d, r)


@njit(cache=True, nogil=True)
def _energy(P, S, y):
    """The mechanical energy [J]: both masses' kinetic, the layer's stored and the storey spring's."""
    u = y[XS] - y[0]
    return (0.5 * P[M] * y[1] * y[1] + 0.5 * S[MS] * y[VS] * y[VS] + _ode._stored(P, y)
            + 0.5 * S[KS] * u * u)


@njit(cache=True, nogil=True)
def _step_size(P, S, y, d, mode):
    """The piece's step [s]: STEPS_PERIOD a period of the faster mode of the two masses on the layer's initial (or
    post-yield, saturated) stiffness and the storey's (the roof's on the fixed base while stuck); over the Bouc-Wen
    transition as ``_ode._step_size``, with the storey's force in the bound on the base's acceleration and the whole
    energy in the bound on its speed. (The friction law's velocity scale bounds each step of a slide by the base's
    own acceleration there: :func:`_rate_step`.) Times ``P[COARSE]`` where that is above 1 (as ``_ode``'s)."""
    ms, ks, cs = S[MS], S[KS], S[CS]
    coarse = max(P[COARSE], 1.0)
    if d == 0.0:
        return 2.0 * math.pi * math.sqrt(ms / ks) * coarse / STEPS_PERIOD
    mb = P[M]
    base = mode & 3
    k1 = P[K]
    if P[HKIND] == H_BOUCWEN and base != YIELDING:
        k1 += P[Q] / P[DY]
    elif P[HKIND] == H_PLASTIC:
        k1 += P[KP]
    a11, a22 = (k1 + ks) / mb, ks / ms
    half = 0.5 * (a11 + a22)
    lam = half + math.sqrt(max(half * half - k1 * ks / (mb * ms), 0.0))
    h = 2.0 * math.pi / math.sqrt(lam) * coarse / STEPS_PERIOD
    energy = _energy(P, S, y)
    vmax = math.sqrt(2.0 * energy / mb)
    xmax = math.sqrt(2.0 * energy / P[K])
    storey = math.sqrt(2.0 * ks * energy) + cs * (vmax + math.sqrt(2.0 * energy / ms))
    amax = (P[K] * xmax + P[Q] + P[FP] + max(P[FFAST], P[FSLOW]) + storey) / mb + 1e-300
    if P[HKIND] == H_BOUCWEN and base == LOADING and vmax > 0.0:
        reach = P[DY] * (1.0 - d * y[2] + math.log(1.0 / SATURATION) / P[N])
        v = min(vmax, math.sqrt(y[1] * y[1] + 2.0 * (amax + P[C] * vmax ** P[ALPHA] / mb) * reach))
        h = min(h, coarse * P[DY] / (max(P[N], 1.0) * v * STEPS_TRANSITION))
    return h


#: Safety factor on the base's acceleration in the friction law's step (:func:`_rate_step`).
RATE_SAFETY = 1.5


@njit(cache=True, nogil=True)
def _rate_step(P, accel):
    """The step [s] that resolves the friction law's velocity scale 1 / a (Constantinou's rate) at the base's
    acceleration ``accel`` [m/s^2]: ``1 / (a RATE_SAFETY accel STEPS_RATE)``, the speed changing by at most
    ``1 / (RATE_SAFETY STEPS_RATE)`` of the scale a step. The integrator takes the larger of the accelerations at
    the step's start and end (the step is taken again, shorter, where the end's exceeds the start's bound): the
    base's actual acceleration, not a bound from the energy (whose storey term, sqrt(2 k_s E) over m_b, was 20
    times a pendulum's actual acceleration under a 0.6 s storey and cost it 18 times the steps). Times
    ``P[COARSE]`` where that is above 1."""
    return max(P[COARSE], 1.0) / (P[RATE] * (RATE_SAFETY * accel + 1e-300) * STEPS_RATE)


@njit(cache=True, nogil=True)
def envelope(S, u, du):
    """The largest magnitude the storey's force ``k_s u + c_s u'`` [N] reaches from now on while the base is held
    (the roof a damped oscillator on the fixed base, zeta_s < 1): ``E = sqrt(h0^2 + ((h0' + a h0) / w)^2)``."""
    ms, ks, cs = S[MS], S[KS], S[CS]
    a = cs / (2.0 * ms)
    w = math.sqrt(ks / ms - a * a)
    h0 = ks * u + cs * du
    dh0 = ks * du - cs * h0 / ms
    return math.sqrt(h0 * h0 + ((dh0 + a * h0) / w) ** 2)


@njit(cache=True, nogil=True)
def margin(P, creep):
    """The excess of the holding force's magnitude over the sliders' static limit f_slow [N] within which the base
    is at rest: at most ``1e-9 f_slow`` (where a slide creeping below ``creep`` [m/s] is stuck, the rounding of
    the holding force), and where the friction grows with the speed (Constantinou's law) or a viscous damper acts,
    the excess whose quasi-static creep speed ``excess / g'(0)`` is below ``creep`` (the rigid kernel's
    :func:`quickrelease.building._ode._held`: ``excess < slope creep`` and ``rate excess < 0.1 slope``).

    Without it a base stuck at its holding limit to rounding (a pendulum crept there under a velocity-strengthening
    friction, the roof's ringing damped out, |G| - f_slow of 1e-16 of f_slow) slipped at every step of the stuck
    piece, turned at once and stuck again: two events and a located instant each 3 ms, to the horizon (13 000 of
    each in a 60 s record, 2.2 s an evaluation against 0.6 ms; the flexible pendulum fit spent 130 of its 145 s
    there)."""
    tol = 1e-9 * P[FSLOW]
    slope = _ode._creep_slope(P)
    if slope > 0.0:
        creeping = slope * creep
        if P[RATE] > 0.0:
            creeping = min(creeping, 0.1 * slope / P[RATE])
        tol = max(tol, creeping)
    if P[ALPHA] < 1.0 and P[C] > 0.0:  # a power-law damper of alpha < 1 balances an excess C s^alpha at speed s
        tol = max(tol, P[C] * creep ** P[ALPHA])
    return tol


@njit(cache=True, nogil=True)
def _relax_step(P, S, y, d, mode, h):
    """The step [s] of a sliding base that a damper of alpha < 1 may dominate (:func:`quickrelease.building._ode.
    _relax_step` with the storey): where the drive exceeds the sliders' static limit (push > f_slow,
    :func:`drive`), at most STEP_RELAX of the base's relaxation time m_b / G'(s) at its speed s (at S0 from rest)
    while the speed relaxes, STEP_STABLE once within BAND_TOL of the slow manifold, and the speed at most halved in
    a step while it slows down onto it; h otherwise. Returns (step, creep, S): whether the piece may creep (the
    expansion's eps of :func:`_slow` at most 1 / CREEP_RATIO^2, the relaxation CREEP_RATIO times faster than the
    roof's own oscillation too, and the speed within CREEP_TOL of the manifold's S)."""
    push = drive(P, S, y, d)
    if push <= P[FSLOW]:
        return h, False, 0.0
    sp, _ds, g1, eps = _slow(P, S, y, d, mode)
    if not (0.0 < g1 < math.inf and sp > 0.0):
        return h, False, 0.0
    m = P[M]
    s = d * y[1]
    off = abs(s - sp)
    if (eps * CREEP_RATIO * CREEP_RATIO <= 1.0 and g1 * g1 * S[MS] >= CREEP_RATIO * CREEP_RATIO * S[KS] * m * m
            and off <= CREEP_TOL * sp):
        return h, True, sp
    if s > 0.0:
        g, g1, _g2 = _resist(P, S, s)
        if not (0.0 < g1 < math.inf):
            return h, False, 0.0
        if g > push:
            h = min(h, 0.5 * s * m / (g - push))
    return min(h, (STEP_STABLE if off <= BAND_TOL * sp else STEP_RELAX) * m / g1), False, 0.0


@njit(cache=True, nogil=True)
def _creep_step(P, S, y, d, mode, h):
    """The step [s] of a creeping piece, or -1 where it must leave the slow manifold (its eps above
    1 / CREEP_EXIT^2, or its relaxation less than CREEP_EXIT times the roof's frequency; the drive at the sliders'
    limit): STEP_CREEP of its slow time ``G' S0 / (|A| + |B| S0)`` (:func:`_slow`), at most a STEPS_PERIOD-th of
    the roof's period on the fixed base and (the Bouc-Wen element loading) the transition's steps at the creep's
    speed, and at least the piece's step h."""
    sp, _ds, g1, eps = _slow(P, S, y, d, mode)
    m = P[M]
    if (not (sp > 0.0 and 0.0 < g1 < math.inf) or eps * CREEP_EXIT * CREEP_EXIT > 1.0
            or g1 * g1 * S[MS] < CREEP_EXIT * CREEP_EXIT * S[KS] * m * m):
        return -1.0
    coarse = max(P[COARSE], 1.0)
    hc = STEP_CREEP * m / (g1 * eps)  # (the slow time is m_b / (G' eps))
    hc = min(hc, 2.0 * math.pi * math.sqrt(S[MS] / S[KS]) * coarse / STEPS_PERIOD)
    if P[HKIND] == H_BOUCWEN and (mode & 3) == LOADING:
        hc = min(hc, coarse * P[DY] / (max(P[N], 1.0) * sp * STEPS_TRANSITION))
    return max(h, hc)


@njit(cache=True, nogil=True)
def held(P, S, y, limit):
    """Whether the stuck base at y is held for good: ``|k x_b + f_h| + E <= limit`` (:func:`envelope`; ``limit``
    f_slow plus the holding :func:`margin` [N])."""
    return abs(_ode._net(P, y)) + envelope(S, y[XS] - y[0], y[VS] - y[1]) <= limit


@njit(cache=True, nogil=True)
def _put(gt, gy, gd, gf, n, t, y, d, mode):
    gt[n] = t
    for j in range(NY):
        gy[n, j] = y[j]
    gd[n] = d
    gf[n] = mode
    return n + 1


@njit(cache=True, nogil=True)
def _grown(gt, gy, gd, gf, n, capacity):
    """The grid's arrays with room for ``capacity`` points, their first n copied."""
    t2 = np.empty(capacity)
    y2 = np.empty((capacity, NY))
    d2 = np.empty(capacity)
    f2 = np.empty(capacity, dtype=np.int64)
    t2[:n] = gt[:n]
    y2[:n] = gy[:n]
    d2[:n] = gd[:n]
    f2[:n] = gf[:n]
    return t2, y2, d2, f2


@njit(cache=True, nogil=True)
def _start(P, S, y, slip, limit):
    """The direction (0: stuck) and mode of a piece starting at y with the base at rest (``slip``: at a re-slip,
    where |G| has reached the limit: it slides; else stuck where ``|G| <= limit``, f_slow plus the holding
    :func:`margin`); the base's velocity and a saturated Bouc-Wen element's z set."""
    y[1] = 0.0
    g = holding(P, S, y)
    if abs(g) <= limit and not slip:
        return 0.0, 0
    d = -1.0 if g > 0.0 else 1.0
    mode = _ode._mode(P, y, d)
    if P[HKIND] == H_BOUCWEN and mode == YIELDING:
        y[2] = d
    return d, mode


@njit(cache=True, nogil=True)
def integrate(P, S, y0, t_end, capacity, max_steps):
    """The free vibration from the state y0 at rest (t = 0) to t_end [s] (inf: until the base is held for good).

    Returns (grid_t, grid_y, grid_d, grid_flags, n, stop_time, status) as ``_ode.integrate``: d = 0 marks a stuck
    piece; stop_time is when the base is held for good (inf: not within the horizon); status 0 done, 2 more than
    max_steps steps, 3 more than MAX_CHAIN events in a row. The grid starts with room for ``capacity`` points and
    grows fourfold as it fills (:func:`_grown`; the integration was run again from the start with four times the
    room, which cost a 60 s motion under a stiff storey, 88 000 points from 4 096, twice its steps).

    With a power-law damper (alpha != 1) a slide's first step is graded from its start and the steps to a reversal
    towards it (``_ode._fractions``; a step's substeps are grid points of their own): a reversal found in a step is
    located again on the substeps graded from the start of the step before (or of the slide's graded first step),
    so that every plain step lies at least its own length away from where the base's speed vanishes. A damper of
    alpha < 1 limits the steps by the base's relaxation (:func:`_relax_step`) and, where it holds the base on its
    slow manifold, the base creeps (:func:`_creep`) until the drive falls to ``S[REST]`` (:data:`EV_REST`: at rest
    there, within the holding limit), a yield or z's zero crossing, or the manifold no longer holds
    (:func:`_creep_step`)."""
    gt = np.empty(capacity)
    gy = np.empty((capacity, NY))
    gd = np.empty(capacity)
    gf = np.empty(capacity, dtype=np.int64)
    k = np.empty((_S, NY))
    tmp = np.empty(NY)
    a = np.empty(NY)
    out = np.empty(NY)
    y1 = np.empty(NY)
    ym = np.empty(NY)
    yb = np.empty(NY)
    r = np.empty(NY)
    r0 = np.empty(NY)  # the right-hand side at y (known0) and at y1 (known1), each computed once
    r1 = np.empty(NY)
    one = np.ones(1)
    fr = one
    known0 = known1 = False
    y = y0.copy()
    t = 0.0
    n = 0
    stop = math.inf
    creep = CREEP * math.sqrt(2.0 * _energy(P, S, y) / (P[M] + S[MS]))
    limit = P[FSLOW] + margin(P, creep)  # the holding limit: stuck within it, re-slips beyond it
    S = np.array([S[MS], S[KS], S[CS], limit, P[FSLOW] + 0.5 * (limit - P[FSLOW])])
    rated = P[RATE] > 0.0 and P[FFAST] != P[FSLOW]
    powered = P[ALPHA] != 1.0
    stiff = P[ALPHA] < 1.0 and P[C] > 0.0  # a damper that can dominate the sliders at low speed
    a0 = 0.0
    d, mode = _start(P, S, y, False, limit)
    if d == 0.0 and held(P, S, y, limit):
        n = _put(gt, gy, gd, gf, n, 0.0, y, 0.0, 0)
        return gt, gy, gd, gf, n, 0.0, 0
    hp = _step_size(P, S, y, d, mode)
    hs = _relax_step(P, S, y, d, mode, hp)[0] if stiff and d != 0.0 else hp  # the plain steps' length
    fresh = True  # the first step of a slide that starts at rest (its d x_b'' starts at 0)
    # the graded substeps of a slide's first step (a power-law damper) and after z's zero crossing with a fractional
    # n (``_ode``'s meshes: ratio 2 where n > 1, FINE where n < 1), each a plain step of its own; queue[iq:nq] the
    # lengths still to take [s]
    queue = np.empty(2 * (_ode.FINE_GRADES + _ode.GRADES + 2))
    iq, nq = 0, 0
    if d != 0.0 and powered:
        g = _ode._fractions(P, 1, False)
        nq = g.size
        for i in range(nq):
            queue[i] = g[i] * hs
    # the grid index, time and grading (``_ode._fractions``' graded_start) of the current (graded or plain) step's
    # start and of the one before it in this piece (-1: none)
    cur_i, cur_t, cur_g = 0, 0.0, (1 if nq > 0 else 0)
    prev_i, prev_t, prev_g = -1, 0.0, 0
    room = 2 * (_ode.FINE_GRADES + _ode.GRADES + 2) + 8
    steps = 0
    chain = 0  # events since the last plain step
    n = _put(gt, gy, gd, gf, n, t, y, d, mode)
    while True:
        if n + room >= capacity:
            capacity *= 4
            gt, gy, gd, gf = _grown(gt, gy, gd, gf, n, capacity)
        steps += 1
        if steps > max_steps:
            return gt, gy, gd, gf, n, stop, 2
        h = hs if iq == nq else queue[iq]
        creeping = mode & CREEPING
        if d != 0.0 and rated:  # the friction law's velocity scale, from the base's acceleration over the step
            if not known0:
                _rhs(P, S, y, d, mode, r0)
                known0 = True
            a0 = abs(r0[1])
            h = min(h, _rate_step(P, a0))
        _step(P, S, y, h, d, mode, k, tmp, y1)
        known1 = False
        if d != 0.0 and rated:
            for _ in range(8):  # the acceleration grew over the step past its start's bound: the step again, shorter
                _rhs(P, S, y1, d, mode, r1)
                known1 = True
                a0 = max(a0, abs(r1[1]))
                if h <= _rate_step(P, a0):
                    break
                h = _rate_step(P, a0)
                _step(P, S, y, h, d, mode, k, tmp, y1)
                known1 = False
        kind = EV_NONE
        theta = h
        walk = False  # the event's step taken again on graded substeps from yb at t_b (grid point i_b)
        i_b, t_b = 0, 0.0
        if d != 0.0:
            if not creeping:
                if d * y1[1] <= 0.0:
                    kind = EV_REVERSAL
                elif not fresh:  # a dip of the speed to zero inside the step
                    if not known0:
                        _rhs(P, S, y, d, mode, r0)
                        known0 = True
                    a0 = d * r0[1]
                    if not known1:
                        _rhs(P, S, y1, d, mode, r1)
                        known1 = True
                    if a0 < 0.0 and d * r1[1] > 0.0:
                        tm = _locate(P, S, y, h, d, mode, EV_DIP, 1.0, one, k, tmp, a, ym, r)
                        if d * ym[1] <= 0.0:
                            kind, theta = EV_REVERSAL, tm
            if kind == EV_REVERSAL:
                if powered:  # located on substeps graded towards it, from the start of the step before
                    if iq < nq or prev_i < 0:
                        i_b, t_b, gs = cur_i, cur_t, cur_g
                    else:
                        i_b, t_b, gs = prev_i, prev_t, prev_g
                    fr = _ode._fractions(P, gs, True)
                    for j in range(NY):
                        yb[j] = gy[i_b, j]
                    _advance(P, S, yb, t + theta - t_b, d, mode, fr, k, tmp, a, out)
                    walk = d * out[1] <= 0.0  # (else, a dip that the graded map does not reach: as before)
                if walk:
                    theta = _locate(P, S, yb, t + theta - t_b, d, mode, EV_REVERSAL, 1.0, fr, k, tmp, a, out, r)
                    theta += t_b - t  # (the event's instant from this step's start)
                else:
                    theta = _locate(P, S, y, theta, d, mode, EV_REVERSAL, 1.0, one, k, tmp, a, out, r)
            base = mode & 3
            ev = EV_NONE
            if ((P[HKIND] == H_PLASTIC and base == 0 and d * y1[2] >= P[FP])
                    or (P[HKIND] == H_BOUCWEN and base == LOADING and d * y1[2] >= 1.0 - SATURATION)):
                ev = EV_YIELD
            if P[HKIND] == H_BOUCWEN and base == 0 and (y1[2] == 0.0 or (y1[2] > 0.0) != (y[2] > 0.0)):
                ev = EV_ZERO
            if creeping and ev == EV_NONE and drive(P, S, y1, d) <= S[REST]:
                ev = EV_REST
            if ev != EV_NONE:
                th = _locate(P, S, y, h, d, mode, ev, 1.0 if ev != EV_ZERO or y[2] > 0.0 else -1.0, one, k, tmp, a,
                             ym, r)
                if kind == EV_NONE or th < theta:
                    kind, theta, walk = ev, th, False
                    for j in range(NY):
                        out[j] = ym[j]
        else:
            # a re-slip where |G| passes the holding limit; located where it passes f_slow (the physical onset),
            # or the limit where the piece starts within the margin (stuck above f_slow)
            if limit - abs(holding(P, S, y1)) < 0.0:
                kind = EV_SLIP
            else:  # a peak of |G| past the limit inside the step
                if _value(P, S, y, EV_PEAK, 0.0, r) > 0.0 and _value(P, S, y1, EV_PEAK, 0.0, r) < 0.0:
                    tm = _locate(P, S, y, h, d, mode, EV_PEAK, 1.0, one, k, tmp, a, ym, r)
                    if limit - abs(holding(P, S, ym)) < 0.0:
                        kind, theta = EV_SLIP, tm
            if kind == EV_SLIP:
                # (a damper of alpha < 1 moves the base at below the creep's speed inside the margin, its slope
                # unbounded at rest: the slide starts where the drive leaves the margin)
                onset = EV_SLIP if abs(holding(P, S, y)) <= P[FSLOW] and not stiff else EV_SLIP_MARGIN
                theta = _locate(P, S, y, theta, d, mode, onset, 1.0, one, k, tmp, a, out, r)
        if kind == EV_NONE:
            chain = 0
            grouped = iq < nq
            if grouped:  # a graded substep taken (the rest of it next, where the friction law shortened it)
                if h < queue[iq]:
                    queue[iq] -= h
                else:
                    iq += 1
            t += h
            for j in range(NY):
                y[j] = y1[j]
                r0[j] = r1[j]
            known0 = known1  # (the right-hand side at the step's end: the next step's start's)
            fresh = False
            if d == 0.0 and held(P, S, y, limit):
                stop = t
                n = _put(gt, gy, gd, gf, n, t, y, 0.0, 0)
                break
            if d != 0.0 and d * y[1] < creep:
                # creeping into the sliders' holding limit: at rest for good from here where the sliders hold it at
                # rest against the roof's ringing too (:func:`held`); else it creeps on (the roof breaks a base
                # stuck there away again at once: under a stiff storey, 3 000 sticks and slips before the hold)
                v = y[1]
                y[1] = 0.0
                if held(P, S, y, limit):
                    stop = t
                    n = _put(gt, gy, gd, gf, n, t, y, 0.0, 0)
                    break
                y[1] = v
                if stiff and drive(P, S, y, d) <= S[REST]:
                    # a damper of alpha < 1 brings the slide to rest: below the creep's speed with the drive down
                    # to where the damper alone would move it at below that speed (as :data:`EV_REST`; the roof
                    # still rings: stuck, not held for good)
                    y[1] = 0.0
                    d, mode = _start(P, S, y, False, limit)
                    fresh = True
                    iq, nq = 0, 0
                    hp = _step_size(P, S, y, d, mode)
                    hs = hp
                    known0 = False
                    n = _put(gt, gy, gd, gf, n, t, y, d, mode)
                    prev_i = -1
                    cur_i, cur_t, cur_g = n - 1, t, 0
                    if t >= t_end:
                        break
                    continue
            n = _put(gt, gy, gd, gf, n, t, y, d, mode)
            if not grouped or iq == nq:  # a (graded or plain) step ends here
                prev_i, prev_t, prev_g = cur_i, cur_t, cur_g
                cur_i, cur_t, cur_g = n - 1, t, 0
            if d != 0.0 and stiff and iq == nq:
                if creeping:
                    hs = _creep_step(P, S, y, d, mode, hp)
                    if hs < 0.0:  # off the slow manifold: explicit steps again
                        mode &= 3
                        gf[n - 1] = mode
                        known0 = False
                        hs = _relax_step(P, S, y, d, mode, hp)[0]
                else:
                    hs, creeps, speed = _relax_step(P, S, y, d, mode, hp)
                    if creeps:  # on the slow manifold: on it from here, on its own slow steps
                        mode |= CREEPING
                        y[1] = d * speed
                        gy[n - 1, 1] = y[1]
                        gf[n - 1] = mode
                        known0 = False
                        hs = _creep_step(P, S, y, d, mode, hp)
                        if hs < 0.0:
                            mode &= 3
                            gf[n - 1] = mode
                            hs = _relax_step(P, S, y, d, mode, hp)[0]
            if t >= t_end:
                break
            continue
        chain += 1
        if chain > MAX_CHAIN:
            return gt, gy, gd, gf, n, stop, 3
        known0 = False  # (the state, direction or mode changes at the event)
        if walk:  # the graded substeps recorded from the grid point i_b (those after it taken back)
            n = _walk(P, S, yb, t + theta - t_b, d, mode, fr, t_b, gt, gy, gd, gf, i_b + 1, k, tmp, a, out)
        t += theta
        for j in range(NY):
            y[j] = out[j]
        creeping = mode & CREEPING
        if kind == EV_YIELD and P[HKIND] == H_PLASTIC:
            y[2] = d * P[FP]
            mode = YIELDING | creeping
        elif kind == EV_YIELD:
            y[2] = d
            mode = YIELDING | creeping
        elif kind == EV_ZERO:
            y[2] = 0.0
            mode = LOADING | creeping
        else:  # a reversal, a re-slip or a creep's end: the base at rest, the holding force decides
            d, mode = _start(P, S, y, kind == EV_SLIP, limit)
            fresh = True
            if d == 0.0 and held(P, S, y, limit):
                stop = t
                n = _put(gt, gy, gd, gf, n, t, y, 0.0, 0)
                break
        hp = _step_size(P, S, y, d, mode)
        if mode & CREEPING:
            hs = _creep_step(P, S, y, d, mode, hp)
            if hs < 0.0:
                mode &= 3
                hs = _relax_step(P, S, y, d, mode, hp)[0]
        elif stiff and d != 0.0:
            hs = _relax_step(P, S, y, d, mode, hp)[0]
        else:
            hs = hp
        iq, nq = 0, 0  # (an event ends a grading)
        cur_g = 0
        if kind == EV_ZERO and P[N] != math.floor(P[N]):
            # |z|^n with a fractional n is not smooth where z leaves 0: the next steps graded from it
            fine = P[N] < 1.0 and P[COARSE] <= 1.0  # (coarse steps: the ratio-2 grading, as ``_ode``)
            cur_g = FINE if fine else 1
            g = _ode._fractions(P, cur_g, False)
            span = hs * FINE_SPAN if fine else hs
            nq = g.size
            for i in range(nq):
                queue[i] = g[i] * span
        elif d != 0.0 and powered and kind != EV_YIELD and kind != EV_ZERO:
            # a slide from rest: |x_b'|^alpha is not smooth at its start
            cur_g = 1
            g = _ode._fractions(P, 1, False)
            nq = g.size
            for i in range(nq):
                queue[i] = g[i] * hs
        n = _put(gt, gy, gd, gf, n, t, y, d, mode)
        prev_i = -1
        cur_i, cur_t = n - 1, t
        if t >= t_end:
            break
    return gt, gy, gd, gf, n, stop, 0


@njit(cache=True, nogil=True)
def _dense(P, S, y, h, d, mode, K, tmp, F, ynew):
    """The coefficients F (7 x NY) of the tableau's continuous extension over the step of length h from y."""
    for i in range(16):
        if i == _S:  # the stage at the step's end
            for j in range(NY):
                acc = 0.0
                for m in range(_S):
                    acc += _B[m] * K[m, j]
                ynew[j] = y[j] + h * acc
            _rhs(P, S, ynew, d, mode, K[_S])
            continue
        for j in range(NY):
            acc = 0.0
            for m in range(i):
                acc += _AX[i, m] * K[m, j]
            tmp[j] = y[j] + h * acc
        _rhs(P, S, tmp, d, mode, K[i])
    _ode.coefficients(y, ynew, h, K, F)


@njit(cache=True, nogil=True)
def _ringing(S, y, tau, out):
    """The roof ringing on the base held for good, tau [s] after the state y: the closed form of
    ``m_s u'' + c_s u' + k_s u = 0`` (zeta_s < 1); the storey damper's work grows by the drop of the roof's energy.
    Returns the roof's acceleration."""
    ms, ks, cs = S[MS], S[KS], S[CS]
    a = cs / (2.0 * ms)
    w = math.sqrt(ks / ms - a * a)
    u0, du0 = y[XS] - y[0], y[VS]
    e = math.exp(-a * tau)
    c, s = math.cos(w * tau), math.sin(w * tau) / w
    u = e * (c * u0 + s * (du0 + a * u0))
    du = e * (c * du0 - s * (a * du0 + (ks / ms) * u0))
    for j in range(NY):
        out[j] = y[j]
    out[XS] = y[0] + u
    out[VS] = du
    out[WS] = y[WS] + 0.5 * (ms * du0 * du0 + ks * u0 * u0) - 0.5 * (ms * du * du + ks * u * u)
    return -(ks * u + cs * du) / ms


@njit(cache=True, nogil=True)
def evaluate(P, S, gt, gy, gd, gf, n, stop, y_push, t):
    """The state and the accelerations of base and roof at times t [s] (any order; sorted is fastest): the
    continuous extension of the grid step that holds each time (computed once per step), the accelerations from
    the equation there; before the release the pushed state at rest; after the stop the base at rest and the roof
    ringing (:func:`_ringing`). At an instant where an acceleration jumps, the value after it."""
    m = t.size
    ys = np.empty((m, NY))
    acc = np.zeros((m, 2))
    K = np.empty((16, NY))
    tmp = np.empty(NY)
    F = np.empty((7, NY))
    ynew = np.empty(NY)
    out = np.empty(NY)
    r = np.empty(NY)
    cached = -1
    for i in range(m):
        ti = t[i]
        if ti < 0.0 or n == 1:
            src = y_push if ti < 0.0 else gy[0]
            for j in range(NY):
                ys[i, j] = src[j]
            continue
        if ti >= stop:
            acc[i, 1] = _ringing(S, gy[n - 1], ti - stop, out)
            for j in range(NY):
                ys[i, j] = out[j]
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
            if p != cached:
                _dense(P, S, gy[p], h, gd[p], mode, K, tmp, F, ynew)
                cached = p
            x = tau / h
            for j in range(NY):
                out[j] = 0.0
            for q in range(7):
                for j in range(NY):
                    out[j] += F[6 - q, j]
                    out[j] *= x if q % 2 == 0 else 1.0 - x
            for j in range(NY):
                out[j] += gy[p, j]
        _rhs(P, S, out, gd[p], mode, r)
        for j in range(NY):
            ys[i, j] = out[j]
        acc[i, 0] = r[1]
        acc[i, 1] = r[VS]
    return ys, acc
