"""Synthetic records: what the instruments would have recorded, from the model, to plan a test.

:func:`synthesize` samples the release of a case (friction from ``[friction]``, or identified from
``[observations]``) on a chosen set of channels at a chosen rate, from a record start at rest through a
release instant to well after the stop, and adds what real records have: a constant offset per channel,
Gaussian noise, optionally jitter of the sampling instants (uneven sampling) and missing samples.
:func:`predicted_errors` answers the planning question directly: the standard errors of F1 and F2 a fit
to such a record would have (the Cramer-Rao bound: the fit's covariance at the truth, noise-free).
:func:`synthesize_building` makes the building's record, and :func:`predicted_building_errors` the precision
of the building's fit (the Cramer-Rao bound at the truth from the fit's own model and Jacobian).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from .._validate import BYTES_PER_SAMPLE, check_seed, check_size
from ..building.isolation_fit import IsolationPrecision
from ..building.model import RECORD_CHANNELS
from ..device.solvers import FirstIntegral
from ..errors import ParameterError, QuickReleaseError
from ..io.case import Case, FitOptions
from ..io.records import CHANNELS, DISPLACEMENT_CHANNELS, Channel, ChannelSpec, Record, release_channels
from .fit import case_friction

__all__ = ["DEFAULT_NOISE", "SyntheticRecord", "synthesize", "predicted_errors", "parse_channel_values", "case_toml",
           "BUILDING_NOISE", "SyntheticBuildingRecord", "synthesize_building", "building_case_toml",
           "predicted_building_errors", "ConstantFrictionPrecision", "constant_friction_truth"]

#: Default noise standard deviations [SI]: video angle, gyroscope, draw-wire or LVDT displacements,
#: velocity transducers, accelerometers (about 5 mg).
DEFAULT_NOISE = {"alpha": 0.002, "alpha_dot": 0.01, "u": 0.5e-3, "v": 0.5e-3, "u_dot": 5e-3, "v_dot": 5e-3,
                 "a_head": 0.05, "a_hinge": 0.05}


#: Fewest samples before the release and during the motion: a fit needs both (noise, then friction).
MIN_SAMPLES = 10


def _column(name: str, channels: dict[str, tuple[str, str, str]] = CHANNELS) -> str:
    """The column of a channel in a written record: its name and SI unit (``a_head_m_s2``)."""
    return f"{name}_{channels[name][1].replace('/', '_').replace('^', '')}"


@dataclass(frozen=True, eq=False)
class _Synthetic:
    """What the device's and the building's synthetic records share: the samples, the truth, how they were
    made, and the record as written (a CSV table and the case-file table that reads it)."""

    t: np.ndarray
    """Sample times from the start of the record [s]."""
    data: dict[str, np.ndarray]
    """Channel -> recorded values (offset and noise added; NaN where a sample is missing)."""
    clean: dict[str, np.ndarray]
    """Channel -> model values without offset and noise."""
    truth: dict[str, Any]
    noise: dict[str, float]
    offsets: dict[str, float]
    rate: float
    """Sampling rate [Hz]."""
    seed: int
    notes: list[str] = field(default_factory=list)

    #: Channel name -> (quantity kind, SI unit, description) of the record's channels.
    _CHANNELS: ClassVar[dict[str, tuple[str, str, str]]] = CHANNELS
    #: The case file's table that reads the record.
    _SECTION: ClassVar[str] = "record"

    def columns(self) -> dict[str, np.ndarray]:
        """The table as written: ``t_s`` and one column per channel, SI units in the names."""
        return {"t_s": self.t, **{_column(n, self._CHANNELS): v for n, v in self.data.items()}}

    def to_pandas(self):
        import pandas as pd

        return pd.DataFrame(self.columns())

    def write_csv(self, path: str | Path) -> Path:
        """Write the record as CSV (atomically); missing samples are empty fields."""
        return _write_csv(self.columns(), path)

    def record_table(self, file: str) -> str:
        """The ``[record]`` (device) or ``[building.record]`` (building) table of a case file that reads this
        record (to paste into a case file)."""
        sec, channels = self._SECTION, self._CHANNELS
        lines = [f"[{sec}]", f"file = {_toml_value(file)}", 'time = "t_s"', "", f"[{sec}.channels]"]
        for name in self.data:
            lines.append(f'{name} = {{ column = "{_column(name, channels)}", unit = "{channels[name][1]}" }}')
        return "\n".join(lines) + "\n"


@dataclass(frozen=True, eq=False)
class SyntheticRecord(_Synthetic):
    """A synthetic record of the device's release and the truth behind it (SI units)."""

    truth: dict[str, float]
    """F1, F2 [N], energy [J], mass_factor, alpha0, release_time, stop_time [s], alpha_final [rad]."""

    def record(self, *, noise_free: bool = False) -> Record:
        """The record as :func:`quickrelease.studies.fit.fit_record` takes it (noise levels given, offsets estimated
        on displacement channels), missing samples left out (noise-free: the model values on the samples the
        record has)."""
        channels = {}
        for name, values in (self.clean if noise_free else self.data).items():
            ok = np.nonzero(np.isfinite(self.data[name]))[0]
            spec = ChannelSpec(name=name, column=_column(name), unit=CHANNELS[name][1], factor=1.0,
                               noise=self.noise[name], offset=name in DISPLACEMENT_CHANNELS)
            channels[name] = Channel(spec=spec, t=self.t[ok], values=values[ok], index=ok,
                                     missing=int(values.size - ok.size))
        return Record(file=Path("<synthetic>"), t=self.t, channels=channels,
                      release_time=self.truth["release_time"])


def _write_csv(cols: dict[str, np.ndarray], path: str | Path) -> Path:
    """Write columns of equal length as CSV (atomically); NaN as an empty field, 10 significant digits."""
    from ..io.export import atomic_path

    names = list(cols)
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write(",".join(names) + "\n")
            for row in np.column_stack([cols[n] for n in names]):
                fh.write(",".join("" if not np.isfinite(v) else f"{v:.10g}" for v in row) + "\n")
    return Path(path)


def _sample_times(duration: float, rate: float, jitter: float, seed: int, n_channels: int):
    """The record's sampling instants (every 1/rate from 0 to ``duration``, shifted by up to +-jitter/2
    intervals) and the noise generator that drew the shifts, after the seed and size checks."""
    check_seed("seed", seed)
    samples = math.floor(duration * rate) + 1 if math.isfinite(duration * rate) else math.inf
    check_size("duration x rate", f"{duration:g} s x {rate:g} Hz", samples,
               f"samples of {n_channels} channel(s)", BYTES_PER_SAMPLE * (n_channels + 1))
    rng = np.random.default_rng(seed)
    n = int(samples)
    t = np.arange(n) / rate
    if jitter:
        t = t + (rng.uniform(-0.5, 0.5, n) * jitter / rate)
        t[0] = max(t[0], 0.0)
    return t, rng


def _measured(channels, clean: dict[str, np.ndarray], offsets: dict[str, float], noise: dict[str, float],
              missing: float, rng) -> dict[str, np.ndarray]:
    """Each channel as an instrument records it: the clean signal plus its offset and white noise, with a
    share ``missing`` of its samples lost (NaN); drawn from ``rng`` channel by channel."""
    data = {}
    for name in channels:
        n = clean[name].size
        values = clean[name] + offsets[name] + rng.normal(0.0, 1.0, n) * noise[name]
        if missing:
            values[rng.uniform(0.0, 1.0, n) < missing] = np.nan
        data[name] = values
    return data


def _sampling(channels, table: dict[str, tuple], defaults: dict[str, float], noise: dict[str, float] | None,
              rate: float, release_time: float, jitter: float, missing: float) -> dict[str, float]:
    """Check a synthetic record's sampling (rate [Hz] and release_time [s] finite and > 0, jitter and missing in
    [0, 1)) and return the noise of every channel (``defaults`` updated by ``noise``), each finite and > 0 (the
    noise weights the fit of the record and its predicted precision), in the unit of ``table[name][1]``;
    ParameterError naming the first that is not."""
    if not (math.isfinite(rate) and rate > 0):
        raise ParameterError("rate", rate, "(0, inf)", "Hz")
    if not (math.isfinite(release_time) and release_time > 0):
        raise ParameterError("release_time", release_time, "(0, inf)", "s")
    if not 0.0 <= jitter < 1.0:
        raise ParameterError("jitter", jitter, "[0, 1)")
    if not 0.0 <= missing < 1.0:
        raise ParameterError("missing", missing, "[0, 1)")
    noise = {**defaults, **(noise or {})}
    for name in channels:
        if not (math.isfinite(noise[name]) and noise[name] > 0):
            raise ParameterError(f"noise of {name}", noise[name], "(0, inf) (the noise weights a fit)", table[name][1])
    return noise


def synthesize(case: Case, channels: list[str] | tuple[str, ...], *, rate: float, noise: dict[str, float] | None = None,
               release_time: float = 0.5, duration: float | None = None, offsets: dict[str, float] | None = None,
               seed: int = 0, jitter: float = 0.0, missing: float = 0.0) -> SyntheticRecord:
    """A synthetic record of the case's release.

    Parameters
    ----------
    case : Case
        Device, E_S, alpha0, mass model, and friction (``[friction]`` or ``[observations]``).
    channels : list of str
        Channels of :data:`quickrelease.io.records.CHANNELS`.
    rate : float
        Sampling rate [Hz].
    noise : dict, optional
        Noise standard deviation per channel [SI], > 0; :data:`DEFAULT_NOISE` for the others.
    release_time : float
        Release instant from the start of the record [s] (the record before it is at rest).
    duration : float, optional
        Record length [s]; default: release + t_F + max(0.5 s, t_F / 4).
    offsets : dict, optional
        Constant offset per channel [SI] (default 0).
    seed : int
        Seed of the noise, jitter and missing samples.
    jitter : float
        Sampling instants shifted by up to +-jitter/2 sampling intervals (uniform), in [0, 1).
    missing : float
        Share of samples missing (NaN) in each channel, in [0, 1).
    """
    unknown = [c for c in channels if c not in CHANNELS]
    if unknown or not channels:
        raise ParameterError("channels", ",".join(unknown) or "(none)", f"a list of {', '.join(CHANNELS)}")
    noise = _sampling(channels, CHANNELS, DEFAULT_NOISE, noise, rate, release_time, jitter, missing)
    offsets = {name: float((offsets or {}).get(name, 0.0)) for name in channels}
    for name, value in offsets.items():
        if not math.isfinite(value):
            raise ParameterError(f"offset of {name}", value, "finite values", CHANNELS[name][1])
    F1, F2, how = case_friction(case)
    d = case.device
    fi = FirstIntegral(case.stored_energy, case.alpha0, F1, F2, d.m1, d.m2, d.L1, case.mass_factor)
    t_stop = fi.stop_time()
    if duration is None:
        duration = release_time + t_stop + max(0.5, 0.25 * t_stop)
    if not (math.isfinite(duration) and duration > release_time):
        raise ParameterError("duration", duration, f"(release_time, inf) = ({release_time:g}, inf)", "s")
    if not rate * min(t_stop, release_time) >= MIN_SAMPLES:  # noise from before the release, the motion after
        raise ParameterError("rate", rate, f"[{MIN_SAMPLES} / min(t_F, release_time), inf) = "
                             f"[{MIN_SAMPLES / min(t_stop, release_time):.4g}, inf) (t_F = {t_stop:.4g} s)", "Hz")
    t, rng = _sample_times(duration, rate, jitter, seed, len(channels))
    clean = release_channels(list(channels), t, release_time, fi, 1.0 / rate)
    data = _measured(channels, clean, offsets, noise, missing, rng)
    truth = {"F1": float(F1), "F2": float(F2), "energy": float(case.stored_energy), "mass_factor": case.mass_factor,
             "alpha0": case.alpha0, "release_time": float(release_time), "stop_time": float(t_stop),
             "alpha_final": float(fi.alpha_final)}
    return SyntheticRecord(t=t, data=data, clean=clean, truth=truth, noise={n_: noise[n_] for n_ in channels},
                           offsets=offsets, rate=float(rate), seed=int(seed), notes=[f"friction {how}"])


def predicted_errors(case: Case, synthetic: SyntheticRecord, options: FitOptions | None = None) -> dict[str, Any]:
    """Standard errors a fit to such a record would have: the covariance at the truth (Cramer-Rao bound).

    The fit of :func:`quickrelease.studies.fit.fit_record` to the noise-free record, with the synthetic noise
    levels as exact weights: ``sqrt(diag((J^T J)^-1))`` at the true parameters.

    Returns
    -------
    dict
        ``F1_se_N``, ``F2_se_N``, ``correlation_F1_F2``, and ``std_errors`` of every estimated parameter.
    """
    from dataclasses import replace

    from ..io.export import jsonable
    from .fit import fit_record

    opts = replace(options or case.fit, absolute_sigma=True, use_observations=False)
    res = fit_record(case, synthetic.record(noise_free=True), options=opts)
    i1, i2 = res.names.index("F1"), res.names.index("F2")
    se = jsonable(res.std_errors)  # a parameter this record cannot see (SE inf): None, and said in the warnings
    rel = {f: None if se[f] is None or not synthetic.truth[f] else se[f] / synthetic.truth[f] for f in ("F1", "F2")}
    return {"F1_se_N": se["F1"], "F2_se_N": se["F2"], "F1_rel_se": rel["F1"], "F2_rel_se": rel["F2"],
            "correlation_F1_F2": jsonable(res.correlation[i1, i2]), "std_errors": se,
            "warnings": list(res.warnings)}


def parse_channel_values(items: list[str] | tuple[str, ...], what: str,
                         channels: dict[str, tuple[str, str, str]] | None = None) -> dict[str, float]:
    """``["u=0.5 mm", "a_head=0.05 m/s^2,v=1mm"]`` -> {channel: SI value}; units per the channel's kind
    (``channels``: the device's :data:`~quickrelease.io.records.CHANNELS` unless given, e.g. the building's)."""
    from ..units import parse_quantity

    channels = CHANNELS if channels is None else channels
    out: dict[str, float] = {}
    for item in items:
        for part in item.split(","):
            if not part.strip():
                continue
            name, sep, value = part.partition("=")
            name = name.strip()
            if not sep or name not in channels:
                raise ParameterError(what, part.strip(), f"CHANNEL=VALUE with CHANNEL one of {', '.join(channels)}")
            if name in out:
                raise QuickReleaseError(f"{what} {part.strip()}: channel {name} is given twice (once per channel)")
            out[name] = parse_quantity(value.strip(), channels[name][0], f"{what} {name}")
    return out


#: TOML basic-string escapes (TOML 1.0, "Strings"): backslash, quote, and every control character
#: (U+0000-U+001F, U+007F), which a basic string must not hold literally.
_TOML_ESCAPES = {0x5C: "\\\\", 0x22: '\\"', 0x08: "\\b", 0x09: "\\t", 0x0A: "\\n", 0x0C: "\\f", 0x0D: "\\r",
                 **{c: f"\\u{c:04X}" for c in (*range(0x00, 0x08), 0x0B, *range(0x0E, 0x20), 0x7F)}}


def _toml_value(value: Any) -> str:
    """``value`` as a TOML value: a string as a basic string with every character TOML requires escaped."""
    if isinstance(value, str):
        return '"' + value.translate(_TOML_ESCAPES) + '"'
    return repr(float(value)) if isinstance(value, float) else str(value)


def case_toml(case: Case, record_table: str, title: str) -> str:
    """A case file (TOML text) with the case's device and test set-up and the given ``[record]`` table."""
    from ..device.parameters import DEVICE_KEYS, preset, preset_names

    notes = _toml_value(f"Made by quickrelease synth from {case.source}")
    lines = [f"title = {_toml_value(title)}", f"notes = {notes}", "", "[device]"]
    d = case.device
    if d.name in preset_names() and preset(d.name) == d:
        lines.append(f"preset = {_toml_value(d.name)}")
    else:
        lines.append(f"name = {_toml_value(d.name)}")
        lines += [f"{k} = {_toml_value(getattr(d, k))}" for k in DEVICE_KEYS]
    lines += ["", "[test]"]
    if case.push_force is not None:
        lines.append(f'force = "{case.push_force!r} N"')
    if case.energy_given or case.push_force is None:
        lines.append(f'energy = "{case.stored_energy!r} J"')
    lines.append(f'alpha0 = "{case.alpha0!r} rad"')
    mm = case.mass_model
    lines.append(f"mass_model = {_toml_value(mm if isinstance(mm, str) else float(mm))}")
    return "\n".join(lines) + "\n\n" + record_table


# -- the building ----------------------------------------------------------------------------------------------

#: Default noise standard deviation per quantity kind of the building's channels [SI]: an LVDT or draw-wire
#: (0.05 mm), a velocity transducer (1 mm/s), an accelerometer (2 mg).
BUILDING_NOISE_BY_KIND = {"length": 0.05e-3, "velocity": 1e-3, "acceleration": 0.002 * 9.80665}
#: Default noise standard deviations of the building's channels [SI] (on the isolation layer and at the roof),
#: by the kind of each channel of :data:`quickrelease.building.model.RECORD_CHANNELS`.
BUILDING_NOISE = {name: BUILDING_NOISE_BY_KIND[kind] for name, (kind, _, _) in RECORD_CHANNELS.items()}


@dataclass(frozen=True, eq=False)
class SyntheticBuildingRecord(_Synthetic):
    """A synthetic record of the building's free vibration and the truth behind it (SI units)."""

    truth: dict[str, Any]
    """The building (model, mass_kg, period_s, damping_ratio, friction_N; bilinear k1_N_m, k2_N_m, Fy_N; 2dof
    superstructure_mass_kg, superstructure_period_s, superstructure_damping_ratio; pendulum radius_m and
    Constantinou's friction_slow, friction_fast, rate_s_m, or for a constant coefficient constant_friction True and
    one friction_coefficient, :func:`constant_friction_truth`), d0_m, release_time_s and stop_time_s (after the
    release; None: still moving at the end of the record)."""
    constant_friction: bool = False
    """The pendulum's friction is a constant coefficient (``[building] friction_coefficient``): its fit holds the
    rate at 0 and mu_fast at mu (:func:`quickrelease.io.building_case.constant_friction_fixed`)."""

    _CHANNELS: ClassVar[dict[str, tuple[str, str, str]]] = RECORD_CHANNELS
    _SECTION: ClassVar[str] = "building.record"

    def building_channels(self, *, noise_free: bool = False) -> list:
        """The record as :func:`quickrelease.building.isolation_fit.fit_isolation` takes it (noise levels given, an
        offset on every channel), missing samples left out (noise-free: the model values on the samples the
        record has)."""
        from ..building.isolation_fit import BuildingChannel

        out = []
        for name, values in (self.clean if noise_free else self.data).items():
            ok = np.isfinite(self.data[name])
            out.append(BuildingChannel(name=name, kind=name, t=self.t[ok], values=values[ok], noise=self.noise[name],
                                       offset=True))
        return out

    def fit_parameters(self) -> dict[str, float]:
        """The truth in :func:`quickrelease.building.isolation_fit.fit_isolation`'s parameter names (SI): period
        (bilinear: the initial period 2 pi sqrt(m / k1)), damping_ratio, friction, bilinear stiffness_ratio =
        k2 / k1 and yield_force, 2dof superstructure_period and superstructure_damping_ratio, d0, release_time
        and offset_<channel>."""
        t = self.truth
        p = {"period": t["period_s"]}
        if "damping_exponent" in t:
            p.update(damping_coefficient=t["damping_coefficient"], damping_exponent=t["damping_exponent"])
        else:
            p["damping_ratio"] = t["damping_ratio"]
        if t["model"] == "pendulum":
            if "friction_coefficient" in t:  # constant friction (constant_friction_truth): mu(v) = mu
                mu = t["friction_coefficient"]
                p.update(friction_slow=mu, friction_fast=mu, rate=0.0)
            else:
                p.update(friction_slow=t["friction_slow"], friction_fast=t["friction_fast"], rate=t["rate_s_m"])
        else:
            p["friction"] = t["friction_N"]
        if t["model"] == "boucwen":
            p.update(characteristic_strength=t["Qd_N"], yield_displacement=t["dy_m"], shape=t["shape"])
        if t["model"] == "bilinear":
            p.update(stiffness_ratio=t["k2_N_m"] / t["k1_N_m"], yield_force=t["Fy_N"])
        if t["model"] == "2dof" or t.get("flexible"):
            p.update(superstructure_period=t["superstructure_period_s"],
                     superstructure_damping_ratio=t["superstructure_damping_ratio"])
        p.update(d0=t["d0_m"], release_time=t["release_time_s"])
        p.update({f"offset_{name}": value for name, value in self.offsets.items()})
        return {k: float(v) for k, v in p.items()}


@dataclass(frozen=True, eq=False)
class ConstantFrictionPrecision(IsolationPrecision):
    """The precision of the constant-friction pendulum's fit (rate and mu_fast held): its mu_slow row is the one
    friction coefficient mu, keyed ``friction_coefficient`` as in the fit's JSON
    (:func:`quickrelease.studies.building_analysis.physical_estimates`)."""

    def physical(self) -> dict[str, dict[str, Any]]:
        return {("friction_coefficient" if key == "friction_slow" else key): row
                for key, row in super().physical().items()}


def predicted_building_errors(synthetic: SyntheticBuildingRecord) -> IsolationPrecision:
    """Standard errors a fit to such a record of the building would have: the Cramer-Rao bound at the truth.

    :func:`quickrelease.building.isolation_fit.predicted_isolation_errors` on the record's channels (its sample times,
    missing samples left out, and its noise levels as the known weights, an offset on every channel) at the
    true parameters of the synthetic record's model: ``(J^T W J)^-1`` with W = 1 / noise^2. A pendulum of constant
    friction (``[building] friction_coefficient``) is predicted as ``quickrelease building`` fits it, the rate
    held at 0 and mu_fast at mu (:func:`quickrelease.io.building_case.constant_friction_fixed`): one row
    ``friction_coefficient``, not Constantinou's three (:class:`ConstantFrictionPrecision`).

    Returns
    -------
    quickrelease.building.isolation_fit.IsolationPrecision
    """
    from dataclasses import fields

    from ..building.isolation_fit import predicted_isolation_errors
    from ..io.building_case import constant_friction_fixed

    t = synthetic.truth
    parameters, fixed = synthetic.fit_parameters(), {}
    if synthetic.constant_friction:
        fixed = constant_friction_fixed(parameters)
        parameters.update(fixed)
    pred = predicted_isolation_errors(synthetic.building_channels(noise_free=True), t["mass_kg"], t["model"],
                                      parameters, superstructure_mass=t.get("superstructure_mass_kg"),
                                      fixed=tuple(fixed), flexible=bool(t.get("flexible", False)))
    if not synthetic.constant_friction:
        return pred
    return ConstantFrictionPrecision(**{f.name: getattr(pred, f.name) for f in fields(pred)})


def constant_friction_truth(truth: dict[str, Any]) -> dict[str, Any]:
    """The truth of a friction pendulum of constant friction (``[building] friction_coefficient``) as its case says
    it and its fit reports it (:func:`quickrelease.studies.building_analysis.physical_estimates`): one
    ``friction_coefficient`` mu [-] (the summary's friction_slow) with ``constant_friction`` True, not Constantinou's
    friction_slow, friction_fast and a rate of 0, in the summary's place."""
    out: dict[str, Any] = {}
    for key, value in truth.items():
        if key == "friction_slow":
            out["constant_friction"] = True
            out["friction_coefficient"] = value
        elif key not in ("friction_fast", "rate_s_m"):
            out[key] = value
    return out


def describe_truth(truth: dict[str, Any]) -> str:
    """The synthetic building's isolation in its model's terms, for a person (SI values with prefixes): the period
    (pendulum: its radius R and 2 pi sqrt(R / g); Bouc-Wen: Kd, Qd, dy, n), the damper (zeta, or C and alpha) and
    the sliders' friction (the pendulum's mu_slow to mu_fast at rate a; one mu where the two are equal or the rate
    is 0: constant friction)."""
    from ..report.display import describe_isolation, quantity

    t = truth
    render = {
        "pendulum": lambda radius, period, friction_slow, friction_fast, rate: (
            f"R = {quantity(radius, 'm')} (T = {quantity(period, 's')}), friction mu = {quantity(friction_slow)} "
            + ("(constant)" if friction_fast == friction_slow or not rate else
               f"to {quantity(friction_fast)} (rate {quantity(rate, 's/m')})")),
        "boucwen": lambda post_yield_stiffness, period, characteristic_strength, yield_displacement, shape: (
            f"Kd = {quantity(post_yield_stiffness, 'N/m')} (T = {quantity(period, 's')}), Qd = "
            f"{quantity(characteristic_strength, 'N')}, dy = {quantity(yield_displacement, 'm')}, "
            f"n = {quantity(shape)}"),
        "period": lambda period: f"T = {quantity(period, 's')}",
        "power": lambda damping_coefficient, damping_exponent: (
            f"dampers C = {quantity(damping_coefficient, 'N')} (s/m)^alpha, alpha = {quantity(damping_exponent)}"),
        "viscous": lambda damping_ratio: f"zeta = {quantity(damping_ratio)}",
        "friction": lambda friction: f"F_s = {quantity(friction, 'N')}",
    }
    power = "damping_exponent" in t
    mu = t.get("friction_coefficient")  # a constant friction coefficient (constant_friction_truth)
    return describe_isolation(t["model"], render, period=t["period_s"], radius=t.get("radius_m"),
                              friction_slow=t.get("friction_slow", mu), friction_fast=t.get("friction_fast", mu),
                              rate=t.get("rate_s_m", 0.0), post_yield_stiffness=t.get("Kd_N_m"),
                              characteristic_strength=t.get("Qd_N"), yield_displacement=t.get("dy_m"),
                              shape=t.get("shape"), power=power, damping_coefficient=t.get("damping_coefficient"),
                              damping_exponent=t.get("damping_exponent"),
                              damping_ratio=t.get("damping_ratio", 0.0) if not power else 0.0,
                              friction=t.get("friction_N", 0.0))


def building_pushed_displacement(case: Case) -> float:
    """The building's pushed displacement d0 [m]: ``[building] displacement``, else from the push force of
    ``[test]`` (:func:`quickrelease.io.building_case.pushed_displacement`)."""
    from ..io.building_case import pushed_displacement

    spec = case.building
    if spec.displacement is not None:
        return spec.displacement
    if case.has_test and case.push_force is not None:
        return pushed_displacement(case.push_force, spec)
    raise ParameterError("[building] displacement", None, "given (the pushed displacement d0, e.g. '0.15 m'), or a "
                         "[test] force to push the building with", "m")


def synthesize_building(case: Case, channels: list[str] | tuple[str, ...], *, rate: float,
                        noise: dict[str, float] | None = None, release_time: float = 2.0,
                        duration: float | None = None, offsets: dict[str, float] | None = None, seed: int = 0,
                        jitter: float = 0.0, missing: float = 0.0) -> SyntheticBuildingRecord:
    """A synthetic record of the building's free vibration after the release, from ``[building]`` (the truth).

    The isolation layer rests at the pushed displacement d0 until ``release_time``, then vibrates freely:
    the exact closed form of :func:`quickrelease.building.model.free_vibration` (linear or bilinear isolation,
    viscous damping, Coulomb sliders, sticking; or the 2dof building, :class:`~quickrelease.building.model.TwoDOF`),
    sampled at the record's instants (point values). The channels x, v, a are the isolation layer's (the
    base), x_roof, v_roof, a_roof the roof's: the 2dof building's superstructure mass (and that of a layer with
    ``[building] flexible = true``, a :class:`~quickrelease.building.flexible.FlexibleBuilding`), for the rigid
    superstructure of the other models the layer's. Each channel gets a constant offset and Gaussian noise;
    optionally jittered instants and missing samples.

    Parameters
    ----------
    case : Case
        With ``[building]`` (model linear, bilinear, 2dof, pendulum or boucwen) and d0 (``displacement``, or a
        ``[test]`` force).
    channels : list of str
        Channels of :data:`quickrelease.io.building_case.BUILDING_CHANNELS`.
    rate : float
        Sampling rate [Hz].
    noise : dict, optional
        Noise standard deviation per channel [SI], > 0; :data:`BUILDING_NOISE` for the others.
    release_time : float
        Release instant from the start of the record [s] (the pre-release segment at the pushed state).
    duration : float, optional
        Record length [s]; default: release + min(stop, 20 T) + 2 T (T the isolation's (initial) period).
        The rate must give 10 samples to the shortest of T, the release time and (2dof) the period of the
        building's higher mode while the base slides.
    offsets : dict, optional
        Constant offset per channel [SI] (default 0).
    seed : int
        Seed of the noise, jitter and missing samples.
    jitter : float
        Sampling instants shifted by up to +-jitter/2 sampling intervals (uniform), in [0, 1).
    missing : float
        Share of samples missing (NaN) in each channel, in [0, 1).
    """
    from ..building.model import TwoDOF, free_vibration, pushed_state
    from ..io.building_case import BUILDING_CHANNELS, constant_friction, spec_building

    spec = case.building
    if spec is None:
        raise QuickReleaseError(f"{case.source}: no [building] table (the building to simulate)")
    unknown = [c for c in channels if c not in BUILDING_CHANNELS]
    if unknown or not channels or len(set(channels)) != len(channels):
        what = f"unknown channel {unknown[0]!r}" if unknown else "no channel" if not channels else "a channel twice"
        raise QuickReleaseError(f"channels = {','.join(channels)!r}: {what}; valid: distinct channels of the "
                                f"building's record, {', '.join(BUILDING_CHANNELS)}")
    noise = _sampling(channels, BUILDING_CHANNELS, BUILDING_NOISE, noise, rate, release_time, jitter, missing)
    offsets = {name: float((offsets or {}).get(name, 0.0)) for name in channels}
    for name, value in offsets.items():
        if not math.isfinite(value):
            raise ParameterError(f"offset of {name}", value, "finite values", BUILDING_CHANNELS[name][1])
    iso = spec_building(spec)
    two = isinstance(iso, TwoDOF)
    flexible = not two and hasattr(iso, "superstructure_mass")  # a FlexibleBuilding: the layer under the storey
    layer = iso.rigid() if two or flexible else iso
    d0 = building_pushed_displacement(case)
    if not (math.isfinite(d0) and d0 > 0):
        raise ParameterError("d0", d0, "(0, inf) (the push must move the building past its sliders' friction)", "m")
    R0 = pushed_state(layer, d0)[1]  # 2dof, flexible: the isolators hold the push, the storey no shear
    if abs(R0) <= layer.friction:
        if spec.friction_coefficient is not None:
            key = f"friction_coefficient = {spec.friction_coefficient:.6g}"
        elif spec.model == "pendulum":
            key = f"friction_slow = {spec.friction_slow:.6g}"
        else:
            key = f"friction = {spec.friction_force:.6g} N"
        raise QuickReleaseError(f"{case.source}: [building] d0 = {d0:.6g} m: the sliders' friction F_s = "
                                f"{layer.friction:.6g} N holds the building there (restoring force {R0:.6g} N <= F_s), "
                                f"so it never moves after the release: push it farther, or give less friction "
                                f"([building] {key})")
    period = layer.period
    motion = free_vibration(iso, d0, t_end=20.0 * period)
    t_stop = motion.stop_time
    if duration is None:
        duration = release_time + min(t_stop, 20.0 * period) + 2.0 * period
    if not (math.isfinite(duration) and duration > release_time):
        raise ParameterError("duration", duration, f"(release_time, inf) = ({release_time:g}, inf)", "s")
    shortest, which = period, f"T = {period:.4g} s"
    if two:  # the faster mode of the sliding base (M^-1 K), shorter than the superstructure's fixed-base T_s
        M, _, K = iso.matrices()
        shortest = 2.0 * math.pi / math.sqrt(float(np.max(np.linalg.eigvals(np.linalg.solve(M, K)).real)))
        which += f", higher mode T_2 = {shortest:.4g} s"
    elif flexible:  # the sliding base's faster mode: w_2^2 <= (m / m_b) (w^2 + w_s^2), w of the layer's period
        r = iso.mass / iso.base_mass
        shortest = 2.0 * math.pi / math.sqrt(r * ((2.0 * math.pi / period) ** 2
                                                  + (2.0 * math.pi / iso.superstructure_period) ** 2))
        which += f", higher mode T_2 >= {shortest:.4g} s"
        two = True  # (the message's T_2)
    if not rate * min(shortest, release_time) >= MIN_SAMPLES:  # noise before the release, the motion after
        raise ParameterError("rate", rate, f"[{MIN_SAMPLES} / min(T{', T_2' if two else ''}, release_time), inf) = "
                             f"[{MIN_SAMPLES / min(shortest, release_time):.4g}, inf) ({which})", "Hz")
    t, rng = _sample_times(duration, rate, jitter, seed, len(channels))
    if duration - release_time > motion.horizon:
        motion = free_vibration(iso, d0, t_end=duration - release_time)
    model = motion.channels(t - release_time)  # a rigid superstructure's roof moves with the layer
    clean = {name: model[name].copy() for name in channels}
    data = _measured(channels, clean, offsets, noise, missing, rng)
    stop = float(motion.stop_time) if motion.stop_time <= duration - release_time else None
    truth = {**iso.summary(), "d0_m": float(d0), "release_time_s": float(release_time), "stop_time_s": stop}
    if flexible and spec.model == "2dof":  # 2dof's linear layer with a power-law damper (on the flexible integrator)
        truth.pop("isolation_model")
        truth["model"] = "2dof"
    elif flexible:  # the layer's model, flexible: its fit's names (fit_isolation(model, flexible=True))
        truth.update(model=truth.pop("isolation_model"), flexible=True)
    if constant_friction(spec):
        truth = constant_friction_truth(truth)
    notes = [] if spec.mass is not None else ["no [building] mass: a unit mass (the motion depends on F_s / m only)"]
    return SyntheticBuildingRecord(t=t, data=data, clean=clean, truth=truth, noise={c: noise[c] for c in channels},
                                   offsets=offsets, rate=float(rate), seed=int(seed), notes=notes,
                                   constant_friction=constant_friction(spec))


def building_case_toml(case: Case, synthetic: SyntheticBuildingRecord, record_table: str, title: str) -> str:
    """A case file (TOML text) of the building alone: ``[building]`` with the synthetic record's truth (SI
    values, exactly as used) and the given ``[building.record]`` table."""
    t = synthetic.truth
    notes = _toml_value(f"Made by quickrelease synth from {case.source}")
    lines = [f"title = {_toml_value(title)}", f"notes = {notes}", "", "[building]",
             f"model = {_toml_value(t['model'])}"]
    if case.building.mass is not None:
        lines.append(f'mass = "{t["mass_kg"]!r} kg"')
    if t["model"] == "bilinear":
        lines += [f'k1 = "{t["k1_N_m"]!r} N/m"', f'k2 = "{t["k2_N_m"]!r} N/m"', f'yield_force = "{t["Fy_N"]!r} N"']
    elif t["model"] == "pendulum" and "friction_coefficient" in t:
        lines += [f'radius = "{t["radius_m"]!r} m"', f"friction_coefficient = {t['friction_coefficient']!r}"]
    elif t["model"] == "pendulum":
        lines += [f'radius = "{t["radius_m"]!r} m"', f"friction_slow = {t['friction_slow']!r}",
                  f"friction_fast = {t['friction_fast']!r}", f'rate = "{t["rate_s_m"]!r} s/m"']
    elif t["model"] == "boucwen":
        lines += [f'post_yield_stiffness = "{t["Kd_N_m"]!r} N/m"', f'characteristic_strength = "{t["Qd_N"]!r} N"',
                  f'yield_displacement = "{t["dy_m"]!r} m"', f"shape = {t['shape']!r}"]
    else:
        lines.append(f'period = "{case.building.period!r} s"')
    if t.get("flexible"):
        lines.append("flexible = true")
    if t["model"] == "2dof" or t.get("flexible"):
        lines += [f'superstructure_mass = "{t["superstructure_mass_kg"]!r} kg"',
                  f'superstructure_period = "{t["superstructure_period_s"]!r} s"',
                  f"superstructure_damping_ratio = {t['superstructure_damping_ratio']!r}"]
    if case.building.damping == "power":
        lines += ['damping = "power"', f'damping_coefficient = "{case.building.damping_coefficient!r} N"',
                  f"damping_exponent = {case.building.damping_exponent!r}"]
    else:
        lines.append(f"damping_ratio = {case.building.damping_ratio!r}")
    if t["model"] != "pendulum":
        lines.append(f'friction = "{t["friction_N"]!r} N"')
    lines.append(f'displacement = "{t["d0_m"]!r} m"')
    return "\n".join(lines) + "\n\n" + record_table
