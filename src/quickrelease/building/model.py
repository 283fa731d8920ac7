"""The isolated building's free vibration after the release (SI units).

The superstructure is rigid on its isolation layer: one degree of freedom, the displacement x(t) of the
isolation layer [m], positive in the push direction. The layer's restoring force is

- ``linear``: ``R = k x`` (rubber bearings as a linear spring, period ``T = 2 pi sqrt(m / k)``);
- ``bilinear``: the rubber bearings as a bilinear hysteretic spring, initial stiffness ``k1``, post-yield
  stiffness ``k2`` (``0 < k2 < k1``), yield force ``F_y`` (reached at ``d_y = F_y / k1``). It is written as
  a linear spring ``k2 x`` in parallel with an elastic-perfectly-plastic element ``z`` of stiffness
  ``k1 - k2`` and yield force ``F_y (1 - k2 / k1)``: ``R = k2 x + z``;

in parallel with a viscous damper ``c x_dot`` and Coulomb sliders ``F_s sign(x_dot)`` (the hybrid isolation
of the Sicilian tests: rubber bearings and sliders). The equation of motion, while the layer slides,

    m x_ddot + c x_dot + R(x, z) + F_s sign(x_dot) = 0,

is linear with constant coefficients between events: a reversal (x_dot = 0, where the sliders either
stick for good, ``|R| <= F_s``, or the motion turns and the plastic element unloads) and a yield (the
plastic element reaches its yield force). Each piece is solved in closed form (under-, critically or
over-damped) and each event is located on the closed form: reversals analytically, yields by a bracketed
root to machine precision. No smoothed sign function, no time step.

The release starts from the pushed state: the jack has pushed the layer monotonically from 0 to ``d0``
(so ``z`` is on its loading branch) and the building is at rest when the fuse breaks.
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
from scipy.optimize import brentq

from .._validate import finite_nonnegative, finite_positive
from ..errors import ParameterError
from . import _ode
from .hysteretic import (
    BoucWen,
    HystereticVibration,
    Pendulum,
    checked_d0,
    damping_exponent,
    hysteretic_vibration,
    real_number,
)

__all__ = ["Isolation", "FreeVibration", "free_vibration", "pushed_state", "MODELS", "TwoDOF", "TwoDOFVibration",
           "free_vibration_2dof", "RECORD_CHANNELS"]

#: Restoring-force models of the isolation layer.
MODELS = ("linear", "bilinear")

#: The channels of the building's record: name -> (quantity kind, SI unit, description). The one table of
#: them: the keys of :meth:`FreeVibration.channels` and :meth:`TwoDOFVibration.channels`; the record reader
#: (:data:`quickrelease.io.building_case.BUILDING_CHANNELS`), the fit
#: (:data:`quickrelease.building.isolation_fit.CHANNEL_KINDS`) and synth
#: (:data:`quickrelease.studies.synth.BUILDING_NOISE`, per quantity kind) derive theirs from it.
RECORD_CHANNELS: dict[str, tuple[str, str, str]] = {
    "x": ("length", "m", "displacement of the isolation layer (e.g. an LVDT)"),
    "v": ("velocity", "m/s", "velocity of the isolation layer"),
    "a": ("acceleration", "m/s^2", "acceleration of the isolation layer (base)"),
    "x_roof": ("length", "m", "displacement of the top of the superstructure"),
    "v_roof": ("velocity", "m/s", "velocity of the top of the superstructure"),
    "a_roof": ("acceleration", "m/s^2", "acceleration of the top of the superstructure"),
}

#: Most pieces (half-cycles and yield events) one free vibration may have.
MAX_PIECES = 1_000_000


@dataclass(frozen=True)
class Isolation:
    """The isolation layer under a rigid superstructure (SI units).

    Build one with :meth:`linear` or :meth:`bilinear`; the fields are the model's coefficients.
    """

    mass: float
    """Mass carried by the isolation layer, m [kg]."""
    stiffness: float
    """Stiffness k [N/m] (linear), or the initial stiffness k1 [N/m] (bilinear)."""
    damping: float = 0.0
    """Viscous damping coefficient c [N s/m]."""
    friction: float = 0.0
    """Coulomb friction force of the sliders, F_s [N] (static = kinetic)."""
    post_yield_stiffness: float | None = None
    """Post-yield stiffness k2 [N/m] of the bilinear model, in (0, k1); None for the linear model."""
    yield_force: float | None = None
    """Yield force F_y [N] of the bilinear model (at d_y = F_y / k1); None for the linear model."""
    damping_exponent: float = 1.0
    """The damper's exponent alpha [-]: 1 is the viscous damper ``c x_dot``; otherwise a fluid viscous damper's
    power law ``C |x_dot|^alpha sign(x_dot)``, ``damping`` being C [N (s/m)^alpha]."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "damping_exponent", damping_exponent(self.damping_exponent))
        finite_positive("mass", self.mass, "kg")
        finite_positive("stiffness", self.stiffness, "N/m")
        finite_nonnegative("damping", self.damping, "N s/m")
        finite_nonnegative("friction", self.friction, "N")
        if (self.post_yield_stiffness is None) != (self.yield_force is None):
            raise ParameterError("post_yield_stiffness/yield_force", "one of the two",
                                 "both (bilinear) or neither (linear)")
        if self.post_yield_stiffness is not None:
            k2 = float(self.post_yield_stiffness)
            if not (math.isfinite(k2) and 0.0 < k2 < self.stiffness):
                raise ParameterError("post_yield_stiffness", k2, f"(0, k1) = (0, {self.stiffness:.6g}) N/m", "N/m")
            finite_positive("yield_force", self.yield_force, "N")

    @classmethod
    def linear(cls, mass: float, period: float, damping_ratio: float = 0.0, friction: float = 0.0) -> Isolation:
        """Linear isolation: period T [s], damping ratio zeta [-] in [0, 1), slider friction F_s [N]."""
        mass = finite_positive("mass", mass, "kg")
        period = finite_positive("period", period, "s")
        zeta = _damping_ratio(damping_ratio)
        k = mass * (2.0 * math.pi / period) ** 2
        return cls(mass=mass, stiffness=k, damping=2.0 * zeta * math.sqrt(k * mass), friction=friction)

    @classmethod
    def bilinear(cls, mass: float, k1: float, k2: float, yield_force: float, damping_ratio: float = 0.0,
                 friction: float = 0.0) -> Isolation:
        """Bilinear isolation: k1, k2 [N/m], F_y [N]; zeta [-] refers to the initial stiffness,
        ``c = 2 zeta sqrt(k1 m)``; slider friction F_s [N]."""
        mass = finite_positive("mass", mass, "kg")
        k1 = finite_positive("k1", k1, "N/m")
        zeta = _damping_ratio(damping_ratio)
        return cls(mass=mass, stiffness=k1, damping=2.0 * zeta * math.sqrt(k1 * mass), friction=friction,
                   post_yield_stiffness=k2, yield_force=yield_force)

    @property
    def model(self) -> str:
        """``"linear"`` or ``"bilinear"``."""
        return "linear" if self.post_yield_stiffness is None else "bilinear"

    @property
    def period(self) -> float:
        """Period of the (initial) stiffness, ``2 pi sqrt(m / k1)`` [s]."""
        return 2.0 * math.pi * math.sqrt(self.mass / self.stiffness)

    @property
    def damping_ratio(self) -> float:
        """Viscous damping ratio referred to the (initial) stiffness, ``c / (2 sqrt(k1 m))`` [-] (nan with a
        power-law damper)."""
        if self.damping_exponent != 1.0:
            return math.nan
        return self.damping / (2.0 * math.sqrt(self.stiffness * self.mass))

    def vector(self) -> np.ndarray:
        """The parameter vector of the event-located integrator (:mod:`quickrelease.building._ode`), which
        solves it with a power-law damper."""
        P = np.zeros(_ode.NP)
        P[_ode.M], P[_ode.K] = self.mass, self.k2
        if self.model == "bilinear":
            P[_ode.HKIND], P[_ode.KP], P[_ode.FP] = _ode.H_PLASTIC, self.stiffness - self.k2, self.plastic_yield
        P[_ode.FSLOW] = P[_ode.FFAST] = self.friction
        P[_ode.C], P[_ode.ALPHA] = self.damping, self.damping_exponent
        return P

    @property
    def k2(self) -> float:
        """Stiffness of the spring in parallel with the plastic element [N/m] (k for the linear model)."""
        return self.stiffness if self.post_yield_stiffness is None else float(self.post_yield_stiffness)

    @property
    def plastic_yield(self) -> float:
        """Yield force of the elastic-plastic element, ``F_y (1 - k2 / k1)`` [N]; inf for the linear model."""
        if self.yield_force is None:
            return math.inf
        return float(self.yield_force) * (1.0 - self.k2 / self.stiffness)

    def restoring_force(self, x: float, z: float) -> float:
        """R = k2 x + z [N] (k x for the linear model, where z = 0)."""
        return self.k2 * x + z

    def summary(self) -> dict[str, Any]:
        out = {"model": self.model, "mass_kg": self.mass, "period_s": self.period,
               "damping_ratio": self.damping_ratio, "damping_N_s_m": self.damping, "friction_N": self.friction}
        if self.model == "bilinear":
            out.update(k1_N_m=self.stiffness, k2_N_m=self.k2, Fy_N=float(self.yield_force))
        else:
            out["stiffness_N_m"] = self.stiffness
        if self.damping_exponent != 1.0:
            out.update(damping_coefficient=self.damping, damping_exponent=self.damping_exponent)
            del out["damping_ratio"], out["damping_N_s_m"]
        return out


def _damping_ratio(value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and 0.0 <= value < 1.0):
        raise ParameterError("damping_ratio", value, "[0, 1)")
    return value


def pushed_state(isolation: Isolation | Pendulum | BoucWen, d0: float) -> tuple[float, float, float]:
    """The state at the release after a monotonic push from 0 to d0 [m], at rest.

    Returns ``(z0, R0, P)``: the plastic element's force z0 [N] (0 for the linear model; the Bouc-Wen
    element's z0 [-]), the restoring force R0 = k2 d0 + z0 [N] (W d0 / R for the pendulum, Kd d0 + Qd z0
    for Bouc-Wen) and the push force that held it, P = R0 + F_s sign(d0) [N] (F_s = mu_slow W for the
    pendulum).
    """
    d0 = real_number("d0", d0, "finite and non-zero", "m", test=lambda v: math.isfinite(v) and v != 0.0)
    if isinstance(isolation, Pendulum | BoucWen):  # W d0 / R; Kd d0 + Qd z0 on the monotonic push curve
        z0 = isolation.pushed(d0)
        R0 = isolation.k2 * d0 + (isolation.characteristic_strength * z0 if isinstance(isolation, BoucWen) else 0.0)
        return z0, R0, R0 + math.copysign(isolation.friction, d0)
    if isolation.model == "linear":
        z0 = 0.0
    else:
        z0 = math.copysign(min(abs(d0) * (isolation.stiffness - isolation.k2), isolation.plastic_yield), d0)
    R0 = isolation.k2 * d0 + z0
    return z0, R0, R0 + math.copysign(isolation.friction, d0)


# -- one piece: m y'' + c y' + k y = 0 about the shifted equilibrium ------------------------------------------

def _ec_es(a: float, q: float, tau):
    """``exp(-a tau) C(tau)`` and ``exp(-a tau) S(tau)`` with C = cos(w tau), S = sin(w tau) / w for
    ``q = w^2 > 0``, cosh and sinh / w for ``q = -w^2 < 0``, and 1, tau for q = 0: the fundamental solutions
    of ``y'' + 2 a y' + b y = 0`` with ``q = b - a^2`` (written without overflow for large tau)."""
    tau = np.asarray(tau, dtype=float)
    if q > 0.0:
        w = math.sqrt(q)
        e = np.exp(-a * tau)
        return e * np.cos(w * tau), e * np.sin(w * tau) / w
    if q < 0.0:
        w = math.sqrt(-q)
        slow = np.exp((w - a) * tau)  # w < a: both exponents are negative
        fast = np.exp(-(w + a) * tau)
        return 0.5 * (slow + fast), -slow * np.expm1(-2.0 * w * tau) / (2.0 * w)
    e = np.exp(-a * tau)
    return e, e * tau


def _ec_es_at(a: float, q: float, tau: float) -> tuple[float, float]:
    """:func:`_ec_es` at one time, as Python floats: the same numpy functions (exp, cos, sin, expm1: numpy's, not
    libm's, so the same bits) and the same IEEE arithmetic, without the 0-d arrays (a hot path of fits)."""
    if q > 0.0:
        w = math.sqrt(q)
        e = float(np.exp(-a * tau))
        return e * float(np.cos(w * tau)), e * float(np.sin(w * tau)) / w
    if q < 0.0:
        w = math.sqrt(-q)
        slow = float(np.exp((w - a) * tau))
        fast = float(np.exp(-(w + a) * tau))
        return 0.5 * (slow + fast), -slow * float(np.expm1(-2.0 * w * tau)) / (2.0 * w)
    e = float(np.exp(-a * tau))
    return e, e * tau


@dataclass(frozen=True)
class _Piece:
    t0: float
    x0: float
    v0: float
    z0: float
    direction: float
    """Sign of the velocity over the piece (+1 or -1)."""
    yielding: bool
    k: float
    """Stiffness of the piece: k1 elastic, k2 yielding [N/m]."""
    x_eq: float
    """The piece's equilibrium, where k x + (R - k x) + F_s direction = 0 [m]."""
    a: float
    b: float
    q: float
    t1: float = math.inf
    """End of the piece [s]."""
    end: str = ""
    """What ended it: "reversal", "yield", "stick" or "" (the horizon)."""

    def state(self, t):
        """x, v at times t of the piece."""
        tau = np.asarray(t, dtype=float) - self.t0
        y0 = self.x0 - self.x_eq
        ec, es = _ec_es(self.a, self.q, tau)
        x = self.x_eq + ec * y0 + es * (self.v0 + self.a * y0)
        v = ec * self.v0 - es * (self.a * self.v0 + self.b * y0)
        return x, v

    def at(self, t: float) -> tuple[float, float]:
        """x, v at one time t (a float) as floats: :meth:`state`'s arithmetic, without numpy's 0-d arrays."""
        tau = float(t) - self.t0
        y0 = self.x0 - self.x_eq
        ec, es = _ec_es_at(self.a, self.q, tau)
        return self.x_eq + ec * y0 + es * (self.v0 + self.a * y0), ec * self.v0 - es * (self.a * self.v0 + self.b * y0)

    def first_reversal(self) -> float:
        """The first tau > 0 where the velocity vanishes (inf if it never does)."""
        p = self.v0
        r = self.a * self.v0 + self.b * (self.x0 - self.x_eq)
        if self.q > 0.0:
            w = math.sqrt(self.q)
            theta = math.fmod(math.atan2(p * w, r), math.pi)
            if theta <= 0.0:
                theta += math.pi
            return theta / w
        if r == 0.0:
            return math.inf
        ratio = p / r
        if self.q < 0.0:
            w = math.sqrt(-self.q)
            return math.atanh(ratio * w) / w if 0.0 < ratio * w < 1.0 else math.inf
        return ratio if ratio > 0.0 else math.inf


def _piece(iso: Isolation, t0: float, x0: float, v0: float, z0: float, direction: float) -> _Piece:
    k1, k2, fp = iso.stiffness, iso.k2, iso.plastic_yield
    yielding = iso.model == "bilinear" and direction * z0 >= fp
    if yielding:  # R = k2 x + direction fp
        k, offset = k2, direction * fp
    else:  # R = k2 x + z0 + (k1 - k2)(x - x0) = k1 x + z0 - (k1 - k2) x0
        k, offset = k1, z0 - (k1 - k2) * x0
    x_eq = -(offset + iso.friction * direction) / k
    a = iso.damping / (2.0 * iso.mass)
    b = k / iso.mass
    out = object.__new__(_Piece)  # the frozen dataclass's __init__ without its per-field setattr (a hot path of fits)
    out.__dict__.update(t0=t0, x0=x0, v0=v0, z0=z0, direction=direction, yielding=yielding, k=k, x_eq=x_eq, a=a, b=b,
                        q=b - a * a, t1=math.inf, end="")
    return out


def _plastic_force(iso: Isolation, piece: _Piece, x):
    """z along a piece: constant while yielding, else z0 + (k1 - k2)(x - x0)."""
    if piece.yielding or iso.model == "linear":
        return np.full(np.shape(x), piece.z0) if np.ndim(x) else piece.z0
    return piece.z0 + (iso.stiffness - iso.k2) * (np.asarray(x) - piece.x0)


@dataclass(frozen=True, eq=False)
class FreeVibration:
    """The free vibration of the isolated building from the pushed state (SI units).

    Exact piecewise closed form; evaluate it anywhere with :meth:`state`. Pieces end at reversals (the
    velocity vanishes), yields (the bilinear spring reaches its yield force) or the final stick.
    """

    isolation: Isolation
    d0: float
    """Pushed displacement at the release [m]."""
    pieces: tuple[_Piece, ...] = field(repr=False)
    stop_time: float
    """When the sliders stick for good [s] (inf: still moving at the horizon, or creeping for ever)."""
    horizon: float
    """The time up to which the pieces were followed [s]."""
    rest: tuple[float, float]
    """(x, z) where it sticks (the last piece's end state when it never sticks)."""

    @property
    def reversal_times(self) -> np.ndarray:
        """Times of the turning points, the release instant first [s]."""
        return np.array([0.0] + [p.t1 for p in self.pieces if p.end in ("reversal", "stick")])

    @property
    def turning_points(self) -> np.ndarray:
        """Displacements at the turning points, d0 first [m]: the peaks of the decay."""
        out = [self.d0]
        for p in self.pieces:
            if p.end in ("reversal", "stick"):
                out.append(float(p.state(p.t1)[0]))
        return np.array(out)

    def state(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Displacement x [m], velocity x_dot [m/s] and acceleration x_ddot [m/s^2] at times t [s].

        Before the release (t < 0) the layer is at d0, at rest. At an instant where the acceleration jumps
        (a reversal, the stick) the value after the instant is returned.
        """
        x, v, a, _ = self._evaluate(t)
        return x, v, a

    def channels(self, t) -> dict[str, np.ndarray]:
        """Every channel of the building's record at times t [s] (SI): x, v, a of the isolation layer, and
        x_roof, v_roof, a_roof, equal to them (a rigid superstructure moves with the layer)."""
        x, v, a = self.state(t)
        return {"x": x, "v": v, "a": a, "x_roof": x, "v_roof": v, "a_roof": a}

    def restoring_force(self, t) -> np.ndarray:
        """The isolators' force R = k2 x + z [N] at times t (the spring alone, no damper, no sliders)."""
        x, _, _, z = self._evaluate(t)
        return self.isolation.k2 * x + z

    @cached_property
    def _columns(self) -> tuple[np.ndarray, ...]:
        """The pieces' t0, x0, v0, z0, x_eq, direction and yielding, each as an array (:meth:`_evaluate`'s)."""
        pieces = self.pieces
        return (*(np.array([getattr(p, f) for p in pieces]) for f in ("t0", "x0", "v0", "z0", "x_eq", "direction")),
                np.array([p.yielding for p in pieces]))

    def _evaluate(self, t):
        # One vectorised closed-form evaluation per kind of piece (elastic, yielding: the pieces of a kind
        # share a, b and q), each sample taking its piece's start state by a search on the start times;
        # elementwise the same arithmetic as _Piece.state and _plastic_force.
        iso = self.isolation
        t = np.asarray(t, dtype=float)
        shape = t.shape
        t = t.ravel()
        x = np.full(t.shape, self.d0)
        v = np.zeros(t.shape)
        acc = np.zeros(t.shape)
        z = np.full(t.shape, pushed_state(iso, self.d0)[0])
        pieces = self.pieces
        if pieces:
            t0, x0, v0, z0, x_eq, direction, yielding = self._columns
            index = np.searchsorted(t0, t, side="right") - 1
            moving = index >= 0
            last = pieces[-1]
            if last.end == "stick":  # only the last piece sticks: at rest from its end on
                after = (index == len(pieces) - 1) & (t >= last.t1)
                moving &= ~after
                x[after], z[after] = self.rest
                v[after] = acc[after] = 0.0
            for kind in (False, True):
                of_kind = yielding == kind
                if not of_kind.any():
                    continue
                first = pieces[int(np.argmax(of_kind))]
                where = np.flatnonzero(moving & of_kind[np.maximum(index, 0)])
                if not where.size:
                    continue
                every = where.size == t.size  # every sample on pieces of this kind: no gathers
                i = index if every else index[where]
                x0i, x_eqi, v0i = x0[i], x_eq[i], v0[i]
                y0 = x0i - x_eqi
                ec, es = _ec_es(first.a, first.q, (t if every else t[where]) - t0[i])
                xs = x_eqi + ec * y0 + es * (v0i + first.a * y0)
                vs = ec * v0i - es * (first.a * v0i + first.b * y0)
                if kind or iso.model == "linear":
                    zs = z0[i]
                else:
                    zs = z0[i] + (iso.stiffness - iso.k2) * (xs - x0i)
                accs = -(iso.damping * vs + iso.k2 * xs + zs + iso.friction * direction[i]) / iso.mass
                if every:
                    x, v, z, acc = xs, vs, zs, accs
                else:
                    x[where], v[where], z[where], acc[where] = xs, vs, zs, accs
        return x.reshape(shape), v.reshape(shape), acc.reshape(shape), z.reshape(shape)

    def energies(self, t) -> dict[str, np.ndarray]:
        """The energy balance at times t [J]: kinetic, stored (springs), hysteretic, friction and viscous
        dissipation so far; their sum is the energy stored at the release, ``initial``.

        The dissipations are summed piece by piece: friction F_s |dx| and hysteresis F_y(1 - k2/k1) |dx| over
        the yielding pieces, exactly; the viscous dissipation of a piece is the drop of its own quadratic
        invariant ``m v^2 / 2 + k (x - x_eq)^2 / 2`` (exact for ``m y'' + c y' + k y = 0``).
        """
        iso = self.isolation
        t = np.atleast_1d(np.asarray(t, dtype=float))
        x, v, _, z = self._evaluate(t)
        kinetic = 0.5 * iso.mass * v**2
        stored = 0.5 * iso.k2 * x**2
        if iso.model == "bilinear":
            stored = stored + 0.5 * z**2 / (iso.stiffness - iso.k2)
        friction = np.zeros(t.shape)
        hysteretic = np.zeros(t.shape)
        viscous = np.zeros(t.shape)
        for p in self.pieces:
            if not np.isfinite(p.t0):
                break
            tt = np.clip(t, p.t0, p.t1)
            xs, vs = p.state(tt)
            moved = np.abs(xs - p.x0)
            friction += iso.friction * moved
            if p.yielding:
                hysteretic += iso.plastic_yield * moved
            inv0 = 0.5 * iso.mass * p.v0**2 + 0.5 * p.k * (p.x0 - p.x_eq) ** 2
            viscous += inv0 - (0.5 * iso.mass * vs**2 + 0.5 * p.k * (xs - p.x_eq) ** 2)
        z0 = pushed_state(iso, self.d0)[0]
        initial = 0.5 * iso.k2 * self.d0**2 + (0.5 * z0**2 / (iso.stiffness - iso.k2) if iso.model == "bilinear"
                                                else 0.0)
        return {"kinetic": kinetic, "stored": stored, "hysteretic": hysteretic, "friction": friction,
                "viscous": viscous, "initial": np.full(t.shape, initial)}

    def summary(self) -> dict[str, Any]:
        return _motion_summary(self.isolation, self)


def _motion_summary(building, motion) -> dict[str, Any]:
    """The building's values and its free vibration's: d0, stop time, rest, half-cycles, first peak (SI)."""
    peaks = motion.turning_points
    return {**building.summary(), "d0_m": motion.d0, "stop_time_s": motion.stop_time,
            "rest_displacement_m": motion.rest[0], "half_cycles": int(peaks.size - 1),
            "first_peak_m": float(peaks[1]) if peaks.size > 1 else None}


def _horizon(t_end: float | None, friction: float) -> float:
    """How long to follow a free vibration [s]: ``t_end`` (finite and > 0), or with None until the sliders hold it
    for good (inf), which needs their ``friction`` [N] > 0; ParameterError naming t_end otherwise."""
    if t_end is not None:
        return real_number("t_end", t_end, "(0, inf)", "s", test=lambda v: math.isfinite(v) and v > 0.0)
    if friction == 0.0:
        raise ParameterError("t_end", None, "a finite time in (0, inf) s when the sliders have no friction "
                             "(the motion never ends)")
    return math.inf


def free_vibration(isolation: Isolation | Pendulum | BoucWen, d0: float, t_end: float | None = None, *,
                   coarse: float = 1.0) -> FreeVibration | HystereticVibration:
    """The building's free vibration after the release from the pushed displacement d0 [m], at rest.

    Parameters
    ----------
    isolation : Isolation, Pendulum, BoucWen, TwoDOF or FlexibleBuilding
        The isolation layer (:meth:`Isolation.linear` or :meth:`Isolation.bilinear`, or a hysteretic one); a
        :class:`TwoDOF` building is handed to :func:`free_vibration_2dof`, a
        :class:`~quickrelease.building.flexible.FlexibleBuilding` to its own solver (their results' ``state`` is
        the base's).
    d0 : float
        Displacement of the isolation layer at the release [m] (reached by a monotonic push), within a pendulum's
        radius and storing at most 1e300 J in the layer (:func:`~.hysteretic.checked_d0`).
    t_end : float, optional
        Follow the motion up to this time [s]; by default until the sliders stick for good (which needs
        F_s > 0: without friction the motion never ends, and t_end is required; for the layers without a closed
        form at most :data:`~.hysteretic.MAX_PERIODS` natural periods).
    coarse : float
        Where the layer has no closed form (pendulum, Bouc-Wen, a power-law damper: the integrator of
        :mod:`quickrelease.building._ode`; a FlexibleBuilding: :mod:`quickrelease.building._ode_flexible`), its
        steps this many times longer, in [1, 4] (default 1). The fit's search
        on a thinned record takes 2: half the steps, the state within ~1e-11 m of the default's on the benchmark's
        60 s records (the 8th-order tableau's error falls as the 8th power of the step).

    Returns
    -------
    FreeVibration
    """
    coarse = real_number("coarse", coarse, "[1, 4]", test=lambda v: 1.0 <= v <= 4.0)
    d0 = real_number("d0", d0, "finite and non-zero", "m", test=lambda v: math.isfinite(v) and v != 0.0)
    if isinstance(isolation, TwoDOF):
        return free_vibration_2dof(isolation, d0, t_end)
    flexible = getattr(isolation, "free_vibration", None)  # a FlexibleBuilding (building.flexible) solves itself
    if flexible is not None and not isinstance(isolation, type):
        return flexible(d0, t_end, coarse=coarse)
    if not isinstance(isolation, Isolation | Pendulum | BoucWen):
        raise ParameterError("isolation", type(isolation).__name__,
                             "an Isolation, Pendulum, BoucWen, TwoDOF or FlexibleBuilding")
    d0 = checked_d0(isolation, d0)  # 1e308 m: the closed form's accelerations overflowed too
    if isinstance(isolation, Pendulum) and isolation.constant_friction and isolation.damping_exponent == 1.0:
        # linear + Coulomb exactly, k = W / R, F_s = mu W: its closed form (the result's isolation is that)
        p = isolation
        return free_vibration(Isolation(p.mass, p.stiffness, p.damping, p.friction), d0, t_end)
    if isinstance(isolation, Pendulum | BoucWen) or isolation.damping_exponent != 1.0:
        z0 = pushed_state(isolation, d0)[0] if isinstance(isolation, Isolation) else isolation.pushed(d0)
        P = isolation.vector()
        P[_ode.COARSE] = coarse
        return hysteretic_vibration(isolation, P, z0, d0, t_end)
    iso = isolation
    d0 = float(d0)
    z0, R0, _ = pushed_state(iso, d0)
    horizon = _horizon(t_end, iso.friction)
    pieces: list[_Piece] = []
    t, x, v, z = 0.0, d0, 0.0, z0
    direction = -math.copysign(1.0, R0)
    stop, rest = math.inf, (d0, z0)
    if abs(R0) <= iso.friction:  # the sliders hold it where it was pushed
        return FreeVibration(iso, d0, (), 0.0, horizon, (d0, z0))
    while t < horizon:
        if len(pieces) >= MAX_PIECES:
            raise ParameterError("t_end", horizon, f"a span of at most {MAX_PIECES} half-cycles and yields", "s")
        piece = _piece(iso, t, x, v, z, direction)
        tau_rev = piece.first_reversal()
        tau_end, end = tau_rev, "reversal"
        if not piece.yielding and iso.model == "bilinear":
            x_yield = piece.x0 + (direction * iso.plastic_yield - piece.z0) / (iso.stiffness - iso.k2)
            tau_yield = _time_to_reach(piece, x_yield, tau_rev)
            if tau_yield is not None:
                tau_end, end = tau_yield, "yield"
        t1 = t + tau_end
        if t1 >= horizon or not math.isfinite(t1):
            pieces.append(_with_end(piece, math.inf, ""))
            rest = (float(piece.state(horizon)[0]) if math.isfinite(horizon) else piece.x_eq, math.nan)
            if math.isfinite(horizon):
                rest = (rest[0], float(_plastic_force(iso, piece, rest[0])))
            break
        x1, v1 = piece.at(t1)
        # _plastic_force at one point, in Python floats (the same IEEE operations as on its 0-d arrays)
        z1 = piece.z0 if piece.yielding or iso.model == "linear" else \
            piece.z0 + (iso.stiffness - iso.k2) * (x1 - piece.x0)
        if end == "yield":
            z1 = direction * iso.plastic_yield
            pieces.append(_with_end(piece, t1, "yield"))
            t, x, v, z = t1, x1, v1, z1
            continue
        R1 = iso.k2 * x1 + z1
        if abs(R1) <= iso.friction:
            pieces.append(_with_end(piece, t1, "stick"))
            stop, rest = t1, (x1, z1)
            break
        pieces.append(_with_end(piece, t1, "reversal"))
        t, x, v, z = t1, x1, 0.0, z1
        direction = -math.copysign(1.0, R1)
    return FreeVibration(iso, d0, tuple(pieces), stop, horizon, rest)


def _with_end(piece: _Piece, t1: float, end: str) -> _Piece:
    out = object.__new__(_Piece)  # dataclasses.replace, without its per-call field checks (a hot path of fits)
    out.__dict__.update(piece.__dict__, t1=t1, end=end)
    return out


def _time_to_reach(piece: _Piece, level: float, tau_max: float) -> float | None:
    """The tau in (0, tau_max] where the piece's x reaches ``level`` (x is monotone over a piece), or None."""
    d = piece.direction
    if d * (level - piece.x0) <= 0.0:
        return 0.0
    if math.isfinite(tau_max):
        hi = tau_max
    else:  # creeps to its equilibrium: reaches the level only if the equilibrium lies beyond it
        if d * (piece.x_eq - level) <= 0.0:
            return None
        hi = 1.0 / math.sqrt(piece.b)
        while d * (piece.at(piece.t0 + hi)[0] - level) < 0.0:
            hi *= 2.0
    if d * (piece.at(piece.t0 + hi)[0] - level) < 0.0:
        return None

    def gap(tau: float) -> float:
        return piece.at(piece.t0 + tau)[0] - level

    return brentq(gap, 0.0, hi, xtol=1e-300, rtol=4.0 * np.finfo(float).eps, maxiter=200)


# -- the optional second degree of freedom: a flexible superstructure (2-DOF shear model) --------------------

@dataclass(frozen=True)
class TwoDOF:
    """The isolated building as a 2-DOF shear model (SI units): the isolation layer (base) and the
    superstructure lumped at the roof.

    - base mass ``m_b = mass - m_s`` [kg] on the isolation layer: linear spring ``k = mass (2 pi / T)^2``
      [N/m] (T the isolation period of the whole mass, as for the rigid model), viscous damper
      ``c = 2 zeta sqrt(k mass)`` [N s/m] and Coulomb sliders ``F_s`` [N] (static = kinetic);
    - roof mass ``m_s`` [kg], joined to the base by the storey stiffness ``k_s = m_s (2 pi / T_s)^2`` [N/m]
      (T_s the fixed-base period of the superstructure) and damper ``c_s = 2 zeta_s sqrt(k_s m_s)`` [N s/m].

    With x_b, x_s the displacements of base and roof [m] and ``u = x_s - x_b`` the storey drift, while the
    base slides (direction ``s = sign(x_b_dot)``)

        m_b x_b'' + c x_b' + k x_b - c_s u' - k_s u + F_s s = 0,
        m_s x_s'' + c_s u' + k_s u = 0,

    and while the sliders hold the base (x_b' = 0) the friction force ``f = -(k x_b - k_s u - c_s u')``
    [N] keeps it in place as long as ``|k x_b - k_s u - c_s u'| <= F_s``, the superstructure vibrating on
    a fixed base, ``m_s u'' + c_s u' + k_s u = 0``. As ``m_s -> 0`` or ``T_s -> 0`` it becomes the rigid
    linear model ``Isolation.linear(mass, T, zeta, F_s)`` (:meth:`rigid`).
    """

    mass: float
    """Whole mass carried by the isolators, m = m_b + m_s [kg]."""
    superstructure_mass: float
    """Superstructure mass lumped at the roof, m_s [kg], in (0, mass)."""
    period: float
    """Isolation period of the whole mass, T = 2 pi sqrt(m / k) [s]."""
    superstructure_period: float
    """Fixed-base period of the superstructure, T_s = 2 pi sqrt(m_s / k_s) [s]."""
    damping_ratio: float = 0.0
    """Viscous damping ratio of the isolation layer, zeta = c / (2 sqrt(k m)) [-], in [0, 1)."""
    friction: float = 0.0
    """Coulomb friction force of the sliders, F_s [N]."""
    superstructure_damping_ratio: float = 0.0
    """Damping ratio of the superstructure on a fixed base, zeta_s = c_s / (2 sqrt(k_s m_s)) [-], in [0, 1)."""

    def __post_init__(self) -> None:
        mass = finite_positive("mass", self.mass, "kg")
        ms = finite_positive("superstructure_mass", self.superstructure_mass, "kg")
        if not ms < mass:
            raise ParameterError("superstructure_mass", ms, f"(0, mass) = (0, {mass:.6g}) kg", "kg")
        finite_positive("period", self.period, "s")
        finite_positive("superstructure_period", self.superstructure_period, "s")
        _damping_ratio(self.damping_ratio)
        zs = float(self.superstructure_damping_ratio)
        if not (math.isfinite(zs) and 0.0 <= zs < 1.0):
            raise ParameterError("superstructure_damping_ratio", zs, "[0, 1)")
        finite_nonnegative("friction", self.friction, "N")

    model = "2dof"

    @property
    def base_mass(self) -> float:
        """m_b = mass - m_s [kg]."""
        return float(self.mass) - float(self.superstructure_mass)

    @property
    def stiffness(self) -> float:
        """Isolation stiffness k = m (2 pi / T)^2 [N/m]."""
        return float(self.mass) * (2.0 * math.pi / float(self.period)) ** 2

    @property
    def damping(self) -> float:
        """Isolation damping coefficient c = 2 zeta sqrt(k m) [N s/m]."""
        return 2.0 * float(self.damping_ratio) * math.sqrt(self.stiffness * float(self.mass))

    @property
    def superstructure_stiffness(self) -> float:
        """Storey stiffness k_s = m_s (2 pi / T_s)^2 [N/m]."""
        return float(self.superstructure_mass) * (2.0 * math.pi / float(self.superstructure_period)) ** 2

    @property
    def superstructure_damping(self) -> float:
        """Storey damping coefficient c_s = 2 zeta_s sqrt(k_s m_s) [N s/m]."""
        return 2.0 * float(self.superstructure_damping_ratio) * math.sqrt(
            self.superstructure_stiffness * float(self.superstructure_mass))

    def rigid(self) -> Isolation:
        """The rigid-superstructure limit: ``Isolation.linear(mass, T, zeta, F_s)``."""
        return Isolation.linear(self.mass, self.period, self.damping_ratio, self.friction)

    def matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Mass, damping and stiffness matrices M, C, K of the sliding base (dofs x_b, x_s; SI)."""
        k, ks, c, cs = self.stiffness, self.superstructure_stiffness, self.damping, self.superstructure_damping
        return (np.diag([self.base_mass, float(self.superstructure_mass)]),
                np.array([[c + cs, -cs], [-cs, cs]]), np.array([[k + ks, -ks], [-ks, ks]]))

    def summary(self) -> dict[str, Any]:
        return {"model": "2dof", "mass_kg": float(self.mass), "period_s": float(self.period),
                "damping_ratio": float(self.damping_ratio), "damping_N_s_m": self.damping,
                "friction_N": float(self.friction), "stiffness_N_m": self.stiffness,
                "superstructure_mass_kg": float(self.superstructure_mass),
                "superstructure_period_s": float(self.superstructure_period),
                "superstructure_damping_ratio": float(self.superstructure_damping_ratio),
                "superstructure_stiffness_N_m": self.superstructure_stiffness}


#: Grid points per period of the fastest mode used to bracket the events of the 2-DOF model.
EVENT_GRID = 16
#: Condition number of the eigenvector matrix above which a piece is evaluated by the matrix exponential.
EIGEN_CONDITION = 1e7


@dataclass(frozen=True)
class _Modes:
    """The sliding system's matrix ``A`` (y' = A y + f, y = (x_b, x_s, v_b, v_s)) and its eigen-decomposition
    ``A V = V diag(lam)``; ``modal``: V is well conditioned (cond < EIGEN_CONDITION), so the closed form sums
    the modes (else the pieces use the matrix exponential). The same for every sliding piece of a motion."""

    A: np.ndarray
    lam: np.ndarray
    V: np.ndarray
    modal: bool
    Vinv: np.ndarray | None
    """V's inverse where modal (a piece's modal amplitudes are ``Vinv (y0 - y_eq)``)."""
    rate: float
    """The fastest oscillation's |lam| [rad/s] (the event grid's scale; the slowest |lam| if none oscillates)."""
    decay: float
    """The slowest decay rate, min(-Re lam) [1/s]."""


def _modes(b: TwoDOF) -> _Modes:
    """The sliding 2-DOF system's :class:`_Modes` (one eigen-decomposition per motion)."""
    M, C, K = b.matrices()
    Minv = np.diag(1.0 / np.diag(M))
    A = np.zeros((4, 4))
    A[0, 2] = A[1, 3] = 1.0
    A[2:, :2] = -Minv @ K
    A[2:, 2:] = -Minv @ C
    lam, V = np.linalg.eig(A)
    Vinv = None
    try:
        if np.linalg.cond(V) < EIGEN_CONDITION:
            Vinv = np.linalg.inv(V)
    except np.linalg.LinAlgError:
        Vinv = None
    # the fastest oscillation sets the grid that brackets the events (an over-damped mode is monotone:
    # its fast transient near tau = 0 is resolved by the grid's geometric start instead)
    oscillating = np.abs(lam.imag) > 0.0
    rate = float(np.max(np.abs(lam[oscillating]))) if np.any(oscillating) else float(np.min(np.abs(lam)))
    return _Modes(A, lam, V, Vinv is not None, Vinv, rate, float(np.min(-lam.real)))


class _Slide:
    """A sliding piece of the 2-DOF model: ``y' = A y + f`` with y = (x_b, x_s, v_b, v_s), in closed form
    ``y(tau) = y_eq + sum_j V_j alpha_j exp(lambda_j tau)`` (eigen-decomposition of the 4x4 matrix A;
    ``y_eq = (x_e, x_e, 0, 0)``, ``x_e = -F_s s / k``)."""

    kind = "slide"

    def __init__(self, b: TwoDOF, t0: float, y0, direction: float, modes: _Modes | None = None):
        modes = _modes(b) if modes is None else modes
        A, lam, V = modes.A, modes.lam, modes.V
        self.A = A
        self.t0, self.direction = float(t0), float(direction)
        self.y0 = np.asarray(y0, dtype=float)
        self.x_eq = -b.friction * direction / b.stiffness
        self.y_eq = np.array([self.x_eq, self.x_eq, 0.0, 0.0])
        self.w0 = self.y0 - self.y_eq
        self.lam = lam
        self.modal = modes.modal
        if self.modal:
            alpha = modes.Vinv @ self.w0
            P = V[:2] * alpha  # position rows of each mode's contribution
            self.P, self.Pv, self.Pa = P, P * lam, P * lam**2
        self.rate, self.decay = modes.rate, modes.decay
        self.speed = float(np.sum(np.abs(self.Pv[0]))) if self.modal else float(np.max(np.abs(lam))) * float(
            np.max(np.abs(self.w0)))
        """A bound on |v_b| over the piece [m/s] (the scale of its rounding)."""
        self.jerk = float(np.sum(np.abs(self.Pa[0] * lam))) if self.modal else math.inf
        """A bound on |a_b'| over the piece [m/s^3] (every mode decays: |exp(lam tau)| <= 1)."""
        if self.modal:  # the root finder's scalar path in Python complex arithmetic (no array per call)
            self._terms = tuple((complex(lj), complex(vj), complex(aj))
                                for lj, vj, aj in zip(lam, self.Pv[0], self.Pa[0], strict=True))
        self.t1, self.end = math.inf, ""

    def _evaluate(self, tau):
        """x_b, x_s, v_b, v_s, a_b, a_s at tau = t - t0 >= 0."""
        tau = np.atleast_1d(np.asarray(tau, dtype=float))
        if self.modal:
            E = np.exp(np.outer(self.lam, tau))
            pos = (self.P @ E).real
            vel = (self.Pv @ E).real
            acc = (self.Pa @ E).real
            return (pos[0] + self.x_eq, pos[1] + self.x_eq, vel[0], vel[1], acc[0], acc[1])
        from scipy.linalg import expm

        Y = expm(self.A[None, :, :] * tau[:, None, None]) @ self.w0  # (n, 4)
        acc = Y @ self.A.T  # the equilibrium y_eq adds A y_eq + f = 0
        return (Y[:, 0] + self.x_eq, Y[:, 1] + self.x_eq, Y[:, 2], Y[:, 3], acc[:, 2], acc[:, 3])

    def state6(self, t):
        return self._evaluate(np.asarray(t, dtype=float) - self.t0)

    def va(self, tau):
        """Base velocity and acceleration at an array of tau."""
        if self.modal:
            E = np.exp(np.outer(self.lam, tau))
            return (self.Pv[0] @ E).real, (self.Pa[0] @ E).real
        vals = self._evaluate(tau)
        return vals[2], vals[4]

    def va1(self, tau: float) -> tuple[float, float]:
        """Base velocity and acceleration at one tau (the root finder's fast path)."""
        if self.modal:
            v = a = 0.0
            for lj, vj, aj in self._terms:
                e = cmath.exp(lj * tau)
                v += (vj * e).real
                a += (aj * e).real
            return v, a
        vals = self._evaluate(tau)
        return float(vals[2][0]), float(vals[4][0])


class _Stick:
    """A stuck piece of the 2-DOF model: the base held at x_b by the sliders, the storey drift
    ``u = x_s - x_b`` in free vibration ``u'' + 2 a u' + b u = 0`` (a = c_s / (2 m_s), b = k_s / m_s)."""

    kind = "stick"

    def __init__(self, b: TwoDOF, t0: float, xb: float, u0: float, du0: float):
        self.t0, self.xb, self.u0, self.du0 = float(t0), float(xb), float(u0), float(du0)
        self.a = b.superstructure_damping / (2.0 * float(b.superstructure_mass))
        self.b = b.superstructure_stiffness / float(b.superstructure_mass)
        self.q = self.b - self.a**2
        self.direction = 0.0
        self.t1, self.end = math.inf, ""

    def drift(self, tau):
        """u, u', u'' at tau = t - t0 >= 0."""
        ec, es = _ec_es(self.a, self.q, tau)
        u = ec * self.u0 + es * (self.du0 + self.a * self.u0)
        du = ec * self.du0 - es * (self.a * self.du0 + self.b * self.u0)
        return u, du, -(2.0 * self.a * du + self.b * u)

    def drift1(self, tau: float) -> tuple[float, float, float]:
        """u, u', u'' at one tau (q > 0: the storey is under-damped, zeta_s < 1)."""
        w = math.sqrt(self.q)
        e = math.exp(-self.a * tau)
        ec, es = e * math.cos(w * tau), e * math.sin(w * tau) / w
        u = ec * self.u0 + es * (self.du0 + self.a * self.u0)
        du = ec * self.du0 - es * (self.a * self.du0 + self.b * self.u0)
        return u, du, -(2.0 * self.a * du + self.b * u)

    def state6(self, t):
        tau = np.atleast_1d(np.asarray(t, dtype=float) - self.t0)
        u, du, ddu = self.drift(tau)
        zero = np.zeros(tau.shape)
        return (np.full(tau.shape, self.xb), self.xb + u, zero, du, zero, ddu)


def _first_rise(FF, f, fp, hi: float, step: float, start_zero: bool, floor: float = 0.0,
                curvature: float = math.inf) -> float | None:
    """The first tau in (0, hi] where F crosses from <= 0 to > 0 (F(0) <= 0), to machine precision.

    ``FF(tau)`` gives F and its derivative F' on an array of tau; ``f``, ``fp`` the same at one tau (for
    the root finder). F is sampled every ``step``; an interval whose ends are both <= 0 but where F' falls
    from + to - (an interior maximum) is checked at the maximum (a brentq root of F'), so two crossings
    within one step are not missed. ``start_zero``: F(0) = 0 with F < 0 just after (a piece that starts at
    a reversal or a breakaway), so the bracket's left end is moved off 0, and values of F up to ``floor``
    (its rounding level) within the first step count as <= 0. ``curvature``: a bound J on |F''| over
    (0, hi]; an interior maximum in [a, b] (h = b - a) is then skipped without a root where
    ``F(a) + F'(a) h + J h^2 / 2 < 0`` or ``F(b) - F'(b) h + J h^2 / 2 < 0`` (Taylor's bound: F stays
    below zero there). Returns None if F stays <= 0.
    """
    tol = dict(xtol=1e-300, rtol=4.0 * np.finfo(float).eps, maxiter=200)
    lo_chunk = 0.0
    chunk = 64 * step  # doubled each chunk up to 2048 steps: most events come within a few dozen steps
    while lo_chunk < hi:
        hi_chunk = min(lo_chunk + chunk, hi)
        chunk = min(2.0 * chunk, 2048 * step)
        n = max(int(math.ceil((hi_chunk - lo_chunk) / step)), 1)
        tau = np.linspace(lo_chunk, hi_chunk, n + 1)
        if lo_chunk == 0.0:  # a geometric start resolves fast transients near 0
            tau = np.concatenate([[0.0], tau[1] * 2.0 ** -np.arange(12.0, 0.0, -1.0), tau[1:]])
        F, Fp = FF(tau)
        if lo_chunk == 0.0 and start_zero:  # F(0) = 0 and F'(0) <= 0 by construction (rounding aside)
            head = tau < tau[13]  # 0 and the geometric start
            F[head] = np.where(F[head] <= floor, np.minimum(F[head], 0.0), F[head])
            Fp[0] = min(Fp[0], 0.0)
        rising = F[1:] > 0.0
        peaked = (Fp[:-1] > 0.0) & (Fp[1:] < 0.0)
        for i in np.nonzero(rising | peaked)[0] + 1:
            a, b = float(tau[i - 1]), float(tau[i])
            if not F[i] > 0.0:
                h2 = 0.5 * curvature * (b - a) ** 2
                if F[i - 1] + Fp[i - 1] * (b - a) + h2 < 0.0 or F[i] - Fp[i] * (b - a) + h2 < 0.0:
                    continue
                tm = brentq(fp, a, b, **tol)
                if f(tm) <= 0.0:
                    continue
                b = tm
            if a == 0.0 and start_zero:  # move off the root at 0: F < 0 just after it
                h = 0.5 * b
                while h > 1e-18 * b and f(h) >= 0.0:
                    h *= 0.5
                if f(h) >= 0.0:
                    return b
                a = h
            if f(a) > 0.0:
                if start_zero and f(a) <= floor:
                    continue
                return a
            return brentq(f, a, b, **tol)
        lo_chunk = hi_chunk
    return None


class BaseAndRoof:
    """The base's and the roof's motion from ``states(t)`` (a 2-DOF vibration's: closed form or integrated)."""

    def state(self, t):
        """The base (isolation layer): x_b [m], v_b [m/s], a_b [m/s^2] at times t [s]."""
        s = self.states(t)
        return s["x_b"], s["v_b"], s["a_b"]

    def roof_state(self, t):
        """The roof: x_s [m], v_s [m/s], a_s [m/s^2] at times t [s]."""
        s = self.states(t)
        return s["x_s"], s["v_s"], s["a_s"]


@dataclass(frozen=True, eq=False)
class TwoDOFVibration(BaseAndRoof):
    """The free vibration of the 2-DOF building from the pushed state (SI units); exact piecewise closed
    form. :meth:`state` gives the base (the isolation layer, as :meth:`FreeVibration.state`, so planning and
    clearance use it for any model), :meth:`roof_state` the roof, :meth:`states` both."""

    building: TwoDOF
    d0: float
    pieces: tuple = field(repr=False)
    stop_time: float
    """When the sliders hold the base for good [s] (inf: not within the horizon)."""
    horizon: float
    rest: tuple[float, float]
    """(x_b, 0): where the base stops (the last piece's base position when it does not)."""

    @property
    def isolation(self) -> TwoDOF:
        return self.building

    @property
    def reversal_times(self) -> np.ndarray:
        """Times where the base velocity vanishes while sliding (reversals and sticks), 0 first [s]."""
        return np.array([0.0] + [p.t1 for p in self.pieces if p.kind == "slide" and p.end in ("reversal", "stick")])

    @property
    def turning_points(self) -> np.ndarray:
        """Base displacements at the turning points, d0 first [m]. A stiff storey can make the base chatter
        (stick, break away, turn) within a storey period near a peak: each of those turns is listed."""
        out = [self.d0]
        for p in self.pieces:
            if p.kind == "slide" and p.end in ("reversal", "stick"):
                out.append(float(p.state6(p.t1)[0][0]))
        return np.array(out)

    def states(self, t) -> dict[str, np.ndarray]:
        """x, v, a of the base (``x_b, v_b, a_b``) and of the roof (``x_s, v_s, a_s``) at times t [s]
        [m, m/s, m/s^2]. Before the release both rest at d0; at an instant where an acceleration jumps the
        value after it is returned."""
        t = np.asarray(t, dtype=float)
        shape = t.shape
        t = t.ravel()
        out = [np.full(t.shape, self.d0), np.full(t.shape, self.d0)] + [np.zeros(t.shape) for _ in range(4)]
        starts = np.array([p.t0 for p in self.pieces])
        index = np.searchsorted(starts, t, side="right") - 1
        for i in np.unique(index[index >= 0]):
            m = index == i
            vals = self.pieces[i].state6(t[m])
            for arr, v in zip(out, vals, strict=True):
                arr[m] = v
        keys = ("x_b", "x_s", "v_b", "v_s", "a_b", "a_s")
        return {k: v.reshape(shape) for k, v in zip(keys, out, strict=True)}


    def channels(self, t) -> dict[str, np.ndarray]:
        """Every channel of the building's record at times t [s] (SI): x, v, a of the base (isolation
        layer) and x_roof, v_roof, a_roof of the roof (one evaluation of the motion)."""
        s = self.states(t)
        return {"x": s["x_b"], "v": s["v_b"], "a": s["a_b"], "x_roof": s["x_s"], "v_roof": s["v_s"],
                "a_roof": s["a_s"]}

    def energies(self, t) -> dict[str, np.ndarray]:
        """The energy balance at times t [J]: kinetic ``(m_b v_b^2 + m_s v_s^2) / 2``, stored
        ``(k x_b^2 + k_s u^2) / 2``, friction ``F_s sum |dx_b|`` and viscous dissipation so far (``hysteretic``
        is 0); their sum is ``initial = k d0^2 / 2``.

        The viscous dissipation of a sliding piece is the drop of its invariant
        ``(m_b v_b^2 + m_s v_s^2 + k (x_b - x_e)^2 + k_s u^2) / 2`` (x_e its equilibrium), of a stuck one the
        drop of ``(m_s u'^2 + k_s u^2) / 2``: exact, since between events only the dampers change them.
        """
        b = self.building
        k, ks, mb, ms = b.stiffness, b.superstructure_stiffness, b.base_mass, float(b.superstructure_mass)
        t = np.atleast_1d(np.asarray(t, dtype=float))
        s = self.states(t)
        u = s["x_s"] - s["x_b"]
        kinetic = 0.5 * mb * s["v_b"] ** 2 + 0.5 * ms * s["v_s"] ** 2
        stored = 0.5 * k * s["x_b"] ** 2 + 0.5 * ks * u**2
        friction = np.zeros(t.shape)
        viscous = np.zeros(t.shape)

        def invariant(p, vals):
            xb, xs, vb, vs = vals[:4]
            if p.kind == "slide":
                return 0.5 * (mb * vb**2 + ms * vs**2 + k * (xb - p.x_eq) ** 2 + ks * (xs - xb) ** 2)
            return 0.5 * (ms * vs**2 + ks * (xs - xb) ** 2)

        for p in self.pieces:
            tt = np.clip(t, p.t0, p.t1)
            vals = p.state6(tt)
            v0 = p.state6(np.array([p.t0]))
            if p.kind == "slide":
                friction += b.friction * np.abs(vals[0] - v0[0][0])
            viscous += invariant(p, [v[0] for v in v0]) - invariant(p, vals)
        return {"kinetic": kinetic, "stored": stored, "hysteretic": np.zeros(t.shape), "friction": friction,
                "viscous": viscous, "initial": np.full(t.shape, 0.5 * k * self.d0**2)}

    def summary(self) -> dict[str, Any]:
        return _motion_summary(self.building, self)


def free_vibration_2dof(building: TwoDOF, d0: float, t_end: float | None = None) -> TwoDOFVibration:
    """The 2-DOF building's free vibration after the release from the pushed state (SI units).

    The jack pushes the base quasi-statically, so the superstructure rides on it undeformed (no inertia
    force, no storey shear): at the release ``x_b = x_s = d0`` [m], at rest, the isolators holding
    ``k d0`` and the sliders at most ``F_s``. The motion is followed piece by piece: while the base slides
    the system is linear with constant coefficients (closed form, :class:`_Slide`); a piece ends where the
    base velocity vanishes (a bracketed brentq root on the closed form), where the sliders either hold the
    base (``|k x_b - k_s u - c_s u'| <= F_s``: a stuck piece, the superstructure vibrating on a fixed base)
    or the sliding turns (direction ``-sign(k x_b - k_s u - c_s u')``). A stuck base breaks away where
    ``|k x_b - k_s u - c_s u'|`` reaches F_s (a bracketed root over one damped period of the storey: the
    excursion of that force shrinks by ``exp(-a T_d)`` every period, so none later if none in the first);
    else it is held for good (``stop_time``) while the superstructure rings on.

    Parameters
    ----------
    building : TwoDOF
    d0 : float
        Base (and roof) displacement at the release [m]: a real number (not a bool), finite, non-zero, storing at
        most 1e300 J in the isolators (``k d0^2 / 2``, :func:`~.hysteretic.checked_d0`).
    t_end : float, optional
        Follow the motion up to this time [s]; by default until the base is held for good (needs F_s > 0).
    """
    if not isinstance(building, TwoDOF):
        raise ParameterError("building", type(building).__name__, "a TwoDOF")
    b = building
    d0 = checked_d0(b, d0)  # True was 1 m, as free_vibration's own check refuses
    horizon = _horizon(t_end, b.friction)
    k, ks, cs, Fs = b.stiffness, b.superstructure_stiffness, b.superstructure_damping, float(b.friction)
    pieces: list = []
    stop = math.inf

    def holding_force(xb, u, du):  # what the sliders must resist to hold the base [N]
        return k * xb - ks * u - cs * du

    modes = _modes(b)
    t, y = 0.0, np.array([d0, d0, 0.0, 0.0])
    g = holding_force(d0, 0.0, 0.0)
    stuck = abs(g) <= Fs
    direction = -math.copysign(1.0, g)
    while t < horizon:
        if len(pieces) >= MAX_PIECES:
            raise ParameterError("t_end", horizon, f"a span of at most {MAX_PIECES} pieces", "s")
        if stuck:
            p = _Stick(b, t, y[0], y[1] - y[0], y[3] - y[2])
            pieces.append(p)
            if p.u0 == 0.0 and p.du0 == 0.0:
                stop = t
                break
            Td = 2.0 * math.pi / math.sqrt(p.q)
            # |u^(n)| <= R b^(n/2) (R the drift's amplitude, b = a^2 + w^2): a bound on |G''| = |k_s u'' + c_s u^(3)|
            amp = math.hypot(p.u0, (p.du0 + p.a * p.u0) / math.sqrt(p.q))
            curvature = (ks * p.b + cs * p.b**1.5) * amp * (1.0 + 1e-9)

            found = []
            for sign in (1.0, -1.0):  # sign G - F_s rising: G reaches +F_s, or -F_s

                def FF(tau, p=p, sign=sign):
                    u, du, ddu = p.drift(tau)
                    return sign * holding_force(p.xb, u, du) - Fs, sign * (-ks * du - cs * ddu)

                def f(tau, p=p, sign=sign):
                    u, du, _ = p.drift1(tau)
                    return sign * holding_force(p.xb, u, du) - Fs

                def fp(tau, p=p, sign=sign):
                    _, du, ddu = p.drift1(tau)
                    return sign * (-ks * du - cs * ddu)

                tau = _first_rise(FF, f, fp, Td, Td / (2 * EVENT_GRID), False, curvature=curvature)
                if tau is not None:
                    found.append((tau, sign))
            if not found:
                stop = t
                break
            tau, sign = min(found)
            t1 = t + tau
            if t1 >= horizon:
                break
            u, du, _ = p.drift(tau)
            p.t1, p.end = t1, "breakaway"
            t, y = t1, np.array([p.xb, p.xb + float(u), 0.0, float(du)])
            direction = -sign  # the base moves along the net force on it, -G (G = sign F_s here)
            stuck = False
            continue
        p = _Slide(b, t, y, direction, modes)
        pieces.append(p)
        step = 2.0 * math.pi / p.rate / EVENT_GRID
        hi = horizon - t
        if not math.isfinite(hi):  # creeping without a reversal: give up once every mode has decayed by 1e-17
            hi = 40.0 / p.decay if p.decay > 0 else math.inf
        tau = _first_rise(lambda s, p=p: (-p.direction * p.va(s)[0], -p.direction * p.va(s)[1]),
                          lambda s, p=p: -p.direction * p.va1(s)[0], lambda s, p=p: -p.direction * p.va1(s)[1],
                          hi, step, True, 64.0 * np.finfo(float).eps * p.speed, curvature=p.jerk * (1.0 + 1e-9))
        if tau is None or t + tau >= horizon:
            break
        t1 = t + tau
        xb, xs, vb, vs, _, _ = (float(v[0]) for v in p._evaluate(tau))
        t, y = t1, np.array([xb, xs, 0.0, vs])
        g = holding_force(xb, xs - xb, vs)
        if abs(g) <= Fs:
            p.t1, p.end = t1, "stick"
            stuck = True
        else:
            p.t1, p.end = t1, "reversal"
            direction = -math.copysign(1.0, g)
    last = pieces[-1]
    if last.kind == "stick":
        rest_x = last.xb
    elif math.isfinite(horizon):
        rest_x = float(last.state6(np.array([horizon]))[0][0])
    else:
        rest_x = last.x_eq
    return TwoDOFVibration(b, d0, tuple(pieces), stop, horizon, (rest_x, 0.0))
