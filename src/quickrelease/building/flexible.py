"""A flexible superstructure (2-DOF shear building) on any isolation layer: the hysteretic ones too (SI units).

:class:`FlexibleBuilding` puts the superstructure, lumped at the roof (mass m_s on a storey of fixed-base period
T_s and damping ratio zeta_s), on an isolation layer of any model: :class:`~quickrelease.building.hysteretic.Pendulum`,
:class:`~quickrelease.building.hysteretic.BoucWen` or :class:`~quickrelease.building.model.Isolation` (linear or
bilinear) with a viscous damper. The layer is the rigid model's, whole mass m included (the weight on the sliders,
k = m (2 pi / T)^2, zeta referred to m); the base's mass is ``m_b = m - m_s``:

    m_b x_b'' + F_iso(x_b, x_b', z) - c_s u' - k_s u = 0,     m_s x_s'' + c_s u' + k_s u = 0,     u = x_s - x_b,

with ``k_s = m_s (2 pi / T_s)^2``, ``c_s = 2 zeta_s sqrt(k_s m_s)``. While the sliders hold the base
(``|F_iso,static - k_s u - c_s u'| <= f_slow``, the sliders' static limit) the roof vibrates on it and the storey's
force can break it away again. :func:`free_vibration_flexible` integrates it by the event-located scheme of
:mod:`quickrelease.building._ode_flexible` (reversals, sticks, re-slips, yields located to machine precision).

:class:`~quickrelease.building.model.TwoDOF` is the linear layer's case in closed form (and its fit's model); this
class composes an isolation with a superstructure rather than adding an optional isolation to TwoDOF, whose fields
(period, damping ratio, friction) are the linear layer's own and would contradict a pendulum's or a Bouc-Wen's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ParameterError
from . import _ode, _ode_flexible
from .hysteretic import (
    MAX_STEPS,
    BoucWen,
    GridTurns,
    Pendulum,
    checked_d0,
    checked_horizon,
    natural_period,
    real_number,
)
from .hysteretic import _ode_net as _net
from .hysteretic import _ode_stored as _stored
from .model import BaseAndRoof, Isolation, pushed_state

__all__ = ["FlexibleBuilding", "FlexibleVibration", "free_vibration_flexible"]


@dataclass(frozen=True)
class FlexibleBuilding:
    """A superstructure lumped at the roof on an isolation layer of any model (SI units)."""

    isolation: Isolation | Pendulum | BoucWen
    """The isolation layer, its ``mass`` the whole building's m (its damper viscous or a power law)."""
    superstructure_mass: float
    """Superstructure mass lumped at the roof, m_s [kg], in (0, m)."""
    superstructure_period: float
    """Fixed-base period of the superstructure, T_s = 2 pi sqrt(m_s / k_s) [s]."""
    superstructure_damping_ratio: float = 0.0
    """Damping ratio of the superstructure on a fixed base, zeta_s = c_s / (2 sqrt(k_s m_s)) [-], in [0, 1)."""

    def __post_init__(self) -> None:
        iso = self.isolation
        if not isinstance(iso, Isolation | Pendulum | BoucWen):
            raise ParameterError("isolation", type(iso).__name__, "an Isolation, Pendulum or BoucWen")
        ms = real_number("superstructure_mass", self.superstructure_mass, f"(0, mass) = (0, {iso.mass:.6g}) kg",
                         "kg", test=lambda v: 0.0 < v < iso.mass)
        Ts = real_number("superstructure_period", self.superstructure_period, "(0, inf)", "s",
                         test=lambda v: math.isfinite(v) and v > 0.0)
        w = 2.0 * math.pi / Ts
        ks = ms * w * w  # (not ** 2: a float's power raises OverflowError where a product is inf)
        if not (math.isfinite(ks) and ks > 0.0):  # 1e308 s: k_s = 0, the roof not held; 1e-200: inf
            raise ParameterError("superstructure_period", Ts, f"(0, inf) s with the storey's stiffness "
                                 f"m_s (2 pi / T_s)^2 finite and > 0 (it is {ks:.6g} N/m)", "s")
        zs = real_number("superstructure_damping_ratio", self.superstructure_damping_ratio, "[0, 1)",
                         test=lambda v: 0.0 <= v < 1.0)
        object.__setattr__(self, "superstructure_mass", ms)  # a 0-d array or numpy scalar given: a float kept
        object.__setattr__(self, "superstructure_period", Ts)
        object.__setattr__(self, "superstructure_damping_ratio", zs)

    model = "flexible"

    @property
    def mass(self) -> float:
        """The whole mass m = m_b + m_s [kg] (the isolation's)."""
        return float(self.isolation.mass)

    @property
    def base_mass(self) -> float:
        """m_b = m - m_s [kg]."""
        return self.mass - float(self.superstructure_mass)

    @property
    def superstructure_stiffness(self) -> float:
        """Storey stiffness k_s = m_s (2 pi / T_s)^2 [N/m]."""
        return float(self.superstructure_mass) * (2.0 * math.pi / float(self.superstructure_period)) ** 2

    @property
    def superstructure_damping(self) -> float:
        """Storey damping coefficient c_s = 2 zeta_s sqrt(k_s m_s) [N s/m]."""
        return 2.0 * float(self.superstructure_damping_ratio) * math.sqrt(
            self.superstructure_stiffness * float(self.superstructure_mass))

    def rigid(self) -> Isolation | Pendulum | BoucWen:
        """The rigid-superstructure limit (m_s -> 0 or T_s -> 0): the isolation itself."""
        return self.isolation

    def vector(self) -> tuple[np.ndarray, np.ndarray]:
        """The integrator's vectors: the layer's (:mod:`~quickrelease.building._ode`'s, its mass slot the base's
        m_b; the weight, stiffness and friction of the whole m) and the storey's (m_s, k_s, c_s)."""
        P = self.isolation.vector()
        P[_ode.M] = self.base_mass
        return P, np.array([float(self.superstructure_mass), self.superstructure_stiffness,
                            self.superstructure_damping])

    def free_vibration(self, d0: float, t_end: float | None = None, coarse: float = 1.0) -> FlexibleVibration:
        """:func:`free_vibration_flexible` of this building (what :func:`quickrelease.building.model.free_vibration`
        calls for it)."""
        return free_vibration_flexible(self, d0, t_end, coarse=coarse)

    def summary(self) -> dict[str, Any]:
        return {**self.isolation.summary(), "isolation_model": self.isolation.model, "model": "flexible",
                "superstructure_mass_kg": float(self.superstructure_mass),
                "superstructure_period_s": float(self.superstructure_period),
                "superstructure_damping_ratio": float(self.superstructure_damping_ratio),
                "superstructure_stiffness_N_m": self.superstructure_stiffness}


_KEYS = ("x_b", "x_s", "v_b", "v_s", "a_b", "a_s")


@dataclass(frozen=True, eq=False)
class FlexibleVibration(GridTurns, BaseAndRoof):
    """The free vibration of a :class:`FlexibleBuilding` from the pushed state (SI units); the interface of
    :class:`~quickrelease.building.model.TwoDOFVibration` (:meth:`state` is the base's, :meth:`roof_state`,
    :meth:`states`, :meth:`channels`, :meth:`energies`, the turning points and the stop) and of
    :class:`~quickrelease.building.hysteretic.HystereticVibration` (:meth:`restoring_force`)."""

    building: FlexibleBuilding
    d0: float
    """Pushed displacement of base and roof at the release [m]."""
    stop_time: float
    """When the sliders hold the base for good [s] (inf: not within the horizon, where the integration's last step
    may have found it); the roof rings on."""
    horizon: float
    """The time up to which the motion was followed [s]."""
    _P: np.ndarray = field(repr=False)
    _S: np.ndarray = field(repr=False)
    _grid: tuple = field(repr=False)
    _push: np.ndarray = field(repr=False)
    _still: float = field(default=math.inf, repr=False)  # where the base came to rest for good (past the horizon too)

    @property
    def isolation(self) -> FlexibleBuilding:
        return self.building

    @property
    def rest(self) -> tuple[float, float]:
        """(x_b, z) where the base is held for good (the last state followed when it is not)."""
        y = self._grid[1][self._grid[4] - 1]
        return float(y[0]), float(y[2])

    def _changes(self, before, after) -> np.ndarray:
        """Grid indices where the piece's direction changes as asked, within the horizon (the last step may
        run past it)."""
        gt, _, gd, _, n = self._grid
        i = np.flatnonzero(before(gd[: n - 1]) & after(gd[1:n]) & (gd[1:n] != gd[: n - 1])) + 1
        return i[gt[i] <= self.horizon]

    def _turns(self) -> np.ndarray:
        return self._changes(lambda d: d != 0.0, lambda d: np.ones(d.shape, bool))


    @property
    def stick_times(self) -> np.ndarray:
        """Times where the sliders start to hold the base [s] (a re-slip may follow)."""
        return self._grid[0][self._changes(lambda d: d != 0.0, lambda d: d == 0.0)]

    @property
    def slip_times(self) -> np.ndarray:
        """Times where the storey's force breaks the held base away again [s]."""
        return self._grid[0][self._changes(lambda d: d == 0.0, lambda d: d != 0.0)]

    def _evaluate(self, t) -> tuple[np.ndarray, np.ndarray]:
        t = np.asarray(t, dtype=float)
        gt, gy, gd, gf, n = self._grid
        ys, acc = _ode_flexible.evaluate(self._P, self._S, gt, gy, gd, gf, n, self._still, self._push,
                                         np.ascontiguousarray(t.ravel()))
        return ys.reshape(t.shape + (_ode_flexible.NY,)), acc.reshape(t.shape + (2,))

    def states(self, t) -> dict[str, np.ndarray]:
        """x, v, a of the base (``x_b, v_b, a_b``) and of the roof (``x_s, v_s, a_s``) at times t [s]
        [m, m/s, m/s^2]; before the release both at rest at d0."""
        ys, acc = self._evaluate(t)
        return {"x_b": ys[..., 0], "x_s": ys[..., _ode_flexible.XS], "v_b": ys[..., 1],
                "v_s": ys[..., _ode_flexible.VS], "a_b": acc[..., 0], "a_s": acc[..., 1]}


    def channels(self, t) -> dict[str, np.ndarray]:
        """Every channel of the building's record at times t [s] (SI): x, v, a of the base and x_roof, v_roof,
        a_roof of the roof."""
        s = self.states(t)
        return {"x": s["x_b"], "v": s["v_b"], "a": s["a_b"], "x_roof": s["x_s"], "v_roof": s["v_s"],
                "a_roof": s["a_s"]}

    def restoring_force(self, t) -> np.ndarray:
        """The isolators' force without the sliders' friction and the damper [N] (as
        :meth:`HystereticVibration.restoring_force`)."""
        ys, _ = self._evaluate(t)
        return _net(self._P, ys)

    def energies(self, t) -> dict[str, np.ndarray]:
        """The energy balance at times t [J]: kinetic ``(m_b v_b^2 + m_s v_s^2) / 2``, stored (the layer's springs
        and hysteretic element's elastic part, and the storey's ``k_s u^2 / 2``), the work of the hysteresis, of
        the sliders' friction and of the dampers (``viscous``: the layer's and the storey's) so far; their sum is
        ``initial``, the layer's energy at the push (the storey undeformed). ``storey_stored`` and
        ``storey_viscous`` are the storey's parts of ``stored`` and ``viscous``."""
        ys, _ = self._evaluate(np.atleast_1d(np.asarray(t, dtype=float)))
        P, S = self._P, self._S
        u = ys[:, _ode_flexible.XS] - ys[:, 0]
        kinetic = 0.5 * P[_ode.M] * ys[:, 1] ** 2 + 0.5 * S[_ode_flexible.MS] * ys[:, _ode_flexible.VS] ** 2
        storey = 0.5 * S[_ode_flexible.KS] * u**2
        stored = _stored(P, ys) + storey
        storey_viscous = ys[:, _ode_flexible.WS]
        initial = float(_stored(P, self._push[None, :])[0])
        return {"kinetic": kinetic, "stored": stored, "hysteretic": ys[:, 5], "friction": ys[:, 3],
                "viscous": ys[:, 4] + storey_viscous, "initial": np.full(kinetic.shape, initial),
                "storey_stored": storey, "storey_viscous": storey_viscous}

    def summary(self) -> dict[str, Any]:
        peaks = self.turning_points
        return {**self.building.summary(), "d0_m": self.d0, "stop_time_s": self.stop_time,
                "rest_displacement_m": self.rest[0], "half_cycles": int(peaks.size - 1),
                "first_peak_m": float(peaks[1]) if peaks.size > 1 else None}


def free_vibration_flexible(building: FlexibleBuilding, d0: float, t_end: float | None = None, *,
                            coarse: float = 1.0) -> FlexibleVibration:
    """The flexible building's free vibration after the release from the pushed state (SI units).

    The jack pushes the base quasi-statically, so the roof rides on it undeformed: at the release
    ``x_b = x_s = d0`` [m], at rest, the layer's internal variable as after the rigid model's push
    (:func:`~quickrelease.building.model.pushed_state`).

    Parameters
    ----------
    building : FlexibleBuilding
    d0 : float
        Base (and roof) displacement at the release [m].
    t_end : float, optional
        Follow the motion up to this time [s]; by default until the sliders hold the base for good (needs the
        sliders' friction; the roof rings on after it).
    coarse : float
        The integrator's steps this many times longer, in [1, 4] (default 1): the fit's search on a thinned record
        takes 2 (as the rigid layers', :func:`quickrelease.building.model.free_vibration`).
    """
    if not isinstance(building, FlexibleBuilding):
        raise ParameterError("building", type(building).__name__, "a FlexibleBuilding")
    coarse = real_number("coarse", coarse, "[1, 4]", test=lambda v: 1.0 <= v <= 4.0)
    d0 = checked_d0(building.isolation, d0)
    P, S = building.vector()
    P[_ode.COARSE] = coarse
    horizon = checked_horizon(t_end, P[_ode.FSLOW], natural_period(building.isolation))  # the layer's, whole m
    z0 = pushed_state(building.isolation, d0)[0]
    y0 = np.array([d0, 0.0, z0, 0.0, 0.0, 0.0, d0, 0.0, 0.0])
    gt, gy, gd, gf, n, stop, status = _ode_flexible.integrate(P, S, y0, horizon, 4096, MAX_STEPS)
    if status == 2:
        raise ParameterError("t_end", horizon, f"a span of at most {MAX_STEPS} integration steps", "s")
    if status == 3:
        raise ParameterError("t_end", horizon, f"a span where the base's events make progress (more than "
                             f"{_ode_flexible.MAX_CHAIN} reversals, sticks or slips in a row)", "s")
    grid = (gt[:n].copy(), gy[:n].copy(), gd[:n].copy(), gf[:n].copy(), int(n))
    # the last step may run past the horizon and find the hold there: within the horizon the base still slides
    return FlexibleVibration(building=building, d0=d0, stop_time=float(stop) if stop <= horizon else math.inf,
                             horizon=horizon, _P=P, _S=S, _grid=grid, _push=y0, _still=float(stop))
