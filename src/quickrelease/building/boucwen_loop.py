"""Bouc-Wen isolators (and their dampers) read off the measured hysteresis loop, without integrating the motion.

With a rigid superstructure and no external force after the release, Newton's law gives the isolators' total
force from the acceleration record, ``F = -m a`` (:func:`quickrelease.building.decay.hysteresis_loop`), and the
Bouc-Wen model says what it is made of:

    F = Kd x + Qd z + C |v|^alpha sign(v) + F_s sign(v) + h,                                            (E)

z the Bouc-Wen element's state along the measured displacement path (``dy dz = dx (1 - |z|^n (sgn(dx z) +
1) / 2)``, :func:`quickrelease.building._ode.boucwen_path`), v the velocity, and h = -Kd e for the
displacement sensor's zero e. Given the element's shape (dy, n) and the damper's exponent alpha, (E) is linear
in Kd, Qd, C, F_s and h: they follow by bounded linear least squares (all but h non-negative), and (dy, n,
alpha) by a search over a grid and a simplex refinement of the least-squares misfit. This is the "equation
error" of system identification: each sample's force is explained from the measured path, so the misfit has
none of the output error's basins (a count of half-cycles, a phase drifting over a long record), and it gives
the whole-record fit (:func:`quickrelease.building.isolation_fit.fit_isolation`) a start that does not depend on
design values.

Two details make it work on real records. The displacement's noise must not drive z: every wiggle of the
sensor's noise is a reversal, and the element unloads at the rate 1 but reloads at ``1 - |z|^n``, so noise
ratchets z towards 0 (an 0.05 mm noise on a 25 mm yield displacement left z 0.37 off after a minute). The path
is therefore the sensor's record through a play operator of width three noise levels (it moves only when the
record leaves a band of that width about it). And only the motion enters: at rest the force is the noise of the
accelerometer and the velocity's estimate, and a power-law damper's ``|v|^alpha`` of that estimate's noise
would bias C.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import lsq_linear, minimize
from scipy.signal import savgol_coeffs, savgol_filter

from ._ode import boucwen_path

__all__ = ["BoucWenLoop", "boucwen_loop", "play"]

#: The yield displacement's grid, as shares of |d0| (log-spaced), the shape exponents' and the damper
#: exponents' (power-law dampers; 1 for viscous) of the search over (dy, n, alpha).
LOOP_YIELD_SHARES = (0.003, 0.5, 14)
LOOP_SHAPES = (0.7, 1.0, 1.5, 2.0, 3.0, 5.0, 8.0)
LOOP_EXPONENTS = (0.15, 0.4, 0.65, 0.9, 1.15, 1.4, 1.65, 1.9)
#: Width of the play operator that takes the noise out of the displacement path, in noise levels.
PLAY_NOISE = 3.0
#: Samples of the loop at most in the least squares (the acceleration channel thinned by an integer step).
LOOP_SAMPLES = 800


@dataclass(frozen=True)
class BoucWenLoop:
    """The Bouc-Wen isolators and dampers read off the loop (:func:`boucwen_loop`), SI units."""

    post_yield_stiffness: float
    """Kd [N/m]."""
    characteristic_strength: float
    """Qd [N]."""
    yield_displacement: float
    """dy [m]."""
    shape: float
    """n [-]."""
    damping: float
    """C [N (s/m)^alpha] (N s/m for the viscous damper)."""
    damping_exponent: float
    """alpha [-] (1 for the viscous damper)."""
    friction: float
    """The sliders' force F_s [N]."""
    zero: float
    """The displacement sensor's zero e [m] (the model's x is the record's less e)."""
    misfit: float
    """The least-squares misfit per sample over the accelerometer's noise variance times m^2 (about 1 where
    (E) explains the loop to the noise)."""
    samples: int
    """The loop's samples in the least squares."""


def play(y, width: float) -> np.ndarray:
    """The play (backlash) operator of ``width`` [units of y]: the output stays while the input lies within
    ``width`` of it and follows the input at that distance when it leaves the band; starts at y[0]."""
    y = np.asarray(y, dtype=float)
    out = np.empty_like(y)
    if y.size == 0:
        return out
    c = float(y[0])
    for i, v in enumerate(y.tolist()):
        if v > c + width:
            c = v - width
        elif v < c - width:
            c = v + width
        out[i] = c
    return out


def _columns(x, z, v, alpha: float) -> np.ndarray:
    return np.column_stack([x, np.ones_like(x), z, np.abs(v) ** alpha * np.sign(v), np.sign(v)])


_LOWER = np.array([0.0, -np.inf, 0.0, 0.0, 0.0])
_UPPER = np.full(5, np.inf)


def boucwen_loop(t, x, t_a, acceleration, mass: float, release_time: float, noise_x: float, noise_a: float | None,
                 period: float, *, damping: str = "viscous") -> BoucWenLoop | None:
    """Bouc-Wen isolators (with dampers and sliders) from the measured loop, by the equation error (E).

    Parameters
    ----------
    t, x : array
        The displacement record [s], [m] (the pre-release rest included: its median is the pushed level; a
        record without one, caught mid-swing, starts at its first turning point, the release from rest).
    t_a, acceleration : array or None
        The acceleration record of the layer [s], [m/s^2] (its median before the release is its zero; 0
        without one). None: the displacement's second derivative (cubics through 10 % of the period; an
        LVDT-only record).
    mass : float
        The mass on the isolators [kg].
    release_time : float
        The release instant [s].
    noise_x, noise_a : float
        The records' noise levels [m], [m/s^2] (noise_a unused without an acceleration record).
    period : float
        The record's apparent period [s]: the velocity is the derivative of a cubic through a window of 5 % of
        it (Savitzky-Golay), and the motion's end is where the displacement stays within 8 noise levels of
        its final level.
    damping : {"viscous", "power"}
        The damper's law: alpha = 1, or searched in [0.15, 1.9].

    Returns None where the record has too little motion (fewer than 30 accelerometer samples in it) or no
    shape gives positive Kd and Qd.
    """
    t, x = np.asarray(t, dtype=float), np.asarray(x, dtype=float)
    t_r = float(release_time)
    pre_x = x[t < t_r]
    if x.size < 10 or not (math.isfinite(period) and period > 0):
        return None
    # the pushed level: the rest before the release, or (a record caught mid-swing, cut at its first turning
    # point) the first sample
    d0 = float(np.median(pre_x)) if pre_x.size >= 3 else float(x[min(int(np.searchsorted(t, t_r)), x.size - 1)])
    level = float(np.median(x[-max(x.size // 10, 5):]))
    off = np.nonzero(np.abs(x - level) > 8.0 * noise_x)[0]
    t_end = float(t[off[-1]]) if off.size else t_r
    # the displacement on a uniform grid (a logger's jittery clock), its velocity from cubics through 5 % of
    # the period, and the path through the play operator from the pushed level
    dt = float(np.median(np.diff(t)))
    if not dt > 0:
        return None
    grid = np.arange(t_r - dt, min(t_end, float(t[-1])) + 0.5 * dt, dt)
    if grid.size < 10:
        return None
    xg = np.interp(grid, t, x)
    window = min(max(5, int(round(0.05 * period / dt)) | 1), grid.size - (1 - grid.size % 2))  # odd
    vg = savgol_filter(xg, window, 3, deriv=1, delta=dt)
    path = play(np.concatenate([[d0], xg[1:]]), PLAY_NOISE * noise_x)
    if acceleration is None:  # the LVDT's own: cubics through 10 % of the period, the samples within half of
        # that of the release left out (the acceleration jumps there); its noise from the filter's weights
        wide = min(max(7, int(round(0.1 * period / dt)) | 1), grid.size - (1 - grid.size % 2))
        t_a, acc = grid, savgol_filter(xg, wide, 3, deriv=2, delta=dt)
        acc = np.where(grid > t_r + 0.5 * wide * dt, acc, np.nan)
        noise_a = noise_x * float(np.linalg.norm(savgol_coeffs(wide, 3, deriv=2, delta=dt)))
        zero = 0.0
    else:
        t_a, acc = np.asarray(t_a, dtype=float), np.asarray(acceleration, dtype=float)
        pre_a = acc[t_a < t_r]
        zero = float(np.median(pre_a)) if pre_a.size >= 3 else 0.0
    moving = (t_a > t_r) & (t_a <= grid[-1]) & np.isfinite(acc)
    if np.count_nonzero(moving) < 30:
        return None
    idx = np.nonzero(moving)[0]
    idx = idx[:: max(1, math.ceil(idx.size / LOOP_SAMPLES))]
    ta = t_a[idx]
    force = -float(mass) * (acc[idx] - zero)
    xa, va = np.interp(ta, grid, xg), np.interp(ta, grid, vg)
    scale = float(mass) * max(float(noise_a), 1e-12)
    exponents = (1.0,) if damping == "viscous" else LOOP_EXPONENTS

    # the element's state at the release: pushed from 0 to |d0| against the first motion's direction (a record
    # caught mid-swing: its first turning point, approached against the coming motion)
    first = np.nonzero(np.abs(xg - d0) > 8.0 * noise_x)[0]
    sense = math.copysign(1.0, float(xg[first[0]] - d0)) if first.size else -math.copysign(1.0, d0)

    def z_of(dy: float, n: float) -> np.ndarray:
        z0 = -sense * float(boucwen_path(np.array([0.0, abs(d0)]), dy, n, 0.0)[-1])  # the monotonic push
        return np.interp(ta, grid, boucwen_path(path, dy, n, z0))

    def score(dy: float, n: float, alpha: float, z=None) -> tuple[float, np.ndarray]:
        z = z_of(dy, n) if z is None else z
        A = _columns(xa, z, va, alpha)
        coef = lsq_linear(A / scale, force / scale, bounds=(_LOWER, _UPPER), method="bvls").x
        r = (A @ coef - force) / scale
        return float(r @ r), coef

    # the grid, scored by plain least squares (bounded where its coefficients come out negative)
    trials = []
    for dy in abs(d0) * np.geomspace(*LOOP_YIELD_SHARES):
        for n in LOOP_SHAPES:
            z = z_of(float(dy), n)
            for alpha in exponents:
                A = _columns(xa, z, va, alpha)
                coef = np.linalg.lstsq(A / scale, force / scale, rcond=None)[0]
                if np.any(coef[[0, 2, 3, 4]] < 0.0):
                    cost, coef = score(float(dy), n, alpha, z)
                else:
                    r = (A @ coef - force) / scale
                    cost = float(r @ r)
                trials.append((cost, float(dy), n, alpha))
    trials.sort(key=lambda item: item[0])
    lo = np.array([math.log(abs(d0) * LOOP_YIELD_SHARES[0]), math.log(0.5), min(exponents)])
    hi = np.array([math.log(abs(d0) * LOOP_YIELD_SHARES[1]), math.log(25.0), max(exponents)])

    def objective(u) -> float:
        u = np.clip(u, lo, hi)
        return score(math.exp(u[0]), math.exp(u[1]), 1.0 if damping == "viscous" else float(u[2]))[0]

    best = None
    for cost, dy, n, alpha in trials[:3]:  # the simplex from the three best grid points
        u0 = np.array([math.log(dy), math.log(n), alpha])
        if damping == "viscous":
            res = minimize(lambda w: objective(np.array([w[0], w[1], 1.0])), u0[:2], method="Nelder-Mead",
                           options={"xatol": 1e-3, "fatol": 1e-3 * max(cost, 1.0), "maxfev": 120})
            u = np.array([*np.clip(res.x, lo[:2], hi[:2]), 1.0])
        else:
            res = minimize(objective, u0, method="Nelder-Mead",
                           options={"xatol": 1e-3, "fatol": 1e-3 * max(cost, 1.0), "maxfev": 180})
            u = np.clip(res.x, lo, hi)
        if best is None or res.fun < best[0]:
            best = (float(res.fun), u)
    cost, u = best
    dy, n, alpha = math.exp(u[0]), math.exp(u[1]), float(u[2])
    _, coef = score(dy, n, alpha)
    kd, h, qd, c, fs = (float(v) for v in coef)
    if not (kd > 0.0 and qd > 0.0):
        return None
    return BoucWenLoop(post_yield_stiffness=kd, characteristic_strength=qd, yield_displacement=dy, shape=n,
                       damping=c, damping_exponent=alpha, friction=fs, zero=-h / kd, misfit=cost / ta.size,
                       samples=int(ta.size))
