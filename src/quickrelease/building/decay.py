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

from ..errors import ParameterError
from ._zigzag import zigzag_scan

__all__ = ["DecayAnalysis", "DecayLaw", "LAW_NAMES", "LawFit", "LoopEstimate", "MidMotionStart", "analyse_decay",
           "bilinear_loop", "combined_decay_law", "decay_laws", "estimate_noise", "first_turning_point",
           "half_cycle_crossings", "hysteresis_loop", "power_next_amplitude", "quadratic_next_amplitude",
           "turning_points", "turning_points_with_errors", "zero_crossings"]


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
    chi2: float = math.nan
    """Generalised chi-square of the law (:class:`LawFit`)."""
    dof: int = 0
    """Half-cycles less unknowns."""
    aic: float = math.nan
    known_errors: bool = False
    """Whether chi2 refers to known peak errors."""
    at_bound: tuple[str, ...] = ()
    """Parameters on a bound of their physical range (``ratio`` at 1: zeta = 0; ``friction_displacement``
    at 0)."""

    @property
    def reduced_chi2(self) -> float:
        """chi2 / dof (nan where the peak errors are not known or without degrees of freedom)."""
        return self.chi2 / self.dof if self.known_errors and self.dof > 0 else math.nan

    def friction_force(self, stiffness: float) -> float:
        """F_s = k delta [N] for the stiffness k [N/m]."""
        return stiffness * self.friction_displacement

    def summary(self) -> dict[str, Any]:
        return {"ratio": self.ratio, "ratio_se": self.ratio_se, "friction_displacement_m": self.friction_displacement,
                "friction_displacement_se_m": self.friction_displacement_se, "damping_ratio": self.damping_ratio,
                "damping_ratio_se": self.damping_ratio_se, "rms_m": self.rms,
                "rms_viscous_only_m": self.rms_viscous_only, "rms_friction_only_m": self.rms_friction_only,
                "half_cycles": self.half_cycles, "chi2": self.chi2, "dof": self.dof,
                "reduced_chi2": self.reduced_chi2, "aic": self.aic, "at_bound": list(self.at_bound)}


def combined_decay_law(peaks, offset: bool = True, peak_se=None) -> DecayLaw:
    """Fit (*) to successive signed turning points [m]: ``x_{n+1} = -r x_n + g s_n + h``.

    ``s_n = +1`` when x_n is a maximum and -1 at a minimum (the direction of the swing, which does not
    depend on the sensor's zero), ``g = (1 + r) delta`` and ``h = (1 + r) e`` (e the reading where the
    isolators carry no force; h = 0 when ``offset`` is False). Bounded generalised least squares
    (:func:`decay_laws`: r in (0, 1], so 0 <= zeta < 1, and delta >= 0, so F_s >= 0; each peak's error
    ``peak_se`` [m] where known, the residuals' correlation through the shared peaks); the standard errors
    include the law's own misfit. Needs one more peak than unknowns.
    """
    x = np.asarray(peaks, dtype=float)
    unknowns = 3 if offset else 2
    if x.ndim != 1 or x.size < unknowns + 1 or not np.all(np.isfinite(x)):
        raise ParameterError("peaks", f"{x.size} value(s)", f"at least {unknowns + 1} finite successive peaks", "m")
    fits = {f.name: f for f in decay_laws(x, peak_se, offset, laws=("viscous", "coulomb", "combined"))}
    law = fits["combined"]
    p, se = law.parameters, law.std_errors
    return DecayLaw(ratio=p["ratio"], friction_displacement=p["friction_displacement"], ratio_se=se["ratio"],
                    friction_displacement_se=se["friction_displacement"], damping_ratio=p["damping_ratio"],
                    damping_ratio_se=se["damping_ratio"], rms=law.rms,
                    rms_viscous_only=fits["viscous"].rms if "viscous" in fits else math.nan,
                    rms_friction_only=fits["coulomb"].rms if "coulomb" in fits else math.nan,
                    half_cycles=x.size - 1, rest=p.get("rest", math.nan), chi2=law.chi2, dof=law.dof,
                    aic=law.aic, known_errors=law.known_errors, at_bound=law.at_bound)


# -- the decrement laws ----------------------------------------------------------------------------------

#: The decrement laws fitted to the turning points (:func:`decay_laws`), with their parameters.
LAW_NAMES = ("viscous", "coulomb", "combined", "quadratic", "power")


@dataclass(frozen=True)
class LawFit:
    """One decrement law fitted to the successive turning points (:func:`decay_laws`), SI units.

    Every law maps the amplitude ``a_n = s_n (x_n - e)`` of a turning point about the rest reading e to the
    next one, ``a_{n+1} = F(a_n)`` (s_n = +1 at a maximum, -1 at a minimum), and is fitted with its
    parameters inside their physical range (a ratio r in (0, 1], so 0 <= zeta < 1; friction, drag and
    decrement coefficients >= 0).
    """

    name: str
    """``viscous``, ``coulomb``, ``combined``, ``quadratic`` or ``power``."""
    parameters: dict[str, float]
    """The law's parameters (see :func:`decay_laws`) and the rest reading ``rest`` e [m]."""
    std_errors: dict[str, float]
    """Their standard errors, scaled up by sqrt(chi2 / dof) where the law misfits the peaks."""
    chi2: float
    """Generalised chi-square of the one-step residuals (peak errors and their correlation, see
    :func:`decay_laws`); with unknown peak errors the residual sum of squares [m^2]."""
    dof: int
    """Equations (half-cycles) less parameters."""
    aic: float
    """Akaike's criterion, ``-2 ln L + 2 k`` (Gaussian errors; unknown scale profiled out where the peak
    errors are not known)."""
    rms: float
    """RMS one-step residual of the peaks [m]."""
    known_errors: bool = True
    """Whether chi2 refers to given peak errors (else their common scale comes from the residuals)."""
    at_bound: tuple[str, ...] = ()
    """Parameters that ended on a bound of their physical range (zeta = 0, F_s = 0, ...)."""

    @property
    def reduced_chi2(self) -> float:
        """chi2 / dof (nan without degrees of freedom, and where the peak errors are not known)."""
        return self.chi2 / self.dof if self.known_errors and self.dof > 0 else math.nan

    def summary(self) -> dict[str, Any]:
        return {"law": self.name, "parameters": dict(self.parameters), "std_errors": dict(self.std_errors),
                "chi2": self.chi2, "dof": self.dof, "reduced_chi2": self.reduced_chi2, "aic": self.aic,
                "rms_m": self.rms, "known_errors": self.known_errors, "at_bound": list(self.at_bound)}


def _psi(z):
    """``z - ln(1 + z)`` without cancellation (series below |z| = 1e-3), z > -1."""
    z = np.asarray(z, dtype=float)
    out = z - np.log1p(z)
    small = np.abs(z) < 1e-3
    zs = z[small]
    out[small] = zs**2 / 2 - zs**3 / 3 + zs**4 / 4 - zs**5 / 5 + zs**6 / 6
    return out


def quadratic_next_amplitude(a, mu: float) -> np.ndarray:
    """The amplitude after one half-cycle of ``x'' + mu x'|x'| + w^2 x = 0`` from rest at amplitude a [m].

    Within a half-cycle the square of the velocity obeys a linear equation in x, ``d(v^2)/dx = 2 mu v^2
    - 2 w^2 x`` (moving towards -x), whose solution from rest at x = a reaches rest again at x = -b with

        (1 + 2 mu a) exp(-2 mu a) = (1 - 2 mu b) exp(2 mu b),

    independent of w (exact; its first order, ``b = a - (4/3) mu a^2``, is the averaged decrement of
    quadratic damping, Nayfeh and Mook, Nonlinear Oscillations, Wiley 1979). Solved for q = 2 mu b in (0, 1)
    by Newton's method on ``psi(-q) = psi(p)``, psi(z) = z - ln(1 + z), p = 2 mu a (convex in q: monotone
    from the start q = min(p, 1)). mu [1/m] >= 0.
    """
    a = np.asarray(a, dtype=float)
    if mu <= 0.0:
        return a.copy()
    p = 2.0 * mu * np.maximum(a, 0.0)
    target = _psi(p)
    q = np.minimum(p, 1.0 - 1e-15)
    for _ in range(80):
        g = _psi(-q) - target
        step = g * (1.0 - q) / np.maximum(q, 1e-300)
        q_new = np.clip(q - step, 0.0, 1.0 - 1e-15)
        if np.all(np.abs(q_new - q) <= 1e-14 * np.maximum(q, 1e-300)):
            q = q_new
            break
        q = q_new
    return np.where(a > 0.0, q / (2.0 * mu), a)


def power_next_amplitude(a, kappa: float, alpha: float, scale: float = 1.0) -> np.ndarray:
    """The amplitude after one half-cycle under the power-law decrement ``dA/dn = -kappa (A / scale)^alpha
    scale`` (A [m], scale [m] the reference amplitude, n the count of half-cycles).

    A damping force ``c |v|^alpha sgn v`` takes ``c w^(alpha + 1) A^(alpha + 1) int |sin|^(alpha + 1)`` of
    energy per half-cycle (the energy balance of Jacobsen's equivalent damping, J. Appl. Mech. 1930; the
    first-order averaging of Nayfeh and Mook 1979), so the amplitude falls per half-cycle in proportion to
    A^alpha. Integrated over one half-cycle: ``A^(1 - alpha) - kappa (1 - alpha)`` (scaled), 0 once that is
    not positive; ``A exp(-kappa)`` at alpha = 1. Exact for viscous damping (alpha = 1, kappa = -ln r) and
    for Coulomb friction (alpha = 0, kappa = 2 delta / scale); alpha = 2 is the averaged quadratic law.
    """
    y = np.maximum(np.asarray(a, dtype=float), 0.0) / scale
    one = 1.0 - alpha
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if abs(one) < 1e-9:
            out = y * np.exp(-kappa * y ** (alpha - 1.0))
        else:
            base = 1.0 - one * kappa * np.where(y > 0, y, 1.0) ** (alpha - 1.0)
            out = np.where(base > 0.0, y * np.exp(np.log(np.where(base > 0, base, 1.0)) / one), 0.0)
    return np.where(y > 0.0, out, 0.0) * scale


def _directions(x: np.ndarray) -> np.ndarray:
    """s_n = +1 where turning point n is a maximum, -1 at a minimum (the direction of the next swing)."""
    return -np.sign(x[1:] - x[:-1])


def _one_step_cov(slopes_next: np.ndarray, se: np.ndarray, slope_n: np.ndarray) -> np.ndarray:
    """Covariance of the one-step residuals ``res_n = x_{n+1} - X(x_n)``, n = 0..N-1, from independent peak
    errors se_n: ``res_n = eps_{n+1} + F'(a_n) eps_n``, so var = se_{n+1}^2 + F'_n^2 se_n^2 and
    cov(res_n, res_{n+1}) = F'_{n+1} se_{n+1}^2 (the peak x_{n+1} enters both)."""
    n = slope_n.size
    cov = np.diag(se[1:] ** 2 + slope_n**2 * se[:-1] ** 2)
    if n > 1:
        off = slopes_next * se[1:-1] ** 2
        cov[np.arange(n - 1), np.arange(1, n)] = off
        cov[np.arange(1, n), np.arange(n - 1)] = off
    return cov


def _whitener(cov: np.ndarray) -> tuple[np.ndarray, float]:
    """Lower Cholesky factor L of the covariance and ln det(cov)."""
    L = np.linalg.cholesky(cov)
    return L, 2.0 * float(np.sum(np.log(np.diag(L))))


#: Smallest viscous amplitude ratio per half-cycle a law may take (zeta just below 1).
_R_MIN = 1e-9
#: Relative floor of the residual RMS (an exact law's rounding) in the criteria of unknown peak errors.
_RMS_FLOOR = 1e-11


def _zeta_of_ratio(r: float) -> tuple[float, float]:
    """zeta = -ln r / sqrt(pi^2 + ln^2 r) and d zeta / d r, r in (0, 1]."""
    lr = math.log(r)
    h = math.hypot(math.pi, lr)
    return -lr / h, -(math.pi**2) / h**3 / r


def _on_bound(value: float, lo: float, hi: float, tol: float) -> bool:
    """Whether value lies on the finite bound lo or hi (within tol relative)."""
    return any(math.isfinite(b) and abs(value - b) <= tol * max(1.0, abs(b)) for b in (lo, hi))


def _box_lstsq(A: np.ndarray, y: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """min |A c - y| with lo <= c <= hi, exactly: the unconstrained least squares where it is feasible, else the
    best feasible solution over the faces of the box (each bounded coefficient free, or fixed at one of its
    finite bounds; a convex problem's minimum lies on one of them). For the two bounded coefficients of the
    decrement laws that is at most nine small solves."""
    import itertools

    bounded = [i for i in range(A.shape[1]) if math.isfinite(lo[i]) or math.isfinite(hi[i])]
    best, best_rss = None, math.inf
    options = [[None] + [b for b in (lo[i], hi[i]) if math.isfinite(b)] for i in bounded]
    for fixes in itertools.product(*options):
        c = np.zeros(A.shape[1])
        fixed = {i: v for i, v in zip(bounded, fixes, strict=True) if v is not None}
        free = [i for i in range(A.shape[1]) if i not in fixed]
        for i, v in fixed.items():
            c[i] = v
        rhs = y - A[:, list(fixed)] @ np.array(list(fixed.values())) if fixed else y
        if free:
            c[free] = np.linalg.lstsq(A[:, free], rhs, rcond=None)[0]
        if np.any(c < lo - 1e-12 * np.maximum(1.0, np.abs(lo))) or np.any(c > hi + 1e-12 * np.maximum(1.0, np.abs(hi))):
            continue
        rss = float(np.sum((A @ c - y) ** 2))
        if rss < best_rss * (1.0 - 1e-12) or best is None:
            best, best_rss = np.clip(c, lo, hi), rss
        if not fixed:  # the unconstrained solution is feasible: it is the minimum
            break
    return best


def _linear_law(name: str, x: np.ndarray, s: np.ndarray, se: np.ndarray, offset: bool):
    """The viscous, Coulomb and combined laws, linear in (r, g, h): ``x_{n+1} = -r x_n + g s_n + h`` with
    g = (1 + r) delta, h = (1 + r) e, solved by bounded generalised least squares (lsq_linear on the
    whitened equations; the residual covariance of :func:`_one_step_cov` with F' = r, updated three times).
    Returns (parameters, covariance, whitened residuals, raw residuals, ln det cov, bound flags)."""
    xn, xn1 = x[:-1], x[1:]
    one = np.ones_like(xn)
    if name == "coulomb":  # r = 1: x_{n+1} + x_n = g s_n + h
        cols, y = [s] + ([one] if offset else []), xn1 + xn
        lo, hi = [0.0] + ([-np.inf] if offset else []), [np.inf] + ([np.inf] if offset else [])
    elif name == "viscous":
        cols, y = [-xn] + ([one] if offset else []), xn1
        lo, hi = [_R_MIN] + ([-np.inf] if offset else []), [1.0] + ([np.inf] if offset else [])
    else:
        cols, y = [-xn, s] + ([one] if offset else []), xn1
        lo, hi = [_R_MIN, 0.0] + ([-np.inf] if offset else []), [1.0, np.inf] + ([np.inf] if offset else [])
    A = np.column_stack(cols)
    scale = np.maximum(np.max(np.abs(A), axis=0), np.finfo(float).tiny)  # columns of like size
    r = 1.0
    coef = np.zeros(A.shape[1])
    for _ in range(4):
        cov = _one_step_cov(np.full(xn.size - 1, r), se, np.full(xn.size, r))
        L, logdet = _whitener(cov)
        Li = np.linalg.inv(L)  # a few dozen half-cycles at most: the explicit inverse is cheapest
        Aw = Li @ (A / scale)
        yw = Li @ y
        coef = _box_lstsq(Aw, yw, np.array(lo) * scale, np.array(hi) * scale) / scale
        r = 1.0 if name == "coulomb" else float(coef[0])
    resid = y - A @ coef
    resid_w = Li @ resid
    cov_coef = np.linalg.pinv(Aw.T @ Aw) / np.outer(scale, scale)
    bound = [_on_bound(c, lo_, hi_, 1e-12) for c, lo_, hi_ in zip(coef, lo, hi, strict=True)
             if math.isfinite(lo_) or math.isfinite(hi_)]
    return coef, cov_coef, resid_w, resid, logdet, bound


def _nonlinear_law(name: str, x: np.ndarray, s: np.ndarray, se: np.ndarray, offset: bool, starts, scale: float):
    """The quadratic and power laws: bounded nonlinear least squares (scipy least_squares, trust region
    reflective) of the whitened one-step residuals, the covariance updated with the law's slope F'(a).

    Solved in u = theta / (1, ..., scale): the law's coefficients are numbers per half-cycle (mu ref, kappa, the
    exponent), the rest reading e counts in ``scale`` (the first half-swing) [m]. scipy's step tolerance compares the
    step's norm with xtol times the norm of the parameters: in theta, a rest reading of tiny peaks (1e-5 m) had its
    steps measured against the coefficients (and the difference step of e, sqrt(eps) max(1, |e|) m, was 1e-3 of
    the amplitude); in u each counts against its own magnitude. e is measured from a level inside the peaks
    (:func:`decay_laws`), so a sensor's zero far away does not set either."""
    from scipy.optimize import least_squares

    def next_amp(a, th):
        if name == "quadratic":
            return quadratic_next_amplitude(a, th[0] / scale)
        return power_next_amplitude(a, th[0], th[1], scale)

    npar = 1 if name == "quadratic" else 2
    lo = [0.0] + ([0.0] if name == "power" else []) + ([-np.inf] if offset else [])
    hi = [np.inf] + ([3.0] if name == "power" else []) + ([np.inf] if offset else [])
    unit = np.array([1.0] * npar + ([scale] if offset else []))  # the solver's coordinates u = theta / unit
    lo, hi = np.array(lo), np.array(hi)

    def raw(th):
        e = th[npar] if offset else 0.0
        a = s * (x[:-1] - e)
        return x[1:] - (e - s * next_amp(a, th))

    def slopes(th):
        e = th[npar] if offset else 0.0
        a = np.maximum(s * (x[:-1] - e), 1e-300)
        h = 1e-6
        return (next_amp(a * (1 + h), th) - next_amp(a * (1 - h), th)) / (2 * h * a)

    def run(th):
        f = slopes(th)
        cov = _one_step_cov(f[1:], se, f)  # the last peak's slope enters the next equation's covariance only
        L, logdet = _whitener(cov)
        Li = np.linalg.inv(L)
        sol = least_squares(lambda u: Li @ raw(u * unit), th / unit, bounds=(lo / unit, hi / unit), method="trf",
                            x_scale=1.0, xtol=1e-10, ftol=1e-10, gtol=1e-10, max_nfev=200)
        return float(sol.fun @ sol.fun), sol.x * unit, sol.jac / unit, sol.fun, logdet

    # each start once with the covariance at the start, then the best one twice more with its own
    best = min((run(np.clip(np.asarray(th0, dtype=float), lo, hi)) for th0 in starts), key=lambda b: b[0])
    for _ in range(2):
        best = run(best[1])
    chi2, th, jac, resid_w, logdet = best
    cov_th = np.linalg.pinv(jac.T @ jac)
    bound = [_on_bound(v, a, b, 1e-9) for v, a, b in zip(th, lo, hi, strict=True)
             if math.isfinite(a) or math.isfinite(b)]
    return th, cov_th, resid_w, raw(th), logdet, bound


#: The peaks :func:`decay_laws` takes: the smallest swing between successive peaks and the largest reading [m].
PEAK_RANGE = (1e-100, 1e100)


def decay_laws(peaks, peak_se=None, offset: bool = True, laws=LAW_NAMES) -> tuple[LawFit, ...]:
    """The decrement laws fitted to successive signed turning points [m], best (lowest AIC) first.

    Each law maps one turning point to the next, ``x_{n+1} = e - s_n F(s_n (x_n - e))`` (s_n = +1 at a
    maximum, e the reading where the restoring force vanishes, fitted when ``offset``), with its
    parameters in their physical range:

    ========== ===================================== ================================================
    law        F(a) per half-cycle                   parameters (bounds)
    ========== ===================================== ================================================
    viscous    r a                                   ratio r in (0, 1] (zeta in [0, 1)), damping_ratio
    coulomb    a - 2 delta                           friction_displacement delta = F_s / k >= 0
    combined   r a - (1 + r) delta                   both (Feeny and Liang, J. Sound Vib. 196(4), 1996)
    quadratic  (1 + 2 mu a) e^(-2 mu a)              quadratic_coefficient mu >= 0 [1/m] (velocity
               = (1 - 2 mu F) e^(2 mu F)             squared damping, :func:`quadratic_next_amplitude`)
    power      dA/dn = -kappa (A / A_0)^alpha A_0    kappa >= 0, exponent alpha in [0, 3]
                                                     (:func:`power_next_amplitude`, A_0 the first amplitude)
    ========== ===================================== ================================================

    ``peak_se`` [m]: the standard error of each turning point (e.g. from the local fits of
    :func:`turning_points`; scalar or one per peak). The one-step residuals ``x_{n+1} - X(x_n)`` are
    correlated (each peak enters two of them, once as the regressor) and have variance ``se_{n+1}^2 +
    F'^2 se_n^2``: the fit is generalised least squares with that covariance, so chi2 is a true chi-square
    with ``dof`` degrees of freedom where the law holds, and the standard errors are scaled up by
    sqrt(chi2 / dof) where it does not (the law's own misfit). Without ``peak_se`` the errors' common
    scale comes from the residuals. AIC ``= chi2 + ln det C + 2 k`` (k parameters, e included), or with
    unknown scale ``n ln(chi2 / n) + ln det C + 2 k``; the lowest describes the peaks best for its
    parameters (a difference above about 4 is clear support). With ``offset`` the laws are fitted to the peaks
    measured from the middle of the last swing (and e reported on the sensor's scale): the answer does not depend
    on where the sensor's zero lies.
    """
    x = np.asarray(peaks, dtype=float)
    if x.ndim != 1 or x.size < 3 or not np.all(np.isfinite(x)):
        raise ParameterError("peaks", f"{x.size} value(s)", "at least 3 finite successive peaks", "m")
    # the laws' arithmetic (squared swings, their logarithms, the one-step covariances) stays finite for readings
    # within +-PEAK_RANGE[1] and swings of at least PEAK_RANGE[0] (1e308 overflowed, 1e-300 underflowed to a
    # math domain error; 1e-99 and 1e99 fit as 1)
    top = float(np.max(np.abs(x)))
    swing = float(np.min(np.abs(np.diff(x)))) if top <= PEAK_RANGE[1] else math.nan
    if not (top <= PEAK_RANGE[1] and (swing >= PEAK_RANGE[0] or swing == 0.0)):  # (equal peaks: refused below)
        raise ParameterError("peaks", f"readings up to {top:.3g}" + ("" if math.isnan(swing) else
                             f" with swings down to {swing:.3g}"),
                             f"readings within +-{PEAK_RANGE[1]:g} and swings of at least {PEAK_RANGE[0]:g}", "m")
    known = peak_se is not None
    se = np.broadcast_to(np.asarray(peak_se if known else 1.0, dtype=float), x.shape).astype(float)
    if not np.all(np.isfinite(se) & (se > 0)):
        raise ParameterError("peak_se", "non-positive or non-finite", "positive standard errors", "m")
    s = _directions(x)
    if np.any(s == 0):
        raise ParameterError("peaks", "two equal successive peaks", "alternating turning points", "m")
    n = x.size - 1
    ref = max(abs(x[0] - x[1]) / 2.0, np.finfo(float).tiny)
    floor = n * (_RMS_FLOOR * float(np.max(np.abs(x)))) ** 2  # the readings' rounding: of x as read
    # with a rest reading fitted, the peaks measured from the middle of the last swing (exactly, where the zero is
    # far: Sterbenz), e from there. A sensor's zero far from the motion (a survey coordinate, 6e6 m) set the
    # nonlinear laws' step tolerance (1e-10 |theta|) and e's difference step (sqrt(eps) |e|, 9 cm): the power law
    # ended 140 standard errors away; and the linear laws' columns x_n and 1 became parallel to 1e-7, the
    # pseudo-inverse dropped their difference and the combined law's standard error of zeta fell to 1e-9
    level = 0.5 * (float(x[-2]) + float(x[-1])) if offset else 0.0
    x = x - level
    fits = []
    linear = {}
    unknown = sorted(set(laws) - set(LAW_NAMES))
    if unknown:
        raise ParameterError("laws", unknown[0], ", ".join(LAW_NAMES))
    for name in laws:
        k = {"viscous": 1, "coulomb": 1, "combined": 2, "quadratic": 1, "power": 2}[name] + (1 if offset else 0)
        if n < k + 1:
            continue
        if name in ("viscous", "coulomb", "combined"):
            coef, cov, rw, raw, logdet, bound = _linear_law(name, x, s, se, offset)
            linear[name] = coef
            params, grads, names = _physical(name, coef, offset)
        else:
            r = float(linear.get("combined", linear.get("viscous", [0.9]))[0]) if linear else 0.9
            r = min(max(r, 0.05), 1.0)
            mean_a = float(np.mean(np.abs(np.diff(x)))) / 2.0
            if name == "quadratic":
                starts = [[max(1.5 * (1.0 - r) * ref / mean_a, 1e-6)], [1e-3], [1.0]]
            else:
                starts = [[max(-math.log(r), 1e-6), 1.0], [max(2.0 * (1.0 - r) * mean_a / ref, 1e-6), 0.0],
                          [max(1.5 * (1.0 - r), 1e-6), 2.0]]
            e0 = float(linear["combined"][-1] / (1.0 + linear["combined"][0])) if offset and "combined" in linear \
                else 0.0
            starts = [st + ([e0] if offset else []) for st in starts]
            coef, cov, rw, raw, logdet, bound = _nonlinear_law(name, x, s, se, offset, starts, ref)
            params, grads, names = _physical(name, coef, offset, ref)
        if offset:
            params["rest"] += level
        chi2 = float(rw @ rw)
        dof = n - k
        if known:
            factor = max(1.0, chi2 / dof) if dof > 0 else 1.0
            aic = chi2 + logdet + 2.0 * k
        else:
            factor = chi2 / dof if dof > 0 else math.nan
            aic = n * math.log(max(chi2, floor) / n) + logdet + 2.0 * k
        ses = {}
        for pname, g in grads.items():
            g = np.asarray(g, dtype=float)
            ses[pname] = math.sqrt(max(float(g @ cov @ g), 0.0) * factor) if math.isfinite(factor) else math.nan
        fits.append(LawFit(name=name, parameters=params, std_errors=ses, chi2=chi2, dof=dof, aic=aic,
                           rms=math.sqrt(float(np.mean(raw**2))), known_errors=known,
                           at_bound=tuple(nm for nm, b in zip(names, bound, strict=False) if b)))
    return tuple(sorted(fits, key=lambda f: f.aic))


def _physical(name: str, coef: np.ndarray, offset: bool, ref: float = 1.0):
    """The law's physical parameters from its fitted coefficients, the gradient of each with respect to
    them (for the delta method), and the names of the bounded coefficients (in order)."""
    c = [float(v) for v in coef]
    p: dict[str, float] = {}
    g: dict[str, list[float]] = {}
    if name == "coulomb":  # (g, h): delta = g / 2, e = h / 2
        p["friction_displacement"], g["friction_displacement"] = c[0] / 2, [0.5] + ([0.0] if offset else [])
        if offset:
            p["rest"], g["rest"] = c[1] / 2, [0.0, 0.5]
        return p, g, ["friction_displacement"]
    if name in ("viscous", "combined"):
        r = c[0]
        zeta, dz = _zeta_of_ratio(r)
        m = len(c)
        p["ratio"], g["ratio"] = r, [1.0] + [0.0] * (m - 1)
        p["damping_ratio"], g["damping_ratio"] = zeta, [dz] + [0.0] * (m - 1)
        names = ["ratio"]
        if name == "combined":
            p["friction_displacement"] = c[1] / (1 + r)
            g["friction_displacement"] = [-c[1] / (1 + r) ** 2, 1 / (1 + r)] + ([0.0] if offset else [])
            names.append("friction_displacement")
        if offset:
            p["rest"] = c[-1] / (1 + r)
            g["rest"] = [-c[-1] / (1 + r) ** 2] + [0.0] * (m - 2) + [1 / (1 + r)]
        return p, g, names
    m = len(c)
    if name == "quadratic":  # (mu ref, e)
        p["quadratic_coefficient"], g["quadratic_coefficient"] = c[0] / ref, [1 / ref] + [0.0] * (m - 1)
        names = ["quadratic_coefficient"]
    else:  # (kappa, alpha, e)
        p["kappa"], g["kappa"] = c[0], [1.0] + [0.0] * (m - 1)
        p["exponent"], g["exponent"] = c[1], [0.0, 1.0] + [0.0] * (m - 2)
        p["reference_amplitude"], g["reference_amplitude"] = ref, [0.0] * m
        names = ["kappa", "exponent"]
    if offset:
        p["rest"], g["rest"] = c[-1], [0.0] * (m - 1) + [1.0]
    return p, g, names


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


def _refine_extremum(t: np.ndarray, x: np.ndarray, i: int, half: int, noise: float = 0.0,
                     jitter: float = 0.0) -> tuple[float, float, float, float]:
    """Time [s] and value [m] of the turning point near sample i, and their standard errors.

    The velocity vanishes at the turning point tp on both sides, but the acceleration (and every higher
    derivative) jumps there when the sliders' force changes sign, so each side has its own Taylor series:
    ``x = X + a_s u^2 + b_s u^3 + c_s u^4`` (u = t - tp, s the side), with X shared. For each tp the model
    is linear in its seven coefficients; tp minimises the residual in value (bounded scalar search between
    the samples next to i). With ``half`` samples a side of about a twelfth of a half-cycle, the neglected
    fifth-order terms are about 1e-7 of the amplitude.

    Time-stamp jitter (standard deviation ``jitter`` [s]) moves a sample's value by ``jitter |dx/dt|``:
    nothing at the turning point, most on the flanks. With jitter > 0 each sample is weighted by
    ``1 / (noise^2 + jitter^2 (dx/dt)^2)`` (dx/dt from an unweighted first pass), so X rests on the samples
    whose values the jitter does not move. The standard errors come from the weighted least squares
    (tp included through the model's derivative), scaled by the residual's own size where no noise is
    given; nan with fewer than nine samples.
    """
    lo, hi = max(i - half, 0), min(i + half + 1, t.size)
    tt, xx = t[lo:hi], x[lo:hi]
    if tt.size < 9:
        return float(t[i]), float(x[i]), math.nan, math.nan
    scale = float(tt[-1] - tt[0])

    def design(tp: float):
        u = (tt - tp) / scale
        left = (u < 0).astype(float)
        right = 1.0 - left
        u2 = u * u
        A = np.column_stack([np.ones_like(u), u2 * left, u2 * right, u2 * u * left, u2 * u * right,
                             u2 * u2 * left, u2 * u2 * right])
        # d(model)/du per coefficient, for the slope and tp's column
        dA = np.column_stack([np.zeros_like(u), 2 * u * left, 2 * u * right, 3 * u2 * left, 3 * u2 * right,
                              4 * u2 * u * left, 4 * u2 * u * right])
        return A, dA

    def solve(tp: float, w: np.ndarray):
        A, _ = design(tp)
        coef, *_ = np.linalg.lstsq(A * w[:, None], xx * w, rcond=None)
        r = (xx - A @ coef) * w
        return float(r @ r), coef

    def locate(w: np.ndarray) -> float:
        # searched as the offset from the sample t[i]: the bounded search stops within sqrt(eps) |x| of its
        # minimum, so on a logger's time of day (36 000 s) the turning points came out 0.9 ms off
        a, b = float(t[max(i - 1, lo)]) - float(t[i]), float(t[min(i + 1, hi - 1)]) - float(t[i])
        res = minimize_scalar(lambda d: solve(float(t[i]) + d, w)[0], bounds=(a, b), method="bounded",
                              options={"xatol": 1e-13 * max(abs(a), abs(b), scale)})
        return float(t[i]) + float(res.x)

    w = np.ones_like(tt)
    tp = locate(w)
    if jitter > 0.0:
        A, dA = design(tp)
        slope = (dA @ solve(tp, w)[1]) / scale  # dx/dt [m/s]
        sigma0 = noise if noise > 0.0 else max(float(np.std(xx - A @ solve(tp, w)[1])), 1e-300)
        w = 1.0 / np.sqrt(sigma0**2 + (jitter * slope) ** 2) * sigma0
        tp = locate(w)
    rss, coef = solve(tp, w)
    A, dA = design(tp)
    J = np.column_stack([A, -(dA @ coef) / scale]) * w[:, None]  # tp's column: -dx/dt
    dof = tt.size - J.shape[1]
    s2 = noise**2 if noise > 0.0 else (rss / dof if dof > 0 else math.nan)
    try:
        cov = s2 * np.linalg.inv(J.T @ J)
        se_x, se_t = math.sqrt(max(cov[0, 0], 0.0)), math.sqrt(max(cov[-1, -1], 0.0))
    except np.linalg.LinAlgError:
        se_x = se_t = math.nan
    return tp, float(coef[0]), se_x, se_t


def turning_points(t, x, noise: float = 0.0, rest: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Times [s] and signed values [m] of the successive turning points of a decay that starts at rest
    (:func:`turning_points_with_errors` without the errors)."""
    times, values, _, _ = turning_points_with_errors(t, x, noise, rest)
    return times, values


def turning_points_with_errors(t, x, noise: float = 0.0, rest: float = 0.0, jitter: float = 0.0) \
        -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Times [s] and signed values [m] of the successive turning points of a decay that starts at rest, and
    the standard errors of the values [m] and of the times [s].

    The first sample is the release (the building at rest at its pushed displacement), the first turning
    point. The others are found by a zigzag with hysteresis: the running extreme in the current direction
    of motion becomes a turning point once the signal has come back from it by more than
    ``(2 sqrt(2 ln n) + 2) noise`` (noise: the standard deviation of the noise on x; n samples), beyond the
    range of the noise alone, so noise does not make half-cycles. When the record ends on a
    rest (the sliders stuck), the last extreme is the final turning point, at the median of the rest.
    Each turning point after the first is located between samples (``_refine_extremum``, weighted against
    time-stamp ``jitter`` [s] where given); their errors come from those local fits (the noise's where given,
    else the fit's residual), the release's is the noise of one sample (time exact), the final rest's that of
    its median.
    """
    t, x = _check_series(t, x)
    n = x.size
    # the range of n Gaussian samples stays below 2 sqrt(2 ln n) standard deviations (their expected
    # extremes), plus a margin of 2: noise alone does not make a half-cycle. Jittered stamps move the
    # samples on the flanks by up to jitter |dx/dt|: that counts as noise for the zigzag
    spread = float(noise)
    if jitter > 0.0:
        span = min(16, n - 1)  # the typical step: bursts of stamps make short and long steps
        rate = np.abs(np.diff(x)) / float(np.median((t[span:] - t[:-span]) / span))
        spread = math.hypot(spread, jitter * float(np.percentile(rate, 99)))
    threshold = spread * (2.0 * math.sqrt(2.0 * math.log(n)) + 2.0)
    idx, direction, best = zigzag_scan(x, threshold, -1.0 if x[0] > rest else 1.0, 1)
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
    se_v, se_t = [float(noise) if noise > 0 else math.nan], [0.0]
    for j, i in enumerate(idx):
        if stuck and j == len(idx) - 1 and n - 1 - i > half:
            tp, _, _, st = _refine_extremum(t, x, i, half, noise, jitter)
            times.append(tp)
            values.append(float(np.median(x[i:])))
            se_v.append(1.2533 * float(noise) / math.sqrt(n - i) if noise > 0 else math.nan)
            se_t.append(st)
            continue
        tp, xp, sv, st = _refine_extremum(t, x, i, half, noise, jitter)
        times.append(tp)
        values.append(xp)
        se_v.append(sv)
        se_t.append(st)
    return np.array(times), np.array(values), np.array(se_v), np.array(se_t)


def estimate_noise(x, window: int = 11) -> float:
    """Standard deviation of the noise on a smooth record x [its unit]: the robust spread (1.4826 MAD) of
    the residual from a cubic Savitzky-Golay smoothing over ``window`` samples, divided by sqrt(1 - c0)
    (c0 the smoother's own weight on the centre sample, so the residual's variance is sigma^2 (1 - c0)).
    The curvature of the motion within the window enters at the order of its fourth derivative: a record
    sampled at 30 or more samples a cycle gives the noise (or the resolution of a quantised channel).

    The smoothing is scipy's ``savgol_filter(x, window, 3)`` (mode "interp": the first and last half-windows
    from the cubic fitted to the first and last windows), written here with numpy: importing scipy.signal
    costs half a second, more than a linear fit of the building."""
    x = np.asarray(x, dtype=float)
    if x.size < window + 2:
        return 0.0
    half = window // 2
    j = np.arange(window, dtype=float) - half
    hat = np.linalg.pinv(np.vander(j, 4, increasing=True))  # cubic least squares: coefficients from samples
    weights = hat[0]  # the fitted value at the centre
    smooth = np.empty_like(x)
    smooth[half:-half] = np.convolve(x, weights[::-1], mode="valid")
    edge = np.vander(j[:half], 4, increasing=True) @ hat  # the first half-window from the first window's cubic
    smooth[:half] = edge @ x[:window]
    smooth[-half:] = edge[::-1, ::-1] @ x[-window:]
    resid = x - smooth
    c0 = float(weights[half])
    return 1.4826 * float(np.median(np.abs(resid - np.median(resid)))) / math.sqrt(1.0 - c0)


@dataclass(frozen=True, eq=False)
class MidMotionStart:
    """A record that starts in motion, trimmed to its first turning point (:func:`first_turning_point`)."""

    t: np.ndarray
    """Times from the turning point on [s], the turning point first."""
    x: np.ndarray
    """The channel from the turning point on [its unit], its value d0 at the turning point first."""
    time: float
    """The turning point's time: the release from rest of the trimmed record [s]."""
    d0: float
    """The channel's value there: the displacement released from rest [its unit]."""
    index: int
    """The first sample after the turning point in the untrimmed record."""
    d0_se: float = math.nan
    """Standard error of d0 from the local fit [its unit]."""


def first_turning_point(t, x, noise: float | None = None) -> MidMotionStart:
    """The first turning point of a record that starts in motion (a free decay caught mid-swing), taken as
    a release from rest: the trimmed channel starts there at d0.

    From the start the running extreme in the direction of the first motion becomes the turning point once
    the record has come back from it by more than ``(2 sqrt(2 ln n) + 2) noise`` (the zigzag of
    :func:`turning_points`); it is located between samples by the local fit of ``_refine_extremum``. A
    record whose first sample is already the extreme (released from rest) gives that sample. ``noise``:
    the standard deviation on x, else :func:`estimate_noise`.
    """
    t, x = _check_series(t, x)
    sigma = estimate_noise(x) if noise is None else float(noise)
    threshold = sigma * (2.0 * math.sqrt(2.0 * math.log(x.size)) + 2.0)
    away = np.nonzero(np.abs(x - x[0]) > threshold)[0]
    if away.size == 0:
        raise ParameterError("x", "no motion beyond the noise", "a record that moves", "")
    direction = math.copysign(1.0, x[away[0]] - x[0])
    best = 0
    turn = None
    for k in range(1, x.size):
        if direction * (x[k] - x[best]) > 0.0:
            best = k
        elif direction * (x[best] - x[k]) > threshold:
            turn = best
            break
    if turn is None:
        raise ParameterError("x", "no turning point", "a record that swings back at least once", "")
    if turn == 0:
        return MidMotionStart(t=t.copy(), x=x.copy(), time=float(t[0]), d0=float(x[0]), index=1, d0_se=sigma)
    nxt, far = turn, turn  # the next turning point: the half-cycle's length sets the local fit's width
    for k in range(turn + 1, x.size):
        if -direction * (x[k] - x[far]) > 0.0:
            far = k
        elif -direction * (x[far] - x[k]) > threshold:
            nxt = far
            break
    half = int(max(5, min((nxt - turn) // 12, 400)))
    tp, xp, se_x, _ = _refine_extremum(t, x, turn, half, sigma if noise is not None else 0.0)
    after = t > tp
    return MidMotionStart(t=np.concatenate([[tp], t[after]]), x=np.concatenate([[xp], x[after]]), time=tp, d0=xp,
                          index=int(np.argmax(after)), d0_se=se_x)


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
    """The combined decrement law fitted to the peaks (None with fewer than five)."""
    period: float
    """Damped period: twice the least-squares slope of the turning-point times against their count [s]
    (nan with fewer than two turning points)."""
    natural_period: float
    """``period sqrt(1 - zeta^2)``, zeta from the combined law [s]."""
    period_se: float = math.nan
    """Standard error of the period: from the turning-point times' own errors (weighted least squares),
    scaled up by the scatter about their line where that is larger [s]."""
    notes: tuple[str, ...] = field(default=())
    laws: tuple[LawFit, ...] = ()
    """Every decrement law fitted to the peaks (:func:`decay_laws`), lowest AIC first."""
    peak_se: np.ndarray | None = None
    """Standard error of each turning point's value [m] (None where no noise level was given)."""
    peak_time_se: np.ndarray | None = None
    """Standard error of each turning point's time [s] (None where no noise level was given)."""
    start: MidMotionStart | None = None
    """Where the record started in motion: its first turning point, taken as the release."""

    @property
    def best_law(self) -> LawFit | None:
        """The law of lowest AIC (None with too few peaks)."""
        return self.laws[0] if self.laws else None

    def stiffness(self, mass: float) -> float:
        """k = m (2 pi / T_n)^2 [N/m] for the mass m [kg]."""
        return float(mass) * (2.0 * math.pi / self.natural_period) ** 2

    def friction_force(self, mass: float) -> float:
        """F_s = k delta [N] from the combined law (nan without one)."""
        return self.law.friction_force(self.stiffness(mass)) if self.law else math.nan

    def friction_force_se(self, mass: float) -> float:
        """Standard error of F_s = k delta [N]: delta's and the stiffness' (k from the period, whose relative
        error enters twice: ``dk / k = 2 dT / T``), taken as independent."""
        if self.law is None:
            return math.nan
        k = self.stiffness(mass)
        rel_k = 2.0 * self.period_se / self.period if math.isfinite(self.period_se) else 0.0
        return math.hypot(k * self.law.friction_displacement_se, self.friction_force(mass) * rel_k)

    def summary(self, mass: float | None = None) -> dict[str, Any]:
        out: dict[str, Any] = {
            "half_cycles": int(max(self.peaks.size - 1, 0)), "period_s": self.period,
            "natural_period_s": self.natural_period, "period_se_s": self.period_se, "peaks_m": self.peaks.tolist(),
            "peak_times_s": self.peak_times.tolist(), "zero_crossings_s": self.zero_crossings.tolist(),
            "amplitude_m": self.amplitude.tolist(), "equivalent_period_s": self.equivalent_period.tolist(),
            "equivalent_damping": self.equivalent_damping.tolist(),
            "damping_amplitude_m": self.damping_amplitude.tolist(),
            "law": self.law.summary() if self.law else None, "laws": [f.summary() for f in self.laws],
            "best_law": self.best_law.name if self.best_law else None, "notes": list(self.notes)}
        if self.start is not None:
            out["start_in_motion"] = {"time_s": self.start.time, "d0": self.start.d0}
        if mass is not None and self.law is not None:
            out["stiffness_N_m"] = self.stiffness(mass)
            out["friction_N"] = self.friction_force(mass)
            out["friction_se_N"] = self.friction_force_se(mass)
        return out


#: Reduced chi-square of a decrement law above which the record says the law misfits its peaks (the
#: 99.9% point of chi2 / dof is below 3.1 from 10 degrees of freedom on).
MISFIT_REDUCED_CHI2 = 3.0
#: Most turning points on which :func:`analyse_decay` fits the nonlinear (quadratic, power) laws.
MAX_NONLINEAR_PEAKS = 300


def analyse_decay(t, x, release_time: float | None = None, noise: float = 0.0, rest: float = 0.0, *,
                  jitter: float = 0.0, start_in_motion: bool = False, laws=LAW_NAMES) -> DecayAnalysis:
    """Model-free analysis of the isolation layer's displacement x(t) [m] after the release.

    Parameters
    ----------
    t, x : arrays
        Times [s] and displacements [m] (offset removed: x = 0 where the isolators carry no force).
    release_time : float, optional
        The release instant [s]; samples before it are ignored (default: the first sample).
    noise : float
        Standard deviation of the noise on x [m]; swings within the range of the noise are not half-cycles.
        With it the turning points carry standard errors, and the decrement laws a true chi-square.
    rest : float
        The unloaded position [m] the zero crossings refer to.
    jitter : float
        Standard deviation of the time stamps' error [s] (e.g.
        :func:`quickrelease.io.timebase.time_base`'s); the turning points then rest on the samples the jitter
        does not move (:func:`_refine_extremum`).
    start_in_motion : bool
        The record starts mid-swing: its first turning point (:func:`first_turning_point`) is taken as the
        release from rest (``release_time`` then only drops the samples before it).
    laws : sequence of str
        The decrement laws to fit and rank (:data:`LAW_NAMES`; the nonlinear quadratic and power laws cost
        most of the time: leave them out where only the combined law is wanted).
    """
    t, x = _check_series(t, x)
    notes = []
    x0_se = float(noise) if noise > 0 else math.nan
    start = None
    if release_time is not None:
        t_r = float(release_time)
        if not (math.isfinite(t_r) and t[0] <= t_r < t[-1]):
            raise ParameterError("release_time", t_r, f"[{t[0]:.6g}, {t[-1]:.6g}) s, within the record", "s")
        before = x[t <= t_r]
        # at rest before the release: the pushed displacement is the mean level of the quiet segment
        x0 = float(np.median(before)) if before.size >= 3 else float(np.interp(t_r, t, x))
        if before.size >= 3 and noise > 0:
            x0_se = 1.2533 * float(noise) / math.sqrt(before.size)
        after = t > t_r
        if start_in_motion:
            t, x = _check_series(t[after], x[after])
        else:
            t, x = _check_series(np.concatenate([[t_r], t[after]]), np.concatenate([[x0], x[after]]))
    if start_in_motion:
        start = first_turning_point(t, x, noise if noise > 0 else None)
        t, x = _check_series(start.t, start.x)
        x0_se = start.d0_se
        notes.append(f"the record starts in motion: its first turning point ({start.d0:.6g} at "
                     f"{start.time:.6g} s) is taken as the release from rest")
    times, peaks, se_v, se_t = turning_points_with_errors(t, x, noise, rest, jitter)
    times, peaks, se_v, se_t, ended = _free_part(times, peaks, se_v, se_t)
    if ended is not None:
        notes.append(f"the decay ends in the ambient motion at {ended:.6g} s: a half-cycle there lasts less than "
                     "half or more than twice the median of the first ones; the turning points after it are left "
                     "out")
    se_v[0] = x0_se
    known = noise > 0
    if known:  # a turning point without a local fit of its own (too few samples): one sample's noise
        se_v = np.where(np.isfinite(se_v) & (se_v > 0), se_v, float(noise))
    crossings = half_cycle_crossings(t, x, times, peaks, rest) if x.size >= 8 else np.empty(0)
    if peaks.size >= 2:
        amplitude = 0.5 * np.abs(np.diff(peaks))
        teq = 2.0 * np.diff(times)
        with np.errstate(divide="ignore", invalid="ignore"):
            d = np.log(amplitude[:-1] / amplitude[1:])
            zeq = np.where(np.isfinite(d), d / np.sqrt(math.pi**2 + d * d), math.nan)
        zamp = np.sqrt(amplitude[:-1] * amplitude[1:])
        period, period_se = _period(times, se_t if known else None)
    else:
        amplitude = teq = zeq = zamp = np.empty(0)
        period = period_se = math.nan
        notes.append("fewer than two turning points: no half-cycle to analyse")
    peak_se = se_v if known else None
    law = combined_decay_law(peaks, peak_se=peak_se) if peaks.size >= 5 else None
    laws = tuple(laws)
    if peaks.size > MAX_NONLINEAR_PEAKS and set(laws) - {"viscous", "coulomb", "combined"}:
        laws = tuple(name for name in laws if name in ("viscous", "coulomb", "combined"))
        notes.append(f"{peaks.size} turning points: the quadratic and power laws are not fitted (more than "
                     f"{MAX_NONLINEAR_PEAKS}; is the noise level right?)")
    fitted = decay_laws(peaks, peak_se=peak_se, laws=laws) if peaks.size >= 4 and laws else ()
    if fitted:
        best = fitted[0]
        notes.append(f"decrement law of lowest AIC: {best.name} ("
                     + ", ".join(f"{f.name} {f.aic - best.aic:+.3g}" for f in fitted[1:]) + " in AIC)")
        if known and best.dof > 0 and best.reduced_chi2 > MISFIT_REDUCED_CHI2:
            notes.append(f"even the best decrement law ({best.name}) misfits the turning points: reduced "
                         f"chi-square {best.reduced_chi2:.3g} on {best.dof} degrees of freedom; its standard "
                         "errors are scaled up by the square root")
    zeta = law.damping_ratio if law and math.isfinite(law.damping_ratio) else 0.0
    natural = period * math.sqrt(1.0 - zeta * zeta) if math.isfinite(period) else math.nan
    return DecayAnalysis(peak_times=times, peaks=peaks, zero_crossings=crossings, amplitude=amplitude,
                         equivalent_period=teq, equivalent_damping=zeq, damping_amplitude=zamp, law=law,
                         period=period, period_se=period_se, natural_period=natural, notes=tuple(notes),
                         laws=fitted, peak_se=peak_se, peak_time_se=se_t if known else None, start=start)


def _free_part(times, peaks, se_v, se_t):
    """The turning points of the free decay: those before the first half-cycle (the last one aside) that
    lasts less than half or more than twice the median of the first eight (or all, if fewer) half-cycles.
    A decay that dies into a record's ambient motion (footsteps, traffic, a building's wind sway) leaves
    turning points of that motion, which the noise threshold does not catch when it is slower than the
    sensor's noise.
    Returns the kept arrays and the time where the decay ended (None where it did not)."""
    if times.size < 4:
        return times, peaks, se_v, se_t, None
    d = np.diff(times)
    med = float(np.median(d[: min(8, d.size)]))
    # the last half-cycle is not judged: where the sliders stick, its end is the rest, located less sharply
    off = np.nonzero((d[:-1] < 0.5 * med) | (d[:-1] > 2.0 * med))[0]
    if off.size == 0 or off[0] < 2:
        return times, peaks, se_v, se_t, None
    j = int(off[0]) + 1  # keep turning points 0..j-1
    return times[:j], peaks[:j], se_v[:j], se_t[:j], float(times[j - 1])


def _period(times: np.ndarray, se_t: np.ndarray | None) -> tuple[float, float]:
    """Twice the slope of the turning-point times against their count, and its standard error [s].

    Least squares over all of them, not just the first and the last; the final stick is located less
    sharply than a turning point (the record is flat after it), so it is left out when there are other
    half-cycles. With the times' standard errors (the release's is exact) the fit is weighted and its error
    scaled up by sqrt(chi2 / dof) where the times scatter more than their errors say; without them the
    error comes from the scatter alone (four or more times).
    """
    use = slice(0, times.size - 1) if times.size > 3 else slice(0, times.size)
    tt = times[use]
    n = np.arange(tt.size, dtype=float)
    if se_t is not None and tt.size >= 3:
        e = np.asarray(se_t[use], dtype=float).copy()
        positive = e[np.isfinite(e) & (e > 0)]
        floor = float(np.min(positive)) * 1e-3 if positive.size else 1.0
        e = np.where(np.isfinite(e) & (e > 0), e, floor)
        w = 1.0 / e**2
        A = np.column_stack([np.ones_like(n), n])
        cov = np.linalg.inv(A.T @ (A * w[:, None]))
        coef = cov @ (A.T @ (w * tt))
        resid = tt - A @ coef
        dof = tt.size - 2
        chi2 = float(np.sum(w * resid**2))
        factor = max(1.0, chi2 / dof) if dof > 0 else 1.0
        return 2.0 * float(coef[1]), 2.0 * math.sqrt(cov[1, 1] * factor)
    slope = float(np.polyfit(n, tt, 1)[0])
    period_se = math.nan
    if tt.size >= 4:  # from the scatter of the turning-point times about the line
        resid = tt - np.polyval(np.polyfit(n, tt, 1), n)
        s2 = float(resid @ resid) / (tt.size - 2)
        period_se = 2.0 * math.sqrt(s2 / float(np.sum((n - n.mean()) ** 2)))
    return 2.0 * slope, period_se


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
