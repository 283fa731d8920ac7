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


# -- the same layer under a flexible superstructure (2-DOF) -----------------------------------------------------

@dataclass(frozen=True)
class Motion2:
    """The reference 2-DOF free vibration sampled at ``t`` (SI): base (x, v, a), roof (xs, vs, as_), the layer's
    z and works, the storey damper's work, the energies."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    xs: np.ndarray
    vs: np.ndarray
    as_: np.ndarray
    z: np.ndarray
    friction: np.ndarray
    viscous: np.ndarray
    """Work of the layer's damper so far [J]."""
    hysteretic: np.ndarray
    storey_viscous: np.ndarray
    """Work of the storey's damper so far [J]."""
    kinetic: np.ndarray
    stored: np.ndarray
    """The layer's stored energy and the storey spring's [J]."""
    initial: float
    reversal_times: np.ndarray
    """The release (0) and every instant where the sliding base's velocity vanishes (reversals, sticks) [s]."""
    stick_times: np.ndarray
    slip_times: np.ndarray
    """Where the storey's force breaks the held base away [s]."""


def simulate_2dof(system: System, superstructure_mass: float, storey_stiffness: float, storey_damping: float,
                  d0: float, t_out, t_end: float | None = None, creep_speed: float = 0.0) -> Motion2:
    """The free vibration of the layer ``system`` (its mass the whole building's m: the weight on the sliders; the
    base's mass m_b = m - m_s) under a roof mass m_s on the storey (k_s [N/m], c_s [N s/m]), from base and roof at
    rest at d0 [m] (the storey undeformed), sampled at t_out [s], followed to t_end (default the last of t_out).

    Sliding (direction s): ``m_b x_b'' = -(spring + s friction(|v|) + s C |v|^alpha) + k_s u + c_s u'``; stuck
    (the base at rest): ``|G| <= static friction`` with ``G = spring - k_s u - c_s u'``, the roof on the fixed base.
    solve_ivp events: the reversal (v_b = 0; then stuck where |G| <= static friction, else it turns, s = -sign(G)),
    z's zero crossing and the plastic yield as :func:`simulate`, and while stuck G reaching +- the static friction
    (the re-slip, s = -sign(G)). The stuck phase is followed to the horizon unless it slips (no "held for good"
    shortcut). Steps at most 1/40 of the fastest period, so that no event is stepped over.

    ``creep_speed`` [m/s] (a damper of alpha < 1 only): the base is held while the damper alone would balance the
    excess of |G| over the static friction at below this speed, ``|G| <= static + C creep_speed^alpha`` (the damper's
    slope is unbounded at rest: a slide that starts from an excess of 0, at a re-slip or a turn where the roof drives
    the base, stops and starts again without end on the solver's rounding). The motion it neglects is a creep below
    creep_speed; the instants of the sticks and slips move with it, the displacements by less than creep_speed times
    the shift."""
    t_out = np.asarray(t_out, dtype=float)
    m, C, alpha, p = system.mass, system.damping, system.exponent, system.params
    ms, ks, cs = superstructure_mass, storey_stiffness, storey_damping
    mb = m - ms
    horizon = float(t_end) if t_end is not None else float(t_out.max())
    z0 = system.pushed_z(d0)
    initial = float(system.stored(d0, z0))
    rows = np.full((9,) + t_out.shape, np.nan)  # x, v, z, friction, viscous, hysteretic, xs, vs, storey viscous
    acc = np.full((2,) + t_out.shape, np.nan)
    rows[:, t_out < 0] = np.array([[d0], [0.0], [z0], [0.0], [0.0], [0.0], [d0], [0.0], [0.0]])
    acc[:, t_out < 0] = 0.0
    k1 = {"pendulum": m * GRAVITY / p.get("radius", 1.0), "boucwen": p.get("Kd", 0.0) + p.get("Qd", 0.0) / p.get(
        "dy", 1.0), "bilinear": p.get("k1", 0.0), "linear": p.get("k", 0.0)}[system.kind]
    fastest = math.sqrt((k1 + ks) / mb + ks / ms)
    max_step = 2.0 * math.pi / fastest / 40.0
    static = system.static_friction
    if alpha < 1.0 and C > 0.0 and creep_speed > 0.0:
        static += C * creep_speed ** alpha
    reversals, sticks, slips = [0.0], [], []
    t, y = 0.0, np.array([d0, 0.0, z0, 0.0, 0.0, 0.0, d0, 0.0, 0.0])

    def holding(q):
        return system.spring(q[0], q[2]) - ks * (q[6] - q[0]) - cs * (q[7] - q[1])

    G0 = holding(y)
    stuck = abs(G0) <= static
    s = -math.copysign(1.0, G0)
    regime = _regime(system, s, z0)
    pieces = 0
    while t < horizon:
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

        def accels(q, s=s, stuck=stuck):
            x, v, z, xs, vs = q[0], q[1], q[2], q[6], q[7]
            storey = ks * (xs - x) + cs * (vs - v)
            if stuck:
                return 0.0 * x, -storey / ms
            layer = system.spring(x, z) + s * system.friction(np.abs(v)) + s * C * np.abs(v) ** alpha
            return (-layer + storey) / mb, -storey / ms

        def rhs(_, q, regime=regime, stuck=stuck):
            v, z = q[1], q[2]
            ab, as_ = accels(q)
            du = q[7] - q[1]
            if stuck:
                return [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, q[7], as_, cs * du * du]
            speed = abs(v)
            hyst = 0.0
            if regime == "loading":
                hyst = p["Qd"] * abs(z) ** p["n"] * z * v
            elif regime == "yielding":
                hyst = z * v
            return [v, ab, zrate(v, z), system.friction(speed) * speed, C * speed ** (alpha + 1.0), hyst, q[7], as_,
                    cs * du * du]

        events = []
        if stuck:
            def up(_, q):
                return holding(q) - static

            def down(_, q):
                return holding(q) + static

            up.terminal, up.direction = True, 1
            down.terminal, down.direction = True, -1
            events = [up, down]
        else:
            def reversal(_, q):
                return q[1]

            reversal.terminal, reversal.direction = True, -s
            events.append(reversal)
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
        scale = np.array([abs(d0), abs(d0), 1.0, initial, initial, initial, abs(d0), abs(d0), initial])
        sol = solve_ivp(rhs, (t, horizon), y, method="DOP853", rtol=RTOL, atol=1e-15 * scale, events=events,
                        dense_output=True, max_step=max_step)
        if sol.status < 0:
            raise RuntimeError(sol.message)
        t1 = float(sol.t[-1])
        seg = (t_out >= t) & (t_out <= t1)
        if seg.any():
            q = sol.sol(t_out[seg])
            if stuck:
                q[0], q[1], q[2] = y[0], 0.0, y[2]
            rows[:, seg] = q
            ab, as_ = accels(q)
            acc[0, seg], acc[1, seg] = ab, as_
        t, y = t1, sol.y[:, -1].copy()
        if sol.status != 1:  # reached the horizon
            break
        if stuck:  # G reached +- the static friction: the base slides, along -G
            slips.append(t)
            stuck = False
            s = -math.copysign(1.0, holding(y))
            regime = _regime(system, s, y[2])
        elif sol.t_events[0].size:  # a reversal: stick, or turn
            y[1] = 0.0
            reversals.append(t)
            G = holding(y)
            if abs(G) <= static:
                stuck = True
                sticks.append(t)
            else:
                s = -math.copysign(1.0, G)
                regime = _regime(system, s, y[2])
        elif regime == "unloading":
            y[2] = 0.0
            regime = "loading"
        else:
            y[2] = s * p["fp"]
            regime = "yielding"
    x, v, z, xs, vs = rows[0], rows[1], rows[2], rows[6], rows[7]
    return Motion2(t=t_out, x=x, v=v, a=acc[0], xs=xs, vs=vs, as_=acc[1], z=z, friction=rows[3], viscous=rows[4],
                   hysteretic=rows[5], storey_viscous=rows[8], kinetic=0.5 * mb * v**2 + 0.5 * ms * vs**2,
                   stored=system.stored(x, z) + 0.5 * ks * (xs - x) ** 2, initial=initial,
                   reversal_times=np.array(reversals), stick_times=np.array(sticks), slip_times=np.array(slips))
