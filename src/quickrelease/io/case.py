"""Case files: a device, a test set-up and friction or observations, in one TOML file.

A case file is what an engineer keeps with the test records::

    title = "Paper test (Table 7)"
    notes = "Free text, shown (escaped) in the report."

    [device]
    preset = "paper"            # or: file = "my_device.toml" (relative to this file), or Table 2 keys inline

    [test]
    force = "1598 kN"           # and/or: energy = "2.90 kJ" (when both: E_S drives the release,
                                # P the statics: fuse force, member forces, Eq. 2 breakdown)
    alpha0 = "0.2 rad"
    mass_model = "distributed"  # "lumped" or a number c

    [friction]                  # to simulate
    F1 = "419.85 N"
    F2 = "804.57 N"

    [observations]              # to identify (then simulate with the identified friction)
    alpha_final = "0.7378 rad"
    stop_time = "1.05 s"

    [simulation]                # optional
    method = "energy"           # "rk", "explicit"
    dt = "0.1 ms"               # explicit only
    n_points = 1001
    t_end = "1.3 s"             # pad with rest samples after the stop

Quantities are bare SI numbers or strings with units. Every error names the file,
the key, the value and what was expected, on one line; unknown keys are errors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from .._validate import check_size
from ..building.hysteretic import RATE_RANGE
from ..building.isolation_fit import SUPERSTRUCTURE_PERIOD_MIN
from ..device.dynamics import mass_factor
from ..device.parameters import Device, load_device, preset, read_toml_text
from ..device.statics import StrainEnergy, strain_energy
from ..errors import CaseFileError, QuickReleaseError
from ..units import parse_quantity
from .records import RecordSpec, parse_record_spec

__all__ = ["Case", "CaseFileError", "Distribution", "FitOptions", "FuseSpec", "BuildingSpec", "BUILDING_MODELS",
           "PlanOptions", "STANDARD_GRAVITY", "load_case", "CASE_SCHEMA", "UNCERTAIN_KEYS"]

#: Entries that may be given with an uncertainty (a table with std, or low and high), and their
#: names in :attr:`Case.uncertainty`.
UNCERTAIN_KEYS = {("test", "force"): "force", ("test", "energy"): "energy", ("test", "alpha0"): "alpha0",
                  ("observations", "alpha_final"): "alpha_final", ("observations", "stop_time"): "stop_time",
                  ("friction", "F1"): "F1", ("friction", "F2"): "F2",
                  ("fuse", "rupture_strength"): "rupture_strength", ("fuse", "target"): "target"}


@dataclass(frozen=True)
class Distribution:
    """The uncertainty of one input: ``normal`` (loc = mean, scale = std) or ``uniform`` (loc = low,
    scale = high - low), SI units."""

    kind: str
    loc: float
    scale: float

    @property
    def nominal(self) -> float:
        return self.loc if self.kind == "normal" else self.loc + 0.5 * self.scale

    def sample(self, rng, n: int):
        if self.kind == "normal":
            return rng.normal(self.loc, self.scale, n)
        return rng.uniform(self.loc, self.loc + self.scale, n)

    def describe(self, unit: str) -> str:
        """The distribution for a person, in SI ``unit`` with its prefix: ``normal(mean 1598 kN, std 16 kN)``."""
        from ..report.display import quantity

        if self.kind == "normal":
            return f"normal(mean {quantity(self.loc, unit)}, std {quantity(self.scale, unit, 4)})"
        return f"uniform({quantity(self.loc, unit)}, {quantity(self.loc + self.scale, unit)})"


@dataclass(frozen=True)
class FuseSpec:
    """The ``[fuse]`` table: the fuse material and the candidate diameters and angles (SI units)."""

    rupture_strength: float
    """Mean rupture strength of the fuse material, from sample tests [Pa]."""
    rupture_strength_std: float = 0.0
    """Its standard deviation [Pa]."""
    diameters: tuple[float, ...] = ()
    """Candidate diameters of the fuse's calibrated section [m]; the device's A4 when empty."""
    angles: tuple[float, ...] = ()
    """Candidate angles alpha0 [rad]; the case's alpha0 when empty."""
    target: tuple[float, float] | None = None
    """Target push force, (low, high) [N]; the case's P +- tolerance when not given."""
    tolerance: float = 0.05
    """Relative tolerance on a single target force [-]."""


#: Models of the isolated building (``[building] model``).
BUILDING_MODELS = ("linear", "bilinear", "2dof", "pendulum", "boucwen")
#: The damper's laws of ``[building] damping``.
DAMPING_LAWS = ("viscous", "power")


@dataclass(frozen=True)
class BuildingSpec:
    """The ``[building]`` table: the isolated building (SI units).

    ``model`` is ``linear`` (period, damping ratio, slider friction), ``bilinear`` (rubber bearings as a
    bilinear hysteretic spring k1, k2, F_y; damping ratio referred to k1; slider friction) or ``2dof``
    (the linear isolation layer under a flexible superstructure: a second mass at the roof with its own
    fixed-base period and damping). In planning the values are the assumed building, in ``synth`` the
    truth, in a fit of the building's record the start values. ``flexible = true`` puts a bilinear, pendulum or
    boucwen layer under a flexible superstructure the same way (superstructure_mass, superstructure_period,
    superstructure_damping_ratio: a :class:`~quickrelease.building.flexible.FlexibleBuilding`).
    """

    period: float | None = None
    """Isolation period T = 2 pi sqrt(mass / k) [s] (linear and 2dof; None for bilinear)."""
    damping_ratio: float = 0.0
    """Viscous damping ratio [-], in [0, 1) (bilinear: referred to k1)."""
    mass: float | None = None
    """Mass carried by the isolators, the whole building [kg] (or weight / g)."""
    friction: float | None = None
    """Coulomb friction of sliding isolators [N] (or friction_coefficient times the weight)."""
    friction_coefficient: float | None = None
    displacement: float | None = None
    """Pushed displacement d0 [m]; else from the push force: (P - friction) / k (linear), the bilinear
    push curve (bilinear)."""
    model: str = "linear"
    """``"linear"``, ``"bilinear"`` or ``"2dof"``."""
    k1: float | None = None
    """Initial stiffness of the bilinear bearings [N/m]."""
    k2: float | None = None
    """Post-yield stiffness of the bilinear bearings [N/m], in (0, k1)."""
    yield_force: float | None = None
    """Yield force of the bilinear bearings F_y [N]."""
    superstructure_mass: float | None = None
    """2dof: the superstructure's mass lumped at the roof [kg], part of ``mass`` (less than it)."""
    superstructure_period: float | None = None
    """2dof: the superstructure's fixed-base period [s]."""
    superstructure_damping_ratio: float | None = None
    """2dof: the superstructure's viscous damping ratio [-], in [0, 1)."""
    damping: str = "viscous"
    """The damper's law: ``"viscous"`` (damping_ratio) or ``"power"`` (damping_coefficient, damping_exponent)."""
    damping_coefficient: float | None = None
    """power: C [N (s/m)^alpha], the damper's force at 1 m/s."""
    damping_exponent: float | None = None
    """power: alpha [-]."""
    radius: float | None = None
    """pendulum: the sliding surface's radius R [m]."""
    friction_slow: float | None = None
    """pendulum: mu_slow [-] (or friction_coefficient: constant friction)."""
    friction_fast: float | None = None
    """pendulum: mu_fast [-] (default: mu_slow)."""
    rate: float | None = None
    """pendulum: Constantinou's rate a [s/m] (default 0: constant friction)."""
    post_yield_stiffness: float | None = None
    """boucwen: Kd [N/m]."""
    characteristic_strength: float | None = None
    """boucwen: Qd [N]."""
    yield_displacement: float | None = None
    """boucwen: dy [m]."""
    shape: float | None = None
    """boucwen: n [-] (default 1)."""
    flexible: bool = False
    """bilinear, pendulum, boucwen: the layer under a flexible superstructure (``superstructure_mass`` at the roof,
    its ``superstructure_period`` and ``superstructure_damping_ratio``), as 2dof puts the linear layer."""
    record: RecordSpec | None = None
    """The building's free-vibration record (``[building.record]``), read by
    :func:`quickrelease.io.building_case.load_building`."""

    @property
    def friction_force(self) -> float:
        """Coulomb friction force of the isolators [N]."""
        if self.friction is not None:
            return self.friction
        if self.friction_coefficient is not None:
            return self.friction_coefficient * self.mass * STANDARD_GRAVITY
        return 0.0

    @property
    def initial_period(self) -> float | None:
        """Period of the isolation layer's (initial) stiffness [s]: T, or 2 pi sqrt(mass / k1) (bilinear);
        None where the design values do not give it."""
        if self.period is not None:
            return self.period
        if self.k1 is None or self.mass is None:
            return None
        return 2.0 * math.pi * math.sqrt(self.mass / self.k1)

    def missing_design(self) -> list[str]:
        """The design values of the model that are not given (``[building]`` keys): a fit of the record needs
        none of them, ``synth``, planning and the clearance check need all."""
        keys = {"linear": ("period",), "bilinear": ("k1", "k2", "yield_force"),
                "2dof": ("period", "superstructure_period"), "pendulum": ("radius",),
                "boucwen": ("post_yield_stiffness", "characteristic_strength", "yield_displacement")}[self.model]
        if self.flexible and self.model != "2dof":
            keys = (*keys, "superstructure_period")
        if self.damping == "power":
            keys = (*keys, "damping_coefficient", "damping_exponent")
        return [k for k in keys if getattr(self, k) is None]

    def require_design(self, purpose: str) -> None:
        """Raise :class:`CaseFileError` naming the first design value missing for ``purpose`` (e.g.
        ``"synth"``)."""
        missing = self.missing_design()
        if missing:
            key = missing[0]
            flexible = " (flexible)" if self.flexible and self.model != "2dof" else ""
            raise CaseFileError(f"missing key [building] {key} for model = {self.model!r}{flexible}: {purpose} "
                                f"needs the design values ({CASE_SCHEMA['building'][key][1]}); a fit of the record "
                                "needs the mass only")


@dataclass(frozen=True)
class PlanOptions:
    """The ``[plan]`` table."""

    samples: int = 20_000
    """Friction samples of the release envelope when friction has a scatter."""
    seed: int = 0


STANDARD_GRAVITY = 9.80665
"""Standard gravity [m/s^2] (weight = mass g)."""


@dataclass(frozen=True)
class FitOptions:
    """The ``[fit]`` table: what a fit to a measured record estimates besides F1 and F2."""

    estimate_energy: bool = False
    """Estimate E_S (else fixed at the case's value)."""
    estimate_mass_factor: bool = False
    """Estimate the mass factor c (else fixed by the mass model)."""
    estimate_release_time: bool = True
    """Estimate the release instant (else fixed at ``[record] release_time``)."""
    absolute_sigma: bool = False
    """Take the channels' noise levels as exact (no scaling of the covariance by the reduced chi-square)."""
    use_observations: bool = True
    """Use ``[observations]`` given with a scatter as two more data (alpha_F, t_F)."""


#: Numbers whose valid range is not the default (> 0; an angle in (0, pi/2)).
_VALID = {
    ("friction", "F1"): lambda x: x >= 0.0,
    ("friction", "F2"): lambda x: x >= 0.0,
    ("friction", "correlation"): lambda x: -1.0 <= x <= 1.0,
    ("fuse", "tolerance"): lambda x: 0.0 < x < 1.0,
    ("building", "damping_ratio"): lambda x: 0.0 <= x < 1.0,
    ("building", "friction"): lambda x: x >= 0.0,
    ("building", "friction_coefficient"): lambda x: 0.0 <= x <= 1.0,
    ("building", "superstructure_damping_ratio"): lambda x: 0.0 <= x < 1.0,
    ("building", "damping_exponent"): lambda x: 0.05 <= x <= 2.0,
    ("building", "friction_slow"): lambda x: 0.0 <= x <= 1.0,
    ("building", "friction_fast"): lambda x: 0.0 <= x <= 1.0,
    # the isolators' ranges that depend on the mass, or say what an isolation system is: ISOLATOR_RANGES below
    ("building", "rate"): lambda x: x >= 0.0,
    ("building", "radius"): lambda x: x > 0.0,
    ("building", "yield_displacement"): lambda x: x > 0.0,
    ("building", "post_yield_stiffness"): lambda x: x > 0.0,
    ("building", "characteristic_strength"): lambda x: x > 0.0,
    ("building", "damping_coefficient"): lambda x: x >= 0.0,
    ("building", "shape"): lambda x: 0.5 <= x <= 25.0,
}

#: section -> key -> (quantity kind or type, what is expected)
CASE_SCHEMA: dict[str, dict[str, tuple[str, str]]] = {
    "": {"title": ("str", "a string"), "notes": ("str", "a string")},
    "device": {"preset": ("str", "a preset name"), "file": ("str", "a device file path")},
    "test": {
        "force": ("force", "a positive force, e.g. '1598 kN'"),
        "energy": ("energy", "a positive energy, e.g. '2.90 kJ'"),
        "alpha0": ("angle", "an angle in (0, pi/2), e.g. '0.2 rad' or '11.46 deg'"),
        "mass_model": ("mass_model", "'distributed', 'lumped' or a positive number"),
    },
    "friction": {
        "F1": ("force", "a force >= 0, e.g. '420 N'"),
        "F2": ("force", "a force >= 0, e.g. '0.8 kN'"),
        "correlation": ("dimensionless", "a correlation of F1 and F2 in [-1, 1] (with F1, F2 given a scatter)"),
        "case": ("str", "a case file whose identified friction (and its scatter) to use"),
    },
    "fuse": {
        "rupture_strength": ("pressure", "a positive stress, e.g. '610 MPa' or {value = '610 MPa', std = '15 MPa'}"),
        "diameters": ("list:length", "a list of positive lengths, e.g. ['24 mm', '26 mm']"),
        "angles": ("list:angle", "a list of angles in (0, pi/2), e.g. ['0.15 rad', '0.2 rad']"),
        "target": ("force", "a positive force, e.g. '1600 kN', or a range {low = '1500 kN', high = '1700 kN'}"),
        "tolerance": ("dimensionless", "a fraction in (0, 1), e.g. 0.05"),
    },
    "building": {
        "model": ("building_model", "'linear', 'bilinear', '2dof', 'pendulum' or 'boucwen'"),
        "damping": ("damping_law", "'viscous' (damping_ratio) or 'power' (damping_coefficient, damping_exponent)"),
        "damping_coefficient": ("force", "the power-law damper's force at 1 m/s, C [N (s/m)^alpha] in [0, 10 m g], "
                                "e.g. '400 kN'"),
        "damping_exponent": ("dimensionless", "the power-law damper's exponent alpha in [0.05, 2], e.g. 0.3"),
        "radius": ("length", "the friction pendulum's radius of curvature R in [0.01, 1000] m, e.g. '2.5 m'"),
        "friction_slow": ("dimensionless", "the pendulum's friction coefficient at low velocity in [0, 1], e.g. 0.03"),
        "friction_fast": ("dimensionless", "the pendulum's friction coefficient at high velocity in [0, 1], e.g. 0.07"),
        "rate": ("slowness", "Constantinou's rate a of mu(v) in [0, 1e4] s/m, e.g. '30 s/m'"),
        "post_yield_stiffness": ("stiffness", "the Bouc-Wen bearings' post-yield stiffness Kd, post-yield period "
                                 "2 pi sqrt(m / Kd) in [0.1, 100] s, e.g. '5 MN/m'"),
        "characteristic_strength": ("force", "the Bouc-Wen bearings' characteristic strength Qd in (0, m g], "
                                    "e.g. '300 kN'"),
        "yield_displacement": ("length", "the Bouc-Wen bearings' yield displacement dy in [1e-5, 1] m, e.g. '10 mm'"),
        "shape": ("dimensionless", "the Bouc-Wen shape exponent n in [0.5, 25], e.g. 1.0"),
        "period": ("time", "an isolation period in [0.01, 1000] s, e.g. '2.5 s'"),
        "damping_ratio": ("dimensionless", "a damping ratio in [0, 1), e.g. 0.1"),
        "mass": ("mass", "a positive mass, e.g. '1500 t'"),
        "weight": ("force", "a positive weight, e.g. '14700 kN'"),
        "friction": ("force", "a force >= 0 (sliding isolators), e.g. '150 kN'"),
        "friction_coefficient": ("dimensionless", "a friction coefficient in [0, 1] (times the weight), e.g. 0.01"),
        "displacement": ("length", "a positive pushed displacement d0, e.g. '50 mm'"),
        "k1": ("stiffness", "a positive initial stiffness of the bilinear bearings, e.g. '40 MN/m'"),
        "k2": ("stiffness", "a positive post-yield stiffness below k1, e.g. '4 MN/m'"),
        "yield_force": ("force", "a positive yield force of the bilinear bearings, e.g. '120 kN'"),
        "superstructure_mass": ("mass", "a positive mass below [building] mass (lumped at the roof), e.g. '500 t'"),
        "superstructure_period": ("time", "a fixed-base period of the superstructure in [0.02, 1000] s, e.g. "
                                  "'0.5 s'"),
        "superstructure_damping_ratio": ("dimensionless", "a damping ratio in [0, 1), e.g. 0.02"),
        "flexible": ("bool", "true or false: the bilinear, pendulum or boucwen layer under a flexible superstructure "
                     "(with superstructure_mass; the linear layer's is model = '2dof'); false with "
                     "superstructure_mass: the rigid layer, its flexible variant fitted by --flexible and --compare"),
    },
    "report": {
        "operator": ("str", "who ran the test or the analysis, e.g. 'A. Engineer'"),
        "organisation": ("str", "their organisation, e.g. 'Test lab Ltd'"),
        "test_id": ("str", "the test's identifier, e.g. 'QR-2024-07'"),
    },
    "plan": {
        "samples": ("int", "an integer >= 2 (friction samples of the release envelope)"),
        "seed": ("seed", "an integer in [0, 2^63)"),
    },
    "observations": {
        "alpha_final": ("angle", "an angle in (alpha0, pi/2), e.g. '0.7378 rad'"),
        "stop_time": ("time", "a positive time, e.g. '1.05 s'"),
    },
    "fit": {
        "estimate_energy": ("bool", "true or false (estimate E_S from the record)"),
        "estimate_mass_factor": ("bool", "true or false (estimate the mass factor c)"),
        "estimate_release_time": ("bool", "true or false (estimate the release instant; default true)"),
        "absolute_sigma": ("bool", "true or false (take the noise levels as exact: no chi-square scaling)"),
        "use_observations": ("bool", "true or false (use [observations] with a scatter as data; default true)"),
    },
    "simulation": {
        "method": ("method", "'energy', 'rk' or 'explicit'"),
        "dt": ("time", "a positive time step, e.g. '0.1 ms'"),
        "n_points": ("int", "an integer >= 2"),
        "t_end": ("time", "a positive time, e.g. '1.3 s'"),
        "rk_method": ("rk_method", "'DOP853' or 'RK45'"),
    },
}


@dataclass(frozen=True)
class Case:
    """A test described by a case file, resolved to SI values."""

    device: Device
    alpha0: float
    """Angle at release [rad]."""
    stored_energy: float
    """E_S [J]: as given, else from Eq. 2 with the push force."""
    push_force: float | None = None
    """P [N] when given (E_S then from Eq. 2)."""
    mass_model: str | float = "distributed"
    F1: float | None = None
    """Friction at the hinges [N] (to simulate)."""
    F2: float | None = None
    """Friction on the rail [N] (to simulate)."""
    alpha_final: float | None = None
    """Observed final angle [rad] (to identify)."""
    stop_time: float | None = None
    """Observed stop time [s] (to identify)."""
    method: str = "energy"
    dt: float | None = None
    n_points: int = 1001
    t_end: float | None = None
    rk_method: str = "DOP853"
    record: RecordSpec | None = None
    """The measured record to fit (``[record]``), read by :func:`quickrelease.io.records.load_record`."""
    fit: FitOptions = field(default_factory=FitOptions)
    """Options of the fit to the record (``[fit]``)."""
    fuse: FuseSpec | None = None
    """Fuse material and candidates for the fuse and angle choice (``[fuse]``)."""
    building: BuildingSpec | None = None
    """The building, for the clearance check (``[building]``)."""
    plan: PlanOptions = field(default_factory=lambda: PlanOptions())
    """Options of test planning (``[plan]``)."""
    friction_case: Case | None = None
    """The case whose identified friction this one uses (``[friction] case``)."""
    friction_correlation: float = 0.0
    """Correlation of F1 and F2 when both are given a scatter (``[friction] correlation``)."""
    uncertainty: dict[str, Distribution] = field(default_factory=dict)
    """Inputs with a scatter (force, energy, alpha0, alpha_final, stop_time) and their distributions."""
    energy_given: bool = False
    """True when E_S was given in the file (not computed from P by Eq. 2)."""
    title: str = "quickrelease case"
    notes: str = ""
    source: str = "<case>"
    source_text: str | None = field(default=None, repr=False)
    """The case file's text as read (echoed, with its SHA-256, in every output: :func:`quickrelease.io.runfolder.
    provenance`); None for a case not read from a file."""
    report: dict[str, str] = field(default_factory=dict)
    """The ``[report]`` table: who ran the test (``operator``, ``organisation``, ``test_id``), for the report's
    sign-off block."""
    has_test: bool = True
    """False for a case of the building alone (no ``[test]``: alpha0 and E_S are NaN; see :func:`load_case`)."""

    @property
    def mass_factor(self) -> float:
        return mass_factor(self.mass_model)

    @property
    def has_observations(self) -> bool:
        return self.alpha_final is not None and self.stop_time is not None

    @property
    def has_friction(self) -> bool:
        return self.F1 is not None or self.F2 is not None

    def strain(self) -> StrainEnergy | None:
        """Eq. 2's breakdown when the push force is known."""
        return None if self.push_force is None else strain_energy(self.push_force, self.alpha0, self.device)

    def replace(self, **changes: Any) -> Case:
        """A copy with some fields changed (e.g. command-line overrides)."""
        new = replace(self, **changes)
        if ("push_force" in changes or "alpha0" in changes or "device" in changes) and new.push_force is not None \
                and "stored_energy" not in changes and not self.energy_given:
            new = replace(new, stored_energy=strain_energy(new.push_force, new.alpha0, new.device).total)
        return new

    def inputs(self) -> dict[str, Any]:
        """The inputs with units in the key names (for reports and JSON)."""
        return {
            "device": self.device.name,
            "push_force_N": self.push_force,
            "stored_energy_J": self.stored_energy,
            "alpha0_rad": self.alpha0,
            "mass_model": self.mass_model,
            "mass_factor": self.mass_factor,
            "F1_N": self.F1,
            "F2_N": self.F2,
            "alpha_final_rad": self.alpha_final,
            "stop_time_s": self.stop_time,
            "method": self.method,
        }


def _fail(source: str, key: str, value: Any, expected: str) -> CaseFileError:
    shown = repr(value) if not isinstance(value, dict) else "a table"
    return CaseFileError(f"{source}: {key} = {shown}: expected {expected}")


#: The pushed displacement d0 a building's case or campaign release may give [m]: up to 10 m (isolators' design
#: displacements are below 2 m; displacement = "1e308 m" was fitted, and a campaign's laws took it as the amplitude).
DISPLACEMENT_RANGE = (1.0e-6, 10.0, "m")

#: The isolators' design values a case file may give, beyond which they are no isolation system (and the
#: floats overflow or underflow: radius = 1e308 m makes the restoring force 1e-302 N): the pendulum's radius
#: [m] (periods 2 pi sqrt(R / g) of 0.2 to 63 s; usual radii 1.5 to 4 m), Constantinou's rate [s/m] (3 / a, the
#: speed where mu reaches 95% of the way to mu_fast, down to 0.3 mm/s), the Bouc-Wen yield displacement [m],
#: the isolation period [s] (within the fit's bounds of 1e-3 to 1e3 s; period = "1e308 s" made the stiffness
#: 0 N/m, refused in a line that named neither the file nor the key) and the superstructure's (from the fit's
#: lower bound, a storey stiffer than that is rigid).
ISOLATOR_RANGES = {"radius": (0.01, 1000.0, "m"), "rate": (*RATE_RANGE, "s/m"),
                   "yield_displacement": (1.0e-5, 1.0, "m"), "displacement": DISPLACEMENT_RANGE,
                   "period": (0.01, 1000.0, "s"), "superstructure_period": (SUPERSTRUCTURE_PERIOD_MIN, 1000.0, "s")}
#: The post-yield period 2 pi sqrt(m / Kd) [s] the Bouc-Wen bearings' post_yield_stiffness may give.
POST_YIELD_PERIOD_RANGE = (0.1, 100.0)
#: Most characteristic strength Qd and most damper force at 1 m/s, in weights m g [-].
MOST_STRENGTH_WEIGHTS = 1.0
MOST_DAMPER_WEIGHTS = 10.0


def _check_isolator_ranges(values: dict[str, Any], table: Any, source: str, mass: float | None) -> None:
    """CaseFileError naming the first design value of the isolators outside its range (the key, its value and
    the range, in SI units; those scaled by the mass where the mass is given)."""
    for key, (lo, hi, unit) in ISOLATOR_RANGES.items():
        value = values.get(f"building.{key}")
        if value is not None and not lo <= value <= hi:
            raise _fail(source, f"[building] {key}", table[key], f"{key} in [{lo:g}, {hi:g}] {unit}")
    if mass is None:
        return
    weight = mass * STANDARD_GRAVITY
    t_lo, t_hi = ISOLATOR_RANGES["period"][:2]  # the bilinear bearings' stiffnesses give periods in that range
    k_lo, k_hi = mass * (2.0 * math.pi / t_hi) ** 2, mass * (2.0 * math.pi / t_lo) ** 2
    for key in ("k1", "k2"):  # k1 = "1e308 N/m" made the damping inf, refused naming neither file nor key
        value = values.get(f"building.{key}")
        if value is not None and not k_lo <= value <= k_hi:
            raise _fail(source, f"[building] {key}", table[key], f"{key} in [{k_lo:.6g}, {k_hi:.6g}] N/m (periods "
                        f"2 pi sqrt(m / {key}) of {t_lo:g} to {t_hi:g} s for the mass {mass:.6g} kg)")
    kd = values.get("building.post_yield_stiffness")
    t_lo, t_hi = POST_YIELD_PERIOD_RANGE
    k_lo, k_hi = mass * (2.0 * math.pi / t_hi) ** 2, mass * (2.0 * math.pi / t_lo) ** 2
    if kd is not None and not k_lo <= kd <= k_hi:
        raise _fail(source, "[building] post_yield_stiffness", table["post_yield_stiffness"],
                    f"post_yield_stiffness in [{k_lo:.6g}, {k_hi:.6g}] N/m (post-yield periods 2 pi sqrt(m / Kd) "
                    f"of {t_lo:g} to {t_hi:g} s for the mass {mass:.6g} kg)")
    for key, most, what in (("characteristic_strength", MOST_STRENGTH_WEIGHTS, "N"),
                            ("damping_coefficient", MOST_DAMPER_WEIGHTS, "N (s/m)^alpha")):
        value = values.get(f"building.{key}")
        if value is not None and not value <= most * weight:
            low = "(0" if key == "characteristic_strength" else "[0"  # Qd > 0 (_VALID), C >= 0
            raise _fail(source, f"[building] {key}", table[key], f"{key} in {low}, {most * weight:.6g}] {what} "
                        f"(at most {most:g} m g, the weight m g = {weight:.6g} N)")


#: The masses a building may have [kg]: 1 kg (a bench model) to 1e12 kg (a hundred times the heaviest
#: structure built). Outside it k = m (2 pi / T)^2 and c = 2 zeta sqrt(k m) leave the floats (1e-300 kg:
#: k m underflows to 0 and the damping ratio divides by it).
BUILDING_MASS_RANGE = (1.0, 1e12)


def _entry(source: str, section: str, key: str, value: Any) -> Any:
    """Validate and convert one entry of the case file."""
    kind, expected = CASE_SCHEMA[section][key]
    where = f"[{section}] {key}" if section else key
    if kind == "str":
        if not isinstance(value, str):
            raise _fail(source, where, value, expected)
        return value
    if kind == "bool":
        if not isinstance(value, bool):
            raise _fail(source, where, value, expected)
        return value
    if kind == "int":
        if isinstance(value, bool) or not isinstance(value, int) or value < 2:
            raise _fail(source, where, value, expected)
        try:  # a size: bounded by what the machine can hold, said before any work
            check_size(where, value, value)
        except QuickReleaseError as exc:
            raise CaseFileError(f"{source}: {exc}") from None
        return value
    if kind == "seed":
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < 2**63:
            raise _fail(source, where, value, expected)
        return value
    if kind.startswith("list:"):
        if not isinstance(value, list) or not value:
            raise _fail(source, where, value, expected)
        return tuple(_number(source, where, key, kind[5:], item, expected, section) for item in value)
    if kind == "mass_model":
        try:
            mass_factor(value)
        except QuickReleaseError:
            raise _fail(source, where, value, expected) from None
        return value
    if kind == "method":
        if value not in ("energy", "rk", "explicit"):
            raise _fail(source, where, value, expected)
        return value
    if kind == "building_model":
        if value not in BUILDING_MODELS:
            raise _fail(source, where, value, expected)
        return value
    if kind == "damping_law":
        if value not in DAMPING_LAWS:
            raise _fail(source, where, value, expected)
        return value
    if kind == "rk_method":
        if value not in ("DOP853", "RK45"):
            raise _fail(source, where, value, expected)
        return value
    if isinstance(value, dict) and (section, key) in UNCERTAIN_KEYS:
        return _distribution(source, section, key, value)
    if isinstance(value, dict | list):
        raise _fail(source, where, value, expected)
    return _number(source, where, key, kind, value, expected, section)


def _number(source: str, where: str, key: str, kind: str, value: Any, expected: str, section: str) -> float:
    """A quantity in SI units, checked against its valid range."""
    if isinstance(value, dict | list):
        raise _fail(source, where, value, expected)
    try:
        number = parse_quantity(value, kind, key)
    except QuickReleaseError as exc:
        reason = _strip_name(str(exc), key, value)
        if "has dimension" not in reason:  # what is not a quantity: the key's own range, not the grammar's example
            reason = f"{reason.split('; expected ')[0]}; expected {expected}"
        raise CaseFileError(f"{source}: {where} = {value!r}: {reason}") from None
    valid = _VALID.get((section, key))
    ok = math.isfinite(number) and (valid(number) if valid else number > 0.0)
    if kind == "angle" and number >= 0.5 * math.pi:
        ok = False
    if not ok:
        raise _fail(source, where, value, expected)
    return number


def _distribution(source: str, section: str, key: str, table: dict[str, Any]) -> Distribution:
    """A quantity with its scatter: {value, std} (normal) or {low, high} (uniform, value optional)."""
    where = f"[{section}] {key}"
    allowed = {"value", "std", "low", "high"}
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise CaseFileError(f"{source}: unknown key {unknown[0]!r} in {where}; valid: value, std (normal) or "
                            "low, high (uniform)")
    kind, _ = CASE_SCHEMA[section][key]

    def q(name: str) -> float:
        try:
            return parse_quantity(table[name], kind, f"{key}.{name}")
        except QuickReleaseError as exc:
            raise CaseFileError(f"{source}: {where}.{name}: {exc}") from None

    if "std" in table:
        if "value" not in table or "low" in table or "high" in table:
            raise CaseFileError(f"{source}: {where}: a normal uncertainty needs value and std (and no low, high)")
        std = q("std")
        if not (math.isfinite(std) and std >= 0.0):
            raise _fail(source, f"{where}.std", table["std"], "a standard deviation >= 0")
        return Distribution("normal", _entry(source, section, key, table["value"]), std)
    if "low" in table and "high" in table:
        low, high = _entry(source, section, key, table["low"]), _entry(source, section, key, table["high"])
        if not high > low:
            raise _fail(source, f"{where}.high", table["high"], f"a value above low = {table['low']!r}")
        return Distribution("uniform", low, high - low)
    raise CaseFileError(f"{source}: {where}: give value and std (normal) or low and high (uniform)")


def _strip_name(reason: str, key: str, value: Any) -> str:
    prefix = f"{key} = {value!r} "
    return reason[len(prefix):] if reason.startswith(prefix) else reason


def load_case(path: str | Path, *, require_test: bool = True) -> Case:
    """Read and validate a case file.

    With ``require_test=False`` a case of the building alone (``[building]`` with its record, no ``[test]``)
    is valid too: its device test is absent (``has_test`` False, alpha0 and E_S NaN), for the commands that
    analyse or synthesize the building only.

    Raises
    ------
    CaseFileError
        For malformed TOML, missing, unknown or invalid entries; the one-line
        message names the file, the key, the value and what was expected.
    """
    path = Path(path)
    source = str(path)
    data, text = read_toml_text(path, "case file", CaseFileError)
    case = case_from_mapping(data, source=source, base=path.parent, require_test=require_test)
    return replace(case, source_text=text)


def case_from_mapping(data: dict[str, Any], source: str = "<case>", base: Path | None = None, *,
                      require_test: bool = True) -> Case:
    """Build a Case from the parsed TOML mapping (see :func:`load_case`)."""
    base = base or Path.cwd()
    sections = [s for s in CASE_SCHEMA if s] + ["record"]
    values: dict[str, Any] = {}
    for key, value in data.items():
        if isinstance(value, dict) and key in sections:
            continue
        if key not in CASE_SCHEMA[""]:
            valid = ", ".join(list(CASE_SCHEMA[""]) + [f"[{s}]" for s in sections])
            raise CaseFileError(f"{source}: unknown key {key!r}; valid top-level entries: {valid}")
        values[key] = _entry(source, "", key, value)
    for section in sections:
        table = data.get(section, {})
        if not isinstance(table, dict):
            raise _fail(source, section, table, f"a table [{section}]")
        if section in ("device", "record"):
            continue
        for key, value in table.items():
            if section == "building" and key == "record":  # [building.record]: parsed with [building]
                continue
            if key not in CASE_SCHEMA[section]:
                raise CaseFileError(f"{source}: unknown key [{section}] {key!r}; "
                                    f"valid: {', '.join(CASE_SCHEMA[section])}")
            values[f"{section}.{key}"] = _entry(source, section, key, value)
    device = _device(data.get("device", {}), source, base)
    building = _building(values, data.get("building"), source, base)
    if "test" not in data and not require_test and building is not None:  # a case of the building alone
        return Case(device=device, alpha0=math.nan, stored_energy=math.nan, building=building, has_test=False,
                    title=values.get("title", Path(source).stem), notes=values.get("notes", ""), source=source,
                    report=_report(values))
    if "test" not in data:
        raise CaseFileError(f"{source}: missing table [test] (force or energy, alpha0)")
    if "test.alpha0" not in values:
        raise CaseFileError(f"{source}: missing key [test] alpha0 ({CASE_SCHEMA['test']['alpha0'][1]})")
    has_force, has_energy = "test.force" in values, "test.energy" in values
    if not (has_force or has_energy):
        raise CaseFileError(f"{source}: missing key [test] force or energy (a push force, e.g. '1598 kN', "
                            "or a stored energy, e.g. '2.90 kJ')")
    friction = data.get("friction")
    friction_case = None
    if friction is not None and "case" in friction:
        if "F1" in friction or "F2" in friction:
            raise CaseFileError(f"{source}: [friction] case beside F1, F2: give one or the other")
        file = Path(values["friction.case"])
        try:
            friction_case = load_case(file if file.is_absolute() else base / file)
        except RecursionError:
            raise CaseFileError(f"{source}: [friction] case refers back to itself") from None
    elif friction is not None and not {"F1", "F2"} <= set(friction):
        missing = sorted({"F1", "F2"} - set(friction))
        raise CaseFileError(f"{source}: missing key [friction] {missing[0]} (give both F1 and F2)")
    observations = data.get("observations")
    if observations is not None and set(observations) != {"alpha_final", "stop_time"}:
        missing = sorted({"alpha_final", "stop_time"} - set(observations))
        raise CaseFileError(f"{source}: missing key [observations] {missing[0]} (give alpha_final and stop_time)")
    record = None
    if "record" in data:
        try:
            record = parse_record_spec(data["record"], source, base)
        except QuickReleaseError as exc:
            raise CaseFileError(str(exc)) from None
    if friction is None and observations is None and record is None:
        raise CaseFileError(f"{source}: missing table [friction] (to simulate), [observations] (to identify) "
                            "or [record] (to fit)")
    uncertainty = {}
    for (section, key), name in UNCERTAIN_KEYS.items():
        value = values.get(f"{section}.{key}")
        if isinstance(value, Distribution):
            uncertainty[name] = value
            values[f"{section}.{key}"] = value.nominal
    alpha0 = values["test.alpha0"]
    aF = values.get("observations.alpha_final")
    if aF is not None and aF <= alpha0:
        raise _fail(source, "[observations] alpha_final", observations["alpha_final"],
                    f"an angle greater than alpha0 = {alpha0:.6g} rad")
    P = values.get("test.force")
    E_S = values["test.energy"] if has_energy else strain_energy(P, alpha0, device).total
    sim = {k.split(".", 1)[1]: v for k, v in values.items() if k.startswith("simulation.")}
    fit = FitOptions(**{k.split(".", 1)[1]: v for k, v in values.items() if k.startswith("fit.")})
    fuse = _fuse(values, uncertainty, data.get("fuse"), source)
    plan = PlanOptions(**{k.split(".", 1)[1]: v for k, v in values.items() if k.startswith("plan.")})
    return Case(
        device=device, alpha0=alpha0, stored_energy=E_S, push_force=P,
        mass_model=values.get("test.mass_model", "distributed"),
        F1=values.get("friction.F1"), F2=values.get("friction.F2"),
        alpha_final=aF, stop_time=values.get("observations.stop_time"),
        energy_given=has_energy, uncertainty=uncertainty, record=record, fit=fit, fuse=fuse, building=building,
        plan=plan, friction_case=friction_case, friction_correlation=values.get("friction.correlation", 0.0),
        title=values.get("title", Path(source).stem), notes=values.get("notes", ""), source=source,
        report=_report(values), **sim,
    )


def _report(values: dict[str, Any]) -> dict[str, str]:
    """The ``[report]`` entries (operator, organisation, test_id) given."""
    return {k.split(".", 1)[1]: v for k, v in values.items() if k.startswith("report.")}


def _device(table: dict[str, Any], source: str, base: Path) -> Device:
    if not table:
        return preset("paper")
    where = f"{source} [device]"
    if "preset" in table or "file" in table:
        extra = sorted(set(table) - {"preset", "file"})
        if extra or ("preset" in table and "file" in table):
            key = extra[0] if extra else "file"
            raise CaseFileError(f"{where}: unknown key {key!r} beside preset/file; give one of preset, file or "
                                "the Table 2 keys inline")
        if "preset" in table:
            name = _entry(source, "device", "preset", table["preset"])
            try:
                return preset(name)
            except QuickReleaseError as exc:
                raise CaseFileError(f"{where}: {exc}") from None
        file = Path(_entry(source, "device", "file", table["file"]))
        return load_device(file if file.is_absolute() else base / file)
    return Device.from_mapping(table, source=where)


def _fuse(values: dict[str, Any], uncertainty: dict[str, Distribution], table: Any, source: str) -> FuseSpec | None:
    if table is None:
        return None
    if "fuse.rupture_strength" not in values:
        raise CaseFileError(f"{source}: missing key [fuse] rupture_strength (the fuse material's, e.g. '610 MPa')")
    strength = uncertainty.pop("rupture_strength", values["fuse.rupture_strength"])
    mean, std = (strength.loc, strength.scale) if isinstance(strength, Distribution) else (strength, 0.0)
    if isinstance(strength, Distribution) and strength.kind != "normal":
        mean, std = strength.nominal, strength.scale / math.sqrt(12.0)
    target = uncertainty.pop("target", values.get("fuse.target"))
    if isinstance(target, Distribution):
        if target.kind != "uniform":
            raise CaseFileError(f"{source}: [fuse] target: give a force or a range {{low = ..., high = ...}}")
        target = (target.loc, target.loc + target.scale)
    elif target is not None:
        tol = values.get("fuse.tolerance", 0.05)
        target = (target * (1.0 - tol), target * (1.0 + tol))
    return FuseSpec(rupture_strength=mean, rupture_strength_std=std, diameters=values.get("fuse.diameters", ()),
                    angles=values.get("fuse.angles", ()), target=target, tolerance=values.get("fuse.tolerance", 0.05))


#: The keys each building model uses beyond mass/weight, damping_ratio, friction, displacement.
_MODEL_KEYS = {
    "linear": ("period",),
    "bilinear": ("k1", "k2", "yield_force"),
    "2dof": ("period", "superstructure_mass", "superstructure_period", "superstructure_damping_ratio"),
    "pendulum": ("radius", "friction_slow", "friction_fast", "rate"),
    "boucwen": ("post_yield_stiffness", "characteristic_strength", "yield_displacement", "shape"),
}
#: Keys that only some models take.
_MODEL_ONLY = {key for keys in _MODEL_KEYS.values() for key in keys}
#: The superstructure's keys: 2dof's, and those of a layer with ``flexible = true``.
_STOREY_KEYS = ("superstructure_mass", "superstructure_period", "superstructure_damping_ratio")
#: The models that take ``flexible = true``.
FLEXIBLE_MODELS = ("bilinear", "pendulum", "boucwen")


def _building(values: dict[str, Any], table: Any, source: str, base: Path) -> BuildingSpec | None:
    """The ``[building]`` table (and ``[building.record]``): every inconsistency one line naming the key,
    its value and what the model expects."""
    if table is None:
        return None
    model = values.get("building.model", "linear")
    given = {key.split(".", 1)[1] for key in values if key.startswith("building.")}
    flexible = bool(values.get("building.flexible", False)) and model != "2dof"  # (2dof: flexible already)
    if flexible and model not in FLEXIBLE_MODELS:
        raise CaseFileError(f"{source}: [building] flexible = true with model = {model!r}: the linear layer under a "
                            "flexible superstructure is model = '2dof' (flexible takes model = "
                            f"{', '.join(repr(m) for m in FLEXIBLE_MODELS)})")
    if flexible and "superstructure_mass" not in given:
        raise CaseFileError(f"{source}: missing key [building] superstructure_mass for flexible = true "
                            f"({CASE_SCHEMA['building']['superstructure_mass'][1]})")
    # the superstructure's mass with a rigid bilinear, pendulum or boucwen layer: for --flexible and --compare's
    # flexible variant (its period and damping are design values of the flexible building only)
    allowed = set(_MODEL_KEYS[model]) | (set(_STOREY_KEYS) if flexible else
                                         {"superstructure_mass"} if model in FLEXIBLE_MODELS else set())
    for key in sorted(given & _MODEL_ONLY - allowed):
        users = " or ".join(m for m, keys in _MODEL_KEYS.items() if key in keys)
        raise CaseFileError(f"{source}: [building] {key} = {table[key]!r} with model = {model!r}: {key} belongs "
                            f"to model = {users!r}{' or flexible = true' if key in _STOREY_KEYS else ''} (the "
                            f"{model} model takes {', '.join(_MODEL_KEYS[model])})")
    # the design values (period, k1, k2, yield_force, superstructure_period, ...) are optional: a fit of the
    # record needs the mass only (and the 2dof model the superstructure's share of it); what needs them
    # (synth, planning, the clearance check) says which is missing (BuildingSpec.require_design)
    if model == "2dof" and "superstructure_mass" not in given:
        raise CaseFileError(f"{source}: missing key [building] superstructure_mass for model = '2dof' "
                            f"({CASE_SCHEMA['building']['superstructure_mass'][1]})")
    mass = values.get("building.mass")
    if "building.weight" in values:
        if mass is not None:
            raise CaseFileError(f"{source}: [building] mass and weight: give one of the two")
        mass = values["building.weight"] / STANDARD_GRAVITY
    if mass is not None and not BUILDING_MASS_RANGE[0] <= mass <= BUILDING_MASS_RANGE[1]:
        key = "weight" if "building.weight" in values else "mass"
        raise _fail(source, f"[building] {key}", table[key], f"a building's mass in [{BUILDING_MASS_RANGE[0]:g}, "
                    f"{BUILDING_MASS_RANGE[1]:g}] kg (its stiffness and damping are products with the mass: "
                    "outside this range they underflow or overflow)")
    damping = values.get("building.damping", "viscous")
    for key in ("damping_coefficient", "damping_exponent"):
        if key in given and damping != "power":
            raise CaseFileError(f"{source}: [building] {key} = {table[key]!r} with damping = {damping!r}: {key} "
                                "belongs to damping = 'power' (the viscous damper takes damping_ratio)")
    if damping == "power" and "damping_ratio" in given:
        raise CaseFileError(f"{source}: [building] damping_ratio = {table['damping_ratio']!r} with damping = "
                            "'power': the power-law damper takes damping_coefficient and damping_exponent")
    if model == "pendulum" and "friction" in given:
        raise CaseFileError(f"{source}: [building] friction = {table['friction']!r} with model = 'pendulum': give "
                            "friction_coefficient (constant) or friction_slow, friction_fast and rate")
    if model == "pendulum" and "friction_coefficient" in given and given & {"friction_slow", "friction_fast"}:
        raise CaseFileError(f"{source}: [building] friction_coefficient and friction_slow/friction_fast: give one "
                            "(a constant coefficient, or Constantinou's law)")
    if model == "pendulum" and "friction_slow" not in given and given & {"friction_fast", "rate"}:
        key = "friction_fast" if "friction_fast" in given else "rate"
        raise CaseFileError(f"{source}: [building] {key} = {table[key]!r} without friction_slow: Constantinou's "
                            "law mu(v) = mu_fast - (mu_fast - mu_slow) exp(-a |v|) needs friction_slow (mu at "
                            "vanishing speed, in [0, 1]), or give a constant friction_coefficient")
    if "building.friction" in values and "building.friction_coefficient" in values:
        raise CaseFileError(f"{source}: [building] friction and friction_coefficient: give one of the two")
    if "building.friction_coefficient" in values and mass is None:
        raise CaseFileError(f"{source}: [building] friction_coefficient needs the mass or the weight")
    if model != "linear" and mass is None:
        raise CaseFileError(f"{source}: missing key [building] mass (or weight) for model = {model!r} (its "
                            "stiffnesses act on the mass), e.g. '650 t'")
    if "building.displacement" not in values and mass is None:
        raise CaseFileError(f"{source}: [building] needs displacement (d0) or the mass or weight (d0 = P / k)")
    _check_isolator_ranges(values, table, source, mass)
    k1, k2 = values.get("building.k1"), values.get("building.k2")
    if k1 is not None and k2 is not None and not k2 < k1:
        raise _fail(source, "[building] k2", table["k2"], f"a post-yield stiffness in (0, k1) = (0, {k1:.6g}) N/m")
    m_s = values.get("building.superstructure_mass")
    if m_s is not None and not m_s < mass:
        raise _fail(source, "[building] superstructure_mass", table["superstructure_mass"],
                    f"a mass in (0, [building] mass) = (0, {mass:.6g}) kg (the superstructure is part of the "
                    "building's mass)")
    record = None
    if "record" in table:
        from .building_case import parse_building_record

        try:
            record = parse_building_record(table["record"], source, base)
        except QuickReleaseError as exc:
            raise CaseFileError(str(exc)) from None
    return BuildingSpec(period=values.get("building.period"), damping_ratio=values.get("building.damping_ratio", 0.0),
                        mass=mass, friction=values.get("building.friction"),
                        friction_coefficient=values.get("building.friction_coefficient"),
                        displacement=values.get("building.displacement"), model=model, k1=k1, k2=k2,
                        yield_force=values.get("building.yield_force"), superstructure_mass=m_s,
                        superstructure_period=values.get("building.superstructure_period"),
                        superstructure_damping_ratio=values.get("building.superstructure_damping_ratio",
                                                                None if model != "2dof" and not flexible else 0.0),
                        damping=damping, damping_coefficient=values.get("building.damping_coefficient"),
                        damping_exponent=values.get("building.damping_exponent"),
                        radius=values.get("building.radius"),
                        friction_slow=values.get("building.friction_slow", values.get("building.friction_coefficient")
                                                 if model == "pendulum" else None),
                        friction_fast=values.get("building.friction_fast"), rate=values.get("building.rate"),
                        post_yield_stiffness=values.get("building.post_yield_stiffness"),
                        characteristic_strength=values.get("building.characteristic_strength"),
                        yield_displacement=values.get("building.yield_displacement"),
                        shape=values.get("building.shape"), flexible=flexible, record=record)
