"""An independent reference simulator for the isolator models of issue 24 (used by the tests and by
examples/make_isolator_records.py); it shares no code with quickrelease.

Models (SI units), one degree of freedom x (the isolation layer's displacement), written from scratch:

- the friction pendulum (curved surface slider): restoring force ``W x / R``, friction ``mu(|v|) W sign(v)``
  with Constantinou's law ``mu(v) = mu_fast - (mu_fast - mu_slow) exp(-a |v|)``; it sticks at a reversal
  where ``|W x / R| <= mu_slow W``;
- Bouc-Wen bearings (lead-rubber, high-damping rubber): force ``Kd x + Qd z`` with
  ``dy z' = v (1 - |z|^n (beta sign(v z) + gamma))``, beta = gamma = 1/2, i.e. ``dy z' = v (1 - |z|^n)`` while
  ``v z > 0`` and ``dy z' = v`` while ``v z < 0``; Coulomb sliders ``F_s`` in parallel; it sticks at a
  reversal where ``|Kd x + Qd z| <= F_s``;
- the linear and bilinear (elastic-perfectly-plastic element ``z``, stiffness ``k1 - k2``, yield force
  ``F_y (1 - k2 / k1)``) isolation with Coulomb sliders;

each with a damper ``C |v|^alpha sign(v)`` (alpha = 1: viscous). scipy's solve_ivp (DOP853, rtol 1e-12) integrates
each piece of constant sliding direction and constant law of z; the pieces end at events located by
solve_ivp: the reversal (v = 0, with its direction), the Bouc-Wen z = 0 crossing (where sign(v z) switches),
the bilinear element's yield. Three more states integrate the dissipated powers (friction ``F |v|``, damper
``C |v|^(alpha + 1)``, hysteresis: ``Qd |z|^n z v`` on the Bouc-Wen loading law, ``z v`` while the plastic
element yields), so that kinetic + stored + dissipated = the energy stored at the release is a check of the
integration itself.

The release starts from the pushed state, at rest: the layer pushed monotonically from x = 0 (z = 0) to d0;
for Bouc-Wen z0 solves ``dz/dx = (1 - |z|^n) / dy`` from 0 to d0 (integrated here, closed form for n = 1:
``1 - exp(-d0 / dy)``). It does not move at all where the static friction holds the pushed force.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

GRAVITY = 9.80665  # m/s^2
RTOL = 1e-12
MAX_PIECES = 100_000


@dataclass(frozen=True)
class System:
    """One isolation system: ``kind`` in pendulum, boucwen, bilinear, linear, and its coefficients (SI)."""

    kind: str
    mass: float
    params: dict = field(default_factory=dict)
    damping: float = 0.0  # C [N (s/m)^alpha]
    exponent: float = 1.0  # alpha [-]

    # -- the forces ------------------------------------------------------------------------------------------
    def spring(self, x, z):
        """The isolators' force without sliders and damper [N]."""
        p = self.params
        if self.kind == "pendulum":
            return self.mass * GRAVITY * x / p["radius"]
        if self.kind == "boucwen":
            return p["Kd"] * x + p["Qd"] * z
        if self.kind == "bilinear":
            return p["k2"] * x + z
        return p["k"] * x

    def friction(self, speed):
        """The sliders' kinetic friction force at speed |v| [N] (>= 0)."""
        p = self.params
        if self.kind == "pendulum":
            W = self.mass * GRAVITY
            return W * (p["mu_fast"] - (p["mu_fast"] - p["mu_slow"]) * np.exp(-p["rate"] * speed))
        return p["Fs"] + 0.0 * speed

    @property
    def static_friction(self) -> float:
        """The friction force that holds the layer at rest [N]."""
        if self.kind == "pendulum":
            return self.params["mu_slow"] * self.mass * GRAVITY
        return self.params["Fs"]

    def stored(self, x, z):
        """The elastic energy [J]: W x^2 / (2 R); Kd x^2 / 2 + Qd dy z^2 / 2; k2 x^2 / 2 + z^2 / (2 (k1 - k2))."""
        p = self.params
        if self.kind == "pendulum":
            return 0.5 * self.mass * GRAVITY * x**2 / p["radius"]
        if self.kind == "boucwen":
            return 0.5 * p["Kd"] * x**2 + 0.5 * p["Qd"] * p["dy"] * z**2
        if self.kind == "bilinear":
            return 0.5 * p["k2"] * x**2 + 0.5 * z**2 / (p["k1"] - p["k2"])
        return 0.5 * p["k"] * x**2

    def pushed_z(self, d0: float) -> float:
        """The internal variable after the monotonic push from 0 to d0 [m]: z0 (0 without one)."""
        p = self.params
        if self.kind == "bilinear":
            return math.copysign(min(abs(d0) * (p["k1"] - p["k2"]), p["fp"]), d0)
        if self.kind == "boucwen":
            return bouc_wen_push(d0, p["dy"], p["n"])
        return 0.0


def bouc_wen_push(d0: float, dy: float, n: float) -> float:
    """z after the monotonic push from x = 0, z = 0 to d0: dz/dx = (1 - |z|^n) / dy, integrated (solve_ivp)."""
    s = math.copysign(1.0, d0)
    sol = solve_ivp(lambda _, z: [(1.0 - abs(z[0]) ** n) / dy], (0.0, abs(d0)), [0.0], method="DOP853",
                    rtol=1e-13, atol=1e-16)
    return s * float(min(sol.y[0, -1], 1.0))


def pendulum(mass, radius, friction_slow, friction_fast=None, rate=0.0, damping=0.0, damping_exponent=1.0):
    """The friction pendulum (api24.md's Pendulum)."""
    fast = friction_slow if friction_fast is None else friction_fast
    return System("pendulum", mass, {"radius": radius, "mu_slow": friction_slow, "mu_fast": fast, "rate": rate},
                  damping, damping_exponent)


def boucwen(mass, post_yield_stiffness, characteristic_strength, yield_displacement, shape=1.0, damping=0.0,
            damping_exponent=1.0, friction=0.0):
    """Bouc-Wen bearings with sliders (api24.md's BoucWen)."""
    return System("boucwen", mass, {"Kd": post_yield_stiffness, "Qd": characteristic_strength,
                                    "dy": yield_displacement, "n": shape, "Fs": friction},
                  damping, damping_exponent)


def bilinear(mass, k1, k2, yield_force, damping=0.0, damping_exponent=1.0, friction=0.0):
    """Bilinear bearings (k1, k2, F_y at d_y = F_y / k1) with sliders."""
    return System("bilinear", mass, {"k1": k1, "k2": k2, "fp": yield_force * (1.0 - k2 / k1), "Fs": friction},
                  damping, damping_exponent)


def linear(mass, stiffness, damping=0.0, damping_exponent=1.0, friction=0.0):
    """Linear bearings with sliders."""
    return System("linear", mass, {"k": stiffness, "Fs": friction}, damping, damping_exponent)


@dataclass(frozen=True)
class Motion:
    """The reference free vibration sampled at ``t`` (SI)."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    z: np.ndarray
    friction: np.ndarray
    """Work of the sliders' friction so far [J]."""
    viscous: np.ndarray
    """Work of the damper so far [J]."""
    hysteretic: np.ndarray
    """Energy dissipated by the hysteresis so far [J]."""
    kinetic: np.ndarray
    stored: np.ndarray
    initial: float
    reversal_times: np.ndarray
    """The release (0) and every reversal, the final stick included [s]."""
    turning_points: np.ndarray
    """d0 and x at each reversal [m]."""
    stop_time: float
    """When it sticks for good [s]; inf if it still moves at the horizon."""
    pieces: int


def _regime(system: System, s: float, z: float) -> str:
    """The law of z on a piece of direction s starting at z."""
    if system.kind == "boucwen":
        return "loading" if s * z >= 0.0 else "unloading"
    if system.kind == "bilinear":
        return "yielding" if s * z >= system.params["fp"] * (1.0 - 1e-13) else "elastic"
    return "none"


def simulate(system: System, d0: float, t_out, t_end: float | None = None) -> Motion:
    """The free vibration from d0 [m] at rest, sampled at t_out [s] (before 0: at rest at d0).

    Follows the motion until it sticks for good, or to t_end (default: the last of t_out; a pendulum whose
    friction grows steeply with the speed may creep towards its rest for ever, never reversing). The samples
    take the value after an instant where the acceleration jumps.
    """
    t_out = np.asarray(t_out, dtype=float)
    m, C, alpha, p = system.mass, system.damping, system.exponent, system.params
    horizon = float(t_end) if t_end is not None else float(t_out.max())
    z0 = system.pushed_z(d0)
    initial = float(system.stored(d0, z0))
    rows = np.full((6,) + t_out.shape, np.nan)  # x, v, z, friction, viscous, hysteretic
    acc = np.full(t_out.shape, np.nan)
    rows[:, t_out < 0] = np.array([[d0], [0.0], [z0], [0.0], [0.0], [0.0]])
    acc[t_out < 0] = 0.0
    reversals, turning = [0.0], [d0]
    t, y = 0.0, np.array([d0, 0.0, z0, 0.0, 0.0, 0.0])
    R0 = system.spring(d0, z0)
    stop = math.inf
    scale = np.array([abs(d0), abs(d0), 1.0 if system.kind == "boucwen" else max(abs(z0), 1.0), initial, initial,
                      initial])
    if abs(R0) <= system.static_friction:
        stop = 0.0
        rows[:, t_out >= 0] = y[:, None]
        acc[t_out >= 0] = 0.0
    s = -math.copysign(1.0, R0)
    regime = _regime(system, s, z0)
    pieces = 0
    while stop == math.inf and t < horizon:
        pieces += 1
        if pieces > MAX_PIECES:
            raise RuntimeError("too many pieces")

        def zrate(v, z, regime=regime):
            if regime == "loading":
                return v * (1.0 - np.abs(z) ** p["n"]) / p["dy"]
            if regime == "unloading":
                return v / p["dy"]
            if regime == "elastic":
                return (p["k1"] - p["k2"]) * v
            return 0.0 * v

        def accel(x, v, z, s=s):
            return -(system.spring(x, z) + s * system.friction(np.abs(v)) + s * C * np.abs(v) ** alpha) / m

        def rhs(_, q, regime=regime):
            x, v, z = q[0], q[1], q[2]
            speed = abs(v)
            hyst = 0.0
            if regime == "loading":
                hyst = p["Qd"] * abs(z) ** p["n"] * z * v
            elif regime == "yielding":
                hyst = z * v
            return [v, accel(x, v, z), zrate(v, z), system.friction(speed) * speed, C * speed ** (alpha + 1.0), hyst]

        def reversal(_, q):
            return q[1]

        reversal.terminal, reversal.direction = True, -s
        events = [reversal]
        if regime == "unloading":
            def crossing(_, q):
                return q[2]

            crossing.terminal, crossing.direction = True, s
            events.append(crossing)
        elif regime == "elastic":
            def yields(_, q, s=s):
                return s * q[2] - p["fp"]

            yields.terminal, yields.direction = True, 1
            events.append(yields)
        sol = solve_ivp(rhs, (t, horizon), y, method="DOP853", rtol=RTOL, atol=1e-15 * scale, events=events,
                        dense_output=True)
        if sol.status < 0:
            raise RuntimeError(sol.message)
        t1 = float(sol.t[-1])
        seg = (t_out >= t) & (t_out <= t1)
        if seg.any():
            q = sol.sol(t_out[seg])
            rows[:, seg] = q
            acc[seg] = accel(q[0], q[1], q[2])
        t, y = t1, sol.y[:, -1].copy()
        if sol.status != 1:  # reached the horizon
            break
        if sol.t_events[0].size:  # a reversal: stick for good or turn
            y[1] = 0.0
            reversals.append(t)
            turning.append(float(y[0]))
            R = system.spring(y[0], y[2])
            if abs(R) <= system.static_friction:
                stop = t
                after = t_out >= t
                rows[:, after] = y[:, None]
                acc[after] = 0.0
                break
            s = -math.copysign(1.0, R)
            regime = _regime(system, s, y[2])
        elif regime == "unloading":  # z = 0: v z changes sign, the loading law from here
            y[2] = 0.0
            regime = "loading"
        else:  # the plastic element yields
            y[2] = s * p["fp"]
            regime = "yielding"
    if stop < math.inf:
        rows[:, t_out > stop] = y[:, None]
    x, v, z = rows[0], rows[1], rows[2]
    return Motion(t=t_out, x=x, v=v, a=acc, z=z, friction=rows[3], viscous=rows[4], hysteretic=rows[5],
                  kinetic=0.5 * m * v**2, stored=system.stored(x, z), initial=initial,
                  reversal_times=np.array(reversals), turning_points=np.array(turning), stop_time=stop,
                  pieces=pieces)
