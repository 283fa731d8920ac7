"""The isolation system from the building's own free-vibration record: a weighted least-squares fit.

Given records of the isolation layer after the release (displacement x [m], velocity [m/s], acceleration
[m/s^2]; each channel on its own time axis), :func:`fit_isolation` estimates the parameters of a model of
:mod:`quickrelease.building` by minimising

    sum over channels and samples of ((model + offset - measured) / sigma_channel)^2

with scipy's bounded ``least_squares``. The model is the exact piecewise closed form of
:func:`quickrelease.building.free_vibration` started from the pushed state (d0, at rest) at the release
instant t_r; before t_r the layer rests at d0. Parameters:

- ``linear``: period T [s], viscous damping ratio zeta [-], slider friction F_s [N] (>= 0);
- ``bilinear``: initial period T1 = 2 pi sqrt(m / k1) [s], stiffness ratio k2 / k1 [-] in (0, 1), yield
  force F_y [N], zeta [-] (referred to k1), F_s [N];

and for both the release displacement d0 [m], the release instant t_r [s] and a constant offset per
channel that has one (the sensor's zero). The mass m [kg] is given (the record fixes the parameters per
unit mass only).

Uncertainty: the covariance ``(J^T J)^-1`` of the weighted residuals, scaled by the reduced chi-square
unless the noise levels are known (given, or estimated from the quiet pre-release segment; a channel with
neither is weighted by its own residual scatter, refitted), gives standard errors, 95% intervals (Student
t) and correlations. J is by central differences guarded against the model's jumps (the acceleration jumps
at each reversal; where one passes a sample inside the stencil the smaller one-sided difference is kept), each
parameter stepped by 1e-4 of its value (1e-4 absolute at least for those of order 1 and more: periods, the
release instant; :data:`SMALL_PARAMETERS`).
Where a parameter sits at its bound (friction 0) or its relative standard error is large, the Jacobian's
interval is replaced by a profile-likelihood interval
(the parameter fixed on a grid, the others re-fitted, the interval where the chi-square rises by the
Student-t quantile squared times the residual variance). Models are compared by AIC and BIC on the same
noise levels, and the residuals are tested for whiteness (Ljung-Box).

:func:`predicted_isolation_errors` gives the standard errors such a fit would have before there is a record
(the Cramer-Rao bound ``(J^T W J)^-1`` at the truth, the same model and Jacobian, W = 1 / noise^2).
"""

from __future__ import annotations

import copy
import hashlib
import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from scipy import stats
from scipy.optimize import brentq

from .._lsq import bounded_least_squares, identified_covariance, jacobian_covariance
from ..errors import ParameterError, QuickReleaseError
from .flexible import FlexibleBuilding
from .hysteretic import EXPONENT_RANGE, GRAVITY, SHAPE_RANGE, BoucWen, HystereticVibration, Pendulum
from .isolation_search import (
    COMPETING_DELTA_CHI2,
    SAME_BASIN_SE,
    SEARCH_EVALUATIONS,
    SEARCH_RUNS,
    SearchCertificate,
    certificate,
    global_candidates,
    noise_scatter,
    record_period,
    same_basin,
    search_box,
    thin_channels,
)
from .model import RECORD_CHANNELS, Isolation, TwoDOF, _damping_ratio, free_vibration

__all__ = ["BuildingChannel", "IsolationFit", "fit_isolation", "compare_models", "decay_check", "ljung_box",
           "CHANNEL_KINDS", "IsolationPrecision", "predicted_isolation_errors", "FitMemo"]

#: Channel kinds of the isolation layer (x, v, a) and of the roof (x_roof, v_roof, a_roof; for the rigid
#: models the roof moves with the layer), and their SI units (from :data:`quickrelease.building.RECORD_CHANNELS`).
CHANNEL_KINDS = {name: unit for name, (_, unit, _) in RECORD_CHANNELS.items()}
_UNITS = {"period": "s", "damping_ratio": "-", "friction": "N", "stiffness_ratio": "-", "yield_force": "N",
          "superstructure_period": "s", "superstructure_damping_ratio": "-", "d0": "m", "release_time": "s",
          "friction_slow": "-", "friction_fast": "-", "rate": "s/m", "characteristic_strength": "N",
          "yield_displacement": "m", "shape": "-", "damping_coefficient": "N (s/m)^alpha", "damping_exponent": "-"}
#: The decrement laws whose fits give the start values (the linear model's; the other laws of
#: :mod:`quickrelease.building.decay` cost 0.3 s more on a 60 s record and give no start).
START_LAWS = ("viscous", "coulomb", "combined")
#: Models :func:`fit_isolation` fits.
FIT_MODELS = ("linear", "bilinear", "2dof", "pendulum", "boucwen")
#: Models :func:`fit_isolation` fits under a flexible superstructure (``flexible=True``; the linear layer's is
#: ``2dof``).
FLEXIBLE_MODELS = ("bilinear", "pendulum", "boucwen")
#: The damper's laws: ``viscous`` (c x_dot, its damping ratio fitted) and ``power`` (C |x_dot|^alpha sign(x_dot),
#: a fluid viscous damper's: damping_coefficient C and damping_exponent alpha fitted).
DAMPING_LAWS = ("viscous", "power")
#: Relative standard error above which the profile-likelihood interval replaces the Jacobian's.
PROFILE_RELATIVE_SE = 0.3
#: The covariance leaves out a sample whose leverage (the hat matrix's diagonal) exceeds LEVERAGE_LIMIT: a model's
#: cusp parked on it, not information (:func:`_covariance_without_cusps`); CUSP_ROUNDS rounds at most.
LEVERAGE_LIMIT, CUSP_ROUNDS = 0.5, 3
#: Condition number of the correlation matrix above which the fit is reported as ill-conditioned.
CONDITION_WARNING = 1e8
#: Lower bound of the fitted fixed-base superstructure period [s] (a stiffer storey is the rigid model).
SUPERSTRUCTURE_PERIOD_MIN = 0.02
#: Spikes (``fit_isolation(exclude_spikes=True)``): a sample whose residual, less the median of its six neighbours,
#: exceeds ``max(SPIKE_LEVEL, sqrt(2 ln n) + 1.5)`` robust scatters (1.4826 MAD of those, n its channel's
#: samples) is excluded; ``SPIKE_ROUNDS`` fits at most. Gaussian noise crosses 5.8 scatters (n = 12000) with
#: probability 7e-9 a sample: a clean record loses none.
SPIKE_LEVEL = 5.0
SPIKE_ROUNDS = 3


@dataclass(frozen=True, eq=False)
class BuildingChannel:
    """One measured channel of the isolation layer: ``kind`` x, v or a; its own time axis (SI)."""

    name: str
    kind: str
    t: np.ndarray
    values: np.ndarray
    noise: float | None = None
    """Noise standard deviation [SI]; None: estimated from the pre-release segment (or the residuals)."""
    offset: bool = True
    """Estimate a constant offset (the sensor's zero)."""
    drift: bool = False
    """Estimate a linear drift of the sensor's zero, ``drift_<name>`` [SI unit / s] (a displacement
    transducer whose zero creeps through a long record): the channel reads ``model + offset + drift (t -
    t_0)``, t_0 the release first detected (the fit's ``drift_origin``), so the offset is the zero at it."""

    def __post_init__(self) -> None:
        if self.kind not in CHANNEL_KINDS:
            raise ParameterError(f"{self.name}.kind", self.kind, ", ".join(CHANNEL_KINDS))
        t = np.asarray(self.t, dtype=float)
        y = np.asarray(self.values, dtype=float)
        if t.ndim != 1 or t.shape != y.shape or t.size < 10:
            raise ParameterError(f"{self.name}", f"{y.size} sample(s)", "at least 10 samples on its own time axis")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
            raise ParameterError(f"{self.name}", "non-finite samples", "finite values (drop missing samples first)")
        if np.any(np.diff(t) <= 0):
            raise ParameterError(f"{self.name}.t", "not increasing", "strictly increasing times", "s")
        if self.noise is not None and not (math.isfinite(self.noise) and self.noise > 0):
            raise ParameterError(f"{self.name}.noise", self.noise, "(0, inf)", CHANNEL_KINDS[self.kind])
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "values", y)


@dataclass(frozen=True, eq=False)
class IsolationFit:
    """Estimates, uncertainty and diagnostics of a fit of the isolation system to a record (SI)."""

    model: str
    mass: float
    names: tuple[str, ...]
    estimates: dict[str, float]
    std_errors: dict[str, float]
    ci95: dict[str, tuple[float, float]]
    interval_method: dict[str, str]
    """``"jacobian"``, ``"profile"`` or ``"not identified"`` per parameter (the last: standard error inf and
    interval (nan, nan), the record does not see the parameter)."""
    correlation: np.ndarray
    condition_number: float
    noise: dict[str, float]
    noise_source: dict[str, str]
    residual_rms: dict[str, float]
    samples: dict[str, int]
    chi2: float
    dof: int
    chi2_reduced: float
    absolute_sigma: bool
    aic: float
    bic: float
    whiteness_p: dict[str, float]
    """Ljung-Box p-value of each channel's residuals (small: the residuals are not white)."""
    converged: bool
    nfev: int
    warnings: tuple[str, ...] = ()
    channels: tuple[BuildingChannel, ...] = field(default=(), repr=False)
    superstructure_mass: float | None = None
    """The superstructure (roof) mass m_s [kg] given to the 2-DOF fit or a flexible fit (``flexible=True``); None
    for the rigid models."""
    fixed: dict[str, float] = field(default_factory=dict)
    """Parameters held fixed in the fit (not in ``estimates``), by name."""
    drift_origin: float = math.nan
    """t_0 of the drifts [s, record time]: a channel's zero is ``offset + drift (t - t_0)``."""
    excluded: dict[str, tuple[float, ...]] = field(default_factory=dict)
    """Samples excluded as spikes (``exclude_spikes=True``): their times per channel [s, record time]."""
    damping: str = "viscous"
    """The damper's law: ``viscous`` (damping_ratio) or ``power`` (damping_coefficient, damping_exponent)."""
    search: SearchCertificate | None = field(default=None, repr=False)
    """The multi-start's certificate (:class:`quickrelease.building.isolation_search.SearchCertificate`): the starts,
    how many reached the best minimum, the distinct minima and the next-best's delta chi-square."""

    @property
    def global_minimum_confirmed(self) -> bool:
        """At least two independent starts reached the best minimum and no other lies within delta chi-square
        ``COMPETING_DELTA_CHI2`` of it (``converged`` says only that the optimiser stopped)."""
        return bool(self.search is not None and self.search.global_minimum_confirmed)

    @property
    def flexible(self) -> bool:
        """Whether the fitted building has a flexible superstructure: the 2-DOF model, or a layer fitted with
        ``flexible=True`` (its ``isolation()`` a :class:`~quickrelease.building.flexible.FlexibleBuilding`)."""
        return self.superstructure_mass is not None

    @property
    def label(self) -> str:
        """The model as tables name it: ``model``, with `` (flexible)`` for a layer under a flexible superstructure
        (``boucwen (flexible)``; ``2dof`` is the linear layer's)."""
        return f"{self.model} (flexible)" if self.flexible and self.model != "2dof" else self.model

    @property
    def parameters(self) -> dict[str, float]:
        """Every parameter of the fitted model: the estimates and those held fixed."""
        return {**self.fixed, **self.estimates}

    def isolation(self, parameters: dict[str, float] | None = None) -> Isolation | TwoDOF:
        """The fitted isolation layer (the :class:`~quickrelease.building.TwoDOF` building for ``2dof``, the
        :class:`~quickrelease.building.flexible.FlexibleBuilding` of a flexible fit); with
        ``parameters`` (a dict of fit parameters by name, e.g. a draw from the estimates' covariance), the
        same model at those values, the missing ones taken from the fit."""
        p = self.parameters if parameters is None else {**self.parameters, **parameters}
        return _isolation(self.model, self.mass, p, self.superstructure_mass)

    @property
    def release_time(self) -> float:
        return self.parameters["release_time"]

    def offsets(self) -> dict[str, float]:
        return {n.removeprefix("offset_"): v for n, v in self.parameters.items() if n.startswith("offset_")}

    def drifts(self) -> dict[str, float]:
        """The fitted drift of each channel's zero that has one [SI unit / s]."""
        return {n.removeprefix("drift_"): v for n, v in self.parameters.items() if n.startswith("drift_")}

    def zero(self, channel: BuildingChannel, t=None) -> np.ndarray | float:
        """The channel's fitted zero at times t (default: the channel's) [SI]: its offset, plus its drift
        times ``t - drift_origin`` where it has one (a float where it has none)."""
        t = channel.t if t is None else np.asarray(t, dtype=float)
        drift = self.drifts().get(channel.name)
        offset = self.offsets().get(channel.name, 0.0)
        return offset if drift is None else offset + drift * (t - self.drift_origin)

    def model_values(self, channel: BuildingChannel, t=None) -> np.ndarray:
        """The fitted model (with the channel's zero: offset and drift) at times t (default: the channel's) [SI]."""
        t = channel.t if t is None else np.asarray(t, dtype=float)
        out = _channel_model(self.isolation(), self.parameters["d0"], self.release_time, channel.kind, t,
                             float(np.max(t)))
        return out + self.zero(channel, t)

    def summary(self) -> dict[str, Any]:
        iso = self.isolation()
        corr = {f"{a}:{b}": float(self.correlation[i, j]) for i, a in enumerate(self.names)
                for j, b in enumerate(self.names) if j > i}
        return {"model": self.model, "flexible": self.flexible, "label": self.label, "damping": self.damping,
                "mass_kg": self.mass, "isolation": iso.summary(),
                **({"superstructure_mass_kg": self.superstructure_mass} if self.flexible else {}),
                "estimates": self.estimates, "fixed": self.fixed, "std_errors": self.std_errors,
                "ci95": {k: list(v) for k, v in self.ci95.items()}, "interval_method": self.interval_method,
                "units": {n: _unit(n, self.channels) for n in self.names},
                "correlation": corr, "condition_number": self.condition_number, "noise": self.noise,
                "noise_source": self.noise_source, "residual_rms": self.residual_rms, "samples": self.samples,
                "chi2": self.chi2, "dof": self.dof, "chi2_reduced": self.chi2_reduced,
                "absolute_sigma": self.absolute_sigma, "aic": self.aic, "bic": self.bic,
                "whiteness_p": self.whiteness_p, "converged": self.converged, "nfev": self.nfev,
                "global_minimum_confirmed": self.global_minimum_confirmed,
                "search": self.search.summary() if self.search is not None else None,
                **({"drift_origin_s": self.drift_origin} if self.drifts() else {}),
                **({"excluded_samples": {k: list(v) for k, v in self.excluded.items()}} if self.excluded else {}),
                "warnings": list(self.warnings)}

    def to_pandas(self):
        """The record, the fitted model and the residuals of every channel on the record's time axis, as a
        DataFrame indexed by ``t_s`` (:func:`quickrelease.io.frames.fit_columns`: ``x_record_m``, ...)."""
        from ..io.frames import fit_frame

        return fit_frame(self)

    def to_xarray(self):
        """The same as an ``xarray.Dataset`` on the time coordinate ``t`` [s], with units and long names
        (:func:`quickrelease.io.frames.fit_dataset`)."""
        from ..io.frames import fit_dataset

        return fit_dataset(self)


def _offset_kind(name: str, channels) -> str:
    for ch in channels:
        if name in (f"offset_{ch.name}", f"drift_{ch.name}"):
            return ch.kind
    return ""


def _unit(name: str, channels) -> str:
    """The SI unit of a fit parameter: the model's, an offset's (its channel's), a drift's (per second)."""
    if name in _UNITS:
        return _UNITS[name]
    unit = CHANNEL_KINDS.get(_offset_kind(name, channels), "")
    return {"m": "m/s", "m/s": "m/s^2", "m/s^2": "m/s^3"}.get(unit, unit) if name.startswith("drift_") else unit


def _isolation(model: str, mass: float, p: dict[str, float], superstructure_mass: float | None = None) \
        -> Isolation | TwoDOF | Pendulum | BoucWen | FlexibleBuilding:
    """The model at the fit's parameters ``p``; the damper is the power law where ``p`` holds a
    ``damping_exponent``, else viscous with ``damping_ratio`` referred to the stiffness of ``period``
    (``m (2 pi / T)^2``: k, k1, W / R, Kd). With a ``superstructure_mass`` (a flexible fit, ``flexible=True``),
    the layer under the superstructure of ``superstructure_period`` and ``superstructure_damping_ratio``: the
    closed-form :class:`~quickrelease.building.TwoDOF` for ``2dof`` (a
    :class:`~quickrelease.building.flexible.FlexibleBuilding` on the linear layer with a power-law damper), a
    FlexibleBuilding on the layer for the others."""
    k = mass * (2.0 * math.pi / p["period"]) ** 2
    if "damping_exponent" in p:
        c, alpha = p["damping_coefficient"], p["damping_exponent"]
    else:
        c, alpha = 2.0 * _damping_ratio(p["damping_ratio"]) * math.sqrt(k * mass), 1.0
    if model == "2dof" and "damping_exponent" not in p:
        return TwoDOF(mass, superstructure_mass, p["period"], p["superstructure_period"], p["damping_ratio"],
                      p["friction"], p["superstructure_damping_ratio"])
    if model == "pendulum":
        layer = Pendulum(mass, GRAVITY * (p["period"] / (2.0 * math.pi)) ** 2, p["friction_slow"],
                         p["friction_fast"], p["rate"], c, alpha)
    elif model == "boucwen":
        layer = BoucWen(mass, k, p["characteristic_strength"], p["yield_displacement"], p["shape"], c, alpha,
                        p["friction"])
    elif model in ("linear", "2dof"):
        layer = Isolation(mass, k, c, p["friction"], damping_exponent=alpha)
    else:
        layer = Isolation(mass, k, c, p["friction"], p["stiffness_ratio"] * k, p["yield_force"],
                          damping_exponent=alpha)
    if superstructure_mass is None:
        return layer
    return FlexibleBuilding(layer, superstructure_mass, p["superstructure_period"], p["superstructure_damping_ratio"])


def _channel_model(iso: Isolation | TwoDOF, d0: float, t_r: float, kind: str, t: np.ndarray, t_last: float) \
        -> np.ndarray:
    horizon = max(t_last - t_r, 1e-9)
    fv = free_vibration(iso, d0, t_end=horizon)
    return fv.channels(t - t_r)[kind]


def ljung_box(residuals, lags: int = 20) -> float:
    """p-value of the Ljung-Box test that the residuals are white (no autocorrelation up to ``lags``).

    ``Q = n (n + 2) sum_k rho_k^2 / (n - k)``, chi-square with ``lags`` degrees of freedom.
    """
    r = np.asarray(residuals, dtype=float)
    r = r - r.mean()
    n = r.size
    lags = int(min(lags, n // 4))
    if lags < 1:
        return math.nan
    # einsum, not BLAS dot: OpenBLAS threads a dot of more than ~10^4 samples, which on a busy machine
    # cost more than the fit's model evaluations
    denom = float(np.einsum("i,i->", r, r))
    if denom == 0.0:
        return 1.0
    rho = np.array([float(np.einsum("i,i->", r[:-k], r[k:])) / denom for k in range(1, lags + 1)])
    q = n * (n + 2) * float(np.sum(rho**2 / (n - np.arange(1, lags + 1))))
    return float(stats.chi2.sf(q, lags))


def _detect_release(channels: list[BuildingChannel]) -> float:
    """Where the record first leaves its initial rest: the first of four samples beyond eight scatters of
    the head of a channel (median, MAD), earliest over the channels [s]. The head is the first tenth of
    the channel, shrunk while it holds the release (a hit inside it, or none at all because the motion in
    it inflates the scatter: a long record after a short quiet segment)."""
    best = math.inf
    for ch in channels:
        n0 = max(10, ch.values.size // 10)
        if ch.values.size < n0 + 5:
            continue
        while True:
            head = ch.values[:n0]
            level = float(np.median(head))
            spread = 1.4826 * float(np.median(np.abs(head - level)))
            spread = max(spread, 1e-12 * max(1.0, float(np.max(np.abs(ch.values)))))
            away = np.abs(ch.values - level) > 8.0 * spread
            run = away[:-3] & away[1:-2] & away[2:-1] & away[3:]
            hits = np.nonzero(run)[0]
            if n0 > 10 and (hits.size == 0 or hits[0] + 1 < n0):
                n0 = max(10, int(hits[0]) if hits.size else n0 // 2)
                continue
            break
        if hits.size:
            best = min(best, float(ch.t[max(int(hits[0]) - 1, 0)]))
    if not math.isfinite(best):
        raise QuickReleaseError("no release found: no channel leaves its initial level (give release_time)")
    return best


def _quiet_noise(ch: BuildingChannel, t_r: float) -> float | None:
    """Standard deviation of a channel before the release (at least 20 samples, linear trend removed)."""
    quiet = ch.t < t_r - 2.0 * float(np.median(np.diff(ch.t)))
    if np.count_nonzero(quiet) < 20:
        return None
    y = ch.values[quiet]
    tt = ch.t[quiet]
    coef = np.polyfit(tt - tt[0], y, 1)
    s = float(np.std(y - np.polyval(coef, tt - tt[0]), ddof=2))
    return s if s > 0 else None


def _start(model: str, mass: float, channels: list[BuildingChannel], t_r: float, d0: float,
           noise: dict[str, float], superstructure_mass: float | None = None) -> dict[str, float]:
    """Start values from the model-free decay analysis of the displacement channel, else generic ones. A layer
    under a flexible superstructure (a ``superstructure_mass``, a model other than ``2dof``) starts as the rigid
    layer, with the 2dof model's superstructure start (:func:`_two_dof_start`, from the decay's period and the
    record's second mode): its superstructure_period and superstructure_damping_ratio."""
    from .decay import analyse_decay

    start = {"period": 2.0, "damping_ratio": 0.05, "friction": 0.0}
    xch = next((c for c in channels if c.kind == "x"), None)
    analysis = None
    if xch is not None:
        try:
            analysis = analyse_decay(xch.t, xch.values, release_time=t_r, noise=noise[xch.name], laws=START_LAWS)
            if math.isfinite(analysis.period) and analysis.period > 0:
                start["period"] = analysis.natural_period if math.isfinite(analysis.natural_period) \
                    else analysis.period
            if analysis.law is not None:
                if math.isfinite(analysis.law.damping_ratio):
                    start["damping_ratio"] = float(np.clip(analysis.law.damping_ratio, 0.005, 0.5))
                k = mass * (2.0 * math.pi / start["period"]) ** 2
                start["friction"] = max(analysis.law.friction_displacement * k, 0.0)
                if math.isfinite(analysis.law.rest):
                    start["rest"] = analysis.law.rest
        except QuickReleaseError:
            pass
    storey = {}
    if superstructure_mass is not None and model != "2dof":  # the linear layer's modes: T_s only, the layer's
        storey = {n: v for n, v in _two_dof_start(mass, superstructure_mass, channels, t_r, dict(start)).items()
                  if n.startswith("superstructure_")}  # period is its model's own (below)
    if model == "bilinear":
        start.update(_bilinear_start(mass, xch, t_r, noise, start, channels, analysis, superstructure_mass))
    if model == "boucwen":  # the bilinear start's loop: Kd = k2, Qd = f_p, dy = F_y / k1
        b = _bilinear_start(mass, xch, t_r, noise, start, channels, analysis, superstructure_mass)
        k1 = mass * (2.0 * math.pi / b["period"]) ** 2
        k2, fy = b["stiffness_ratio"] * k1, b["yield_force"]
        zeta = b.get("damping_ratio", start["damping_ratio"])
        qd, dy = _boucwen_of_bilinear(k1, k2, fy)
        start.update(period=2.0 * math.pi * math.sqrt(mass / k2), characteristic_strength=qd,
                     yield_displacement=dy, shape=2.0, friction=b["friction"],
                     damping_ratio=float(np.clip(zeta * math.sqrt(k1 / k2), 0.002, 0.5)))
    if model == "pendulum":  # the decay's Coulomb share as the friction coefficient, spread about it
        mu = start.pop("friction") / (mass * GRAVITY)
        start.update(friction_slow=0.8 * mu, friction_fast=1.2 * mu, rate=20.0,
                     damping_ratio=min(start["damping_ratio"], 0.02))
    if model == "2dof":
        start.update(_two_dof_start(mass, superstructure_mass, channels, t_r, start))
    start.update(storey)
    return start


def _two_dof_start(mass: float, ms: float, channels: list[BuildingChannel], t_r: float,
                   linear: dict[str, float]) -> dict[str, float]:
    """Start values of the 2-DOF model: the decay's period is the first mode's, w1 = 2 pi / T_1; the second
    mode's w2 is the spectral peak of a roof (else base) acceleration, velocity or displacement above
    1.5 w1 (Hann window). With r = m / m_b the modes satisfy ``w1^2 + w2^2 = r (w^2 + w_s^2)`` and
    ``w1^2 w2^2 = r w^2 w_s^2`` (w = 2 pi / T the isolation's, w_s = 2 pi / T_s the storey's fixed-base
    circular frequencies), so w^2 and w_s^2 are the roots of ``z^2 - (S / r) z + P / r = 0``."""
    out = {"superstructure_period": 0.25 * linear["period"], "superstructure_damping_ratio": 0.02}
    w1 = 2.0 * math.pi / linear["period"]
    w2 = _second_mode(channels, t_r, w1)
    if w2 is None:
        return out
    r = mass / (mass - ms)
    S, P = w1**2 + w2**2, w1**2 * w2**2
    disc = (S / r) ** 2 - 4.0 * P / r
    if disc <= 0.0:
        return out
    lo, hi = 0.5 * (S / r - math.sqrt(disc)), 0.5 * (S / r + math.sqrt(disc))
    if lo > 0.0:
        out["period"] = 2.0 * math.pi / math.sqrt(lo)
    out["superstructure_period"] = max(2.0 * math.pi / math.sqrt(hi), 2.0 * SUPERSTRUCTURE_PERIOD_MIN)
    return out


def _second_mode(channels, t_r: float, w1: float) -> float | None:
    """The circular frequency of the record's spectral peak above 1.5 ``w1`` [rad/s]: of a roof (else base)
    acceleration, velocity or displacement from the release ``t_r`` to its last sample more than 8 noise levels
    off its final level (Hann window); None where none shows one. (Over a whole 60 s record whose roof rang for
    its first 10 s the window's taper left the ringing under the noise, and the peak was the noise's.)"""
    order = ("a_roof", "v_roof", "x_roof", "a", "v")
    pick = sorted((c for c in channels if c.kind in order), key=lambda c: order.index(c.kind))
    for ch in pick:
        moving = ch.t >= t_r
        level = float(np.median(ch.values[-max(ch.values.size // 10, 5):]))
        off = np.nonzero(np.abs(ch.values - level) > 8.0 * noise_scatter(ch.values))[0]
        if off.size and np.count_nonzero(moving & (ch.t <= ch.t[off[-1]])) >= 64:
            moving &= ch.t <= ch.t[off[-1]]
        if np.count_nonzero(moving) < 64:
            continue
        y = ch.values[moving] - float(np.mean(ch.values[moving]))
        dt = float(np.median(np.diff(ch.t[moving])))
        n = 1 << int(math.ceil(math.log2(4 * y.size)))
        spec = np.abs(np.fft.rfft(y * np.hanning(y.size), n))
        w = 2.0 * math.pi * np.fft.rfftfreq(n, dt)
        band = w > 1.5 * w1
        if not np.any(band) or not np.any(spec[band] > 0):
            continue
        return float(w[band][int(np.argmax(spec[band]))])
    return None


def _layer_acceleration(channels, noise: dict[str, float], mass: float, superstructure_mass: float | None = None) \
        -> tuple[BuildingChannel | None, float]:
    """The acceleration whose product with the whole mass is the layer's force, ``F_iso = -m a``, for the
    hysteresis loops of the starts, and its noise level: the layer's accelerometer (a rigid superstructure's roof
    moves with it: else the roof's). Under a flexible superstructure (``superstructure_mass`` m_s) the layer holds
    both masses, ``F_iso = -(m_b a_b + m_s a_s)``: with a roof accelerometer beside the layer's, the mass-weighted
    mean ``(m_b a_b + m_s a_s) / m`` on the layer's time axis (the roof's interpolated; their zeros combine alike);
    else the layer's (the roof's ringing then biases the loop's start, which the global search corrects)."""
    ach = next((c for c in channels if c.kind == "a"), None)
    roof = next((c for c in channels if c.kind == "a_roof"), None)
    if ach is None:
        return (roof, noise[roof.name]) if roof is not None and superstructure_mass is None else (None, math.nan)
    if roof is None or superstructure_mass is None:
        return ach, noise[ach.name]
    share = float(superstructure_mass) / mass
    inside = (ach.t >= roof.t[0]) & (ach.t <= roof.t[-1])
    if np.count_nonzero(inside) < 10:
        return ach, noise[ach.name]
    t = ach.t[inside]
    values = (1.0 - share) * ach.values[inside] + share * np.interp(t, roof.t, roof.values)
    level = math.hypot((1.0 - share) * noise[ach.name], share * noise[roof.name])
    return BuildingChannel(ach.name, "a", t, values, ach.noise and level, ach.offset), level


def _bilinear_start(mass: float, xch: BuildingChannel | None, t_r: float, noise: dict[str, float],
                    linear: dict[str, float], channels: list[BuildingChannel] = (), analysis=None,
                    superstructure_mass: float | None = None) -> dict[str, float]:
    """Start values of the bilinear model from the record, without design values (``analysis``: the decay
    analysis of the displacement channel, made once by :func:`_start`).

    With an acceleration channel of the layer: the hysteresis loop (:func:`quickrelease.building.decay.bilinear_loop`:
    k2, Q and c from the loading branches, k1 and the sliders' share of Q from the elastic unloading after
    each reversal). Else from the decay (the secant period): the last half-cycles are elastic (period of
    k1), and the first ones, on the soft branch, have the equivalent stiffness ``k_eff = k2 + f_p / A``
    (A the half-cycle's amplitude, f_p = F_y (1 - k2 / k1) the plastic element's force), so two of them
    give k2 and f_p."""
    from .decay import bilinear_loop

    k_lin = mass * (2.0 * math.pi / linear["period"]) ** 2
    guess = {"period": linear["period"] / 2.0, "stiffness_ratio": 0.2, "yield_force": 0.5 * k_lin * 0.02,
             "friction": 0.5 * linear["friction"]}
    if xch is None or analysis is None:  # no displacement, or its decay analysis failed (in _start)
        return guess
    ach, _ = _layer_acceleration(channels, noise, mass, superstructure_mass)
    if ach is not None:
        moving = (ach.t > t_r) & (ach.t >= xch.t[0]) & (ach.t <= xch.t[-1])
        pre = ach.values[ach.t < t_r]
        zero = float(np.median(pre)) if pre.size >= 3 else 0.0
        loop = bilinear_loop(ach.t[moving], np.interp(ach.t[moving], xch.t, xch.values), ach.values[moving] - zero,
                             mass, analysis.peak_times, analysis.peaks, t_r)
        if loop is not None and 0.0 < loop.k2 < loop.k1 and loop.yield_force > 0.0:
            return {"period": 2.0 * math.pi * math.sqrt(mass / loop.k1), "stiffness_ratio": loop.k2 / loop.k1,
                    "yield_force": loop.yield_force, "friction": max(loop.friction, 0.0),
                    "damping_ratio": float(np.clip(loop.damping / (2.0 * math.sqrt(loop.k1 * mass)), 0.002, 0.5)),
                    "friction_se": loop.friction_se if math.isfinite(loop.friction_se)
                    else 0.05 * loop.characteristic_strength}
    teq, amp = analysis.equivalent_period, analysis.amplitude
    if teq.size < 4:
        return guess
    k_eff = mass * (2.0 * math.pi / teq) ** 2
    k1 = float(np.max(k_eff[-3:]))
    A = np.column_stack([np.ones(2), 1.0 / amp[:2]])
    k2, fp = (float(v) for v in np.linalg.lstsq(A, k_eff[:2], rcond=None)[0])
    if not (0.0 < k2 < k1 and fp > 0.0):
        k2, fp = 0.2 * k1, 0.5 * float(k_eff[0]) * float(amp[0])
    return {"period": 2.0 * math.pi * math.sqrt(mass / k1), "stiffness_ratio": k2 / k1,
            "yield_force": fp / (1.0 - k2 / k1), "friction": 0.5 * linear["friction"]}


def _first_peak(xch: BuildingChannel, t_r: float, period: float, d0: float) -> float | None:
    """|x| at the first turning point after the release (the extreme of the displacement channel, past
    the static level, within a quarter to three quarters of a period after t_r) [m], or None."""
    sel = (xch.t > t_r + 0.25 * period) & (xch.t < t_r + 0.75 * period)
    if np.count_nonzero(sel) < 3:
        return None
    level = float(np.median(xch.values[xch.t < t_r])) - d0 if np.count_nonzero(xch.t < t_r) >= 3 else 0.0
    return float(np.max(-math.copysign(1.0, d0) * (xch.values[sel] - level)))


#: The physical parameters' bounds in the fit [SI]: a profile interval that reaches one is cut there (its
#: side is the bound's, not the likelihood's: e.g. friction at 0 gives [0, upper]).
PARAMETER_BOUNDS = {"period": (1e-3, 1e3), "damping_ratio": (0.0, 0.95), "friction": (0.0, math.inf),
                    "stiffness_ratio": (1e-4, 0.9999), "yield_force": (0.0, math.inf),
                    "superstructure_period": (SUPERSTRUCTURE_PERIOD_MIN, 1e3),
                    "superstructure_damping_ratio": (0.0, 0.95), "friction_slow": (0.0, 1.0),
                    "friction_fast": (0.0, 1.0), "rate": (0.0, 1e3), "characteristic_strength": (0.0, math.inf),
                    "yield_displacement": (1e-6, 10.0), "shape": SHAPE_RANGE, "damping_coefficient": (0.0, math.inf),
                    "damping_exponent": EXPONENT_RANGE}


#: Each fitted parameter's key in the building's JSON (the fitted values of
#: :func:`quickrelease.studies.building_analysis.physical_estimates` and the predicted precision of
#: :meth:`IsolationPrecision.physical`), in the order the rows are given.
JSON_KEYS = {"period": "period_s", "yield_force": "Fy_N", "friction_slow": "friction_slow",
             "friction_fast": "friction_fast", "rate": "rate_s_m", "characteristic_strength": "Qd_N",
             "yield_displacement": "dy_m", "shape": "shape", "damping_ratio": "damping_ratio",
             "damping_coefficient": "damping_coefficient", "damping_exponent": "damping_exponent",
             "friction": "friction_N", "superstructure_period": "superstructure_period_s",
             "superstructure_damping_ratio": "superstructure_damping_ratio", "d0": "d0_m",
             "release_time": "release_time_s"}


def _physical_names(model: str, damping: str = "viscous", flexible: bool = False) -> list[str]:
    """The physical parameters of a model with its damper's law (in the fit's order); ``flexible``: the layer's,
    then the superstructure's (``superstructure_period``, ``superstructure_damping_ratio``, as the 2dof model's)."""
    damper = ["damping_ratio"] if damping == "viscous" else ["damping_coefficient", "damping_exponent"]
    friction = ["friction_slow", "friction_fast", "rate"] if model == "pendulum" else ["friction"]
    storey = ["superstructure_period", "superstructure_damping_ratio"]
    return ["period"] + damper + friction + {
        "bilinear": ["stiffness_ratio", "yield_force"],
        "boucwen": ["characteristic_strength", "yield_displacement", "shape"],
        "2dof": storey}.get(model, []) + (storey if flexible and model != "2dof" else [])


def _parameter_names(model: str, channels, damping: str = "viscous", flexible: bool = False) -> list[str]:
    """Every parameter of a fit of ``model`` to ``channels``: the physical ones, d0, the release time, an
    offset per channel that has one and a drift per channel that has one."""
    return (_physical_names(model, damping, flexible) + ["d0", "release_time"]
            + [f"offset_{c.name}" for c in channels if c.offset] + [f"drift_{c.name}" for c in channels if c.drift])


def _bounds(channels, t_r0: float, period: float = 0.0) -> tuple[dict[str, float], dict[str, float]]:
    """The fit's bounds (lower, upper) of each parameter; the release time from a quarter of the (start)
    ``period`` (at least 50 samples) before ``t_r0`` to 50 samples after it.

    The detected release lags the true one by a time, not by a count of samples: a displacement leaves
    its rest quadratically, beyond 8 noise levels only tens of ms later however fine the sampling (0.2 mm
    on 0.15 m: 49 ms, 157 samples at 3200 Hz, where a bound of 50 samples kept the fit from the release
    and in a wrong basin). The layer reaches its static level a quarter of a period after the release,
    so a departure is seen by then: the search reaches back that far."""
    dt = min(float(np.median(np.diff(c.t))) for c in channels)
    lag = max(50 * dt, 0.25 * period)
    lower = {**{n: b[0] for n, b in PARAMETER_BOUNDS.items()}, "d0": -math.inf, "release_time": t_r0 - lag}
    upper = {**{n: b[1] for n, b in PARAMETER_BOUNDS.items()}, "d0": math.inf, "release_time": t_r0 + 50 * dt}
    return lower, upper


def _unpack(theta, free, base) -> dict[str, float]:
    p = dict(base)
    p.update(zip(free, (float(v) for v in theta), strict=True))
    return p


#: Parameters whose values lie well below 1 in SI (coefficients, ratios, displacements): the Jacobian's step is
#: 1e-4 of the value (at least 1e-7), not 1e-4 absolute. A friction coefficient of 0.005 was stepped by 2 % of
#: itself, 115 of its standard errors, and the guarded difference gave its gradient the wrong sign: the fit of a
#: constant-friction pendulum's record stopped 10.5 above the minimum, the friction 29 standard errors low
#: (h28a's finding; one Gauss-Newton step with the relative step reaches the minimum). The starts' solves on the
#: thinned record keep the absolute step (``coarse_steps``): its wide stencil smooths the cliffs where the count
#: of half-cycles before the stick changes, which they must cross to reach the basin (with the relative step all
#: four starts of that record ended one micro-swing later, 300 above the minimum, and the certificate confirmed it).
#: The integrator's steps on the thinned record's misfit (the starts' solves and the global search), this many times
#: the default's (where the layer has no closed form): 2 takes 25 % off a Bouc-Wen evaluation (3.7 -> 2.9 ms on the
#: benchmark's 60 s record) and moves the state by 2e-12 m (the pendulum's 1e-12 m), far below any record's noise.
THIN_COARSE = 2.0
#: The Jacobian's step of the release time, relative to its distance from the record's first sample (at least 1 s),
#: and how many such steps each motion runs past the record's last sample (for the one-sided stencil's 2 steps).
RELEASE_STEP, RELEASE_REACH = 1e-4, 3.0
#: A solve whose release time ends within this fraction of the Jacobian's release step of a sample instant was
#: stopped against the step the misfit takes there (:meth:`_Misfit.release_edge`): solved again with the release
#: bounded at that instant.
RELEASE_EDGE = 1.0
SMALL_PARAMETERS = frozenset({"friction_slow", "friction_fast", "damping_ratio", "superstructure_damping_ratio",
                              "stiffness_ratio", "damping_exponent", "yield_displacement", "d0"})


class _Misfit:
    """The weighted residuals ``(model + offset - measured) / sigma`` of the channels, stacked, and their
    Jacobian: what :func:`fit_isolation` minimises and :func:`predicted_isolation_errors` evaluates at the
    truth."""

    def __init__(self, channels, noise: dict[str, float], mass: float, model: str,
                 superstructure_mass: float | None, lower: dict[str, float], upper: dict[str, float],
                 drift_origin: float = 0.0, coarse_steps: bool = False) -> None:
        self.channels, self.mass, self.model, self.superstructure_mass = channels, mass, model, superstructure_mass
        self.coarse_steps = coarse_steps  # the Jacobian's steps 1e-4 absolute below 1 (see SMALL_PARAMETERS)
        self.lower, self.upper = lower, upper
        self.t_last = max(float(c.t[-1]) for c in channels)
        self.t_first = min(float(c.t[0]) for c in channels)
        self.dt = min(float(np.median(np.diff(c.t))) for c in channels)  # the finest sampling interval [s]
        self.sig = np.concatenate([np.full(c.t.size, noise[c.name]) for c in channels])
        self.data = np.concatenate([c.values for c in channels])
        # the model is evaluated once at the union of the channels' times (channels often share an axis)
        t_all, where = np.unique(np.concatenate([c.t for c in channels]), return_inverse=True)
        self.t_all = t_all
        self.where = np.split(where.ravel(), np.cumsum([c.t.size for c in channels])[:-1])
        # each channel's samples of the union (None where the channel's times are the union's: no gather) and its
        # rows of the stacked vector
        self._take = [None if at.size == t_all.size and np.array_equal(at, np.arange(t_all.size)) else at
                      for at in self.where]
        self._rows = [slice(int(i), int(i) + c.t.size)
                      for c, i in zip(channels, np.cumsum([0] + [c.t.size for c in channels])[:-1], strict=True)]
        # the offsets enter linearly: their columns are exact (1 / sigma on their channel's rows), and only the
        # other parameters need the two model evaluations each of the central differences
        self.rows_of, i0 = {}, 0
        self.drift_origin = float(drift_origin)
        self.ramp = {}  # a drifting channel's t - t_0 [s]: its drift's column times sigma
        for c in channels:
            self.rows_of[f"offset_{c.name}"] = slice(i0, i0 + c.t.size)
            if c.drift:
                self.rows_of[f"drift_{c.name}"] = self.rows_of[f"offset_{c.name}"]
                self.ramp[f"drift_{c.name}"] = c.t - self.drift_origin
            i0 += c.t.size
        self._samples = None  # the digest of the channels' samples (fingerprint)

    def fingerprint(self) -> bytes:
        """A digest of everything the residuals depend on besides the parameters: the model, the mass, the
        bounds, the steps, the channels' samples and the weights (which the residuals' reweighting changes)."""
        if self._samples is None:
            h = hashlib.blake2b(digest_size=16)
            for c in self.channels:
                h.update(repr((c.name, c.kind, c.drift, c.t.size)).encode())
                h.update(np.ascontiguousarray(c.t, dtype=float).tobytes())
                h.update(np.ascontiguousarray(c.values, dtype=float).tobytes())
            self._samples = h.digest()
        h = hashlib.blake2b(self._samples, digest_size=16)
        h.update(repr((self.model, self.mass, self.superstructure_mass, self.coarse_steps, self.drift_origin,
                       sorted(self.lower.items()), sorted(self.upper.items()))).encode())
        h.update(np.ascontiguousarray(self.sig, dtype=float).tobytes())
        return h.digest()

    def motion(self, p: dict[str, float]):
        """The model's free vibration at ``p``, to the record's last sample and RELEASE_REACH past it: the Jacobian's
        release-time column evaluates this same motion at shifted times (its steps do not depend on the horizon:
        the record's samples come out the same to the last bit)."""
        iso = _isolation(self.model, self.mass, p, self.superstructure_mass)
        reach = RELEASE_REACH * RELEASE_STEP * max(1.0, abs(p["release_time"] - self.t_first))
        return free_vibration(iso, p["d0"], t_end=max(self.t_last - p["release_time"], 1e-9) + reach,
                              coarse=THIN_COARSE if self.coarse_steps else 1.0)

    def release_edge(self, x, free, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """The bounds ``(lo, hi)`` of a solve that ended at ``x`` with the release time bounded at the sample
        instant t_k it was stopped against (within ``RELEASE_EDGE`` of the Jacobian's release step of it), on the
        side where it ended: above by ``t_k`` where ``t_r <= t_k`` (the sample after the release: the motion's
        value there), below by the next float after ``t_k`` where ``t_r > t_k`` (the sample at rest); None where
        the release is not free or not at a sample.

        Where the release crosses a sample, that sample switches between the rest before the release and the
        released motion: an acceleration jumps there (by the pushed force over the mass, thousands of chi-square on
        a record's noise), so the chi-square is a cliff in the release time at every sample instant. The
        Jacobian's guarded differences do not see the jump (by design: it would read as infinite information);
        where the minimum of the smooth side lies beyond the cliff (a release on a sample instant: 6 of 8
        Bouc-Wen records, rigid or flexible) the solver's steps cross it, each is refused, its trust region
        shrinks to nothing against it and it stops there, 1e-12 to 1e-7 s short of the sample, with the other
        parameters not yet at their optimum (a flexible Bouc-Wen record released at 0.5 s: 7.9 above the minimum
        with the release at the sample, from the truth and from the global search alike). The cliff is a bound:
        solved again against it, the release goes to the bound and the others are solved on
        (:func:`~quickrelease._lsq.bounded_least_squares` holds a parameter at a bound where its optimum lies
        beyond)."""
        if "release_time" not in free:
            return None
        i = list(free).index("release_time")
        t_r = float(x[i])
        k = int(np.searchsorted(self.t_all, t_r))
        near = [float(self.t_all[j]) for j in (k - 1, k) if 0 <= j < self.t_all.size]
        if not near:
            return None
        t_k = min(near, key=lambda v: abs(v - t_r))
        if abs(t_r - t_k) > RELEASE_EDGE * RELEASE_STEP * max(1.0, abs(t_r - self.t_first)):
            return None
        lo, hi = np.array(lo, dtype=float), np.array(hi, dtype=float)
        if t_r <= t_k:
            hi[i] = min(hi[i], t_k)
        else:
            lo[i] = max(lo[i], float(np.nextafter(t_k, math.inf)))
        return (lo, hi) if lo[i] <= t_r <= hi[i] else None

    def vector(self, fv, p: dict[str, float]) -> np.ndarray:
        """The channels of the motion ``fv`` released at ``p["release_time"]``, with their offsets and drifts."""
        # written into one array (each channel's samples plus its offset, then its drift: the arithmetic, and so
        # the bits, of adding them channel by channel and stacking)
        out = np.empty(self.data.size)
        t = self.t_all - p["release_time"]
        if type(fv) is HystereticVibration:  # the union's times shifted are sorted: its state's path for sorted
            x, v, a = fv._motion(t)  # times, without the check of their order
            kinds = {"x": x, "v": v, "a": a, "x_roof": x, "v_roof": v, "a_roof": a}  # as its channels()
        else:
            kinds = fv.channels(t)
        for c, at, rows in zip(self.channels, self._take, self._rows, strict=True):
            y = kinds[c.kind]
            o = out[rows]
            np.add(y if at is None else y[at], p.get(f"offset_{c.name}", 0.0), out=o)
            if c.drift:
                o += p.get(f"drift_{c.name}", 0.0) * self.ramp[f"drift_{c.name}"]
        return out

    def _residuals_of(self, fv, p: dict[str, float]) -> np.ndarray:
        """``(vector - data) / sigma``, in place on the fresh vector."""
        r = self.vector(fv, p)
        r -= self.data
        r /= self.sig
        return r

    def model_vector(self, p: dict[str, float]) -> np.ndarray:
        return self.vector(self.motion(p), p)

    def _evaluate(self, theta: np.ndarray, free, base):
        """The residuals at ``theta`` and the motion (None outside the model's domain), kept as the last point's:
        the least-squares solvers ask for the Jacobian where they have just evaluated the residuals (one model
        evaluation of the 2 n + 1 saved)."""
        p = _unpack(theta, free, base)
        try:
            fv = self.motion(p)
            r = self._residuals_of(fv, p)
        except ParameterError:  # outside the model's domain (e.g. held by friction at a bound): penalise
            fv, r = None, np.full(self.data.size, 1e6)
        self._last = (theta.copy(), tuple(free), dict(base), r, fv)
        return r, fv

    def residuals(self, theta, free, base) -> np.ndarray:
        return self._evaluate(np.asarray(theta, dtype=float), free, base)[0]

    def _evaluated_at(self, theta: np.ndarray, free, base):
        """The residuals and the motion at ``theta``: the last evaluation's where it was this point, else evaluated."""
        last = getattr(self, "_last", None)
        if last is not None and last[1] == tuple(free) and np.array_equal(last[0], theta) and last[2] == base:
            return last[3], last[4]
        return self._evaluate(theta, free, base)

    def step(self, name: str, value: float) -> float:
        """The Jacobian's difference step of parameter ``name`` at ``value``: 1e-4 of it (1e-4 absolute at least, or
        1e-7 for :data:`SMALL_PARAMETERS` off the coarse steps); the release time's from the record's first sample."""
        if name == "release_time":  # from the record's start, not its clock's origin: a logger's time of day
            # (36 000 s) stepped the release by 3.6 s, and the fit ended 453 above the unshifted record's
            return RELEASE_STEP * max(1.0, abs(value - self.t_first))
        small = name in SMALL_PARAMETERS and not self.coarse_steps
        return 1e-4 * (max(abs(value), 1e-3) if small else max(1.0, abs(value)))

    def scales(self, free, theta) -> tuple[np.ndarray, np.ndarray]:
        """Each free parameter's origin and typical magnitude for the solver's coordinates (see
        :func:`quickrelease._lsq.bounded_least_squares`'s ``scale``): its value's magnitude at ``theta``, at least a
        floor in its own units where the value may be 0 (forces and a damper's coefficient 1e-3 of the weight,
        ratios and shares 0.01, friction coefficients 1e-3, displacements 1 mm, the rate 1 s/m, an offset its
        channel's noise level, a drift that level over the record); the release time from the record's first
        sample (a logger's time of day would else outweigh every other parameter)."""
        origin, scale = np.zeros(len(free)), np.ones(len(free))
        weight = self.mass * GRAVITY
        floors = {"friction": 1e-3 * weight, "yield_force": 1e-3 * weight, "characteristic_strength": 1e-3 * weight,
                  "damping_coefficient": 1e-3 * weight, "damping_ratio": 0.01, "superstructure_damping_ratio": 0.01,
                  "stiffness_ratio": 0.01, "friction_slow": 1e-3, "friction_fast": 1e-3, "rate": 1.0,
                  "yield_displacement": 1e-3, "d0": 1e-3}
        span = max(self.t_last - self.t_first, self.dt)
        for i, n in enumerate(free):
            v = float(theta[i])
            if n == "release_time":
                origin[i] = self.t_first
                v -= self.t_first
                floor = self.dt
            elif n in self.rows_of:
                floor = float(self.sig[self.rows_of[n].start]) / (span if n.startswith("drift_") else 1.0)
            else:
                floor = floors.get(n, 1e-3)
            scale[i] = max(abs(v), floor)
        return origin, scale

    def jacobian(self, theta, free, base, order: str = "C") -> np.ndarray:
        # order: the array's layout; "F" for the solver (bounded_least_squares hands scipy its columns, which come
        # out in Fortran order: built so, each column is written and taken contiguously)
        # Central differences, guarded against the jumps of the record model: where a piece boundary (a
        # reversal, where the friction force flips and the acceleration jumps; the stick) passes a sample
        # inside the stencil, one one-sided difference holds the jump over h and the other does not. There
        # the smaller one is the derivative (the jump would make the sample look infinitely informative
        # and the standard errors far too small, as the optimiser likes to park a jump on a sample).
        theta = np.asarray(theta, dtype=float)
        J = np.zeros((self.data.size, len(free)), order=order)
        f0 = motion = None
        for i, n in enumerate(free):
            if n in self.rows_of:
                J[self.rows_of[n], i] = self.ramp.get(n, 1.0) / self.sig[self.rows_of[n]]
                continue
            if f0 is None:
                f0, motion = self._evaluated_at(theta, free, base)
            x, lo, hi = theta[i], self.lower.get(n, -math.inf), self.upper.get(n, math.inf)
            h = self.step(n, x)

            def at(value, i=i, n=n, motion=motion):
                moved = theta.copy()
                moved[i] = value
                if n == "release_time" and motion is not None:  # the same motion released earlier or later: no
                    # integration (the motion does not depend on the instant it starts)
                    p = _unpack(moved, free, base)
                    return self._residuals_of(motion, p)
                return self.residuals(moved, free, base)

            if x - h < lo or x + h > hi:  # one-sided, second order, into the feasible side
                s_ = 1.0 if x + 2.0 * h <= hi else -1.0
                f1, f2 = at(x + s_ * h), at(x + 2.0 * s_ * h)
                d1 = f1 - f0
                d1 /= s_ * h
                d2 = f2 - f1
                d2 /= s_ * h
                smooth = 1.5 * d1
                smooth -= 0.5 * d2
                J[:, i] = _guarded(d1, d2, smooth)
            else:
                dp = at(x + h) - f0
                dp /= h
                dm = f0 - at(x - h)
                dm /= h
                smooth = dp + dm
                smooth *= 0.5
                J[:, i] = _guarded(dp, dm, smooth)
        return J


def _guarded(d1: np.ndarray, d2: np.ndarray, smooth: np.ndarray) -> np.ndarray:
    """A Jacobian column from two difference quotients ``d1``, ``d2`` and their ``smooth`` combination: that, but
    the smaller quotient where they differ by more than half their mean magnitude (a jump inside the stencil);
    ``np.where(|d1 - d2| > (|d1| + |d2|) / 2, np.where(|d1| < |d2|, d1, d2), smooth)``, computed in place on
    ``smooth`` and on the few rows that jump."""
    a1, a2 = np.abs(d1), np.abs(d2)
    gap = d1 - d2
    np.abs(gap, out=gap)
    a1 += a2  # the sum of the magnitudes, in a1 until the jumping rows are found
    a1 *= 0.5
    jump = np.flatnonzero(gap > a1)
    if jump.size:
        smooth[jump] = np.where(np.abs(d1[jump]) < a2[jump], d1[jump], d2[jump])
    return smooth


#: The bytes of arrays a :class:`FitMemo` keeps at most (beyond, results are computed and not kept).
MEMO_BYTES = 256 * 2**20


def _held(base: dict[str, float], free) -> tuple:
    """The values a solve takes from its base: those of the parameters it does not fit, by name."""
    return tuple(sorted((n, float(v)) for n, v in base.items() if n not in free))


def _nbytes(value) -> int:
    if isinstance(value, np.ndarray):
        return value.nbytes
    if isinstance(value, dict):
        return sum(_nbytes(v) for v in value.values()) + 64 * len(value)
    if isinstance(value, (list, tuple)):
        return sum(_nbytes(v) for v in value) + 64
    return 64


class FitMemo:
    """What fits of a record computed on their way, kept for a later fit of the same record: the global
    stage's candidates and each step that refines a fit (every least-squares solve: the starts' on the thinned
    record, the minima's, the polish's and the profiles' on the whole record; the polish and the step search
    as a whole), each under a key of everything it depends on (the record's samples and weights, the model,
    the bounds and steps, the parameters held and their values, the start point, the tolerance, the seed).
    Given to :func:`fit_isolation` (``memo``), a refit from other start values (a campaign's restart from
    another release's estimates) solves only what its new start changes, and its result is the one without
    the memo (each kept result is what the same computation gives again: the fit is deterministic). Keeps
    results up to ``budget`` bytes of arrays; ``hits`` and ``misses`` count the look-ups."""

    def __init__(self, budget: int = MEMO_BYTES) -> None:
        self.budget = int(budget)
        self.size = 0
        self.hits = 0
        self.misses = 0
        self._kept: dict[tuple, Any] = {}

    def value(self, key: tuple, compute):
        """The kept result of ``key`` (a copy), or ``compute()``'s, kept while the budget allows."""
        if key in self._kept:
            self.hits += 1
            return copy.deepcopy(self._kept[key])
        self.misses += 1
        out = compute()
        size = _nbytes(out)
        if self.size + size <= self.budget:
            self._kept[key] = copy.deepcopy(out)
            self.size += size
        return out


def _refinement_key(name: str, misfit: _Misfit, names, values: dict[str, float], res, seed, tolerance) -> tuple:
    """The :class:`FitMemo` key of a refinement of the solve ``res`` (the polish, the step search): the record
    (its samples and weights: ``misfit.fingerprint()``), the parameters fitted and the values of those held, the
    point it starts from, with its cost and evaluations, the seed and the tolerance."""
    return (name, misfit.fingerprint(), tuple(names), _held(values, names), np.asarray(res.x, dtype=float).tobytes(),
            float(res.cost), int(res.nfev), seed, float(tolerance))


def _noise_levels(channels, t_r0: float) -> tuple[dict[str, float], dict[str, str], bool]:
    """The noise level [SI] of each channel and where it came from: given; else the scatter of the quiet
    segment before the release ``t_r0`` (:func:`_quiet_noise`); else the channel's spread, a first guess
    for the weights that the fit replaces by the residuals' scatter. Also whether every level is known
    (``absolute``: the covariance is not rescaled by the reduced chi-square)."""
    noise, source = {}, {}
    for ch in channels:
        if ch.noise is not None:
            noise[ch.name], source[ch.name] = ch.noise, "given"
        else:
            q = _quiet_noise(ch, t_r0)
            if q is not None:
                noise[ch.name], source[ch.name] = q, "pre-release segment"
    absolute = len(noise) == len(channels)
    for ch in channels:  # unknown: the spread of the channel, rescaled by the reduced chi-square below
        if ch.name not in noise:
            noise[ch.name], source[ch.name] = float(np.std(ch.values)) or 1.0, "residuals"
    return noise, source, absolute


#: A record whose swing grows past this factor of its first (plus 8 noise levels) is no free decay.
GROWTH_LIMIT = 1.25


def _check_decays(channels) -> None:
    """Refuse a record whose oscillation grows: after a push and release from rest the layer's energy only
    falls, so each swing of the displacement (and, for a rigid superstructure, of the velocity and the
    acceleration) about the final level is at most the first. The record of each layer channel is cut in
    eight equal windows; the largest deviation from the level in any later window must not exceed
    ``GROWTH_LIMIT`` times that of the first two windows (the push and the first swings) plus 8 noise levels
    (the noise from the samples' second differences, 1.4826 MAD / sqrt(6), which holds whatever the release: a
    record that never settles has no quiet segment); a velocity or acceleration from its first departure from
    its initial level. The level: the median of the last tenth (a record that ends at rest), or the middle of
    the second half's range (a record that ends mid-swing, whose last tenth lies near a turning point: a 5 s
    record of a 2 s building was refused, its "level" 2 cm off the swing's centre); the record is refused where
    it grows about both. Raises QuickReleaseError naming the channel and the two swings."""
    for ch in channels:
        if ch.kind not in ("x", "v", "a") or ch.values.size < 80:
            continue
        sigma = noise_scatter(ch.values)
        start = 0
        if ch.kind != "x":  # a velocity or an acceleration rests at 0 before the release: from its first motion
            pre = ch.values[: max(ch.values.size // 20, 3)]
            moved = np.nonzero(np.abs(ch.values - np.median(pre)) > 8.0 * sigma)[0]
            if moved.size == 0 or ch.values.size - moved[0] < 80:
                continue
            start = int(moved[0])
        half = ch.values[ch.values.size // 2:]
        swings = []
        for level in (float(np.median(ch.values[-max(ch.values.size // 10, 5):])),
                      0.5 * (float(np.max(half)) + float(np.min(half)))):
            windows = np.array_split(np.abs(ch.values - level)[start:], 8)
            swings.append((max(float(np.max(windows[0])), float(np.max(windows[1]))),
                           max(float(np.max(w)) for w in windows[2:])))
        if all(later > GROWTH_LIMIT * first + 8.0 * sigma for first, later in swings):
            first, later = swings[0]
            unit = CHANNEL_KINDS[ch.kind]
            raise QuickReleaseError(
                f"channel {ch.name}: the oscillation grows (a swing of {later:.3g} {unit} after a first of "
                f"{first:.3g} {unit}): a free vibration from a push and release only decays, so no isolation "
                "model describes this record (a forced or self-excited motion, a wrong time column, or records "
                "joined end to end?)")


#: Samples at the head of a displacement channel that must rest (within 8 noise levels) for the record to
#: hold its release; a record that moves beyond that within them started in motion.
REST_HEAD = 40


def _start_in_motion(channels, model: str):
    """A record that starts in motion (caught mid-swing, no quiet segment before the release): its first
    turning point, where the layer is at rest for an instant, taken as a release from rest
    (:func:`quickrelease.building.decay.first_turning_point` on the displacement channel), every channel cut there.
    Returns the channels (cut or as given), the release instant (None where the record rests at its head or
    has no displacement channel) and the warnings to report.

    Exact for the linear model and the pendulum (at rest their state is the displacement alone; the dampers' and
    the sliders' forces depend on the velocity). The bilinear and Bouc-Wen elements hold a state of their own,
    which the fit takes as that of a monotonic push from 0 to the turning point: after the swing before it they
    have yielded the other way, and the fit is biased. Measured (bench_isolators' boucwen record, seed 11, cut 0.3
    of its period after the release): period 1.635 +- 0.003 s, Qd 103 +- 1.4 kN, dy 13.5 mm against the truth's
    3.0 s, 400 kN and 25 mm, the reduced chi-square 1.0; with the element's state at the turn saturated the other
    way the truth-started fit ended at the truth, 3.1 in chi-square above another minimum (period 1.8 s): the
    element's parameters are not identified apart from each other by the ringing after the first turn. The
    warning says so."""
    from .decay import estimate_noise, first_turning_point

    xch = next((c for c in channels if c.kind == "x"), None)
    if xch is None or xch.t.size < 4 * REST_HEAD:
        return channels, None, []
    sigma = estimate_noise(xch.values)
    head = xch.values[:REST_HEAD]
    if not np.max(np.abs(head - head[0])) > 8.0 * sigma + 1e-12 * max(abs(float(head[0])), 1.0):
        return channels, None, []
    try:
        turn = first_turning_point(xch.t, xch.values, noise=sigma)
    except QuickReleaseError:
        return channels, None, []
    kept = []
    for ch in channels:
        keep = ch.t >= turn.time
        if np.count_nonzero(keep) < 10:
            continue
        kept.append(BuildingChannel(ch.name, ch.kind, ch.t[keep], ch.values[keep], ch.noise, ch.offset, ch.drift))
    head_note = (f"the record starts in motion (channel {xch.name} moves in its first {REST_HEAD} samples): its first "
                 f"turning point, t = {turn.time:.6g} s at {turn.d0:.6g} m, is taken as a release from rest, the "
                 "samples before it left out and the noise levels taken from the residuals")
    if model in ("bilinear", "boucwen"):
        return kept, turn.time, [
            head_note + f"; the {model} bearings' state there is taken as that of a push to it, but on the swing "
            "before it they yielded the other way: this record's estimates of the bearings are biased and their "
            "intervals too narrow (fit a record that holds the release)"]
    return kept, turn.time, [head_note + f" (exact for the {model} model: at rest its state is the displacement)"]


def _d0_from_motion(channels, t_r: float, mass: float) -> float:
    """The pushed displacement of a record without a displacement channel, roughly (a start for the search,
    which scales it by up to 3 either way): the record's apparent period T and the first swing's peak
    acceleration or velocity after the release (A_a = w^2 d0, A_v = w d0 for the elastic layer, w = 2 pi
    / T), the sign opposite to the first motion [m]; nan where the record shows neither."""
    from .isolation_search import record_period

    period = record_period(channels, t_r)
    if period is None:
        return math.nan
    w = 2.0 * math.pi / period
    for kind, power in (("a", 2), ("v", 1), ("a_roof", 2), ("v_roof", 1)):
        ch = next((c for c in channels if c.kind == kind), None)
        if ch is None:
            continue
        pre = ch.values[ch.t < t_r]
        zero = float(np.median(pre)) if pre.size >= 3 else 0.0
        first = (ch.t > t_r) & (ch.t < t_r + 0.5 * period)
        if np.count_nonzero(first) < 3:
            continue
        y = ch.values[first] - zero
        i = int(np.argmax(np.abs(y)))
        return -math.copysign(abs(float(y[i])) / w**power, float(y[i]))
    return math.nan


def _initial_values(model: str, mass: float, channels, t_r0: float, fixed: dict[str, float],
                    noise: dict[str, float], superstructure_mass: float | None, d0_start: float | None = None,
                    damping: str = "viscous"):
    """The start of the fit from the record: the pushed displacement d0 (the displacement channel's median
    before the release, or the fixed one), each channel's offset (its median before the release; 0 for a
    displacement), the model's parameters from the decay analysis or the hysteresis loop (:func:`_start`),
    and for the linear model the displacement sensor's zero from the decay law's rest reading. Returns the
    start values, the displacement channel (or None), d0 [m] and the bilinear loop's standard error of
    F_s (or None)."""
    # the pushed displacement and the offsets before the release
    xch = next((c for c in channels if c.kind == "x"), None) or next(
        (c for c in channels if c.kind == "x_roof"), None)  # the roof rests at d0 too before the release
    offsets0 = {}
    for ch in channels:
        pre = ch.values[ch.t < t_r0]
        offsets0[ch.name] = float(np.median(pre)) if (pre.size >= 3 and ch.kind not in ("x", "x_roof")) else 0.0
    d0 = 0.0
    if xch is not None:
        pre = xch.values[xch.t < t_r0]
        d0 = float(np.median(pre)) if pre.size >= 3 else float(xch.values[0])
    if "d0" in fixed:
        d0 = float(fixed["d0"])
    elif xch is None and d0_start is not None:
        d0 = float(d0_start)
    elif xch is None:
        d0 = _d0_from_motion(channels, t_r0, mass)
    if not (math.isfinite(d0) and d0 != 0.0):
        raise ParameterError("d0", d0, "a non-zero pushed displacement (give a displacement channel, "
                             "[building] displacement or fixed d0)", "m")
    p0 = _start(model, mass, channels, t_r0, d0, noise, superstructure_mass)
    if damping == "power":  # the viscous start's force at a typical velocity (half the first cycle's largest)
        zeta = p0.pop("damping_ratio")
        k = mass * (2.0 * math.pi / p0["period"]) ** 2
        v_ref = math.pi * abs(d0) / p0["period"]
        p0.update(damping_coefficient=2.0 * zeta * math.sqrt(k * mass) * math.sqrt(v_ref), damping_exponent=0.5)
    rest = p0.pop("rest", None)
    friction_se = p0.pop("friction_se", None)  # of the bilinear loop's F_s: the spread of its multi-start
    p0.update(d0=d0, release_time=t_r0)
    for ch in channels:
        if ch.offset:
            p0[f"offset_{ch.name}"] = offsets0[ch.name]
        if ch.drift:
            p0[f"drift_{ch.name}"] = 0.0
    if (model == "linear" and rest is not None and xch is not None and xch.offset and "d0" not in fixed
            and abs(rest) < 0.5 * abs(d0)):
        # the displacement sensor's zero: the decay law's rest reading, not 0 (the pushed level is d0 plus
        # that zero, and a start with the zero off by a few noise levels can settle in a wrong count of
        # half-cycles before the sliders stick); the law is exact for the linear model only
        p0[f"offset_{xch.name}"], p0["d0"] = rest, d0 - rest
    return p0, xch, d0, friction_se


def _start_points(model: str, mass: float, names: list[str], values: dict[str, float], fixed: dict[str, float],
                  start: dict[str, float] | None, from_decay: dict[str, float], friction_se: float | None,
                  xch, d0: float, misfit: _Misfit) -> list[dict[str, float]]:
    """The multi-start's start points, the first the start ``values`` (given or from the record)."""
    # The sliders' stick ends the motion at one reversal or another, so the misfit jumps where the count
    # of half-cycles changes and a local search can settle in the wrong count's basin; the friction is
    # also traded against the damping (linear) and against the yield force (bilinear: both act alike on
    # the soft branch). Several splits of the dissipation are tried as starts and the best fit kept.
    starts = [dict(values)]
    if "superstructure_period" in names and model != "2dof":
        # a flexible layer's record often ends with the base held by the sliders and the roof ringing on it at
        # its fixed-base period: the roof's spectral peak read as that (T_s = 2 pi / w_peak), beside the 2dof
        # start's reading of it as the sliding building's second mode
        peak = _second_mode(misfit.channels, values["release_time"], 2.0 * math.pi / values["period"])
        if peak is not None:
            ts = max(2.0 * math.pi / peak, 2.0 * SUPERSTRUCTURE_PERIOD_MIN)
            if abs(ts - values["superstructure_period"]) > 0.05 * ts:
                starts.append({**values, "superstructure_period": ts})
    if model == "linear" and start:  # design values off by 15-25% can lead into the wrong basin: the decay's
        starts.append({**from_decay, **fixed})  # start (cheap for the linear model) is tried beside them
    if "friction" in names:
        if model in ("linear", "2dof") and "damping_ratio" in names:
            k = mass * (2.0 * math.pi / values["period"]) ** 2
            starts.append({**values, "friction": max(values["friction"], 0.02 * k * abs(d0)),
                           "damping_ratio": 0.5 * values["damping_ratio"]})
            # and the first half-cycle's decrement d0 - |x1| taken by the sliders alone (2 F_s / k per
            # half-cycle), by the damper alone (|x1| = d0 exp(-pi zeta)) and half by each: a start in the
            # right basin where the decay analysis found no law
            # Eleven shares (0, 0.1, ..., 1) are scored by their misfit at the start (one model evaluation
            # each) and the three lowest are tried: the basin of the right count of half-cycles can be
            # narrow in the share (the shipped example's record, 3 half-cycles: only shares near 0.63 lead
            # there, and the three shares 0, 0.5 and 1 tried before all missed it)
            x1 = _first_peak(xch, values["release_time"], values["period"], d0) if xch is not None else None
            if x1 is not None and 0.0 < x1 < abs(d0):
                drop = abs(d0) - x1
                splits = []
                for share in np.linspace(0.0, 1.0, 11):
                    zeta = -math.log1p(-(1.0 - share) * drop / abs(d0)) / math.pi
                    trial = {**values, "friction": share * 0.5 * k * drop,
                             "damping_ratio": float(np.clip(zeta, 0.002, 0.5))}
                    r0 = misfit.residuals(np.array([trial[n] for n in names]), names, values)
                    splits.append((float(np.sum(r0 * r0)) if np.all(np.isfinite(r0)) else math.inf, trial))
                splits.sort(key=lambda pair: pair[0])
                starts.extend(trial for _, trial in splits[:3])
    if model == "pendulum" and {"friction_slow", "friction_fast", "rate"} <= set(names):
        # Constantinou's law trades the slow friction against the rate (both shape the friction near the
        # reversals): the fit of a 60 s record settled on (mu_slow 0.0013, a 61 s/m) from every start, the
        # certificate confirming it, 593 above the truth's basin (0.0105, 38). Laws spread over the ratio
        # mu_slow / mu_fast, mu_fast from the first half-cycle's decrement (2 mu R = d0 - |x1|: the friction
        # of the fast sliding that fills most of it), are scored over the rates by the misfit at the start,
        # and the best rate of each ratio is tried.
        x1 = _first_peak(xch, values["release_time"], values["period"], d0) if xch is not None else None
        radius = GRAVITY * (values["period"] / (2.0 * math.pi)) ** 2
        fast = values["friction_fast"]
        if x1 is not None and 0.0 < x1 < abs(d0):
            fast = (abs(d0) - x1) / (2.0 * radius)
        if fast > 0.0:
            for ratio in PENDULUM_RATIOS:
                scored = []
                for rate in PENDULUM_RATES:
                    trial = {**values, "friction_slow": ratio * fast, "friction_fast": fast, "rate": rate}
                    r0 = misfit.residuals(np.array([trial[n] for n in names]), names, values)
                    scored.append((float(np.sum(r0 * r0)) if np.all(np.isfinite(r0)) else math.inf, rate, trial))
                scored.sort(key=lambda item: item[:2])
                starts.append(scored[0][2])
    if model == "bilinear" and "friction" in names and "yield_force" in names:
        if friction_se is not None and not start:
            # the loop's F_s = Q - f_p is its least certain value: f_p comes from the jumps of the gap at
            # the reversals, Q from the loading branches, which hold the displacement sensor's zero e as
            # k2 e where they run in one direction only. F_s two standard errors either way, F_y kept
            for shift in (-2.0 * friction_se, 2.0 * friction_se):
                starts.append({**values, "friction": max(values["friction"] + shift, 0.0)})
        # and splits of the dissipation between the sliders and the rubber
        total = values["friction"] + values["yield_force"]
        for share in (0.05, 0.2, 0.4):
            starts.append({**values, "friction": share * total, "yield_force": (1.0 - share) * total})
    return starts


#: Each start's local solve on the thinned record: its tolerance, and its evaluations per free parameter.
THIN_TOLERANCE, THIN_EVALUATIONS = 1e-6, 40
#: ... and its step tolerance, relative to each parameter's magnitude (:meth:`_Misfit.scales`): a start's solve finds
#: its basin, the whole record's solve its minimum. Measured on bench_isolators' records (seed 11 unless named, load
#: ~2): with 1e-6 the starts in far basins crawled on (boucwen-weak 9.4 s -> 18.2 s, 1 911 evaluations in the
#: starts' solves); 1e-4: 12.1 s, boucwen-damper seeds 3 / 11 11.8 s / 9.6 s, each confirmed; 1e-3 left seed 3's
#: best minimum reached from one start.
THIN_XTOL = 1e-4
#: The pendulum's extra starts (:func:`_start_points`): the ratios mu_slow / mu_fast of Constantinou's law, and the
#: rates [s/m] scored for each.
PENDULUM_RATIOS = (0.1, 0.3, 0.5, 0.75)
PENDULUM_RATES = (10.0, 30.0, 100.0)
#: Distinct minima solved again on the whole record at most (the lowest first), and how far above the best
#: (delta chi-square over the reduced chi-square, estimated on the thinned record) one may lie to be solved.
FULL_SOLVES, FULL_SOLVE_DELTA = 3, 100.0


def _compared(names: list[str], model: str) -> list[str]:
    """The parameters by which two minima are told apart: the physical ones and d0, where free."""
    return [n for n in names if n in PARAMETER_BOUNDS or n == "d0"]  # every model's physical ones


def _basin_errors(J, names: list[str], compare: list[str], chi2: float, dof: int) -> dict[str, float]:
    """Standard errors of the compared parameters from a Jacobian, scaled by the reduced chi-square where it
    exceeds 1 (a misfit above the noise widens the basins alike)."""
    try:
        cov, blind = identified_covariance(np.asarray(J, dtype=float))
    except np.linalg.LinAlgError:
        return dict.fromkeys(compare, math.nan)
    scale = max(chi2 / max(dof, 1), 1.0)
    se = np.sqrt(np.clip(np.diag(cov) * scale, 0.0, None))
    return {n: (math.nan if blind[i] else float(se[i])) for i, n in enumerate(names) if n in compare}


def _multistart(named, names: list[str], values: dict[str, float], solve, thin_misfit, model: str, factor: float,
                progress=None, full_solves: int = FULL_SOLVES):
    """Every start polished on the thinned record (``THIN_TOLERANCE``), the results grouped into basins
    (:func:`quickrelease.building.isolation_search.same_basin`, on the standard errors of the thinned record's best
    fit), and the lowest ``full_solves`` basins solved on the whole record. Returns the best whole-record
    least-squares result and the groups (``{"chi2", "parameters", "x", "starts", "res"}``; chi2 on the whole
    record where solved there, else the thinned one times ``factor``), lowest first."""
    polished = []
    for k, (origin, trial) in enumerate(named):
        if not all(n in trial and math.isfinite(trial[n]) for n in names):
            continue
        if progress is not None:
            progress(f"{model}: start {k + 1} of {len(named)} ({origin})")
        r = solve(names, values, [trial[n] for n in names], tol=THIN_TOLERANCE, on=thin_misfit,
                  max_nfev=THIN_EVALUATIONS * len(names), xtol=THIN_XTOL)
        polished.append({"origin": origin, "chi2": 2.0 * float(r.cost) * factor, "x": np.asarray(r.x), "jac": r.jac})
    polished.sort(key=lambda d: d["chi2"])
    dof_thin = thin_misfit.data.size - len(names)
    if "friction" in names:
        # the sliders' force trades against the other dissipation (a damper, the rubber's hysteresis), and the
        # stick it causes changes the motion's pieces (a layer with sliders stops, one without creeps back): a
        # local search does not cross from a basin with sliders to the face without them. The lowest start whose
        # sliders carry a force is solved again from its point with them removed (a Bouc-Wen + damper record's
        # four starts that ended with 10.6 kN of friction, 1 534 above the truth's basin, reached it from there).
        # A force within SAME_BASIN_SE standard errors of 0 is that face's basin already (the whole record's error,
        # the thinned record's over the square root of the thinning: a start's 0.007 N did not count, the 10.6 kN
        # did, 7.6 errors).
        i = names.index("friction")

        def carries(d) -> bool:
            se = _basin_errors(d["jac"], names, ["friction"], d["chi2"] / factor, dof_thin)["friction"]
            return bool(d["x"][i] > SAME_BASIN_SE * se / math.sqrt(factor))  # (not where the record does not see
            # the sliders: an error of nan)

        item = next((d for d in polished if carries(d)), None)
        if item is not None:
            x0 = item["x"].copy()
            x0[i] = 0.0
            origin = f"{item['origin']}, no sliders"
            if progress is not None:
                progress(f"{model}: start {len(named) + 1} ({origin})")
            r = solve(names, values, x0, tol=THIN_TOLERANCE, on=thin_misfit, max_nfev=THIN_EVALUATIONS * len(names),
                      xtol=THIN_XTOL)
            new = {"origin": origin, "chi2": 2.0 * float(r.cost) * factor, "x": np.asarray(r.x), "jac": r.jac}
            low = min(polished[0], new, key=lambda d: d["chi2"])
            se = _basin_errors(low["jac"], names, _compared(names, model), low["chi2"] / factor, dof_thin)
            # back in the basin it left (the sliders are the record's): no new start, no second count of that one
            if not same_basin(_unpack(new["x"], names, values), _unpack(item["x"], names, values), se):
                polished.append(new)
                polished.sort(key=lambda d: d["chi2"])
    compare = _compared(names, model)
    se = _basin_errors(polished[0]["jac"], names, compare, polished[0]["chi2"] / factor, dof_thin)
    groups: list[dict[str, Any]] = []
    for item in polished:
        p = _unpack(item["x"], names, values)
        for g in groups:
            if same_basin(p, g["parameters"], se):
                g["starts"].append(item["origin"])
                break
        else:
            groups.append({"chi2": item["chi2"], "parameters": p, "x": item["x"], "starts": [item["origin"]],
                           "res": None})
    red = max(groups[0]["chi2"] / factor / max(dof_thin, 1), 1.0)
    for k, g in enumerate(groups[:full_solves]):
        if progress is not None:
            progress(f"{model}: minimum {k + 1} of {min(len(groups), full_solves)} on the whole record")
        if g is not groups[0] and (g["chi2"] - groups[0]["chi2"]) / red > FULL_SOLVE_DELTA:
            break
        g["res"] = solve(names, values, g["x"])
        g["chi2"], g["x"] = 2.0 * float(g["res"].cost), np.asarray(g["res"].x)
        g["parameters"] = _unpack(g["x"], names, values)
    solved = [g for g in groups if g["res"] is not None]
    best = min(solved, key=lambda g: g["chi2"])
    return best["res"], sorted(groups, key=lambda g: g["chi2"])


def _final_groups(groups, res, names: list[str], values: dict[str, float], misfit, model: str,
                  cov_se: dict[str, float]) -> list[dict[str, Any]]:
    """The multi-start's basins after the fit's last steps: the final fit heads the group it lies in; every
    basin solved on the whole record gets its chi-square with the final weights; basins that the whole-record
    solves put in one basin (within ``SAME_BASIN_SE`` final standard errors) merge. A final fit that the polish
    (:func:`_polish`) moved out of the multi-start's best basin, into a lower piece of the misfit, was reached by
    no start: the basin the starts reached is listed as a minimum of its own, and the certificate does not
    confirm the global minimum."""
    best = {"chi2": 2.0 * float(res.cost), "parameters": _unpack(res.x, names, values), "starts": []}
    se = {n: cov_se[n] for n in _compared(names, model) if n in cov_se}
    out = [best]
    for g in groups:
        if g["res"] is not None:
            r = misfit.residuals(g["x"], names, values)
            g = {**g, "chi2": float(r @ r)}
        for h in out:
            if same_basin(g["parameters"], h["parameters"], se):
                h["starts"] += g["starts"]
                break
        else:
            out.append({"chi2": g["chi2"], "parameters": g["parameters"], "starts": list(g["starts"])})
    return out


def _profile_step(names: list[str], physical: list[str], unseen: set[str], est: dict[str, float],
                  std_errors: dict[str, float], lower: dict[str, float], upper: dict[str, float],
                  profile: bool | None, chi2: float, tq: float, scale: float, solve,
                  ci: dict[str, tuple[float, float]], method: dict[str, str], progress=None,
                  cov=None) -> list[str]:
    """Profile-likelihood intervals (into ``ci`` and ``method``) for the physical parameters that want one
    (``profile`` True; or None and at a bound or with a relative standard error above
    ``PROFILE_RELATIVE_SE``), the chi-square target ``chi2 + t^2 scale``; ``cov`` (the fit's covariance, in the
    order of ``names``) gives each refit's start its slope along the correlations. Returns the warnings."""
    warnings = []
    for n in physical:
        if n not in names or n in unseen:
            continue
        lo_n, hi_n = lower.get(n, -math.inf), upper.get(n, math.inf)  # (d0 and the zeros are unbounded)
        at_bound = est[n] - lo_n <= 2.0 * std_errors[n] or hi_n - est[n] <= 2.0 * std_errors[n]
        rel = std_errors[n] / abs(est[n]) if est[n] != 0 else math.inf
        want = profile if profile is not None else (at_bound or rel > PROFILE_RELATIVE_SE)
        if want and len(names) > 1:
            target = chi2 + tq**2 * scale
            if progress is not None:
                progress(f"profile-likelihood interval of {n}")
            slope = None
            if cov is not None:
                i = names.index(n)
                slope = {m: float(cov[j, i] / cov[i, i]) for j, m in enumerate(names)
                         if m != n and m not in unseen and cov[i, i] > 0 and math.isfinite(cov[j, i] / cov[i, i])}
            ci[n] = _profile_interval(n, names, est, lo_n, hi_n, std_errors[n], target, solve, slope)
            method[n] = "profile"
            if ci[n] == (lo_n, hi_n):
                warnings.append(f"{n} not identified by this record (its profile interval is its whole range "
                                f"[{lo_n:.4g}, {hi_n:.4g}])")
        if rel > PROFILE_RELATIVE_SE and not at_bound:
            warnings.append(f"{n} is poorly determined (standard error {rel:.0%} of the estimate)")
    return warnings


def fit_isolation(channels, mass: float, model: str = "linear", *, release_time: float | None = None,
                  fit_release_time: bool = True, start: dict[str, float] | None = None,
                  fixed: dict[str, float] | None = None, profile: bool | None = None,
                  superstructure_mass: float | None = None, tolerance: float = 1e-12, global_search: bool = True,
                  seed: int = 0, progress=None, exclude_spikes: bool = False, damping: str = "viscous",
                  memo: FitMemo | None = None, flexible: bool = False) -> IsolationFit:
    """Fit the isolation system (:mod:`quickrelease.building`) to records of the isolation layer.

    Parameters
    ----------
    channels : sequence of BuildingChannel
        Displacement (x [m]), velocity (v [m/s]) and/or acceleration (a [m/s^2]) of the isolation layer,
        and of the roof (x_roof [m], v_roof [m/s], a_roof [m/s^2]: the 2-DOF model's roof mass; the rigid
        models' roof moves with the layer), each on its own time axis, the pre-release segment included
        where there is one.
    mass : float
        Mass carried by the isolation layer [kg] (the whole building).
    model : {"linear", "bilinear", "2dof"}
        ``2dof``: the flexible superstructure of :class:`quickrelease.building.TwoDOF`, parameters period
        T [s] (of the whole mass on the isolators), damping_ratio, friction [N], superstructure_period T_s
        [s] (fixed-base) and superstructure_damping_ratio; needs ``superstructure_mass``.
    release_time : float, optional
        Start value (or, with ``fit_release_time=False``, the value) of the release instant [s, record
        time]; detected where the record leaves its initial rest when not given.
    start, fixed : dict, optional
        Start values, and parameters held fixed (by name: period, damping_ratio, friction,
        stiffness_ratio, yield_force, superstructure_period, superstructure_damping_ratio, d0, release_time,
        offset_<channel>). Without them the fit starts from the record itself: the linear model from the
        decay analysis (period from the turning-point times, F_s and zeta from the linear and geometric
        parts of the combined decrement law, d0 and the release from the record), the bilinear model from
        the hysteresis loop of the acceleration channel (:func:`quickrelease.building.decay.bilinear_loop`: k2, Q,
        c from the loading branches, k1 and F_s from the elastic unloading after each reversal), and each
        from a few more starts that split the dissipation otherwise, keeping the lowest chi-square, then
        polished (restarts into a neighbouring piece of the misfit where it lies lower, ``_polish``). The
        bilinear model's misfit has local minima (the count of half-cycles before the sliders stick changes
        in jumps, and friction and yield force act alike on the soft branch): without an acceleration
        channel its start comes from the secant periods of the decay only, which may not find the right
        one, and the result then warns (give the bearings' design values as start values).
    profile : bool, optional
        Profile-likelihood intervals: True for every physical parameter, False never, None (default) for
        those at a bound or with a relative standard error above ``PROFILE_RELATIVE_SE``.
    superstructure_mass : float, optional
        The roof mass m_s [kg] of the 2-DOF model, in (0, mass) (given, not fitted: the record fixes the
        parameters per unit mass only).
    global_search : bool
        The global stage (default True, :mod:`quickrelease.building.isolation_search`): independent CMA-ES runs over
        the model's bounded space on the thinned record, whose best points are polished beside the record's
        own starts and the design values; the result's ``search`` certificate counts the starts that reached
        the best minimum and gives the next distinct minimum's delta chi-square. False: the record's starts
        and the design values only (faster; no certificate that the minimum is global).
    seed : int
        Seed of the global search's runs (the fit is deterministic for a given seed).
    progress : callable, optional
        Called with a line saying what runs (the model, the global search's run or the start, with counts;
        the profile intervals), for a progress display.
    exclude_spikes : bool
        Spikes (a logger's glitches, a sensor's dropouts): after the fit, the samples whose residual less
        the median of its six neighbours exceeds ``max(SPIKE_LEVEL, sqrt(2 ln n) + 1.5)`` robust
        scatters of those (1.4826 MAD; a misfit that varies over many samples is not a spike) are excluded
        and the fit is redone on the rest, global stage included; each round judges the whole record again
        by the latest fit, until the excluded samples stay the same (``SPIKE_ROUNDS`` fits at most). The
        estimates and intervals are those of ordinary least squares on the kept samples (a clean record
        keeps them all); ``excluded`` lists the times, a warning counts them.
    memo : FitMemo, optional
        Filled with what this fit computes (the global stage's candidates, each least-squares solve), and
        read back where a computation repeats: a later fit of the same record given the same memo (other
        start values, e.g. a campaign's restart from another release's estimates) solves only what its new
        start changes and gives the result it gives without the memo.
    tolerance : float
        Relative tolerance of the least-squares solves (scipy's ``ftol``, ``xtol``, ``gtol``). The default, 1e-12,
        settles the estimates to far below their standard errors; a model fitted only to be ranked by AIC/BIC
        (``analyse_building(compare=True)``) needs its chi-square to about 1e-2 and is solved to 1e-8.

    Returns
    -------
    IsolationFit
    """
    from threadpoolctl import threadpool_limits

    kwargs = dict(release_time=release_time, fit_release_time=fit_release_time, start=start, fixed=fixed,
                  profile=profile, superstructure_mass=superstructure_mass, tolerance=tolerance,
                  global_search=global_search, seed=seed, progress=progress, damping=damping, memo=memo,
                  flexible=flexible)
    with threadpool_limits(1, user_api="blas"):  # thin Jacobians: BLAS threads cost more than they give
        fit = _fit_isolation(channels, mass, model, **kwargs)
        if not exclude_spikes:
            return fit
        # a fixed point: each round judges every sample of the whole record by the latest fit, so a sample a
        # first fit in a wrong minimum took for a spike comes back once the fit is right
        channels = list(channels)
        excluded: dict[str, tuple[float, ...]] = {}
        for _ in range(SPIKE_ROUNDS - 1):
            found = _spikes(fit, channels)
            if found == excluded:
                break
            excluded = found
            fit = _fit_isolation(drop_excluded(channels, excluded), mass, model, **kwargs)
    if not excluded:
        return fit
    count = sum(len(v) for v in excluded.values())
    where = ", ".join(f"{len(v)} of {k}" for k, v in excluded.items())
    note = (f"{count} sample(s) excluded as spikes ({where}): residuals that stand out of their neighbours' by "
            f"{SPIKE_LEVEL:g} or more robust scatters")
    return replace(fit, excluded=excluded, warnings=(*fit.warnings, note))


def drop_excluded(channels, excluded: dict[str, Any]) -> list[BuildingChannel]:
    """The channels without the samples at the times ``excluded`` lists for them (an
    :attr:`IsolationFit.excluded`), so that what is drawn or analysed beside the fit is what it saw."""
    out = []
    for ch in channels:
        gone = excluded.get(ch.name)
        if gone:
            keep = ~np.isin(ch.t, np.asarray(gone, dtype=float))
            ch = replace(ch, t=ch.t[keep], values=ch.values[keep])
        out.append(ch)
    return out


def _local_residuals(resid: np.ndarray) -> np.ndarray:
    """Each residual less the median of its six neighbours (three each side): a spike stands out of it whole
    (two spikes among the six leave the median between clean values), while a misfit that varies over many
    samples (a first fit in a wrong minimum, pulled there by the spikes themselves) and a step (a friction
    force that flips a sample early) do not. The sample itself is left out of the median, so white noise
    gives a difference of independent terms (no share of exact zeros to shrink its MAD)."""
    from numpy.lib.stride_tricks import sliding_window_view

    window = sliding_window_view(np.pad(resid, 3, mode="edge"), 7)
    return resid - np.median(window[:, [0, 1, 2, 4, 5, 6]], axis=1)


def _spikes(fit: IsolationFit, channels) -> dict[str, tuple[float, ...]]:
    """The times of the samples of ``channels`` (the whole record) that ``fit`` shows as spikes: the residual
    less the median of its six neighbours (:func:`_local_residuals`) beyond ``max(SPIKE_LEVEL, sqrt(2 ln n) + 1.5)``
    times 1.4826 MAD of those, within the span the fit saw (a record that starts in motion is fitted from its
    first turning point)."""
    fitted = {c.name: c for c in fit.channels}
    out = {}
    for ch in channels:
        seen = fitted.get(ch.name)
        if seen is None:
            continue
        inside = ch.t >= seen.t[0]
        t, values = ch.t[inside], ch.values[inside]
        local = _local_residuals(values - fit.model_values(ch, t))
        scatter = 1.4826 * float(np.median(np.abs(local)))
        level = max(SPIKE_LEVEL, math.sqrt(2.0 * math.log(local.size)) + 1.5)
        spikes = t[np.abs(local) > level * scatter] if scatter > 0 else t[:0]
        if spikes.size and ch.t.size - spikes.size >= 10:
            out[ch.name] = tuple(float(v) for v in spikes)
    return out


def _fit_isolation(channels, mass: float, model: str, *, release_time, fit_release_time, start, fixed, profile,
                   superstructure_mass, tolerance, global_search, seed, progress=None,
                   damping: str = "viscous", memo: FitMemo | None = None, flexible: bool = False,
                   as_start: bool = False) -> IsolationFit:
    # as_start: a fit that is itself a start of another (the Bouc-Wen fit's bilinear start): its solves' step
    # tolerance the starts' (THIN_XTOL, relative to each parameter's magnitude), its best basin alone solved on the
    # whole record, and no quiet segment detected again, no polish, no reweighting: the fit it starts does those
    # (on the benchmark's boucwen-weak record 2.8 -> 2.1 s, seeds 1-4 of it and of boucwen / boucwen-damper at the
    # same minima, each confirmed)
    step_tolerance = THIN_XTOL if as_start else None
    channels = list(channels)
    if not channels:
        raise ParameterError("channels", "none", "at least one channel of the isolation layer")
    if model not in FIT_MODELS:
        raise ParameterError("model", model, ", ".join(f"'{m}'" for m in FIT_MODELS))
    if damping not in DAMPING_LAWS:
        raise ParameterError("damping", damping, "'viscous' or 'power'")
    if not isinstance(flexible, bool | np.bool_):
        raise ParameterError("flexible", flexible, "True or False")
    flexible = bool(flexible) and model != "2dof"  # 2dof is the linear layer under a flexible superstructure
    if flexible and model not in FLEXIBLE_MODELS:
        raise ParameterError("model", model, f"{', '.join(repr(m) for m in FLEXIBLE_MODELS)} with flexible=True "
                             "(the linear layer under a flexible superstructure is model='2dof', in closed form)")
    mass = float(mass)
    if not (math.isfinite(mass) and mass > 0):
        raise ParameterError("mass", mass, "(0, inf)", "kg")
    if model == "2dof" or flexible:
        ms = math.nan if superstructure_mass is None else float(superstructure_mass)
        if not (math.isfinite(ms) and 0.0 < ms < mass):
            raise ParameterError("superstructure_mass", superstructure_mass, f"(0, mass) = (0, {mass:.6g}) kg (the "
                                 f"{'2dof model' if model == '2dof' else 'flexible superstructure'} needs it)", "kg")
        superstructure_mass = ms
    else:
        superstructure_mass = None
    two_dof = superstructure_mass is not None  # 2dof or flexible: the base and a roof that rings
    names_seen = [c.name for c in channels]
    if len(set(names_seen)) != len(names_seen):
        raise ParameterError("channels", ", ".join(names_seen), "distinct channel names")
    fixed = dict(fixed or {})
    started_in_motion = []
    if release_time is None and not two_dof:
        channels, release_time, started_in_motion = _start_in_motion(channels, model)
    t_r0 = float(release_time) if release_time is not None else _detect_release(channels)
    if not fit_release_time:
        fixed["release_time"] = t_r0
    noise, source, absolute = _noise_levels(channels, t_r0)
    if not two_dof:  # the roof can pull a held base away again: the base's swings need not fall
        _check_decays(channels)
    p0, xch, d0, friction_se = _initial_values(model, mass, channels, t_r0, fixed, noise, superstructure_mass,
                                               (start or {}).get("d0"), damping)
    from_decay = dict(p0)  # the start of the model-free decay analysis, before the caller's start values
    physical = _physical_names(model, damping, flexible)
    all_names = _parameter_names(model, channels, damping, flexible)
    # start values of this fit's parameters only: a case's design values of another model or damper law (a
    # power-law case fitted with viscous damping, --compare's other models) would otherwise enter the model
    # (a damping_exponent in the values makes the damper a power law, and damping_ratio had no effect)
    p0.update({n: v for n, v in (start or {}).items() if n in all_names})
    unknown = sorted(set(fixed) - set(all_names))
    if unknown:
        raise ParameterError("fixed", unknown[0], ", ".join(all_names))
    names = [n for n in all_names if n not in fixed]
    values = {**p0, **fixed}
    hint = record_period(channels, t_r0)
    # the release's search reaches back a quarter of the record's apparent period (else the start's)
    lower, upper = _bounds(channels, t_r0, hint if hint is not None else values["period"])
    misfit = _Misfit(channels, noise, mass, model, superstructure_mass, lower, upper, drift_origin=t_r0)
    sig, data = misfit.sig, misfit.data

    def unpack(theta, free=names, base=values) -> dict[str, float]:
        return _unpack(theta, free, base)

    def residuals(theta, free=names, base=values) -> np.ndarray:
        return misfit.residuals(theta, free, base)

    def jacobian(theta, free=names, base=values):
        return misfit.jacobian(theta, free, base)

    def solve(free, base, x0, tol=tolerance, on=misfit, max_nfev=None, xtol=step_tolerance):
        lo = np.array([lower.get(n, -math.inf) for n in free])
        hi = np.array([upper.get(n, math.inf) for n in free])
        x0 = np.clip(np.asarray(x0, dtype=float), lo, hi)
        max_nfev = max_nfev or 400 * max(len(free), 1)

        origin, scale = on.scales(free, x0)

        def jacobian_f(theta, free, base):
            return on.jacobian(theta, free, base, order="F")

        def run():
            # the Jacobian by central differences over a relative step of 1e-4 (_Misfit.jacobian): the misfit
            # jumps where a piece boundary (a stick, a yield) passes a sample, so a step near the rounding level
            # would see those jumps; a parameter whose optimum is its bound is held there (bounded_least_squares);
            # each parameter's step measured against its own magnitude (``scale``)
            res = bounded_least_squares(on.residuals, x0, jacobian_f, lo, hi, args=(free, base), tol=tol,
                                        max_nfev=max_nfev, x_scale="jac", scale=scale, origin=origin, xtol=xtol)
            # stopped against a sample instant: solved again with the release bounded there (on the whole record;
            # a start's solve on the thinned record is one of several, refined on the whole record after it: a
            # benchmark Bouc-Wen + fluid damper fit spent 2.5 s of 12.4 s re-solving one of them)
            edge = None if on.coarse_steps else on.release_edge(res.x, free, lo, hi)
            if edge is not None:
                pinned = bounded_least_squares(on.residuals, res.x, jacobian_f, *edge, args=(free, base), tol=tol,
                                               max_nfev=max_nfev, x_scale="jac", scale=scale, origin=origin, xtol=xtol)
                if pinned.cost < res.cost:
                    pinned.nfev += res.nfev
                    res = pinned
            return res

        if memo is None:
            return run()
        return memo.value(("solve", on.fingerprint(), tuple(free), _held(base, free), x0.tobytes(), float(tol),
                           int(max_nfev), None if xtol is None else float(xtol)), run)

    def stage(name, step, res, *args):
        """A refinement of ``res`` on the whole record (the polish, the step search), kept in the memo."""
        if memo is None:
            return step(res, *args)
        return memo.value(_refinement_key(name, misfit, names, values, res, seed, tolerance),
                          lambda: step(res, *args))

    # the starts: the record's own (decay analysis or hysteresis loop, and splits of the dissipation), the
    # design values where given (one start among several, never a restriction), and the global search's
    record_values = {**from_decay, **fixed}
    named = [(f"record {i + 1}", trial) for i, trial in enumerate(
        _start_points(model, mass, names, record_values, fixed, None, from_decay, friction_se, xch, d0, misfit))]
    if start:
        named.append(("design values", values))
    loop = _boucwen_from_loop(channels, mass, t_r0, noise, hint, names, record_values, fixed, damping,
                              superstructure_mass) \
        if model == "boucwen" else []
    named += loop
    if model == "boucwen" and global_search:  # with the loop's start, the bilinear fit's at shape 1 alone (those
        # at 2 and 5 reached the best minimum with it or not at all on the benchmark's and the example's records)
        named += _boucwen_from_bilinear(channels, mass, t_r0, fit_release_time, fixed, record_values, damping, seed,
                                        progress, BOUCWEN_SHAPES[:1] if loop else BOUCWEN_SHAPES,
                                        global_search=not loop, memo=memo)
    thin, factor = thin_channels(channels, t_r0)
    thin_misfit = _Misfit(thin, noise, mass, model, superstructure_mass, lower, upper, drift_origin=t_r0,
                          coarse_steps=True)
    if loop:  # the loop's start, its stiffness, damper and zero first adjusted to the record (LOOP_HELD held)
        origin, trial = loop[0]
        inner = [n for n in names if n not in LOOP_HELD]
        r = solve(inner, trial, [trial[n] for n in inner], tol=THIN_TOLERANCE, on=thin_misfit,
                  max_nfev=THIN_EVALUATIONS * len(inner), xtol=THIN_XTOL)
        named = [(o, {**trial, **_unpack(r.x, inner, trial)} if o == origin else t) for o, t in named]
    evaluations = 0
    if global_search:
        search_d0 = xch is None and "d0" not in fixed
        release = None
        if "release_time" in names:  # from 6% of the apparent period (20 samples at least) before the detected
            # release to two samples after it: the detection lags by tens of ms, and a wider range holds the
            # search in the phases of other releases (the polish reaches the fit's whole range)
            reach = max(20.0 * misfit.dt, 0.06 * (hint if hint is not None else values["period"]))
            release = (max(lower["release_time"], t_r0 - reach), min(upper["release_time"], t_r0 + 2.0 * misfit.dt))
        box = search_box(model, hint, search_d0, release, damping, flexible)
        runs, spend = SEARCH_RUNS[model] + search_d0, SEARCH_EVALUATIONS[model] * (1 + search_d0)

        def search():
            return global_candidates(model, mass, thin_misfit, box, record_values, record_values["d0"], runs=runs,
                                     evaluations=spend, seed=seed, fixed=fixed, progress=progress, damping=damping)

        if memo is None:
            found, evaluations = search()
        else:
            found, evaluations = memo.value(("search", thin_misfit.fingerprint(), model, mass, damping, repr(box),
                                             _held(record_values, ()), _held(fixed, ()), runs, spend, seed), search)
        named += [(c["origin"], c["parameters"]) for c in found]
    res, groups = _multistart(named, names, values, solve, thin_misfit, model, factor, progress,
                              1 if as_start else FULL_SOLVES)
    if not as_start:
        res = _requiet(res, channels, noise, source, sig, names, values, solve, t_r0)
    if (model != "2dof" or damping == "power") and not as_start:  # (2dof's closed form is smooth but at its
        # sticks; with fluid dampers it is the flexible integrator's, the misfit's cusps at the turns (C |v|^alpha)
        # as the others')
        res = stage("polish", _polish, res, names, values, solve, misfit.residuals, lower, upper, misfit.dt)
        res = stage("turn polish", _turn_polish, res, names, values, solve, misfit, lower, upper)
        if not any(c.kind in ("x", "x_roof") for c in channels):  # no smooth channel: the steps rule the misfit
            res = stage("step search", _step_search, res, names, values, solve, misfit.residuals, lower, upper,
                        seed)
    if not absolute and not as_start:
        # a noise level taken from the residuals: weight each such channel by its own residual scatter
        # and refit (twice; the weights settle at once). One global chi-square scale cannot correct
        # channels whose first guesses (their spread) are wrong by different factors.
        for _ in range(2):
            i = 0
            for ch in channels:
                if source[ch.name] == "residuals":
                    seg = res.fun[i:i + ch.t.size] * sig[i:i + ch.t.size]
                    noise[ch.name] = float(np.sqrt(np.mean(seg**2))) or noise[ch.name]
                    sig[i:i + ch.t.size] = noise[ch.name]
                i += ch.t.size
            res = solve(names, values, res.x)
    est = unpack(res.x)
    r = res.fun
    n_data = data.size
    p = len(names)
    dof = n_data - p
    chi2 = float(r @ r)
    chi2_red = chi2 / dof if dof > 0 else math.nan
    scale = 1.0 if absolute else chi2_red
    cov, blind = _covariance_without_cusps(res.jac, scale)
    unseen = {n for n, b in zip(names, blind, strict=True) if b}
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se, se)
    corr = np.where(np.isfinite(corr), corr, 0.0)
    corr[blind, blind] = 1.0
    try:
        cond = float(np.linalg.cond(corr))
    except np.linalg.LinAlgError:
        cond = math.inf
    tq = float(stats.t.ppf(0.975, max(dof, 1)))
    estimates = {n: est[n] for n in names}
    std_errors = {n: float(s) for n, s in zip(names, se, strict=True)}
    ci = {}
    method = {}
    for n in names:
        lo_b, hi_b = lower.get(n, -math.inf), upper.get(n, math.inf)
        ci[n] = (max(est[n] - tq * std_errors[n], lo_b), min(est[n] + tq * std_errors[n], hi_b))
        method[n] = "jacobian"
    warnings = []
    for n in names:  # the record does not see it: no interval (the pseudo-inverse would say SE ~0)
        if n in unseen:
            ci[n], method[n] = (math.nan, math.nan), "not identified"
            warnings.append(f"{n} not identified by this record (standard error inf, no interval)")
    warnings += _profile_step(names, physical, unseen, est, std_errors, lower, upper, profile, chi2, tq, scale,
                              solve, ci, method, progress, cov)
    final = _final_groups(groups, res, names, values, misfit, model, std_errors)
    cert = certificate(final, sum(len(g["starts"]) for g in final), chi2_red, evaluations)
    warnings += list(cert.warnings)
    for m in cert.minima[1:]:
        if m.delta_chi2 < COMPETING_DELTA_CHI2:  # a second basin as good as the best: the intervals cover it
            for n in names:
                if n in physical and n not in unseen and math.isfinite(m.parameters.get(n, math.nan)):
                    lo_, hi_ = ci[n]
                    ci[n] = (min(lo_, m.parameters[n]), max(hi_, m.parameters[n]))
                    method[n] = "covers two minima"
    if "superstructure_period" in names and "superstructure_period" not in unseen and \
            est["superstructure_period"] - lower["superstructure_period"] <= 2.0 * std_errors["superstructure_period"]:
        rigid = "the rigid layer (flexible=False)" if flexible else "model='linear'"
        warnings.append(f"superstructure_period at its lower bound ({SUPERSTRUCTURE_PERIOD_MIN:g} s): the record "
                        "does not resolve a superstructure this stiff (it moves with the isolation layer), and "
                        f"the rigid model is this fit's limit: fit {rigid} and compare_models")
    warnings += _limits(names, unseen, est, std_errors, ci)
    if cond > CONDITION_WARNING:
        warnings.append(f"ill-conditioned fit (condition number of the correlations {cond:.2g}): some combination "
                        "of parameters is not determined by the record")
    warnings += started_in_motion
    rms, samples, white = {}, {}, {}
    i = 0
    for ch in channels:
        seg = r[i:i + ch.t.size] * noise[ch.name]
        i += ch.t.size
        rms[ch.name] = float(np.sqrt(np.mean(seg**2)))
        samples[ch.name] = int(ch.t.size)
        moving = ch.t >= est["release_time"]
        white[ch.name] = ljung_box(seg[moving]) if np.count_nonzero(moving) > 40 else math.nan
        if source[ch.name] == "residuals":
            noise[ch.name] = noise[ch.name] * math.sqrt(chi2_red) if math.isfinite(chi2_red) else noise[ch.name]
    chi2_scaled = chi2 / scale if scale > 0 else chi2
    aic = chi2_scaled + 2 * p
    bic = chi2_scaled + p * math.log(n_data)
    if not res.success:
        warnings.append(f"the optimiser did not converge ({res.message})")
    if absolute and math.isfinite(chi2_red) and chi2_red > 1.3:
        warnings.append(f"the misfit is {math.sqrt(chi2_red):.2g} times the noise: the record does not support the "
                        f"{model} model, or the fit sits in a local minimum (give start values)")
    return IsolationFit(model=model, mass=mass, names=tuple(names), estimates=estimates, std_errors=std_errors,
                        ci95=ci, interval_method=method, correlation=corr, condition_number=cond, noise=noise,
                        noise_source=source, residual_rms=rms, samples=samples, chi2=chi2, dof=dof,
                        chi2_reduced=chi2_red, absolute_sigma=absolute, aic=aic, bic=bic, whiteness_p=white,
                        converged=bool(res.success), nfev=int(res.nfev), warnings=tuple(warnings),
                        channels=tuple(channels), superstructure_mass=superstructure_mass,  # flexible: not None
                        fixed={n: float(values[n]) for n in fixed}, search=cert, drift_origin=misfit.drift_origin,
                        damping=damping)


def _covariance(J, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """``scale (J^T J)^-1`` over the identified parameters and the mask of the unidentified ones (nan where the
    information is singular)."""
    try:  # columns scaled first: parameters in SI units span many orders of magnitude
        cov, blind = identified_covariance(J)
    except np.linalg.LinAlgError:
        p = np.shape(J)[1]
        return np.full((p, p), np.nan), np.zeros(p, dtype=bool)
    return cov * scale, blind


def _leverages(J, blind) -> np.ndarray:
    """The diagonal of the hat matrix ``J (J^T J)^-1 J^T`` over the identified columns: the share of each sample's
    fitted value that its own measurement makes (they sum to the count of parameters)."""
    Jg = np.asarray(J, dtype=float)[:, ~np.asarray(blind, dtype=bool)]
    if Jg.shape[1] == 0:
        return np.zeros(Jg.shape[0])
    norms = np.linalg.norm(Jg, axis=0)
    q, _ = np.linalg.qr(Jg / np.where(norms > 0, norms, 1.0))
    return np.sum(q * q, axis=1)


def _covariance_without_cusps(J, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """The covariance of the estimates (``scale (J^T J)^-1``) and the unidentified mask, the samples whose leverage
    exceeds ``LEVERAGE_LIMIT`` left out (``CUSP_ROUNDS`` rounds at most; none where that would leave a parameter
    unidentified).

    A power-law damper (alpha < 1) has a cusp at each reversal and at the stick: its force C |v|^alpha grows as
    |t - t_rev|^alpha, with an infinite slope. The least-squares fit likes to park such a cusp on a sample (that
    sample's model value then moves infinitely fast with the parameters that move the cusp, and its residual is
    zeroed at no cost to the others). There the Jacobian's column reads that one sample as all the information
    along some direction of the parameters: its leverage was 0.89-0.999 where an ordinary sample's is about p / n,
    and the standard errors came out 1.4-14 times too small (seeds 2400-2599 of test_hysteretic_coverage's
    power-law record: 83 of 200 fits, and nearly all the misses: period covered 180 times of 200, d0 179). Within
    the interval the cusp moves hundreds of microseconds, that sample's value by a fraction of its noise: it
    carries no such information. A sample that alone would halve some direction's variance (leverage above 0.5:
    leaving it out multiplies that variance by 1 / (1 - h)) is left out of the covariance (not of the fit); the
    others' information, as in the fits whose cusps lie between samples, makes the standard errors."""
    cov, blind = _covariance(J, scale)
    J = np.asarray(J, dtype=float)
    keep = np.ones(J.shape[0], dtype=bool)
    for _ in range(CUSP_ROUNDS):
        if not np.all(np.isfinite(cov[np.ix_(~blind, ~blind)])):
            break
        high = np.flatnonzero(keep)[_leverages(J[keep], blind) > LEVERAGE_LIMIT]
        if high.size == 0:
            break
        trial = keep.copy()
        trial[high] = False
        cov_t, blind_t = _covariance(J[trial], scale)
        if np.any(blind_t & ~blind) or not np.all(np.isfinite(cov_t[np.ix_(~blind_t, ~blind_t)])):
            break
        keep, cov, blind = trial, cov_t, blind_t
    return cov, blind


def _limits(names: list[str], unseen: set[str], est: dict[str, float], se: dict[str, float],
            ci: dict[str, tuple[float, float]]) -> list[str]:
    """Where a Bouc-Wen fit ends at one of its limits, the warning that says which simpler model it fell to: the
    shape n within two standard errors of its upper bound (the bilinear limit: the record holds no evidence of
    a rounded transition), or Qd's interval reaching 0 (the linear limit: no hysteresis the record resolves
    beyond the sliders' friction). There the model fits the record as well as its limit does, with more
    parameters, and its Qd, dy, n describe no loop the record holds: the comparison (BIC) should decide."""
    out = []
    top = PARAMETER_BOUNDS["shape"][1]
    if "shape" in names and "shape" not in unseen and top - est["shape"] <= max(2.0 * se["shape"], 1e-3 * top):
        out.append(f"shape n = {est['shape']:.4g} within two standard errors of its bound ({top:g}): the record "
                   "holds no evidence of a rounded transition, and this fit is the bilinear model's limit (compare "
                   "with model='bilinear', fewer parameters)")
    if "characteristic_strength" in names and "characteristic_strength" not in unseen \
            and ci["characteristic_strength"][0] <= 0.0:
        out.append("characteristic_strength's interval reaches 0: the record resolves no hysteresis beyond the "
                   "sliders' friction, and this fit is the linear model's limit (compare with model='linear', "
                   "fewer parameters)")
    return out


def _boucwen_of_bilinear(k1: float, k2: float, fy: float) -> tuple[float, float]:
    """The Bouc-Wen bearings' Qd [N] and dy [m] of bilinear ones (k1, k2 = Kd [N/m], F_y [N]; their limit
    n -> inf): ``Qd = F_y (1 - k2 / k1)``, ``dy = F_y / k1``, the initial stiffness ``Kd + Qd / dy = k1``. Where the
    bilinear layer yields beyond the yield displacement's upper bound (a fit whose F_y ran off: the layer elastic
    with k1 over the record), dy is that bound and ``Qd = (k1 - k2) dy``: the same initial stiffness. (dy clipped
    to the bound alone kept Qd = F_y (1 - k2 / k1): a bilinear fit of a lead-rubber + damper record under a storey
    ended at F_y = 6e16 N, and its start, Qd 5e14 N over dy 10 m, held the base on a spring of 5e13 N/m whose every
    evaluation took 5 s: one fit ran for tens of minutes.)"""
    top = PARAMETER_BOUNDS["yield_displacement"][1]
    if fy / k1 <= top:
        return fy * (1.0 - k2 / k1), fy / k1
    return (k1 - k2) * top, top


#: The Bouc-Wen shapes tried from the bilinear fit (n = 1 the rounded loop of lead-rubber, larger: sharper).
BOUCWEN_SHAPES = (1.0, 2.0, 5.0)


def _boucwen_from_bilinear(channels, mass: float, t_r0: float, fit_release_time: bool, fixed: dict[str, float],
                           record_values: dict[str, float], damping: str, seed: int, progress,
                           shapes: tuple[float, ...] = BOUCWEN_SHAPES, global_search: bool = True,
                           memo: FitMemo | None = None) -> list[tuple[str, dict[str, float]]]:
    """Starts of the Bouc-Wen fit from a bilinear fit of the same record (its limit n -> inf: Kd = k2,
    Qd = F_y (1 - k2 / k1), dy = F_y / k1, the damper's c kept), one per shape of ``shapes``.

    The Bouc-Wen misfit has wide regions where the shape and the damping run to their bounds (a chi-square a
    thousand times the noise's from the global stage alone on 5 of 16 independent records); the bilinear
    model, exactly solved and cheap, finds the loop's stiffnesses and strength first. That fit is a start
    (``as_start``: not polished, which took 524 of its 626 whole-record evaluations on the benchmark's record; its
    best basin alone solved on the whole record, no reweighting): the Bouc-Wen fit's own multi-start and polish
    follow from it."""
    keep = {k: v for k, v in fixed.items() if k in ("d0", "release_time") or k.startswith(("offset_", "drift_"))}
    try:
        bl = _fit_isolation(channels, mass, "bilinear", release_time=t_r0, fit_release_time=fit_release_time,
                            start=None, fixed=keep, profile=False, superstructure_mass=None, tolerance=1e-6,
                            global_search=global_search, seed=seed, progress=progress, memo=memo, as_start=True)
    except QuickReleaseError:
        return []
    e = bl.parameters
    k1 = mass * (2.0 * math.pi / e["period"]) ** 2
    k2, fy = e["stiffness_ratio"] * k1, e["yield_force"]
    c = 2.0 * e["damping_ratio"] * math.sqrt(k1 * mass)
    base = {**record_values, **{n: v for n, v in e.items() if n in record_values and n not in PARAMETER_BOUNDS}}
    qd, dy = _boucwen_of_bilinear(k1, k2, fy)
    base.update(period=2.0 * math.pi * math.sqrt(mass / k2), characteristic_strength=qd, yield_displacement=dy,
                friction=e["friction"])
    if damping == "power":
        v_ref = math.pi * abs(e["d0"]) / base["period"]
        base.update(damping_coefficient=c * math.sqrt(v_ref), damping_exponent=0.5)
    else:
        base["damping_ratio"] = min(c / (2.0 * math.sqrt(k2 * mass)), 0.9)
    return [(f"bilinear fit, shape {n:g}", {**base, "shape": n, **fixed}) for n in shapes]


#: The Bouc-Wen parameters that the measured loop determines best, held at its values while the others adjust to
#: the whole record's thinned misfit, before the loop's start enters the multi-start: Kd, C, alpha and the LVDT's
#: zero trade with each other through the loop's noise (Kd +-25 % over five records), and from the loop's values
#: alone the local search went through the sliders' force into a basin beside the truth's (the shipped lead-rubber
#: + damper record from its LVDT alone: F_s 1.4-3 kN, chi-square 1 000 above the minimum).
LOOP_HELD = ("yield_displacement", "shape", "friction")


def _boucwen_from_loop(channels, mass: float, t_r0: float, noise: dict[str, float], hint: float | None,
                       names: list[str], record_values: dict[str, float], fixed: dict[str, float],
                       damping: str, superstructure_mass: float | None = None) -> list[tuple[str, dict[str, float]]]:
    """The Bouc-Wen fit's start from the measured loop (:func:`quickrelease.building.boucwen_loop.boucwen_loop`:
    the equation error F = -m a of the displacement and acceleration channels of the layer; the displacement's
    second derivative without an accelerometer), where the record has a displacement; none else. Its values are
    independent of the misfit's basins and of any design value."""
    from .boucwen_loop import boucwen_loop

    xch = next((c for c in channels if c.kind == "x"), None)
    ach, ach_noise = _layer_acceleration(channels, noise, mass, superstructure_mass)  # (flexible: m_b a_b + m_s a_s)
    if xch is None:
        return []
    period = hint if hint is not None else record_values["period"]
    try:  # a start: a record it cannot read (too short, degenerate) leaves the others
        loop = boucwen_loop(xch.t, xch.values, None if ach is None else ach.t, None if ach is None else ach.values,
                            mass, t_r0, noise[xch.name], None if ach is None else ach_noise, period,
                            damping=damping)
    except (ValueError, ArithmeticError, np.linalg.LinAlgError):
        loop = None
    if loop is None or not all(math.isfinite(v) for v in (loop.post_yield_stiffness, loop.zero, loop.damping)):
        return []
    kd = loop.post_yield_stiffness
    trial = {**record_values, "period": 2.0 * math.pi * math.sqrt(mass / kd),
             "characteristic_strength": loop.characteristic_strength,
             "yield_displacement": loop.yield_displacement,
             "shape": float(np.clip(loop.shape, *SHAPE_RANGE)), "friction": loop.friction}
    if damping == "power":
        trial.update(damping_coefficient=loop.damping, damping_exponent=float(np.clip(loop.damping_exponent,
                                                                                      *EXPONENT_RANGE)))
    else:
        trial["damping_ratio"] = loop.damping / (2.0 * math.sqrt(kd * mass))
    if f"offset_{xch.name}" in names and "d0" in names:  # the sensor's zero the loop found, and d0 from it
        trial[f"offset_{xch.name}"] = loop.zero
        trial["d0"] = record_values["d0"] - loop.zero
    return [("hysteresis loop", {**trial, **fixed})]


#: The chi-square drop a polish restart must reach to replace the fit (:func:`_polish`).
POLISH_GAIN = 1.0
#: Rounds of polish restarts at most, the leading axes of the correlations they probe and the steps along
#: them (in standard deviations), and the shifts of the release time (in sampling intervals).
POLISH_ROUNDS, POLISH_AXES, POLISH_STEPS, POLISH_SHIFTS = 3, 3, (1.0, 2.0), (1,)
#: The polish's steps along each parameter's regression line (in its standard errors).
POLISH_ALONG = (1.0, 2.0, 4.0)


def _polish(res, names, values, solve, residuals, lower, upper, dt: float):
    """Restarts from the best fit of the multi-start into a neighbouring minimum, kept where it fits better.

    Near the optimum the misfit has steps: where a stick or a reversal crosses a sample, the piecewise model
    jumps at that sample, so the chi-square is piecewise smooth with a local minimum in many pieces, and a
    local search stops at the first (often against a cliff: one side of it a different count of half-cycles
    before the sliders stick, thousands higher). The chi-square is probed at trial points: the release time
    shifted by ``POLISH_SHIFTS`` sampling intervals ``dt`` either way, and the fit moved along the
    ``POLISH_AXES`` leading axes of the correlation matrix (the combinations the record fixes least) by
    ``POLISH_STEPS`` standard deviations either way, ``x +- s sqrt(lambda_k) (v_k * se)`` (lambda_k, v_k its
    eigenpairs, se the standard errors), and along each parameter's regression line by ``POLISH_ALONG`` of its
    standard errors, ``x +- s se_i cov[:, i] / cov[i, i]`` (the others at their conditional means, the valley of
    the chi-square; a linear record of issue 24's model choice, seed 37, ended 63 above its minimum even from the
    truth, which lay 3.6 standard errors of the release time along that line, across one of the misfit's
    steps): one model evaluation each. A probe whose chi-square lies below the
    local quadratic ``chi2 + |J (y - x)|^2`` by at least ``POLISH_GAIN`` sees a lower piece; the fit
    restarts (full tolerance) from the lowest such probe and keeps the refit if its chi-square falls by at
    least ``POLISH_GAIN`` (less is within the noise of where the sampled steps fall); the round repeats from
    it, at most ``POLISH_ROUNDS`` times."""
    lo = np.array([lower.get(n, -math.inf) for n in names])
    hi = np.array([upper.get(n, math.inf) for n in names])
    for _ in range(POLISH_ROUNDS):
        x = np.asarray(res.x, dtype=float)
        J = np.asarray(res.jac, dtype=float)
        chi2 = 2.0 * res.cost
        try:
            cov, blind = identified_covariance(J)
        except np.linalg.LinAlgError:
            return res
        trials = []
        if "release_time" in names:
            i = names.index("release_time")
            for k in POLISH_SHIFTS:
                for sign in (-1.0, 1.0):
                    y = x.copy()
                    y[i] += sign * k * dt
                    trials.append(y)
        se = np.where(blind, 0.0, np.sqrt(np.clip(np.diag(cov), 0.0, None)))
        ok = se > 0.0
        for i in np.nonzero(ok)[0]:  # along each parameter's regression line: the others at their conditional
            slope = np.where(ok, cov[:, i] / cov[i, i], 0.0)  # means, where the chi-square's valley runs
            for step in POLISH_ALONG:
                trials.extend((x + step * se[i] * slope, x - step * se[i] * slope))
        if np.count_nonzero(ok) >= 2:
            w, v = np.linalg.eigh(cov[np.ix_(ok, ok)] / np.outer(se[ok], se[ok]))
            for k in range(1, min(POLISH_AXES, w.size) + 1):
                axis = np.zeros_like(x)
                axis[ok] = math.sqrt(max(float(w[-k]), 0.0)) * v[:, -k] * se[ok]
                for step in POLISH_STEPS:
                    trials.extend((x + step * axis, x - step * axis))
        best, best_chi2 = None, math.inf
        for y in trials:
            y = np.clip(y, lo, hi)
            r = residuals(y, names, values)
            probe = float(r @ r)
            if probe <= chi2 + float(np.sum((J @ (y - x)) ** 2)) - POLISH_GAIN and probe < best_chi2:
                best, best_chi2 = y, probe
        done = _restarted(res, best, solve, names, values)
        if done is None:
            return res
        res = done
    return res


def _restarted(res, best, solve, names, values):
    """The fit solved again from the probe ``best`` (None: no probe), where that lowers its chi-square by at least
    ``POLISH_GAIN`` (less is within the noise of where the sampled steps fall); else None."""
    if best is None:
        return None
    done = solve(names, values, best)
    return done if 2.0 * (res.cost - done.cost) >= POLISH_GAIN else None


#: The turning-point polish (:func:`_turn_polish`): rounds at most; where a probe puts the turning point, past the
#: sample it moves across (a share of the sampling interval); a channel's jump at a turning point below this many
#: of its noise levels is not a step.
TURN_ROUNDS, TURN_PAST, TURN_JUMP = 4, 0.05, 0.1


def _turn_times(motion, t_r: float) -> np.ndarray:
    """The turning points (reversals, the stick) of ``motion`` released at ``t_r`` [s, record time]."""
    turns = t_r + np.asarray(motion.reversal_times, dtype=float)[1:]
    return turns[np.isfinite(turns)]


def _least_move(cov: np.ndarray, G: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, float] | None:
    """The step of least chi-square (the local quadratic of covariance ``cov`` = (J^T J)^-1) that moves the linear
    functions with gradients ``G`` (a column each) by ``d``: ``cov G (G^T cov G)^-1 d``, and what it costs, ``d^T
    (G^T cov G)^-1 d``; None where the functions do not move independently."""
    A = G.T @ cov @ G
    try:
        if not np.linalg.cond(A) < 1e12:
            return None
        lam = np.linalg.solve(A, d)
    except np.linalg.LinAlgError:
        return None
    cost = float(d @ lam)
    if not (math.isfinite(cost) and cost > 0.0):
        return None
    return cov @ G @ lam, cost


def _turn_polish(res, names, values, solve, misfit, lower, upper):
    """Moves each turning point of the fit across the sample next to it where that sample's fit gains more than the
    move costs, restarts from there and keeps the refit where it fits better by ``POLISH_GAIN``.

    At a reversal the sliders' friction flips and the acceleration jumps (by 2 F_s / m), and at the stick it drops
    to zero: each sample of an acceleration channel that a turning point crosses is a step of the chi-square. The
    guarded Jacobian does not see the steps (by design, :meth:`_Misfit.jacobian`), so every solve ends at the
    smooth minimum of the piece it started in; where a turning point of the record lies just past a sample and the
    fit's lies before it, that sample's residual is the jump, and the piece with the turning point past the sample
    lies lower. Rigid Bouc-Wen records with sliders (2 F_s / m 2.5 noise levels of the accelerometer), released on a
    sample (0.5 s and 2.0 s, 12 noise seeds each; a turning point 0.5 ms past a sample): on 9 of 24 every start
    ended with it 0.8-2 ms early (its standard error about 1 ms) and the fit 2.4-9.5 above the piece past the
    sample, 7 of them certified (the polish's probes, a standard error and more along whole axes, move every turning
    point at once across its own samples and did not see it; the certificate's basins span 3 standard errors and
    count the piece as the basin's floor). Released off a sample the same: at 0.50893 s (the fourth turning point
    0.5 ms past a sample) 1 of 12 (2.8, certified); at 0.5037 s (none near one) none.

    For each turning point tau of the fit and the nearest sample t_k of a channel that jumps there, on either side,
    the sample's gain (its residual with the jump moved across it) is set against the cost of moving tau to
    ``TURN_PAST`` of a sampling interval past t_k at the least chi-square: ``delta^2 / (g^T C g)``, g = d tau / d
    theta by central differences of the motion over the Jacobian's steps, C = (J^T J)^-1, the probe ``x + delta C g
    / (g^T C g)`` (:func:`_least_move`; where that would take the release across a sample, the release is held at
    it as a second constraint: the acceleration jumps there by the pushed force over the mass). Probes predicted to
    gain ``POLISH_GAIN`` are evaluated (one motion each); the fit restarts from the lowest below the fit's
    chi-square by ``POLISH_GAIN``, ``TURN_ROUNDS`` rounds at most. One turning point a probe: a gain that needs two
    moved at once is not seen."""
    lo = np.array([lower.get(n, -math.inf) for n in names])
    hi = np.array([upper.get(n, math.inf) for n in names])
    rows = np.cumsum([0] + [c.t.size for c in misfit.channels])
    for _ in range(TURN_ROUNDS):
        x = np.asarray(res.x, dtype=float)
        chi2, r = 2.0 * float(res.cost), np.asarray(res.fun, dtype=float)
        p = _unpack(x, names, values)
        try:
            motion = misfit.motion(p)
        except ParameterError:
            return res
        turns = _turn_times(motion, p["release_time"])
        if turns.size == 0:
            return res
        since = turns - p["release_time"]  # each channel either side of the turn (a nanosecond: the value at the
        eta = 1e-9 * np.maximum(since, 1.0)  # turn is the one after it, a float's step before may be the same)
        after, before = motion.channels(since + eta), motion.channels(since - eta)
        wanted = []  # (turning point, its move, the gain predicted)
        for j, tau in enumerate(turns):
            for side in (1, -1):  # past the first sample at or after tau (it reads the value after the turn), or
                k = int(np.searchsorted(misfit.t_all, tau, side="left"))  # before the last one before it
                k = k if side > 0 else k - 1
                if not 0 <= k < misfit.t_all.size:
                    continue
                t_k = float(misfit.t_all[k])
                gain = 0.0
                for c, i0, sigma in zip(misfit.channels, rows[:-1], (misfit.sig[i] for i in rows[:-1]), strict=True):
                    jump = float(after[c.kind][j] - before[c.kind][j]) / sigma
                    i = int(np.searchsorted(c.t, t_k))
                    if abs(jump) < TURN_JUMP or i >= c.t.size or c.t[i] != t_k:
                        continue
                    now = r[i0 + i]  # later: the sample reads the value before the turn; earlier: after it
                    gain += now**2 - (now - side * jump) ** 2
                if gain > POLISH_GAIN:
                    wanted.append((j, t_k + side * TURN_PAST * misfit.dt - tau, gain))
        if not wanted:
            return res
        try:
            cov, blind = identified_covariance(np.asarray(res.jac, dtype=float))
        except np.linalg.LinAlgError:
            return res
        c = np.where(blind[:, None] | blind[None, :], 0.0, cov)
        grad = np.zeros((turns.size, len(names)))
        for i, n in enumerate(names):
            if n == "release_time":  # every turn moves with the release
                grad[:, i] = 1.0
                continue
            if n in misfit.rows_of or c[i, i] == 0.0:  # the zeros do not move the motion
                continue
            h = misfit.step(n, x[i])
            up, down = min(x[i] + h, hi[i]), max(x[i] - h, lo[i])
            moved = []
            for v in (up, down):
                try:
                    m = misfit.motion({**p, n: float(v)})
                except ParameterError:
                    m = None
                moved.append(_turn_times(m, p["release_time"]) if m is not None else None)
            if moved[0] is None or moved[1] is None or not up > down:
                grad[:, i] = math.nan
                continue
            common = min(moved[0].size, moved[1].size, turns.size)
            grad[:common, i] = (moved[0][:common] - moved[1][:common]) / (up - down)
            if moved[0].size != turns.size or moved[1].size != turns.size:
                grad[max(common - 1, 0):, i] = math.nan  # the stick came or went: the last turn is another
        best, best_chi2 = None, chi2 - POLISH_GAIN
        for j, delta, gain in wanted:
            g = grad[j]
            if not np.all(np.isfinite(g)):
                continue
            move = _least_move(c, g[:, None], np.array([delta]))
            if move is not None and "release_time" in names:
                # the release stays between the samples it lies between: there the acceleration jumps by the
                # pushed force over the mass (it often rests against a sample, :meth:`_Misfit.release_edge`)
                i = names.index("release_time")
                k = int(np.searchsorted(misfit.t_all, x[i], side="left"))
                if int(np.searchsorted(misfit.t_all, x[i] + move[0][i], side="left")) != k:
                    later = move[0][i] > 0.0
                    if not (0 <= (k if later else k - 1) < misfit.t_all.size):
                        continue
                    edge = float(misfit.t_all[k]) if later else float(np.nextafter(misfit.t_all[k - 1], math.inf))
                    move = _least_move(c, np.column_stack([g, np.eye(len(names))[i]]), np.array([delta, edge - x[i]]))
            if move is None or move[1] - gain > -POLISH_GAIN:
                continue
            y = np.clip(x + move[0], lo, hi)
            probe = misfit.residuals(y, names, values)
            value = float(probe @ probe)
            if value < best_chi2:
                best, best_chi2 = y, value
        done = _restarted(res, best, solve, names, values)
        if done is None:
            return res
        res = done
    return res


#: The step search (:func:`_step_search`): half-width of its box in standard errors, evaluations a run, runs.
STEP_BOX, STEP_EVALUATIONS, STEP_ROUNDS = 3.0, 400, 4


def _step_search(res, names, values, solve, residuals, lower, upper, seed: int):
    """A CMA-ES run on the whole record within ``STEP_BOX`` standard errors of the fit, restarted by least
    squares from its best point and kept where it fits better by ``POLISH_GAIN``; ``STEP_ROUNDS`` rounds.

    The misfit is piecewise smooth: a piece per sample that the release, a reversal or the stick crosses,
    and on an acceleration record each such crossing is a step (the acceleration jumps there). Within one
    basin the pieces form a staircase that a local search stops on, tens of chi-square above the basin's
    floor (an acceleration-only record: 87 above the fit started at the truth, though every parameter lay
    within its standard error of it), and the certificate counted the basin as reached. The evolution
    strategy needs no derivative and steps across them (``STEP_EVALUATIONS`` a run: about 0.4 s on a linear
    record of 12 000 samples). Run on records without a displacement channel: a displacement is continuous
    at every event, and where one is recorded its smooth misfit rules (the fits of x and x + a records reach
    the truth-started minimum without it, and on the benchmark's records it found nothing lower while it
    cost a linear fit 30% and a bilinear one 140% more)."""
    from .isolation_search import cma_es

    lo = np.array([lower.get(n, -math.inf) for n in names])
    hi = np.array([upper.get(n, math.inf) for n in names])
    for k in range(STEP_ROUNDS):
        x = np.asarray(res.x, dtype=float)
        try:
            cov, blind = identified_covariance(np.asarray(res.jac, dtype=float))
        except np.linalg.LinAlgError:
            return res
        se = np.where(blind, 0.0, np.sqrt(np.clip(np.diag(cov), 0.0, None)))
        se = np.where(np.isfinite(se), se, 0.0)
        if not np.any(se > 0.0):
            return res

        def point(u, x=x, se=se):
            return np.clip(x + (2.0 * np.asarray(u) - 1.0) * STEP_BOX * se, lo, hi)

        def chi2(u):
            r = residuals(point(u), names, values)
            return float(r @ r)

        u, best, _ = cma_es(chi2, np.full(x.size, 0.5), 0.5 / STEP_BOX, STEP_EVALUATIONS, seed + 7919 * (k + 1))
        if not best < 2.0 * res.cost - POLISH_GAIN:
            return res
        done = solve(names, values, point(u))
        if 2.0 * (res.cost - done.cost) < POLISH_GAIN:
            return res
        res = done
    return res


def _requiet(res, channels, noise, source, sig, names, values, solve, t_detected: float):
    """The noise levels from the quiet segment before the FITTED release, and the fit redone with them.

    The detected release lags the true one (a displacement leaves its rest quadratically: beyond 8 noise
    levels some 50 ms later), so the segment before the detected instant holds the first tens of ms of the
    motion and its scatter overstates the noise (displacement-only records: 14-20%). Once the fit has put
    the release at t_r, the levels are taken again from the samples before t_r (``_quiet_noise``); where one
    moves by more than 0.1% the weights change (in place, in ``sig``) and the fit restarts from its optimum.
    """
    if "release_time" not in names:
        return res
    t_fit = float(res.x[names.index("release_time")])
    if not t_fit < t_detected:
        return res
    changed, i = False, 0
    for ch in channels:
        if source[ch.name] == "pre-release segment":
            q = _quiet_noise(ch, t_fit)
            if q is not None and abs(q - noise[ch.name]) > 1e-3 * noise[ch.name]:
                noise[ch.name], changed = q, True
                sig[i:i + ch.t.size] = q
        i += ch.t.size
    return solve(names, values, res.x) if changed else res


def _profile_interval(name, names, est, lo_b, hi_b, se, target, solve, slope=None) -> tuple[float, float]:
    """The interval of ``name`` where the profile chi-square (others re-fitted) stays below ``target``.

    Each refit starts from the nearest one so far, moved along the correlations: the others by ``slope`` (their
    regression on ``name``, ``cov[other, name] / cov[name, name]``) times the step in ``name``. Where the record
    leaves a family of parameters exactly undetermined (a pendulum that sticks after one half-cycle: d0, the
    LVDT's zero and both friction levels shift together and the record does not change), that start lies on
    the family and the refit keeps its chi-square; from the unmoved start, the local refits of an
    ill-conditioned misfit ended short of the family and the interval of friction_slow left out values that
    give the same record (0.0044-0.0083 beside a truth of 0.02)."""
    others = [n for n in names if n != name]
    done = {est[name]: [est[n] for n in others]}  # refits so far: each starts from the nearest one
    slopes = np.array([(slope or {}).get(n, 0.0) for n in others])

    known: dict[float, float] = {}  # each value refitted once (brentq's bracket repeats the last two)

    def profile_chi2(value: float) -> float:
        if value in known:
            return known[value]
        base = dict(est)
        base[name] = value
        near = min(done, key=lambda v: abs(v - value))
        start = np.asarray(done[near]) + slopes * (value - near)
        # the chi-square is compared with a target ~ chi2 + 4: a relative tolerance of 1e-10 is ample
        res = solve(others, base, start, tol=1e-10)
        done[value] = list(res.x)
        known[value] = float(res.fun @ res.fun)
        return known[value]

    def edge(direction: int) -> float:
        bound = hi_b if direction > 0 else lo_b
        step = max(se, 1e-3 * abs(est[name]), 1e-12)
        inner = est[name]
        for _ in range(30):
            outer = inner + direction * step
            if (direction > 0 and outer >= bound) or (direction < 0 and outer <= bound):
                outer = bound
                if not math.isfinite(outer) or profile_chi2(outer) <= target:
                    return outer
                break
            if profile_chi2(outer) > target:
                break
            inner, step = outer, 2.0 * step
        else:
            return bound
        lo_v, hi_v = sorted((inner, outer))
        f_lo, f_hi = profile_chi2(lo_v) - target, profile_chi2(hi_v) - target
        if f_lo * f_hi > 0:  # the piecewise profile stepped over the target between two refits: the outer one
            return outer
        try:
            return brentq(lambda v: profile_chi2(v) - target, lo_v, hi_v, xtol=1e-3 * max(se, 1e-12))
        except ValueError:  # the refits (each from the nearest one so far) moved the ends' profile values
            # across the target: the outer end, the wider side (the model's profile has steps, issue 24's
            # Bouc-Wen record of seed 2403)
            return outer

    return edge(-1), edge(+1)


@dataclass(frozen=True, eq=False)
class IsolationPrecision:
    """The precision a fit of :func:`fit_isolation` to a record would have: the Cramer-Rao bound at the truth
    (SI units; :func:`predicted_isolation_errors`)."""

    model: str
    mass: float
    names: tuple[str, ...]
    """The fit's free parameters (its names: period, damping_ratio, friction, ..., d0, release_time,
    offset_<channel>)."""
    parameters: dict[str, float]
    """The truth at which the information is evaluated, every parameter (free and fixed)."""
    covariance: np.ndarray
    """``(J^T W J)^-1`` [SI^2], in the order of ``names`` (inf where it exceeds the float range)."""
    std_errors: dict[str, float]
    """inf for a parameter that has no effect on such a record."""
    correlation: np.ndarray
    condition_number: float
    units: dict[str, str]
    warnings: tuple[str, ...] = ()
    noise_scale: float = 1.0
    """The largest noise level s; ``unit_covariance`` is the covariance for the noise levels over s."""
    unit_covariance: np.ndarray | None = field(default=None, repr=False)

    def physical(self) -> dict[str, dict[str, Any]]:
        """The building's parameters with their predicted standard errors, keyed as the building's JSON
        (:func:`quickrelease.studies.building_analysis.analyse_building`'s ``isolation``): the model's, then the
        damper's, the sliders' friction and the rest.

        - linear, 2dof: ``period_s``;
        - bilinear: ``k1_N_m = m (2 pi / T1)^2`` and ``k2_N_m = (k2/k1) k1``, ``Fy_N``;
        - pendulum: ``period_s``, ``radius_m = g (T / 2 pi)^2``, ``friction_slow``, ``friction_fast``, ``rate_s_m``;
        - boucwen: ``period_s``, ``Kd_N_m = m (2 pi / T)^2``, ``Qd_N``, ``dy_m``, ``shape``;
        - the damper: ``damping_ratio`` (viscous) or ``damping_coefficient`` and ``damping_exponent`` (power);
        - ``friction_N`` (not the pendulum's), 2dof ``superstructure_period_s`` and
          ``superstructure_damping_ratio``, then ``d0_m``, ``release_time_s``, ``offset_<channel>`` and
          ``drift_<channel>``.

        The derived k1, k2, R and Kd by the delta method, ``se^2 = g^T C g`` with g their gradient in the fit's
        parameters and C the whole covariance (so k2 honours the correlation of k2/k1 and T1; R and Kd, functions
        of T alone, come out 2 R / T and 2 Kd / T times T's standard error). Each row is
        ``{"truth", "se", "relative_se" (None where the truth is 0 or a time on the record's clock), "unit"}``
        (parameters held fixed are left out; ``se`` inf where not determined; :meth:`summary` gives None)."""
        p, index = self.parameters, {n: i for i, n in enumerate(self.names)}

        def row(value: float, gradient: dict[str, float], unit_name: str, relative: bool = True) -> dict[str, Any]:
            g = np.zeros(len(self.names))
            for name, d in gradient.items():
                g[index[name]] = d
            if any(math.isinf(self.std_errors[name]) for name, d in gradient.items() if d != 0):
                se = math.inf
            else:
                unit = self.covariance / self.noise_scale / self.noise_scale if self.unit_covariance is None \
                    else self.unit_covariance
                with np.errstate(over="ignore"):
                    se = float(self.noise_scale * math.sqrt(max(float(g @ unit @ g), 0.0)))
            return {"truth": float(value), "se": se, "unit": unit_name,
                    "relative_se": se / abs(value) if relative and value != 0 else None}

        out: dict[str, dict[str, Any]] = {}
        keys: dict[str, str] = {}
        if self.model == "bilinear":
            if "period" in index or "stiffness_ratio" in index:
                T1, r = p["period"], p["stiffness_ratio"]
                k1 = self.mass * (2.0 * math.pi / T1) ** 2
                d_T = {"period": -2.0 * k1 / T1} if "period" in index else {}
                out["k1_N_m"] = row(k1, d_T, "N/m")
                out["k2_N_m"] = row(r * k1, {**{n: r * d for n, d in d_T.items()},
                                             **({"stiffness_ratio": k1} if "stiffness_ratio" in index else {})}, "N/m")
            keys["yield_force"] = JSON_KEYS["yield_force"]
        elif "period" in index:
            T = p["period"]
            out["period_s"] = row(T, {"period": 1.0}, self.units["period"])
            if self.model == "pendulum":  # R = g (T / 2 pi)^2: dR/dT = 2 R / T
                R = GRAVITY * (T / (2.0 * math.pi)) ** 2
                out["radius_m"] = row(R, {"period": 2.0 * R / T}, "m")
            elif self.model == "boucwen":  # Kd = m (2 pi / T)^2: dKd/dT = -2 Kd / T
                Kd = self.mass * (2.0 * math.pi / T) ** 2
                out["Kd_N_m"] = row(Kd, {"period": -2.0 * Kd / T}, "N/m")
        keys.update((name, key) for name, key in JSON_KEYS.items() if name not in ("period", "yield_force"))
        for name, key in keys.items():
            if name in index:
                out[key] = row(p[name], {name: 1.0}, self.units[name], relative=name != "release_time")
        for name in self.names:
            if name.startswith(("offset_", "drift_")):
                out[name] = row(p[name], {name: 1.0}, self.units[name])
        return out

    def summary(self) -> dict[str, Any]:
        corr = {f"{a}:{b}": float(self.correlation[i, j]) for i, a in enumerate(self.names)
                for j, b in enumerate(self.names) if j > i}
        return {"method": "Cramer-Rao bound: (J^T W J)^-1 at the truth, W = 1 / noise^2",
                "model": self.model,
                "parameters": {k: {kk: _finite(vv) if isinstance(vv, float) else vv for kk, vv in row.items()}
                               for k, row in self.physical().items()},
                "std_errors": {n: _finite(v) for n, v in self.std_errors.items()},
                "correlation": corr, "condition_number": _finite(self.condition_number),
                "warnings": list(self.warnings)}


def _finite(value: float) -> float | None:
    """A float for JSON: None where it is not finite (a standard error beyond the float range, or infinite)."""
    return float(value) if math.isfinite(value) else None


def predicted_isolation_errors(channels, mass: float, model: str, parameters: dict[str, float], *,
                               superstructure_mass: float | None = None,
                               fixed: tuple[str, ...] | list[str] = (), flexible: bool = False) -> IsolationPrecision:
    """The standard errors a fit of ``model`` (:func:`fit_isolation`, noise levels given) to records on these
    channels would have, at the true ``parameters``: the Cramer-Rao bound.

    The Fisher information of the weighted least-squares problem with Gaussian noise of known standard
    deviations sigma_i is ``I = J^T W J``, with J the derivatives of the channel models (the fit's own model
    and its guarded central differences, :class:`_Misfit`) with respect to the free parameters and
    ``W = diag(1 / sigma_i^2)``; the covariance is ``I^-1`` (:func:`quickrelease._lsq.jacobian_covariance`).
    Only the channels' sample times, noise levels and offset flags enter, not their values.

    Parameters
    ----------
    channels : sequence of BuildingChannel
        The record's channels, each with its ``noise`` given [SI].
    mass : float
        Mass on the isolators [kg].
    model : {"linear", "bilinear", "2dof", "pendulum", "boucwen"}
    parameters : dict
        The truth, in the fit's parameter names [SI]: period, damping_ratio (or, for the power-law damper,
        damping_coefficient and damping_exponent), friction (bilinear also stiffness_ratio, yield_force; 2dof
        superstructure_period, superstructure_damping_ratio; boucwen characteristic_strength,
        yield_displacement, shape; the pendulum friction_slow, friction_fast, rate [s/m] instead of friction),
        d0, release_time [s, record time], and offset_<channel> (default 0; they enter linearly).
    superstructure_mass : float, optional
        2dof, or a layer under a flexible superstructure (``flexible``): the roof mass [kg].
    fixed : sequence of str
        Parameters the fit would hold fixed (not estimated).
    flexible : bool
        The layer (bilinear, pendulum, boucwen) under a flexible superstructure, as ``fit_isolation(flexible=True)``:
        ``parameters`` hold superstructure_period and superstructure_damping_ratio too.
    """
    channels = list(channels)
    if not channels:
        raise ParameterError("channels", "none", "at least one channel of the isolation layer")
    if model not in FIT_MODELS:
        raise ParameterError("model", model, ", ".join(f"'{m}'" for m in FIT_MODELS))
    damping = "power" if "damping_exponent" in parameters else "viscous"
    flexible = bool(flexible) and model != "2dof"
    if flexible and model not in FLEXIBLE_MODELS:
        raise ParameterError("model", model, f"{', '.join(repr(m) for m in FLEXIBLE_MODELS)} with flexible=True "
                             "(the linear layer under a flexible superstructure is model='2dof', in closed form)")
    if (flexible or model == "2dof") and superstructure_mass is None:
        raise ParameterError("superstructure_mass", None, f"(0, mass) = (0, {float(mass):.6g}) kg (the "
                             f"{'2dof model' if model == '2dof' else 'flexible superstructure'} needs it)", "kg")
    if not (flexible or model == "2dof"):
        superstructure_mass = None
    for ch in channels:
        if ch.noise is None:
            raise ParameterError(f"{ch.name}.noise", None, "given (the noise weights the information)",
                                 CHANNEL_KINDS[ch.kind])
    all_names = _parameter_names(model, channels, damping, flexible)
    values = {n: 0.0 for n in all_names if n.startswith(("offset_", "drift_"))}
    values.update({n: float(v) for n, v in parameters.items() if n in all_names})
    missing = [n for n in all_names if n not in values]
    if missing:
        raise ParameterError("parameters", missing[0], ", ".join(all_names))
    unknown = sorted(set(fixed) - set(all_names))
    if unknown:
        raise ParameterError("fixed", unknown[0], ", ".join(all_names))
    names = [n for n in all_names if n not in fixed]
    lower, upper = _bounds(channels, values["release_time"], values["period"])
    # the noise levels relative to the largest, s: J (and so the information) stays in the float range for
    # noise levels of any size, and the covariance is s^2 times that of the relative levels
    s = max(float(c.noise) for c in channels)
    misfit = _Misfit(channels, {c.name: float(c.noise) / s for c in channels}, float(mass), model,
                     superstructure_mass, lower, upper, drift_origin=values["release_time"])
    J = misfit.jacobian(np.array([values[n] for n in names]), names, values)  # weighted: rows / (sigma_i / s)
    if not np.all(np.isfinite(J)):
        levels = ", ".join(f"{c.name} = {c.noise:.3g} {CHANNEL_KINDS[c.kind]}" for c in channels)
        raise ParameterError("noise", levels, "levels whose ratios keep the information J^T W J in the float range")
    unseen = [n for n, norm in zip(names, np.linalg.norm(J, axis=0), strict=True) if norm == 0.0]
    unit_cov = jacobian_covariance(J)
    with np.errstate(over="ignore"):
        cov = (unit_cov * s) * s
        se = s * np.sqrt(np.clip(np.diag(unit_cov), 0.0, None))
    for n in unseen:  # no information at all: not determined (the pseudo-inverse would say 0)
        se[names.index(n)] = math.inf
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = unit_cov / np.outer(np.sqrt(np.diag(unit_cov)), np.sqrt(np.diag(unit_cov)))
    corr = np.where(np.isfinite(corr), corr, 0.0)
    cond = float(np.linalg.cond(corr))
    warnings = [f"{n} has no effect on such a record: it is not determined" for n in unseen]
    if cond > CONDITION_WARNING:
        warnings.append(f"ill-conditioned (condition number of the correlations {cond:.2g}): some combination of "
                        "parameters is not determined by such a record")
    for n, s_ in zip(names, se, strict=True):
        if (n in PARAMETER_BOUNDS and n not in unseen and values[n] != 0
                and s_ / abs(values[n]) > PROFILE_RELATIVE_SE):
            warnings.append(f"{n} would be poorly determined (standard error {100 * s_ / abs(values[n]):.3g}% of the "
                            "truth)")
    units = {n: _unit(n, channels) for n in names}
    return IsolationPrecision(model=model, mass=float(mass), names=tuple(names), parameters=values, covariance=cov,
                              std_errors={n: float(v) for n, v in zip(names, se, strict=True)}, correlation=corr,
                              condition_number=cond, units=units, warnings=tuple(warnings), noise_scale=s,
                              unit_covariance=unit_cov)


def compare_models(fits) -> list[dict[str, Any]]:
    """AIC and BIC of fits of different models to the same record, best first, with their differences (each row's
    ``model`` the fit's :attr:`IsolationFit.label`: ``boucwen (flexible)`` beside ``boucwen``).

    The fits must share the channels and noise levels (known noise, ``absolute_sigma``) for the criteria
    to be comparable; a difference above about 10 is strong support for the lower one.
    """
    fits = list(fits)
    best_aic = min(f.aic for f in fits)
    best_bic = min(f.bic for f in fits)
    rows = [{"model": f.label, "parameters": len(f.names), "chi2": f.chi2, "aic": f.aic, "bic": f.bic,
             "delta_aic": f.aic - best_aic, "delta_bic": f.bic - best_bic,
             "whiteness_p": f.whiteness_p} for f in fits]
    return sorted(rows, key=lambda row: row["bic"])


#: Difference between the fit and the decay analysis, in combined standard errors, beyond which
#: :func:`decay_check` warns (the standard errors include the decay law's own misfit).
DECAY_CHECK_LIMIT = 5.0


def decay_check(fit: IsolationFit) -> dict[str, Any]:
    """The model-free decay analysis (:mod:`quickrelease.building.decay`) of the fit's displacement channel beside
    the fitted model: where they agree, and where they cannot.

    For the linear model the combined decrement law is exact, so the period, damping ratio and friction of
    the decay and of the fit estimate the same quantities: each row gives both values and their
    difference in units of the combined standard error (the fit's and the decay's, the two taken as
    independent, which overstates the spread a little since they share the record). The decay's standard
    errors come from the turning points' own errors (the channel's noise through the local fits), the
    residuals' correlation (each peak enters two half-cycles) and the law's misfit (scaled up by
    sqrt(chi2 / dof) where the peaks scatter more than their errors), and the friction's includes the
    stiffness' (from the period). Earlier versions took the standard errors from the scatter of 1 to 3
    residuals alone and left the period's error out of the friction's: on correct fits of short records
    they came out tens of times too small.

    A row whose difference exceeds :data:`DECAY_CHECK_LIMIT` is flagged (``disagrees``) and said in
    ``warnings``; notes say where the combined law misfits the peaks, and where another decrement law
    (quadratic or power-law damping) describes them clearly better (Delta AIC > 10). For the bilinear model
    no decay law exists (period and decrement change with the amplitude by themselves) and only the
    per-half-cycle equivalents are returned, with a note saying so.
    """
    from .decay import MISFIT_REDUCED_CHI2, analyse_decay

    xch = next((c for c in fit.channels if c.kind == "x"), None)
    if xch is None:
        return {"rows": [], "notes": ["no displacement channel: no decay analysis"], "warnings": []}
    analysis = analyse_decay(xch.t, xch.values - fit.zero(xch), release_time=fit.release_time,
                             noise=fit.noise[xch.name])
    out: dict[str, Any] = {"analysis": analysis.summary(fit.mass), "rows": [], "notes": [], "warnings": []}
    if fit.model == "bilinear":
        out["notes"].append("bilinear isolators follow no decay law: compare the equivalent period and damping "
                            "against the amplitude instead")
        return out
    if fit.model == "boucwen" or fit.damping == "power" or (
            fit.model == "pendulum" and fit.parameters.get("friction_fast") != fit.parameters.get("friction_slow")):
        out["notes"].append(f"the {fit.model} model{' with a power-law damper' if fit.damping == 'power' else ''} "
                            "follows no decay law of the linear model's form (its period, friction or damping change "
                            "with the amplitude or the velocity): compare the equivalent quantities per cycle "
                            "instead")
        return out
    if fit.flexible:
        out["notes"].append("the 2dof base decays in two coupled modes (and the roof can make the sliders stick "
                            "and slip again): the single-mode decay law does not hold; compare the equivalent "
                            "period and damping against the amplitude instead")
        return out
    if analysis.law is None:
        out["notes"].append("fewer than four half-cycles: no decay law")
        return out
    law = analysis.law
    if law.known_errors and law.dof > 0 and law.reduced_chi2 > MISFIT_REDUCED_CHI2:
        out["notes"].append(f"the combined decrement law misfits the turning points (reduced chi-square "
                            f"{law.reduced_chi2:.3g} on {law.dof} degrees of freedom): the decay's standard errors "
                            "are scaled up by its square root")
    aic = {f.name: f.aic for f in analysis.laws}
    best = analysis.best_law
    if best is not None and best.name in ("quadratic", "power") and aic.get("combined", math.inf) - best.aic > 10:
        out["notes"].append(f"the turning points follow the {best.name} decrement law better than the combined "
                            f"viscous and Coulomb law (AIC lower by {aic['combined'] - best.aic:.3g}): the model's "
                            "damping may not describe the isolators")
    pairs = {"period": (analysis.natural_period, analysis.period_se),
             "damping_ratio": (law.damping_ratio, law.damping_ratio_se),
             "friction": (analysis.friction_force(fit.mass), analysis.friction_force_se(fit.mass))}
    for name, (value, decay_se) in pairs.items():
        if name not in fit.estimates:
            continue
        se = math.hypot(fit.std_errors[name], decay_se if math.isfinite(decay_se) else 0.0)
        z = (float(value) - fit.estimates[name]) / se if se > 0 else math.nan
        row = {"parameter": name, "fit": fit.estimates[name], "decay": float(value), "decay_se": float(decay_se),
               "difference_in_se": z, "disagrees": bool(math.isfinite(z) and abs(z) > DECAY_CHECK_LIMIT)}
        out["rows"].append(row)
        if row["disagrees"]:
            out["warnings"].append(f"{name}: the decay analysis ({float(value):.6g}) and the fit "
                                   f"({fit.estimates[name]:.6g}) differ by {z:.3g} standard errors (the fit's and "
                                   "the decay law's, its misfit included)")
    return out
