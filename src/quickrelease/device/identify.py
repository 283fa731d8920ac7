"""Identification of the friction forces from a test (Eq. 11-13, Table 7).

What a test shows: the angle at release alpha0, the final angle alpha_F, the time
t_F the device took to get there, and the push force P (hence E_S by Eq. 2). The
friction forces must satisfy Eq. 8, which puts them on the line of Eq. 13,
``F2 = F2* (1 - F1 / F1*)`` with ``0 <= F1 <= F1*`` (Eq. 11-12). Along that line
the stop time grows monotonically with F1 (the hinge friction, whose dissipation
is concentrated late in the motion, leaves more kinetic energy early on), from
``t_F(F1 = 0)`` to ``t_F(F1 = F1*)``; a bracketed root find on F1 then matches the
measured t_F.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from .._results import Summarised
from .._roots import brent
from .._validate import check_angle, check_positive
from ..errors import InfeasibleObservationError, ParameterError, QuickReleaseError
from ..units import si_scalar
from . import dynamics
from ._kernels import feasible_slack
from .parameters import Device, preset
from .solvers import FirstIntegral
from .statics import strain_energy

__all__ = ["Identification", "identify_friction", "stop_time_on_line"]


@dataclass(frozen=True, repr=False)
class Identification(Summarised):
    """Friction forces identified from a stop observation (Eq. 11-13), with the inputs."""

    _repr_keys = ("F1_N", "F2_N", "stop_time_s", "alpha_final_rad")

    F1: float
    """Friction at the central hinges [N]."""
    F2: float
    """Friction at the rail supports [N]."""
    F1_max: float
    """F1*, the bound of Eq. 11 [N]."""
    F2_max: float
    """F2*, the bound of Eq. 12 [N]."""
    stored_energy: float
    """E_S used [J]."""
    alpha0: float
    """Angle at release [rad]."""
    alpha_final: float
    """Observed final angle alpha_F [rad]."""
    stop_time: float
    """Observed stop time t_F [s]."""
    mass_factor: float
    """c of Eq. 5 [-]."""
    device: Device
    """The device."""
    stop_time_residual: float
    """Model t_F at the identified (F1, F2) minus the observed t_F [s]."""
    feasible_stop_times: tuple[float, float]
    """(t_F(F1 = 0), t_F(F1 = F1*)) [s]: what the line of Eq. 13 can produce."""
    push_force: float | None = None
    """P, when E_S was computed from it by Eq. 2 [N]."""
    iterations: int = 0
    """Function evaluations of the root find."""
    boundary: str | None = None
    """``"F1 = 0"`` or ``"F2 = 0"`` when t_F is an end of the feasible interval (within rounding, see
    :func:`quickrelease.device._kernels.feasible_slack`): the solution lies on that boundary of Eq. 13."""

    @property
    def F2_ratio(self) -> float:
        """F2 / F2*, the paper's identification parameter [-]."""
        return self.F2 / self.F2_max

    @property
    def F1_ratio(self) -> float:
        """F1 / F1* [-]; ``F1_ratio + F2_ratio = 1`` (Eq. 13)."""
        return self.F1 / self.F1_max

    def summary(self) -> dict[str, Any]:
        """The identification in numbers, units in the key names (JSON-ready): the keys of
        ``quickrelease identify --json``, the device's name last."""
        return {
            "F1_N": self.F1,
            "F2_N": self.F2,
            "F1_max_N": self.F1_max,
            "F2_max_N": self.F2_max,
            "F2_ratio": self.F2_ratio,
            "stored_energy_J": self.stored_energy,
            "push_force_N": self.push_force,
            "alpha0_rad": self.alpha0,
            "alpha_final_rad": self.alpha_final,
            "stop_time_s": self.stop_time,
            "stop_time_residual_s": self.stop_time_residual,
            "feasible_stop_time_s": list(self.feasible_stop_times),
            "mass_factor": self.mass_factor,
            "boundary": self.boundary,
            "device": self.device.name,
        }

    def line_curve(self, points: int = 41) -> dict[str, Any]:
        """The numbers behind the identification figure: the stop time along the line of Eq. 13,
        ``F1 = F1* (1 - F2/F2*)``, at ``points`` ratios F2/F2* from 0 to 1 (``F2_ratio`` [-], ``F1``, ``F2`` [N],
        ``stop_time`` [s], :func:`stop_time_on_line`)."""
        import numpy as np

        ratio = np.linspace(0.0, 1.0, points)
        F1 = self.F1_max * (1.0 - ratio)
        t = np.array([stop_time_on_line(f, self.stored_energy, self.alpha0, self.alpha_final, device=self.device,
                                        mass_model=self.mass_factor) for f in F1])
        return {"F2_ratio": ratio, "F1": F1, "F2": self.F2_max * ratio, "stop_time": t}

    def to_pandas(self):
        """The identification as a one-row DataFrame, columns keyed with their units as in
        :meth:`summary` (``F1_N``, ..., the feasible interval as ``feasible_stop_time_min_s`` and ``_max_s``)."""
        from ..io.frames import summary_frame

        return summary_frame(self.summary())

    def to_xarray(self):
        """The identification as an ``xarray.Dataset`` of 0-d variables (``F1``, ``F2``, ...) with ``units`` and
        ``long_name``; the device and the boundary as global attributes."""
        from ..io.frames import summary_dataset

        return summary_dataset(self.summary(), "quickrelease friction identification (Eq. 11-13)")


def stop_time_on_line(F1: float, E_S: float, alpha0: float, alpha_final: float, *,
                      device: Device | None = None, mass_model: str | float = "distributed") -> float:
    """Stop time of the release with F1 and ``F2 = F2* (1 - F1/F1*)`` (Eq. 13) [s].

    Every point of the line stops at alpha_final (Eq. 8); only the time differs.
    """
    device = device or preset("paper")
    c = dynamics.mass_factor(mass_model)
    lim = dynamics.friction_limits(E_S, alpha0, alpha_final, device.L1)
    return _line_time(F1, E_S, alpha0, float(lim["F1_max"]), float(lim["F2_max"]), device, c)


def _line_time(F1, E_S, alpha0, F1_max, F2_max, device, c) -> float:
    F1 = min(max(F1, 0.0), F1_max)
    F2 = F2_max * (1.0 - F1 / F1_max) if F1 < F1_max else 0.0
    return FirstIntegral(E_S, alpha0, F1, F2, device.m1, device.m2, device.L1, c).stop_time()


def identify_friction(alpha0: float, alpha_final: float, stop_time: float, *,
                      stored_energy: float | None = None, push_force: float | None = None,
                      device: Device | None = None,
                      mass_model: str | float = "distributed") -> Identification:
    """Identify F1 and F2 from a test (Eq. 11-13): the paper's Table 7 procedure.

    Parameters
    ----------
    alpha0 : float
        Angle at release [rad], in (0, pi/2).
    alpha_final : float
        Observed final angle alpha_F [rad], in (alpha0, pi/2).
    stop_time : float
        Observed time from release to stop t_F [s], > 0.
    stored_energy : float, optional
        E_S [J]. Give this or ``push_force``.
    push_force : float, optional
        P [N]; E_S then follows from Eq. 2 with the device's data.
    device : Device, optional
        The paper's device by default.
    mass_model : {"distributed", "lumped"} or float
        Mass factor c.

    Numbers are SI; the quantities also take strings with units (``"2.9 kJ"``) or pint Quantities.

    Returns
    -------
    Identification

    Raises
    ------
    InfeasibleObservationError
        When t_F is outside ``[t_F(F1 = 0), t_F(F1 = F1*)]``.
    ParameterError
        For out-of-range inputs.
    """
    device = device or preset("paper")
    c = dynamics.mass_factor(mass_model)
    alpha0, alpha_final = si_scalar(alpha0, "angle", "alpha0"), si_scalar(alpha_final, "angle", "alpha_final")
    stop_time = si_scalar(stop_time, "time", "stop_time")
    stored_energy = None if stored_energy is None else si_scalar(stored_energy, "energy", "stored_energy")
    push_force = None if push_force is None else si_scalar(push_force, "force", "push_force")
    check_angle("alpha0", alpha0)
    check_angle("alpha_final", alpha_final)
    if alpha_final <= alpha0:
        raise ParameterError("alpha_final", float(alpha_final), f"(alpha0, pi/2) = ({alpha0:.6g}, 1.5708)", "rad")
    check_positive("stop_time", stop_time, "s")
    if (stored_energy is None) == (push_force is None):
        raise ParameterError("stored_energy/push_force", "both" if stored_energy is not None else "neither",
                             "exactly one of the two")
    if push_force is not None:
        check_positive("P", push_force, "N")
        E_S = strain_energy(push_force, alpha0, device).total
    else:
        check_positive("E_S", stored_energy, "J")
        E_S = float(stored_energy)
    lim = dynamics.friction_limits(E_S, alpha0, alpha_final, device.L1)
    F1_max, F2_max = float(lim["F1_max"]), float(lim["F2_max"])
    count = 0

    def residual(F1: float) -> float:
        nonlocal count
        count += 1
        return _line_time(F1, E_S, alpha0, F1_max, F2_max, device, c) - stop_time

    feasible = (_line_time(0.0, E_S, alpha0, F1_max, F2_max, device, c),
                _line_time(F1_max, E_S, alpha0, F1_max, F2_max, device, c))  # not residual + t_F: exact
    count += 2
    F1_top = F1_max
    if feasible[1] == math.inf and math.isfinite(feasible[0]):
        # alpha_F within rounding of pi/2: the F1* end (F2 = 0) creeps towards pi/2 (dynamics.creeps_terms), so the
        # feasible interval is unbounded above; the root is searched below the rounding band (F1* (1 - 1e-12) moves
        # the margin by 1e-12 W_F, far outside it), and any slower observation is that end
        F1_top = F1_max * (1.0 - 1e-12)
        t_top = _line_time(F1_top, E_S, alpha0, F1_max, F2_max, device, c)
        count += 1
        if math.isfinite(t_top) and stop_time >= t_top:
            return Identification(
                F1=F1_max, F2=0.0, F1_max=F1_max, F2_max=F2_max, stored_energy=E_S, alpha0=float(alpha0),
                alpha_final=float(alpha_final), stop_time=float(stop_time), mass_factor=c, device=device,
                stop_time_residual=0.0, feasible_stop_times=feasible,
                push_force=None if push_force is None else float(push_force), iterations=count, boundary="F2 = 0")
    if not (all(t > 0.0 for t in feasible) and math.isfinite(feasible[0])
            and (math.isfinite(feasible[1]) or F1_top < F1_max)):
        raise QuickReleaseError(f"E_S = {E_S:.6g} J (alpha0 = {alpha0:.6g} rad, alpha_F = {alpha_final:.6g} rad): "
                                f"the feasible stop times are [{feasible[0]:.6g}, {feasible[1]:.6g}] s, not finite "
                                "in floating point; E_S is outside the range the model resolves")
    lo, hi = feasible[0] - stop_time, feasible[1] - stop_time
    # The ends of the feasible interval are feasible: an observation within rounding of one of them (see
    # _kernels.feasible_slack) is that end, returned as such (F1 = 0 or F2 = 0 exactly, ``boundary`` set).
    # (on either side of it: the end is the solution there, to within what rounding can tell)
    boundary = None
    if abs(lo) <= feasible_slack(feasible[0], alpha0, alpha_final, 0.0):
        F1, F2, res, boundary = 0.0, F2_max, lo, "F1 = 0"
    elif math.isfinite(hi) and abs(hi) <= feasible_slack(feasible[1], alpha0, alpha_final, 0.0) or \
            0.0 > hi >= -feasible_slack(feasible[1], alpha0, alpha_final, 1.0):  # the F1* end: widened outwards
        F1, F2, res, boundary = F1_max, 0.0, hi, "F2 = 0"
    elif lo > 0.0 or hi < 0.0:
        raise InfeasibleObservationError(float(stop_time), feasible)
    else:
        hi = hi if F1_top == F1_max else residual(F1_top)
        F1 = brent(residual, 0.0, F1_top, lo, hi, xtol=1e-14 * F1_max)
        F2 = F2_max * (1.0 - F1 / F1_max)
        res = residual(F1)
    return Identification(
        F1=float(F1), F2=float(F2), F1_max=F1_max, F2_max=F2_max, stored_energy=E_S,
        alpha0=float(alpha0), alpha_final=float(alpha_final), stop_time=float(stop_time),
        mass_factor=c, device=device, stop_time_residual=float(res), feasible_stop_times=feasible,
        push_force=None if push_force is None else float(push_force), iterations=count, boundary=boundary,
    )
