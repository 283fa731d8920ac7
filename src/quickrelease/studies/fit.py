"""Friction from measured time histories: a weighted nonlinear least-squares fit of the release model.

The paper identified F1 and F2 from two numbers (alpha_F, t_F) and remarks that measuring displacements
and accelerations on the device would have made the identification "much more reliable". Given a record
(:mod:`quickrelease.io.records`), :func:`fit_record` estimates F1 and F2, and optionally E_S, the mass factor
c, the release instant and a constant offset per channel, by minimizing

    sum over channels and samples of ((model + offset - measured) / sigma_channel)^2

(plus, when the case gives ``[observations]`` with a scatter, the two stop observations weighted by
their standard deviations) with scipy's bounded ``least_squares`` (friction >= 0). The model is the energy
solution (Eq. 9-10) at the sample times, at rest before the release and after the stop; within the motion
each channel is interpolated from a table built per parameter vector and checked to 1e-11 of the channel's
range (:mod:`quickrelease.io.records`), so a model evaluation costs time linear in the record. The noise level
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

from .._lsq import identified_covariance
from .._results import Summarised
from ..device import dynamics
from ..device.identify import identify_friction
from ..device.parameters import Device
from ..device.solvers import FirstIntegral
from ..errors import InfeasibleObservationError, QuickReleaseError
from ..io.case import Case, FitOptions
from ..io.export import jsonable
from ..io.records import (
    DISPLACEMENT_CHANNELS,
    NOISE_FLOOR,
    Record,
    RecordError,
    ReleaseChannels,
    check_release_time,
    detect_release,
    load_record,
    noise_floor,
    record_origin,
    release_channels,
    shifted_record,
)

__all__ = ["FitResult", "fit_record", "load_case_record", "case_friction", "observation_sigma", "CORRELATION_WARNING",
           "RELATIVE_SE_WARNING"]

#: |correlation(F1, F2)| above which a poorly determined F1 or F2 is explained as indistinguishable from the other.
CORRELATION_WARNING = 0.99
#: Relative standard error above which an estimate is reported as poorly determined.
RELATIVE_SE_WARNING = 0.25
#: Condition number of the correlation matrix above which the fit is reported as ill-conditioned.
CONDITION_WARNING = 1e8

#: Rows of a time axis per chunk in the streamed stages of a fit: a stage that evaluates the model at more times
#: than this never holds all its residuals or its Jacobian at once (:func:`_solve`).
FIT_CHUNK_ROWS = 1 << 16

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
        """JSON-ready summary: the keys of ``quickrelease fit --json`` (a standard error or interval the record
        does not identify, inf or nan, as None)."""
        return jsonable(self._summary())

    def _summary(self) -> dict[str, Any]:
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
        #: each channel's stride in a coarse stage ({} for the fit proper); the stage's layout (:meth:`smooth`)
        self.sel: dict[str, int] = {}
        self.layout: list[tuple[list[str], np.ndarray, float, dict[str, np.ndarray], dict[str, np.ndarray]]] = []
        #: rows of a time axis per chunk of the streamed stages (:func:`_solve`)
        self.chunk = FIT_CHUNK_ROWS
        self.smooth(0.0)

    def values(self, x: np.ndarray) -> dict[str, float]:
        v = dict(self.fixed)
        v.update({n: float(x[i]) for i, n in enumerate(self.names)})
        return v

    def release(self, v: dict[str, float]) -> FirstIntegral:
        return FirstIntegral(v["energy"], v["alpha0"], v["F1"], v["F2"], self.m1, self.m2, self.L1,
                             v["mass_factor"])

    def model(self, x: np.ndarray) -> tuple[dict[str, np.ndarray], FirstIntegral]:
        """Model values (with offsets) at each channel's samples of the current stage, and the release."""
        v = self.values(x)
        fi = self.release(v)
        out: dict[str, np.ndarray] = {}
        for g, evaluate in enumerate(self._evaluators(v, fi)):  # one time axis: one table of the model
            for name in self.layout[g][0]:
                out[name] = np.empty(self.layout[g][4][name].size)
            for a, b in self._spans(g):
                full = evaluate(slice(a, b))
                for name, lo, hi, local in self._pieces(g, a, b):
                    out[name][lo:hi] = full[name][local] + v.get(f"offset_{name}", 0.0)
        return out, fi

    def smooth(self, width: float) -> None:
        """Model the rate channels with a sampling window of ``width`` [s] (0: their own) and use every k-th
        sample of each time axis, k = floor(width / (2 Delta)) (Delta its sampling interval): a coarse stage
        of the fit (:func:`_smoothing_windows`)."""
        self.smoothing = width
        self.sel = {}
        #: per time axis: its channels, the times the stage evaluates, the sampling window, and per channel
        #: the position of each of its samples among those times and the samples' measured values
        self.layout = []
        for names, t, window in self.groups:
            if width <= 0.0:
                self.layout.append((names, t, window, {n: self.channels[n].index for n in names},
                                    {n: self.channels[n].values for n in names}))
                continue
            k = max(1, int(width / (2.0 * window))) if window > 0.0 else 1
            picked = {name: self.channels[name].index[::k] for name in names}
            rows = np.unique(np.concatenate(list(picked.values())))
            self.layout.append((names, t[rows], max(window, width),
                                {name: np.searchsorted(rows, r) for name, r in picked.items()},
                                {name: self.channels[name].values[::k] for name in names}))
            self.sel.update({name: k for name in names})

    def rows(self) -> int:
        """Times the current stage evaluates the model at, over all time axes."""
        return sum(int(t.size) for _, t, _, _, _ in self.layout)

    def size(self) -> int:
        """Residuals of the current stage: samples of every channel, and the stop observations."""
        return sum(int(data[n].size) for names, _, _, _, data in self.layout for n in names) + len(self.obs)

    def _evaluators(self, v: dict[str, float], fi: FirstIntegral) -> list[ReleaseChannels]:
        return [ReleaseChannels(names, t, v["release_time"], fi, window) for names, t, window, _, _ in self.layout]

    def _spans(self, g: int):
        """Row ranges [a, b) of time axis ``g``, :attr:`chunk` rows each (the last one the rest)."""
        n = self.layout[g][1].size
        for a in range(0, n, self.chunk):
            yield a, min(a + self.chunk, n)

    def _pieces(self, g: int, a: int, b: int) -> list[tuple[str, int, int, np.ndarray]]:
        """Per channel of time axis ``g``: its samples lo:hi that lie in rows [a, b), and their rows - a."""
        names, _, _, pos, _ = self.layout[g]
        out = []
        for name in names:
            lo, hi = (int(i) for i in np.searchsorted(pos[name], (a, b)))
            out.append((name, lo, hi, pos[name][lo:hi] - a))
        return out

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """All weighted residuals at once (the dense path: a stage with at most :attr:`chunk` rows)."""
        model, fi = self.model(x)
        data = {n: d for _, _, _, _, dd in self.layout for n, d in dd.items()}
        parts = [(model[n] - data[n]) / self.sigma[n] for n in self.channels]
        if self.obs:
            parts.append(self._observed(fi))
        return np.concatenate(parts) if parts else np.empty(0)

    def _observed(self, fi: FirstIntegral) -> np.ndarray:
        fitted = {"alpha_final": fi.alpha_final, "stop_time": fi.stop_time()}
        return np.array([(fitted[n] - o) / s for n, (o, s) in self.obs.items()])

    def blocks(self, xs: list[np.ndarray]):
        """The weighted residuals of each parameter vector in ``xs``, :attr:`chunk` rows of a time axis at a
        time: arrays of shape (len(xs), residuals of the chunk), each residual computed as by
        :meth:`residuals`; the stop observations last. Memory: of order len(xs) x chunk x channels."""
        prepared = []
        for x in xs:
            v = self.values(x)
            fi = self.release(v)
            prepared.append((v, fi, self._evaluators(v, fi)))
        for g, (_, _, _, _, data) in enumerate(self.layout):
            for a, b in self._spans(g):
                pieces = self._pieces(g, a, b)
                block = np.empty((len(xs), sum(hi - lo for _, lo, hi, _ in pieces)))
                if not block.shape[1]:
                    continue
                for j, (v, _, evaluators) in enumerate(prepared):
                    full = evaluators[g](slice(a, b))
                    k = 0
                    for name, lo, hi, local in pieces:
                        model = full[name][local] + v.get(f"offset_{name}", 0.0)
                        block[j, k:k + hi - lo] = (model - data[name][lo:hi]) / self.sigma[name]
                        k += hi - lo
                yield block
        if self.obs:
            yield np.array([self._observed(fi) for _, fi, _ in prepared])

    def cost(self, x: np.ndarray) -> float:
        """Sum of the squared weighted residuals (in chunks: no vector of all residuals)."""
        total = 0.0
        for block in self.blocks([x]):
            total += float(block[0] @ block[0])
        return total

    def compressed(self, x: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
        """R, (p + 1) x (p + 1) upper triangular with R^T R = A^T A for A = [r, J] (r the weighted residuals
        at x, J their forward-difference Jacobian with scipy's steps and bound rules, as ``least_squares``
        forms it), accumulated over chunks of rows by QR: ``R <- qr([R; A_chunk])``. Its first row is
        ``(|r|, r^T J / |r|)`` (rows signed so the diagonal is >= 0): the weighted least-squares problem
        ``|r + J d|^2 = (|r| + R[0, 1:] d)^2 + |R[1:, 1:] d|^2`` in p + 1 rows, exactly. Memory: of order
        chunk x channels x (p + 1); model evaluations: p + 1 over the whole record."""
        h = _forward_steps(x, lower, upper)
        xs = [x]
        for i in range(x.size):
            x1 = x.copy()
            x1[i] = x[i] + h[i]
            xs.append(x1)
        dx = np.array([(x[i] + h[i]) - x[i] for i in range(x.size)])
        p = x.size
        R = np.zeros((0, p + 1))
        for block in self.blocks(xs):
            A = np.empty((block.shape[1], p + 1))
            A[:, 0] = block[0]
            A[:, 1:] = ((block[1:] - block[0]) / dx[:, None]).T
            R = np.linalg.qr(np.vstack([R, A]), mode="r")
        out = np.zeros((p + 1, p + 1))
        out[:R.shape[0]] = R
        return out * np.where(np.diag(out) < 0.0, -1.0, 1.0)[:, None]


def _forward_steps(x: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """The steps of scipy's 2-point finite differences (``approx_derivative``, ``least_squares`` default):
    sqrt(eps) max(1, |x|), signed as x (0 as +), reversed where x + h leaves the bounds and -h does not,
    else cut to the farther bound."""
    h = math.sqrt(np.finfo(float).eps) * np.where(x >= 0.0, 1.0, -1.0) * np.maximum(1.0, np.abs(x))
    if np.all((lower == -np.inf) & (upper == np.inf)):
        return h
    h = h.copy()
    lower_dist, upper_dist = x - lower, upper - x
    violated = (x + h < lower) | (x + h > upper)
    fitting = np.abs(h) <= np.maximum(lower_dist, upper_dist)
    h[violated & fitting] *= -1
    forward = (upper_dist >= lower_dist) & ~fitting
    h[forward] = upper_dist[forward]
    backward = (upper_dist < lower_dist) & ~fitting
    h[backward] = -lower_dist[backward]
    return h


def _rest_value(name: str, alpha0: float) -> float:
    return alpha0 if name == "alpha" else 0.0


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
        floor = noise_floor(ch.values)
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
    from ..device.identify import identify_friction

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
    from ..io.records import RATE_OF

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


def _solve(problem: _Problem, x0: np.ndarray, lower: np.ndarray, upper: np.ndarray, tol: float,
           max_nfev: int):
    """One stage: scipy's ``least_squares`` (trf, bounds, ``x_scale="jac"``, tolerances ``tol``) from ``x0``;
    returns the result and the number of residuals m.

    A stage that evaluates the model at no more than :attr:`_Problem.chunk` times sees every residual and
    the m x p forward-difference Jacobian (the dense path). A longer one is streamed: the solver sees the
    problem compressed to p + 1 rows, ``f = (|r|, 0, ..., 0)`` and ``J_c = R[:, 1:]`` with R from the chunked
    QR of [r, J] (:meth:`_Problem.compressed`). Then ``|f|^2 = |r|^2``, ``J_c^T f = J^T r`` and
    ``J_c^T J_c = J^T J``, so every quantity the trust-region steps, their acceptance, the x_scale, the
    termination tests and the covariance use is the dense path's, up to rounding. (One exception: the
    solver's rank test of the scaled Jacobian compares its smallest singular value with eps x rows x the
    largest, and sees p + 1 rows instead of m; this matters only for a Jacobian singular to within 1e-16 m.)
    The result's ``fun`` and ``jac`` are then f and J_c: ``fun @ fun`` is still the chi-square and
    ``jac^T jac`` still J^T J. Each Jacobian costs p + 1 model evaluations (p on the dense path, which has
    the residuals at x at hand); memory is of order chunk x channels x (p + 1), whatever the record's length.
    """
    from scipy.optimize import least_squares

    options = dict(bounds=(lower, upper), x_scale="jac", method="trf", xtol=tol, ftol=tol, gtol=tol,
                   max_nfev=max_nfev)
    if problem.rows() <= problem.chunk:
        res = least_squares(problem.residuals, x0, **options)
        return res, int(res.fun.size)
    p = x0.size

    def norm_only(x):
        f = np.zeros(p + 1)
        f[0] = math.sqrt(problem.cost(x))
        return f

    res = least_squares(norm_only, x0, jac=lambda x: problem.compressed(x, lower, upper)[:, 1:], **options)
    return res, problem.size()


def load_case_record(case: Case) -> Record | None:
    """The case's ``[record]`` read (:func:`quickrelease.io.records.load_record`), its ``release_time`` checked
    against the record's time span at once (:func:`quickrelease.io.records.check_release_time`: one line naming
    the case file, the key, its value and the span, as the building's ``load_building`` does); None without one.

    Raises
    ------
    RecordError
        For a record that cannot be read, or a release_time outside its first to last time stamp."""
    if case.record is None:
        return None
    record = load_record(case.record)
    check_release_time(case.record, record)
    return record


def fit_record(case: Case, record: Record | None = None, *, options: FitOptions | None = None) -> FitResult:
    """Fit the release model to a measured record (and/or stop observations with a scatter).

    Parameters
    ----------
    case : Case
        The test: device, E_S, alpha0, mass model; ``[record]`` (read here unless ``record`` is given),
        ``[fit]`` options, and optionally ``[observations]``.
    record : Record, optional
        An already loaded record (default: :func:`load_case_record` when the case has one).
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
    from scipy.special import stdtrit

    options = options or case.fit
    if record is None and case.record is not None:
        record = load_case_record(case)
    given, origin = record, 0.0
    if record is not None:  # record-relative time: a Unix-time clock (1.7e9 s) would drown the release in rounding
        origin = record_origin(record)
        record = shifted_record(record, origin)
    problem = _Problem(case, record, options)
    x0, how = _start(problem)
    if record is not None:  # a record that starts in motion: said before the work (and after it, below)
        _check_release_inside(record, problem.values(x0)["release_time"], origin)
        _check_rest_before(record, problem.values(x0)["release_time"], origin)
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
        stage, _ = _solve(problem, x_stage, lower, upper, 1e-6, 50 * x0.size)
        x_stage, nfev = stage.x, nfev + stage.nfev
    problem.smooth(0.0)
    if not problem.cost(x_stage) <= problem.cost(x0):  # kept only where they lower the misfit of the fit proper
        x_stage = x0
    res, m = _solve(problem, x_stage, lower, upper, 1e-12, 200 * x0.size)
    x = res.x
    r = res.fun
    nfev += int(res.nfev)
    J = res.jac
    p = J.shape[1]
    dof = m - p
    chi2 = float(r @ r)
    chi2_red = chi2 / dof if dof > 0 else None
    cov, blind = identified_covariance(J)  # columns scaled first: F1, F2 [N], E_S [J], c, t_r [s], offsets
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
        ci[n] = (lo, hi) if math.isfinite(ses[n]) else (math.nan, math.nan)
    model, fi = problem.model(x)
    t_stop = fi.stop_time()
    values = problem.values(x)
    if record is not None:
        _check_release_inside(record, values["release_time"], origin)
    if record is not None and values["release_time"] + t_stop > record.end:
        raise RecordError(f"{record.file}: the record ends at {record.end + origin:.6g} s, before the device "
                          f"stops: release at {values['release_time'] + origin:.6g} s + t_F {t_stop:.4g} s = "
                          f"{values['release_time'] + origin + t_stop:.6g} s; record past the stop")
    rms = {n: float(np.sqrt(np.mean((model[n] - ch.values) ** 2))) for n, ch in problem.channels.items()}
    fitted_obs = {"alpha_final": fi.alpha_final, "stop_time": t_stop}
    obs = {n: (o, s, float(fitted_obs[n])) for n, (o, s) in problem.obs.items()}
    warns = [f"{n} not identified by this record (standard error inf, no interval)"
             for n, b in zip(names, blind, strict=True) if b]
    warns += _warnings(names, est, ses, corr, cond, x, lower, upper, problem)
    start = {n: float(x0[i]) for i, n in enumerate(names)}
    fixed = {k: v for k, v in problem.fixed.items() if k not in est}
    if origin != 0.0:  # back on the record's own clock
        for table in (est, start, fixed):
            if "release_time" in table:
                table["release_time"] += origin
        if "release_time" in ci:
            ci["release_time"] = (ci["release_time"][0] + origin, ci["release_time"][1] + origin)
    record = given
    return FitResult(
        names=names, estimates=est, std_errors=ses, ci95=ci, correlation=corr, condition_number=cond,
        fixed=fixed, noise=dict(problem.sigma), noise_source=dict(problem.sigma_source), residual_rms=rms,
        samples={n: int(ch.values.size) for n, ch in problem.channels.items()},
        chi2_reduced=chi2_red, dof=dof, converged=bool(res.success), message=str(res.message), nfev=nfev,
        start=start, start_source=how, stop_time=float(t_stop),
        alpha_final=float(fi.alpha_final), stopped_by=fi.stopped_by, warnings=tuple(warns),
        notes=tuple(record.notes) if record is not None else (), device=case.device, record=record, fitted=model,
        observations=obs,
    )


#: Samples a record must hold before the fitted release instant: fewer, and the record started while the
#: device was already moving (the model starts at rest at alpha0 and cannot describe it).
PRE_RELEASE_SAMPLES = 3


def _check_release_inside(record: Record, release: float, origin: float) -> None:
    """RecordError when the fitted release instant is not after the record's start (record-relative times):
    a record that starts after the release (its first samples already in motion) gives a fit that puts the
    release at the record's first sample, and friction that is wrong without a word."""
    start = min(float(ch.t[0]) for ch in record.channels.values())
    dt = record.sampling_interval()
    if not release > start + PRE_RELEASE_SAMPLES * dt:
        raise RecordError(f"{record.file}: the record starts at {start + origin:.6g} s, at or after the release "
                          f"(fitted at {release + origin:.6g} s): the device is already moving in its first samples; "
                          "a fit needs the record from before the release, at rest")


#: A displacement channel whose level moves by more than this many times its sample-to-sample scatter over the
#: segment before the start value of the release is not at rest there: the record started in motion.
REST_DRIFT_FACTOR = 50.0


def _check_rest_before(record: Record, release: float, origin: float) -> None:
    """RecordError when a displacement channel (alpha, u, v) moves before ``release`` (the start value of the
    release instant): the first and last quarters of that segment differ by more than
    :data:`REST_DRIFT_FACTOR` times the scatter of its sample-to-sample steps. A record that starts after the
    release (already moving) is said at once, before a fit that would end at a bound after many evaluations."""
    for ch in record.channels.values():
        if ch.name not in DISPLACEMENT_CHANNELS:
            continue
        seg = ch.values[ch.t < release]
        if seg.size < 40:
            continue
        q = seg.size // 4
        drift = abs(float(np.median(seg[-q:])) - float(np.median(seg[:q])))
        steps = np.diff(seg)
        scatter = 1.4826 * float(np.median(np.abs(steps - np.median(steps))))
        span = float(np.ptp(ch.values))
        if drift > REST_DRIFT_FACTOR * scatter and drift > 1e-3 * span:
            raise RecordError(f"{record.file}: the record starts at {float(ch.t[0]) + origin:.6g} s in motion: channel "
                              f"{ch.name} moves by {drift:.3g} {ch.unit} before the release found at "
                              f"{release + origin:.6g} s (the record must start before the release, at rest)")


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


def case_friction(case) -> tuple[float, float, str]:
    """F1, F2 of a case file [N] and where they come from.

    In order: ``[friction]`` F1, F2; the friction of the case named by ``[friction] case`` (found the same
    way); the fit to ``[record]``; the identification from ``[observations]`` (Eq. 11-13).
    """
    if case.has_friction:
        return case.F1 or 0.0, case.F2 or 0.0, "[friction]"
    if case.friction_case is not None:
        F1, F2, how = case_friction(case.friction_case)
        return F1, F2, f"{how} of {case.friction_case.source}"
    if case.record is not None:
        fit = fit_record(case)
        return fit.F1, fit.F2, "fitted to [record]"
    if case.has_observations:
        ident = identify_friction(case.alpha0, case.alpha_final, case.stop_time, stored_energy=case.stored_energy,
                                  device=case.device, mass_model=case.mass_model)
        return ident.F1, ident.F2, "identified from [observations]"
    raise QuickReleaseError(f"{case.source}: no friction: give [friction], [observations] or [record]")
