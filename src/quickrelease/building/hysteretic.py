"""The isolation systems without a closed form: friction pendulums, Bouc-Wen bearings, power-law dampers (SI).

- :class:`Pendulum`, the curved surface slider (friction pendulum): restoring force ``W x / R`` (W = m g, R the
  radius of the sliding surface), friction ``mu(|v|) W sign(v)`` with Constantinou's law
  ``mu(v) = mu_fast - (mu_fast - mu_slow) exp(-a |v|)`` (Constantinou, Mokha and Reinhorn 1990), or a constant
  coefficient; the slider sticks at a reversal while ``|W x / R| <= mu_slow W``.
- :class:`BoucWen`, smooth hysteresis for lead-rubber and high-damping rubber bearings: ``Kd x + Qd z`` with
  ``dy z_dot = x_dot (1 - |z|^n (beta sgn(x_dot z) + gamma))``, beta = gamma = 1/2 (Wen 1976; the form of
  Constantinou's and Park's isolator models: ``|z| <= 1``, initial stiffness ``Kd + Qd / dy``), in parallel with
  optional sliders. As n grows it tends to the bilinear model with k1 = Kd + Qd / dy, k2 = Kd,
  F_y = Qd + Kd dy.
- Any model's damper may follow the power law of a fluid viscous damper, ``C |v|^alpha sign(v)``
  (``damping_exponent`` alpha; 1 is the viscous damper): :class:`~quickrelease.building.model.Isolation` with
  ``damping_exponent != 1``, and these two.

Their free vibration (:class:`HystereticVibration`, made by :func:`quickrelease.building.model.free_vibration`)
is integrated by the event-located scheme of :mod:`quickrelease.building._ode`: every reversal, stick, yield and
zero crossing of z located to machine precision, no smoothed sign function; the dissipated energies are
integrated with the motion.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

from .._validate import check_real, finite_nonnegative, finite_positive
from ..errors import ParameterError
from . import _ode

__all__ = ["GRAVITY", "Pendulum", "BoucWen", "HystereticVibration", "SHAPE_RANGE", "EXPONENT_RANGE", "MAX_PERIODS",
           "MAX_PUSH_ENERGY"]

#: Standard gravity [m/s^2]: the weight W = m g on the sliders.
GRAVITY = 9.80665
#: The Bouc-Wen shape exponent n's range (beyond ~20 the element is bilinear to the eye and the steps over its
#: transition grow many).
SHAPE_RANGE = (0.5, 25.0)
#: The damper's exponent alpha's range (fluid viscous dampers: 0.1 to 2).
EXPONENT_RANGE = (0.05, 2.0)
#: Steps of the monotonic push of a Bouc-Wen element, a yield displacement per this many (and n times more).
PUSH_STEPS = 4
#: Constantinou's rate a's range [s/m] (measured: 10 to 100 s/m): above 1e4 s/m mu(v) reaches mu_fast within
#: 0.5 mm/s, and the steps that resolve mu(v) (1 / (a |a_max| STEPS_RATE)) grow past millions a record (a = 1e6
#: took 11 s for one free vibration; 1e308 ran into MAX_STEPS).
RATE_RANGE = (0.0, 1.0e4)
#: Most steps one free vibration may take.
MAX_STEPS = 20_000_000
#: Most of its natural periods on the post-yield stiffness (:func:`natural_period`) a free vibration without the
#: sliders' friction (one that never ends) may be followed: a horizon of 1e308 s ran 111 s and 14.9 GB into
#: :data:`MAX_STEPS` (a Bouc-Wen layer of 4.4 s: 1e4 periods are ~1.3 million steps, ~15 s).
MAX_PERIODS = 10_000
#: Largest energy [J] the push may store in the layer, ``k1 d0^2 / 2`` (its initial stiffness k1): beyond ~1e308
#: the forces and works overflow and the integration ran on NaN (d0 = 1e153 m).
MAX_PUSH_ENERGY = 1.0e300


def real_number(name: str, value, valid: str, unit: str = "", test=math.isfinite) -> float:
    """``float(value)``; ParameterError (naming ``name``, its value and ``valid``) unless ``value`` is a real number
    (an int, float, numpy scalar or 0-d numeric array; not a bool, a string or an array) for which ``test`` holds."""
    if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf":
        value = value[()]
    return check_real(name, value, valid, unit, test=test)


def checked_d0(system, d0) -> float:
    """The release displacement d0 [m] as a float: ParameterError unless it is a real number, finite, non-zero,
    within a pendulum's radius R (a point of its spherical surface) and storing at most :data:`MAX_PUSH_ENERGY`
    in the layer's initial stiffness (``k1 d0^2 / 2``)."""
    d0 = real_number("d0", d0, "finite and non-zero", "m", test=lambda v: math.isfinite(v) and v != 0.0)
    reach = math.sqrt(2.0 * MAX_PUSH_ENERGY / float(system.stiffness))
    if isinstance(system, Pendulum):
        reach = min(reach, float(system.radius))
    if not abs(d0) < reach:
        what = "the radius R" if isinstance(system, Pendulum) and reach == float(system.radius) else \
            f"the push's energy k1 d0^2 / 2 <= {MAX_PUSH_ENERGY:g} J"
        raise ParameterError("d0", d0, f"non-zero, |d0| < {reach:.6g} m ({what})", "m")
    return d0


def checked_horizon(t_end, friction: float, period: float) -> float:
    """How long to follow a free vibration [s]: ``t_end`` (a real number, finite and > 0), or with None until the
    sliders hold it for good (inf), which needs their ``friction`` [N] > 0; without friction (the motion never
    ends) at most :data:`MAX_PERIODS` of the system's natural ``period`` [s]. ParameterError naming t_end
    otherwise."""
    if t_end is None:
        if friction == 0.0:
            raise ParameterError("t_end", None, "a finite time in (0, inf) s when the isolation has no sliders' "
                                 "friction (the motion never ends)")
        return math.inf
    horizon = real_number("t_end", t_end, "(0, inf)", "s", test=lambda v: math.isfinite(v) and v > 0.0)
    if friction == 0.0 and not horizon <= MAX_PERIODS * period:
        raise ParameterError("t_end", horizon, f"(0, {MAX_PERIODS * period:.6g}] s, {MAX_PERIODS} periods of "
                             f"{period:.6g} s, when the isolation has no sliders' friction (the motion never ends)",
                             "s")
    return horizon


def natural_period(system) -> float:
    """The layer's period on its post-yield stiffness k2, ``2 pi sqrt(m / k2)`` [s] (the pendulum's W / R, the
    Bouc-Wen element's Kd, the linear model's k): the longest of its elastic motions, the scale of
    :data:`MAX_PERIODS` (generous: the steps follow the shorter ones)."""
    return 2.0 * math.pi * math.sqrt(float(system.mass) / float(system.k2))


def viscous_damping_ratio(system) -> float:
    """The viscous damper's ratio of an isolation ``system`` (Pendulum, BoucWen) referred to its post-yield
    stiffness k2, ``c / (2 sqrt(k2 m))`` [-] (nan with a power-law damper, exponent other than 1)."""
    if system.damping_exponent != 1.0:
        return math.nan
    return system.damping / (2.0 * math.sqrt(system.k2 * system.mass))


def damping_exponent(value: float) -> float:
    """The damper's exponent alpha, checked against :data:`EXPONENT_RANGE`."""
    value = float(value)
    lo, hi = EXPONENT_RANGE
    if not (math.isfinite(value) and lo <= value <= hi):
        raise ParameterError("damping_exponent", value, f"[{lo}, {hi}]")
    return value


def _set(obj, **values) -> None:
    for name, value in values.items():
        object.__setattr__(obj, name, value)


@dataclass(frozen=True)
class Pendulum:
    """The friction pendulum (curved surface slider) under a rigid superstructure (SI units)."""

    mass: float
    """Mass on the sliders m [kg]; the weight W = m g (:data:`GRAVITY`)."""
    radius: float
    """Radius of the sliding surface R [m] (the effective radius; the pendulum period is 2 pi sqrt(R / g))."""
    friction_slow: float
    """Friction coefficient at vanishing velocity mu_slow [-] (also the static one: the slider holds below it)."""
    friction_fast: float | None = None
    """Friction coefficient at high velocity mu_fast [-]; None: equal to ``friction_slow`` (constant friction)."""
    rate: float = 0.0
    """Constantinou's rate a [s/m] of ``mu(v) = mu_fast - (mu_fast - mu_slow) exp(-a |v|)``."""
    damping: float = 0.0
    """Coefficient C of a damper in parallel, ``C |v|^alpha sign(v)`` [N (s/m)^alpha]."""
    damping_exponent: float = 1.0
    """The damper's exponent alpha [-] (1: viscous, C in N s/m)."""

    def __post_init__(self) -> None:
        finite_positive("mass", self.mass, "kg")
        finite_positive("radius", self.radius, "m")
        finite_nonnegative("friction_slow", self.friction_slow)
        if self.friction_fast is None:
            _set(self, friction_fast=float(self.friction_slow))
        finite_nonnegative("friction_fast", self.friction_fast)
        finite_nonnegative("rate", self.rate, "s/m")
        if self.rate > RATE_RANGE[1]:
            raise ParameterError("rate", self.rate, f"[{RATE_RANGE[0]:g}, {RATE_RANGE[1]:g}] s/m")
        finite_nonnegative("damping", self.damping, "N (s/m)^alpha")
        _set(self, damping_exponent=damping_exponent(self.damping_exponent))

    model = "pendulum"

    @property
    def weight(self) -> float:
        """W = m g [N]."""
        return self.mass * GRAVITY

    @property
    def stiffness(self) -> float:
        """The pendulum's stiffness W / R [N/m]."""
        return self.weight / self.radius

    @property
    def period(self) -> float:
        """The pendulum period 2 pi sqrt(R / g) [s] (independent of the mass)."""
        return 2.0 * math.pi * math.sqrt(self.radius / GRAVITY)

    @property
    def constant_friction(self) -> bool:
        """Whether the friction coefficient is the same at every velocity."""
        return self.friction_fast == self.friction_slow or self.rate == 0.0

    def friction_coefficient(self, v) -> np.ndarray:
        """Constantinou's mu(|v|) [-] at velocities v [m/s]."""
        s = np.abs(np.asarray(v, dtype=float))
        if self.rate == 0.0:
            return np.full(s.shape, float(self.friction_slow))
        return self.friction_fast - (self.friction_fast - self.friction_slow) * np.exp(-self.rate * s)

    @property
    def friction(self) -> float:
        """The sliders' friction force at vanishing velocity, mu_slow W [N] (what holds the building at rest)."""
        return self.friction_slow * self.weight

    @property
    def k2(self) -> float:
        return self.stiffness

    @property
    def damping_ratio(self) -> float:
        """The viscous damper's ratio referred to the stiffness of ``period``, ``c / (2 sqrt(k m))`` [-] (nan
        with a power-law damper)."""
        return viscous_damping_ratio(self)

    def vector(self) -> np.ndarray:
        """The integrator's parameter vector (:mod:`quickrelease.building._ode`)."""
        P = np.zeros(_ode.NP)
        P[_ode.M], P[_ode.K] = self.mass, self.stiffness
        P[_ode.FSLOW] = self.friction
        P[_ode.FFAST] = self.friction_fast * self.weight
        P[_ode.RATE] = self.rate if not self.constant_friction else 0.0
        P[_ode.C], P[_ode.ALPHA] = self.damping, self.damping_exponent
        return P

    def pushed(self, d0: float) -> float:
        """The hysteretic variable after the push (none: 0)."""
        return 0.0

    def summary(self) -> dict[str, Any]:
        return {"model": "pendulum", "mass_kg": self.mass, "radius_m": self.radius, "period_s": self.period,
                "stiffness_N_m": self.stiffness, "friction_slow": self.friction_slow,
                "friction_fast": float(self.friction_fast), "rate_s_m": self.rate, "friction_N": self.friction,
                **_damper(self)}


@dataclass(frozen=True)
class BoucWen:
    """Smooth hysteretic bearings (lead-rubber, high-damping rubber) as a Bouc-Wen element (SI units)."""

    mass: float
    """Mass carried m [kg]."""
    post_yield_stiffness: float
    """Kd [N/m]: the stiffness once the element has yielded."""
    characteristic_strength: float
    """Qd [N]: the hysteretic force at full yield (the loop's force at zero displacement)."""
    yield_displacement: float
    """dy [m]: the element's elastic range (initial stiffness Kd + Qd / dy)."""
    shape: float = 1.0
    """n [-]: the sharpness of the transition (large n: bilinear)."""
    damping: float = 0.0
    """Coefficient C of a damper in parallel, ``C |v|^alpha sign(v)`` [N (s/m)^alpha]."""
    damping_exponent: float = 1.0
    """The damper's exponent alpha [-] (1: viscous, C in N s/m)."""
    friction: float = 0.0
    """Coulomb friction of sliders in parallel F_s [N] (static = kinetic)."""

    def __post_init__(self) -> None:
        finite_positive("mass", self.mass, "kg")
        finite_positive("post_yield_stiffness", self.post_yield_stiffness, "N/m")
        finite_positive("characteristic_strength", self.characteristic_strength, "N")
        finite_positive("yield_displacement", self.yield_displacement, "m")
        n = float(self.shape)
        if not (math.isfinite(n) and SHAPE_RANGE[0] <= n <= SHAPE_RANGE[1]):
            raise ParameterError("shape", n, f"[{SHAPE_RANGE[0]}, {SHAPE_RANGE[1]}]")
        finite_nonnegative("damping", self.damping, "N (s/m)^alpha")
        _set(self, damping_exponent=damping_exponent(self.damping_exponent))
        finite_nonnegative("friction", self.friction, "N")

    model = "boucwen"

    @property
    def stiffness(self) -> float:
        """The initial stiffness Kd + Qd / dy [N/m]."""
        return self.post_yield_stiffness + self.characteristic_strength / self.yield_displacement

    @property
    def k2(self) -> float:
        return float(self.post_yield_stiffness)

    @property
    def damping_ratio(self) -> float:
        """The viscous damper's ratio referred to the stiffness of ``period``, ``c / (2 sqrt(k m))`` [-] (nan
        with a power-law damper)."""
        return viscous_damping_ratio(self)

    @property
    def period(self) -> float:
        """The post-yield period 2 pi sqrt(m / Kd) [s]."""
        return 2.0 * math.pi * math.sqrt(self.mass / self.post_yield_stiffness)

    def bilinear(self) -> tuple[float, float, float]:
        """The bilinear model it tends to as n grows: (k1, k2, F_y) = (Kd + Qd / dy, Kd, Qd + Kd dy)."""
        return (self.stiffness, self.k2,
                self.characteristic_strength + self.post_yield_stiffness * self.yield_displacement)

    def vector(self) -> np.ndarray:
        P = np.zeros(_ode.NP)
        P[_ode.M], P[_ode.K] = self.mass, self.post_yield_stiffness
        P[_ode.HKIND], P[_ode.Q] = _ode.H_BOUCWEN, self.characteristic_strength
        P[_ode.DY], P[_ode.N] = self.yield_displacement, self.shape
        P[_ode.FSLOW] = P[_ode.FFAST] = self.friction
        P[_ode.C], P[_ode.ALPHA] = self.damping, self.damping_exponent
        return P

    def pushed(self, d0: float) -> float:
        """z after the monotonic push from x = 0, z = 0 to d0 [m]: ``dz/dx = (1 - |z|^n) / dy`` (for n = 1
        ``1 - exp(-|d0| / dy)``, signed), integrated on steps of dy / (:data:`PUSH_STEPS` max(n, 1))."""
        n, dy = float(self.shape), float(self.yield_displacement)
        # beyond dy (1 + 40 / min(n, 1)) z is 1 to rounding (1 - z falls as exp(-n x / dy) once past dy)
        reach = min(abs(d0), dy * (1.0 + 40.0 / min(n, 1.0)))
        steps = max(int(math.ceil(reach / dy * PUSH_STEPS * max(n, 1.0))), 8)
        return _pushed_z(n, dy, math.copysign(reach, d0), steps)

    def summary(self) -> dict[str, Any]:
        return {"model": "boucwen", "mass_kg": self.mass, "Kd_N_m": self.k2, "Qd_N": self.characteristic_strength,
                "dy_m": self.yield_displacement, "shape": self.shape, "initial_stiffness_N_m": self.stiffness,
                "period_s": self.period, "friction_N": self.friction, **_damper(self)}


@lru_cache(maxsize=256)
def _pushed_z(n: float, dy: float, reach: float, steps: int) -> float:
    """:func:`quickrelease.building._ode.boucwen_push`, remembered: a fit's Jacobian moves one parameter at a time,
    and most of its columns push the same element to the same displacement (0.1 ms a push)."""
    return float(_ode.boucwen_push(n, dy, reach, steps))


def _damper(system) -> dict[str, float]:
    if system.damping_exponent == 1.0:
        return {"damping_ratio": system.damping_ratio, "damping_N_s_m": system.damping}
    return {"damping_coefficient": system.damping, "damping_exponent": system.damping_exponent}


def _works(ys: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return ys[:, 3], ys[:, 4], ys[:, 5]


class GridTurns:
    """The turning points of an integrated motion, from its grid (``_grid``) and the grid points where it turns
    (``_turns()``: reversals, and sticks of a sliding base, within the horizon)."""

    @property
    def reversal_times(self) -> np.ndarray:
        """Times of the turning points (the layer's velocity vanishes) within the horizon, the release first [s]."""
        return np.concatenate(([0.0], self._grid[0][self._turns()]))

    @property
    def turning_points(self) -> np.ndarray:
        """Displacements of the layer at the turning points within the horizon, d0 first [m]."""
        return np.concatenate(([self.d0], self._grid[1][self._turns(), 0]))


@dataclass(frozen=True, eq=False)
class HystereticVibration(GridTurns):
    """The free vibration of an isolation layer without a closed form, from the pushed state (SI units).

    The same interface as :class:`~quickrelease.building.model.FreeVibration`: :meth:`state`, :meth:`channels`,
    :meth:`restoring_force`, :meth:`energies`, the turning points and the stop.
    """

    isolation: Any
    """The isolation (:class:`Pendulum`, :class:`BoucWen`, or an Isolation with a power-law damper)."""
    d0: float
    """Pushed displacement at the release [m]."""
    stop_time: float
    """When the sliders stick for good [s] (inf: still moving at the horizon; a stick that the integration's last
    step found past the horizon is not within it)."""
    horizon: float
    """The time up to which the motion was followed [s]."""
    _P: np.ndarray = field(repr=False)
    _grid: tuple = field(repr=False)
    _push: np.ndarray = field(repr=False)
    _dense: np.ndarray = field(repr=False)  # each grid step's continuous extension (7 x NY coefficients)
    _still: float = field(default=math.inf, repr=False)  # where the integration came to rest (past the horizon too)

    @property
    def rest(self) -> tuple[float, float]:
        """(x, z) where it sticks (the last state followed when it does not)."""
        y = self._grid[1][self._grid[4] - 1]
        return float(y[0]), float(y[2])

    def _turns(self) -> np.ndarray:
        """Grid indices of the turning points after the release, within the horizon (the integration's last step
        may run past it and find an event there)."""
        gt, _, gd, _, n = self._grid
        turns = np.flatnonzero((gd[1:n] != gd[: n - 1]) & (gd[: n - 1] != 0.0)) + 1
        return turns[gt[turns] <= self.horizon]


    def _evaluate(self, t) -> tuple[np.ndarray, np.ndarray]:
        t = np.asarray(t, dtype=float)
        gt, gy, gd, gf, n = self._grid
        ys, acc = _ode.evaluate(self._P, gt, gy, gd, gf, self._dense, n, self._still, self._push,
                                np.ascontiguousarray(t.ravel()))
        return ys.reshape(t.shape + (_ode.NY,)), acc.reshape(t.shape)

    def state(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Displacement [m], velocity [m/s] and acceleration [m/s^2] at times t [s] (the value after an instant
        where the acceleration jumps; before the release at rest at d0)."""
        t = np.asarray(t, dtype=float)
        flat = np.ascontiguousarray(t.ravel())
        if flat.size > 1 and not np.all(flat[1:] >= flat[:-1]):  # any order: through the sorted times
            order = np.argsort(flat, kind="stable")
            out = np.empty((3, flat.size))
            out[:, order] = self._motion(flat[order])
        else:
            out = self._motion(flat)
        return out[0].reshape(t.shape), out[1].reshape(t.shape), out[2].reshape(t.shape)

    def _motion(self, t: np.ndarray) -> np.ndarray:
        gt, gy, gd, gf, n = self._grid
        return _ode.motion(self._P, gt, gy, gd, gf, self._dense, n, self._still, self._push, t)

    def channels(self, t) -> dict[str, np.ndarray]:
        """Every channel of the building's record at times t [s] (the roof moves with the rigid layer)."""
        x, v, a = self.state(t)
        return {"x": x, "v": v, "a": a, "x_roof": x, "v_roof": v, "a_roof": a}

    def restoring_force(self, t) -> np.ndarray:
        """The isolators' force without the sliders' friction and the damper [N]: ``W x / R`` (pendulum),
        ``Kd x + Qd z`` (Bouc-Wen), ``k2 x + z`` (bilinear), ``k x`` (linear)."""
        ys, _ = self._evaluate(t)
        return _ode_net(self._P, ys)

    def energies(self, t) -> dict[str, np.ndarray]:
        """The energy balance at times t [J]: kinetic, stored (springs and the hysteretic element's elastic part:
        ``Qd dy z^2 / 2`` for Bouc-Wen, ``z^2 / (2 (k1 - k2))`` for the plastic element), the work of the
        hysteresis, of the sliders' friction and of the damper so far; their sum is ``initial``."""
        ys, _ = self._evaluate(np.atleast_1d(np.asarray(t, dtype=float)))
        P = self._P
        kinetic = 0.5 * P[_ode.M] * ys[:, 1] ** 2
        stored = _ode_stored(P, ys)
        friction, viscous, hysteretic = _works(ys)
        initial = float(_ode_stored(P, self._push[None, :])[0])
        return {"kinetic": kinetic, "stored": stored, "hysteretic": hysteretic, "friction": friction,
                "viscous": viscous, "initial": np.full(kinetic.shape, initial)}

    def summary(self) -> dict[str, Any]:
        peaks = self.turning_points
        return {**self.isolation.summary(), "d0_m": self.d0, "stop_time_s": self.stop_time,
                "rest_displacement_m": self.rest[0], "half_cycles": int(peaks.size - 1),
                "first_peak_m": float(peaks[1]) if peaks.size > 1 else None}


def _ode_net(P: np.ndarray, ys: np.ndarray) -> np.ndarray:
    fh = np.zeros(ys.shape[:-1])
    if P[_ode.HKIND] == _ode.H_BOUCWEN:
        fh = P[_ode.Q] * ys[..., 2]
    elif P[_ode.HKIND] == _ode.H_PLASTIC:
        fh = ys[..., 2]
    return P[_ode.K] * ys[..., 0] + fh


def _ode_stored(P: np.ndarray, ys: np.ndarray) -> np.ndarray:
    e = 0.5 * P[_ode.K] * ys[..., 0] ** 2
    if P[_ode.HKIND] == _ode.H_BOUCWEN:
        e = e + 0.5 * P[_ode.Q] * P[_ode.DY] * ys[..., 2] ** 2
    elif P[_ode.HKIND] == _ode.H_PLASTIC:
        e = e + 0.5 * ys[..., 2] ** 2 / P[_ode.KP]
    return e


def hysteretic_vibration(system, P: np.ndarray, z0: float, d0: float, t_end: float | None) -> HystereticVibration:
    """The free vibration of ``system`` (parameter vector P, hysteretic variable z0 after the push to d0 [m]) up
    to t_end [s] (None: until the sliders stick, which needs friction)."""
    d0 = checked_d0(system, d0)
    horizon = checked_horizon(t_end, P[_ode.FSLOW], natural_period(system))
    y0 = np.array([d0, 0.0, z0, 0.0, 0.0, 0.0])
    capacity = 4096
    while True:
        gt, gy, gd, gf, gF, n, stop, status = _ode.integrate(P, y0, horizon, capacity, MAX_STEPS)
        if status == 0:
            break
        if status == 2:
            raise ParameterError("t_end", horizon, f"a span of at most {MAX_STEPS} integration steps", "s")
        if status == 3:
            raise ParameterError("isolation", type(system).__name__, "a layer whose motion advances: it turned "
                                 f"{_ode.MAX_STALLED} times at t = {gt[n - 1]:.9g} s without moving (at its sliders' "
                                 "holding limit to rounding)")
        capacity *= 4
    grid = (gt[:n].copy(), gy[:n].copy(), gd[:n].copy(), gf[:n].copy(), int(n))
    # the last step may run past the horizon and stick there: within the horizon the layer still moves
    return HystereticVibration(isolation=system, d0=d0, stop_time=float(stop) if stop <= horizon else math.inf,
                               horizon=horizon, _P=P, _grid=grid, _dense=gF[:n].copy(), _push=y0, _still=float(stop))
