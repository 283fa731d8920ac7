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

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import brentq

from .errors import ParameterError

__all__ = ["Isolation", "FreeVibration", "free_vibration", "pushed_state", "MODELS"]

#: Restoring-force models of the isolation layer.
MODELS = ("linear", "bilinear")

#: Most pieces (half-cycles and yield events) one free vibration may have.
MAX_PIECES = 1_000_000


def _finite_positive(name: str, value: float, unit: str) -> float:
    value = float(value)
    if not (math.isfinite(value) and value > 0.0):
        raise ParameterError(name, value, "(0, inf)", unit)
    return value


def _finite_nonnegative(name: str, value: float, unit: str) -> float:
    value = float(value)
    if not (math.isfinite(value) and value >= 0.0):
        raise ParameterError(name, value, "[0, inf)", unit)
    return value


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

    def __post_init__(self) -> None:
        _finite_positive("mass", self.mass, "kg")
        _finite_positive("stiffness", self.stiffness, "N/m")
        _finite_nonnegative("damping", self.damping, "N s/m")
        _finite_nonnegative("friction", self.friction, "N")
        if (self.post_yield_stiffness is None) != (self.yield_force is None):
            raise ParameterError("post_yield_stiffness/yield_force", "one of the two",
                                 "both (bilinear) or neither (linear)")
        if self.post_yield_stiffness is not None:
            k2 = float(self.post_yield_stiffness)
            if not (math.isfinite(k2) and 0.0 < k2 < self.stiffness):
                raise ParameterError("post_yield_stiffness", k2, f"(0, k1) = (0, {self.stiffness:.6g}) N/m", "N/m")
            _finite_positive("yield_force", self.yield_force, "N")

    @classmethod
    def linear(cls, mass: float, period: float, damping_ratio: float = 0.0, friction: float = 0.0) -> Isolation:
        """Linear isolation: period T [s], damping ratio zeta [-] in [0, 1), slider friction F_s [N]."""
        mass = _finite_positive("mass", mass, "kg")
        period = _finite_positive("period", period, "s")
        zeta = _damping_ratio(damping_ratio)
        k = mass * (2.0 * math.pi / period) ** 2
        return cls(mass=mass, stiffness=k, damping=2.0 * zeta * math.sqrt(k * mass), friction=friction)

    @classmethod
    def bilinear(cls, mass: float, k1: float, k2: float, yield_force: float, damping_ratio: float = 0.0,
                 friction: float = 0.0) -> Isolation:
        """Bilinear isolation: k1, k2 [N/m], F_y [N]; zeta [-] refers to the initial stiffness,
        ``c = 2 zeta sqrt(k1 m)``; slider friction F_s [N]."""
        mass = _finite_positive("mass", mass, "kg")
        k1 = _finite_positive("k1", k1, "N/m")
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
        """Viscous damping ratio referred to the (initial) stiffness, ``c / (2 sqrt(k1 m))`` [-]."""
        return self.damping / (2.0 * math.sqrt(self.stiffness * self.mass))

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
        return out


def _damping_ratio(value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and 0.0 <= value < 1.0):
        raise ParameterError("damping_ratio", value, "[0, 1)")
    return value


def pushed_state(isolation: Isolation, d0: float) -> tuple[float, float, float]:
    """The state at the release after a monotonic push from 0 to d0 [m], at rest.

    Returns ``(z0, R0, P)``: the plastic element's force z0 [N] (0 for the linear model), the restoring
    force R0 = k2 d0 + z0 [N] and the push force that held it, P = R0 + F_s sign(d0) [N].
    """
    d0 = float(d0)
    if not math.isfinite(d0) or d0 == 0.0:
        raise ParameterError("d0", d0, "finite and non-zero", "m")
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
    return _Piece(t0=t0, x0=x0, v0=v0, z0=z0, direction=direction, yielding=yielding, k=k, x_eq=x_eq, a=a, b=b,
                  q=b - a * a)


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

    def restoring_force(self, t) -> np.ndarray:
        """The isolators' force R = k2 x + z [N] at times t (the spring alone, no damper, no sliders)."""
        x, _, _, z = self._evaluate(t)
        return self.isolation.k2 * x + z

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
            starts = np.array([p.t0 for p in pieces])
            index = np.searchsorted(starts, t, side="right") - 1
            moving = index >= 0
            last = pieces[-1]
            if last.end == "stick":  # only the last piece sticks: at rest from its end on
                after = (index == len(pieces) - 1) & (t >= last.t1)
                moving &= ~after
                x[after], z[after] = self.rest
                v[after] = acc[after] = 0.0
            t0, x0, v0, z0, x_eq, direction = (np.array([getattr(p, f) for p in pieces])
                                               for f in ("t0", "x0", "v0", "z0", "x_eq", "direction"))
            yielding = np.array([p.yielding for p in pieces])
            for kind in (False, True):
                if not np.any(yielding == kind):
                    continue
                first = pieces[int(np.argmax(yielding == kind))]
                sel = moving & (yielding[np.maximum(index, 0)] == kind)
                if not np.any(sel):
                    continue
                i = index[sel]
                y0 = x0[i] - x_eq[i]
                ec, es = _ec_es(first.a, first.q, t[sel] - t0[i])
                xs = x_eq[i] + ec * y0 + es * (v0[i] + first.a * y0)
                vs = ec * v0[i] - es * (first.a * v0[i] + first.b * y0)
                if kind or iso.model == "linear":
                    zs = z0[i]
                else:
                    zs = z0[i] + (iso.stiffness - iso.k2) * (xs - x0[i])
                x[sel], v[sel], z[sel] = xs, vs, zs
                acc[sel] = -(iso.damping * vs + iso.k2 * xs + zs + iso.friction * direction[i]) / iso.mass
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
        peaks = self.turning_points
        return {**self.isolation.summary(), "d0_m": self.d0, "stop_time_s": self.stop_time,
                "rest_displacement_m": self.rest[0], "half_cycles": int(peaks.size - 1),
                "first_peak_m": float(peaks[1]) if peaks.size > 1 else None}


def free_vibration(isolation: Isolation, d0: float, t_end: float | None = None) -> FreeVibration:
    """The building's free vibration after the release from the pushed displacement d0 [m], at rest.

    Parameters
    ----------
    isolation : Isolation
        The isolation layer (:meth:`Isolation.linear` or :meth:`Isolation.bilinear`).
    d0 : float
        Displacement of the isolation layer at the release [m] (reached by a monotonic push).
    t_end : float, optional
        Follow the motion up to this time [s]; by default until the sliders stick for good (which needs
        F_s > 0: without friction the motion never ends, and t_end is required).

    Returns
    -------
    FreeVibration
    """
    iso = isolation
    d0 = float(d0)
    z0, R0, _ = pushed_state(iso, d0)
    if t_end is None:
        if iso.friction == 0.0:
            raise ParameterError("t_end", None, "a finite time in (0, inf) s when the sliders have no friction "
                                 "(the motion never ends)")
        horizon = math.inf
    else:
        horizon = _finite_positive("t_end", t_end, "s")
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
        x1, v1 = (float(s) for s in piece.state(t1))
        z1 = float(_plastic_force(iso, piece, x1))
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
        while d * (float(piece.state(piece.t0 + hi)[0]) - level) < 0.0:
            hi *= 2.0
    if d * (float(piece.state(piece.t0 + hi)[0]) - level) < 0.0:
        return None

    def gap(tau: float) -> float:
        return float(piece.state(piece.t0 + tau)[0]) - level

    return brentq(gap, 0.0, hi, xtol=1e-300, rtol=4.0 * np.finfo(float).eps, maxiter=200)
