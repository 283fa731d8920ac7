"""The building's part of a case file: ``[building]`` and its free-vibration record ``[building.record]``.

The record of the building after the release is read like the device's record (the grammar of
:func:`quickrelease.io.records.parse_record_spec`: a file, a time column, and a table of channels, each with
``column``, ``unit``, ``noise``, ``offset``, ``scale``, and ``file`` and ``time`` for a channel in a file
of its own with its own time axis and sampling rate), with the building's channels:

========== ===================================================== ==========
channel    what                                                  SI unit
========== ===================================================== ==========
x          displacement of the isolation layer (e.g. an LVDT)    m
v          velocity of the isolation layer                       m/s
a          acceleration of the isolation layer (base)            m/s^2
x_roof     displacement of the top of the superstructure         m
v_roof     velocity of the top of the superstructure             m/s
a_roof     acceleration of the top of the superstructure         m/s^2
========== ===================================================== ==========

Every channel has a constant offset by default (a sensor's zero is never exactly zero); ``drift = true``
adds a linear drift of the zero (a displacement transducer whose zero creeps through a long record: the
fit's ``drift_<channel>`` per second, from the detected release). With a rigid
superstructure (models ``linear`` and ``bilinear``) the roof moves with the isolation layer.

:func:`load_building` turns a case into :class:`BuildingData`: the ``[building]`` values as a model (the
design values: start values of a fit, the truth of ``synth``, the assumed building of planning) and the
record's channels in SI units, missing samples skipped and reported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..building.hysteretic import GRAVITY, BoucWen, Pendulum
from ..building.model import RECORD_CHANNELS, Isolation, TwoDOF
from ..errors import ParameterError, QuickReleaseError
from .records import RecordSpec, check_release_time, load_record, noise_floor, parse_record_spec

if TYPE_CHECKING:
    from ..building.isolation_fit import BuildingChannel
    from .case import BuildingSpec, Case

__all__ = ["BUILDING_CHANNELS", "BuildingData", "load_building", "parse_building_record", "spec_building",
           "spec_isolation", "pushed_displacement", "constant_friction", "constant_friction_fixed"]

#: Channel name -> (quantity kind, SI unit, description) of the building's record (the table of
#: :data:`quickrelease.building.model.RECORD_CHANNELS`).
BUILDING_CHANNELS: dict[str, tuple[str, str, str]] = RECORD_CHANNELS
#: Fewest valid samples of a channel (a fit needs the rest before the release and the motion after it).
MIN_SAMPLES = 10


def constant_friction(spec: BuildingSpec) -> bool:
    """Whether ``[building]`` gives the friction pendulum a constant friction coefficient (``model = "pendulum"``
    with ``friction_coefficient``, not Constantinou's friction_slow, friction_fast and rate): its fits hold
    the rate at 0 (:func:`constant_friction_fixed`)."""
    return spec.model == "pendulum" and spec.friction_coefficient is not None


def constant_friction_fixed(start: dict[str, float] | None = None) -> dict[str, float]:
    """The parameters a fit of the friction pendulum holds fixed (``fit_isolation(fixed=...)``) for a constant
    friction coefficient mu: Constantinou's rate a at 0 [s/m], so that ``mu(v) = mu_slow`` at every speed and the
    fit's friction_slow is mu, and mu_fast, which then plays no part, at the start's friction_slow (0 without
    one). A free decay at constant friction does not identify mu_fast and a: fitted, their profiles run over
    their whole ranges (the rate "not identified" in [0, 1000] s/m) and the fit costs several times more.
    Building campaigns and ``quickrelease building`` both call this."""
    return {"rate": 0.0, "friction_fast": float((start or {}).get("friction_slow", 0.0))}


def parse_building_record(table: Any, source: str, base: Path) -> RecordSpec:
    """Validate ``[building.record]`` (the grammar of :func:`quickrelease.io.records.parse_record_spec`, the
    channels of :data:`BUILDING_CHANNELS`, an offset on every channel by default)."""
    return parse_record_spec(table, source, base, channels=BUILDING_CHANNELS, offsets=tuple(BUILDING_CHANNELS),
                             section="building.record", drifts=True)


def spec_isolation(spec: BuildingSpec) -> Isolation | Pendulum | BoucWen:
    """The ``[building]`` values as an :class:`~quickrelease.building.model.Isolation` (SI units).

    ``linear``: ``Isolation.linear(mass, T, zeta, F_s)``; ``bilinear``: ``Isolation.bilinear(mass, k1, k2,
    F_y, zeta, F_s)``; ``2dof``: the isolation layer with the superstructure taken as rigid on it, the whole
    mass on the layer's period T (the rigid-body mode; the superstructure's own mode is left out). Without
    a mass (linear only) a unit mass stands in when the friction is 0 (the motion depends on F_s / m only).
    Planning's model (:func:`quickrelease.studies.planning.building_isolation`); the 2dof building itself is
    :func:`spec_building`'s.
    """
    spec.require_design("the building's model")
    friction = spec.friction_force
    mass = spec.mass
    if mass is None:
        if friction > 0.0:
            raise ParameterError("[building] mass", None, "given with the isolators' friction (the motion depends "
                                 "on friction / mass)", "kg")
        mass = 1.0
    if spec.model == "pendulum":
        k = mass * GRAVITY / spec.radius
    elif spec.model == "boucwen":
        k = spec.post_yield_stiffness
    elif spec.model == "bilinear":
        k = spec.k1
    else:
        k = mass * (2.0 * math.pi / spec.period) ** 2
    if spec.damping == "power":
        c, alpha = spec.damping_coefficient, spec.damping_exponent
    else:  # the damping ratio refers to the stiffness named above (k, k1, W / R, Kd)
        c, alpha = 2.0 * spec.damping_ratio * math.sqrt(k * mass), 1.0
    if spec.model == "pendulum":
        return Pendulum(mass, spec.radius, spec.friction_slow or 0.0, spec.friction_fast, spec.rate or 0.0, c, alpha)
    if spec.model == "boucwen":
        return BoucWen(mass, spec.post_yield_stiffness, spec.characteristic_strength, spec.yield_displacement,
                       spec.shape if spec.shape is not None else 1.0, c, alpha, friction)
    if spec.model == "bilinear":
        if alpha != 1.0:
            return Isolation(mass, spec.k1, c, friction, spec.k2, spec.yield_force, damping_exponent=alpha)
        return Isolation.bilinear(mass, spec.k1, spec.k2, spec.yield_force, spec.damping_ratio, friction)
    if alpha != 1.0:
        return Isolation(mass, k, c, friction, damping_exponent=alpha)
    return Isolation.linear(mass, spec.period, spec.damping_ratio, friction)


def spec_building(spec: BuildingSpec) -> Isolation | TwoDOF:
    """The ``[building]`` values as the model they name (SI units): :func:`spec_isolation` for ``linear`` and
    ``bilinear``; for ``2dof`` the :class:`~quickrelease.building.model.TwoDOF` building, ``TwoDOF(mass, m_s, T,
    T_s, zeta, F_s, zeta_s)`` (``mass`` the whole mass on the isolators, ``m_s`` lumped at the roof, T the
    isolation period of the whole mass, T_s the superstructure's fixed-base period); with ``flexible = true`` (and
    for 2dof with ``damping = "power"``) the layer of :func:`spec_isolation` under the superstructure, a
    :class:`~quickrelease.building.flexible.FlexibleBuilding`. Planning keeps :func:`spec_isolation` (the 2dof
    building rigid on its isolation layer)."""
    from ..building.flexible import FlexibleBuilding

    if spec.model != "2dof" and spec.flexible:  # the layer under a flexible superstructure
        spec.require_design("the building's model")
        return FlexibleBuilding(spec_isolation(spec), float(spec.superstructure_mass),
                                float(spec.superstructure_period), float(spec.superstructure_damping_ratio or 0.0))
    if spec.model != "2dof":
        return spec_isolation(spec)
    spec.require_design("the building's model")
    if spec.mass is None:
        raise ParameterError("[building] mass", None, "given for model = '2dof' (its stiffnesses act on the mass)",
                             "kg")
    if spec.damping == "power":  # the linear layer with a power-law damper: no closed form, the flexible integrator
        return FlexibleBuilding(spec_isolation(spec), float(spec.superstructure_mass),
                                float(spec.superstructure_period), float(spec.superstructure_damping_ratio or 0.0))
    return TwoDOF(mass=float(spec.mass), superstructure_mass=float(spec.superstructure_mass), period=float(spec.period),
                  superstructure_period=float(spec.superstructure_period), damping_ratio=float(spec.damping_ratio),
                  friction=float(spec.friction_force),
                  superstructure_damping_ratio=float(spec.superstructure_damping_ratio or 0.0))


@dataclass(frozen=True, eq=False)
class BuildingData:
    """The building of a case: its ``[building]`` values and its record (SI units)."""

    model: str
    """``"linear"``, ``"bilinear"``, ``"2dof"``, ``"pendulum"`` or ``"boucwen"``."""
    mass: float
    """Mass carried by the isolators, the whole building [kg]."""
    isolation: Isolation | TwoDOF | None
    """The ``[building]`` values as a model of :mod:`quickrelease.building` (:func:`spec_building`: an
    :class:`~quickrelease.building.model.Isolation`, or for 2dof a :class:`~quickrelease.building.model.TwoDOF`)."""
    start: dict[str, float]
    """The ``[building]`` values given, as start values in :func:`quickrelease.building.isolation_fit.fit_isolation`'s
    parameter names: period [s] (bilinear: the initial period 2 pi sqrt(m / k1)), stiffness_ratio = k2 / k1,
    yield_force [N], damping_ratio, friction [N], d0 [m]; 2dof also superstructure_period [s] and
    superstructure_damping_ratio."""
    d0: float | None
    """Pushed displacement [m] when ``[building] displacement`` is given."""
    channels: list[BuildingChannel]
    """The record's channels (SI; missing samples skipped); empty without ``[building.record]``."""
    release_time: float | None
    """``[building.record] release_time`` (a start value) [s, record time]."""
    notes: list[str] = field(default_factory=list)
    """What was found while reading the record (missing samples, rows without a time)."""
    source: str = "<case>"
    superstructure_mass: float | None = None
    """2dof: the superstructure's mass at the roof [kg] (part of ``mass``)."""
    spec: BuildingSpec | None = None
    """The parsed ``[building]`` table."""
    exclude_spikes: bool = False
    """``[building.record] spikes = "exclude"``: the fit leaves out the samples its residuals show as spikes."""
    jitter: dict[str, float] = field(default_factory=dict)
    """Per channel, how far its time stamps scatter about a uniform clock [s] where the record says so
    (:func:`quickrelease.io.timebase.time_base`; for :func:`quickrelease.building.decay.analyse_decay`'s ``jitter``)."""
    flexible: bool = False
    """``[building] flexible = true``: the layer (bilinear, pendulum, boucwen) under a flexible superstructure of
    ``superstructure_mass`` (``fit_isolation(flexible=True)``)."""
    constant_friction: bool = False
    """The pendulum's friction is a constant coefficient (``[building] friction_coefficient``,
    :func:`constant_friction`): its fit holds the rate at 0 (:func:`constant_friction_fixed`)."""


def _start(spec: BuildingSpec) -> dict[str, float]:
    start: dict[str, float] = {}
    if spec.model == "bilinear":
        if spec.k1 is not None:
            start["period"] = 2.0 * math.pi * math.sqrt(spec.mass / spec.k1)
            if spec.k2 is not None:
                start["stiffness_ratio"] = spec.k2 / spec.k1
        if spec.yield_force is not None:
            start["yield_force"] = spec.yield_force
    elif spec.model == "pendulum":
        if spec.radius is not None:
            start["period"] = 2.0 * math.pi * math.sqrt(spec.radius / GRAVITY)
        if spec.friction_slow is not None:
            start["friction_slow"] = spec.friction_slow
            start["friction_fast"] = spec.friction_fast if spec.friction_fast is not None else spec.friction_slow
        if spec.rate is not None:
            start["rate"] = spec.rate
    elif spec.model == "boucwen":
        if spec.post_yield_stiffness is not None:
            start["period"] = 2.0 * math.pi * math.sqrt(spec.mass / spec.post_yield_stiffness)
        for key in ("characteristic_strength", "yield_displacement", "shape"):
            if getattr(spec, key) is not None:
                start[key] = getattr(spec, key)
    elif spec.period is not None:
        start["period"] = spec.period
    if spec.damping == "power":
        for key in ("damping_coefficient", "damping_exponent"):
            if getattr(spec, key) is not None:
                start[key] = getattr(spec, key)
    elif spec.damping_ratio > 0.0:
        start["damping_ratio"] = spec.damping_ratio
    if spec.model != "pendulum" and (spec.friction is not None or spec.friction_coefficient is not None):
        start["friction"] = spec.friction_force
    if spec.displacement is not None:
        start["d0"] = spec.displacement
    if spec.model == "2dof" or spec.flexible:
        if spec.superstructure_period is not None:
            start["superstructure_period"] = spec.superstructure_period
        if spec.superstructure_damping_ratio:
            start["superstructure_damping_ratio"] = spec.superstructure_damping_ratio
    return start


def load_building(case: Case) -> BuildingData:
    """The building of ``case``: ``[building]`` as a model and start values, and ``[building.record]`` read.

    Raises
    ------
    CaseFileError
        No ``[building]`` table, or no mass for a record to be fitted; one line naming the file and key.
    RecordError
        A record file or column missing, a unit of the wrong dimension, a time column not increasing, a
        channel with fewer than :data:`MIN_SAMPLES` valid samples, a noise level above the channel's range,
        a release time outside the record's time span; one line naming the file and the column or key.
    """
    from ..building.isolation_fit import BuildingChannel
    from ..errors import CaseFileError
    from .records import RecordError

    spec = case.building
    if spec is None:
        raise CaseFileError(f"{case.source}: missing table [building] (the isolated building: model, mass, period, "
                            "damping_ratio, friction; [building.record] for its record)")
    if spec.mass is None:
        raise CaseFileError(f"{case.source}: missing key [building] mass (or weight): the building's record "
                            "fixes its parameters per unit mass only, e.g. mass = '650 t'")
    isolation = spec_building(spec) if not spec.missing_design() else None
    channels: list[BuildingChannel] = []
    notes: list[str] = []
    release_time = None
    jitter: dict[str, float] = {}
    if spec.record is not None:
        record = load_record(spec.record)
        check_release_time(spec.record, record)
        notes = list(record.notes)
        release_time = record.release_time
        for name, ch in record.channels.items():
            where = f"{(ch.spec.file or spec.record.file)}: column {ch.spec.column!r} (channel {name})"
            if ch.values.size < MIN_SAMPLES:
                raise RecordError(f"{where}: {ch.values.size} valid sample(s), fewer than {MIN_SAMPLES}")
            if ch.jitter > 0.0:
                jitter[name] = ch.jitter
            if ch.spec.noise is not None and not ch.spec.noise >= noise_floor(ch.values):
                unit = BUILDING_CHANNELS[name][1]
                raise RecordError(f"{where}: noise = {ch.spec.noise:.3g} {unit}: expected a noise standard deviation "
                                  f"of at least {noise_floor(ch.values):.3g} {unit}, 1e-14 times the channel's "
                                  "largest value (weights of 1/noise below it are set by rounding)")
            try:
                channels.append(BuildingChannel(name=name, kind=name, t=ch.t, values=ch.values,
                                                noise=ch.spec.noise, offset=ch.spec.offset,
                                                drift=ch.spec.drift))
            except QuickReleaseError as exc:
                raise RecordError(f"{where}: {exc}") from None
    start = _start(spec)
    if ("d0" not in start and channels and not any(c.kind in ("x", "x_roof") for c in channels)
            and case.has_test and case.push_force is not None and not spec.missing_design()):
        # no displacement in the record: d0 from the push force and the design values, one start among the
        # fit's (which searches d0 too)
        start["d0"] = pushed_displacement(case.push_force, spec)
    return BuildingData(model=spec.model, mass=float(spec.mass), isolation=isolation, start=start,
                        d0=spec.displacement, channels=channels, release_time=release_time, notes=notes,
                        source=case.source, superstructure_mass=spec.superstructure_mass, spec=spec, jitter=jitter,
                        exclude_spikes=spec.record is not None and spec.record.spikes == "exclude",
                        constant_friction=constant_friction(spec), flexible=spec.flexible and spec.model != "2dof")


def pushed_displacement(push_force: float, building: BuildingSpec) -> float:
    """The building's displacement under the push, d0 [m]: given, else where the push ``P`` is held by the
    isolators' friction and restoring force, ``P - F_f = R(d0)``: ``(P - F_f) / k`` with
    ``k = m (2 pi / T)^2`` (linear, 2dof), and on the bilinear push curve ``(P - F_f) / k1`` up to the
    yield force, ``d_y + (P - F_f - F_y) / k2`` beyond it (``d_y = F_y / k1``)."""
    if building.displacement is not None:
        return building.displacement
    building.require_design("d0 from the push force (without [building] displacement)")
    held = max(push_force - building.friction_force, 0.0)
    if building.model == "bilinear":
        k1, k2, F_y = building.k1, building.k2, building.yield_force
        return held / k1 if held <= F_y else F_y / k1 + (held - F_y) / k2
    if building.model == "pendulum":  # the weight's restoring force W d0 / R holds P less mu_slow W
        weight = building.mass * GRAVITY
        return max(push_force - (building.friction_slow or 0.0) * weight, 0.0) * building.radius / weight
    if building.model == "boucwen":  # Kd d0 + Qd z(d0) = P - F_s on the monotonic push curve
        from scipy.optimize import brentq

        iso = spec_isolation(building)
        if held <= 0.0:
            return 0.0
        hi = held / iso.k2
        return brentq(lambda d: iso.k2 * d + iso.characteristic_strength * iso.pushed(d) - held, 1e-12, hi,
                      xtol=1e-15, rtol=1e-13)
    k = building.mass * (2.0 * math.pi / building.period) ** 2
    return held / k
