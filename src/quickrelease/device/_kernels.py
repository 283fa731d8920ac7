"""Vectorized first-integral kernels (Eq. 8-10): the one implementation of the time integrand.

Used by the scalar energy solver (:class:`quickrelease.device.solvers.FirstIntegral`) and by the batch
engine (:mod:`quickrelease.batch`). Every function works on 1-D arrays of cases.

The time to the end of the motion is ``t = int sqrt(M(alpha) / K(alpha)) dalpha`` with
``M = m2 L1^2 (k + sin^2 alpha)``, ``k = c m1/m2`` and ``K = E_S - W_F(alpha)`` (Eq. 9-10).
W_F is a sinusoid, ``R (sin(alpha - phi) - sin(alpha0 - phi))``. Three regimes:

``friction`` (stop at alpha_F <= pi/2): with the anchor ``a = alpha_F`` of Eq. 8 and
``sigma = sin((a - alpha)/2)``, ``K = 2 R C sigma`` with ``C = cos(a - phi) q + sin(a - phi) sigma``
and ``q = sqrt(1 - sigma^2)``; ``sin(alpha) = sin(a)(1 - 2 sigma^2) - cos(a) 2 sigma q``. Then
``sigma = sigma_m w^2`` removes the inverse square root at the stop:
``dt/dw = 4 L1 sqrt(sigma_m m2 / (2R)) sqrt((k + sin^2 alpha) / C) / q``, w in [0, 1]; since
``a - alpha0 < pi/2``, q stays above cos(pi/4). No trigonometric function is evaluated at a
quadrature node: only square roots and arithmetic.

``limit`` (friction cannot stop the device before the rhombus is flat, E_S > W_F(pi/2)): anchor pi/2,
``sigma = sin((pi/2 - alpha)/2)``,
``K = K_lim + 2 A sigma^2 + 2 B sigma q`` (all terms >= 0, ``K_lim = E_S - W_F(pi/2)``),
``sin(alpha) = 1 - 2 sigma^2`` and ``dt/dw = 4 sigma_m w sqrt(M/K) / q``.

``creep`` (the margin within its rounding of 0 and no rail friction to speak of,
:func:`quickrelease.device.dynamics.creeps_terms`): the ``limit`` formulas with ``K_lim = 0``; the integrand then
grows like 1/w at w = 0 and t_F = inf (the device creeps towards pi/2 and never arrives).

Smooth cases take a 16-node Gauss-Legendre rule. Cases whose integrand has a near-singularity close
to the end of the interval (C or K nearly vanishing there: a stop close to the flat rhombus with
little rail friction, or barely reaching it) are detected per case from the ratio of that factor at
the two ends; cases whose mass factor ``k + sin^2 alpha`` has a complex zero close to the start (a small
``k = c m1/m2`` with a small alpha0: the zero sits at about ``sin(alpha) = +-i sqrt(k)``) from
``sqrt(k + sin^2 alpha0)`` over the sweep. Both criteria hold on both regimes (friction stop and
geometric limit). Nearly singular cases take 24 nodes, or Gauss-Legendre on panels graded
geometrically towards both ends of [0, 1]. Every tier keeps the relative error below 1e-12
(calibrated against mpmath; the tests check 1e-10 on grids of the hard corners).

The sweep ``delta = alpha_F - alpha0`` comes from the cancellation-free closed form of Eq. 8
(:func:`quickrelease.device.dynamics.sweep_terms`), never from a rounded alpha_F, and the classification
friction / geometric limit from :func:`quickrelease.device.dynamics.limit_margin_terms` (the one classifier).
Scale factors are taken as products of square roots so that extreme inputs (1e-300 J, 1e300 N) do
not underflow or overflow in an intermediate.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .dynamics import (
    _limit_dissipation,
    amplitude_terms,
    creeps_terms,
    limit_margin_terms,
    limit_sweep,
    stop_cosine_terms,
    sweep_terms,
)

HALF_PI = 0.5 * math.pi

#: Nodes of the basic rule, panels and grading of the rule for nearly singular cases.
N_NODES = 16
N_NODES_MASS = 24
N_PANELS = 16
GRADING = 0.2
#: The factor that may vanish at the end of the interval (C, or K in the free regime) puts a complex
#: singularity of the integrand at a distance of about sqrt(ratio) from w = 0, ratio being its value at
#: the end over its value at the start. Below NEAR_RATIO the 24-node rule, below HARD_RATIO the graded
#: rule. Calibrated against the full graded rule (itself within 1e-15 of mpmath) on 400k cases of the bench and
#: wide samples: the 16-node rule's worst error 4.5e-13, the 24-node rule's 9.3e-13. (HARD_RATIO was 0.01 and
#: MASS_RATIO 0.5, worst 4.9e-11 and 3.4e-12, when the graded rule cost 544 nodes.)
HARD_RATIO = 0.05
NEAR_RATIO = 0.3
#: Cases whose sqrt(k + sin^2 alpha0) is below this share of the angle swept take the 24-node rule
#: (a complex zero of the mass factor k + sin^2 alpha near the start of a long sweep).
MASS_RATIO = 1.0
#: ... and below this share the graded rule (24 nodes leave ~1e-12 at 0.25, 1e-7 at 0.01).
MASS_HARD = 0.25

#: ``creep`` (:func:`quickrelease.device.dynamics.creeps_terms`): the margin within rounding of 0 without rail friction;
#: the motion is that of the ``limit`` regime with ``K_lim = 0`` and never ends (t_F = inf, alpha_F = pi/2).
REGIME_FRICTION, REGIME_LIMIT, REGIME_CREEP = 0, 1, 2

#: Relative rounding allowance of a stop time at an end of the feasible interval of the identification:
#: each of the two evaluations that meet there (the observation, when it comes from a model, and the
#: endpoint t_F(F1 = 0) or t_F(F1 = F1*)) carries up to 1e-12 of quadrature error (see above) and a few
#: ulps of arithmetic; 4e-12 covers both with room.
FEASIBLE_RTOL = 4e-12


def feasible_slack(t_end, alpha0, alpha_final, hinge_end):
    """How far [s] an observed t_F may lie from an end ``t_end`` of the feasible interval and still be that end.

    ``t_end (FEASIBLE_RTOL + eps alpha_F (1 / (alpha_F - alpha0) + hinge_end / cos(alpha_F)))``: the quadrature
    allowance, plus the effect of alpha_F being known only to its rounding (half an ulp, at most
    ``eps alpha_F / 2``). t_F grows at most in proportion to the sweep alpha_F - alpha0 for a small sweep, so a
    relative error ``ulp / sweep`` of the sweep moves an end by as much, relatively. The end F1 = F1*
    (``hinge_end = 1``: pure hinge friction, which does no work at pi/2) has t_F ~ ln(1 / cos alpha_F) as
    alpha_F -> pi/2, so its relative sensitivity to alpha_F is bounded by ``1 / cos(alpha_F)``: within an ulp or
    so of pi/2 that end is not determined by the rounded alpha_F at all, and any slower stop is that end.
    Pure arithmetic and one cosine (compiled as is by :mod:`quickrelease.batch._fast`).
    """
    return t_end * (FEASIBLE_RTOL + 2.220446049250313e-16 * alpha_final
                    * (1.0 / (alpha_final - alpha0) + hinge_end / np.cos(alpha_final)))


_local = threading.local()


def _buffers(shape: tuple[int, int]) -> list[np.ndarray]:
    """Five work arrays of ``shape``, reused across calls in this thread (no allocation on the hot path)."""
    cache = getattr(_local, "buffers", None)
    if cache is None or cache[0].shape != shape:
        cache = [np.empty(shape) for _ in range(5)]
        _local.buffers = cache
    return cache


@lru_cache(maxsize=8)
def gauss_unit(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on [0, 1]."""
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


@lru_cache(maxsize=4)
def graded_unit(n: int = N_NODES, panels: int = N_PANELS, r: float = GRADING) -> tuple[np.ndarray, np.ndarray]:
    """Composite Gauss-Legendre on [0, 1] graded geometrically towards both ends.

    [0, 1/2] is split into panels [r^(j+1)/2, r^j/2] (plus [0, r^panels/2]) towards 0, where C or K may
    nearly vanish (the end of the motion), and [1/2, 1] mirrored towards 1, where the mass factor may
    nearly vanish (the start).
    """
    x, w = gauss_unit(n)
    edges = 0.5 * np.concatenate([r ** np.arange(panels + 1), [0.0]])
    nodes, weights = [], []
    for hi, lo in zip(edges[:-1], edges[1:], strict=True):
        nodes.append(lo + (hi - lo) * x)
        weights.append((hi - lo) * w)
    left, wl = np.concatenate(nodes), np.concatenate(weights)
    return np.concatenate([left, 1.0 - left[::-1]]), np.concatenate([wl, wl[::-1]])


def tier_of(end_ratio, mass_ratio_sq):
    """The quadrature tier of each case: 0 (16 nodes), 1 (24 nodes) or 2 (graded), from the ratio of the
    factor that may vanish at the end and ``(k + sin^2 alpha0) / chord^2`` with the chord ``2 sin(delta / 2)``
    of the sweep (within 11% of delta; the identification takes delta itself) (see the module notes).
    The one criterion: used by the numpy kernels, the identification and (compiled) :mod:`._fast`."""
    hard = (end_ratio < HARD_RATIO) | (mass_ratio_sq < MASS_HARD**2)
    near = (end_ratio < NEAR_RATIO) | (mass_ratio_sq < MASS_RATIO**2)
    return np.where(hard, 2, np.where(near, 1, 0)).astype(np.int8)


@dataclass
class Releases:
    """Per-case constants of the first integral for arrays of releases (all 1-D, same length).

    ``sin_a``, ``cos_a`` are the sine and cosine of the anchor, ``cos_p``, ``sin_p`` those of
    ``anchor - phi``: all obtained algebraically from A, B, R (no trigonometric call per case beyond
    sin/cos of alpha0, one arctan2 for alpha_F and one sine for sigma_m).
    """

    E_S: np.ndarray
    alpha0: np.ndarray
    F1: np.ndarray
    F2: np.ndarray
    k: np.ndarray
    m2: np.ndarray
    L1: np.ndarray
    A: np.ndarray
    B: np.ndarray
    R: np.ndarray
    W_limit: np.ndarray
    K_lim: np.ndarray
    """E_S - W_F(pi/2) from the classifier (> 0 exactly for the geometric limit) [J]."""
    regime: np.ndarray
    anchor: np.ndarray
    sin_a: np.ndarray
    cos_a: np.ndarray
    cos_p: np.ndarray
    sin_p: np.ndarray
    sigma_m: np.ndarray
    """sigma at alpha0 (w = 1)."""
    delta: np.ndarray
    """The sweep alpha_F - alpha0, cancellation-free [rad]."""
    alpha_final: np.ndarray
    tier: np.ndarray
    """0: smooth (16-node rule), 1: nearly singular mass factor (24 nodes), 2: nearly singular end (graded)."""

    @property
    def geometric_limit(self) -> np.ndarray:
        return self.regime == REGIME_LIMIT

    @property
    def hard(self) -> np.ndarray:
        return self.tier == 2

    @classmethod
    def build(cls, E_S, alpha0, F1, F2, k, m2, L1) -> Releases:
        E_S, alpha0, F1, F2, k, m2, L1 = (np.asarray(v, dtype=float) for v in (E_S, alpha0, F1, F2, k, m2, L1))
        sa0, ca0 = np.sin(alpha0), np.cos(alpha0)
        A = 2.0 * F1 * L1
        B = 4.0 * F2 * L1
        R = amplitude_terms(A, B)
        W_limit = _limit_dissipation(A, B, sa0, ca0)
        to_limit = limit_sweep(alpha0)  # pi/2 - alpha0, two-term pi/2
        K_lim = limit_margin_terms(E_S, A, B, sa0, ca0)
        creep = creeps_terms(K_lim, E_S, A, B)
        K_lim = np.where(creep, 0.0, K_lim)  # the creeping motion: the margin is 0 (within its rounding)
        geo = (K_lim > 0.0) | creep  # anchor pi/2 for both
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            # Eq. 8: sin(alpha_F - phi) = sin(alpha0 - phi) + E_S/R, with cos(phi) = A/R, sin(phi) = B/R
            s = (A * sa0 - B * ca0) / R + E_S / R  # u of sweep_terms, rounded the same way: one alpha_F
            delta = sweep_terms(E_S, A, B, R, sa0, ca0)
            at_flat = ~geo & (delta >= to_limit)  # (u may round to 1 short of it: cb is exact there)
            if np.any(geo):
                s = np.where(geo, 1.0, s)
            cb = stop_cosine_terms(E_S, A, B, R, sa0, ca0)  # cos(alpha_F - phi), no cancellation at u -> -1
            if np.any(at_flat):
                # a friction stop at pi/2 within rounding: sin, cos of alpha_F - phi at alpha_F = pi/2
                # (cos(phi), sin(phi)), consistent with the sweep pi/2 - alpha0
                s = np.where(at_flat, A / R, s)
                cb = np.where(at_flat, B / R, cb)
            sin_a = (B * cb + A * s) / R
            cos_a = (A * cb - B * s) / R
            if np.any(geo):
                sin_a = np.where(geo, 1.0, sin_a)
                cos_a = np.where(geo, 0.0, cos_a)
                cb = np.where(geo, 0.0, cb)
        regime = np.where(creep, REGIME_CREEP, geo.astype(np.int8)).astype(np.int8)
        delta = np.where(geo, to_limit, np.clip(delta, 0.0, to_limit))
        anchor = np.minimum(alpha0 + delta, HALF_PI)
        sigma_m = np.sin(0.5 * delta)
        rel = cls(E_S, alpha0, F1, F2, k, m2, L1, A, B, R, W_limit, K_lim, regime, anchor, sin_a, cos_a,
                  cb, s, sigma_m, delta, anchor, np.zeros(E_S.shape, dtype=np.int8))
        # tiers: a nearly singular end, or a near-singular mass factor close to the start
        with np.errstate(divide="ignore", invalid="ignore"):
            rel.tier = tier_of(rel._end_ratio(), (k + sa0 * sa0) / (4.0 * sigma_m * sigma_m))
        return rel

    def _end_ratio(self) -> np.ndarray:
        """Value of the factor that may vanish at the end (C, or K for ``limit``) over its value at w = 1."""
        sm = self.sigma_m
        q_m = np.sqrt(1.0 - sm * sm)
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = self.cos_p / (self.cos_p * q_m + self.sin_p * sm)
            if np.any(self.regime):
                K_lim = self.K_lim
                K_start = K_lim + 2.0 * self.A * sm * sm + 2.0 * self.B * sm * q_m
                ratio = np.where(self.regime != REGIME_FRICTION, K_lim / K_start, ratio)
        return ratio

    def take(self, index) -> Releases:
        return Releases(*(getattr(self, f)[index] for f in self.__dataclass_fields__))

    # -- the integrand ---------------------------------------------------------------------------------
    def integrand(self, w: np.ndarray) -> np.ndarray:
        """dt/dw at w (shape (n_cases, n_nodes), or broadcastable), all regimes [s]."""
        col = (slice(None), None)
        sm = self.sigma_m[col]
        sigma = sm * w * w
        q = np.sqrt(1.0 - sigma * sigma)
        free = (self.regime != REGIME_FRICTION)[col]
        sin_alpha = self.sin_a[col] * (1.0 - 2.0 * sigma * sigma) - self.cos_a[col] * 2.0 * sigma * q
        mass = self.k[col] + sin_alpha * sin_alpha
        with np.errstate(divide="ignore", invalid="ignore"):
            C = self.cos_p[col] * q + self.sin_p[col] * sigma
            f_stop = self._stop_prefactor()[col] * np.sqrt(mass / C) / q
            if np.any(free):
                K = self.K_lim[col] + 2.0 * self.A[col] * sigma * sigma + 2.0 * self.B[col] * sigma * q
                f_free = (4.0 * self.L1 * np.sqrt(self.m2))[col] * sm * w * (np.sqrt(mass) / np.sqrt(K)) / q
                return np.where(free, f_free, f_stop)
        return f_stop

    def _stop_prefactor(self) -> np.ndarray:
        """``4 L1 sqrt(sigma_m m2 / (2 R))`` as a product of square roots (no underflow for tiny sweeps) [s]."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return 4.0 * self.L1 * np.sqrt(self.sigma_m) * np.sqrt(self.m2) / np.sqrt(2.0 * self.R)

    def _smooth_stop_time(self, n: int) -> np.ndarray:
        """The n-node rule for friction-regime cases: the hot path.

        Nodes-first layout (n_nodes, n_cases) and in-place ufuncs: about 17 passes over the node
        array, two square roots and one division per node, no trigonometric call.
        """
        x, wt = gauss_unit(n)
        w2 = (x * x)[:, None]
        S, S2, Q2, Q, T = _buffers((n, self.sigma_m.size))
        np.multiply(w2, self.sigma_m, out=S)  # sigma
        np.multiply(S, S, out=S2)
        np.subtract(1.0, S2, out=Q2)  # q^2 = 1 - sigma^2
        np.sqrt(Q2, out=Q)
        np.multiply(S, Q, out=T)
        T *= -2.0 * self.cos_a
        S2 *= -2.0 * self.sin_a
        S2 += T
        S2 += self.sin_a  # sin(alpha) = sin(a)(1 - 2 sigma^2) - cos(a) 2 sigma q
        np.multiply(S2, S2, out=S2)
        S2 += self.k  # k + sin^2(alpha)
        np.multiply(Q, self.cos_p, out=T)
        S *= self.sin_p
        T += S  # C = cos(a - phi) q + sin(a - phi) sigma
        T *= Q2
        S2 /= T
        np.sqrt(S2, out=S2)  # sqrt((k + sin^2 alpha) / C) / q
        return self._stop_prefactor() * (wt @ S2)

    def _limit_stop_time(self, n: int) -> np.ndarray:
        """The n-node rule for cases that reach the flat rhombus (anchor pi/2), in place.

        ``dt/dw = 4 sigma_m L1 sqrt(m2) w sqrt((k + sin^2 alpha) / K) / q`` with ``sin(alpha) = 1 - 2 sigma^2``
        and ``K = K_lim + 2 A sigma^2 + 2 B sigma q``.
        """
        x, wt = gauss_unit(n)
        w2 = (x * x)[:, None]
        S, S2, Q2, Q, T = _buffers((n, self.sigma_m.size))
        np.multiply(w2, self.sigma_m, out=S)
        np.multiply(S, S, out=S2)
        np.subtract(1.0, S2, out=Q2)
        np.sqrt(Q2, out=Q)
        np.multiply(S, Q, out=T)
        T *= 2.0 * self.B
        T += self.K_lim
        np.multiply(S2, 2.0 * self.A, out=S)
        T += S  # K
        np.multiply(S2, -2.0, out=S)
        S += 1.0  # sin(alpha)
        np.multiply(S, S, out=S)
        S += self.k  # k + sin^2(alpha)
        T *= Q2
        np.sqrt(S, out=S)
        np.sqrt(T, out=T)  # square roots apart: K may be as small as 1e-320 J
        S /= T
        pref = 4.0 * self.sigma_m * self.L1 * np.sqrt(self.m2)
        return pref * ((wt * x) @ S)

    def stop_time(self) -> np.ndarray:
        """Time from release to the end of the motion (stop or flat rhombus) [s]."""
        rules = {(REGIME_FRICTION, 0): lambda r: r._smooth_stop_time(N_NODES),
                 (REGIME_FRICTION, 1): lambda r: r._smooth_stop_time(N_NODES_MASS),
                 (REGIME_LIMIT, 0): lambda r: r._limit_stop_time(N_NODES),
                 (REGIME_LIMIT, 1): lambda r: r._limit_stop_time(N_NODES_MASS)}
        creep = self.regime == REGIME_CREEP
        if np.any(creep):  # never arrives (t_F = inf); the others as usual
            t = np.full(self.E_S.shape, np.inf)
            if not np.all(creep):
                t[~creep] = self.take(~creep).stop_time()
            return t
        key = self.regime.astype(np.int16) * 3 + self.tier
        present = np.unique(key) if key.size > 1 else key
        if present.size == 1 and int(present[0]) != 2 and int(present[0]) != 5:
            return rules[(int(present[0]) // 3, int(present[0]) % 3)](self)
        t = np.empty(self.E_S.shape)
        for value in present:
            mask = key == value
            sub = self.take(mask)
            regime, tier = int(value) // 3, int(value) % 3
            if tier == 2:
                x, wt = graded_unit()
                t[mask] = sub.integrand(np.broadcast_to(x, (sub.E_S.size, x.size))) @ wt
            else:
                t[mask] = rules[(regime, tier)](sub)
        return t

    def elapsed(self, w: np.ndarray, case: int = 0) -> np.ndarray:
        """Time from release to the angle at w (array), for one case of this set [s]."""
        one = self.take(np.array([case]))
        w = np.asarray(w, dtype=float)
        x, wt = graded_unit() if one.tier[0] == 2 else gauss_unit(N_NODES_MASS)
        span = 1.0 - w
        nodes = w[:, None] + span[:, None] * x[None, :]
        vals = one.integrand(nodes.reshape(1, -1)).reshape(nodes.shape)
        return span * (vals @ wt)

    def alpha_at(self, w: np.ndarray, case: int = 0) -> np.ndarray:
        """The angle at w for one case [rad]."""
        sigma = self.sigma_m[case] * np.asarray(w) ** 2
        return self.anchor[case] - 2.0 * np.arcsin(sigma)

    def rate_at(self, w: np.ndarray, case: int = 0) -> np.ndarray:
        """alpha_dot = sqrt((E_S - W_F) / M) at w for one case (Eq. 10) [rad/s].

        Computed from sigma = sigma_m w^2 directly (``K = 2 R C sigma``, or ``K_lim + 2 A sigma^2 +
        2 B sigma q`` at the geometric limit), so it stays accurate to rounding as the stop is approached.
        """
        sigma = self.sigma_m[case] * np.asarray(w, dtype=float) ** 2
        q = np.sqrt(1.0 - sigma * sigma)
        sin_alpha = self.sin_a[case] * (1.0 - 2.0 * sigma * sigma) - self.cos_a[case] * 2.0 * sigma * q
        if self.regime[case] != REGIME_FRICTION:
            K = self.K_lim[case] + 2.0 * self.A[case] * sigma * sigma \
                + 2.0 * self.B[case] * sigma * q
        else:
            K = 2.0 * self.R[case] * (self.cos_p[case] * q + self.sin_p[case] * sigma) * sigma
        M = self.m2[case] * self.L1[case] ** 2 * (self.k[case] + sin_alpha * sin_alpha)
        return np.sqrt(np.maximum(K, 0.0)) / np.sqrt(M)

    def remaining_energy(self, alpha: np.ndarray, case: int = 0) -> np.ndarray:
        """E_S - W_F(alpha) without cancellation, for one case [J] (Eq. 9)."""
        alpha = np.asarray(alpha, dtype=float)
        if self.regime[case] != REGIME_FRICTION:
            x = limit_sweep(alpha)
            return self.K_lim[case] + 2.0 * self.A[case] * np.sin(0.5 * x) ** 2 \
                + self.B[case] * np.sin(x)
        half = 0.5 * (self.anchor[case] - alpha)
        # K = 2 R C sigma with C = cos(anchor - phi - half)
        value = 2.0 * self.R[case] * (self.cos_p[case] * np.cos(half) + self.sin_p[case] * np.sin(half)) * np.sin(half)
        return np.maximum(value, 0.0)


# -- peak accelerations: the value and its slope in alpha, and the maximum at a root of the slope ------------

def head_hinge_acceleration(alpha, E, s0, c0, A, B, F1, F2, k, m2, L1, which):
    """u_ddot (``which = 0``) or v_ddot (``which = 1``) at angle alpha of a release [m/s^2], and its derivative
    in alpha [m/s^2/rad] (Table 4, alpha_dot^2 from Eq. 10 and alpha_ddot from Eq. 3/4).

    With ``K = E - A (sin a - s0) - B (c0 - cos a)`` (A = 2 F1 L1, B = 4 F2 L1: Eq. 9), ``d = k + sin^2 a``,
    ``r = alpha_dot^2 = K / (m2 L1^2 d)`` and ``q = alpha_ddot = -r sin a cos a / d - (2 F2 sin a + F1 cos a) /
    (m2 L1 d)``: ``u_ddot = L1 (cos a r + sin a q)``, ``v_ddot = L1 (-sin a r + cos a q)``. Along the motion
    alpha increases, so the jerk d/dt = alpha_dot d/dalpha vanishes where the derivative returned does.
    Scalar and plain ``math`` (compiled as is by :mod:`quickrelease.batch._fast`).
    """
    s = math.sin(alpha)
    c = math.cos(alpha)
    K = E - A * (s - s0) - B * (c0 - c)
    Kp = -A * c - B * s
    if K < 0.0:
        K = 0.0
    return acceleration_terms(s, c, K, Kp, F1, F2, k, m2, L1, which)


def acceleration_terms(s, c, K, Kp, F1, F2, k, m2, L1, which):
    """:func:`head_hinge_acceleration` from ``s = sin(alpha)``, ``c = cos(alpha)``, the remaining energy K >= 0 and
    its slope Kp = dK/dalpha: pure arithmetic, so that the compiled kernels and the array-module (GPU) ones share
    the formula (each computes s, c and K its own way) [m/s^2], [m/s^2/rad]."""
    ml = m2 * L1
    d = k + s * s
    dpd = 2.0 * s * c / d  # d'/d
    r = K / (ml * L1 * d)
    rp = (Kp / (ml * L1) - r * 2.0 * s * c) / d
    Q = 2.0 * F2 * s + F1 * c
    Qp = 2.0 * F2 * c - F1 * s
    q = -r * s * c / d - Q / (ml * d)
    qp = -(rp * s * c + r * (c * c - s * s)) / d + (r * s * c / d) * dpd - Qp / (ml * d) + (Q / (ml * d)) * dpd
    if which == 0:
        return L1 * (c * r + s * q), L1 * (-s * r + c * rp + c * q + s * qp)
    return L1 * (-s * r + c * q), L1 * (-c * r - s * rp - s * q + c * qp)


def refine_peak(lo, hi, E, s0, c0, A, B, F1, F2, k, m2, L1, which):
    """The maximum of |u_ddot| (which 0) or |v_ddot| (which 1) inside [lo, hi] [rad], at the root of its
    slope, when the slope goes from + at lo to - at hi; -1 otherwise [m/s^2].

    The root (of the jerk, see :func:`head_hinge_acceleration`) by the Illinois false position, bracketed,
    to a bracket of 4 ulps or a zero slope; the value is then the acceleration there (no interpolation, so it
    never exceeds the true maximum by more than rounding). :mod:`quickrelease.batch._fast` compiles this very
    function, with its global ``head_hinge_acceleration`` bound to the compiled one.
    """
    g_lo, p_lo = head_hinge_acceleration(lo, E, s0, c0, A, B, F1, F2, k, m2, L1, which)
    g_hi, p_hi = head_hinge_acceleration(hi, E, s0, c0, A, B, F1, F2, k, m2, L1, which)
    f_lo = p_lo if g_lo >= 0.0 else -p_lo
    f_hi = p_hi if g_hi >= 0.0 else -p_hi
    if not (f_lo > 0.0 and f_hi < 0.0):
        return -1.0
    x = 0.5 * (lo + hi)
    side = 0
    for _ in range(200):
        x = hi - f_hi * ((hi - lo) / (f_hi - f_lo))
        if not (lo < x < hi):
            x = 0.5 * (lo + hi)
        g, p = head_hinge_acceleration(x, E, s0, c0, A, B, F1, F2, k, m2, L1, which)
        f = p if g >= 0.0 else -p
        if f == 0.0:
            break
        if f > 0.0:
            lo, f_lo = x, f
            if side == 1:
                f_hi *= 0.5
            side = 1
        else:
            hi, f_hi = x, f
            if side == -1:
                f_lo *= 0.5
            side = -1
        if hi - lo <= 8.8e-16 * max(abs(lo), abs(hi)):
            break
    return abs(head_hinge_acceleration(x, E, s0, c0, A, B, F1, F2, k, m2, L1, which)[0])
