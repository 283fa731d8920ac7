"""Model-free analysis of the building's free-vibration decay (SI units).

From the displacement of the isolation layer after the release (a record, or a model), without fitting a
model of the isolators:

- the turning points (peaks) of each half-cycle, located between samples, and the zero crossings;
- per half-cycle n (from turning point n to n + 1): the amplitude ``A_n = |x_{n+1} - x_n| / 2`` (half the
  swing: free of the sensor's zero and of a permanent offset), the equivalent period
  ``T_eq = 2 (t_{n+1} - t_n)``, and between successive half-cycles the equivalent viscous damping ratio
  ``zeta_eq = d / sqrt(pi^2 + d^2)``, ``d = ln(A_{n-1} / A_n)``: with viscous damping alone zeta_eq is
  constant, with Coulomb friction it grows as the amplitude falls (the signature of sliders);
- the decay law. A linear isolator with viscous damping ratio zeta and sliders of friction F_s moves, in
  each half-cycle, as a damped free vibration about the shifted centre ``sign(x_n) delta``,
  ``delta = F_s / k``, so successive signed peaks obey exactly

      x_{n+1} - e = -r (x_n - e) + (1 + r) delta sign(x_n - e),   r = exp(-pi zeta / sqrt(1 - zeta^2)),  (*)

  (e the sensor's reading where the isolators carry no force)
  the combined decrement law (Coulomb and viscous damping together, cf. Feeny and Liang, J. Sound Vib.
  196(4), 1996, 439-451): the amplitude falls geometrically (factor r) for viscous damping alone and
  linearly (2 delta per half-cycle) for friction alone. Fitting (*) to the peaks by linear least squares
  separates the two: ``zeta = -ln r / sqrt(pi^2 + ln^2 r)`` and ``F_s = k delta`` (k from the period and the
  mass). The pure laws (delta = 0; r = 1) are fitted too and their residuals reported, so the record says
  which law it follows;
- the hysteresis loop: the isolators' total force ``-m x_ddot`` against the displacement (rubber, dampers
  and sliders together; the inertia force of a rigid superstructure), when an acceleration channel exists.

(*) holds for the linear model with sliders; a bilinear rubber spring has no such law (its period and
decrement change with the amplitude by themselves), which the per-half-cycle equivalents then show.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import minimize_scalar

from .errors import ParameterError

__all__ = ["DecayAnalysis", "DecayLaw", "LoopEstimate", "analyse_decay", "bilinear_loop", "combined_decay_law",
           "turning_points",
           "zero_crossings", "half_cycle_crossings", "hysteresis_loop"]


@dataclass(frozen=True)
class DecayLaw:
    """The combined decrement law (*) fitted to successive peaks, and the two pure laws beside it."""

    ratio: float
    """r, the viscous amplitude ratio per half-cycle [-]."""
    friction_displacement: float
    """delta = F_s / k [m]."""
    ratio_se: float
    friction_displacement_se: float
    damping_ratio: float
    """zeta = -ln r / sqrt(pi^2 + ln^2 r) [-]."""
    damping_ratio_se: float
    rms: float
    """RMS residual of (*) over the peaks [m]."""
    rms_viscous_only: float
    """RMS residual of the geometric law (delta = 0) [m]."""
    rms_friction_only: float
    """RMS residual of the linear law (r = 1) [m]."""
    half_cycles: int
    rest: float = math.nan
    """e = h / (1 + r), the reading where the isolators carry no force [m] (nan when fitted without the
    constant)."""

    def friction_force(self, stiffness: float) -> float:
        """F_s = k delta [N] for the stiffness k [N/m]."""
        return stiffness * self.friction_displacement

    def summary(self) -> dict[str, Any]:
        return {"ratio": self.ratio, "ratio_se": self.ratio_se, "friction_displacement_m": self.friction_displacement,
                "friction_displacement_se_m": self.friction_displacement_se, "damping_ratio": self.damping_ratio,
                "damping_ratio_se": self.damping_ratio_se, "rms_m": self.rms,
                "rms_viscous_only_m": self.rms_viscous_only, "rms_friction_only_m": self.rms_friction_only,
                "half_cycles": self.half_cycles}


def combined_decay_law(peaks, offset: bool = True) -> DecayLaw:
    """Fit (*) to successive signed turning points [m]: ``x_{n+1} = -r x_n + g s_n + h``.

    ``s_n = +1`` when x_n is a maximum and -1 at a minimum (the direction of the swing, which does not
    depend on the sensor's zero), ``g = (1 + r) delta`` and ``h = (1 + r) e`` (e the reading where the
    isolators carry no force; h = 0 when ``offset`` is False). Linear least squares; standard errors from
    the residuals (zero for exact peaks). Needs one more peak than unknowns.
    """
    x = np.asarray(peaks, dtype=float)
    unknowns = 3 if offset else 2
    if x.ndim != 1 or x.size < unknowns + 1 or not np.all(np.isfinite(x)):
        raise ParameterError("peaks", f"{x.size} value(s)", f"at least {unknowns + 1} finite successive peaks", "m")
    xn, xn1 = x[:-1], x[1:]
    s = -np.sign(xn1 - xn)
    columns = [-xn, s] + ([np.ones_like(xn)] if offset else [])
    A = np.column_stack(columns)
    coef, *_ = np.linalg.lstsq(A, xn1, rcond=None)
    r, g = float(coef[0]), float(coef[1])
    resid = xn1 - A @ coef
    n = xn.size
    dof = n - unknowns
    s2 = float(resid @ resid) / dof if dof > 0 else 0.0
    cov = s2 * np.linalg.pinv(A.T @ A)
    delta = g / (1.0 + r)
    # delta = g / (1 + r): gradient (-g / (1 + r)^2, 1 / (1 + r)) in (r, g)
    grad = np.array([-g / (1.0 + r) ** 2, 1.0 / (1.0 + r)])
    delta_se = math.sqrt(max(float(grad @ cov[:2, :2] @ grad), 0.0))
    r_se = math.sqrt(max(float(cov[0, 0]), 0.0))
    if 0.0 < r < 1.0:
        lr = math.log(r)
        zeta = -lr / math.hypot(math.pi, lr)
        dzeta = -(math.pi**2) / math.hypot(math.pi, lr) ** 3 / r  # d zeta / d r
        zeta_se = abs(dzeta) * r_se
    else:
        zeta, zeta_se = (0.0 if r >= 1.0 else math.nan), math.nan

    def rms_of(cols) -> float:
        B = np.column_stack(cols)
        c, *_ = np.linalg.lstsq(B, xn1, rcond=None)
        return math.sqrt(float(np.mean((xn1 - B @ c) ** 2)))

    const = [np.ones_like(xn)] if offset else []
    rms_v = rms_of([-xn] + const)  # geometric decay: delta = 0
    # linear decay: r = 1, x_{n+1} + x_n = g s_n + h
    B = np.column_stack([s] + const)
    c, *_ = np.linalg.lstsq(B, xn1 + xn, rcond=None)
    rms_f = math.sqrt(float(np.mean((xn1 + xn - B @ c) ** 2)))
    return DecayLaw(ratio=r, friction_displacement=delta, ratio_se=r_se, friction_displacement_se=delta_se,
                    damping_ratio=zeta, damping_ratio_se=zeta_se, rms=math.sqrt(float(np.mean(resid**2))),
                    rms_viscous_only=rms_v, rms_friction_only=rms_f, half_cycles=n,
                    rest=float(coef[2]) / (1.0 + r) if offset else math.nan)


def _check_series(t, x, name: str = "x") -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    if t.ndim != 1 or t.shape != x.shape or t.size < 8:
        raise ParameterError(name, f"{x.size} sample(s)", "at least 8 samples on a time axis of the same length")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(x))):
        raise ParameterError(name, "non-finite samples", "finite values (drop missing samples first)")
    if np.any(np.diff(t) <= 0):
        raise ParameterError("t", "not increasing", "strictly increasing times", "s")
    return t, x


def _refine_extremum(t: np.ndarray, x: np.ndarray, i: int, half: int) -> tuple[float, float]:
    """Time and value of the turning point near sample i.

    The velocity vanishes at the turning point tp on both sides, but the acceleration (and every higher
    derivative) jumps there when the sliders' force changes sign, so each side has its own Taylor series:
    ``x = X + a_s u^2 + b_s u^3 + c_s u^4`` (u = t - tp, s the side), with X shared. For each tp the model
    is linear in its seven coefficients; tp minimises the residual (bounded scalar search between the
    samples next to i). With ``half`` samples a side of about a twelfth of a half-cycle, the neglected
    fifth-order terms are about 1e-7 of the amplitude.
    """
    lo, hi = max(i - half, 0), min(i + half + 1, t.size)
    tt, xx = t[lo:hi], x[lo:hi]
    if tt.size < 9:
        return float(t[i]), float(x[i])
    scale = float(tt[-1] - tt[0])

    def solve(tp: float):
        u = (tt - tp) / scale
        left = (u < 0).astype(float)
        right = 1.0 - left
        u2 = u * u
        A = np.column_stack([np.ones_like(u), u2 * left, u2 * right, u2 * u * left, u2 * u * right,
                             u2 * u2 * left, u2 * u2 * right])
        coef, *_ = np.linalg.lstsq(A, xx, rcond=None)
        r = xx - A @ coef
        return float(r @ r), float(coef[0])

    a, b = float(t[max(i - 1, lo)]), float(t[min(i + 1, hi - 1)])
    res = minimize_scalar(lambda tp: solve(tp)[0], bounds=(a, b), method="bounded",
                          options={"xatol": 1e-13 * max(abs(a), abs(b), scale)})
    tp = float(res.x)
    return tp, solve(tp)[1]


def turning_points(t, x, noise: float = 0.0, rest: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Times [s] and signed values [m] of the successive turning points of a decay that starts at rest.

    The first sample is the release (the building at rest at its pushed displacement), the first turning
    point. The others are found by a zigzag with hysteresis: the running extreme in the current direction
    of motion becomes a turning point once the signal has come back from it by more than
    ``(2 sqrt(2 ln n) + 2) noise`` (noise: the standard deviation of the noise on x; n samples), beyond the
    range of the noise alone, so noise does not make half-cycles. When the record ends on a
    rest (the sliders stuck), the last extreme is the final turning point, at the median of the rest.
    Each turning point after the first is located between samples (``_refine_extremum``).
    """
    t, x = _check_series(t, x)
    n = x.size
    # the range of n Gaussian samples stays below 2 sqrt(2 ln n) standard deviations (their expected
    # extremes), plus a margin of 2: noise alone does not make a half-cycle
    threshold = float(noise) * (2.0 * math.sqrt(2.0 * math.log(n)) + 2.0)
    direction = -1.0 if x[0] > rest else 1.0
    idx: list[int] = []
    best = 1
    for k in range(2, n):
        if direction * (x[k] - x[best]) > 0.0:
            best = k
        elif direction * (x[best] - x[k]) > threshold:
            idx.append(best)
            direction = -direction
            best = k
    # the record ends on a rest (the sliders stuck) when the samples within the threshold of the running
    # extreme reach the end, at least four of them, with no trend across them beyond half the threshold
    # (a swing still under way rises by about the threshold there). Not "the extreme lies four samples
    # before the end": on a noisy rest the extreme is the noise's largest sample, which falls among the
    # last four in ~4/n_rest of records, and that record lost its last half-cycle (and its decay law).
    k = best
    while k > (idx[-1] if idx else 0) + 1 and direction * (x[best] - x[k - 1]) <= threshold:
        k -= 1
    stuck = n - 1 - best >= 4
    if not stuck and n - k >= 8:
        rise = np.polyfit(t[k:] - t[k], x[k:], 1)[0] * (t[-1] - t[k])
        stuck = abs(rise) < 0.5 * threshold
    if stuck:
        idx.append(best if n - 1 - best >= 4 else k)
    half = 3
    if len(idx) >= 2:
        half = int(max(5, min(np.median(np.diff(idx)) // 12, 400)))
    times, values = [float(t[0])], [float(x[0])]
    for j, i in enumerate(idx):
        if stuck and j == len(idx) - 1 and n - 1 - i > half:
            times.append(_refine_extremum(t, x, i, half)[0])
            values.append(float(np.median(x[i:])))
            continue
        tp, xp = _refine_extremum(t, x, i, half)
        times.append(tp)
        values.append(xp)
    return np.array(times), np.array(values)


def zero_crossings(t, x, level: float = 0.0) -> np.ndarray:
    """Times [s] where x crosses ``level``, between samples by the cubic through the four nearest samples."""
    t, x = _check_series(t, x)
    y = x - level
    k = np.nonzero((y[:-1] < 0) & (y[1:] >= 0) | (y[:-1] > 0) & (y[1:] <= 0))[0]
    return np.array([_crossing_at(t, y, int(i)) for i in k])


def _crossing_at(t: np.ndarray, y: np.ndarray, i: int) -> float:
    """The root of y between samples i and i + 1 (a sign change there), by the cubic through the four
    nearest samples; the chord's root where the cubic has none in the interval [s]."""
    lo = max(i - 1, 0)
    hi = min(lo + 4, y.size)
    lo = max(hi - 4, 0)
    tt, yy = t[lo:hi], y[lo:hi]
    t0 = float(tt[0])
    p = np.polynomial.Polynomial.fit(tt - t0, yy, deg=min(3, tt.size - 1))
    roots = [float(r.real) + t0 for r in p.roots() if abs(r.imag) < 1e-12 * (1 + abs(r.real))]
    roots = [r for r in roots if t[i] <= r <= t[i + 1]]
    return roots[0] if roots else float(t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i]))


def half_cycle_crossings(t, x, times, peaks, rest: float = 0.0) -> np.ndarray:
    """One crossing of ``rest`` per half-cycle [s]: for each pair of successive turning points (times,
    peaks) on opposite sides of rest, the sign change of x - rest nearest the middle of the half-cycle,
    located between samples (:func:`zero_crossings`' cubic). A half-cycle crosses the rest level once;
    near it the noise can add sign changes, and after the sliders stick the noise about the rest position
    makes thousands (712 on a 60 s record at 200 Hz), none of them a crossing of the motion."""
    t, x = _check_series(t, x)
    y = x - rest
    k = np.nonzero((y[:-1] < 0) & (y[1:] >= 0) | (y[:-1] > 0) & (y[1:] <= 0))[0]
    out = []
    for a, b, pa, pb in zip(times[:-1], times[1:], peaks[:-1], peaks[1:], strict=True):
        if (pa - rest) * (pb - rest) >= 0.0:
            continue
        inside = k[(t[k] >= a) & (t[k + 1] <= b)]
        if inside.size:
            mid = 0.5 * (a + b)
            out.append(_crossing_at(t, y, int(inside[np.argmin(np.abs(t[inside] - mid))])))
    return np.array(out)


@dataclass(frozen=True, eq=False)
class DecayAnalysis:
    """Model-free analysis of a free-vibration decay (SI units)."""

    peak_times: np.ndarray
    """Times of the turning points [s], the release first."""
    peaks: np.ndarray
    """Signed displacements at the turning points [m], the release displacement first."""
    zero_crossings: np.ndarray
    """Times where the displacement crosses its rest level, one per half-cycle that crosses it [s] (sign changes
    of the noise about the rest after the sliders stick are not crossings: :func:`half_cycle_crossings`)."""
    amplitude: np.ndarray
    """Amplitude of each half-cycle, half its swing |x_{n+1} - x_n| / 2 [m]."""
    equivalent_period: np.ndarray
    """2 (t_{n+1} - t_n) per half-cycle [s]."""
    equivalent_damping: np.ndarray
    """d / sqrt(pi^2 + d^2), d = ln(A_{n-1} / A_n), between successive half-cycles [-] (one fewer than the
    half-cycles)."""
    damping_amplitude: np.ndarray
    """The amplitude each equivalent damping refers to, sqrt(A_{n-1} A_n) [m]."""
    law: DecayLaw | None
    """The combined decrement law fitted to the peaks (None with fewer than three)."""
    period: float
    """Damped period: twice the least-squares slope of the turning-point times against their count [s]
    (nan with fewer than two turning points)."""
    natural_period: float
    """``period sqrt(1 - zeta^2)``, zeta from the combined law [s]."""
    period_se: float = math.nan
    """Standard error of the period from the scatter of the turning-point times about their line [s]."""
    notes: tuple[str, ...] = field(default=())

    def stiffness(self, mass: float) -> float:
        """k = m (2 pi / T_n)^2 [N/m] for the mass m [kg]."""
        return float(mass) * (2.0 * math.pi / self.natural_period) ** 2

    def friction_force(self, mass: float) -> float:
        """F_s = k delta [N] from the combined law (nan without one)."""
        return self.law.friction_force(self.stiffness(mass)) if self.law else math.nan

    def summary(self, mass: float | None = None) -> dict[str, Any]:
        out: dict[str, Any] = {
            "half_cycles": int(max(self.peaks.size - 1, 0)), "period_s": self.period,
            "natural_period_s": self.natural_period, "period_se_s": self.period_se, "peaks_m": self.peaks.tolist(),
            "peak_times_s": self.peak_times.tolist(), "zero_crossings_s": self.zero_crossings.tolist(),
            "amplitude_m": self.amplitude.tolist(), "equivalent_period_s": self.equivalent_period.tolist(),
            "equivalent_damping": self.equivalent_damping.tolist(),
            "damping_amplitude_m": self.damping_amplitude.tolist(),
            "law": self.law.summary() if self.law else None, "notes": list(self.notes)}
        if mass is not None and self.law is not None:
            out["stiffness_N_m"] = self.stiffness(mass)
            out["friction_N"] = self.friction_force(mass)
        return out


def analyse_decay(t, x, release_time: float | None = None, noise: float = 0.0, rest: float = 0.0) -> DecayAnalysis:
    """Model-free analysis of the isolation layer's displacement x(t) [m] after the release.

    Parameters
    ----------
    t, x : arrays
        Times [s] and displacements [m] (offset removed: x = 0 where the isolators carry no force).
    release_time : float, optional
        The release instant [s]; samples before it are ignored (default: the first sample).
    noise : float
        Standard deviation of the noise on x [m]; swings within the range of the noise are not half-cycles.
    rest : float
        The unloaded position [m] the zero crossings refer to.
    """
    t, x = _check_series(t, x)
    notes = []
    if release_time is not None:
        t_r = float(release_time)
        if not (math.isfinite(t_r) and t[0] <= t_r < t[-1]):
            raise ParameterError("release_time", t_r, f"[{t[0]:.6g}, {t[-1]:.6g}) s, within the record", "s")
        before = x[t <= t_r]
        # at rest before the release: the pushed displacement is the mean level of the quiet segment
        x0 = float(np.median(before)) if before.size >= 3 else float(np.interp(t_r, t, x))
        after = t > t_r
        t, x = _check_series(np.concatenate([[t_r], t[after]]), np.concatenate([[x0], x[after]]))
    times, peaks = turning_points(t, x, noise, rest)
    crossings = half_cycle_crossings(t, x, times, peaks, rest) if x.size >= 8 else np.empty(0)
    if peaks.size >= 2:
        amplitude = 0.5 * np.abs(np.diff(peaks))
        teq = 2.0 * np.diff(times)
        with np.errstate(divide="ignore", invalid="ignore"):
            d = np.log(amplitude[:-1] / amplitude[1:])
            zeq = np.where(np.isfinite(d), d / np.sqrt(math.pi**2 + d * d), math.nan)
        zamp = np.sqrt(amplitude[:-1] * amplitude[1:])
        # the period: twice the slope of the turning-point times against their count (least squares over
        # all of them, not just the first and the last); the final stick is located less sharply than a
        # turning point (the record is flat after it), so it is left out when there are other half-cycles
        use = times[:-1] if times.size > 3 else times
        n_use = np.arange(use.size)
        slope = float(np.polyfit(n_use, use, 1)[0])
        period = 2.0 * slope
        period_se = math.nan
        if use.size >= 4:  # from the scatter of the turning-point times about the line
            resid = use - np.polyval(np.polyfit(n_use, use, 1), n_use)
            s2 = float(resid @ resid) / (use.size - 2)
            period_se = 2.0 * math.sqrt(s2 / float(np.sum((n_use - n_use.mean()) ** 2)))
    else:
        amplitude = teq = zeq = zamp = np.empty(0)
        period = period_se = math.nan
        notes.append("fewer than two turning points: no half-cycle to analyse")
    law = combined_decay_law(peaks) if peaks.size >= 5 else None
    zeta = law.damping_ratio if law and math.isfinite(law.damping_ratio) else 0.0
    natural = period * math.sqrt(1.0 - zeta * zeta) if math.isfinite(period) else math.nan
    return DecayAnalysis(peak_times=times, peaks=peaks, zero_crossings=crossings, amplitude=amplitude,
                         equivalent_period=teq, equivalent_damping=zeq, damping_amplitude=zamp, law=law,
                         period=period, period_se=period_se, natural_period=natural, notes=tuple(notes))


def hysteresis_loop(x, acceleration, mass: float) -> tuple[np.ndarray, np.ndarray]:
    """The isolators' total force ``F = -m x_ddot`` [N] against the displacement x [m].

    For a rigid superstructure on the isolation layer, F is the force of rubber, dampers and sliders
    together (Newton's law with no external force after the release). Returns (x, F).
    """
    x = np.asarray(x, dtype=float)
    acc = np.asarray(acceleration, dtype=float)
    if x.shape != acc.shape:
        raise ParameterError("acceleration", f"{acc.size} sample(s)", f"{x.size} samples, like x")
    m = float(mass)
    if not (math.isfinite(m) and m > 0):
        raise ParameterError("mass", m, "(0, inf)", "kg")
    return x, -m * acc


@dataclass(frozen=True)
class LoopEstimate:
    """The bilinear isolators read off the hysteresis loop (:func:`bilinear_loop`), SI units."""

    k1: float
    """Initial (unloading) stiffness [N/m]: the slope right after each reversal."""
    k2: float
    """Post-yield stiffness [N/m]: the slope of the loading branches at large amplitude."""
    characteristic_strength: float
    """Q = F_y (1 - k2 / k1) + F_s [N]: the loading branches' intercept at x = 0."""
    friction: float
    """F_s = Q - f_p [N]: the part of Q that flips at the reversal itself (the sliders; may come out slightly
    negative where there are none)."""
    damping: float
    """Viscous coefficient c [N s/m]."""
    reversals: int
    """Reversals whose elastic unloading entered the estimate of k1."""
    friction_se: float = math.nan
    """Standard error of F_s from the scatter of the reversals' intercepts 2 f_p (nan with one reversal) [N]."""

    @property
    def yield_force(self) -> float:
        """F_y = (Q - F_s) / (1 - k2 / k1) [N]."""
        return (self.characteristic_strength - self.friction) / (1.0 - self.k2 / self.k1)


def bilinear_loop(t, x, acceleration, mass: float, peak_times, peaks, release_time: float) -> LoopEstimate | None:
    """Bilinear isolators (with dampers and sliders) from the hysteresis loop, without fitting a model.

    t [s], x [m] and the acceleration [m/s^2] on one time axis, the sensor's zero removed from the
    acceleration, the samples after the release instant t_r [s]; peak_times and peaks: the turning points
    (:func:`turning_points`).
    The restoring force is ``F = -m x_ddot`` (:func:`hysteresis_loop`) and the velocity v the integral of the
    acceleration from rest at the release. In a half-cycle moving in direction s = +-1, once yielded,

        F = k2 x + s Q + c v,   Q = F_y (1 - k2 / k1) + F_s,                                     (L)

    so k2, Q and c (and a constant -k2 e for the displacement sensor's zero e, where branches of both
    directions enter) follow by linear least squares from the samples of the outer half of each large
    half-cycle's travel. At a reversal the sliders' force flips at once (F jumps by 2 F_s) and the rubber
    unloads elastically, with stiffness k1, until it meets (L) of the new direction; the gap to (L),
    ``g = s (k2 x + s Q + c v - F)``, is ``2 f_p - (k1 - k2) u`` there (u the travel since the reversal,
    f_p = F_y (1 - k2 / k1)). A common slope and an intercept per reversal by least squares over the
    samples with g above a quarter of its value at the reversal give k1 - k2 and 2 f_p, so F_s = Q - f_p.
    The outer samples of (L) are then those past the elastic travel 2 f_p / (k1 - k2), and both steps are
    repeated once. None where the record has fewer than two yielded half-cycles or no elastic samples.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    acc = np.asarray(acceleration, dtype=float)
    peak_times = np.asarray(peak_times, dtype=float)
    peaks = np.asarray(peaks, dtype=float)
    if peaks.size < 3 or t.size < 20:
        return None
    force = -float(mass) * acc
    keep = t > float(release_time)
    t, x, acc, force = t[keep], x[keep], acc[keep], force[keep]
    if t.size < 20:
        return None
    v = acc[0] * (t[0] - float(release_time)) + np.concatenate([[0.0], np.cumsum(0.5 * (acc[1:] + acc[:-1])
                                                                                  * np.diff(t))])
    swing = np.abs(np.diff(peaks))
    half = np.searchsorted(peak_times, t, side="right") - 1  # the half-cycle of each sample
    inside = (half >= 0) & (half < swing.size)
    half = np.where(inside, half, 0)
    s = np.where(inside, np.sign(peaks[np.minimum(half + 1, peaks.size - 1)] - peaks[half]), 0.0)
    u = s * (x - peaks[half])  # travel since the half-cycle's turning point
    yielded = swing >= 0.5 * swing[0]  # first pass: the half-cycles of at least half the first swing
    elastic_travel = 0.0
    est = None
    for _ in range(2):
        lo = 0.5 * swing[half] if est is None else np.minimum(1.2 * elastic_travel, 0.8 * swing[half])
        outer = inside & yielded[half] & (u > lo) & (u < swing[half])
        if np.count_nonzero(outer) < 6:
            return est
        # a constant h = -k2 e for the displacement sensor's zero e, where both directions are there
        both = np.unique(s[outer]).size == 2
        A = np.column_stack([x[outer], s[outer], v[outer]] + ([np.ones(np.count_nonzero(outer))] if both else []))
        coef = np.linalg.lstsq(A, force[outer], rcond=None)[0]
        k2, Q, c, h = float(coef[0]), float(coef[1]), float(coef[2]), float(coef[3]) if both else 0.0
        if not (k2 > 0.0 and Q > 0.0):
            return est
        gap = s * (k2 * x + s * Q + c * v + h - force)
        runs = []
        for n in range(swing.size):  # the release, and each reversal after a yielded half-cycle
            if n > 0 and not yielded[n - 1]:
                continue
            mine = np.nonzero(inside & (half == n))[0]
            if mine.size < 6:
                continue
            g0 = float(np.median(gap[mine[:3]]))
            if not g0 > 0.0:
                continue
            run = mine[: int(np.argmax(gap[mine] < 0.25 * g0)) or mine.size]
            if run.size >= 6:
                runs.append((n, run))
        if not runs:
            return est
        idx = np.concatenate([run for _, run in runs])
        B = np.zeros((idx.size, len(runs) + 1))
        i0 = 0
        for j, (n, run) in enumerate(runs):
            B[i0:i0 + run.size, j] = 1.0
            # the travel from the reversal's position as the cubic through the run's own samples gives it
            # at the turning-point time (linear in the samples: the located turning point of a noisy record
            # lies outward of the truth by about 0.7 noise levels, which (k1 - k2) turns into f_p)
            tau = t[run] - peak_times[n]
            origin = float(np.linalg.lstsq(np.vander(tau, 6), x[run], rcond=None)[0][-1])
            B[i0:i0 + run.size, -1] = -s[run] * (x[run] - origin)
            i0 += run.size
        coef = np.linalg.lstsq(B, gap[idx], rcond=None)[0]
        dk, fp = float(coef[-1]), 0.5 * float(np.mean(coef[:-1]))
        if not (dk > 0.0 and fp > 0.0):  # F_s = Q - f_p may come out a rounding below 0 without sliders
            return est
        elastic_travel = 2.0 * fp / dk
        fp_se = 0.5 * float(np.std(coef[:-1], ddof=1)) / math.sqrt(len(runs)) if len(runs) > 1 else math.nan
        est = LoopEstimate(k1=k2 + dk, k2=k2, characteristic_strength=Q, friction=Q - fp, damping=max(c, 0.0),
                           reversals=len(runs), friction_se=fp_se)
        yielded = swing >= 2.0 * elastic_travel  # second pass: every half-cycle past the elastic travel
    return est
