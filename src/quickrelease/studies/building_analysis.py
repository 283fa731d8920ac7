"""The building's free vibration analysed as a whole: fit, model comparison, decay and hysteresis (SI units).

:func:`analyse_building` takes the records of the isolation layer (a :class:`~quickrelease.io.building_case.
BuildingData` loaded from a case file, or channels and a mass) and calls what exists:

- :func:`quickrelease.building.isolation_fit.fit_isolation` for the chosen model (estimates, intervals, AIC/BIC,
  residual whiteness), and with ``compare`` for the other models too, ranked by
  :func:`~quickrelease.building.isolation_fit.compare_models`;
- :func:`quickrelease.building.decay.analyse_decay` on the displacement channel (offset of the fit removed) and
  :func:`~quickrelease.building.isolation_fit.decay_check`: the model-free decay beside the fit (the combined
  decrement law is exact for the linear model; a bilinear spring follows no decay law);
- :func:`quickrelease.building.decay.hysteresis_loop`: the isolators' force ``-m a`` against ``x``, the acceleration
  interpolated (linearly) onto the displacement channel's times when the two have their own time axes.

:meth:`BuildingResult.summary` is the JSON of ``quickrelease building --json``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import stats

from .._results import Summarised
from ..building.decay import DecayAnalysis, analyse_decay, hysteresis_loop
from ..building.effective import CycleProperties, loop_cycles
from ..building.identified import parameter_identified
from ..building.isolation_fit import (
    FLEXIBLE_MODELS,
    JSON_KEYS,
    BuildingChannel,
    IsolationFit,
    compare_models,
    decay_check,
    drop_excluded,
    fit_isolation,
)
from ..building.model import free_vibration
from ..errors import ParameterError, QuickReleaseError
from ..io.building_case import constant_friction_fixed
from ..io.export import jsonable
from .building_effective import CycleJudgement, EffectiveCurve, effective_curves, judge_cycles

__all__ = ["BuildingResult", "analyse_building", "MODELS", "physical_estimates", "holds_constant_friction"]

#: The models of the isolation layer the command knows (``2dof`` where the fit supports it).
MODELS = ("linear", "bilinear", "2dof", "pendulum", "boucwen")

#: Samples of the model curves in the figures (per channel).
_CURVE_POINTS = 4000


@dataclass(frozen=True, eq=False, repr=False)
class BuildingResult(Summarised):
    """The analysis of a building's free-vibration record: the chosen model's fit and the cross-checks."""

    fit: IsolationFit
    """The fit of the chosen model."""
    compared: tuple[IsolationFit, ...] = ()
    """Fits of every model compared (the chosen one included); empty without ``compare``."""
    comparison: tuple[dict[str, Any], ...] = ()
    """:func:`~quickrelease.building.isolation_fit.compare_models` rows, best (lowest BIC) first."""
    decay: DecayAnalysis | None = None
    """The model-free decay of the displacement channel (None without one)."""
    decay_check: dict[str, Any] = field(default_factory=dict)
    """:func:`~quickrelease.building.isolation_fit.decay_check` of the fit."""
    loop: dict[str, np.ndarray] | None = None
    """Hysteresis loop: at the displacement channel's times ``t`` [s] after the release, ``x`` [m] and
    ``force`` [N] measured (the acceleration interpolated onto ``t``), and the model's ``model_x``,
    ``model_force`` on a fine grid."""
    warnings: tuple[str, ...] = ()
    """The fit's warnings and those of the cross-checks."""
    notes: tuple[str, ...] = ()
    source: str = ""
    curves: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)
    """The fitted model for the figures, per channel name: ``t`` [s] on a fine grid over the channel's span
    (:data:`_CURVE_POINTS` samples), ``model`` there and ``residual`` (measured - model) at the channel's
    samples [the channel's SI unit] (:func:`model_curves`)."""
    model_decay: DecayAnalysis | None = None
    """The model-free decay analysis of the fitted model's own displacement, noise-free, from the release
    (:func:`model_decay`; None without a decay analysis of the record or a displacement channel)."""
    decay_envelope: dict[str, np.ndarray] = field(default_factory=dict)
    """The numbers behind the decay figure (:func:`decay_envelope`; empty without a decay analysis)."""
    effective: tuple[CycleProperties, ...] = ()
    """The engineering quantities per cycle of the fitted model's loop along the record's decay (keff, EDC,
    beta_eff, Qd, Kd, Teff, mu: :func:`effective_cycles`); empty for the 2dof model."""
    effective_curve: EffectiveCurve | None = None
    """keff, EDC, beta_eff and Teff of the identified model against the cycle amplitude with 95% bands
    (:func:`quickrelease.studies.building_effective.effective_curves`; None for the 2dof model)."""
    effective_judgement: CycleJudgement | None = None
    """The cycles of :attr:`effective` against that curve, criterion by criterion (:func:`~quickrelease.studies.
    building_effective.judge_cycles`; None without a curve)."""
    measured: Any = None
    """The record's own loop per cycle with standard errors (:func:`quickrelease.studies.building_cycles.
    measured_cycles`: -m a against x on one clock); None without a displacement channel, for 2dof, or where
    the record holds no whole cycle."""

    @property
    def model(self) -> str:
        return self.fit.model

    def summary(self) -> dict[str, Any]:
        """The JSON of ``quickrelease building --json``: the physical estimates with ``_ci95`` intervals,
        AIC/BIC, residual RMS per channel, convergence, warnings, notes, the comparison and the decay
        cross-check; the full fit under ``fit``."""
        out: dict[str, Any] = {"model": self.model, "source": self.source}
        if self.model == "pendulum":  # one friction_coefficient, or Constantinou's three
            out["constant_friction"] = holds_constant_friction(self.fit)
        out.update(physical_estimates(self.fit))
        out.update({"aic": self.fit.aic, "bic": self.fit.bic, "residual_rms": dict(self.fit.residual_rms),
                    "converged": self.fit.converged, "global_minimum_confirmed": self.fit.global_minimum_confirmed,
                    "search": None if self.fit.search is None else jsonable(self.fit.search.summary()),
                    "release_time_s": self.fit.release_time,
                    "d0_m": self.fit.parameters.get("d0"), "warnings": list(self.warnings),
                    "notes": list(self.notes), "comparison": [jsonable(r) for r in self.comparison],
                    "decay_check": jsonable({k: v for k, v in self.decay_check.items() if k != "analysis"}),
                    "decay": None if self.decay is None else jsonable(self.decay.summary(self.fit.mass)),
                    "effective": [jsonable(c.summary()) for c in self.effective],
                    "effective_curve": (None if self.effective_curve is None
                                        else jsonable(self.effective_curve.summary())),
                    "effective_judgement": (None if self.effective_judgement is None
                                            else jsonable(self.effective_judgement.summary())),
                    "measured_cycles": None if self.measured is None else jsonable(self.measured.summary()),
                    # the Bouc-Wen model's Qd_N and Kd_N_m are its fitted parameters, with their intervals: the
                    # sliders' friction_N stays apart (the model's Qd_N would add it, under the bearings' interval)
                    **{k: v for k, v in characteristic_strength(self.fit).items() if f"{k}_ci95" not in out},
                    "fit": jsonable(self.fit.summary())})
        return out


def effective_cycles(fit: IsolationFit, points_per_period: int = 20000) -> tuple[CycleProperties, ...]:
    """The engineering quantities per cycle (:func:`quickrelease.building.effective.loop_cycles`) of the fitted
    model's own loop, the isolators' total force ``-m x_ddot`` against x, from the release until the sliders
    hold the building (or over the record's span), ``points_per_period`` samples a period: the cycles of the
    record as the identified isolator runs them, free of the record's noise. Empty for ``2dof`` and a flexible
    fit (their base force is not the isolators' alone). The force at an extreme is the largest within two samples
    of it, which carries the damper's force of those samples: 4 zeta (2 pi / points_per_period) of keff (3e-5 at
    zeta = 0.03 and the default 20000, within the bands of
    :func:`~quickrelease.studies.building_effective.effective_curves` on clean records; 3e-4 at 2000); 0.09 s for a
    60 s record of 22 cycles."""
    if getattr(fit, "flexible", fit.model == "2dof"):
        return ()
    iso = fit.isolation()
    span = max(float(np.max(c.t)) for c in fit.channels) - fit.release_time if fit.channels else 0.0
    horizon = span if span > 0.0 else 20.0 * iso.period
    fv = free_vibration(iso, fit.parameters["d0"], t_end=horizon)
    end = fv.stop_time if math.isfinite(fv.stop_time) else horizon  # a stop lies within the horizon
    t = np.linspace(0.0, end, max(int(points_per_period * end / iso.period), 16) + 1)
    x, _, a = fv.state(t)
    # the turning points: the release from rest, the reversals, and the stop where the sliders hold
    turns = [0] + [int(i) for i in np.searchsorted(t, fv.reversal_times[1:]) if 0 < i < t.size - 1]
    if math.isfinite(fv.stop_time) and turns[-1] != t.size - 1:
        turns.append(t.size - 1)
    force = -fit.mass * a
    if turns[-1] == t.size - 1 and math.isfinite(fv.stop_time) and hasattr(fv, "restoring_force"):
        # at rest after the stop -m a is 0 (the sliders hold the spring): the last cycle's closing chord needs the
        # spring's force there, as at a reversal (the mean either side); without it that cycle's EDC lost
        # F_s (x_start - x_end) / 2 (1.5% of it on the building command's test record)
        force[-1] = float(np.asarray(fv.restoring_force(np.array([t[-1]])))[0])
    return loop_cycles(t + fit.release_time, x, force, mass=fit.mass, turns=sorted(set(turns)))


def characteristic_strength(fit: IsolationFit) -> dict[str, float]:
    """The model's characteristic strength ``Qd_N`` (the loading branches' force at x = 0: the sliders' F_s,
    plus ``F_y (1 - k2/k1)`` for the bilinear rubber) and post-yield stiffness ``Kd_N_m`` (k, or k2), where the
    model has them (not for 2dof; a flexible fit's layer's)."""
    if fit.model == "2dof":
        return {}
    iso = fit.isolation().rigid() if getattr(fit, "flexible", fit.model == "2dof") else fit.isolation()
    if fit.model == "pendulum":  # the loading branch's force at x = 0 at vanishing velocity: mu_slow W
        return {"Qd_N": float(iso.friction), "Kd_N_m": float(iso.stiffness)}
    if fit.model == "boucwen":
        return {"Qd_N": float(iso.friction + iso.characteristic_strength), "Kd_N_m": float(iso.k2)}
    qd = float(iso.friction) + (iso.plastic_yield if fit.model == "bilinear" else 0.0)
    return {"Qd_N": qd, "Kd_N_m": float(iso.k2)}


def physical_estimates(fit: IsolationFit) -> dict[str, Any]:
    """The isolation's parameters in engineering units with their 95% intervals ``<key>_ci95``.

    ``linear``/``2dof``: ``period_s``; ``bilinear``: ``k1_N_m = m (2 pi / T1)^2`` (its interval the image
    of T1's, k1 decreasing in T1), ``k2_N_m = (k2/k1) k1`` (interval by the delta method on ln k2 with the
    correlation of k2/k1 and T1), ``Fy_N``; ``pendulum``: ``period_s``, ``radius_m`` (the image of T's
    interval) and either Constantinou's ``friction_slow``, ``friction_fast``, ``rate_s_m`` or, for a fit
    that held the rate at 0 (:func:`holds_constant_friction`), the one ``friction_coefficient`` mu (the fit's
    friction_slow, with its interval; as building campaigns name it);
    all: ``damping_ratio`` (or the power-law damper's ``damping_coefficient``, ``damping_exponent``),
    ``friction_N`` (not the pendulum). A parameter held fixed has its value and no interval (None), and so has
    one the record does not identify (its key listed in ``not_identified``).
    """
    est, ci, model = fit.estimates, fit.ci95, fit.model
    flexible = getattr(fit, "flexible", False) and model != "2dof"  # a layer under a flexible superstructure
    iso = fit.isolation().rigid() if flexible else fit.isolation()  # the layer's values
    out: dict[str, Any] = {}

    # the record does not identify it (found so by the fit, or an interval over its whole range): the rule of
    # building campaigns (building.identified)
    blind = {n for n in fit.interval_method if not parameter_identified(fit, n)}
    out["not_identified"] = []

    def put(name: str, value: float | None = None, key: str | None = None) -> None:
        key = key or JSON_KEYS[name]
        out[key] = float(est[name]) if name in est else value
        out[f"{key}_ci95"] = [float(v) for v in ci[name]] if name in ci and name not in blind else None
        if name in blind:
            out["not_identified"].append(key)

    if model == "bilinear":
        m = fit.mass
        out["k1_N_m"] = float(iso.stiffness)
        out["k1_N_m_ci95"] = None
        if "period" in blind:
            out["not_identified"].append("k1_N_m")
        elif "period" in ci:
            lo, hi = ci["period"]
            out["k1_N_m_ci95"] = [m * (2 * math.pi / hi) ** 2 if hi > 0 else 0.0,
                                  m * (2 * math.pi / lo) ** 2 if lo > 0 else math.inf]
        out["k2_N_m"] = float(iso.k2)
        k2_ci = None if blind & {"period", "stiffness_ratio"} else _k2_interval(fit)
        if blind & {"period", "stiffness_ratio"} or (k2_ci is not None and not math.isfinite(k2_ci[1])):
            k2_ci = None  # the record does not bound k2
            out["not_identified"].append("k2_N_m")
        out["k2_N_m_ci95"] = k2_ci
        put("yield_force", float(iso.yield_force))
    elif model == "pendulum":
        put("period", float(iso.period))
        out["radius_m"] = float(iso.radius)  # R = g (T / 2 pi)^2, increasing in T: its interval the image of T's
        out["radius_m_ci95"] = (None if "period" not in ci or "period" in blind
                                else [9.80665 * (v / (2.0 * math.pi)) ** 2 for v in ci["period"]])
        if holds_constant_friction(fit):  # mu(v) = mu_slow at every speed: mu_fast plays no part
            put("friction_slow", float(iso.friction_slow), key="friction_coefficient")
        else:
            for name in ("friction_slow", "friction_fast", "rate"):
                put(name, float(getattr(iso, name)))
    elif model == "boucwen":
        put("period", float(iso.period))
        out["Kd_N_m"] = float(iso.k2)  # Kd = m (2 pi / T)^2, decreasing in T
        out["Kd_N_m_ci95"] = (None if "period" not in ci or "period" in blind
                              else sorted(fit.mass * (2.0 * math.pi / v) ** 2 if v > 0 else math.inf
                                          for v in ci["period"]))
        put("characteristic_strength", float(iso.characteristic_strength))
        put("yield_displacement", float(iso.yield_displacement))
        put("shape", float(iso.shape))
    else:
        put("period", float(iso.period))
    if fit.damping == "power":
        put("damping_coefficient", float(iso.damping))
        put("damping_exponent", float(iso.damping_exponent))
    else:
        put("damping_ratio", float(est.get("damping_ratio", fit.parameters.get("damping_ratio"))))
    if model != "pendulum":
        put("friction", float(iso.friction))
    if flexible:  # the superstructure's, as the 2dof fit names them
        for name in ("superstructure_period", "superstructure_damping_ratio"):
            put(name, float(fit.parameters[name]))
    # as building campaigns label it: a parameter the record does not identify has no interval, whatever method
    out["interval_method"] = {n: "not identified" if n in blind else m for n, m in fit.interval_method.items()}
    return {k: jsonable(v) for k, v in out.items()}


def holds_constant_friction(fit: IsolationFit) -> bool:
    """Whether ``fit`` is of the friction pendulum with a constant friction coefficient: Constantinou's rate held
    at 0 (:func:`quickrelease.io.building_case.constant_friction_fixed`), so that its friction_slow is mu."""
    return fit.model == "pendulum" and getattr(fit, "fixed", {}).get("rate") == 0.0


def _k2_interval(fit: IsolationFit) -> list[float] | None:
    """95% interval of k2 = r m (2 pi / T1)^2 by the delta method on ln k2 = ln r - 2 ln T1 + const."""
    names = list(fit.names)
    if "stiffness_ratio" not in names:
        return None
    r = fit.estimates["stiffness_ratio"]
    se_r = fit.std_errors["stiffness_ratio"]
    var = (se_r / r) ** 2
    if "period" in names:
        T, se_T = fit.estimates["period"], fit.std_errors["period"]
        rho = float(fit.correlation[names.index("stiffness_ratio"), names.index("period")])
        var += (2.0 * se_T / T) ** 2 - 2.0 * (2.0 / T) * (1.0 / r) * rho * se_r * se_T
    k2 = fit.isolation().k2
    half = float(stats.t.ppf(0.975, max(fit.dof, 1))) * math.sqrt(max(var, 0.0))
    if half > 700.0:  # beyond the float range: the record does not bound k2 (JSON: [0, null])
        return [0.0, math.inf]
    return [k2 * math.exp(-half), k2 * math.exp(half)]


#: Least-squares tolerance of the models fitted only to be ranked (AIC/BIC need chi-square to a fraction of a unit):
#: a bilinear model fitted to a linear record crawls along its degenerate valley (the yield force towards 0). Before
#: the global stage, 1e-6 stopped at a reduced chi-square of 209 (one start, far off); with the stage's starts, on
#: the benchmark's linear record, 1e-7 ends 0.18 above 1e-8 (chi-square 37893.64 against 37893.46, delta BIC 18.5
#: against 18.3) in 6 evaluations instead of 188 (5.8 s of CPU): ``--compare`` 17.3 -> 11.4 s.
COMPARE_TOLERANCE = 1e-7


def analyse_building(data: Any = None, *, channels=None, mass: float | None = None, model: str | None = None,
                     start: dict[str, float] | None = None, release_time: float | None = None,
                     compare: bool = False, source: str = "", superstructure_mass: float | None = None,
                     progress=None, global_search: bool = True, exclude_spikes: bool | None = None,
                     damping: str | None = None, constant_friction: bool | None = None,
                     flexible: bool | None = None) -> BuildingResult:
    """Fit the isolation model to the building's record and cross-check it (see the module docstring).

    Parameters
    ----------
    data : BuildingData, optional
        From :func:`quickrelease.io.building_case.load_building`: model, mass, start values, release time,
        channels, notes and source. Or give ``channels`` and ``mass`` (and optionally the rest) directly.
    model : {"linear", "bilinear", "2dof", "pendulum", "boucwen"}, optional
        The model to fit (default: the data's, else linear).
    damping : {"viscous", "power"}, optional
        The damper's law (default: the data's ``[building] damping``, else viscous).
    superstructure_mass : float, optional
        The roof mass m_s [kg] of the ``2dof`` model and of a flexible fit (default: the data's ``[building]
        superstructure_mass``).
    flexible : bool, optional
        Fit the bilinear, pendulum or boucwen layer under a flexible superstructure of ``superstructure_mass``
        (``fit_isolation(flexible=True)``; default: the data's ``[building] flexible``, else False).
    compare : bool
        Also fit the other models and rank them by AIC/BIC and residual whiteness; where the superstructure's mass
        is known, also the chosen layer's other variant: the flexible one of a rigid bilinear, pendulum or boucwen
        fit (and the rigid one of a flexible fit, among the others anyway).
    progress : callable, optional
        Called with a line saying what runs (see :func:`quickrelease.building.isolation_fit.fit_isolation`).
    global_search : bool
        The fit's global stage (:func:`quickrelease.building.isolation_fit.fit_isolation`; default True).
    exclude_spikes : bool, optional
        Leave out the samples the residuals show as spikes (``fit_isolation(exclude_spikes=True)``; default:
        the data's ``[building.record] spikes``, else False).
    constant_friction : bool, optional
        The friction pendulum's friction is a constant coefficient mu: every pendulum fit (the chosen model's,
        and the compared one's) holds Constantinou's rate at 0 and reports mu alone
        (:func:`quickrelease.io.building_case.constant_friction_fixed`, as building campaigns do); default: the
        data's (``[building] friction_coefficient`` with ``model = "pendulum"``), else False.

    Raises
    ------
    QuickReleaseError
        No release in the record, a record too short to hold one cycle, a model the fit does not support
        (the message names the source file).
    """
    notes: list[str] = []
    if data is not None:
        channels = data.channels if channels is None else channels
        mass = data.mass if mass is None else mass
        model = model or data.model
        start = dict(data.start or {}) if start is None else start
        release_time = data.release_time if release_time is None else release_time
        source = source or str(data.source)
        notes += list(data.notes or ())
        if superstructure_mass is None:
            superstructure_mass = getattr(data, "superstructure_mass", None)
        if exclude_spikes is None:
            exclude_spikes = bool(getattr(data, "exclude_spikes", False))
        if damping is None and getattr(data, "spec", None) is not None:
            damping = data.spec.damping
        if constant_friction is None:
            constant_friction = bool(getattr(data, "constant_friction", False))
        if flexible is None:
            flexible = bool(getattr(data, "flexible", False))
    flexible = bool(flexible) and model != "2dof"
    exclude_spikes = bool(exclude_spikes)
    damping = damping or "viscous"
    model = model or "linear"
    if model not in MODELS:
        raise ParameterError("model", model, ", ".join(MODELS))
    channels = list(channels or [])
    if mass is None:
        raise ParameterError("mass", None, "(0, inf), the mass carried by the isolators", "kg")
    prefix = f"{source}: " if source else ""
    held = constant_friction_fixed(start) if constant_friction else None  # the pendulum's fits only
    fit = _fit(channels, mass, model, start, release_time, prefix, superstructure_mass, progress, global_search,
               exclude_spikes, damping, held if model == "pendulum" else None, flexible)
    _check_long_enough(fit, prefix)
    if fit.excluded:  # the decay analysis, the loop and the other models see what the fit saw
        channels = drop_excluded(channels, fit.excluded)
    warnings = list(fit.warnings)
    warnings += _bilinear_yield_warning(fit)
    compared: list[IsolationFit] = []
    comparison: list[dict[str, Any]] = []
    if compare:
        compared.append(fit)
        if damping != "viscous":
            notes.append(f'every model compared with the same damper law: damping = "{damping}"')
        # the case's start values belong to its model, but for the push, the release and the dampers (a power-law
        # damper's C and alpha are the dampers' own, whatever the bearings): the others start from the decay analysis
        shared = ("d0", "release_time") + (("damping_coefficient", "damping_exponent") if damping == "power" else ())
        variants = [(other, False) for other in MODELS if other != model or flexible]
        if model in FLEXIBLE_MODELS and not flexible:  # the chosen layer under a flexible superstructure
            if superstructure_mass is None:
                notes.append(f"model {model} (flexible) not compared: no superstructure_mass in [building]")
            else:
                variants.append((model, True))
        for other, flex in variants:
            label = f"{other} (flexible)" if flex else other
            if other == "2dof" and superstructure_mass is None:
                notes.append("model 2dof not compared: no superstructure_mass in [building]")
                continue
            try:  # their intervals are not reported (AIC/BIC only), so no profile-likelihood re-fits
                compared.append(fit_isolation(channels, mass, other, release_time=release_time, profile=False,
                                              tolerance=COMPARE_TOLERANCE, progress=progress,
                                              exclude_spikes=exclude_spikes, damping=damping,
                                              superstructure_mass=superstructure_mass if other == "2dof" or flex
                                              else None, flexible=flex,
                                              start={k: v for k, v in (start or {}).items() if k in shared} or None,
                                              fixed=held if other == "pendulum" else None))
            except QuickReleaseError as exc:  # (a model the record cannot carry: named, the others ranked)
                notes.append(f"model {label} not compared: {exc}")
        comparison = compare_models(compared)
        if len(comparison) > 1:
            best, second = comparison[0], comparison[1]
            gap = second["delta_bic"]
            strength = "strongly" if gap > 10 else "weakly" if gap > 2 else "not clearly"
            notes.append(f"the record {strength} supports the {best['model']} model (BIC lower by "
                         f"{second['delta_bic']:.3g} than {second['model']})")
            if not all(f.absolute_sigma for f in compared):
                notes.append("noise levels taken from the residuals (no quiet pre-release segment on every channel):"
                             " AIC and BIC then count parameters only and do not compare the models' misfits")
    xch = next((c for c in channels if c.kind == "x"), None)
    decay = None
    check: dict[str, Any] = {}
    if xch is None:
        notes.append("no displacement channel of the isolation layer: no model-free decay analysis (the double "
                     "integral of an acceleration drifts); the fit alone describes the decay")
    else:
        try:
            decay = analyse_decay(xch.t, xch.values - fit.zero(xch), release_time=fit.release_time,
                                  noise=fit.noise[xch.name])
            check = decay_check(fit)
        except QuickReleaseError as exc:
            notes.append(f"decay analysis of {xch.name} not possible: {exc}")
        notes += [n for n in check.get("notes", []) if n not in notes]
        warnings += [w for w in check.get("warnings", []) if w not in warnings]
    loop = _loop(fit, channels, notes)
    effective = effective_cycles(fit)
    curve, judgement = _effective_curve(fit, effective)
    measured = _measured(fit, notes)
    return BuildingResult(fit=fit, compared=tuple(compared), comparison=tuple(comparison), decay=decay,
                          decay_check=check, loop=loop, warnings=tuple(warnings), notes=tuple(notes),
                          effective=effective, effective_curve=curve, effective_judgement=judgement,
                          measured=measured, source=source, curves=model_curves(fit),
                          model_decay=None if decay is None else model_decay(fit),
                          decay_envelope={} if decay is None else decay_envelope(decay))


def _measured(fit: IsolationFit, notes: list[str]):
    """The record's own cycles (:func:`quickrelease.studies.building_cycles.measured_cycles`), None where it has
    none; a reason it could not be read goes to ``notes``."""
    from .building_cycles import measured_cycles

    try:
        out = measured_cycles(fit)
    except QuickReleaseError as exc:
        notes.append(f"measured cycles not read: {exc}")
        return None
    return out if out is not None and out.cycles else None


def _effective_curve(fit: IsolationFit, cycles) -> tuple[EffectiveCurve | None, CycleJudgement | None]:
    """The identified model's curves against amplitude with 95% bands and the cycles judged against them (None,
    None for 2dof or a flexible fit, or a motion too short for two cycles after the release's)."""
    if getattr(fit, "flexible", fit.model == "2dof"):
        return None, None
    curve = effective_curves(fit)
    if curve.amplitude_m.size == 0:
        return curve, None
    return curve, judge_cycles(cycles, curve, release_time=fit.release_time)


def model_curves(fit: IsolationFit) -> dict[str, dict[str, np.ndarray]]:
    """The fitted model of each channel for the figures: ``t`` [s], :data:`_CURVE_POINTS` samples over the
    channel's span, ``model`` there, and ``residual`` (measured - model) at the channel's own samples."""
    curves = {}
    for ch in fit.channels:
        t_fine = np.linspace(float(ch.t[0]), float(ch.t[-1]), _CURVE_POINTS)
        curves[ch.name] = {"t": t_fine, "model": fit.model_values(ch, t_fine),
                           "residual": ch.values - fit.model_values(ch)}
    return curves


def model_decay(fit: IsolationFit) -> DecayAnalysis | None:
    """The model-free decay analysis of the fitted model's own displacement (noise-free, from the release)."""
    xch = next((c for c in fit.channels if c.kind == "x"), None)
    if xch is None:
        return None
    t = np.linspace(fit.release_time, float(xch.t[-1]), 8000)
    x = fit.model_values(xch, t) - fit.zero(xch, t)
    try:
        return analyse_decay(t, x, noise=1e-9 * max(abs(float(x[0])), 1e-12))
    except ValueError:
        return None


def decay_envelope(decay: DecayAnalysis) -> dict[str, np.ndarray]:
    """Numbers behind the decay figure: half-cycle amplitudes H_n of the record (n = 0, 1, ...) and the laws.

    Half-swing amplitudes obey ``H_{n+1} = r H_n - (1 + r) delta`` under the combined law (decay.py (*)), so
    ``H_n = (H_0 + c) r^n - c``, ``c = (1 + r) delta / (1 - r)``, with r and delta from the combined law
    fitted to the peaks and ``H_0 + c`` by least squares; the pure laws are least-squares fits of the
    amplitudes themselves: Coulomb ``H_n = H_0 - 2 delta n`` (a straight line), viscous ``H_n = H_0 r^n``
    (a straight line in log H).
    """
    a = decay
    H = np.asarray(a.amplitude, dtype=float)
    n = np.arange(H.size, dtype=float)
    out: dict[str, np.ndarray] = {"n": n, "amplitude": H}
    if H.size >= 2:
        out["coulomb"] = np.polyval(np.polyfit(n, H, 1), n)
        pos = H > 0
        if np.count_nonzero(pos) >= 2:
            out["viscous"] = np.exp(np.polyval(np.polyfit(n[pos], np.log(H[pos]), 1), n))
    law = a.law
    if law is not None and math.isfinite(law.ratio):
        r, delta = law.ratio, law.friction_displacement
        if abs(1.0 - r) > 1e-12:
            c = (1.0 + r) * delta / (1.0 - r)
            basis = r**n
            amp = float(np.sum((H + c) * basis) / np.sum(basis * basis))
            out["combined"] = amp * basis - c
        else:
            out["combined"] = float(np.mean(H + 2.0 * delta * n)) - 2.0 * delta * n
    return out


def _fit(channels, mass, model, start, release_time, prefix, superstructure_mass=None, progress=None,
         global_search=True, exclude_spikes=False, damping="viscous", fixed=None, flexible=False) -> IsolationFit:
    try:
        return fit_isolation(channels, mass, model, release_time=release_time, start=start or None, fixed=fixed,
                             superstructure_mass=superstructure_mass if model == "2dof" or flexible else None,
                             progress=progress, global_search=global_search, exclude_spikes=exclude_spikes,
                             damping=damping, flexible=flexible)
    except ParameterError:
        raise
    except QuickReleaseError as exc:  # e.g. no release found: name the record
        raise QuickReleaseError(f"{prefix}{exc}") from None


def _check_long_enough(fit: IsolationFit, prefix: str) -> None:
    """A record must hold one cycle after the release (or the motion up to its stick, if sooner)."""
    span = max(float(c.t[-1]) for c in fit.channels) - fit.release_time
    iso = fit.isolation()
    period = float(getattr(iso, "period", math.nan))
    if not math.isfinite(period):
        return
    try:
        from ..building.model import free_vibration

        stop = free_vibration(iso, fit.parameters.get("d0", 1.0), t_end=2.0 * period).stop_time
    except (QuickReleaseError, TypeError, AttributeError):  # a model without the rigid closed form
        stop = math.inf
    if not span >= 0.999 * min(period, stop):
        raise QuickReleaseError(f"{prefix}the record holds {span:.4g} s after the release (at {fit.release_time:.4g} s)"
                                f": too short for one cycle of the isolation (period {period:.4g} s); record at least "
                                "one full cycle")


def _bilinear_yield_warning(fit: IsolationFit) -> list[str]:
    """A bilinear fit whose spring never yields after the release: k2 and F_y are not identified."""
    if fit.model != "bilinear":
        return []
    from ..building.model import free_vibration

    span = max(float(c.t[-1]) for c in fit.channels) - fit.release_time
    iso = fit.isolation()
    try:
        fv = free_vibration(iso, fit.parameters["d0"], t_end=max(span, 1e-9))
    except QuickReleaseError:
        return []
    if any(p.yielding and p.t0 < span for p in fv.pieces):
        return []
    return [f"yield_force: the fitted bilinear spring never yields after the release (F_y = {iso.yield_force:.4g} N, "
            f"k2 = {iso.k2:.4g} N/m): the record does not identify yield_force and stiffness_ratio (k2); "
            "use the linear model"]


def _loop(fit: IsolationFit, channels, notes: list[str]) -> dict[str, np.ndarray] | None:
    """The hysteresis loop -m a against x after the release, measured and model (None without x and a)."""
    xch = next((c for c in channels if c.kind == "x"), None)
    ach = next((c for c in channels if c.kind == "a"), None)
    if xch is None or ach is None:
        notes.append("no hysteresis loop: it needs a displacement and an acceleration channel of the isolation layer")
        return None
    t_r = fit.release_time
    t = xch.t[(xch.t >= max(t_r, ach.t[0])) & (xch.t <= ach.t[-1])]
    if t.size < 8:
        notes.append("no hysteresis loop: the displacement and acceleration channels do not overlap after the release")
        return None
    same = xch.t.size == ach.t.size and np.array_equal(xch.t, ach.t)
    acc = np.interp(t, ach.t, ach.values - fit.zero(ach))
    if not same:
        notes.append(f"hysteresis loop: {ach.name} interpolated linearly onto the times of {xch.name} (own time axes)")
    x = np.interp(t, xch.t, xch.values - fit.zero(xch))
    x, force = hysteresis_loop(x, acc, fit.mass)
    tm = np.linspace(t_r, float(t[-1]), _CURVE_POINTS)
    mx = fit.model_values(xch, tm) - fit.zero(xch, tm)
    ma = fit.model_values(ach, tm) - fit.zero(ach, tm)
    model_x, model_force = hysteresis_loop(mx, ma, fit.mass)
    return {"t": t, "x": x, "force": force, "model_x": model_x, "model_force": model_force}


def _model_channel(fit: IsolationFit, channel: BuildingChannel, n: int = _CURVE_POINTS):
    """The fitted model of one channel on a fine time grid over its record (for the figures)."""
    t = np.linspace(float(channel.t[0]), float(channel.t[-1]), n)
    return t, fit.model_values(channel, t)
