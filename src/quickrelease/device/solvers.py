"""Three solvers of the release, one Response.

``explicit``
    The paper's scheme of Table 6, exactly as printed: the angular velocity from a
    first-order Taylor step, the angle by the mid-point (trapezoidal) rule on the
    velocity, the acceleration from the equation of motion (Eq. 3/4). First order
    in dt. The stop is located inside the last step, where the velocity (linear
    within a step) vanishes, so sign(alpha_dot) never chatters at rest.
``rk``
    scipy ``solve_ivp`` (DOP853 by default, or RK45) on the first-order system
    (alpha, alpha_dot) with a terminal event at alpha_dot = 0 (friction stop) or, where the
    one classifier of the stop (:func:`quickrelease.device.dynamics.limit_margin_terms`) says the rhombus
    becomes flat first, at alpha = pi/2 (geometric limit). Every method takes ``stopped_by`` from
    that classifier, so they agree on it even for a stop within rounding of pi/2.
``energy``
    The first integral, Eq. 9-10: ``alpha_dot = sqrt((E_S - W_F(alpha)) / M(alpha))``
    and the time map ``t(alpha) = int dalpha / alpha_dot`` by Gauss quadrature (see ``_kernels``).
    The substitution ``sin((alpha_F - alpha)/2) = sin((alpha_F - alpha0)/2) w^2`` removes the
    inverse-square-root singularity at the stop and writes the remaining energy without
    cancellation, so the integrand is smooth and the result accurate to near machine precision.

During the release alpha_dot > 0, so sign(alpha_dot) = +1 until the stop; the
``rk`` solver integrates that smooth branch and lets the event end it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._roots import brent
from .._statetable import StateTable
from .._timemap import TimeMap
from .._validate import HALF_PI, check_angle, check_nonnegative, check_positive, check_size, renamed
from ..errors import ParameterError
from ..units import si_scalar
from . import dynamics
from ._kernels import Releases
from .parameters import Device, preset
from .response import Response

__all__ = ["METHODS", "simulate", "stop_time", "FirstIntegral"]

#: Default tolerances of ``rk``: rtol, and atol as a share of the initial rate alpha_dot0 (for both alpha and
#: alpha_dot). With these the energy balance |E_K + W_F - E_S| / E_S stays below 2e-9 along the solution over
#: the whole valid space (max 1.0e-9 over the 1,000 seeded hypothesis cases of tests/device/test_properties.py, incl.
#: tiny sweeps and stops at pi/2, which checks 2e-9; at rtol 1e-10, atol 1e-12 max(1, alpha_dot0) it reached
#: 1.5e-8, 4.5% of cases above 1e-9), at the same cost (mean 123 against 131 right-hand side evaluations).
RK_RTOL = 1e-11
RK_ATOL_SHARE = 1e-14

#: Solver names accepted by :func:`simulate`.
METHODS = ("energy", "rk", "explicit")


class FirstIntegral:
    """The energy solution of one release (Eq. 8-10): a scalar view of :class:`_kernels.Releases`.

    See :mod:`quickrelease.device._kernels` for the regimes (``friction``, ``virtual``, ``free``), the
    substitution that makes the time integrand smooth, and the rule for nearly singular cases.
    Parameters are SI floats; ``c`` is the mass factor.
    """

    def __init__(self, E_S: float, alpha0: float, F1: float, F2: float,
                 m1: float, m2: float, L1: float, c: float) -> None:
        self.E_S, self.alpha0, self.F1, self.F2 = float(E_S), float(alpha0), float(F1), float(F2)
        self.m1, self.m2, self.L1, self.c = float(m1), float(m2), float(L1), float(c)
        self._rel = Releases.build(*(np.array([v]) for v in (E_S, alpha0, F1, F2, c * m1 / m2, m2, L1)))
        self.regime = ("friction", "limit", "creep")[int(self._rel.regime[0])]
        self.geometric_limit = self.regime == "limit"
        self.creeps = self.regime == "creep"  # t_F = inf (dynamics.creeps_terms): creeps towards pi/2
        self.anchor = float(self._rel.anchor[0])
        self.alpha_final = float(self._rel.alpha_final[0])
        self.stopped_by = {"friction": "friction", "limit": "geometric_limit", "creep": "creeps_to_limit"}[self.regime]
        self._time_map: TimeMap | None = None
        self._state_table: StateTable | None | bool = False  # False: not built yet; None: none meets the tolerance
        coarse = [v for v in (self.E_S,) if 0.0 < v < _FINEST_SUBNORMAL]
        if coarse:  # a deep subnormal E_S carries few bits: the results would be off in their leading digits
            _unresolved(self, f"an input of {coarse[0]:.6g} < {_FINEST_SUBNORMAL:.3g}, a subnormal float with fewer "
                        "than 43 significant bits")
        if not (math.isfinite(self.alpha_final) and 0.0 < self.alpha_dot0 < math.inf):
            _unresolved(self, f"alpha_F = {self.alpha_final:.6g} rad, alpha_dot0 = {self.alpha_dot0:.6g} rad/s")

    def alpha(self, w):
        """Angle at the integration variable w [rad]."""
        return self._rel.alpha_at(w)

    def mass(self, alpha):
        return dynamics.generalized_mass(alpha, self.m1, self.m2, self.L1, self.c)

    def remaining(self, alpha):
        """E_S - W_F(alpha) without cancellation [J] (Eq. 9)."""
        return self._rel.remaining_energy(alpha)

    def rate(self, alpha):
        """alpha_dot from the first integral (Eq. 10) [rad/s]."""
        return np.sqrt(self.remaining(alpha) / self.mass(alpha))

    def integrand(self, w):
        """dt/dw, smooth on [0, 1] [s]."""
        w = np.asarray(w, dtype=float)
        return self._rel.integrand(w.reshape(1, -1)).reshape(w.shape)

    def stop_time(self) -> float:
        """Time from release to the end of the motion [s] (Eq. 10 integrated)."""
        return float(self._rel.stop_time()[0])

    def elapsed(self, w) -> np.ndarray:
        """Time from release to the angle alpha(w), for an array of w in [0, 1] [s]."""
        return self._rel.elapsed(np.asarray(w, dtype=float))

    @property
    def alpha_dot0(self) -> float:
        """Angular velocity just after release (Eq. 6) [rad/s]."""
        return float(self._rel.rate_at(np.array([1.0]))[0])

    @property
    def w_end(self) -> float:
        """w where the returned motion ends: 0 (the stop, or the flat rhombus), or for a creeping release the
        horizon, where the kinetic energy has come down to ``CREEP_HORIZON E_S`` (K = 2 A sigma^2 + 2 B sigma q
        with K_lim = 0, solved for sigma with q = 1, exact to O(sigma^2)) [-]."""
        if not self.creeps:
            return 0.0
        rel, hE = self._rel, CREEP_HORIZON * self.E_S
        A, B = float(rel.A[0]), float(rel.B[0])
        sigma_h = hE / (B + math.sqrt(B * B + 2.0 * A * hE))
        return math.sqrt(sigma_h / float(rel.sigma_m[0]))

    def horizon(self) -> float:
        """Time to :attr:`w_end` [s]: the stop time, or for a creeping release the end of the returned history."""
        if not self.creeps:
            return self.stop_time()
        return float(self.elapsed(np.array([self.w_end]))[0])

    @property
    def time_constant(self) -> float:
        """tau = sqrt(2 M(pi/2) / A) [s]: pi/2 - alpha decays like exp(-t / tau) as a creeping release nears pi/2."""
        return math.sqrt(2.0 * float(self.mass(HALF_PI)) / float(self._rel.A[0]))

    @property
    def time_map(self) -> TimeMap:
        """t(w) as a piecewise Chebyshev series on [w_end, 1] (built on first use)."""
        if self._time_map is None:
            w0 = self.w_end
            self._time_map = TimeMap(lambda u: (1.0 - w0) * self.integrand(w0 + (1.0 - w0) * u))
        return self._time_map

    def w_at_times(self, t) -> np.ndarray:
        """The integration variable w reached at times t since release (clipped to the motion) [-]."""
        w0 = self.w_end
        return w0 + (1.0 - w0) * self.time_map.invert(t)

    def state_at(self, t) -> tuple[np.ndarray, np.ndarray]:
        """alpha and alpha_dot at times t since release [rad, rad/s], at rest before 0 and after the stop.

        Before release the device rests at alpha0; after the end of the motion at alpha_F (a friction
        stop, Eq. 8) or at pi/2 (the flat rhombus, where the motion ends).
        """
        t = np.asarray(t, dtype=float)
        t_stop = self.stop_time()
        before, after = t <= 0.0, t > t_stop
        moving = ~(before | after)
        if np.all(moving):
            w = self.w_at_times(t)
            alpha = self.alpha(w)
            alpha_dot = self._rel.rate_at(w)
        else:  # the time map inverted at the times of the motion only: a record's rests cost nothing
            alpha, alpha_dot = np.empty(t.shape), np.empty(t.shape)
            w = self.w_at_times(t[moving])
            alpha[moving] = self.alpha(w)
            alpha_dot[moving] = self._rel.rate_at(w)
        alpha[before], alpha_dot[before] = self.alpha0, 0.0
        alpha[after], alpha_dot[after] = self.alpha_final, 0.0
        if self.creeps:  # past the horizon, the exponential creep towards pi/2 (leading order in pi/2 - alpha)
            t_h, tau = self.horizon(), self.time_constant
            late = t > t_h
            x = (HALF_PI - float(self.alpha(np.array([self.w_end]))[0])) * np.exp(-(t[late] - t_h) / tau)
            alpha[late], alpha_dot[late] = HALF_PI - x, x / tau
        return alpha, alpha_dot

    @property
    def state_table(self) -> StateTable | None:
        """alpha(t) on the motion as a quintic Hermite table (built on first use; None where no table of
        :data:`quickrelease._statetable.MAX_CELLS` cells meets :data:`quickrelease._statetable.TOL`)."""
        if self._state_table is False:
            def acceleration(alpha, alpha_dot):  # on the branch alpha_dot > 0, the stop included (its limit)
                return dynamics.angular_acceleration(alpha, np.maximum(alpha_dot, 1e-300), self.F1, self.F2,
                                                     self.m1, self.m2, self.L1, self.c)

            def exact(t):
                w = self.w_at_times(t)
                return self.alpha(w), self._rel.rate_at(w)

            self._state_table = StateTable.build(self.stop_time(), exact, acceleration)
        return self._state_table

    def state_at_many(self, t, acceleration: bool = False) -> tuple[np.ndarray, ...]:
        """As :meth:`state_at`, for many times at a cost linear in their number: the times at rest take the
        rest values, the times within the motion the interpolated :attr:`state_table` (relative error at most
        :data:`quickrelease._statetable.TOL` in alpha, alpha_dot and alpha_ddot; see :mod:`quickrelease._statetable`).
        Falls back to :meth:`state_at` for few times or where no table meets the tolerance.
        """
        t = np.asarray(t, dtype=float)
        t_stop = self.stop_time()
        moving = (t > 0.0) & (t <= t_stop)
        count = int(np.count_nonzero(moving))
        table = self.state_table if count >= 1 << 16 else None
        if table is None:
            alpha, alpha_dot = self.state_at(t)
            if not acceleration:
                return alpha, alpha_dot
            alpha_ddot = dynamics.angular_acceleration(alpha, alpha_dot, self.F1, self.F2, self.m1, self.m2,
                                                       self.L1, self.c)
            return alpha, alpha_dot, alpha_ddot
        alpha = np.full(t.shape, self.alpha0)
        alpha_dot = np.zeros(t.shape)
        alpha_ddot = np.zeros(t.shape)
        alpha[t > t_stop] = self.alpha_final
        a, ad, add = table.state(t[moving], acceleration=True)
        alpha[moving], alpha_dot[moving], alpha_ddot[moving] = a, ad, add
        return (alpha, alpha_dot, alpha_ddot) if acceleration else (alpha, alpha_dot)


@renamed(E_S="stored_energy")
def stop_time(stored_energy: float, alpha0: float, F1: float, F2: float, *,
              device: Device | None = None, mass_model: str | float = "distributed") -> float:
    """Time from release to the end of the motion, t_F, by the energy solution (Eq. 10) [s].

    Quantity arguments are SI numbers, strings with units or pint Quantities.

    Parameters
    ----------
    stored_energy : float
        Stored strain energy E_S [J].
    alpha0 : float
        Angle at release [rad], in (0, pi/2).
    F1, F2 : float
        Friction at the central hinges and at the rail supports [N], >= 0.
    device : Device, optional
        The device (m1, m2, L1 enter); the paper's device by default.
    mass_model : {"distributed", "lumped"} or float
        Mass factor c (Eq. 5).
    """
    device = device or preset("paper")
    c = dynamics.mass_factor(mass_model)
    E_S, alpha0, F1, F2 = _release_args(stored_energy, alpha0, F1, F2)
    return FirstIntegral(E_S, alpha0, F1, F2, device.m1, device.m2, device.L1, c).stop_time()


#: A creeping release (t_F = inf, :func:`quickrelease.device.dynamics.creeps_terms`) is returned up to the time
#: where its kinetic energy has come down to this share of E_S (its speed to about 1e-3 of the initial):
#: ``stats["horizon_s"]``.
CREEP_HORIZON = 1e-6

#: Below this a subnormal float has fewer than 43 significant bits (relative spacing above 1e-13).
_FINEST_SUBNORMAL = math.ldexp(1.0, -1031)


def _unresolved(fi: FirstIntegral, derived: str) -> None:
    """Raise the error for a release whose derived quantities are not finite floats, naming the inputs
    (the one of most extreme magnitude first: that is the one to look at)."""
    inputs = {"E_S": (fi.E_S, "J"), "F1": (fi.F1, "N"), "F2": (fi.F2, "N"), "c": (fi.c, ""),
              "m1": (fi.m1, "kg"), "m2": (fi.m2, "kg"), "L1": (fi.L1, "m")}
    worst = max(inputs, key=lambda k: abs(math.log10(inputs[k][0])) if inputs[k][0] > 0 else -1.0)
    others = ", ".join(f"{k} = {v:.6g} {u}".rstrip() for k, (v, u) in inputs.items() if k != worst)
    raise ParameterError(worst, inputs[worst][0], f"the range the release model resolves in floating point "
                         f"(with {others}, alpha0 = {fi.alpha0:.6g} rad it gives {derived})", inputs[worst][1])


def _release_args(E_S, alpha0, F1, F2) -> tuple[float, float, float, float]:
    """The release's arguments as SI floats (numbers, strings with units or pint Quantities), checked."""
    E_S, alpha0 = si_scalar(E_S, "energy", "E_S"), si_scalar(alpha0, "angle", "alpha0")
    F1, F2 = si_scalar(F1, "force", "F1"), si_scalar(F2, "force", "F2")
    _check_release(E_S, alpha0, F1, F2)
    return E_S, alpha0, F1, F2


def _check_release(E_S, alpha0, F1, F2) -> None:
    check_positive("E_S", E_S, "J")
    check_angle("alpha0", alpha0)
    check_nonnegative("F1", F1, "N")
    check_nonnegative("F2", F2, "N")


# -- the three methods ----------------------------------------------------------------

def _creep_stats(fi: FirstIntegral) -> dict[str, float]:
    """What a creeping release's history covers: its horizon and the time constant of the creep after it."""
    return {"horizon_s": fi.horizon(), "time_constant_s": fi.time_constant} if fi.creeps else {}


def _solve_energy(fi: FirstIntegral, n_points: int, **_: Any) -> dict[str, Any]:
    t_stop = fi.stop_time()
    t = np.linspace(0.0, fi.horizon(), n_points)
    w = fi.w_at_times(t)
    w[0], w[-1] = 1.0, fi.w_end
    alpha = fi.alpha(w)
    alpha[0] = fi.alpha0
    if not fi.creeps:
        alpha[-1] = fi.alpha_final
    alpha_dot = fi._rel.rate_at(w)
    return {"t": t, "alpha": alpha, "alpha_dot": alpha_dot, "stop_time": t_stop,
            "alpha_final": fi.alpha_final, "stats": {"n_points": n_points, **_creep_stats(fi)}}


def _solve_rk(fi: FirstIntegral, n_points: int, rtol: float = RK_RTOL, atol: float | None = None,
              rk_method: str = "DOP853", max_time: float | None = None, **_: Any) -> dict[str, Any]:
    from scipy.integrate import solve_ivp

    if rk_method not in ("DOP853", "RK45"):
        raise ParameterError("rk_method", rk_method, "'DOP853' or 'RK45'")
    m1, m2, L1, c, F1, F2 = fi.m1, fi.m2, fi.L1, fi.c, fi.F1, fi.F2
    k = c * m1 / m2
    q = 1.0 / (m2 * L1)

    def rhs(_t, y):
        s, co = math.sin(y[0]), math.cos(y[0])
        d = k + s * s
        # Eq. 3/4 on the branch sign(alpha_dot) = +1, valid until the stop event.
        return [y[1], -(y[1] * y[1]) * s * co / d - (2.0 * F2 * s + F1 * co) * q / d]

    def stopped(_t, y):
        return y[1]

    stopped.terminal = True
    stopped.direction = -1

    def flat(_t, y):
        return y[0] - HALF_PI

    flat.terminal = True
    flat.direction = 1

    alpha_dot0 = float(dynamics.initial_rate(fi.E_S, fi.alpha0, m1, m2, L1, c))
    if fi.creeps:  # never stops (t_F = inf): integrated to the first integral's horizon
        max_time = fi.horizon()
    elif max_time is None:
        # generous horizon: the slowest release stops long before this
        max_time = 1e3 * (HALF_PI - fi.alpha0) / alpha_dot0 + 10.0
    atol = RK_ATOL_SHARE * alpha_dot0 if atol is None else atol
    # Integrated on the release's own clock, tau = t alpha_dot0 (one radian at the initial rate per unit), with
    # the state (alpha, d alpha / d tau): solve_ivp locates its events to an absolute 4 eps in its time
    # variable, which in seconds was 1e-3 of a t_F of 1e-12 s (E_S >= 1e27 J: 1e-5 to 1e-2 off the energy
    # solution, t_F = 0 at E_S = 1e35 J). The tolerances are the same in alpha and alpha_dot.
    T = 1.0 / alpha_dot0

    def rhs_tau(_tau, z):
        s, co = math.sin(z[0]), math.cos(z[0])
        d = k + s * s
        return [z[1], -(z[1] * z[1]) * s * co / d - (2.0 * F2 * s + F1 * co) * (q * T * T) / d]

    sol = solve_ivp(rhs_tau, (0.0, max_time / T), [fi.alpha0, 1.0], method=rk_method,
                    rtol=rtol, atol=[atol, atol * T], events=(stopped, flat), dense_output=True)
    if sol.status != 1 and not (fi.creeps and sol.status == 0):
        raise RuntimeError(f"solve_ivp ended without reaching a stop: {sol.message}")

    def state(t):  # (alpha, alpha_dot) at t [s] from the dense output on the release's clock
        z = sol.sol(np.asarray(t) / T)
        return np.array([z[0], z[1] / T])

    t_zero = T * float(sol.t_events[0][0]) if sol.t_events[0].size else math.inf
    t_flat = T * float(sol.t_events[1][0]) if sol.t_events[1].size else math.inf
    if t_zero < t_flat and float(sol.y_events[0][0][0]) > HALF_PI:
        # The step that crossed pi/2 also passed alpha_dot = 0, and alpha had fallen back below pi/2 by its
        # end (the smooth branch runs on past the stop), so the sign check at the step ends saw no crossing
        # of pi/2: find it on the dense output of that step.
        t_lo = T * float(sol.t[-2]) if sol.t.size > 1 else 0.0
        t_flat = brent(lambda t: float(state(t)[0]) - HALF_PI, t_lo, t_zero, xtol=1e-15 * max(t_zero, 1e-300))
    rate_flat = float(state(t_flat)[1]) if math.isfinite(t_flat) else 0.0

    def arrival(rate_true: float) -> float:
        # alpha = pi/2 is crossed nearly tangentially when the rate there is small (an error e in alpha moves the
        # crossing by ~sqrt(e)); the first integral gives the rate there exactly (Eq. 10), so the arrival is
        # where the integrated rate, linear in t there, has come down to it at the local deceleration
        # (only for a nearly tangential crossing, rate_true < 1e-4 alpha_dot0: a transversal one is well
        # conditioned, and a small deceleration would turn the rk error of the rate into a large shift)
        if rate_true >= 1e-4 * alpha_dot0:
            return t_flat
        decel = -float(rhs(t_flat, [HALF_PI, rate_flat])[1])
        extra = (rate_flat - rate_true) / decel if decel > 0.0 and rate_flat > rate_true else 0.0
        return t_flat + (extra if extra < t_flat else 0.0)

    if fi.creeps:
        # t_F = inf (dynamics.creeps_terms): the history up to the first integral's horizon (K = 1e-6 E_S there,
        # far above rk's error), or an event of the integration's own before it (within its error of pi/2)
        t_stop, stopped_by, alpha_final, end_rate = math.inf, "creeps_to_limit", HALF_PI, None
        t_hist = min(fi.horizon(), t_zero, t_flat)
    elif fi.geometric_limit:
        # The one classifier (dynamics.limit_margin_terms) says the rhombus becomes flat with kinetic energy
        # left. Within rounding of the boundary the integrated alpha_dot may vanish a hair before pi/2: that
        # instant (the closest approach) is then the arrival at the flat rhombus.
        if t_flat <= t_zero:
            rate_true = math.sqrt(max(float(fi._rel.K_lim[0]), 0.0)) / math.sqrt(m2 * L1 * L1 * (k + 1.0))
            t_stop, end_rate = arrival(rate_true), rate_flat
        else:
            t_stop, end_rate = t_zero, 0.0
        alpha_final = HALF_PI
        stopped_by = "geometric_limit"
    else:
        # A friction stop (alpha_F <= pi/2 by Eq. 8): alpha_dot = 0 is crossed transversally, so its event
        # is well conditioned. alpha = pi/2 is approached tangentially by a stop there (an error e in alpha
        # moves that crossing by ~sqrt(e)): when the integration reaches pi/2 first, within its error of a
        # stop at pi/2, the stop is where the velocity, linear in t there, runs out at the local deceleration
        # (what an event at alpha_dot = 0 just past pi/2 would give); without deceleration at pi/2 (F2 = 0,
        # where t_F is not determined by the rounded inputs: it diverges logarithmically as the stop
        # approaches pi/2) at the crossing itself.
        if t_zero <= t_flat:
            t_stop = t_zero
            alpha_final = min(float(sol.y_events[0][0][0]), HALF_PI)
        else:
            t_stop = arrival(0.0)
            alpha_final = HALF_PI
        stopped_by = "friction"
        end_rate = 0.0
    t = np.linspace(0.0, t_hist if fi.creeps else t_stop, n_points)
    y = state(t)
    alpha, alpha_dot = y[0].copy(), y[1].copy()
    alpha[0], alpha_dot[0] = fi.alpha0, alpha_dot0
    if not fi.creeps:
        alpha[-1], alpha_dot[-1] = alpha_final, end_rate
    return {"t": t, "alpha": alpha, "alpha_dot": alpha_dot, "stop_time": t_stop,
            "alpha_final": alpha_final, "stopped_by": stopped_by,
            "stats": {"nfev": int(sol.nfev), "steps": int(sol.t.size - 1), "rk_method": rk_method,
                      "rtol": rtol, "atol": atol, **_creep_stats(fi)}}


#: The fewest steps of the explicit scheme over the motion (t_F / dt): a larger dt is refused, since a first
#: order scheme over one or two steps answers without a word (dt = 1e308 s: alpha_F 0.770 for 0.739).
EXPLICIT_MIN_STEPS = 10


def _solve_explicit(fi: FirstIntegral, dt: float | None = None, max_steps: int = 20_000_000,
                    **_: Any) -> dict[str, Any]:
    """Table 6, step by step; the stop is found inside the last step."""
    dt = 1e-4 if dt is None else float(dt)
    check_positive("dt", dt, "s")
    t_stop = fi.horizon()  # the energy solution's t_F (or a creeping release's horizon): the steps needed
    if t_stop / dt > max_steps:
        raise ParameterError("dt", dt, f"[t_F / {max_steps:,}, inf) = [{t_stop / max_steps:.3g}, inf) (t_F = "
                             f"{t_stop:.6g} s; at most {max_steps:,} steps)", "s")
    if dt > t_stop / EXPLICIT_MIN_STEPS:  # a step over the whole motion: Table 6 would answer from two samples
        raise ParameterError("dt", dt, f"(0, t_F / {EXPLICIT_MIN_STEPS}] = (0, {t_stop / EXPLICIT_MIN_STEPS:.3g}] (t_F"
                             f" = {t_stop:.6g} s of the energy solution; at least {EXPLICIT_MIN_STEPS} steps over "
                             "the motion)", "s")
    m1, m2, L1, c, F1, F2 = fi.m1, fi.m2, fi.L1, fi.c, fi.F1, fi.F2
    k = c * m1 / m2
    q = 1.0 / (m2 * L1)
    sin, cos = math.sin, math.cos

    def acc(a, ad):
        # Table 6, third line; sign(alpha_dot) = +1 while the device moves
        s, co = sin(a), cos(a)
        d = k + s * s
        return -(ad * ad) * s * co / d - (2.0 * F2 * s + F1 * co) * q / d

    a = fi.alpha0
    ad = float(dynamics.initial_rate(fi.E_S, fi.alpha0, m1, m2, L1, c))
    add = acc(a, ad)
    ts, als, ads = [0.0], [a], [ad]
    stopped_by = "friction"
    t = 0.0
    for k_step in range(1, max_steps + 1):
        ad_new = ad + add * dt  # Table 6, first line
        if ad_new <= 0.0:
            # velocity is linear in the step: it vanishes at tau = -ad/add
            tau = -ad / add
            a = a + 0.5 * ad * tau  # mid-point rule with alpha_dot = 0 at the end
            t = t + tau
            if a >= HALF_PI:  # cannot happen before the flat check below, but be safe
                a = HALF_PI
            ts.append(t)
            als.append(a)
            ads.append(0.0)
            break
        a_new = a + 0.5 * (ad_new + ad) * dt  # Table 6, second line
        if a_new >= HALF_PI:
            # alpha(tau) = a + ad tau + add tau^2 / 2 reaches pi/2 inside the step
            gap = HALF_PI - a
            disc = ad * ad + 2.0 * add * gap
            tau = 2.0 * gap / (ad + math.sqrt(max(disc, 0.0)))
            t = t + tau
            ad = ad + add * tau
            ts.append(t)
            als.append(HALF_PI)
            ads.append(ad)
            stopped_by = "geometric_limit"
            break
        a, ad = a_new, ad_new
        add = acc(a, ad)  # Table 6, third line
        t = k_step * dt
        ts.append(t)
        als.append(a)
        ads.append(ad)
        if fi.creeps and t >= t_stop:  # a creeping release (t_F = inf) is stepped to its horizon
            stopped_by = "horizon"
            break
    else:
        raise ParameterError("dt", dt, f"values that reach the stop within max_steps = {max_steps}", "s")
    # stopped_by is the one classifier's (as for every method); the first-order trajectory may end the other
    # way within its O(dt) error of a stop at pi/2: its own ending is kept in the stats.
    return {"t": np.array(ts), "alpha": np.array(als), "alpha_dot": np.array(ads),
            "stop_time": math.inf if fi.creeps else t, "alpha_final": HALF_PI if fi.creeps else als[-1],
            "stopped_by": fi.stopped_by,
            "stats": {"dt": dt, "steps": len(ts) - 1, "scheme_end": stopped_by, **_creep_stats(fi)}}


_SOLVERS = {"energy": _solve_energy, "rk": _solve_rk, "explicit": _solve_explicit}


def _energy_from(stored_energy, push_force, alpha0: float, device: Device) -> tuple[float, float | None]:
    """(E_S, P) of a release given by its stored energy, or by its push force (E_S by Eq. 2). Given both, E_S
    is the one simulated and P is kept as reported (a test may report the jack's P beside an E_S of its own)."""
    if stored_energy is None and push_force is None:
        raise ParameterError("stored_energy/push_force", "neither", "at least one of the two (E_S [J], or P [N] "
                             "for E_S by Eq. 2)")
    P = None if push_force is None else si_scalar(push_force, "force", "push_force")
    if stored_energy is not None:
        return stored_energy, P
    from .statics import strain_energy

    return strain_energy(P, alpha0, device).total, P


class _Required:
    """The default of an argument that must be given but follows an optional one (``simulate``'s alpha0)."""

    def __repr__(self) -> str:
        return "<required>"


_REQUIRED: Any = _Required()


@renamed(E_S="stored_energy")
def simulate(stored_energy: float | None = None, alpha0: float = _REQUIRED, F1: float = 0.0, F2: float = 0.0, *,
             push_force: float | None = None, device: Device | None = None, mass_model: str | float = "distributed",
             method: str = "energy", dt: float | None = None, n_points: int = 1001,
             t_end: float | None = None, rtol: float = RK_RTOL, atol: float | None = None,
             rk_method: str = "DOP853") -> Response:
    """Simulate the release of the device from the fuse rupture to the stop.

    Parameters
    ----------
    stored_energy : float, optional
        Strain energy E_S stored before release [J] (e.g. ``strain_energy(P, alpha0, device).total``);
        from ``push_force`` by Eq. 2 when left out.
    alpha0 : float
        Angle of the bars with the loading axis at release [rad], in (0, pi/2).
    F1, F2 : float
        Coulomb friction at the central hinges and at the rail supports [N], >= 0.
    push_force : float, optional
        Push force P at release [N]: E_S by Eq. 2 when ``stored_energy`` is left out. Kept in the response
        (``summary()["push_force_N"]``, as ``quickrelease simulate --force`` prints it); given beside
        ``stored_energy`` it is only recorded.
    device : Device, optional
        The device; the paper's (Table 2) by default.
    mass_model : {"distributed", "lumped"} or float
        Mass factor c: 2/3 (Eq. 4), 1 (Eq. 3) or a positive number.
    method : {"energy", "rk", "explicit"}
        The solver (see the module notes).
    dt : float, optional
        Time step of ``explicit`` [s] (default 1e-4 s).
    n_points : int
        Samples, evenly spaced in time, returned by ``energy`` and ``rk``.
    t_end : float, optional
        Pad the response with rest samples up to this time [s] (after a friction stop).
    rtol, atol : float
        Tolerances of ``rk`` (default rtol 1e-11, atol 1e-14 alpha_dot0: energy balance within 2e-9).
    rk_method : {"DOP853", "RK45"}
        Runge-Kutta scheme of ``rk``.

    Numbers are SI; every quantity argument also takes a string with units (``"2.9 kJ"``) or a pint
    Quantity (``2.9 * ureg.kJ``), converted at the boundary.

    Returns
    -------
    Response
    """
    if alpha0 is _REQUIRED:
        raise TypeError("simulate() missing the release angle alpha0")
    device = device or preset("paper")
    alpha0 = si_scalar(alpha0, "angle", "alpha0")
    check_angle("alpha0", alpha0)
    stored_energy, push_force = _energy_from(stored_energy, push_force, alpha0, device)
    E_S, alpha0, F1, F2 = _release_args(stored_energy, alpha0, F1, F2)
    dt = None if dt is None else si_scalar(dt, "time", "dt")
    t_end = None if t_end is None else si_scalar(t_end, "time", "t_end")
    if method not in _SOLVERS:
        raise ParameterError("method", method, "'" + "', '".join(METHODS) + "'")
    if not isinstance(n_points, int | np.integer) or n_points < 2:
        raise ParameterError("n_points", n_points, "integers >= 2")
    check_size("n_points", n_points, n_points, "time samples")
    c = dynamics.mass_factor(mass_model)
    fi = FirstIntegral(E_S, alpha0, F1, F2, device.m1, device.m2, device.L1, c)
    t_stop = fi.horizon()  # t_F, or where the returned history of a creeping release ends (t_F = inf)
    if not 0.0 < t_stop < math.inf:
        _unresolved(fi, f"t_F = {t_stop:.6g} s")
    out = _SOLVERS[method](fi, n_points=int(n_points), dt=dt, rtol=rtol, atol=atol, rk_method=rk_method)
    stopped_by = out.get("stopped_by", fi.stopped_by)
    alpha_dot = out["alpha_dot"]
    alpha_ddot = dynamics.angular_acceleration(out["alpha"], alpha_dot, float(F1), float(F2),
                                               device.m1, device.m2, device.L1, c)
    response = Response(
        t=out["t"], alpha=out["alpha"], alpha_dot=alpha_dot, alpha_ddot=alpha_ddot,
        stored_energy=float(E_S), alpha0=float(alpha0), F1=float(F1), F2=float(F2),
        mass_factor=c, device=device, stop_time=float(out["stop_time"]),
        alpha_final=float(out["alpha_final"]), stopped_by=stopped_by, method=method,
        stats=out["stats"], push_force=push_force,
    )
    if t_end is not None:
        check_positive("t_end", t_end, "s")
        spacing = float(np.min(np.diff(response.t))) if response.t.size > 1 else t_end
        spacing = max(spacing, response.stop_time / max(n_points - 1, 1)) if method == "explicit" else spacing
        check_size("t_end", f"{t_end:.6g} s", (t_end - response.stop_time) / spacing, "rest samples")
        response = response.pad_to(float(t_end), spacing)
    return response
