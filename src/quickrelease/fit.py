"""Friction from measured time histories: a weighted nonlinear least-squares fit of the release model.

The paper identified F1 and F2 from two numbers (alpha_F, t_F) and remarks that measuring displacements
and accelerations on the device would have made the identification "much more reliable". Given a record
(:mod:`quickrelease.records`), :func:`fit_record` estimates F1 and F2, and optionally E_S, the mass factor
c, the release instant and a constant offset per channel, by minimizing

    sum over channels and samples of ((model + offset - measured) / sigma_channel)^2

(plus, when the case gives ``[observations]`` with a scatter, the two stop observations weighted by
their standard deviations) with scipy's bounded ``least_squares`` (friction >= 0). The model is the energy
solution (Eq. 9-10) at the sample times, at rest before the release and after the stop; within the motion
each channel is interpolated from a table built per parameter vector and checked to 1e-11 of the channel's
range (:mod:`quickrelease.records`), so a model evaluation costs time linear in the record. The noise level
sigma of each channel is given in the case file or estimated from the record's pre-release segment (the
device at rest).

Uncertainty: the covariance of the estimates is ``(J^T J)^-1`` (J the Jacobian of the weighted
residuals at the solution), scaled by the reduced chi-square unless ``absolute_sigma``; standard errors,
95% intervals (Student t) and the correlation matrix follow. A fit whose F1 and F2 are nearly
indistinguishable (the data fix only their combined dissipation, Eq. 8) is flagged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import dynamics
from ._lsq import jacobian_covariance
from .case import Case, FitOptions
from .device import Device
from .display import Summarised
from .errors import InfeasibleObservationError, QuickReleaseError
from .records import (
    DISPLACEMENT_CHANNELS,
    Record,
    RecordError,
    detect_release,
    load_record,
    release_channels,
)
from .solvers import FirstIntegral

__all__ = ["FitResult", "fit_record", "observation_sigma", "CORRELATION_WARNING", "RELATIVE_SE_WARNING"]

#: |correlation(F1, F2)| above which a poorly determined F1 or F2 is explained as indistinguishable from the other.
CORRELATION_WARNING = 0.99
#: Relative standard error above which an estimate is reported as poorly determined.
RELATIVE_SE_WARNING = 0.25
#: Condition number of the correlation matrix above which the fit is reported as ill-conditioned.
CONDITION_WARNING = 1e8

_UNITS = {"F1": "N", "F2": "N", "energy": "J", "mass_factor": "-", "release_time": "s"}


@dataclass(frozen=True, eq=False, repr=False)
class FitResult(Summarised):
    """Estimates, uncertainties and diagnostics of a fit to a measured record (SI units)."""

    names: tuple[str, ...]
    """Estimated parameters, in order: F1, F2, then energy, mass_factor, release_time, offset_<channel>."""
    estimates: dict[str, float]
    std_errors: dict[str, float]
    ci95: dict[str, tuple[float, float]]
    """95% confidence intervals (Student t); friction intervals are cut at 0."""
    correlation: np.ndarray
    """Correlation matrix of the estimates, in the order of ``names``."""
    condition_number: float
    """Of the correlation matrix: large when some combination of parameters is not determined."""
    fixed: dict[str, float]
    """Model inputs held fixed: E_S, c, alpha0, release time when not estimated."""
    noise: dict[str, float]
    """Noise standard deviation of each channel used as its weight [SI]."""
    noise_source: dict[str, str]
    """``"given"`` or ``"pre-release segment"`` per channel."""
    residual_rms: dict[str, float]
    """RMS of (model - measured) per channel [SI unit of the channel]."""
    samples: dict[str, int]
    """Samples used per channel."""
    chi2_reduced: float | None
    """Chi-square over the degrees of freedom (None without any: e.g. two stop observations, two unknowns)."""
    dof: int
    converged: bool
    message: str
    nfev: int
    start: dict[str, float]
    """Start values of the estimated parameters."""
    start_source: str
    """How the start values were found."""
    stop_time: float
    """t_F of the fitted model [s]."""
    alpha_final: float
    """alpha_F of the fitted model [rad]."""
    stopped_by: str
    warnings: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    """What was found reading the record (missing samples, dropped rows)."""
    device: Device | None = field(default=None, repr=False)
    """The device (for model curves)."""
    record: Record | None = field(default=None, repr=False)
    fitted: dict[str, np.ndarray] = field(default_factory=dict, repr=False)
    """Model (with offset) at each channel's sample times."""
    observations: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    """Stop observations used as data: name -> (observed, sigma, fitted)."""

    @property
    def F1(self) -> float:
        return self.estimates["F1"]

    @property
    def F2(self) -> float:
        return self.estimates["F2"]

    @property
    def release_time(self) -> float | None:
        """The release instant on the record's clock (estimated or fixed) [s]."""
        if "release_time" in self.estimates:
            return self.estimates["release_time"]
        return self.fixed.get("release_time")

    @property
    def energy(self) -> float:
        return self.estimates["energy"] if "energy" in self.estimates else self.fixed["energy"]

    @property
    def mass_factor(self) -> float:
        return self.estimates["mass_factor"] if "mass_factor" in self.estimates else self.fixed["mass_factor"]

    def release(self) -> FirstIntegral:
        """The energy solution of the fitted release."""
        d = self.device
        return FirstIntegral(self.energy, self.fixed["alpha0"], self.F1, self.F2, d.m1, d.m2, d.L1,
                             self.mass_factor)

    def model_curves(self, n: int = 2000) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """The fitted model (with offsets) of every channel on a fine grid over the record [s, SI] (each
        channel with the sampling window of its own time axis)."""
        if self.record is None:
            return np.empty(0), {}
        rec = self.record
        t = np.linspace(min(float(rec.t[0]), *(float(ch.t[0]) for ch in rec.channels.values())),
                        max(float(rec.t[-1]), rec.end), n)
        offsets = self.offsets()
        out = {}
        for name, ch in rec.channels.items():
            curve = release_channels([name], t, self.release_time, self.release(), ch.sampling_interval(rec.t))
            out[name] = curve[name] + offsets.get(name, 0.0)
        return t, out

    def offsets(self) -> dict[str, float]:
        return {n.removeprefix("offset_"): v for n, v in self.estimates.items() if n.startswith("offset_")}

    def summary(self) -> dict[str, Any]:
        """JSON-ready summary: the keys of ``quickrelease fit --json``."""
        def pair(name):
            lo, hi = self.ci95[name]
            return [lo, hi]

        corr = {f"{a}:{b}": float(self.correlation[i, j]) for i, a in enumerate(self.names)
                for j, b in enumerate(self.names) if j > i}
        out: dict[str, Any] = {
            "F1_N": self.F1, "F2_N": self.F2,
            "F1_se_N": self.std_errors["F1"], "F2_se_N": self.std_errors["F2"],
            "F1_ci95_N": pair("F1"), "F2_ci95_N": pair("F2"),
            "release_time_s": self.release_time,
            "release_time_se_s": self.std_errors.get("release_time"),
            "stored_energy_J": self.energy, "mass_factor": self.mass_factor,
            "stop_time_s": self.stop_time, "alpha_final_rad": self.alpha_final, "stopped_by": self.stopped_by,
            "residual_rms": self.residual_rms, "noise": self.noise, "noise_source": self.noise_source,
            "samples": self.samples, "offsets": self.offsets(),
            "estimates": self.estimates, "std_errors": self.std_errors,
            "ci95": {k: list(v) for k, v in self.ci95.items()},
            "correlation": corr, "condition_number": self.condition_number,
            "chi2_reduced": self.chi2_reduced, "dof": self.dof,
            "converged": self.converged, "message": self.message, "nfev": self.nfev,
            "start": self.start, "start_source": self.start_source,
            "warnings": list(self.warnings), "notes": list(self.notes),
        }
        if self.observations:
            out["observations"] = {k: {"observed": o, "sigma": s, "fitted": f}
                                   for k, (o, s, f) in self.observations.items()}
        return out


def observation_sigma(case: Case) -> dict[str, float]:
    """Standard deviations of the stop observations given with a scatter (normal: std; uniform: width/sqrt(12))."""
    out = {}
    for name in ("alpha_final", "stop_time"):
        dist = case.uncertainty.get(name)
        if dist is not None:
            out[name] = dist.scale if dist.kind == "normal" else dist.scale / math.sqrt(12.0)
    return out


class _Problem:
    """The data and parameter layout of one fit."""

    def __init__(self, case: Case, record: Record | None, options: FitOptions) -> None:
        self.case = case
        self.record = record
        self.options = options
        d = case.device
        self.m1, self.m2, self.L1 = d.m1, d.m2, d.L1
        self.names: list[str] = ["F1", "F2"]
        if options.estimate_energy:
            self.names.append("energy")
        if options.estimate_mass_factor:
            self.names.append("mass_factor")
        self.fixed: dict[str, float] = {"energy": case.stored_energy, "mass_factor": case.mass_factor,
                                        "alpha0": case.alpha0}
        self.channels = dict(record.channels) if record is not None else {}
        self.window = record.sampling_interval() if record is not None else 0.0
        if record is not None:
            if options.estimate_release_time:
                self.names.append("release_time")
            elif record.release_time is None:
                raise RecordError(f"{record.file}: the release instant is fixed ([fit] estimate_release_time = "
                                  "false) but not given: set [record] release_time")
            else:
                self.fixed["release_time"] = record.release_time
            self.names += [f"offset_{n}" for n, ch in self.channels.items() if ch.spec.offset]
        self.obs = {}
        if options.use_observations:
            sig = observation_sigma(case)
            if sig and not case.has_observations:
                raise QuickReleaseError(f"{case.source}: an observation has a scatter but [observations] is "
                                        "incomplete")
            for name, s in sig.items():
                if s > 0:
                    self.obs[name] = (float(getattr(case, name)), s)
        if record is None and not self.obs:
            raise QuickReleaseError(f"{case.source}: nothing to fit: give a [record], or [observations] with a "
                                    "scatter (e.g. stop_time = {value = \"1.05 s\", std = \"0.01 s\"})")
        self.index = {n: i for i, n in enumerate(self.names)}
        #: (channels, time axis, sampling window) per time axis: the record's, and each channel's own
        self.groups: list[tuple[list[str], np.ndarray, float]] = []
        if record is not None:
            shared = [n for n, ch in self.channels.items() if ch.own_axis is None]
            if shared:
                self.groups.append((shared, record.t, self.window))
            self.groups += [([n], ch.own_axis, ch.sampling_interval(record.t)) for n, ch in self.channels.items()
                            if ch.own_axis is not None]
        self.sigma: dict[str, float] = {}
        self.sigma_source: dict[str, str] = {}
        #: a sampling window [s] the rate channels are modelled with when it is wider than their own: the
        #: first stages of the fit (:func:`_smoothing_windows`); 0 for the fit proper
        self.smoothing = 0.0
        #: per time axis, the rows a coarse stage evaluates and each channel's positions among them; and each
        #: channel's stride (:meth:`smooth`); None and {} for the fit proper
        self.sub: list[tuple[np.ndarray, dict[str, np.ndarray]]] | None = None
        self.sel: dict[str, int] = {}

    def values(self, x: np.ndarray) -> dict[str, float]:
        v = dict(self.fixed)
        v.update({n: float(x[i]) for i, n in enumerate(self.names)})
        return v

    def release(self, v: dict[str, float]) -> FirstIntegral:
        return FirstIntegral(v["energy"], v["alpha0"], v["F1"], v["F2"], self.m1, self.m2, self.L1,
                             v["mass_factor"])

    def model(self, x: np.ndarray) -> tuple[dict[str, np.ndarray], FirstIntegral]:
        """Model values (with offsets) at each channel's samples, and the release."""
        v = self.values(x)
        fi = self.release(v)
        out: dict[str, np.ndarray] = {}
        if self.record is not None:
            for g, (names, t, window) in enumerate(self.groups):  # one time axis: one evaluation of the model
                if self.sub is None:
                    full = release_channels(names, t, v["release_time"], fi, window)
                    for name in names:
                        out[name] = full[name][self.channels[name].index] + v.get(f"offset_{name}", 0.0)
                    continue
                rows, pos = self.sub[g]
                full = release_channels(names, t[rows], v["release_time"], fi, max(window, self.smoothing))
                for name in names:
                    out[name] = full[name][pos[name]] + v.get(f"offset_{name}", 0.0)
        return out, fi

    def smooth(self, width: float) -> None:
        """Model the rate channels with a sampling window of ``width`` [s] (0: their own) and use every k-th
        sample of each time axis, k = floor(width / (2 Delta)) (Delta its sampling interval): a coarse stage
        of the fit (:func:`_smoothing_windows`)."""
        self.smoothing = width
        self.sub, self.sel = None, {}
        if width <= 0.0:
            return
        self.sub = []
        for names, _t, window in self.groups:
            k = max(1, int(width / (2.0 * window))) if window > 0.0 else 1
            picked = {name: self.channels[name].index[::k] for name in names}
            rows = np.unique(np.concatenate(list(picked.values())))
            self.sub.append((rows, {name: np.searchsorted(rows, r) for name, r in picked.items()}))
            self.sel.update({name: k for name in names})

    def residuals(self, x: np.ndarray) -> np.ndarray:
        model, fi = self.model(x)
        parts = [(model[n] - ch.values[::self.sel.get(n, 1)]) / self.sigma[n] for n, ch in self.channels.items()]
        if self.obs:
            fitted = {"alpha_final": fi.alpha_final, "stop_time": fi.stop_time()}
            parts.append(np.array([(fitted[n] - o) / s for n, (o, s) in self.obs.items()]))
        return np.concatenate(parts)

    def cost(self, x: np.ndarray) -> float:
        r = self.residuals(x)
        return float(r @ r)


def _rest_value(name: str, alpha0: float) -> float:
    return alpha0 if name == "alpha" else 0.0


#: Smallest noise of a channel relative to its largest value: about 50 ulp of double precision. A smaller
#: noise (e.g. 1e-300 m) would weight residuals that are rounding errors, and overflow the Jacobian.
NOISE_FLOOR = 1e-14


def _noise(problem: _Problem, t_release: float) -> None:
    """Each channel's sigma: given, or the scatter of its pre-release samples (at rest), and at least
    :data:`NOISE_FLOOR` times the channel's largest value."""
    rec = problem.record
    for name, ch in problem.channels.items():
        if ch.spec.noise is not None:
            problem.sigma[name], problem.sigma_source[name] = ch.spec.noise, "given"
            continue
        quiet = ch.values[ch.t < t_release - 3.0 * ch.sampling_interval(rec.t)]
        if quiet.size < 10:
            raise RecordError(f"{rec.file}: column {ch.spec.column!r} (channel {name}): only {quiet.size} samples "
                              f"before the release at {t_release:.4g} s, too few to estimate its noise: give "
                              "its noise in [record.channels]")
        s = float(np.std(quiet, ddof=1))
        if not s > 0:
            raise RecordError(f"{rec.file}: column {ch.spec.column!r} (channel {name}): no scatter before the "
                              "release, so no noise level to weight it by: give its noise in [record.channels]")
        problem.sigma[name], problem.sigma_source[name] = s, "pre-release segment"
    for name, ch in problem.channels.items():
        floor = max(NOISE_FLOOR * float(np.max(np.abs(ch.values))), 1e-150)
        if not problem.sigma[name] >= floor:
            raise RecordError(f"{rec.file}: column {ch.spec.column!r} (channel {name}): noise = "
                              f"{problem.sigma[name]:.3g} ({problem.sigma_source[name]}) is below {floor:.3g}, "
                              f"{NOISE_FLOOR:g} x the largest value: weights of 1/noise would be set by rounding")


def _offset_starts(problem: _Problem, t_release: float) -> dict[str, float]:
    out = {}
    rec = problem.record
    for name, ch in problem.channels.items():
        if not ch.spec.offset:
            continue
        quiet = ch.values[ch.t < t_release - 2.0 * ch.sampling_interval(rec.t)]
        base = float(np.mean(quiet)) if quiet.size else float(ch.values[0])
        out[f"offset_{name}"] = base - _rest_value(name, problem.case.alpha0)
    return out


def _read_stop(problem: _Problem, t_release: float, offsets: dict[str, float]) -> tuple[float, float] | None:
    """alpha_F and t_F read off a displacement channel that ends at rest, or None."""
    a0, L1 = problem.case.alpha0, problem.L1
    for name in DISPLACEMENT_CHANNELS:
        ch = problem.channels.get(name)
        if ch is None:
            continue
        y = ch.values - offsets.get(f"offset_{name}", 0.0)
        n_end = max(5, y.size // 20)
        final = float(np.median(y[-n_end:]))
        if name == "alpha":
            aF = final
        elif name == "u":
            c = math.cos(a0) - final / L1
            aF = math.acos(c) if -1.0 < c < 1.0 else float("nan")
        else:
            s = math.sin(a0) + final / L1
            aF = math.asin(s) if -1.0 < s < 1.0 else float("nan")
        if not (a0 < aF < 0.5 * math.pi):
            continue
        rest = _rest_value(name, a0)
        level = rest + 0.995 * (final - rest)
        reached = np.nonzero((ch.t > t_release) & ((y - level) * np.sign(final - rest) >= 0))[0]
        if not reached.size:
            continue
        return aF, float(ch.t[reached[0]]) - t_release
    return None


def _read_stop_time(problem: _Problem, t_release: float) -> float | None:
    """t_F read off an acceleration channel: where it last departs from its final rest level, or None.

    At a friction stop the model's acceleration drops from its friction value to 0 at once, a jump of
    many noise levels that dates the stop to a sample."""
    for name in ("a_head", "a_hinge"):
        ch = problem.channels.get(name)
        if ch is None:
            continue
        n_end = max(5, ch.values.size // 20)
        level = float(np.median(ch.values[-n_end:]))
        away = np.nonzero((np.abs(ch.values - level) > 6.0 * problem.sigma[name]) & (ch.t > t_release))[0]
        if away.size and away[-1] < ch.values.size - n_end:
            return float(ch.t[away[-1]]) + 0.5 * ch.sampling_interval(problem.record.t) - t_release
    return None


def _start(problem: _Problem) -> tuple[np.ndarray, str]:
    """Start values: the release instant and offsets from the pre-release segment, friction from the stop
    observations (case file or read off the record) and the best of a scan along the line of Eq. 13."""
    from .identify import identify_friction

    case = problem.case
    x = np.zeros(len(problem.names))
    fixed = {"energy": problem.fixed["energy"], "mass_factor": problem.fixed["mass_factor"]}
    for name in ("energy", "mass_factor"):
        if name in problem.index:
            x[problem.index[name]] = fixed[name]
    t_release = 0.0
    if problem.record is not None:
        rec = problem.record
        t_release = rec.release_time if rec.release_time is not None else detect_release(rec)
        if "release_time" in problem.index:
            x[problem.index["release_time"]] = t_release
        _noise(problem, t_release)
        for name, value in _offset_starts(problem, t_release).items():
            x[problem.index[name]] = value
    E, c = fixed["energy"], fixed["mass_factor"]
    a0, L1 = case.alpha0, problem.L1
    candidates: list[tuple[float, float, str]] = []
    stops: list[tuple[float, float | None, str]] = []
    if case.has_observations:
        stops.append((case.alpha_final, case.stop_time, "[observations]"))
    if problem.record is not None:
        read = _read_stop(problem, t_release, {n: x[problem.index[n]] for n in problem.names
                                               if n.startswith("offset_")})
        if read is not None:
            stops.append((read[0], read[1], "read off the record"))
    for aF, tF, how in stops:
        lim = dynamics.friction_limits(E, a0, aF, L1)
        try:
            ident = identify_friction(a0, aF, tF, stored_energy=E, device=case.device, mass_model=c)
            candidates.append((ident.F1, ident.F2, f"stop observations ({how})"))
        except (InfeasibleObservationError, QuickReleaseError):
            pass
        for lam in np.linspace(0.1, 0.9, 9):
            candidates.append((lam * float(lim["F1_max"]), (1 - lam) * float(lim["F2_max"]),
                               f"scan along Eq. 13 with alpha_F {how}"))
    if not stops:  # no final angle to read: scan final angles too
        t_read = _read_stop_time(problem, t_release) if problem.record is not None else None
        for aF in a0 + (0.5 * math.pi - a0) * np.linspace(0.04, 0.96, 24):
            if t_read is not None:  # on each line of Eq. 13, the point that stops at the time read
                try:
                    ident = identify_friction(a0, aF, t_read, stored_energy=E, device=case.device, mass_model=c)
                    candidates.append((ident.F1, ident.F2, "scan over alpha_F with t_F read off the record"))
                except (InfeasibleObservationError, QuickReleaseError):
                    pass
                continue
            lim = dynamics.friction_limits(E, a0, aF, L1)
            for lam in (0.1, 0.3, 0.5, 0.7, 0.9):
                candidates.append((lam * float(lim["F1_max"]), (1 - lam) * float(lim["F2_max"]),
                                   "scan over alpha_F and the line of Eq. 13"))
        if not candidates:
            raise RecordError(f"{problem.record.file}: no start values: the stop time read off the record, "
                              f"{t_read:.4g} s after the release, fits no final angle; give [observations]")
    best, how_best = math.inf, ""
    for F1, F2, how in candidates:
        x[0], x[1] = F1, F2
        cost = problem.cost(x)
        if cost < best:
            best, keep, how_best = cost, (F1, F2), how
    x[0], x[1] = keep
    return x, how_best


#: The first stage's window as a fraction of the motion's duration t_F, and the ratio between stages.
SMOOTHING_START, SMOOTHING_RATIO = 1.0 / 256.0, 8.0


def _smoothing_windows(problem: _Problem, x0: np.ndarray) -> list[float]:
    """Sampling windows [s] of the stages that precede the fit proper, widest first (none for a coarse record).

    A rate channel's model jumps at the release (velocity, acceleration) and at the stop (acceleration): the
    window spreads each jump over +-Delta, so a sample's residual depends on where the jump lies only while
    it is within Delta of it. Gauss-Newton then sees the misplacement of a jump through the one or two
    samples in transition and moves the jump by a few samples per iteration: the iteration count grew with
    the number of samples between the start's stop and the fitted stop (1e4 rows: 47 model evaluations,
    3e4: 119, 1e5: 364 from a start 10% off in F1 and F2; with the stages 20, 27, 28, and 31 at 1e6).
    Fitting first with a window of t_F / 256, then 8 times narrower per stage until within 4 Delta of the
    record's own, keeps every stage within a few windows of its optimum: the count of stages grows with
    log(rate), the iterations per stage do not. A stage with window W uses every floor(W / 2 Delta)-th
    sample (a decimation that keeps a few samples on each spread jump), so it costs little. The fit proper
    (window Delta, every sample) then starts within a few samples of its optimum.
    """
    from .records import RATE_OF

    if problem.record is None or not any(n in RATE_OF for n in problem.channels):
        return []
    t_F = problem.release(problem.values(x0)).stop_time()
    delta = min(w for _, _, w in problem.groups)
    if not (math.isfinite(t_F) and t_F > 0.0 and delta > 0.0):
        return []
    out, w = [], SMOOTHING_START * t_F
    while w > 4.0 * delta:
        out.append(w)
        w /= SMOOTHING_RATIO
    return out


def fit_record(case: Case, record: Record | None = None, *, options: FitOptions | None = None) -> FitResult:
    """Fit the release model to a measured record (and/or stop observations with a scatter).

    Parameters
    ----------
    case : Case
        The test: device, E_S, alpha0, mass model; ``[record]`` (read here unless ``record`` is given),
        ``[fit]`` options, and optionally ``[observations]``.
    record : Record, optional
        An already loaded record (default: ``load_record(case.record)`` when the case has one).
    options : FitOptions, optional
        Override the case's ``[fit]`` table.

    Returns
    -------
    FitResult

    Raises
    ------
    RecordError
        For an unusable record, or one that ends before the fitted model stops.
    QuickReleaseError
        When there is nothing to fit.
    """
    from scipy.optimize import least_squares
    from scipy.special import stdtrit

    options = options or case.fit
    if record is None and case.record is not None:
        record = load_record(case.record)
    problem = _Problem(case, record, options)
    x0, how = _start(problem)
    lower = np.full(x0.size, -np.inf)
    upper = np.full(x0.size, np.inf)
    lower[0] = lower[1] = 0.0
    for name in ("energy", "mass_factor"):
        if name in problem.index:
            lower[problem.index[name]] = 1e-9 * x0[problem.index[name]]
    if "release_time" in problem.index:
        lower[problem.index["release_time"]] = float(record.t[0])
        upper[problem.index["release_time"]] = float(record.t[-1])
    x0 = np.clip(x0, lower, upper)
    x_stage, nfev = x0, 0
    for w in _smoothing_windows(problem, x0):  # coarse to fine: see _smoothing_windows
        problem.smooth(w)
        stage = least_squares(problem.residuals, x_stage, bounds=(lower, upper), x_scale="jac", method="trf",
                              xtol=1e-6, ftol=1e-6, gtol=1e-6, max_nfev=50 * x0.size)
        x_stage, nfev = stage.x, nfev + stage.nfev
    problem.smooth(0.0)
    if not problem.cost(x_stage) <= problem.cost(x0):  # kept only where they lower the misfit of the fit proper
        x_stage = x0
    res = least_squares(problem.residuals, x_stage, bounds=(lower, upper), x_scale="jac", method="trf",
                        xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=200 * x0.size)
    x = res.x
    r = res.fun
    nfev += int(res.nfev)
    J = res.jac
    m, p = J.shape
    dof = m - p
    chi2 = float(r @ r)
    chi2_red = chi2 / dof if dof > 0 else None
    cov = jacobian_covariance(J)  # columns scaled first: F1, F2 [N], E_S [J], c, t_r [s], offsets
    if not options.absolute_sigma and chi2_red is not None:
        cov = cov * chi2_red
    se = np.sqrt(np.maximum(np.diag(cov), 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        corr = cov / np.outer(se, se)
    corr = np.where(np.isfinite(corr), corr, 0.0)
    np.fill_diagonal(corr, 1.0)
    cond = float(np.linalg.cond(corr))
    q = float(stdtrit(dof, 0.975)) if dof > 0 else 1.959963984540054
    names = tuple(problem.names)
    est = {n: float(x[i]) for i, n in enumerate(names)}
    ses = {n: float(se[i]) for i, n in enumerate(names)}
    ci = {}
    for n in names:
        lo, hi = est[n] - q * ses[n], est[n] + q * ses[n]
        if n in ("F1", "F2", "energy", "mass_factor"):
            lo = max(lo, 0.0)
        ci[n] = (lo, hi)
    model, fi = problem.model(x)
    t_stop = fi.stop_time()
    values = problem.values(x)
    if record is not None and values["release_time"] + t_stop > record.end:
        raise RecordError(f"{record.file}: the record ends at {record.end:.4g} s, before the device stops: "
                          f"release at {values['release_time']:.4g} s + t_F {t_stop:.4g} s = "
                          f"{values['release_time'] + t_stop:.4g} s; record past the stop")
    rms = {n: float(np.sqrt(np.mean((model[n] - ch.values) ** 2))) for n, ch in problem.channels.items()}
    fitted_obs = {"alpha_final": fi.alpha_final, "stop_time": t_stop}
    obs = {n: (o, s, float(fitted_obs[n])) for n, (o, s) in problem.obs.items()}
    warns = _warnings(names, est, ses, corr, cond, x, lower, upper, problem)
    fixed = {k: v for k, v in problem.fixed.items() if k not in est}
    return FitResult(
        names=names, estimates=est, std_errors=ses, ci95=ci, correlation=corr, condition_number=cond,
        fixed=fixed, noise=dict(problem.sigma), noise_source=dict(problem.sigma_source), residual_rms=rms,
        samples={n: int(ch.values.size) for n, ch in problem.channels.items()},
        chi2_reduced=chi2_red, dof=dof, converged=bool(res.success), message=str(res.message), nfev=nfev,
        start={n: float(x0[i]) for i, n in enumerate(names)}, start_source=how, stop_time=float(t_stop),
        alpha_final=float(fi.alpha_final), stopped_by=fi.stopped_by, warnings=tuple(warns),
        notes=tuple(record.notes) if record is not None else (), device=case.device, record=record, fitted=model,
        observations=obs,
    )


def _warnings(names, est, ses, corr, cond, x, lower, upper, problem) -> list[str]:
    out = []
    r12 = float(corr[names.index("F1"), names.index("F2")])
    for n in ("F1", "F2"):
        if est[n] > 0 and ses[n] > RELATIVE_SE_WARNING * est[n]:
            text = (f"{n} is poorly determined: standard error {ses[n]:.3g} N is {100 * ses[n] / est[n]:.0f}% of "
                    f"the estimate {est[n]:.4g} N")
            if abs(r12) > CORRELATION_WARNING:
                text += (f"; F1 and F2 are nearly indistinguishable (correlation {r12:+.4f}): the data fix mainly "
                         "their combined dissipation (Eq. 8), and a channel that follows the motion over time "
                         "(u, v or alpha) would separate them")
            out.append(text)
    if cond > CONDITION_WARNING:
        out.append(f"ill-conditioned: the correlation matrix of the estimates has condition number {cond:.3g}")
    for i, n in enumerate(names):
        if x[i] <= lower[i] or x[i] >= upper[i]:
            out.append(f"{n} = {x[i]:.6g} is at its bound: its interval is not reliable")
    if problem.record is None:
        out.append("only the stop observations are used: two data for two unknowns, so the intervals reflect "
                   "their stated scatter alone and no misfit can show")
    return out

