"""The quantities engineers report for an isolation system, per cycle of its force-displacement loop.

EN 15129, ASCE 7 (chapter 17) and AASHTO judge an isolator by its loops: per cycle the effective stiffness,
the energy dissipated, the effective damping, the characteristic strength and the post-yield stiffness.
:func:`loop_cycles` reads them off a loop ``(x, F)`` sampled in time, where F is the isolators' total force
(``-m x_ddot`` of :func:`quickrelease.building.decay.hysteresis_loop` for a rigid superstructure, or a
model's force), one :class:`CycleProperties` per cycle:

* a cycle is two successive half-cycles, from a turning point of x to the turning point two half-cycles later,
  and each cycle starts where the one before ended (:func:`cycle_starts`: turning points 0 to 2, 2 to 4, ...;
  a half-cycle left over at the end is no cycle): each half-cycle is counted once, and every cycle of a free
  decay runs from one peak on the pushed side to the next (its first turning point is the release). Cycles
  from every turning point (0 to 2, 1 to 3, ...) overlapped, and in a decay about a drifting centre (a
  lead-rubber building's loops shrink about a residual displacement that creeps back) those from the other
  side's peaks, which move apart there rather than closing in, had the D and keff of their neighbour and a
  negative area (a free decay's cycles shrink; a constant-amplitude test's repeat);
* ``D+``, ``D-``: the cycle's largest and smallest displacements; ``F+``, ``F-``: the force at them, taken
  on the branch that reaches them (the extreme force within two samples of the displacement's extreme: a
  slider's force flips at the reversal, and the standards read the force before the flip);
* ``keff = (F+ - F-) / (D+ - D-)`` (ASCE 7-16 Eq. 17.8-1 with signed values; EN 15129 8.2.1.2.4);
* ``EDC``: the area of the loop, the path's integral of F dx closed by the chord between its ends (a closed
  loop's area; for a decaying loop on a linear spring, the energy the cycle dissipated: then
  ``integral F dx = 0`` between turning points and the chord adds ``k (D_start^2 - D_end^2) / 2``, with the
  chord's forces at the turning points taken as the means of the samples either side, the spring's force
  without the slider's flip);
* ``beta_eff = EDC / (2 pi keff D^2)``, D = (D+ - D-) / 2 (ASCE 7-16 Eq. 17.8-2);
* ``Qd``: the characteristic strength, half the jump of the force between the two branches at x = 0
  (``(F_up(0) - F_down(0)) / 2``, each branch's crossing of x = 0 interpolated between samples, or, for a
  measured loop, the intercept of each branch's line over ``|x| < qd_window D``);
* ``Kd``: the post-yield (second) stiffness, the least-squares slope of F against x on the loading branches
  (moving away from x = 0) beyond half the cycle's amplitude;
* ``Teff = 2 pi sqrt(m / keff)`` where the mass is given, and ``mu = Qd / (m g)`` (a slider's friction
  coefficient, with g = 9.80665 m/s^2).

All in SI units (m, N, J, s).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from ..errors import ParameterError
from ._zigzag import zigzag as _zigzag
from ._zigzag import zigzag_scan as zigzag_scan  # re-exported: its home before building._zigzag

__all__ = ["CycleProperties", "loop_cycles", "cycle_turns", "cycle_starts", "G0"]

#: Standard gravity [m/s^2] (mu = Qd / (m g)).
G0 = 9.80665


@dataclass(frozen=True)
class CycleProperties:
    """One cycle of an isolator's loop, as the standards read it (SI units; :func:`loop_cycles`)."""

    start_s: float
    """Time of the cycle's first turning point [s]."""
    end_s: float
    """Time of its last turning point (two half-cycles later) [s]."""
    amplitude_m: float
    """D = (D+ - D-) / 2 [m]."""
    d_plus_m: float
    d_minus_m: float
    f_plus_N: float
    """The force at D+ [N]."""
    f_minus_N: float
    """The force at D- [N]."""
    keff_N_m: float
    """Effective stiffness (F+ - F-) / (D+ - D-) [N/m]."""
    edc_J: float
    """Energy dissipated in the cycle: the loop's area [J]."""
    beta_eff: float
    """Effective damping EDC / (2 pi keff D^2) [-]."""
    qd_N: float
    """Characteristic strength: half the force jump between the branches at x = 0 [N] (nan where the cycle
    does not cross 0 twice)."""
    kd_N_m: float
    """Post-yield stiffness: slope of the loading branches beyond D/2 [N/m] (nan with fewer than 4 samples)."""
    teff_s: float = math.nan
    """Effective period 2 pi sqrt(m / keff) [s] (nan without the mass)."""
    mu: float = math.nan
    """Qd / (m g) [-] (nan without the mass)."""

    def summary(self) -> dict[str, Any]:
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in asdict(self).items()}


def cycle_turns(x: np.ndarray, noise: float = 0.0) -> np.ndarray:
    """Indices of the turning points of a sampled displacement.

    Without ``noise``: the sample of each half-cycle's extreme between the sign changes of its increments
    (runs of equal samples count with the run before), for a loop sampled without noise, or smoothed.

    With ``noise`` (the standard deviation of the noise on x [m], e.g. a transducer's resolution): a zigzag
    with hysteresis, the running extreme in the current direction becoming a turning point once x has come
    back from it by more than ``(2 sqrt(2 ln n) + 2) noise`` (n samples), beyond the range of the noise alone,
    as :func:`quickrelease.building.decay.turning_points` does for a decay. A measured loop needs it: the
    friction damper's records in ``tests/data/friction_damper`` (displacement quantised to 1.5 um at 1024 Hz)
    hold 14 turning points, and 260 and 56 sign changes of their increments.
    """
    x = np.asarray(x, dtype=float)
    if noise < 0.0 or not math.isfinite(noise):
        raise ParameterError("noise", noise, "[0, inf)", "m")
    if noise > 0.0:
        return _zigzag(x, noise * (2.0 * math.sqrt(2.0 * math.log(max(x.size, 2))) + 2.0))
    dx = np.diff(x)
    sign = np.sign(dx)
    for i in range(1, sign.size):  # a flat step continues the run before it
        if sign[i] == 0.0:
            sign[i] = sign[i - 1]
    change = np.nonzero(sign[1:] * sign[:-1] < 0.0)[0] + 1
    return change


def cycle_starts(n_turns: int) -> range:
    """The index, among ``n_turns`` turning points, of each cycle's first: 0, 2, 4, ... (a cycle runs to the
    turning point two after its first, where the next begins); empty with fewer than 3 turning points."""
    return range(0, max(int(n_turns) - 2, 0), 2)


def _turning_force(f: np.ndarray, i: int) -> float:
    """The force at a turning point without the jump a slider's force makes there: the mean of the samples
    either side of it (the sample itself at the record's ends)."""
    if 0 < i < f.size - 1:
        return 0.5 * float(f[i - 1] + f[i + 1])
    return float(f[i])


def _branch_crossing(x: np.ndarray, f: np.ndarray, direction: float) -> float:
    """The force where the path crosses x = 0 moving in ``direction`` (+1 up, -1 down), interpolated between
    the two samples about the crossing; nan if it does not cross."""
    s = direction * x
    idx = np.nonzero((s[:-1] < 0.0) & (s[1:] >= 0.0))[0]
    if idx.size == 0:
        return math.nan
    i = int(idx[0])
    w = -x[i] / (x[i + 1] - x[i])
    return float(f[i] + w * (f[i + 1] - f[i]))


def _branch_intercept(x: np.ndarray, f: np.ndarray, direction: float, half_width: float) -> float:
    """The force at x = 0 of the branch moving in ``direction`` (+1 up, -1 down): the intercept of the
    least-squares line of F on x over its samples with |x| < ``half_width``; nan with fewer than 3 of them."""
    moving = np.sign(np.diff(x)) == direction
    xs, fs = x[1:][moving], f[1:][moving]
    near = np.abs(xs) < half_width
    if np.count_nonzero(near) < 3 or np.ptp(xs[near]) == 0.0:
        return math.nan
    return float(np.polyfit(xs[near], fs[near], 1)[1])


def _loading_slope(x: np.ndarray, f: np.ndarray, amplitude: float, guard: int = 2) -> float:
    """Least-squares slope of F on x over the loading samples (x moving away from 0) beyond amplitude / 2,
    leaving out ``guard`` samples either side of each extreme (a slider's force may have flipped at the
    sample of the extreme already)."""
    dx = np.diff(x)
    xm = x[1:]
    near = np.zeros(xm.size, dtype=bool)
    for i in (int(np.argmax(x)), int(np.argmin(x))):
        near[max(i - 1 - guard, 0):i + guard] = True  # xm[j] is x[j + 1]
    loading = (np.sign(dx) == np.sign(xm)) & (np.abs(xm) > 0.5 * amplitude) & ~near
    xs, fs = xm[loading], f[1:][loading]
    if xs.size < 4 or np.ptp(xs) == 0.0:
        return math.nan
    # one slope for both branches, each with its own intercept (the branches are offset by 2 Qd)
    side = (xs > 0).astype(float)
    A = np.column_stack([xs, side, 1.0 - side])
    coef = np.linalg.lstsq(A, fs, rcond=None)[0]
    return float(coef[0])


def loop_cycles(t, x, force, mass: float | None = None, neighbourhood: int = 2,
                turns=None, noise: float = 0.0, qd_window: float = 0.0) -> tuple[CycleProperties, ...]:
    """The engineering quantities of every whole cycle of the loop ``(x, force)`` sampled at times t (see the
    module docstring for each definition and its source).

    Parameters
    ----------
    t, x, force : array_like
        Times [s], displacement [m] and the isolators' total force [N] (e.g. ``-m x_ddot``), one sample each.
    mass : float, optional
        The mass on the isolators [kg]: gives Teff and mu.
    neighbourhood : int
        Samples either side of a displacement's extreme where the extreme force is taken (F+ and F-).
    turns : array_like of int, optional
        The samples of the turning points, increasing (e.g. the release from rest, the reversals and the
        stop of a free decay, which the increments alone do not show at the record's ends); default
        :func:`cycle_turns` with ``noise``.
    noise : float
        Standard deviation of the noise on x [m] (a measured loop's): the turning points by a zigzag beyond
        its range (:func:`cycle_turns`); 0 for a loop without noise.
    qd_window : float
        Where positive, Qd from each branch's least-squares line of F on x over ``|x| < qd_window D``, its
        intercept at x = 0, instead of the force interpolated between the two samples about the crossing:
        a measured force rings and carries noise there (on the friction damper's 1 Hz record in
        ``tests/data/friction_damper`` the single crossing scatters Qd by 17 % between steady cycles,
        a window of D/4 by 4 %). 0 (default): the crossing, exact for a loop without noise.

    Returns
    -------
    tuple of CycleProperties
        One per cycle (turning point to the turning point two half-cycles later, each cycle starting where the
        one before ended: :func:`cycle_starts`), in time order; empty where the loop holds fewer than two
        half-cycles.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    f = np.asarray(force, dtype=float)
    if not (t.ndim == 1 and t.shape == x.shape == f.shape):
        raise ParameterError("force", f"{f.size} sample(s)", f"{x.size} samples, like x and t")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(x)) and np.all(np.isfinite(f))):
        raise ParameterError("x", "non-finite samples", "finite values")
    if mass is not None and not (math.isfinite(float(mass)) and float(mass) > 0.0):
        raise ParameterError("mass", mass, "(0, inf)", "kg")
    if not (math.isfinite(float(qd_window)) and 0.0 <= float(qd_window) <= 1.0):
        raise ParameterError("qd_window", qd_window, "[0, 1]", "of the amplitude")
    turns = cycle_turns(x, noise) if turns is None else np.asarray(turns, dtype=int)
    if turns.size and (np.any(np.diff(turns) <= 0) or turns[0] < 0 or turns[-1] >= x.size):
        raise ParameterError("turns", f"{turns.size} indices", f"increasing sample indices in [0, {x.size - 1}]")
    out = []
    for k in cycle_starts(turns.size):
        i0, i1 = int(turns[k]), int(turns[k + 2])
        xs, fs = x[i0:i1 + 1], f[i0:i1 + 1]
        ip, im = i0 + int(np.argmax(xs)), i0 + int(np.argmin(xs))
        d_plus, d_minus = float(x[ip]), float(x[im])
        near = slice(max(ip - neighbourhood, 0), ip + neighbourhood + 1)
        f_plus = float(np.max(f[near]))
        near = slice(max(im - neighbourhood, 0), im + neighbourhood + 1)
        f_minus = float(np.min(f[near]))
        span = d_plus - d_minus
        if not span > 0.0:
            continue
        keff = (f_plus - f_minus) / span
        D = 0.5 * span
        # the work done on the isolators along the path, closed by the chord from its end back to its start;
        # the chord's forces at the turning points are the means of the samples either side (a slider's force
        # flips there: the mean is the spring's force, so a decaying loop on a linear spring closes exactly)
        path = float(np.sum(0.5 * (fs[1:] + fs[:-1]) * np.diff(xs)))
        edc = path + 0.5 * (_turning_force(f, i0) + _turning_force(f, i1)) * (xs[0] - xs[-1])
        beta = edc / (2.0 * math.pi * keff * D * D) if keff > 0.0 else math.nan
        if qd_window > 0.0:
            qd = 0.5 * (_branch_intercept(xs, fs, 1.0, qd_window * D) - _branch_intercept(xs, fs, -1.0, qd_window * D))
        else:
            qd = 0.5 * (_branch_crossing(xs, fs, 1.0) - _branch_crossing(xs, fs, -1.0))
        kd = _loading_slope(xs, fs, D, neighbourhood)
        teff = mu = math.nan
        if mass is not None:
            m = float(mass)
            teff = 2.0 * math.pi * math.sqrt(m / keff) if keff > 0.0 else math.nan
            mu = qd / (m * G0)
        out.append(CycleProperties(start_s=float(t[i0]), end_s=float(t[i1]), amplitude_m=D, d_plus_m=d_plus,
                                   d_minus_m=d_minus, f_plus_N=f_plus, f_minus_N=f_minus, keff_N_m=keff,
                                   edc_J=edc, beta_eff=beta, qd_N=qd, kd_N_m=kd, teff_s=teff, mu=mu))
    return tuple(out)
