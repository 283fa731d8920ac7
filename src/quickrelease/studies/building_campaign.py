"""Campaigns of releases of one building: the isolation system against the release amplitude.

A snap-back campaign releases one building several times from different pushed displacements d0 (or push
forces P). Each release is fitted on its own (:func:`quickrelease.building.isolation_fit.fit_isolation`, with
standard errors and 95% intervals); then, for each quantity of the isolation system, the law
``q = a + b x`` across the campaign is fitted by weighted least squares (the device campaign's machinery,
:func:`quickrelease.studies.campaign.fit_line`: weights ``1 / SE^2``, the covariance inflated by the reduced
chi-square when the tests scatter more than their standard errors say), with its 95% confidence band and
a Student t test of ``b = 0`` (does the amplitude matter?). The variable x is the release amplitude
``|d0|`` [m] (``displacement``), its logarithm ``ln(|d0| / 1 m)`` (``log_displacement``) or the push force
P [N] (``force``).

Quantities (per release, from the fitted model, SI):

- ``period``: the linear model's period ``T = 2 pi sqrt(m / k)`` (the bilinear model's: of k1) [s];
- ``secant_period``: ``2 pi sqrt(m / k_sec)``, ``k_sec = R(d0) / d0`` the bearings' secant stiffness at the
  pushed state (:func:`quickrelease.building.model.pushed_state`; the sliders' friction is left out of it and
  counted in the damping) [s]; equals ``period`` for the linear model;
- ``damping_ratio``: the viscous damping ratio zeta [-] (bilinear: referred to k1);
- ``friction``: the sliders' friction F_s [N];
- ``equivalent_damping_ratio``: ``zeta_eq = E_D / (4 pi E_S)`` of one cycle of amplitude |d0| at the secant
  frequency, ``E_S = k_sec d0^2 / 2`` and ``E_D = pi c omega_sec d0^2 + 4 F_s |d0| + 4 f_p (|d0| - d_y)``
  (viscous, Coulomb and hysteretic loops; f_p = F_y (1 - k2 / k1), d_y = F_y / k1, the last term only
  beyond d_y); for the linear model ``zeta_eq = zeta + 2 F_s / (pi k |d0|)``;
- bilinear also ``stiffness_ratio`` k2 / k1 [-] and ``yield_force`` F_y [N];
- ``pendulum`` (the friction pendulum, :class:`quickrelease.building.hysteretic.Pendulum`): ``radius`` R =
  g (T / 2 pi)^2 [m] of the fitted pendulum period T = 2 pi sqrt(R / g) (``period``, when asked for), the friction
  coefficients ``friction_slow`` mu_slow and ``friction_fast`` mu_fast [-] and Constantinou's ``rate`` a [s/m] of
  ``mu(v) = mu_fast - (mu_fast - mu_slow) exp(-a |v|)``, ``damping_ratio`` referred to W / R, and
  ``equivalent_damping_ratio``; with ``[building] friction_coefficient`` (a constant coefficient, as the model
  that key names everywhere else) each release is fitted with the rate held at 0 and the campaign's quantity is
  ``friction_coefficient`` mu [-] (the fit's mu_slow) in place of the three (a constant-friction record does
  not identify mu_fast and a: their profiles run over their whole ranges, at 10-60 s a fit);
- ``boucwen`` (:class:`~quickrelease.building.hysteretic.BoucWen`, lead-rubber and high-damping rubber):
  ``post_yield_stiffness`` Kd = m (2 pi / T)^2 [N/m] (its period ``period`` when asked for),
  ``characteristic_strength`` Qd [N], ``yield_displacement`` dy [m], ``shape`` n [-], the sliders' ``friction``
  F_s [N] (0 for bearings alone: its interval then a profile from the bound), ``damping_ratio`` referred to Kd
  and ``equivalent_damping_ratio``;
- ``damping = "power"`` (fluid viscous dampers ``C |v|^alpha sign(v)``, any model, 2dof and flexible too):
  ``damping_coefficient`` C [N (s/m)^alpha] and ``damping_exponent`` alpha [-] in place of ``damping_ratio``.

The equivalent damping of every model is that of one harmonic cycle ``x = d cos(omega t)``, d = |d0|, at the
secant frequency ``omega = sqrt(k_sec / m)`` (the bearings' force at d over d, sliders left out), each energy
per cycle in closed form or by quadrature (:func:`cycle_energy`, derived here, not read from the model's free
vibration: a free decay never runs a cycle at constant amplitude):

- the damper: ``lambda C d^(1 + alpha) omega^alpha``, ``lambda = 2 sqrt(pi) Gamma(1 + alpha / 2) /
  Gamma(3/2 + alpha / 2)`` (pi at alpha = 1: ``pi c omega d^2``) (:func:`damper_energy`);
- the pendulum's friction: ``4 W d (mu_fast - (mu_fast - mu_slow) S(a d omega))``, ``S(b) = int_0^(pi/2)
  exp(-b sin t) sin t dt`` (:func:`pendulum_friction_energy`; ``4 mu W d`` at constant friction, so a pendulum
  equals the linear model with k = W / R and F_s = mu W), with ``k_sec = W / R``;
- Bouc-Wen: the steady symmetric loop between -d and +d, ``Qd int z dx`` (:func:`boucwen_cycle`: z_m at the
  extremes and the loop's area by Gauss-Legendre quadrature, closed forms for n = 1, the bilinear loop's
  ``4 Qd (d - dy)`` as n grows), ``k_sec = Kd + Qd z_m / d`` the cycle's own secant stiffness (the push's virgin
  curve is not a cycle's), and ``4 F_s d`` of its sliders; ``secant_period`` (when asked for) of that k_sec.
- 2dof (:class:`quickrelease.building.model.TwoDOF`, each release fitted with the superstructure's mass at the roof
  given): ``period``, ``damping_ratio`` and ``friction`` are the isolation layer's (T of the whole mass on the
  isolators), with laws as for the linear model, ``secant_period`` and ``equivalent_damping_ratio`` those of
  the isolation layer under the whole mass (the linear model's formulas; the superstructure's own damping is
  not in them); the superstructure's fixed-base period ``superstructure_period`` T_s [s] and damping ratio
  ``superstructure_damping_ratio`` zeta_s [-] are reported per release with their intervals (laws for them
  when asked for in ``quantities``).

The pooled cycles (:func:`pooled_cycles`: keff, EDC, beta_eff, Teff of each release's fitted model over its
record, :func:`quickrelease.studies.building_effective.model_cycles`) and their laws in the cycle amplitude
(:func:`cycle_laws`) are the same for every model.

Physically, a linear spring with viscous damping and Coulomb sliders has constant T, zeta and F_s: a
campaign of such a building finds no significant amplitude effect on them, while its equivalent damping
falls with the amplitude (the friction's share, ``2 F_s / (pi k d0)``). A significant slope of F_s or T
says the isolators are not what the model assumes (friction that depends on the pressure or the velocity,
a stiffness that softens with the strain).

Derived quantities carry the delta-method standard error (the gradient by central differences, the fit's
covariance). The laws weight each release by ``1 / sigma^2``, where sigma is the release's standard error:

- a Jacobian interval: the fit's standard error (the interval is ``est +- t sigma``);
- a profile-likelihood interval ``[lo, hi]`` (a parameter at a bound, or far from quadratic): each side that
  the likelihood ends (where the profile chi-square has risen by ``t^2``) gives ``sigma_- = (est - lo) / t``
  and ``sigma_+ = (hi - est) / t`` (the release's term ``((q - law) / sigma)^2`` in the law's chi-square
  then equals the profile's rise where the law passes through that end), and sigma is their mean,
  ``(hi - lo) / (2 t)`` for an interval within the bounds (not the Jacobian's standard error: that is the
  curvature at the estimate, which the profile says is not the likelihood's width); a side cut by the
  parameter's bound (:data:`quickrelease.building.isolation_fit.PARAMETER_BOUNDS`:
  friction 0, damping 0) says nothing of the likelihood and is left out, so a friction at its bound 0 with
  interval ``[0, hi]`` has ``sigma = (hi - est) / t``, not the half-width (which would halve sigma and
  give that release four times its weight). With both sides cut the half-width stands (the record does not
  determine the parameter); ``t`` is the Student quantile of the fit's degrees of freedom;
- an interval widened to cover a second minimum as good as the best (``covers two minima``): as a profile's.

A release whose record does not identify a quantity (the fit's ``not identified``: standard error inf, no
interval; a profile interval over the parameter's whole range, e.g. Constantinou's rate of a slow record; or a
derived quantity that depends on such a parameter; the rule of the building's JSON too:
:func:`quickrelease.building.identified.parameter_identified`) gives no weight to that quantity's laws: it is left
out of them (``left_out``; standard error inf, shown "not identified" in the tables and as a hollow point in the
figure), and a quantity that fewer than three releases identify has no law. (It once made the law unweighted,
every release then weighing the same, the unidentified one included.)

The releases share one building, so a release whose fit misfits its record (reduced chi-square above
:data:`MISFIT_RESTART` with known noise: the fit's local minima, e.g. a wrong count of half-cycles before
the sliders stick, or the bilinear model's friction traded against its yield force) is refitted from the
estimates of each release that fits well, and the better fit kept (``restarted_from`` names its start); so is
a release that fits its noise but whose fit did not confirm its minimum as the global one, from the estimates
of the :data:`UNCONFIRMED_RESTARTS` best-fitting other releases (a pendulum's local minima can fit the noise).
A refit takes what the release's first fit computed (its global search, its record's own starts, every solve
the new start leaves as it was: :class:`~quickrelease.building.isolation_fit.FitMemo`) and gives the fit that
is computed afresh.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import stats

from ..building.hysteretic import GRAVITY
from ..building.identified import parameter_identified
from ..building.isolation_fit import (
    FLEXIBLE_MODELS,
    PARAMETER_BOUNDS,
    BuildingChannel,
    FitMemo,
    IsolationFit,
    _isolation,
    fit_isolation,
)
from ..building.model import pushed_state
from ..errors import ParameterError, QuickReleaseError
from ..io.building_case import constant_friction_fixed
from ..io.export import jsonable
from ..report._style import styled
from ._laws import LinearLaw, fit_line, iter_tests, law_panel, weights_or_none
from .building_effective import model_cycles, record_span

__all__ = ["BuildingRelease", "ReleaseEstimates", "BuildingCampaignResult", "fit_building_campaign",
           "building_campaign_figure", "derived_quantity", "pooled_cycles", "cycle_laws", "CYCLE_QUANTITIES",
           "CYCLE_VARIABLES", "law_standard_error", "BUILDING_VARIABLES", "QUANTITIES",
           "DEFAULT_QUANTITIES", "REPORTED"]

#: Regressors of the amplitude laws: (label, unit, scale for plots, plot unit).
BUILDING_VARIABLES = {
    "displacement": ("release amplitude |d0|", "m", 1e2, "cm"),
    "log_displacement": ("ln(|d0| / 1 m)", "-", 1.0, "-"),
    "force": ("push force P", "N", 1e-3, "kN"),
}
#: Quantities of the isolation system: (label, unit, scale for plots, plot unit, symbol).
QUANTITIES = {
    "period": ("period T", "s", 1.0, "s", "T"),
    "secant_period": ("secant period at d0", "s", 1.0, "s", "T_sec"),
    "damping_ratio": ("viscous damping ratio", "-", 1e2, "%", "zeta"),
    "friction": ("slider friction F_s", "N", 1e-3, "kN", "F_s"),
    "equivalent_damping_ratio": ("equivalent damping ratio at d0", "-", 1e2, "%", "zeta_eq"),
    "stiffness_ratio": ("stiffness ratio k2/k1", "-", 1.0, "-", "k2/k1"),
    "yield_force": ("yield force F_y", "N", 1e-3, "kN", "F_y"),
    "superstructure_period": ("superstructure period (fixed base)", "s", 1.0, "s", "T_s"),
    "superstructure_damping_ratio": ("superstructure damping ratio", "-", 1e2, "%", "zeta_s"),
    "radius": ("radius of the sliding surface R", "m", 1.0, "m", "R"),
    "friction_coefficient": ("friction coefficient mu", "-", 1e2, "%", "mu"),
    "friction_slow": ("friction coefficient at low speed mu_slow", "-", 1e2, "%", "mu_slow"),
    "friction_fast": ("friction coefficient at speed mu_fast", "-", 1e2, "%", "mu_fast"),
    "rate": ("friction's rate a (Constantinou)", "s/m", 1.0, "s/m", "a"),
    "post_yield_stiffness": ("post-yield stiffness Kd", "N/m", 1e-3, "kN/m", "Kd"),
    "characteristic_strength": ("characteristic strength Qd", "N", 1e-3, "kN", "Qd"),
    "yield_displacement": ("yield displacement dy", "m", 1e3, "mm", "dy"),
    "shape": ("Bouc-Wen shape exponent n", "-", 1.0, "-", "n"),
    "damping_coefficient": ("damper coefficient C", "N (s/m)^alpha", 1e-3, "kN (s/m)^alpha", "C"),
    "damping_exponent": ("damper exponent alpha", "-", 1.0, "-", "alpha"),
}
#: The quantities a campaign fits laws for, by model (with viscous dampers: :func:`default_quantities` puts the
#: power law's C and alpha in place of damping_ratio).
DEFAULT_QUANTITIES = {
    "linear": ("period", "damping_ratio", "friction", "equivalent_damping_ratio"),
    "bilinear": ("secant_period", "damping_ratio", "friction", "equivalent_damping_ratio", "period",
                 "stiffness_ratio", "yield_force"),
    "2dof": ("period", "damping_ratio", "friction", "equivalent_damping_ratio"),
    "pendulum": ("radius", "friction_slow", "friction_fast", "rate", "damping_ratio", "equivalent_damping_ratio"),
    "boucwen": ("post_yield_stiffness", "characteristic_strength", "yield_displacement", "shape", "damping_ratio",
                "friction", "equivalent_damping_ratio"),
}
#: The constant-friction pendulum's (``[building] friction_coefficient``: each release fitted with rate = 0).
CONSTANT_FRICTION_QUANTITIES = ("radius", "friction_coefficient", "damping_ratio", "equivalent_damping_ratio")
#: Quantities a campaign also fits laws for when asked (``quantities``), by model.
EXTRA_QUANTITIES = {"linear": ("secant_period",), "2dof": ("secant_period",), "pendulum": ("period",),
                    "boucwen": ("period",)}
#: The damper laws, and their quantities in place of ``damping_ratio``.
DAMPER_QUANTITIES = {"viscous": ("damping_ratio",), "power": ("damping_coefficient", "damping_exponent")}
#: The engineering quantities of the releases' cycles pooled, with laws in the cycle amplitude D: (label, unit,
#: scale for tables, table unit, symbol).
CYCLE_QUANTITIES = {
    "keff_N_m": ("effective stiffness keff", "N/m", 1e-3, "kN/m", "keff"),
    "beta_eff": ("effective damping beta_eff", "-", 1e2, "%", "beta_eff"),
}
#: Regressors of the cycles' laws (the release variables' counterparts): (label, unit).
CYCLE_VARIABLES = {"displacement": ("cycle amplitude D", "m"), "log_displacement": ("ln(D / 1 m)", "-")}
#: Quantities reported per release beside those with laws, by model (with their intervals; no law unless
#: asked for in ``quantities``).
REPORTED = {"2dof": ("superstructure_period", "superstructure_damping_ratio")}
_FITTED = ("period", "damping_ratio", "friction", "stiffness_ratio", "yield_force", "superstructure_period",
           "superstructure_damping_ratio", "friction_slow", "friction_fast", "rate", "characteristic_strength",
           "yield_displacement", "shape", "damping_coefficient", "damping_exponent")
#: Quantities that are a fitted parameter under another name (the constant-friction pendulum's mu is its mu_slow).
_ALIASES = {"friction_coefficient": "friction_slow"}
#: Reduced chi-square (known noise) above which a release is refitted from the other releases' estimates.
MISFIT_RESTART = 1.3


@dataclass(frozen=True, eq=False)
class BuildingRelease:
    """One release of the campaign: its records and what was pushed (SI)."""

    name: str
    channels: tuple[BuildingChannel, ...]
    d0: float | None = None
    """The pushed displacement [m]; None: from the record (the fit's d0). Given and a displacement channel
    present, the fit still estimates d0 from the record and the law uses the estimate."""
    force: float | None = None
    """The push force P [N] (needed for laws in ``force``)."""
    release_time: float | None = None
    """Start value of the release instant [s, record time]; None: detected."""
    exclude_spikes: bool = False
    """Leave out the samples the fit's residuals show as spikes (``[building.record] spikes = "exclude"``)."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "channels", tuple(self.channels))
        if not self.channels:
            raise ParameterError(f"{self.name}.channels", "none", "at least one channel of the isolation layer")
        if self.d0 is not None and not (math.isfinite(self.d0) and self.d0 != 0.0):
            raise ParameterError(f"{self.name}.d0", self.d0, "finite and non-zero", "m")
        if self.force is not None and not (math.isfinite(self.force) and self.force > 0.0):
            raise ParameterError(f"{self.name}.force", self.force, "(0, inf)", "N")


def default_quantities(model: str, damping: str = "viscous", constant_friction: bool = False) -> tuple[str, ...]:
    """The quantities a campaign of ``model`` fits laws for by default: :data:`DEFAULT_QUANTITIES` (the
    constant-friction pendulum's :data:`CONSTANT_FRICTION_QUANTITIES`), the power-law damper's C and alpha in
    place of damping_ratio."""
    base = CONSTANT_FRICTION_QUANTITIES if model == "pendulum" and constant_friction else DEFAULT_QUANTITIES[model]
    out: list[str] = []
    for q in base:
        out.extend(DAMPER_QUANTITIES[damping] if q == "damping_ratio" else (q,))
    return tuple(out)


def damper_energy(coefficient: float, exponent: float, amplitude: float, omega: float) -> float:
    """Energy a damper ``C |v|^alpha sign(v)`` dissipates over one harmonic cycle ``x = d cos(omega t)`` [J]:
    ``lambda C d^(1 + alpha) omega^alpha`` with ``lambda = 4 int_0^(pi/2) sin^(1 + alpha) = 2 sqrt(pi)
    Gamma(1 + alpha / 2) / Gamma(3/2 + alpha / 2)`` (``pi c omega d^2`` for the viscous damper, alpha = 1).
    ``coefficient`` C [N (s/m)^alpha], ``exponent`` alpha [-], ``amplitude`` d [m], ``omega`` [rad/s]."""
    lam = 2.0 * math.sqrt(math.pi) * math.exp(math.lgamma(1.0 + 0.5 * exponent) - math.lgamma(1.5 + 0.5 * exponent))
    return lam * coefficient * amplitude ** (1.0 + exponent) * omega**exponent


def pendulum_friction_energy(weight: float, slow: float, fast: float, rate: float, amplitude: float,
                             omega: float) -> float:
    """Energy the friction ``mu(|v|) W`` of Constantinou's law dissipates over one harmonic cycle
    ``x = d cos(omega t)`` [J]: ``4 W d (mu_fast - (mu_fast - mu_slow) S(a d omega))`` with
    ``S(b) = int_0^(pi/2) exp(-b sin t) sin t dt`` (1 at b = 0: ``4 mu W d``, Coulomb's; ~1/b^2 for large b), by
    adaptive quadrature to 1e-13. ``weight`` W [N], ``rate`` a [s/m], ``amplitude`` d [m], ``omega`` [rad/s]."""
    from scipy.integrate import quad

    b = rate * amplitude * omega
    share = 1.0 if b == 0.0 else quad(lambda t: math.exp(-b * math.sin(t)) * math.sin(t), 0.0, 0.5 * math.pi,
                                      epsabs=0.0, epsrel=1e-13, limit=200)[0]
    return 4.0 * weight * amplitude * (fast - (fast - slow) * share)


#: Gauss-Legendre nodes of the Bouc-Wen cycle's integrals (fixed nodes: a smooth function of the parameters, for
#: the delta method's central differences).
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(64)


def _boucwen_integrals(shape: float, z: float) -> tuple[float, float]:
    """``B(z) = int_0^z (1 / (1 - s^n) - 1 / (n (1 - s))) ds`` and ``A(z) = int_0^z (1 - s) / (1 - s^n) ds`` (both
    integrands bounded on [0, 1]), by Gauss-Legendre on ``s = z u^2``."""
    if z <= 0.0:
        return 0.0, 0.0
    u = 0.5 * (_NODES + 1.0)
    s = z * u * u
    jac = 0.5 * _WEIGHTS * 2.0 * z * u
    one_minus_sn = -np.expm1(shape * np.log(s))
    one_minus_s = 1.0 - s
    b = float(np.sum(jac * (1.0 / one_minus_sn - 1.0 / (shape * one_minus_s))))
    a = float(np.sum(jac * one_minus_s / one_minus_sn))
    return b, a


def boucwen_cycle(shape: float, yield_displacement: float, amplitude: float) -> tuple[float, float]:
    """The steady symmetric cycle of the Bouc-Wen element (beta = gamma = 1/2) between -d and +d: ``(z_m, e)``,
    z at the cycle's extremes [-] and the loop's area per unit Qd, ``e = int z dx`` over the cycle [m].

    On the loading branch from -d, z rises with slope 1 / dy from -z_m to 0 (``v z < 0``), then follows
    ``dz/dx = (1 - z^n) / dy`` to z_m at +d; the unloading branch is its image. So z_m solves
    ``xi(z_m) + z_m = 2 d / dy`` with ``xi(z) = int_0^z ds / (1 - s^n)`` (solved in ``w = -ln(1 - z_m)``:
    ``xi = B(z) + w / n``), and ``e = 2 dy (xi(z_m) - A(z_m) - z_m^2 / 2) = 2 dy (2 d / dy - z_m - z_m^2 / 2 -
    A(z_m))`` (:func:`_boucwen_integrals`). For n = 1: ``-ln(1 - z_m) + z_m = 2 d / dy``,
    ``e = 2 dy (2 d / dy - 2 z_m - z_m^2 / 2)``; as n grows, ``e -> 4 (d - dy)`` beyond dy (the bilinear loop)."""
    from scipy.optimize import brentq

    n, ratio = float(shape), 2.0 * amplitude / yield_displacement

    def f(w: float) -> float:
        z = -math.expm1(-w)
        return _boucwen_integrals(n, z)[0] + w / n + z - ratio

    hi = n * (ratio + 3.0 + 1.0 / n)
    w = brentq(f, 0.0, hi, xtol=1e-15, rtol=4.0 * np.finfo(float).eps, maxiter=400)
    z_m = -math.expm1(-w)
    area = 2.0 * yield_displacement * (ratio - z_m - 0.5 * z_m * z_m - _boucwen_integrals(n, z_m)[1])
    return z_m, area


def cycle_energy(iso, amplitude: float, omega: float) -> float:
    """Energy the isolation ``iso`` (:func:`quickrelease.building.isolation_fit._isolation`'s model) dissipates over
    one harmonic cycle of amplitude d [m] at ``omega`` [rad/s] (see the module's docstring) [J]."""
    d = amplitude
    energy = damper_energy(iso.damping, getattr(iso, "damping_exponent", 1.0), d, omega)
    if iso.model == "pendulum":
        return energy + pendulum_friction_energy(iso.weight, iso.friction_slow, iso.friction_fast,
                                                 iso.rate if not iso.constant_friction else 0.0, d, omega)
    energy += 4.0 * iso.friction * d
    if iso.model == "bilinear":
        d_y = float(iso.yield_force) / iso.stiffness
        energy += 4.0 * iso.plastic_yield * max(d - d_y, 0.0)
    elif iso.model == "boucwen":
        energy += iso.characteristic_strength * boucwen_cycle(iso.shape, iso.yield_displacement, d)[1]
    return energy


def derived_quantity(name: str, model: str, mass: float, p: dict[str, float]) -> float:
    """A quantity of the isolation system from the model's parameters ``p`` (fit_isolation's names, with
    ``d0``, and the damper's), in SI: see the module's docstring for the equations (``2dof``: of its isolation
    layer under the whole mass, the linear model's)."""
    if name in _ALIASES:
        return float(p[_ALIASES[name]])
    if name in _FITTED:
        return float(p[name])
    if name == "radius":  # the pendulum period 2 pi sqrt(R / g)
        return GRAVITY * (float(p["period"]) / (2.0 * math.pi)) ** 2
    if name == "post_yield_stiffness":  # Kd = m (2 pi / T)^2
        return mass * (2.0 * math.pi / float(p["period"])) ** 2
    if name not in ("secant_period", "equivalent_damping_ratio"):
        raise ParameterError("quantity", name, ", ".join(QUANTITIES))
    iso = _isolation("linear" if model == "2dof" else model, mass, p)
    d = abs(float(p["d0"]))
    if iso.model == "boucwen":  # the steady cycle's force at d: Kd d + Qd z_m
        k_sec = iso.k2 + iso.characteristic_strength * boucwen_cycle(iso.shape, iso.yield_displacement, d)[0] / d
    else:
        k_sec = pushed_state(iso, d)[1] / d
    if name == "secant_period":
        return 2.0 * math.pi * math.sqrt(mass / k_sec)
    omega = math.sqrt(k_sec / mass)
    return cycle_energy(iso, d, omega) / (2.0 * math.pi * k_sec * d * d)


@dataclass(frozen=True, eq=False)
class ReleaseEstimates:
    """One release fitted: its amplitude and force, and each quantity with standard error and interval."""

    name: str
    d0: float
    """The release amplitude used by the laws [m] (the fit's d0 where it estimated one, else the given)."""
    d0_given: float | None
    force: float | None
    values: dict[str, float]
    std_errors: dict[str, float]
    """For the laws' weights: the Jacobian's standard error, or where the fit gave a profile interval the
    standard error that interval implies (:func:`law_standard_error`: the far side alone at a bound)."""
    ci95: dict[str, tuple[float, float]]
    interval_method: dict[str, str]
    fit: IsolationFit = field(repr=False)
    restarted_from: str | None = None
    """The release whose estimates started this fit, when the first fit's misfit exceeded the noise and
    the restart fitted better (:data:`MISFIT_RESTART`)."""

    def identified(self, quantity: str) -> bool:
        """Whether this release's record determines ``quantity``: a finite, positive standard error (not a
        parameter the fit found not identified, nor a profile interval over the parameter's whole range, nor a
        derived quantity that depends on one). A release that does not is left out of that quantity's laws."""
        se = self.std_errors[quantity]
        return math.isfinite(se) and se > 0.0 and self.interval_method[quantity] != "not identified"

    def value(self, variable: str) -> float:
        if variable == "displacement":
            return abs(self.d0)
        if variable == "log_displacement":
            return math.log(abs(self.d0))
        if variable == "force":
            if self.force is None:
                raise QuickReleaseError(f"release {self.name} has no push force (give force, or drop 'force' "
                                        "from variables)")
            return float(self.force)
        raise ParameterError("variable", variable, ", ".join(BUILDING_VARIABLES))

    def summary(self) -> dict[str, Any]:
        return jsonable({
            "name": self.name, "d0_m": self.d0, "d0_given_m": self.d0_given, "push_force_N": self.force,
            "estimates": self.values, "std_errors": self.std_errors,
            "ci95": {k: list(v) for k, v in self.ci95.items()}, "interval_method": self.interval_method,
            "units": {k: QUANTITIES[k][1] for k in self.values}, "chi2_reduced": self.fit.chi2_reduced,
            "converged": self.fit.converged, "warnings": list(self.fit.warnings),
            "restarted_from": self.restarted_from})


def law_standard_error(estimate: float, interval: tuple[float, float], bounds: tuple[float, float],
                       t_quantile: float) -> float:
    """The standard error a profile-likelihood interval gives a law's weight (see the module's docstring):
    the mean of ``(estimate - lo) / t`` and ``(hi - estimate) / t`` over the sides the likelihood ends,
    leaving out a side that ends at the parameter's bound; the half-width over t when both do."""
    lo, hi = (float(v) for v in interval)
    sides = []
    if lo > bounds[0]:
        sides.append(estimate - lo)
    if hi < bounds[1]:
        sides.append(hi - estimate)
    width = sum(sides) / len(sides) if sides else 0.5 * (hi - lo)
    return width / t_quantile


def _estimates(release: BuildingRelease, fit: IsolationFit, quantities: tuple[str, ...],
               restarted_from: str | None = None) -> ReleaseEstimates:
    """The release's quantities: fitted ones with the fit's intervals, derived ones by the delta method."""
    params = dict(fit.parameters)  # the estimates and those held fixed (the constant-friction pendulum's rate)
    if "d0" not in params:
        params["d0"] = float(release.d0)
    tq = float(stats.t.ppf(0.975, max(fit.dof, 1)))
    se_all = np.array([fit.std_errors[n] for n in fit.names])
    # not identified by the record (SE inf, or a profile interval over the parameter's whole range): a quantity
    # that depends on one has SE inf
    blind = np.array([not parameter_identified(fit, n) for n in fit.names], dtype=bool)
    se_known = np.where(blind, 0.0, se_all)
    cov = fit.correlation * np.outer(se_known, se_known)
    values, ses, ci, method = {}, {}, {}, {}
    for q in quantities:
        name = _ALIASES.get(q, q)
        if name in _FITTED and name in fit.estimates:
            values[q] = fit.estimates[name]
            ci[q] = tuple(fit.ci95[name])
            method[q] = fit.interval_method[name]
            bounds = PARAMETER_BOUNDS[name]
            if not parameter_identified(fit, name):
                method[q] = "not identified"  # its interval is the parameter's whole range: no weight in a law
            if method[q] == "not identified":
                ses[q] = math.inf
            elif method[q] == "jacobian":
                ses[q] = fit.std_errors[name]
            else:  # a profile interval, or one widened over two minima: the weight the interval implies
                ses[q] = law_standard_error(values[q], ci[q], bounds, tq)
            continue
        values[q] = derived_quantity(q, fit.model, fit.mass, params)
        grad = np.zeros(len(fit.names))
        for i, n in enumerate(fit.names):  # central differences on the free parameters
            if n.startswith(("offset_", "drift_")) or n == "release_time":
                continue
            # relative to the value (a standard error far above it, as of a parameter the record hardly sees,
            # would step out of the model's domain); to the standard error for a value of 0
            h = 1e-6 * max(abs(params[n]) if params[n] != 0.0 else se_known[i], 1e-12)
            hi, lo = dict(params), dict(params)
            hi[n] += h
            lo[n] -= h
            try:
                grad[i] = (derived_quantity(q, fit.model, fit.mass, hi)
                           - derived_quantity(q, fit.model, fit.mass, lo)) / (2.0 * h)
            except ParameterError:  # at a bound (friction 0): one-sided
                grad[i] = (derived_quantity(q, fit.model, fit.mass, hi) - values[q]) / h
        ses[q] = math.inf if np.any(grad[blind] != 0.0) else math.sqrt(max(float(grad @ cov @ grad), 0.0))
        ci[q] = (values[q] - tq * ses[q], values[q] + tq * ses[q])
        method[q] = "delta"
    return ReleaseEstimates(name=release.name, d0=params["d0"], d0_given=release.d0, force=release.force,
                            values=values, std_errors=ses, ci95=ci, interval_method=method, fit=fit,
                            restarted_from=restarted_from)


def _fixed(release: BuildingRelease, shared: dict[str, float] | None = None) -> dict[str, float] | None:
    """The parameters held fixed in a release's fit: ``shared`` (the constant-friction pendulum's rate), and d0
    where the record has no displacement channel (the given d0 is then the release state)."""
    out = dict(shared or {})
    if release.d0 is not None and not any(c.kind in ("x", "x_roof") for c in release.channels):
        out["d0"] = float(release.d0)
    return out or None


def _misfit(fit: IsolationFit) -> bool:
    """The fit's misfit exceeds its noise (the warning of :func:`fit_isolation`): a local minimum, or a
    model the record does not support."""
    return fit.absolute_sigma and math.isfinite(fit.chi2_reduced) and fit.chi2_reduced > MISFIT_RESTART


#: Releases of a campaign fitted in parallel processes at most (one per core; 1: one after the other).
CAMPAIGN_WORKERS = max(1, min(os.cpu_count() or 1, 8))


def _fit_one(r, mass: float, model: str, start, superstructure_mass, damping: str = "viscous", shared=None,
             memo: FitMemo | None = None, flexible: bool = False):
    try:
        return fit_isolation(r.channels, mass, model, release_time=r.release_time, start=start,
                             fixed=_fixed(r, shared), superstructure_mass=superstructure_mass,
                             exclude_spikes=r.exclude_spikes, damping=damping, memo=memo, flexible=flexible)
    except ParameterError as exc:  # its own arguments (type(exc)(message) was a TypeError: a traceback)
        raise type(exc)(f"release {r.name}: {exc.name}", exc.value, exc.valid, exc.unit) from None
    except QuickReleaseError as exc:
        raise type(exc)(f"release {r.name}: {exc}") from None


#: The bytes of arrays each release's :class:`~quickrelease.building.isolation_fit.FitMemo` keeps for the restarts
#: (the global stage's candidates and the thinned record's solves come first and are small; a long record's
#: whole-record solves beyond it are solved again where a restart needs them).
CAMPAIGN_MEMO_BYTES = 64 * 2**20


def _fit_kept(r, mass: float, model: str, start, superstructure_mass, damping: str = "viscous", shared=None,
              flexible: bool = False) -> tuple[IsolationFit, FitMemo]:
    """A release's fit, and the memo of what it computed (for the restarts; from a worker process too)."""
    memo = FitMemo(CAMPAIGN_MEMO_BYTES)
    return _fit_one(r, mass, model, start, superstructure_mass, damping, shared, memo, flexible), memo


def _fit_releases(releases, mass: float, model: str, start, superstructure_mass, damping: str = "viscous",
                  shared=None, memos: dict[str, FitMemo] | None = None, flexible: bool = False) \
        -> list[IsolationFit]:
    """Each release's fit, in parallel processes (``CAMPAIGN_WORKERS``, spawned: each fit is Python-bound, so
    threads would share one core) where there are at least three releases and two cores; the fits are the
    same as one after the other (each fit is deterministic for its seed). ``memos`` gets each release's
    :class:`~quickrelease.building.isolation_fit.FitMemo` (what its fit computed), by name, for
    :func:`_restart_misfits`."""
    workers = min(CAMPAIGN_WORKERS, len(releases))
    if workers < 2 or len(releases) < 3:
        out = [_fit_kept(r, mass, model, start, superstructure_mass, damping, shared, flexible)
               for r in releases]
    else:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            jobs = [pool.submit(_fit_kept, r, mass, model, start, superstructure_mass, damping, shared, flexible)
                    for r in releases]
            out = [job.result() for job in jobs]
    if memos is not None:
        memos.update((r.name, kept) for r, (_, kept) in zip(releases, out, strict=True))
    return [fit for fit, _ in out]


#: Other releases' estimates tried as starts of a release whose fit matches its noise but whose global minimum the
#: fit's multi-start did not confirm (a misfit release tries every release that fits well).
UNCONFIRMED_RESTARTS = 2


def _unconfirmed(fit: IsolationFit) -> bool:
    """The fit's search certificate does not confirm its minimum as the global one (fewer than two independent
    starts reached it, or another minimum lies close): a local minimum as good as the noise may hide a better."""
    return fit.search is not None and not fit.global_minimum_confirmed


def _restart_misfits(releases, fits: list[IsolationFit], mass: float, model: str,
                     superstructure_mass: float | None = None, damping: str = "viscous",
                     shared: dict[str, float] | None = None, memos: dict[str, FitMemo] | None = None,
                     flexible: bool = False) -> dict[str, str]:
    """Refit each release whose misfit exceeds its noise from the estimates of every release that fits
    well (the campaign knows the building: the model's misfit has local minima, e.g. the count of
    half-cycles before the sliders stick), keeping the lowest chi-square; and each release that fits its noise
    but whose global minimum is not confirmed (:func:`_unconfirmed`) from the estimates of the
    :data:`UNCONFIRMED_RESTARTS` best-fitting other releases (confirmed ones first). A pendulum of Constantinou's
    friction, 150 mm release (tests/studies/test_building_campaign_isolators.py): its fit settled at mu_slow =
    0.0025 +- 0.0001 (truth 0.005; chi2/dof 1.01, "reached from 0 of 5 starts"); from the 200 mm release's
    estimates chi-square fell by 37. ``fits`` is updated in place. Returns {release: the release whose estimates
    started its kept fit}. ``memos``: what each release's fit computed (:func:`_fit_releases`), by name: a restart
    takes the global stage, the record's own starts and every solve that its new start leaves as it was from its
    release's, and solves only what the new start changes (the fit is the one computed afresh)."""
    good = [(r.name, f) for r, f in zip(releases, fits, strict=True) if not _misfit(f) and f.converged]
    good.sort(key=lambda pair: (_unconfirmed(pair[1]), pair[1].chi2_reduced))
    restarted = {}
    for i, r in enumerate(releases):
        misfit = _misfit(fits[i])
        if not (misfit or _unconfirmed(fits[i])):
            continue
        others = [(name, other) for name, other in good if name != r.name]
        for name, other in others if misfit else others[:UNCONFIRMED_RESTARTS]:
            start = {n: other.estimates[n] for n in _FITTED if n in other.estimates}
            try:
                trial = fit_isolation(r.channels, mass, model, release_time=r.release_time, start=start,
                                      fixed=_fixed(r, shared), superstructure_mass=superstructure_mass,
                                      exclude_spikes=r.exclude_spikes, damping=damping,
                                      memo=(memos or {}).get(r.name), flexible=flexible)
            except QuickReleaseError:
                continue
            if trial.chi2 < fits[i].chi2:
                fits[i], restarted[r.name] = trial, name
            if misfit and not _misfit(fits[i]):
                break
    return restarted


@dataclass(frozen=True, eq=False)
class BuildingCampaignResult:
    """The releases of one building fitted one by one, and the laws of each quantity in each variable."""

    title: str
    source: str
    model: str
    mass: float
    releases: list[ReleaseEstimates]
    laws: dict[tuple[str, str], LinearLaw]
    """(quantity, variable) -> law."""
    variables: tuple[str, ...]
    quantities: tuple[str, ...]
    notes: str = ""
    reported: tuple[str, ...] = ()
    """Quantities reported per release without a law (2dof: the superstructure's period and damping)."""
    superstructure_mass: float | None = None
    """2dof or a flexible campaign: the superstructure's mass at the roof given to every fit [kg]."""
    cycles: tuple[dict[str, Any], ...] = ()
    """Every release's cycles of its fitted model's loop, pooled (:func:`pooled_cycles`): ``release``,
    ``amplitude_m``, ``keff_N_m``, ``edc_J``, ``beta_eff``, ``teff_s``; empty for 2dof."""
    cycle_laws: dict[tuple[str, str], LinearLaw] = field(default_factory=dict)
    """(quantity of :data:`CYCLE_QUANTITIES`, variable of :data:`CYCLE_VARIABLES`) -> the law over the pooled
    cycles (unweighted: the cycles of one release share its fit's errors; the scatter sets the covariance)."""
    damping: str = "viscous"
    """The dampers' law every release was fitted with: ``viscous`` (damping_ratio) or ``power`` (C, alpha)."""
    constant_friction: bool = False
    """The pendulum's friction fitted as constant (``[building] friction_coefficient``: rate held at 0)."""
    flexible: bool = False
    """Every release fitted with the layer under a flexible superstructure (``fit_isolation(flexible=True)``)."""
    left_out: dict[str, tuple[str, ...]] = field(default_factory=dict)
    """Per quantity, the releases left out of its laws because their records do not identify it
    (:meth:`ReleaseEstimates.identified`); a quantity identified by fewer than three releases has no law."""

    @property
    def kind(self) -> str:
        return "building"

    @property
    def columns(self) -> tuple[str, ...]:
        """Every quantity of each release: those with laws, then those reported."""
        return self.quantities + self.reported

    def significant_effects(self) -> list[tuple[str, str]]:
        """The (quantity, variable) pairs whose slope differs from 0 at the 5% level."""
        return [key for key, law in self.laws.items() if law.significant]

    def summary(self) -> dict[str, Any]:
        """JSON-ready (no NaN): the keys of ``quickrelease campaign --json`` for a building campaign."""
        laws = []
        for law in self.laws.values():
            y_unit, x_unit = QUANTITIES[law.quantity][1], BUILDING_VARIABLES[law.variable][1]
            slope_unit = y_unit if x_unit == "-" else (f"1/{x_unit}" if y_unit == "-" else f"{y_unit}/{x_unit}")
            laws.append({**law.summary(), "units": {"a": y_unit, "b": slope_unit}})
        return jsonable({"kind": "building", "title": self.title, "campaign": self.source, "model": self.model,
                           "mass_kg": self.mass, "superstructure_mass_kg": self.superstructure_mass,
                           "variables": list(self.variables), "quantities": list(self.quantities),
                           "reported": list(self.reported), "damping": self.damping,
                           "constant_friction": self.constant_friction, "flexible": self.flexible,
                           "units": {q: QUANTITIES[q][1] for q in self.columns},
                           "releases": [r.summary() for r in self.releases],
                           "laws": laws, "left_out": {q: list(v) for q, v in self.left_out.items()},
                           "significant_5pct": [f"{q} ~ {v}" for q, v in self.significant_effects()],
                           "cycles": [dict(c) for c in self.cycles],
                           "cycle_laws": [{**law.summary(), "units": {
                               "a": CYCLE_QUANTITIES[law.quantity][1],
                               "b": _slope_unit(CYCLE_QUANTITIES[law.quantity][1], CYCLE_VARIABLES[law.variable][1])}}
                               for law in self.cycle_laws.values()],
                           "notes": self.notes})


def _slope_unit(y_unit: str, x_unit: str) -> str:
    return y_unit if x_unit == "-" else (f"1/{x_unit}" if y_unit == "-" else f"{y_unit}/{x_unit}")


def pooled_cycles(names, fits) -> tuple[dict[str, Any], ...]:
    """The cycles of each release's fitted model over its record (:func:`quickrelease.studies.building_effective.
    model_cycles`, exact; the cycle from the release left out: its F+ is the unloading branch's), pooled in
    the releases' order; none for 2dof (its base force is not the isolators' alone)."""
    out = []
    for name, fit in zip(names, fits, strict=True):
        if getattr(fit, "flexible", fit.model == "2dof"):  # 2dof, or a layer under a flexible superstructure
            continue
        cyc = model_cycles(fit.isolation(), fit.parameters["d0"], record_span(fit))
        for i in range(cyc["amplitude_m"].size):
            if cyc["from_release"][i] or not math.isfinite(cyc["edc_J"][i]):
                continue
            out.append({"release": name, **{k: float(cyc[k][i]) for k in
                                            ("amplitude_m", "keff_N_m", "edc_J", "beta_eff", "teff_s")}})
    return tuple(out)


def cycle_laws(cycles, variables) -> dict[tuple[str, str], LinearLaw]:
    """keff and beta_eff against the cycle amplitude D (``displacement``) or ln D (``log_displacement``) over the
    pooled cycles, unweighted (:func:`quickrelease.studies._laws.fit_line`); the release variable ``force`` has
    no per-cycle counterpart. Empty with fewer than three cycles."""
    out: dict[tuple[str, str], LinearLaw] = {}
    if len(cycles) < 3:
        return out
    d = np.array([c["amplitude_m"] for c in cycles])
    for v in variables:
        if v not in CYCLE_VARIABLES:
            continue
        x = d if v == "displacement" else np.log(d)
        if np.ptp(x) == 0:
            continue
        for q in CYCLE_QUANTITIES:
            out[(q, v)] = fit_line(x, [c[q] for c in cycles], quantity=q, variable=v)
    return out


def fit_building_campaign(releases, mass: float, model: str = "linear", *, variables=("displacement",),
                          quantities=None, start: dict[str, float] | None = None, title: str = "",
                          source: str = "", notes: str = "", superstructure_mass: float | None = None,
                          damping: str = "viscous", constant_friction: bool = False,
                          flexible: bool = False) -> BuildingCampaignResult:
    """Fit every release of one building, then the law of each quantity in each variable.

    Parameters
    ----------
    releases : sequence of BuildingRelease
        At least three releases (a law needs a degree of freedom), at different amplitudes (or forces).
    mass : float
        Mass carried by the isolation layer [kg], the same in every release.
    model : {"linear", "bilinear", "2dof", "pendulum", "boucwen"}
    variables : sequence of str
        Regressors of the laws: ``displacement`` (|d0| [m]), ``log_displacement`` (ln |d0|), ``force`` (P [N]).
    quantities : sequence of str, optional
        Default :func:`default_quantities` of the model, damper and friction law.
    start : dict, optional
        Start values of every fit (the design values; the bilinear fit needs them).
    superstructure_mass : float, optional
        The ``2dof`` model's (or a flexible campaign's) superstructure mass at the roof [kg], in (0, mass): the
        same in every release.
    damping : {"viscous", "power"}
        The dampers' law of every fit (``fit_isolation(damping=...)``).
    constant_friction : bool
        The pendulum's friction is a constant coefficient: each release fitted with Constantinou's rate held at 0
        (and mu_fast, which then plays no part, at the start's mu_slow); quantity ``friction_coefficient``.
    flexible : bool
        Fit each release's bilinear, pendulum or boucwen layer under a flexible superstructure of
        ``superstructure_mass`` (``fit_isolation(flexible=True)``); the superstructure's period and damping ratio are
        reported per release (laws where asked in ``quantities``), and there are no pooled cycles (as 2dof).

    Raises
    ------
    ParameterError
        For an unknown model, variable or quantity, repeated release names, or a 2dof campaign without a
        superstructure mass in (0, mass).
    QuickReleaseError
        With fewer than three releases, a variable that is constant or missing, or a fit that fails (the
        message names the release).
    """
    releases = list(releases)
    if model not in DEFAULT_QUANTITIES:
        raise ParameterError("model", model, ", ".join(DEFAULT_QUANTITIES))
    variables = tuple(variables)
    bad = [v for v in variables if v not in BUILDING_VARIABLES]
    if bad or not variables:
        raise ParameterError("variables", bad[0] if bad else "none", ", ".join(BUILDING_VARIABLES))
    flexible = bool(flexible) and model != "2dof"
    if flexible and model not in FLEXIBLE_MODELS:
        raise ParameterError("model", model, f"{', '.join(repr(m) for m in FLEXIBLE_MODELS)} with flexible=True "
                             "(the linear layer under a flexible superstructure is model='2dof')")
    if model == "2dof" or flexible:
        ms = math.nan if superstructure_mass is None else float(superstructure_mass)
        if not (math.isfinite(ms) and 0.0 < ms < float(mass)):
            raise ParameterError("superstructure_mass", superstructure_mass, f"(0, mass) = (0, {float(mass):.6g}) kg "
                                 f"(the {'2dof model' if model == '2dof' else 'flexible superstructure'} needs it)",
                                 "kg")
        superstructure_mass = ms
    else:
        superstructure_mass = None
    if damping not in DAMPER_QUANTITIES:
        raise ParameterError("damping", damping, ", ".join(DAMPER_QUANTITIES))
    constant_friction = bool(constant_friction) and model == "pendulum"
    shared = constant_friction_fixed(start) if constant_friction else None
    defaults = default_quantities(model, damping, constant_friction)
    quantities = tuple(quantities) if quantities is not None else defaults
    storey = REPORTED["2dof"] if flexible else ()  # the superstructure's, as 2dof reports them
    allowed = defaults + EXTRA_QUANTITIES.get(model, ()) + REPORTED.get(model, ()) + storey
    bad = [q for q in quantities if q not in allowed]
    if bad or not quantities:
        raise ParameterError("quantities", bad[0] if bad else "none", ", ".join(allowed))
    names = [r.name for r in releases]
    if len(set(names)) != len(names):
        raise ParameterError("releases", ", ".join(names), "distinct release names")
    if len(releases) < 3:
        raise QuickReleaseError(f"{len(releases)} release(s): an amplitude law needs at least 3")
    # what can be checked before the fits
    if "force" in variables:
        missing = [r.name for r in releases if r.force is None]
        if missing:
            raise QuickReleaseError(f"release {missing[0]} has no push force (give force, or drop 'force' from "
                                    "variables)")
        if len({r.force for r in releases}) == 1:
            raise QuickReleaseError("every release has the same push force: no law in force can be fitted")
    if any(v != "force" for v in variables) and all(r.d0 is not None for r in releases) \
            and len({abs(r.d0) for r in releases}) == 1:
        raise QuickReleaseError("every release has the same pushed displacement d0: no law in the amplitude can be "
                                "fitted")
    memos: dict[str, FitMemo] = {}  # what each fit computes, for the restarts (its global stage, its own starts)
    fits = _fit_releases(releases, mass, model, start, superstructure_mass, damping, shared, memos=memos,
                         flexible=flexible)
    restarts = _restart_misfits(releases, fits, mass, model, superstructure_mass, damping, shared, memos=memos,
                                flexible=flexible)
    reported = tuple(q for q in REPORTED.get(model, ()) + storey if q not in quantities)
    estimates = [_estimates(r, fit, quantities + reported, restarts.get(r.name))
                 for r, fit in zip(releases, fits, strict=True)]
    laws = {}
    left_out = {q: tuple(r.name for r in estimates if not r.identified(q)) for q in quantities}
    left_out = {q: names for q, names in left_out.items() if names}
    for v in variables:
        x = [r.value(v) for r in estimates]
        if np.ptp(x) == 0:
            raise QuickReleaseError(f"every release has the same {BUILDING_VARIABLES[v][0]}: no law in {v} can be "
                                    "fitted")
        for q in quantities:
            # the releases whose records identify q: one that does not has no weight to give (no law with fewer
            # than three, or where they share one value of the variable)
            kept = [(xi, r) for xi, r in zip(x, estimates, strict=True) if r.identified(q)]
            if len(kept) < 3 or np.ptp([xi for xi, _ in kept]) == 0:
                continue
            laws[(q, v)] = fit_line([xi for xi, _ in kept], [r.values[q] for _, r in kept],
                                    weights_or_none(r.std_errors[q] for _, r in kept), quantity=q, variable=v)
    cycles = pooled_cycles([r.name for r in releases], fits)
    return BuildingCampaignResult(title=title or "Building campaign", source=source, model=model, mass=float(mass),
                                  releases=estimates, laws=laws, variables=variables, quantities=quantities,
                                  notes=notes, reported=reported, superstructure_mass=superstructure_mass,
                                  cycles=cycles, cycle_laws=cycle_laws(cycles, variables), damping=damping,
                                  constant_friction=constant_friction, left_out=left_out, flexible=flexible)


@styled
def building_campaign_figure(result: BuildingCampaignResult, fig=None, ax=None):
    """Each quantity against each variable: the releases with their 95% intervals, the law and its band. ``ax``:
    (variables) x (quantities) Axes to draw into, a row per variable. Returns the figure."""
    from ..report._style import panels, per
    from ..report.plots import user_label

    nq, nv = len(result.quantities), len(result.variables)
    height = 2.9 * nv + 0.9  # [in]: 0.85 in for the titles above, 0.5 in for the labels below
    fig, axes = panels(3.2 * nq + 0.6, height, (nv, nq), fig=fig, ax=ax, subplots={"squeeze": False}, left=0.06,
                       right=0.98, bottom=0.5 / height, top=1 - 0.85 / height, wspace=0.35, hspace=0.6)
    axes = np.asarray(axes, dtype=object).reshape(nv, nq)
    for row, v in enumerate(result.variables):
        x_label, _, x_scale, x_unit = BUILDING_VARIABLES[v]
        x = [r.value(v) for r in result.releases]
        for col, q in enumerate(result.quantities):
            y_label, _, y_scale, y_unit, symbol = QUANTITIES[q]
            y = np.array([r.values[q] for r in result.releases])
            lo = np.array([r.ci95[q][0] for r in result.releases])
            hi = np.array([r.ci95[q][1] for r in result.releases])
            panel = axes[row, col]
            slope_unit = per(y_unit, x_unit)
            seen = np.array([r.identified(q) for r in result.releases])
            yerr = np.where(seen, np.vstack([y - lo, hi - y]), 0.0).clip(min=0.0)
            names = [r.name if ok else f"{r.name} (not identified)" for r, ok in zip(result.releases, seen,
                                                                                     strict=True)]
            law = result.laws.get((q, v))
            if law is not None:
                law_panel(panel, law, np.asarray(x)[seen], y[seen], yerr[:, seen], list(np.array(names)[seen]),
                          x_scale=x_scale, y_scale=y_scale, x_label=f"{x_label} [{x_unit}]",
                          y_label=f"{y_label} [{y_unit}]", slope_unit=slope_unit, name=symbol)
            else:
                _points_panel(panel, x, y, yerr, names, x_scale, y_scale, f"{x_label} [{x_unit}]",
                              f"{y_label} [{y_unit}]", f"{symbol}: no law (identified by {int(seen.sum())} of "
                                                       f"{seen.size} releases)")
            if law is not None and not seen.all():
                _points_panel(panel, np.asarray(x)[~seen], y[~seen], yerr[:, ~seen],
                              list(np.array(names)[~seen]), x_scale, y_scale)
            panel.ticklabel_format(axis="y", useOffset=False)
            if row == 0 and col == 0:
                panel.legend(loc="best")
    if ax is None:
        user_label(fig, "suptitle", f"{result.title}: the isolation system against the release amplitude "
                                    f"({result.model} model)")
    return fig


def _points_panel(ax, x, y, yerr, names, x_scale: float, y_scale: float, x_label: str | None = None,
                  y_label: str | None = None, title: str | None = None) -> None:
    """Releases drawn without a law (those whose records do not identify the quantity: hollow markers)."""
    from ..report._style import STYLE
    from ..report.plots import _COLORS, user_label

    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    ax.errorbar(x * x_scale, y * y_scale, yerr=np.asarray(yerr, dtype=float) * y_scale, fmt="o", ms=4,
                mfc="none", color=_COLORS["b"], capsize=2, label="not identified")
    for xi, yi, name in zip(x, y, names, strict=True):
        user_label(ax, "annotate", name, (xi * x_scale, yi * y_scale), textcoords="offset points", xytext=(4, 3),
                   fontsize=STYLE["legend.fontsize"])
    if x_label is not None:
        ax.set_xlabel(x_label)
        ax.set_ylabel(y_label)
        ax.set_title(title, fontsize=STYLE["legend.fontsize"])


# -- the campaign file ------------------------------------------------------------------------------------------

_TOP_KEYS = {"title", "notes", "variables", "building", "tests"}
_TEST_KEYS = {"name", "record", "displacement", "force", "release_time"}
#: Keys of a device campaign, refused beside [building] (a campaign is of the device or of the building).
_DEVICE_TOP = {"device", "test", "record", "fit", "simulation"}
_DEVICE_TEST = {"case", "alpha0", "alpha_final", "stop_time", "energy", "mass_model"}


def load_building_campaign(path, data: dict[str, Any]) -> tuple[str, str, tuple[str, ...], str, float,
                                                                 dict[str, float], list[BuildingRelease],
                                                                 float | None, str, bool]:
    """Read a building campaign file (its parsed TOML ``data``): every release's record is read and checked
    here, before any fit. Returns (title, notes, variables, model, mass, start values, releases,
    superstructure mass (2dof, flexible; else None), the dampers' law, whether a pendulum's friction is constant
    (``friction_coefficient``), whether the layer is under a flexible superstructure (``flexible = true``)).

    Campaign file::

        title = "..."
        variables = ["displacement"]       # also "log_displacement", "force"
        [building]                         # shared: model, mass, the design values (start values)
        model = "linear"                   # or "bilinear" (k1, k2, yield_force), "2dof" (with
        mass = "400 t"                     #   superstructure_mass, superstructure_period), "pendulum"
        period = "2 s"                     #   (radius, friction_coefficient or friction_slow, friction_fast,
                                           #   rate), "boucwen" (post_yield_stiffness, ...); damping = "power"
                                           #   (damping_coefficient, damping_exponent) for fluid dampers
        [building.record]                  # shared: time column and channel mapping of the records
        time = "t_s"
        [building.record.channels]
        x = { column = "x_mm", unit = "mm" }

        [[tests]]
        name = "R1"
        displacement = "50 mm"             # the pushed displacement d0, and/or force = "220 kN"
        record = "records/R1.csv"          # the building's record of this release (relative to this file)
        # release_time = "1 s"             # optional start value

    Raises
    ------
    CaseFileError
        A malformed file or test, a device key beside ``[building]`` (one line naming the file and key).
    RecordError
        A record file or column missing (one line naming the file and the column).
    """
    import copy
    from pathlib import Path

    from ..io.building_case import load_building
    from ..io.case import CaseFileError, case_from_mapping
    from ..io.records import RecordError
    from ..units import parse_quantity

    path = Path(path)
    source = str(path)
    mixed = sorted(set(data) & _DEVICE_TOP)
    if mixed:
        raise CaseFileError(f"{source}: [{mixed[0]}] beside [building]: a campaign is of the device ([device], "
                            "[record], [[tests]] with force and alpha0) or of the building ([building], [[tests]] "
                            "with displacement or force and record), not both")
    unknown = sorted(set(data) - _TOP_KEYS)
    if unknown:
        raise CaseFileError(f"{source}: unknown key {unknown[0]!r}; valid: {', '.join(sorted(_TOP_KEYS))}")
    template = data["building"]
    if not isinstance(template, dict):
        raise CaseFileError(f"{source}: [building] is not a table")
    # the model and the damper law ([building] model, damping) are checked with the rest of [building] by the
    # case's own parser below, for each release (one line naming the file, key and the valid values)
    if "displacement" in template:
        raise CaseFileError(f"{source}: [building] displacement: give each release's own in [[tests]] "
                            "displacement")
    variables = data.get("variables", ["displacement"])
    if not isinstance(variables, list) or not variables or any(v not in BUILDING_VARIABLES for v in variables):
        raise CaseFileError(f"{source}: variables = {variables!r}: expected a list of {', '.join(BUILDING_VARIABLES)}")
    tests = data.get("tests")
    if not isinstance(tests, list) or not tests:
        raise CaseFileError(f"{source}: missing [[tests]]: give one table per release (name, displacement or "
                            "force, record)")
    releases, start, mass, superstructure_mass = [], {}, math.nan, None
    for name, where, entry in iter_tests(tests, source, "R"):
        device = sorted(set(entry) & _DEVICE_TEST)
        if device:
            raise CaseFileError(f"{where}: {device[0]!r} is a key of a device campaign, beside [building] (a "
                                "campaign is of the device or of the building, not both)")
        bad = sorted(set(entry) - _TEST_KEYS)
        if bad:
            raise CaseFileError(f"{where}: unknown key {bad[0]!r}; valid: {', '.join(sorted(_TEST_KEYS))}")
        if "record" not in entry:
            raise CaseFileError(f"{where}: missing key record (the building's record of this release, e.g. "
                                "record = 'records/R1.csv')")
        if "displacement" not in entry and "force" not in entry:
            raise CaseFileError(f"{where}: give displacement (the pushed d0, e.g. '120 mm') or force (the push "
                                "force, e.g. '500 kN')")
        building = copy.deepcopy(template)
        record = building.setdefault("record", {})
        if not isinstance(record, dict):
            raise CaseFileError(f"{source}: [building.record] is not a table")
        record["file"] = entry["record"]
        if "release_time" in entry:
            record["release_time"] = entry["release_time"]
        if "displacement" in entry:
            building["displacement"] = entry["displacement"]
        case = case_from_mapping({"title": name, "building": building}, source=where, base=path.parent,
                                 require_test=False)
        try:
            loaded = load_building(case)
        except RecordError as exc:  # the record's file and column, and which test's record it is
            text = str(exc)
            raise RecordError(text if text.startswith(where) else f"{where}: {text}") from None
        force = None
        if "force" in entry:
            try:
                force = parse_quantity(entry["force"], "force", "force")
            except QuickReleaseError as exc:
                raise CaseFileError(f"{where}: {exc}") from None
            if not force > 0.0:
                raise CaseFileError(f"{where}: force = {entry['force']!r}: expected a positive push force, e.g. "
                                    "'500 kN'")
        if not loaded.channels:
            raise CaseFileError(f"{where}: [building.record.channels] maps no channel")
        releases.append(BuildingRelease(name, loaded.channels, d0=loaded.d0, force=force,
                                        release_time=loaded.release_time, exclude_spikes=loaded.exclude_spikes))
        start = {k: v for k, v in loaded.start.items() if k != "d0"}  # d0: each release's own, from its record
        mass, superstructure_mass = loaded.mass, loaded.superstructure_mass
    if len(releases) < 3:
        raise CaseFileError(f"{source}: {len(releases)} test(s): an amplitude law needs at least 3 releases")
    title = str(data.get("title", path.stem))
    model = str(template.get("model", "linear"))
    constant = loaded.constant_friction  # the last release's: [building] is every release's
    return title, str(data.get("notes", "")), tuple(variables), model, mass, start, releases, superstructure_mass, \
        str(template.get("damping", "viscous")), constant, loaded.flexible


def run_building_campaign(path, data: dict[str, Any]) -> BuildingCampaignResult:
    """Read a building campaign file (:func:`load_building_campaign`) and fit it
    (:func:`fit_building_campaign`)."""
    (title, notes, variables, model, mass, start, releases, ms, damping, constant,
     flexible) = load_building_campaign(path, data)
    return fit_building_campaign(releases, mass, model, variables=variables, start=start or None, title=title,
                                 source=str(path), notes=notes, superstructure_mass=ms, damping=damping,
                                 constant_friction=constant, flexible=flexible)
