"""Test planning: the fuse and the angle, the members, the release envelope, the clearance with the building.

Before a test the engineer chooses the fuse and the angle for the push wanted, checks that the device's
members survive it, sizes the rail and the lateral room for the device's motion, and checks that the
device gets out of the way of the building springing back. :func:`plan_case` answers all four for a case
file with the optional tables ``[fuse]``, ``[building]`` and ``[plan]``.

Conventions. Eq. 1 is applied with Table 3's angle: the fuse carries ``S = P tan(alpha0)``, so a fuse of
strength S releases at ``P = S / tan(alpha0)`` (see :mod:`quickrelease.device.statics` for why). Forces and
stresses are magnitudes; the bars E1 are compressed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .. import batch
from .._results import Summarised
from .._threads import check_threads, using_threads
from .._validate import check_size
from ..building.model import FreeVibration, Isolation, free_vibration, pushed_state
from ..device.dynamics import angular_acceleration
from ..device.kinematics import retraction
from ..device.parameters import Device
from ..device.solvers import FirstIntegral
from ..device.statics import InternalForces, internal_forces, strain_energy
from ..errors import ParameterError, QuickReleaseError
from ..io.building_case import pushed_displacement
from ..io.case import BuildingSpec, Case, Distribution
from ..report._style import STYLE as _STYLE
from ..report._style import styled, unit_text
from .fit import case_friction

__all__ = [
    "FuseChoice", "FuseTable", "fuse_choices", "MemberCheck", "MemberChecks", "member_checks", "Envelope",
    "release_envelope", "FrictionSamples", "friction_samples", "building_motion", "building_isolation",
    "pushed_displacement", "Clearance", "clearance", "GAP_GROWS",
    "PlanResult", "plan_case", "ENVELOPE_QUANTITIES", "plan_figures", "choices_figure", "utilisation_figure",
    "envelope_figure", "gap_figure",
]

# -- fuse and angle --------------------------------------------------------------------------------------------

def _normal_cdf(x):
    from scipy.special import ndtr

    return ndtr(np.asarray(x, dtype=float))


@dataclass(frozen=True)
class FuseChoice:
    """One (fuse diameter, angle) candidate: the push force it releases at (Eq. 1) and what it stores (Eq. 2)."""

    diameter: float
    """Diameter of the fuse's calibrated section [m]."""
    alpha0: float
    """Angle [rad]."""
    area: float
    """Fuse section A4 = pi d^2 / 4 [m^2]."""
    strength: float
    """Rupture force S = f_u A4 (mean) [N]."""
    strength_std: float
    push_force: float
    """Expected push force at rupture P = S / tan(alpha0) [N] (Eq. 1, Table 3's angle)."""
    push_force_std: float
    """Its standard deviation from the scatter of the rupture strength [N]."""
    stored_energy: float
    """E_S at the expected P (Eq. 2, this fuse's A4) [J]."""
    deviation: float
    """P over the target's centre, minus 1 [-]."""
    within: bool
    """P lies in the target range."""
    probability_within: float
    """Probability that the rupture happens inside the target range (normal rupture strength) [-]."""

    def summary(self) -> dict[str, Any]:
        return {"diameter_m": self.diameter, "alpha0_rad": self.alpha0, "area_m2": self.area,
                "strength_N": self.strength, "strength_std_N": self.strength_std, "push_force_N": self.push_force,
                "push_force_std_N": self.push_force_std, "stored_energy_J": self.stored_energy,
                "deviation": self.deviation, "within_target": self.within,
                "probability_within_target": self.probability_within}


@dataclass(frozen=True)
class FuseTable:
    """Every candidate (diameter, angle), the target range and the material."""

    choices: tuple[FuseChoice, ...]
    diameters: tuple[float, ...]
    angles: tuple[float, ...]
    target: tuple[float, float]
    """Target push force range [N]."""
    rupture_strength: float
    """Mean rupture strength of the material [Pa]."""
    rupture_strength_std: float
    warnings: tuple[str, ...] = ()

    @property
    def best(self) -> FuseChoice:
        """The choice most likely to release inside the target range (closest to its centre on ties)."""
        return max(self.choices, key=lambda c: (round(c.probability_within, 12), -abs(c.deviation)))

    def grid(self, attribute: str) -> np.ndarray:
        """An attribute of the choices on the (diameter, angle) grid."""
        return np.array([getattr(c, attribute) for c in self.choices]).reshape(len(self.diameters), len(self.angles))

    def summary(self) -> dict[str, Any]:
        return {"target_N": list(self.target), "rupture_strength_Pa": self.rupture_strength,
                "rupture_strength_std_Pa": self.rupture_strength_std, "best": self.best.summary(),
                "within_target": [c.summary() for c in self.choices if c.within],
                "choices": [c.summary() for c in self.choices], "warnings": list(self.warnings)}


def fuse_choices(target: tuple[float, float], rupture_strength: float, rupture_strength_std: float,
                 diameters, angles, device: Device) -> FuseTable:
    """The table of (diameter, angle) choices for a target push force (Eq. 1 with Table 3's angle, Eq. 2).

    Parameters
    ----------
    target : (float, float)
        Target push force range [N].
    rupture_strength, rupture_strength_std : float
        Mean and standard deviation of the fuse material's rupture strength, from sample tests [Pa].
    diameters : sequence of float
        Candidate diameters of the fuse's calibrated section [m].
    angles : sequence of float
        Candidate angles alpha0 [rad], in (0, pi/2).
    device : Device
        Member data for E_S (its A4 replaced by each fuse's section).

    Raises
    ------
    ParameterError
        When the target lies outside every push force the candidates give (no angle reaches it).
    """
    lo, hi = float(target[0]), float(target[1])
    if not (0 < lo <= hi and math.isfinite(hi)):
        raise ParameterError("target push force", f"[{lo:.6g}, {hi:.6g}] N", "a range 0 < low <= high")
    for d in diameters:
        if not (math.isfinite(d) and d > 0):
            raise ParameterError("fuse diameter", float(d), "(0, inf)", "m")
    for a in angles:
        if not (math.isfinite(a) and 0 < a < 0.5 * math.pi):
            raise ParameterError("alpha0", float(a), "(0, pi/2)", "rad")
    if not (math.isfinite(rupture_strength) and rupture_strength > 0):
        raise ParameterError("rupture_strength", rupture_strength, "(0, inf)", "Pa")
    centre = 0.5 * (lo + hi)
    choices = []
    for d in diameters:
        area = math.pi * d * d / 4.0
        dev = device.replace(A4=area)
        S, S_std = rupture_strength * area, rupture_strength_std * area
        for a in angles:
            P = S / math.tan(a)  # Eq. 1 with Table 3's angle: S = P tan(alpha0)
            P_std = S_std / math.tan(a)
            if P_std > 0:
                prob = float(_normal_cdf((hi - P) / P_std) - _normal_cdf((lo - P) / P_std))
            else:
                prob = float(lo <= P <= hi)
            choices.append(FuseChoice(diameter=float(d), alpha0=float(a), area=area, strength=S, strength_std=S_std,
                                      push_force=P, push_force_std=P_std,
                                      stored_energy=strain_energy(P, a, dev).total, deviation=P / centre - 1.0,
                                      within=lo <= P <= hi, probability_within=prob))
    forces = [c.push_force for c in choices]
    if hi < min(forces) or lo > max(forces):
        raise ParameterError("target push force", f"[{lo / 1e3:.6g}, {hi / 1e3:.6g}] kN",
                             f"what the candidate fuses and angles reach, [{min(forces) / 1e3:.6g}, "
                             f"{max(forces) / 1e3:.6g}] kN")
    warnings = []
    if not any(c.within for c in choices):
        near = min(choices, key=lambda c: abs(c.deviation))
        warnings.append(f"no candidate lies in the target range; the closest is d = {1e3 * near.diameter:.4g} mm at "
                        f"alpha0 = {near.alpha0:.4g} rad, P = {near.push_force / 1e3:.6g} kN")
    return FuseTable(choices=tuple(choices), diameters=tuple(float(d) for d in diameters),
                     angles=tuple(float(a) for a in angles), target=(lo, hi), rupture_strength=rupture_strength,
                     rupture_strength_std=rupture_strength_std, warnings=tuple(warnings))


# -- member checks ---------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class MemberCheck:
    """One check of one member: demand against capacity."""

    member: str
    """``E1``, ``E2``, ``E3`` or ``E4`` (the fuse)."""
    check: str
    demand: float
    """Stress [Pa] or force [N] (see ``unit``)."""
    capacity: float | None
    unit: str
    utilisation: float | None
    """demand / capacity; None when the check is skipped."""
    note: str = ""


@dataclass(frozen=True)
class MemberChecks:
    """The checks of every member at a push force and angle (Table 3's internal forces)."""

    forces: InternalForces
    checks: tuple[MemberCheck, ...]
    fuse_stress: float
    """N4 / A4 [Pa]."""

    def utilisation(self) -> dict[str, float | None]:
        """Per member E1, E2, E3: the largest utilisation of its checks (None where every check is skipped)."""
        out: dict[str, float | None] = {}
        for member in ("E1", "E2", "E3"):
            values = [c.utilisation for c in self.checks if c.member == member and c.utilisation is not None]
            out[member] = max(values) if values else None
        return out

    @property
    def notes(self) -> list[str]:
        return [f"{c.member} {c.check}: {c.note}" for c in self.checks if c.note]

    def summary(self) -> dict[str, Any]:
        return {"push_force_N": self.forces.P, "alpha0_rad": self.forces.alpha0, "fuse_stress_Pa": self.fuse_stress,
                "utilisation": self.utilisation(),
                "checks": [{"member": c.member, "check": c.check,  # a skipped check may have no demand (NaN)
                            "demand": c.demand if math.isfinite(c.demand) else None, "capacity": c.capacity,
                            "unit": c.unit, "utilisation": c.utilisation, "note": c.note} for c in self.checks],
                "internal_forces_N": {"N1": self.forces.N1, "N2": self.forces.N2, "V2": self.forces.V2,
                                      "N3": self.forces.N3, "N4": self.forces.N4},
                "M2_Nm": self.forces.M2}


def _check(member, check, demand, capacity, unit, missing: str | None = None) -> MemberCheck:
    if capacity is None:
        return MemberCheck(member, check, demand, None, unit, None, f"skipped: {missing} not in the device file")
    return MemberCheck(member, check, demand, capacity, unit, demand / capacity)


def member_checks(push_force: float, alpha0: float, device: Device, rupture_strength: float | None = None) \
        -> MemberChecks:
    """Stresses and utilisations of the members before release (Table 3's internal forces).

    * E1 (bars, compressed): ``N1 / A1`` against its yield strength, and flexural buckling, ``N1`` against the
      Euler load ``pi^2 E I1 / Lcr1^2`` (Lcr1 = L1 unless given; pinned bars).
    * E2 (heads): at midspan ``sigma = N2 / A2 + M2 / W2`` and ``tau = V2 / (kappa A2)`` (the shear area Eq. 2
      uses), combined as von Mises ``sqrt(sigma^2 + 3 tau^2)`` against the yield strength (conservative: the
      largest normal and shear stresses taken at one point). ``W2 = I2 / (h2 / 2)`` when only h2 is given.
    * E3 (fuse lodgings): ``N3 / A3`` against the yield strength.
    * E4 (the fuse): ``N4 / A4``, against the material's rupture strength when given (1 is the design: the fuse
      is meant to break at this push).

    Checks whose data are absent from the device file are skipped with a note.
    """
    f = internal_forces(push_force, alpha0, device)
    d = device
    checks = []
    fy1, fy2, fy3 = (d.yield_strength(m) for m in (1, 2, 3))
    checks.append(_check("E1", "axial compression N1/A1 (yield)", f.N1 / d.A1, fy1, "Pa", "fy1 (or fy)"))
    if d.I1 is None:
        checks.append(MemberCheck("E1", "flexural buckling (Euler)", f.N1, None, "N", None,
                                  "skipped: I1 not in the device file"))
    else:
        Lcr = d.Lcr1 if d.Lcr1 is not None else d.L1
        N_cr = math.pi**2 * d.E * d.I1 / Lcr**2
        checks.append(MemberCheck("E1", f"flexural buckling (Euler, Lcr = {Lcr:.4g} m)", f.N1, N_cr, "N", f.N1 / N_cr))
    W2 = d.W2 if d.W2 is not None else (d.I2 / (0.5 * d.h2) if d.h2 is not None else None)
    if W2 is None:
        checks.append(MemberCheck("E2", "axial + bending + shear (von Mises)", math.nan, fy2, "Pa", None,
                                  "skipped: W2 (or h2) not in the device file"))
    else:
        sigma = f.N2 / d.A2 + f.M2 / W2
        tau = f.V2 / (d.kappa * d.A2)
        checks.append(_check("E2", "axial + bending + shear (von Mises)", math.hypot(sigma, math.sqrt(3.0) * tau),
                             fy2, "Pa", "fy2 (or fy)"))
    checks.append(_check("E3", "axial tension N3/A3 (yield)", f.N3 / d.A3, fy3, "Pa", "fy3"))
    fuse_stress = f.N4 / d.A4
    if rupture_strength is None:
        checks.append(MemberCheck("E4", "fuse stress N4/A4 (rupture)", fuse_stress, None, "Pa", None,
                                  "no rupture strength given ([fuse])"))
    else:
        checks.append(MemberCheck("E4", "fuse stress N4/A4 (rupture)", fuse_stress, rupture_strength, "Pa",
                                  fuse_stress / rupture_strength, "1 is the design: the fuse breaks at this push"))
    return MemberChecks(forces=f, checks=tuple(checks), fuse_stress=fuse_stress)


# -- release envelope ------------------------------------------------------------------------------------------

#: Quantities of the release envelope: (batch field, unit, label).
ENVELOPE_QUANTITIES = {
    "stop_time": ("s", "time to stop t_F"),
    "alpha_final": ("rad", "final angle alpha_F"),
    "u_final": ("m", "head stroke u_F (rail travel)"),
    "v_final": ("m", "hinge opening v_F (lateral room)"),
    "width_final": ("m", "hinge-to-hinge width at the end 2 L1 sin(alpha_F)"),
    "peak_u_dot": ("m/s", "peak head velocity"),
    "peak_v_dot": ("m/s", "peak hinge velocity"),
    "peak_u_ddot": ("m/s^2", "peak head acceleration"),
    "peak_v_ddot": ("m/s^2", "peak hinge acceleration"),
}


@dataclass(frozen=True, eq=False)
class Envelope:
    """The release at the planned push for the friction estimate: nominal values and, over the friction's
    distribution, their ranges (SI units)."""

    friction: str
    """Where the friction comes from."""
    F1: float
    F2: float
    samples: int
    """Friction samples (1: a single value)."""
    nominal: dict[str, float]
    ranges: dict[str, dict[str, float]]
    """Quantity -> min, p5, p50, p95, max over the samples."""
    geometric_limit_share: float
    """Share of the samples that reach the flat rhombus (alpha = pi/2)."""
    clipped_share: float = 0.0
    """Share of the friction samples drawn below 0 and set to 0."""
    values: dict[str, np.ndarray] = field(default_factory=dict, repr=False)
    """The per-sample values of the quantities, and the friction samples F1, F2 (for figures)."""

    def summary(self) -> dict[str, Any]:
        return {"friction": self.friction, "F1_N": self.F1, "F2_N": self.F2, "samples": self.samples,
                "nominal": self.nominal, "ranges": self.ranges, "geometric_limit_share": self.geometric_limit_share,
                "clipped_share": self.clipped_share}


def _correlated_normals(rng, n: int, rho: float) -> tuple[np.ndarray, np.ndarray]:
    z1 = rng.standard_normal(n)
    z2 = rho * z1 + math.sqrt(max(1.0 - rho * rho, 0.0)) * rng.standard_normal(n)
    return z1, z2


def _from_normal(z: np.ndarray, dist: Distribution) -> np.ndarray:
    if dist.kind == "normal":
        return dist.loc + dist.scale * z
    return dist.loc + dist.scale * _normal_cdf(z)  # uniform marginal, Gaussian copula


@dataclass(frozen=True, eq=False)
class FrictionSamples:
    """Friction pairs to plan with, and the nominal pair they scatter about (SI units)."""

    F1: np.ndarray
    """Hinge friction of each sample [N]."""
    F2: np.ndarray
    """Rail friction of each sample [N]."""
    nominal: tuple[float, float]
    """(F1, F2) of :func:`quickrelease.device.identify.case_friction` [N]."""
    description: str
    """Where they come from."""
    dropped_share: float = 0.0
    """Share of the draws set to 0 (negative) or dropped (infeasible identification)."""


def friction_samples(case: Case, n: int, seed: int = 0) -> FrictionSamples:
    """Friction pairs (F1, F2) [N] to plan with: the case's scatter, or that of the case it takes its friction from.

    * ``[friction]`` F1, F2 with a scatter (``{value, std}`` or ``{low, high}``) and ``correlation``: drawn jointly
      (a Gaussian copula for uniform marginals); draws below 0 are set to 0.
    * ``[friction] case`` naming a case with observations that carry a scatter: each draw of its observations
      identified (Eq. 11-13, the batch kernel); infeasible draws are dropped.
    * otherwise the single friction pair of :func:`quickrelease.device.identify.case_friction`.

    """
    F1_nom, F2_nom, how = case_friction(case)
    nominal = (F1_nom, F2_nom)
    rng = np.random.default_rng(seed)
    d1, d2 = case.uncertainty.get("F1"), case.uncertainty.get("F2")
    if d1 is not None or d2 is not None:
        z1, z2 = _correlated_normals(rng, n, case.friction_correlation)
        F1 = _from_normal(z1, d1) if d1 is not None else np.full(n, F1_nom)
        F2 = _from_normal(z2, d2) if d2 is not None else np.full(n, F2_nom)
        clipped = float(np.mean((F1 < 0) | (F2 < 0)))
        words = ", ".join(f"{k} {v.describe('N')}" for k, v in (("F1", d1), ("F2", d2)) if v is not None)
        rho = f", correlation {case.friction_correlation:g}" if case.friction_correlation else ""
        return FrictionSamples(np.maximum(F1, 0.0), np.maximum(F2, 0.0), nominal, f"[friction] {words}{rho}", clipped)
    source = case.friction_case
    if source is not None and source.has_observations and any(
            k in source.uncertainty for k in ("alpha0", "alpha_final", "stop_time", "force", "energy")):
        from .uq import _identify, _inputs

        ident = _identify(source, _inputs(source, rng, n))
        ok = ident.status == 0
        if not np.any(ok):
            raise QuickReleaseError(f"{source.source}: no draw of its observations is feasible")
        return FrictionSamples(ident.F1[ok], ident.F2[ok], nominal,
                               f"identified from {n:,} draws of the observations of {source.source}",
                               float(1.0 - ok.mean()))
    return FrictionSamples(np.array([F1_nom]), np.array([F2_nom]), nominal, how)


def _percentiles(values: np.ndarray) -> dict[str, float]:
    p = np.percentile(values, [0, 5, 50, 95, 100])
    return dict(zip(("min", "p5", "p50", "p95", "max"), (float(x) for x in p), strict=True))


def release_envelope(case: Case, E_S: float | None = None, alpha0: float | None = None, samples: int | None = None,
                     seed: int | None = None, *, threads: int | None = None) -> Envelope:
    """The release envelope of a case (or of another E_S, alpha0) over its friction estimate (batch kernels).

    ``threads``: threads of the compiled kernels, 1 to ``numba.config.NUMBA_NUM_THREADS`` (default: numba's
    current count, all cores unless changed; :func:`quickrelease.using_threads`); the envelope is the same for
    any count.
    """
    check_threads(threads)
    E_S = case.stored_energy if E_S is None else E_S
    alpha0 = case.alpha0 if alpha0 is None else alpha0
    n = case.plan.samples if samples is None else samples
    check_size("samples", n, n, "friction samples")
    with using_threads(threads):  # the friction samples may come from identifying scattered observations
        fs = friction_samples(case, n, case.plan.seed if seed is None else seed)
    F1, F2 = fs.nominal
    d = case.device
    c = case.mass_factor

    def run(f1, f2):
        r = batch.release(E_S, alpha0, f1, f2, c, d.m1, d.m2, d.L1)
        out = {name: np.atleast_1d(getattr(r, name)).astype(float) for name in ENVELOPE_QUANTITIES
               if name != "width_final"}
        out["width_final"] = 2.0 * d.L1 * np.sin(out["alpha_final"])
        return out, np.atleast_1d(r.stopped_by)

    with using_threads(threads):
        nominal, _ = run(np.array([F1]), np.array([F2]))
        values, stopped = run(fs.F1, fs.F2)
    values["F1"], values["F2"] = fs.F1, fs.F2
    return Envelope(friction=fs.description, F1=float(F1), F2=float(F2), samples=int(fs.F1.size),
                    nominal={k: float(v[0]) for k, v in nominal.items()},
                    ranges={k: _percentiles(v) for k, v in values.items()},
                    geometric_limit_share=float(np.mean(stopped == 1)), clipped_share=fs.dropped_share, values=values)


# -- the building and the clearance -----------------------------------------------------------------------------

def building_motion(t, d0: float, period: float, damping_ratio: float = 0.0, friction_acceleration: float = 0.0):
    """Free vibration of the isolated building released at rest from d0: x(t), x_dot(t), x_ddot(t) [m, m/s, m/s^2].

    Single degree of freedom, ``x_ddot + 2 zeta omega x_dot + omega^2 x = -a_f sign(x_dot)`` with
    ``omega = 2 pi / T`` and ``a_f`` the Coulomb friction of sliding isolators over the mass; x is positive in
    the push direction. The motion is :func:`quickrelease.building.model.free_vibration` of the linear isolation
    (exact closed form half-cycle by half-cycle, sticking for good at a turning point where
    ``omega^2 |x| <= a_f``), for a unit mass: only ``a_f = F_s / m`` enters.
    """
    for name, value, valid in (("period", period, "(0, inf) s"), ("damping_ratio", damping_ratio, "[0, 1)"),
                               ("isolator friction", friction_acceleration, "[0, inf) m/s^2")):
        if not math.isfinite(value):
            raise ParameterError(name, value, valid)
    if period <= 0:
        raise ParameterError("period", period, "(0, inf)", "s")
    if not 0.0 <= damping_ratio < 1.0:
        raise ParameterError("damping_ratio", damping_ratio, "[0, 1)")
    if friction_acceleration < 0:
        raise ParameterError("isolator friction", friction_acceleration, "[0, inf)", "m/s^2")
    t = np.asarray(t, dtype=float)
    if float(d0) == 0.0:
        return np.zeros(t.shape), np.zeros(t.shape), np.zeros(t.shape)
    t_max = float(np.max(t)) if t.size else 0.0
    iso = Isolation.linear(1.0, period, damping_ratio, friction_acceleration)
    return free_vibration(iso, d0, t_end=max(t_max, period)).state(t)


def building_isolation(building: BuildingSpec) -> Isolation:
    """The ``[building]`` table as an isolation of :mod:`quickrelease.building`: linear (k = m (2 pi / T)^2,
    viscous damping ratio, Coulomb sliders), bilinear (k1, k2, F_y, damping ratio, sliders), or for the 2dof
    model the isolation layer with the superstructure taken as rigid on it (the whole mass on the layer's
    period: the superstructure's own mode is left out of the clearance check). Without a mass (linear) the
    motion needs no friction (``a_f = F_s / m``): a unit mass stands in when the friction is 0
    (:func:`quickrelease.io.building_case.spec_isolation`)."""
    from ..io.building_case import spec_isolation

    return spec_isolation(building)


#: What :class:`Clearance` says when the gap grows over the whole horizon (no minimum after it opens).
GAP_GROWS = ("the gap grows over the whole horizon: the head outruns the building's first (largest) approach and "
             "has stopped, so no later approach can close it; there is no minimum after the opening")


@dataclass(frozen=True, eq=False)
class Clearance:
    """The gap between the front head and the building after release (SI units)."""

    t: np.ndarray
    gap: np.ndarray
    """Head retraction u(t) minus the building's approach d0 - x(t) [m]."""
    head: np.ndarray
    """u(t) [m]."""
    approach: np.ndarray
    """d0 - x(t) [m]: how far the building has come back towards the device."""
    d0: float
    min_gap: float | None
    """The smallest gap once the gap has opened (see :func:`clearance`) [m]; None when the gap grows over the
    whole horizon (then ``note`` says so)."""
    min_gap_time: float | None
    contact: bool
    first_contact_time: float | None
    """The first instant the gap closes (a bracketed root of the closed-form gap) [s]; None without contact."""
    margin_needed: float
    """How much more room the head needs to stay clear: max(0, -min_gap) [m]."""
    max_approach: float
    """The building's largest approach [m] (d0 plus its overshoot towards the device)."""
    horizon: float
    """The time span checked [s]."""
    gap_series: tuple[float, float]
    """(u_dot0, (u_ddot0 - a_b0) / 2): gap ~ u_dot0 t + that t^2 for small t."""
    note: str = ""
    """Why no minimum is reported (:data:`GAP_GROWS`), else empty."""
    building_period: float = math.nan
    """The building model's period [s]: 2 pi sqrt(m / k) (linear, 2dof rigid), the initial one 2 pi sqrt(m / k1)
    (bilinear), 2 pi sqrt(R / g) whatever the mass (pendulum), the post-yield 2 pi sqrt(m / Kd) (Bouc-Wen)."""
    first_return_time: float | None = None
    """The building's first reversal after the release, where it comes closest to the device [s]; None where it
    stops or creeps on beyond 100 periods without one."""

    def describe_minimum(self) -> str:
        """``minimum gap X mm at Y s``, or why there is none."""
        if self.min_gap is None:
            return "no minimum gap: " + self.note
        return f"minimum gap {1e3 * self.min_gap:.4g} mm at {self.min_gap_time:.4g} s"

    def summary(self) -> dict[str, Any]:
        return {"d0_m": self.d0, "min_gap_m": self.min_gap, "min_gap_time_s": self.min_gap_time,
                "contact": self.contact, "first_contact_time_s": self.first_contact_time,
                "margin_needed_m": self.margin_needed, "max_approach_m": self.max_approach, "horizon_s": self.horizon,
                "building_period_s": self.building_period, "first_return_time_s": self.first_return_time,
                "note": self.note}


class _Gap:
    """The gap u(t) - (d0 - x(t)) [m] and its rate u_dot + x_dot [m/s], from the device's first integral and the
    building's closed form: continuous functions of t for the root finders."""

    def __init__(self, release: FirstIntegral, motion: FreeVibration, d0: float):
        self.release, self.motion, self.d0 = release, motion, float(d0)

    def __call__(self, s: float) -> float:
        alpha, _ = self.release.state_at(np.array([s]))
        x, _, _ = self.motion.state(np.array([s]))
        return float(retraction(alpha[0], self.release.alpha0, self.release.L1) - (self.d0 - x[0]))

    def rate(self, s: float) -> float:
        alpha, alpha_dot = self.release.state_at(np.array([s]))
        _, v, _ = self.motion.state(np.array([s]))
        return float(self.release.L1 * math.sin(alpha[0]) * alpha_dot[0] + v[0])


def _root(f, a: float, b: float) -> float:
    """The root of f in [a, b] (f(a) >= 0 > f(b)) to machine precision."""
    from scipy.optimize import brentq

    return float(brentq(f, a, b, xtol=1e-300, rtol=4.0 * np.finfo(float).eps, maxiter=200))


def clearance(release: FirstIntegral, building: BuildingSpec, d0: float, n: int = 6001, refine: bool = True) \
        -> Clearance:
    """The gap between the front head and the building over time, its minimum and whether they touch.

    At the rupture the head and the building are in contact (gap 0). The head retracts by u(t) (Table 4;
    the device's centre stays put, both heads retract symmetrically, and the jack's ram does not follow
    within the second or so of the release); the building springs back from d0 (the exact closed form of
    :func:`quickrelease.building.model.free_vibration`, :func:`building_isolation`). The gap opens at once
    (``u_dot0 > 0`` while the building starts from rest); the minimum gap is taken after the gap's first
    maximum, when the building catches up, over ``max(1.5 t_F, one period, the building's first return)``
    (a bilinear isolation pushed past its yield returns on its soft branch, later than its initial period
    says): after the device has stopped the
    gap is ``u_F`` minus the approach, smallest at the building's first largest approach half a period after
    release. A gap below 0 is a contact: the building hits the device, which would spoil the free-vibration
    test.

    The gap is sampled at ``n`` instants to bracket its events, which are then located on the continuous gap:
    the minimum as the root of the gap's rate ``u_dot + x_dot`` (brentq; a golden section where the rate jumps,
    at a stop on the flat rhombus), and the first contact as the first root of the gap (brentq, to machine
    precision), both bracketed by the samples (the first contact also by the refined minimum, when the gap dips
    below 0 only between two samples).

    When the gap never falls within the horizon (the head outruns the building's first, largest, approach),
    there is no minimum after the opening: ``min_gap`` and ``min_gap_time`` are None, ``contact`` is False
    (the later approaches are smaller and the head has stopped, so none can close the gap) and ``note`` says
    so (:data:`GAP_GROWS`).
    """
    iso = building_isolation(building)
    period = iso.period
    a_f = iso.friction / iso.mass
    t_stop = release.stop_time()
    # the building's first return (its largest approach) within the horizon: half a period for the linear
    # isolation, later for a bilinear one pushed past its yield (the soft branch's longer period)
    first = first_return(iso, d0)
    horizon = max(1.5 * t_stop, period, float(first[1]) if first.size > 1 else 0.0)
    motion = free_vibration(iso, d0, t_end=horizon)
    f = _Gap(release, motion, d0)
    t = np.linspace(0.0, horizon, n)
    alpha, alpha_dot = release.state_at(t)
    L1 = release.L1
    head = retraction(alpha, release.alpha0, L1)
    x, _, _ = motion.state(t)
    approach = d0 - x
    gap = head - approach
    # the gap opens, then the building may catch up: the minimum after the gap's first maximum
    falling = np.nonzero(np.diff(gap) < 0)[0]
    t_min = g_min = None
    note = ""
    if falling.size:
        first_max = int(falling[0])
        k = first_max + int(np.argmin(gap[first_max:]))
        t_min = float(t[k])
        if refine and 0 < k < n - 1:
            a, b = float(t[k - 1]), float(t[k + 1])
            ra, rb = f.rate(a), f.rate(b)
            if ra < 0.0 < rb:  # the gap's rate changes sign: its root is the minimum
                t_min = _root(lambda s: -f.rate(s), a, b)
            else:  # a kink (the head stops on the flat rhombus): golden section on the bracketing samples
                t_min = _refine_minimum(f, a, b)
        g_min = f(t_min)
    else:
        note = GAP_GROWS
    first_contact = None
    negative = np.nonzero(gap[1:] < 0)[0]
    if negative.size:  # the first sample past the crossing and the one before it bracket the first contact
        j = int(negative[0]) + 1
        a, b = float(t[j - 1]), float(t[j])
    elif g_min is not None and g_min < 0:  # the gap dips below 0 only between samples: bracket by the minimum
        b = float(t_min)
        a = float(t[max(int(np.searchsorted(t, b)) - 1, 0)])
    else:
        a = b = None
    if a is not None:
        while a == 0.0:  # the gap is 0 at the release and opens at once: halve towards it for a positive gap
            s = 0.5 * b
            if s == 0.0 or f(s) > 0.0:
                a = s
            else:
                b = s
        first_contact = _root(f, a, b) if f(a) >= 0.0 > f(b) else b
    alpha0 = release.alpha0
    s0, c0 = math.sin(alpha0), math.cos(alpha0)
    rate0 = release.alpha_dot0
    acc0 = float(angular_acceleration(alpha0, rate0, release.F1, release.F2, release.m1, release.m2, L1, release.c))
    R0 = pushed_state(iso, d0)[1] if d0 != 0.0 else 0.0
    a_b0 = R0 / iso.mass - a_f  # the building's initial acceleration towards the device
    u_dot0 = L1 * s0 * rate0
    u_ddot0 = L1 * (c0 * rate0**2 + s0 * acc0)
    contact = first_contact is not None
    return Clearance(t=t, gap=gap, head=head, approach=approach, d0=float(d0), min_gap=g_min, min_gap_time=t_min,
                     contact=bool(contact), first_contact_time=first_contact,
                     margin_needed=max(0.0, -g_min) if g_min is not None else 0.0,
                     max_approach=float(np.max(approach)), horizon=horizon,
                     gap_series=(u_dot0, 0.5 * (u_ddot0 - a_b0)), note=note, building_period=float(period),
                     first_return_time=float(first[1]) if first.size > 1 else None)


def first_return(iso, d0: float, limit: float = 100.0) -> np.ndarray:
    """The reversal times [s] of the building released from ``d0`` over the shortest horizon that holds its first
    return: 2 periods, grown fourfold up to ``limit`` periods until a reversal after the release, or the stop, is
    in it. A model without a closed form (pendulum, Bouc-Wen, a power-law damper) is integrated step by step, and
    a power-law damper's creep near rest costs seconds per period (17 s for 100 periods): the clearance check of
    each friction sample needs its first return only."""
    period = float(iso.period)
    span = 2.0 * period
    while True:
        motion = free_vibration(iso, d0, t_end=span)
        if motion.reversal_times.size > 1 or motion.stop_time <= span or span >= limit * period:
            return motion.reversal_times
        span = min(4.0 * span, limit * period)


def _gap_at(s: float, release: FirstIntegral, building: BuildingSpec, d0: float) -> float:
    """The gap at one instant s [s] (see :func:`clearance`) [m]."""
    iso = building_isolation(building)
    motion = free_vibration(iso, d0, t_end=max(float(s), iso.period))
    return _Gap(release, motion, d0)(s)


def _refine_minimum(f, a: float, b: float, tol: float = 1e-10) -> float:
    g = (math.sqrt(5.0) - 1.0) / 2.0
    c, d = b - g * (b - a), a + g * (b - a)
    fc, fd = f(c), f(d)
    while b - a > tol * max(1.0, abs(b)):
        if fc < fd:
            b, d, fd = d, c, fc
            c = b - g * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, d, fd
            d = a + g * (b - a)
            fd = f(d)
    return 0.5 * (a + b)


# -- the plan ----------------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False, repr=False)
class PlanResult(Summarised):
    """Everything :func:`plan_case` found for a case."""

    case: Case
    push_force: float
    alpha0: float
    stored_energy: float
    members: MemberChecks
    envelope: Envelope
    fuse: FuseTable | None = None
    clearance: Clearance | None = None
    clearance_spread: dict[str, Any] | None = None
    """Over friction samples: the 5th percentile of the minimum gap and the share of samples in contact."""
    notes: tuple[str, ...] = ()

    def summary(self) -> dict[str, Any]:
        """JSON-ready: the keys of ``quickrelease plan --json``."""
        env = self.envelope
        out: dict[str, Any] = {
            "push_force_N": self.push_force, "alpha0_rad": self.alpha0, "stored_energy_J": self.stored_energy,
            "fuse_stress_Pa": self.members.fuse_stress, "utilisation": self.members.utilisation(),
            "stroke_m": env.nominal["u_final"], "opening_m": env.nominal["v_final"],
            "stroke_range_m": [env.ranges["u_final"]["min"], env.ranges["u_final"]["max"]],
            "opening_range_m": [env.ranges["v_final"]["min"], env.ranges["v_final"]["max"]],
            "stop_time_s": env.nominal["stop_time"], "alpha_final_rad": env.nominal["alpha_final"],
            "min_gap_m": None, "min_gap_time_s": None, "contact": None,
            "members": self.members.summary(), "envelope": env.summary(), "notes": list(self.notes),
        }
        if self.clearance is not None:
            out.update({"min_gap_m": self.clearance.min_gap, "min_gap_time_s": self.clearance.min_gap_time,
                        "contact": self.clearance.contact, "clearance": self.clearance.summary()})
            if self.clearance_spread is not None:
                out["clearance"].update(self.clearance_spread)
        if self.fuse is not None:
            out["fuse"] = self.fuse.summary()
        return out


def plan_case(case: Case, *, clearance_samples: int = 200, threads: int | None = None) -> PlanResult:
    """Plan the test of a case: fuse and angle choices (``[fuse]``), member checks, release envelope over the
    friction estimate, and the clearance with the building (``[building]``).

    The planned push is the case's P and alpha0 (``[test]``); E_S from Eq. 2 unless given. ``threads``: threads
    of the release envelope's compiled kernels (:func:`release_envelope`; default all cores).

    Raises
    ------
    QuickReleaseError
        When the case has no push force (member checks need P).
    """
    check_threads(threads)
    if case.push_force is None:
        raise QuickReleaseError(f"{case.source}: planning needs the push force: give [test] force")
    P, a0 = case.push_force, case.alpha0
    notes = []
    fuse_table = None
    strength = None
    if case.fuse is not None:
        fs = case.fuse
        strength = fs.rupture_strength
        target = fs.target or (P * (1.0 - fs.tolerance), P * (1.0 + fs.tolerance))
        diameters = fs.diameters or (math.sqrt(4.0 * case.device.A4 / math.pi),)
        angles = fs.angles or (a0,)
        fuse_table = fuse_choices(target, fs.rupture_strength, fs.rupture_strength_std, diameters, angles,
                                  case.device)
    members = member_checks(P, a0, case.device, strength)
    notes += members.notes
    envelope = release_envelope(case, threads=threads)
    if envelope.clipped_share:
        notes.append(f"{100 * envelope.clipped_share:.2f}% of the friction draws were negative (set to 0) or "
                     "infeasible (dropped)")
    clear = spread = None
    if case.building is not None:
        d = case.device
        d0 = pushed_displacement(P, case.building)
        if case.building.model == "2dof":
            notes.append("clearance: the 2dof building taken as rigid on its isolation layer (the whole mass on the "
                         "isolation period; the superstructure's own mode left out)")
        elif getattr(case.building, "flexible", False):
            notes.append(f"clearance: the flexible {case.building.model} building taken as rigid on its isolation "
                         "layer (the whole mass on the layer; the superstructure's own mode left out)")
        if not d0 > 0:
            raise QuickReleaseError(f"{case.source}: the isolators' friction ({case.building.friction_force:.6g} N) "
                                    f"holds the push (P = {P:.6g} N): no displacement to release from")
        fi = FirstIntegral(case.stored_energy, a0, envelope.F1, envelope.F2, d.m1, d.m2, d.L1, case.mass_factor)
        clear = clearance(fi, case.building, d0)
        if envelope.samples > 1:
            idx = np.linspace(0, envelope.samples - 1, min(clearance_samples, envelope.samples)).astype(int)
            F1s, F2s = envelope.values["F1"], envelope.values["F2"]
            runs = [clearance(FirstIntegral(case.stored_energy, a0, F1s[i], F2s[i], d.m1, d.m2, d.L1,
                                            case.mass_factor), case.building, d0, n=1501, refine=False)
                    for i in idx]
            gaps = np.array([r.min_gap for r in runs if r.min_gap is not None])
            # a sample whose gap grows all the while has no minimum (and no contact): the 5th percentile is
            # over the samples that have one, and their count is reported
            spread = {"min_gap_p5_m": float(np.percentile(gaps, 5)) if gaps.size else None,
                      "contact_share": float(np.mean([r.contact for r in runs])),
                      "clearance_samples": int(idx.size), "clearance_samples_with_minimum": int(gaps.size)}
    return PlanResult(case=case, push_force=P, alpha0=a0, stored_energy=case.stored_energy, members=members,
                      envelope=envelope, fuse=fuse_table, clearance=clear, clearance_spread=spread,
                      notes=tuple(notes))


# -- figures --------------------------------------------------------------------------------------------------

@styled
def choices_figure(table: FuseTable, fig=None, ax=None):
    """The (diameter, angle) choices: push force at rupture (kN, +- one standard deviation) on a grid, the
    choices inside the target range outlined, the most likely one in bold. ``ax``: an Axes to draw into.
    Returns the figure."""
    from matplotlib.patches import Rectangle

    from ..report._style import panels

    P = table.grid("push_force") / 1e3
    std = table.grid("push_force_std") / 1e3
    within = table.grid("within")
    nd, na = P.shape
    fig, ax = panels(1.6 + 1.05 * na, 1.5 + 0.55 * nd, fig=fig, ax=ax, left=0.16, right=0.97, bottom=0.2, top=0.8)
    centre = 0.5 * sum(table.target) / 1e3
    dev = np.clip(P / centre - 1.0, -0.5, 0.5)
    ax.imshow(dev, cmap="RdBu_r", vmin=-0.5, vmax=0.5, aspect="auto")
    best = table.best
    for i in range(nd):
        for j in range(na):
            c = table.choices[i * na + j]
            text = f"{P[i, j]:.0f}" + (f"\n±{std[i, j]:.0f}" if std[i, j] > 0 else "")
            ax.text(j, i, text, ha="center", va="center", fontsize=_STYLE["legend.fontsize"],
                    fontweight="bold" if c is best else "normal")
            if within[i, j]:
                ax.add_patch(Rectangle((j - 0.5, i - 0.5), 1, 1, fill=False, lw=2.0, ec="black"))
    ax.set_xticks(range(na), [f"{a:.3g}" for a in table.angles])
    ax.set_yticks(range(nd), [f"{1e3 * d:.3g}" for d in table.diameters])
    ax.set_xlabel(r"angle $\alpha_0$ [rad]")
    ax.set_ylabel("fuse diameter [mm]")
    ax.grid(False)
    lo, hi = (x / 1e3 for x in table.target)
    ax.set_title(f"Push force at rupture P = S / tan($\\alpha_0$) [kN]\ntarget {lo:.0f} to {hi:.0f} kN (outlined); "
                 f"$f_u$ = {table.rupture_strength / 1e6:.0f} ± {table.rupture_strength_std / 1e6:.0f} MPa")
    return fig


@styled
def utilisation_figure(members: MemberChecks, fig=None, ax=None):
    """Utilisation of the member checks made (a check without its capacity in the device file has no bar;
    the title counts them), with the limit 1 named under the axis, where it covers no bar or value. ``ax``: an
    Axes to draw into. Returns the figure."""
    from ..report._style import panels
    from ..report.plots import _COLORS

    checks = [c for c in members.checks if c.utilisation is not None]
    if not checks:
        raise QuickReleaseError("no member was checked (no capacity in the device file): "
                                "there is no utilisation to draw")
    skipped = len(members.checks) - len(checks)
    height = 1.45 + 0.42 * len(checks) + (0.15 if skipped else 0.0)
    fig, ax = panels(6.4, height, fig=fig, ax=ax, left=0.46, right=0.95, bottom=0.9 / height,
                     top=1.0 - (0.65 if skipped else 0.5) / height)
    labels = [f"{c.member}: {c.check}" for c in checks]
    values = [c.utilisation for c in checks]
    colors = [_COLORS["d"] if c.member == "E4" else (_COLORS["b"] if c.utilisation > 1 else _COLORS["a"])
              for c in checks]
    bars = ax.barh(labels, values, color=colors)
    for bar, c in zip(bars, checks, strict=True):
        ax.text(max(bar.get_width(), 0.0), bar.get_y() + bar.get_height() / 2, f" {c.utilisation:.3f}",
                va="center", fontsize=_STYLE["legend.fontsize"])
    ax.axvline(1.0, color=_COLORS["b"], lw=1.0, ls="--", label="capacity (utilisation 1)")
    ax.invert_yaxis()
    ax.set_xlim(0, max(1.2, max(values) * 1.25))
    ax.set_xlabel("utilisation, demand / capacity [-]")
    axes_height = ax.get_position().height * fig.get_figheight() if hasattr(fig, "get_figheight") else height
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.55 / axes_height), frameon=False)
    f = members.forces
    note = "" if not skipped else f"\n{skipped} check(s) skipped: no capacity in the device file"
    ax.set_title(f"Member checks at P = {f.P / 1e3:.0f} kN, $\\alpha_0$ = {f.alpha0:.4g} rad\n"
                 f"(the fuse E4 is meant to reach 1: it breaks){note}")
    return fig


@styled
def envelope_figure(envelope: Envelope, fig=None, ax=None):
    """Distributions over the friction estimate of the stroke, the opening, the time to stop and the peak head
    velocity, with the nominal value and the 5-95% range (an envelope of two samples or more). ``ax``: four
    Axes to draw into. Returns the figure."""
    from ..report._style import panels
    from ..report.plots import _COLORS

    if envelope.samples < 2:
        raise QuickReleaseError(f"the envelope has {envelope.samples} friction sample(s): "
                                "a histogram needs two or more")

    fig, axes = panels(7.0, 4.6, (2, 2), fig=fig, ax=ax, left=0.08, right=0.98, bottom=0.11, top=0.88,
                       wspace=0.25, hspace=0.45)
    for panel, key in zip(axes.flat, ("u_final", "v_final", "stop_time", "peak_u_dot"), strict=True):
        unit, label = ENVELOPE_QUANTITIES[key]
        panel.hist(envelope.values[key], bins=60, color=_COLORS["a"], alpha=0.75)
        r = envelope.ranges[key]
        for q in ("p5", "p95"):
            panel.axvline(r[q], color=_COLORS["d"], ls="--", lw=0.9)
        panel.axvline(envelope.nominal[key], color=_COLORS["b"], lw=1.4)
        panel.set_yticks([])
        panel.set_xlabel(f"{label} [{unit_text(unit)}]")
    if ax is None:
        fig.suptitle(f"Release envelope over {envelope.samples:,} friction samples (red: nominal, dashed: 5-95%)")
    return fig


@styled
def gap_figure(clear: Clearance, fig=None, ax=None):
    """The head's retraction, the building's approach and the gap between them after release. ``ax``: an Axes
    to draw into. Returns the figure."""
    from ..report._style import panels
    from ..report.plots import _COLORS

    fig, ax = panels(6.4, 3.4, fig=fig, ax=ax, left=0.11, right=0.97, bottom=0.14, top=0.86)
    mm = 1e3  # plotted in mm
    ax.plot(clear.t, mm * clear.head, color=_COLORS["a"], label="head retraction u(t)")
    ax.plot(clear.t, mm * clear.approach, color=_COLORS["c"], label="building approach d0 - x(t)")
    ax.plot(clear.t, mm * clear.gap, color=_COLORS["b"], lw=1.8, label="gap")
    ax.axhline(0.0, color="black", lw=0.8)
    if clear.contact:
        ax.fill_between(clear.t, mm * clear.gap, 0.0, where=clear.gap < 0, color=_COLORS["b"], alpha=0.3,
                        label="contact")
    if clear.min_gap is not None:  # named in the legend, not in an annotation that may cover the curves
        ax.plot([clear.min_gap_time], [mm * clear.min_gap], "o", color=_COLORS["b"],
                label=f"min gap {mm * clear.min_gap:.0f} mm at {clear.min_gap_time:.3g} s")
    ax.set_xlabel("time after release [s]")
    ax.set_ylabel("distance [mm]")
    verdict = "CONTACT" if clear.contact else "clear"
    ax.set_title(f"Clearance between the front head and the building ({verdict}); d0 = {1e3 * clear.d0:.0f} mm")
    # the curves fill the axes from their lowest to their highest point: the legend goes in room made above
    values = mm * np.concatenate([clear.head, clear.approach, clear.gap, [0.0]])
    lo, hi = float(np.nanmin(values)), float(np.nanmax(values))
    ax.set_ylim(lo - 0.05 * (hi - lo), hi + 0.45 * (hi - lo))
    ax.legend(loc="upper left", ncol=2)
    return fig


def plan_figures(plan: PlanResult) -> dict[str, Any]:
    """The planning figures by stem: fuse choices, utilisation, release envelope, gap (where computed)."""
    figs: dict[str, Any] = {}
    if plan.fuse is not None:
        figs["plan_choices"] = choices_figure(plan.fuse)
    if any(c.utilisation is not None for c in plan.members.checks):  # a chart only of checks made
        figs["plan_utilisation"] = utilisation_figure(plan.members)
    if plan.envelope.samples > 1:  # histograms only over samples (one friction value: the table says it all)
        figs["plan_envelope"] = envelope_figure(plan.envelope)
    if plan.clearance is not None:
        figs["plan_gap"] = gap_figure(plan.clearance)
    return figs
