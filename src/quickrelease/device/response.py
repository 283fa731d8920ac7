"""The result of a release simulation: one Response type for every solver."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._results import Summarised
from . import dynamics, kinematics
from .parameters import Device

__all__ = ["Response", "STOP_REASONS", "TIME_HISTORIES"]

#: The time histories of a release: column (CSV, with its unit), variable name (NetCDF, xarray), unit
#: (UDUNITS) and long name. The order is the files' column order.
TIME_HISTORIES: dict[str, tuple[str, str, str]] = {
    "t_s": ("t", "s", "time since the fuse broke"),
    "alpha_rad": ("alpha", "rad", "angle of the bars with the loading axis"),
    "alpha_dot_rad_s": ("alpha_dot", "rad/s", "angular velocity of the bars"),
    "alpha_ddot_rad_s2": ("alpha_ddot", "rad/s^2", "angular acceleration of the bars"),
    "u_m": ("u", "m", "retraction of the head along the loading axis"),
    "v_m": ("v", "m", "opening of the rhombus across the loading axis"),
    "u_dot_m_s": ("u_dot", "m/s", "velocity of the head"),
    "v_dot_m_s": ("v_dot", "m/s", "opening velocity"),
    "u_ddot_m_s2": ("u_ddot", "m/s^2", "acceleration of the head"),
    "v_ddot_m_s2": ("v_ddot", "m/s^2", "opening acceleration"),
    "E_K_J": ("E_K", "J", "kinetic energy of the device"),
    "W_F_J": ("W_F", "J", "energy dissipated by friction"),
    "E_S_J": ("E_S", "J", "strain energy stored at release"),
}

#: Why the motion ended: friction dissipated E_S (Eq. 8), or the rhombus became flat.
STOP_REASONS = {
    "friction": "friction dissipated the stored energy (Eq. 8)",
    "geometric_limit": "the rhombus became flat (alpha = pi/2) with kinetic energy left",
    "creeps_to_limit": "creeps towards the flat rhombus and never arrives (stop_time = inf, alpha_final = pi/2 "
                       "its limit): no rail friction and E_S = W_F(pi/2) within rounding "
                       "(quickrelease.device.dynamics.creeps_terms)",
}


@dataclass(frozen=True, eq=False)
class Response(Summarised):
    """Time history and summary of one release.

    Arrays share the time axis ``t`` (shape ``(n,)``). Angles in rad, lengths in m,
    times in s, energies in J. The last sample before any padding is the end of the
    motion: at a friction stop ``alpha_dot = 0`` and ``alpha_ddot = 0`` there
    (friction balances inertia at rest, as the paper notes for Fig. 13c); samples
    after ``stop_time`` (requested with ``t_end``) are at rest.
    """

    t: np.ndarray
    """Time since release [s]."""
    alpha: np.ndarray
    """Bar angle with the loading axis [rad]."""
    alpha_dot: np.ndarray
    """Angular velocity [rad/s]."""
    alpha_ddot: np.ndarray
    """Angular acceleration [rad/s^2] (Eq. 3/4)."""
    stored_energy: float
    """E_S, the strain energy released [J]."""
    alpha0: float
    """Angle at release [rad]."""
    F1: float
    """Friction force at the central hinges [N]."""
    F2: float
    """Friction force at the rail supports [N]."""
    mass_factor: float
    """c of Eq. 5: 1 lumped, 2/3 distributed [-]."""
    device: Device
    """The device simulated."""
    stop_time: float
    """t_F, when the motion ended [s]; inf for ``"creeps_to_limit"`` (the arrays then end at the horizon
    ``stats["horizon_s"]``, where the kinetic energy is 1e-6 E_S; pi/2 - alpha decays like exp(-t / tau) after it,
    ``tau = stats["time_constant_s"]``)."""
    alpha_final: float
    """alpha_F, the angle where the motion ended [rad]."""
    stopped_by: str
    """``"friction"``, ``"geometric_limit"`` or ``"creeps_to_limit"`` (see :data:`STOP_REASONS`)."""
    method: str
    """Solver that produced the response: ``energy``, ``rk`` or ``explicit``."""
    stats: dict[str, Any] = field(default_factory=dict)
    """Solver statistics (steps, function evaluations, time step)."""
    push_force: float | None = None
    """P, the push force at release that stored E_S (Eq. 2) [N]; ``None`` when E_S was given directly."""

    # -- derived time histories -------------------------------------------------
    @property
    def L1(self) -> float:
        return self.device.L1

    @property
    def u(self) -> np.ndarray:
        """Head retraction u(t) (Table 4) [m]."""
        return kinematics.retraction(self.alpha, self.alpha0, self.L1)

    @property
    def v(self) -> np.ndarray:
        """Central hinge opening v(t) (Table 4) [m]."""
        return kinematics.opening(self.alpha, self.alpha0, self.L1)

    @property
    def u_dot(self) -> np.ndarray:
        """Head velocity [m/s]."""
        return kinematics.retraction_rate(self.alpha, self.alpha_dot, self.L1)

    @property
    def v_dot(self) -> np.ndarray:
        """Central hinge velocity [m/s]."""
        return kinematics.opening_rate(self.alpha, self.alpha_dot, self.L1)

    @property
    def u_ddot(self) -> np.ndarray:
        """Head acceleration [m/s^2]."""
        return kinematics.retraction_acceleration(self.alpha, self.alpha_dot, self.alpha_ddot, self.L1)

    @property
    def v_ddot(self) -> np.ndarray:
        """Central hinge acceleration [m/s^2]."""
        return kinematics.opening_acceleration(self.alpha, self.alpha_dot, self.alpha_ddot, self.L1)

    @property
    def kinetic_energy(self) -> np.ndarray:
        """E_K(t) (Eq. 5) [J]."""
        d = self.device
        return dynamics.kinetic_energy(self.alpha, self.alpha_dot, d.m1, d.m2, d.L1, self.mass_factor)

    @property
    def dissipated_energy(self) -> np.ndarray:
        """W_F(t) (Eq. 7) [J]."""
        return dynamics.dissipated_energy(self.alpha, self.alpha0, self.F1, self.F2, self.L1)

    @property
    def alpha_dot0(self) -> float:
        """Initial angular velocity (Eq. 6) [rad/s]."""
        return float(self.alpha_dot[0])

    @property
    def u_final(self) -> float:
        """Head stroke at the end of the motion, u_F [m]."""
        return float(kinematics.retraction(self.alpha_final, self.alpha0, self.L1))

    @property
    def v_final(self) -> float:
        """Central hinge opening at the end of the motion, v_F [m]."""
        return float(kinematics.opening(self.alpha_final, self.alpha0, self.L1))

    def energy_balance_error(self) -> np.ndarray:
        """``(E_K + W_F - E_S) / E_S`` along the solution (0 for an exact solution) [-]."""
        return (self.kinetic_energy + self.dissipated_energy - self.stored_energy) / self.stored_energy

    def state_diagram(self, points: int = 400) -> dict[str, np.ndarray]:
        """The numbers behind Fig. 15: the solution's states, Eq. 10 at them, and its distance from Eq. 10.

        ``alpha``, ``alpha_dot`` [rad, rad/s]: the numerical states up to the stop; ``alpha_dot_analytic``:
        Eq. 10, ``sqrt((E_S - W_F(alpha)) / M(alpha))``, at the same angles; ``energy_residual`` [J]:
        ``|F|`` with ``F(alpha, alpha_dot) = M(alpha) alpha_dot^2 + W_F(alpha) - E_S`` (Eq. 9, ``E_K + W_F -
        E_S``), whose zero level is the curve (relative to E_S, the distance printed on Fig. 15; unlike the
        vertical gap it stays meaningful near the stop, where the curve is vertical); ``distance``: that
        residual turned into a distance in the state plane, to first order ``|F| / |grad F|`` (rad and rad/s
        taken together: a check, not a quantity with one unit); ``curve_alpha``, ``curve_alpha_dot``: Eq. 10
        on ``points`` angles from alpha0 to alpha_F (the analytic curve drawn under the states)."""
        d = self.device
        moving = self.t <= self.stop_time
        alpha, alpha_dot = self.alpha[moving], self.alpha_dot[moving]
        W = dynamics.dissipated_energy(alpha, self.alpha0, self.F1, self.F2, d.L1)
        M = dynamics.generalized_mass(alpha, d.m1, d.m2, d.L1, self.mass_factor)
        analytic = np.sqrt(np.maximum(self.stored_energy - W, 0.0) / M)
        F = M * alpha_dot**2 + W - self.stored_energy
        dM = d.m2 * d.L1**2 * np.sin(2.0 * alpha)
        dW = 2.0 * self.F1 * d.L1 * np.cos(alpha) + 4.0 * self.F2 * d.L1 * np.sin(alpha)
        grad = np.hypot(dM * alpha_dot**2 + dW, 2.0 * M * alpha_dot)
        fine = np.linspace(self.alpha0, self.alpha_final, points)
        W_fine = dynamics.dissipated_energy(fine, self.alpha0, self.F1, self.F2, d.L1)
        M_fine = dynamics.generalized_mass(fine, d.m1, d.m2, d.L1, self.mass_factor)
        return {"alpha": alpha, "alpha_dot": alpha_dot, "alpha_dot_analytic": analytic,
                "energy_residual": np.abs(F), "distance": np.abs(F) / grad, "curve_alpha": fine,
                "curve_alpha_dot": np.sqrt(np.maximum(self.stored_energy - W_fine, 0.0) / M_fine)}

    # -- summaries ---------------------------------------------------------------
    def summary(self) -> dict[str, Any]:
        """The release in numbers, with units in the key names (JSON-ready): the keys and values
        ``quickrelease simulate --json`` prints, the push force P first (``None`` when E_S was given) and the
        device's name last."""
        moving = self.t <= self.stop_time
        return {
            "push_force_N": self.push_force,
            "method": self.method,
            "mass_factor": self.mass_factor,
            "stored_energy_J": self.stored_energy,
            "alpha0_rad": self.alpha0,
            "alpha_dot0_rad_s": self.alpha_dot0,
            "F1_N": self.F1,
            "F2_N": self.F2,
            "alpha_final_rad": self.alpha_final,
            "stop_time_s": self.stop_time if math.isfinite(self.stop_time) else None,  # None: never (JSON null)
            "stopped_by": self.stopped_by,
            "u_final_m": self.u_final,
            "v_final_m": self.v_final,
            "peak_alpha_dot_rad_s": float(np.max(self.alpha_dot[moving])),
            "peak_u_dot_m_s": float(np.max(np.abs(self.u_dot[moving]))),
            "peak_v_dot_m_s": float(np.max(np.abs(self.v_dot[moving]))),
            "peak_u_ddot_m_s2": float(np.max(np.abs(self.u_ddot[moving]))),
            "peak_v_ddot_m_s2": float(np.max(np.abs(self.v_ddot[moving]))),
            "samples": int(self.t.size),
            "device": self.device.name,
        }

    def to_dict(self) -> dict[str, np.ndarray]:
        """The time histories as a dict of arrays, keys with units."""
        return {
            "t_s": self.t,
            "alpha_rad": self.alpha,
            "alpha_dot_rad_s": self.alpha_dot,
            "alpha_ddot_rad_s2": self.alpha_ddot,
            "u_m": self.u,
            "v_m": self.v,
            "u_dot_m_s": self.u_dot,
            "v_dot_m_s": self.v_dot,
            "u_ddot_m_s2": self.u_ddot,
            "v_ddot_m_s2": self.v_ddot,
            "E_K_J": self.kinetic_energy,
            "W_F_J": self.dissipated_energy,
            "E_S_J": np.full_like(self.t, self.stored_energy),
        }

    def to_pandas(self):
        """The time histories as a pandas DataFrame indexed by the time ``t_s`` (columns with units in their
        names, as in the CSV; ``.reset_index()`` gives the time as a column)."""
        import pandas as pd

        return pd.DataFrame(self.to_dict()).set_index("t_s")

    def to_xarray(self, provenance: dict[str, Any] | None = None):
        """The time histories as an ``xarray.Dataset`` on the time coordinate ``t`` [s], each variable with its
        ``units`` and ``long_name`` (CF conventions), the summary as global attributes: what
        ``quickrelease run`` writes as ``timeseries.nc``. ``ds.alpha.plot()`` plots against time. ``provenance``
        (:func:`quickrelease.io.runfolder.provenance`) adds the version, the input file and its SHA-256."""
        import xarray as xr

        from .._version import __version__

        data = self.to_dict()
        name, unit, long_name = TIME_HISTORIES["t_s"]
        coords = {name: (name, data.pop("t_s"), {"units": unit, "long_name": long_name, "axis": "T"})}
        variables = {TIME_HISTORIES[col][0]: (name, np.asarray(values, dtype=float),
                                              {"units": TIME_HISTORIES[col][1], "long_name": TIME_HISTORIES[col][2]})
                     for col, values in data.items()}
        attrs: dict[str, Any] = {"title": "quickrelease release time history", "Conventions": "CF-1.8",
                                 "source": f"quickrelease {__version__}"}
        for key, value in self.summary().items():
            if value is not None:
                attrs[key] = int(value) if isinstance(value, bool) else value
        if provenance is not None:
            from .._version import provenance_attrs

            attrs.update(provenance_attrs(provenance))
        return xr.Dataset(variables, coords=coords, attrs=attrs)

    def plot(self, kind: str = "fig13", fig=None, ax=None):
        """Draw the release: ``"fig13"`` (angle, rate, acceleration, energy balance; four panels), ``"fig14"``
        (displacements and velocities; two) or ``"state"`` (the state diagram, Fig. 15; one). ``fig``: a
        Figure or SubFigure to fill; ``ax``: Axes to draw into instead (as many as the figure has panels).
        Returns the figure (:mod:`quickrelease.report.plots`)."""
        from ..report import plots

        kinds = {"fig13": plots.fig13, "fig14": plots.fig14, "state": plots.fig15}
        if kind not in kinds:
            from ..errors import ParameterError

            raise ParameterError("kind", repr(kind), ", ".join(kinds))
        return kinds[kind](self, fig=fig, ax=ax)

    def __repr__(self) -> str:
        return (
            f"Response(method={self.method!r}, stop_time={self.stop_time:.6g} s, "
            f"alpha_final={self.alpha_final:.6g} rad, stopped_by={self.stopped_by!r}, "
            f"samples={self.t.size})"
        )

    def pad_to(self, t_end: float, spacing: float) -> Response:
        """A copy with rest samples appended after a friction stop, up to ``t_end`` [s]."""
        if self.stopped_by != "friction" or t_end <= self.stop_time:
            return self
        n_extra = max(1, math.ceil((t_end - self.stop_time) / spacing - 1e-9))
        t_extra = self.stop_time + (t_end - self.stop_time) * np.arange(1, n_extra + 1) / n_extra
        zeros = np.zeros(n_extra)
        return Response(
            t=np.concatenate([self.t, t_extra]),
            alpha=np.concatenate([self.alpha, np.full(n_extra, self.alpha_final)]),
            alpha_dot=np.concatenate([self.alpha_dot, zeros]),
            alpha_ddot=np.concatenate([self.alpha_ddot, zeros]),
            stored_energy=self.stored_energy,
            alpha0=self.alpha0,
            F1=self.F1,
            F2=self.F2,
            mass_factor=self.mass_factor,
            device=self.device,
            stop_time=self.stop_time,
            alpha_final=self.alpha_final,
            stopped_by=self.stopped_by,
            method=self.method,
            stats=self.stats,
            push_force=self.push_force,
        )
