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
- 2dof (:class:`quickrelease.building.model.TwoDOF`, each release fitted with the superstructure's mass at the roof
  given): ``period``, ``damping_ratio`` and ``friction`` are the isolation layer's (T of the whole mass on the
  isolators), with laws as for the linear model, ``secant_period`` and ``equivalent_damping_ratio`` those of
  the isolation layer under the whole mass (the linear model's formulas; the superstructure's own damping is
  not in them); the superstructure's fixed-base period ``superstructure_period`` T_s [s] and damping ratio
  ``superstructure_damping_ratio`` zeta_s [-] are reported per release with their intervals (laws for them
  when asked for in ``quantities``).

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
  determine the parameter); ``t`` is the Student quantile of the fit's degrees of freedom.

The releases share one building, so a release whose fit misfits its record (reduced chi-square above
:data:`MISFIT_RESTART` with known noise: the fit's local minima, e.g. a wrong count of half-cycles before
the sliders stick, or the bilinear model's friction traded against its yield force) is refitted from the
estimates of each release that fits well, and the better fit kept (``restarted_from`` names its start).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import stats

from ..building.isolation_fit import PARAMETER_BOUNDS, BuildingChannel, IsolationFit, _isolation, fit_isolation
from ..building.model import pushed_state
from ..errors import ParameterError, QuickReleaseError
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
}
#: The quantities a campaign fits laws for, by model.
DEFAULT_QUANTITIES = {
    "linear": ("period", "damping_ratio", "friction", "equivalent_damping_ratio"),
    "bilinear": ("secant_period", "damping_ratio", "friction", "equivalent_damping_ratio", "period",
                 "stiffness_ratio", "yield_force"),
    "2dof": ("period", "damping_ratio", "friction", "equivalent_damping_ratio"),
}
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
           "superstructure_damping_ratio")
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


def derived_quantity(name: str, model: str, mass: float, p: dict[str, float]) -> float:
    """A quantity of the isolation system from the model's parameters ``p`` (fit_isolation's names, with
    ``d0``), in SI: see the module's docstring for the equations (``2dof``: of its isolation layer under the
    whole mass, the linear model's)."""
    if name in _FITTED:
        return float(p[name])
    iso = _isolation("linear" if model == "2dof" else model, mass, p)
    d = abs(float(p["d0"]))
    _, R0, _ = pushed_state(iso, d)
    k_sec = R0 / d
    if name == "secant_period":
        return 2.0 * math.pi * math.sqrt(mass / k_sec)
    if name == "equivalent_damping_ratio":
        omega = math.sqrt(k_sec / mass)
        hysteretic = 0.0
        if iso.model == "bilinear":
            d_y = float(iso.yield_force) / iso.stiffness
            hysteretic = 4.0 * iso.plastic_yield * max(d - d_y, 0.0)
        dissipated = math.pi * iso.damping * omega * d * d + 4.0 * iso.friction * d + hysteretic
        return dissipated / (2.0 * math.pi * k_sec * d * d)
    raise ParameterError("quantity", name, ", ".join(QUANTITIES))


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
    params = dict(fit.estimates)
    if "d0" not in params:
        params["d0"] = float(release.d0)
    tq = float(stats.t.ppf(0.975, max(fit.dof, 1)))
    se_all = np.array([fit.std_errors[n] for n in fit.names])
    blind = ~np.isfinite(se_all)  # not identified by the record: a quantity that depends on one has SE inf
    se_known = np.where(blind, 0.0, se_all)
    cov = fit.correlation * np.outer(se_known, se_known)
    values, ses, ci, method = {}, {}, {}, {}
    for q in quantities:
        if q in _FITTED and q in fit.estimates:
            values[q] = fit.estimates[q]
            ci[q] = tuple(fit.ci95[q])
            method[q] = fit.interval_method[q]
            ses[q] = (law_standard_error(values[q], ci[q], PARAMETER_BOUNDS[q], tq) if method[q] == "profile"
                      else fit.std_errors[q])
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


def _fixed(release: BuildingRelease) -> dict[str, float] | None:
    if release.d0 is not None and not any(c.kind in ("x", "x_roof") for c in release.channels):
        return {"d0": float(release.d0)}  # no displacement channel: the given d0 is the release state
    return None


def _misfit(fit: IsolationFit) -> bool:
    """The fit's misfit exceeds its noise (the warning of :func:`fit_isolation`): a local minimum, or a
    model the record does not support."""
    return fit.absolute_sigma and math.isfinite(fit.chi2_reduced) and fit.chi2_reduced > MISFIT_RESTART


#: Releases of a campaign fitted in parallel processes at most (one per core; 1: one after the other).
CAMPAIGN_WORKERS = max(1, min(os.cpu_count() or 1, 8))


def _fit_one(r, mass: float, model: str, start, superstructure_mass):
    try:
        return fit_isolation(r.channels, mass, model, release_time=r.release_time, start=start, fixed=_fixed(r),
                             superstructure_mass=superstructure_mass, exclude_spikes=r.exclude_spikes)
    except QuickReleaseError as exc:
        raise type(exc)(f"release {r.name}: {exc}") from None


def _fit_releases(releases, mass: float, model: str, start, superstructure_mass) -> list[IsolationFit]:
    """Each release's fit, in parallel processes (``CAMPAIGN_WORKERS``, spawned: each fit is Python-bound, so
    threads would share one core) where there are at least three releases and two cores; the fits are the
    same as one after the other (each fit is deterministic for its seed)."""
    workers = min(CAMPAIGN_WORKERS, len(releases))
    if workers < 2 or len(releases) < 3:
        return [_fit_one(r, mass, model, start, superstructure_mass) for r in releases]
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        jobs = [pool.submit(_fit_one, r, mass, model, start, superstructure_mass) for r in releases]
        return [job.result() for job in jobs]


def _restart_misfits(releases, fits: list[IsolationFit], mass: float, model: str,
                     superstructure_mass: float | None = None) -> dict[str, str]:
    """Refit each release whose misfit exceeds its noise from the estimates of every release that fits
    well (the campaign knows the building: the model's misfit has local minima, e.g. the count of
    half-cycles before the sliders stick), keeping the lowest chi-square; ``fits`` is updated in place.
    Returns {release: the release whose estimates started its kept fit}."""
    good = [(r.name, f) for r, f in zip(releases, fits, strict=True) if not _misfit(f) and f.converged]
    restarted = {}
    for i, r in enumerate(releases):
        if not _misfit(fits[i]):
            continue
        for name, other in good:
            start = {n: other.estimates[n] for n in _FITTED if n in other.estimates}
            try:
                trial = fit_isolation(r.channels, mass, model, release_time=r.release_time, start=start,
                                      fixed=_fixed(r), superstructure_mass=superstructure_mass,
                                      exclude_spikes=r.exclude_spikes)
            except QuickReleaseError:
                continue
            if trial.chi2 < fits[i].chi2:
                fits[i], restarted[r.name] = trial, name
            if not _misfit(fits[i]):
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
    """2dof: the superstructure's mass at the roof given to every fit [kg]."""
    cycles: tuple[dict[str, Any], ...] = ()
    """Every release's cycles of its fitted model's loop, pooled (:func:`pooled_cycles`): ``release``,
    ``amplitude_m``, ``keff_N_m``, ``edc_J``, ``beta_eff``, ``teff_s``; empty for 2dof."""
    cycle_laws: dict[tuple[str, str], LinearLaw] = field(default_factory=dict)
    """(quantity of :data:`CYCLE_QUANTITIES`, variable of :data:`CYCLE_VARIABLES`) -> the law over the pooled
    cycles (unweighted: the cycles of one release share its fit's errors; the scatter sets the covariance)."""

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
                           "reported": list(self.reported), "releases": [r.summary() for r in self.releases],
                           "laws": laws,
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
        if fit.model == "2dof":
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
                          source: str = "", notes: str = "", superstructure_mass: float | None = None
                          ) -> BuildingCampaignResult:
    """Fit every release of one building, then the law of each quantity in each variable.

    Parameters
    ----------
    releases : sequence of BuildingRelease
        At least three releases (a law needs a degree of freedom), at different amplitudes (or forces).
    mass : float
        Mass carried by the isolation layer [kg], the same in every release.
    model : {"linear", "bilinear", "2dof"}
    variables : sequence of str
        Regressors of the laws: ``displacement`` (|d0| [m]), ``log_displacement`` (ln |d0|), ``force`` (P [N]).
    quantities : sequence of str, optional
        Default :data:`DEFAULT_QUANTITIES` of the model.
    start : dict, optional
        Start values of every fit (the design values; the bilinear fit needs them).
    superstructure_mass : float, optional
        The ``2dof`` model's superstructure mass at the roof [kg], in (0, mass): the same in every release.

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
    if model == "2dof":
        ms = math.nan if superstructure_mass is None else float(superstructure_mass)
        if not (math.isfinite(ms) and 0.0 < ms < float(mass)):
            raise ParameterError("superstructure_mass", superstructure_mass,
                                 f"(0, mass) = (0, {float(mass):.6g}) kg (the 2dof model needs it)", "kg")
        superstructure_mass = ms
    else:
        superstructure_mass = None
    quantities = tuple(quantities) if quantities is not None else DEFAULT_QUANTITIES[model]
    allowed = DEFAULT_QUANTITIES[model] + (("secant_period",) if model in ("linear", "2dof") else ()) \
        + REPORTED.get(model, ())
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
    fits = _fit_releases(releases, mass, model, start, superstructure_mass)
    restarts = _restart_misfits(releases, fits, mass, model, superstructure_mass)
    reported = tuple(q for q in REPORTED.get(model, ()) if q not in quantities)
    estimates = [_estimates(r, fit, quantities + reported, restarts.get(r.name))
                 for r, fit in zip(releases, fits, strict=True)]
    laws = {}
    for v in variables:
        x = [r.value(v) for r in estimates]
        if np.ptp(x) == 0:
            raise QuickReleaseError(f"every release has the same {BUILDING_VARIABLES[v][0]}: no law in {v} can be "
                                    "fitted")
        for q in quantities:
            laws[(q, v)] = fit_line(x, [r.values[q] for r in estimates],
                                    weights_or_none(r.std_errors[q] for r in estimates), quantity=q, variable=v)
    cycles = pooled_cycles([r.name for r in releases], fits)
    return BuildingCampaignResult(title=title or "Building campaign", source=source, model=model, mass=float(mass),
                                  releases=estimates, laws=laws, variables=variables, quantities=quantities,
                                  notes=notes, reported=reported, superstructure_mass=superstructure_mass,
                                  cycles=cycles, cycle_laws=cycle_laws(cycles, variables))


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
            law_panel(panel, result.laws[(q, v)], x, y, np.vstack([y - lo, hi - y]).clip(min=0.0),
                      [r.name for r in result.releases], x_scale=x_scale, y_scale=y_scale,
                      x_label=f"{x_label} [{x_unit}]", y_label=f"{y_label} [{y_unit}]", slope_unit=slope_unit,
                      name=symbol)
            panel.ticklabel_format(axis="y", useOffset=False)
            if row == 0 and col == 0:
                panel.legend(loc="best")
    if ax is None:
        user_label(fig, "suptitle", f"{result.title}: the isolation system against the release amplitude "
                                    f"({result.model} model)")
    return fig


# -- the campaign file ------------------------------------------------------------------------------------------

_TOP_KEYS = {"title", "notes", "variables", "building", "tests"}
_TEST_KEYS = {"name", "record", "displacement", "force", "release_time"}
#: Keys of a device campaign, refused beside [building] (a campaign is of the device or of the building).
_DEVICE_TOP = {"device", "test", "record", "fit", "simulation"}
_DEVICE_TEST = {"case", "alpha0", "alpha_final", "stop_time", "energy", "mass_model"}


def load_building_campaign(path, data: dict[str, Any]) -> tuple[str, str, tuple[str, ...], str, float,
                                                                 dict[str, float], list[BuildingRelease],
                                                                 float | None]:
    """Read a building campaign file (its parsed TOML ``data``): every release's record is read and checked
    here, before any fit. Returns (title, notes, variables, model, mass, start values, releases,
    superstructure mass (2dof; else None)).

    Campaign file::

        title = "..."
        variables = ["displacement"]       # also "log_displacement", "force"
        [building]                         # shared: model, mass, the design values (start values)
        model = "linear"                   # or "bilinear" (k1, k2, yield_force), "2dof" (with
        mass = "400 t"                     #   superstructure_mass, superstructure_period)
        period = "2 s"
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
    if template.get("model", "linear") not in DEFAULT_QUANTITIES:
        raise CaseFileError(f"{source}: [building] model = {template.get('model')!r}: a campaign fits the "
                            f"{' or '.join(repr(m) for m in DEFAULT_QUANTITIES)} model (fit each release of a "
                            "pendulum or Bouc-Wen building with `quickrelease building`)")
    if template.get("damping", "viscous") != "viscous":
        raise CaseFileError(f"{source}: [building] damping = {template.get('damping')!r}: a campaign fits viscous "
                            "damping (damping_ratio) only (fit each release with fluid dampers with "
                            "`quickrelease building`)")
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
        loaded = load_building(case)
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
    return title, str(data.get("notes", "")), tuple(variables), str(template.get("model", "linear")), mass, \
        start, releases, superstructure_mass


def run_building_campaign(path, data: dict[str, Any]) -> BuildingCampaignResult:
    """Read a building campaign file (:func:`load_building_campaign`) and fit it
    (:func:`fit_building_campaign`)."""
    title, notes, variables, model, mass, start, releases, ms = load_building_campaign(path, data)
    return fit_building_campaign(releases, mass, model, variables=variables, start=start or None, title=title,
                                 source=str(path), notes=notes, superstructure_mass=ms)
