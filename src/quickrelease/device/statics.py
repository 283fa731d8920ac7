"""Statics of the device before release: push force, internal forces, strain energy.

Notation of the paper: P the push force, S the fuse strength, alpha0 the angle the
bars E1 make with the loading axis (Fig. 6), Table 3 for the internal forces and
Eq. 2 for the stored strain energy E_S.

A note on Eq. 1. The paper prints ``P = S tan(alpha)``, but its Table 3 (fuse force
``N4 = P tan(alpha0)``) and its kinematics (Table 4: ``u = L1 (cos alpha0 - cos alpha)``)
measure alpha from the loading axis, for which equilibrium of a central hinge
gives ``S = P tan(alpha0)``, i.e. ``P = S / tan(alpha0)``: Eq. 1 holds with alpha
measured from the transverse (fuse) axis. Taken literally with alpha0 = 0.2 rad,
Eq. 1 would need a fuse force of 7.9 MN for P = 1598 kN, a stress of 14.8 GPa in
the 531 mm^2 fuse; Table 3 gives 324 kN and 610 MPa, a high-strength steel. We
follow Table 3 throughout.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass

import numpy as np

from .._validate import check_angle, check_positive, renamed
from ..errors import ParameterError
from ..units import si, si_scalar
from .parameters import Device, preset

__all__ = [
    "push_force",
    "fuse_force",
    "internal_forces",
    "InternalForces",
    "strain_energy",
    "StrainEnergy",
    "strain_energy_coefficient",
    "strain_energy_limit",
    "strain_energy_coefficient_derivative",
]


def push_force(fuse_strength, alpha0):
    """Push force P at which a fuse of strength S breaks (Eq. 1 with Table 3's angle).

    ``P = S / tan(alpha0)``: the fuse carries ``N4 = P tan(alpha0)`` (Table 3), so it
    breaks when P reaches ``S / tan(alpha0)``. See the module notes on Eq. 1.

    Parameters
    ----------
    fuse_strength : float or array
        Rupture strength S of the fuse [N].
    alpha0 : float or array
        Angle of the bars with the loading axis before release [rad], in (0, pi/2).

    Returns
    -------
    float or array
        Push force P [N].
    """
    check_positive("fuse_strength", fuse_strength, "N")
    check_angle("alpha0", alpha0)
    return fuse_strength / np.tan(alpha0)


@renamed(push="push_force")
def fuse_force(push_force, alpha0):
    """Axial force in the fuse, ``N4 = P tan(alpha0)`` (Table 3) [N].

    This is also the fuse strength S needed for a target push force P (Eq. 1
    inverted, with Table 3's angle convention).

    Parameters
    ----------
    push_force : float or array
        Push force P [N].
    alpha0 : float or array
        Angle of the bars with the loading axis [rad], in (0, pi/2).
    """
    push, alpha0 = si(push_force, "force", "P"), si(alpha0, "angle", "alpha0")
    check_positive("P", push, "N")
    check_angle("alpha0", alpha0)
    return push * np.tan(alpha0)


@dataclass(frozen=True)
class InternalForces:
    """Internal forces of Table 3 for a push force P at angle alpha0 (SI units).

    Signs follow the paper: magnitudes. The bars E1 are compressed, the fuse
    line (E3, E4) is in tension, the heads E2 bend between the two bar hinges.
    """

    P: float
    """Push force [N]."""
    alpha0: float
    """Angle of the bars with the loading axis [rad]."""
    N1: float
    """Axial force in each bar E1, ``P / (2 cos alpha0)`` [N]."""
    N2: float
    """Axial force in each head E2, ``P tan(alpha0) / 2`` [N]."""
    V2: float
    """Shear force in each head E2, ``P / 2`` [N]."""
    M2: float
    """Midspan bending moment in each head E2, ``P L2 / 4`` [N m]."""
    N3: float
    """Axial force in each element E3, ``P tan(alpha0)`` [N]."""
    N4: float
    """Axial force in the fuse E4, ``P tan(alpha0)`` [N]."""


@renamed(push="push_force")
def internal_forces(push_force: float, alpha0: float, device: Device | None = None) -> InternalForces:
    """Internal forces in the device members before release (Table 3).

    Parameters
    ----------
    push_force : float
        Push force P [N].
    alpha0 : float
        Angle of the bars with the loading axis [rad], in (0, pi/2).
    device : Device, optional
        Supplies L2 for the bending moment; the paper's device (Table 2) by default.
    """
    push, alpha0 = si_scalar(push_force, "force", "P"), si_scalar(alpha0, "angle", "alpha0")
    device = device or preset("paper")
    check_positive("P", push, "N")
    check_angle("alpha0", alpha0)
    P = float(push)
    a = float(alpha0)
    t = float(np.tan(a))
    return InternalForces(
        P=P,
        alpha0=a,
        N1=P / (2.0 * float(np.cos(a))),
        N2=P * t / 2.0,
        V2=P / 2.0,
        M2=P * device.L2 / 4.0,
        N3=P * t,
        N4=P * t,
    )


@dataclass(frozen=True)
class StrainEnergy:
    """Strain energy stored in the device before release, term by term (Eq. 2) [J].

    Each field is one term of Eq. 2 (already multiplied by the number of members).
    """

    axial_E1: float
    """``4 N1^2 L1 / (2 E A1)`` [J]."""
    axial_E2: float
    """``2 N2^2 L2 / (2 E A2)`` [J]."""
    axial_E3: float
    """``2 N3^2 L3 / (2 E A3)`` [J]."""
    axial_E4: float
    """``N4^2 L4 / (2 E A4)`` [J]."""
    bending_E2: float
    """``2 M2^2 L2 / (6 E I2)`` [J]."""
    shear_E2: float
    """``2 V2^2 L2 / (2 kappa G A2)`` [J]."""
    forces: InternalForces
    """The internal forces the energy was computed from."""

    @property
    def total(self) -> float:
        """E_S, the sum of the six terms of Eq. 2 [J]."""
        return (
            self.axial_E1 + self.axial_E2 + self.axial_E3 + self.axial_E4
            + self.bending_E2 + self.shear_E2
        )

    @property
    def by_member(self) -> dict[str, float]:
        """Energy per member type: E1, E2 (axial + bending + shear), E3, E4 [J]."""
        return {
            "E1": self.axial_E1,
            "E2": self.axial_E2 + self.bending_E2 + self.shear_E2,
            "E3": self.axial_E3,
            "E4": self.axial_E4,
        }

    @property
    def by_effect(self) -> dict[str, float]:
        """Energy per effect: axial, bending, shear [J]."""
        return {
            "axial": self.axial_E1 + self.axial_E2 + self.axial_E3 + self.axial_E4,
            "bending": self.bending_E2,
            "shear": self.shear_E2,
        }

    def terms(self) -> dict[str, float]:
        """The six terms of Eq. 2 by name [J]."""
        return {
            "axial_E1": self.axial_E1,
            "axial_E2": self.axial_E2,
            "axial_E3": self.axial_E3,
            "axial_E4": self.axial_E4,
            "bending_E2": self.bending_E2,
            "shear_E2": self.shear_E2,
        }


@renamed(push="push_force")
def strain_energy(push_force: float, alpha0: float, device: Device | None = None) -> StrainEnergy:
    """Elastic strain energy stored before release, E_S (Eq. 2), with its breakdown.

    ``E_S = 4 N1^2 L1/(2 E A1) + 2 N2^2 L2/(2 E A2) + 2 N3^2 L3/(2 E A3)
    + N4^2 L4/(2 E A4) + 2 M2^2 L2/(6 E I2) + 2 V2^2 L2/(2 kappa G A2)``
    with the internal forces of Table 3.

    Parameters
    ----------
    push_force : float
        Push force P [N].
    alpha0 : float
        Angle of the bars with the loading axis [rad].
    device : Device, optional
        Member data; the paper's device (Table 2) by default.

    Returns
    -------
    StrainEnergy
        The six terms; ``.total`` is E_S [J].

    ``push`` and ``alpha0`` also take strings with units or pint Quantities.
    """
    push, alpha0 = si_scalar(push_force, "force", "P"), si_scalar(alpha0, "angle", "alpha0")
    device = device or preset("paper")
    f = internal_forces(push, alpha0, device)
    d = device
    limit = strain_energy_limit(alpha0, d)
    if float(push) > limit:
        raise ParameterError("P", float(push), f"(0, {limit:.4g}] N, where the terms of E_S (Eq. 2) stay "
                             f"finite at alpha0 = {float(alpha0):.6g} rad", "N")
    return StrainEnergy(
        axial_E1=4.0 * f.N1**2 * d.L1 / (2.0 * d.E * d.A1),
        axial_E2=2.0 * f.N2**2 * d.L2 / (2.0 * d.E * d.A2),
        axial_E3=2.0 * f.N3**2 * d.L3 / (2.0 * d.E * d.A3),
        axial_E4=f.N4**2 * d.L4 / (2.0 * d.E * d.A4),
        bending_E2=2.0 * f.M2**2 * d.L2 / (6.0 * d.E * d.I2),
        shear_E2=2.0 * f.V2**2 * d.L2 / (2.0 * d.kappa * d.G * d.A2),
        forces=f,
    )


def strain_energy_limit(alpha0, device: Device):
    """Largest push force P for which Eq. 2 is finite in floating point [N] (scalar alpha0).

    Every internal force is ``P`` times a factor r of alpha0 (Table 3), and each term of Eq. 2 is
    evaluated as ``a N^2 L / (...)`` (a = 4, 2, 2, 1, 2, 2), so its product ``a N^2 L`` overflows above
    ``sqrt(max float / (a L)) / |r|``, and ``E_S = P^2 k(alpha0)`` above ``sqrt(max float / k)``; the
    smallest of these, against max float / 8 so that the sum of the six terms stays finite.
    """
    d = device
    f = internal_forces(1.0, alpha0, d)
    root = math.sqrt(sys.float_info.max / 8.0)
    terms = [(f.N1, 4.0 * d.L1), (f.N2, 2.0 * d.L2), (f.N3, 2.0 * d.L3), (f.N4, d.L4), (f.M2, 2.0 * d.L2),
             (f.V2, 2.0 * d.L2)]
    limits = [root / (abs(r) * math.sqrt(aL)) for r, aL in terms if r != 0.0]
    return min(*limits, root / math.sqrt(float(strain_energy_coefficient(alpha0, d))))


def strain_energy_coefficient(alpha0, device: Device):
    """E_S / P^2 as a function of alpha0 (Eq. 2 with Table 3), vectorized [J/N^2].

    Every term of Eq. 2 is quadratic in P, so ``E_S(P, alpha0) = P^2 * strain_energy_coefficient(alpha0)``.
    """
    a = np.asarray(alpha0, dtype=float)
    d = device
    t = np.tan(a)
    c = np.cos(a)
    return (4.0 * (0.5 / c) ** 2 * d.L1 / (2.0 * d.E * d.A1) + 2.0 * (0.5 * t) ** 2 * d.L2 / (2.0 * d.E * d.A2)
            + 2.0 * t**2 * d.L3 / (2.0 * d.E * d.A3) + t**2 * d.L4 / (2.0 * d.E * d.A4)
            + 2.0 * (d.L2 / 4.0) ** 2 * d.L2 / (6.0 * d.E * d.I2) + 2.0 * 0.25 * d.L2 / (2.0 * d.kappa * d.G * d.A2))


def strain_energy_coefficient_derivative(alpha0, device: Device):
    """d(E_S / P^2) / d alpha0, the derivative of :func:`strain_energy_coefficient` (Eq. 2, Table 3) [J/(N^2 rad)].

    Only the axial terms depend on alpha0: N1 = P / (2 cos alpha0) and N2, N3, N4 proportional to
    P tan alpha0, and ``d(1/cos^2)/d alpha = d(tan^2)/d alpha = 2 tan(alpha) / cos^2(alpha)``.
    """
    a = np.asarray(alpha0, dtype=float)
    d = device
    t = np.tan(a)
    c = np.cos(a)
    coefficient = (4.0 * 0.25 * d.L1 / (2.0 * d.E * d.A1) + 2.0 * 0.25 * d.L2 / (2.0 * d.E * d.A2)
                   + 2.0 * d.L3 / (2.0 * d.E * d.A3) + d.L4 / (2.0 * d.E * d.A4))
    return 2.0 * t / (c * c) * coefficient
