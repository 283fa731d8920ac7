"""Random cases over the valid parameter space, for tests and benchmarks (seeded, reproducible).

Two distributions:

* :func:`random_releases`, the *bench sample*: typical releases (alpha0 in [0.05, 1.3] rad, mass
  factors near the device's, 15% reaching the geometric limit). The kernels are fast and their easy
  rule suffices for most of it.
* :func:`wide_releases`, the *wide sample*: the whole valid space with its hard corners over-weighted
  (the geometric limit reached or just missed, stops just short of pi/2, small and large mass factors,
  releases from nearly flat or nearly upright rhombi, nearly immediate stops, one or both friction forces
  near zero). Speed and accuracy claims are made on both (``quickrelease bench``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["random_releases", "wide_releases", "WIDE_STRATA"]

HALF_PI = 0.5 * np.pi


def _friction_for(E_S, alpha0, alpha_stop, share, L1):
    """F1, F2 [N] that stop a release of energy E_S from alpha0 exactly at alpha_stop (Eq. 8 / 13), a share
    ``share`` of the work done by the head's rail friction F1 and the rest by the hinge friction F2."""
    F1_max = E_S / (2.0 * L1 * (np.sin(alpha_stop) - np.sin(alpha0)))
    F2_max = E_S / (4.0 * L1 * (np.cos(alpha0) - np.cos(alpha_stop)))
    return share * F1_max, (1.0 - share) * F2_max


def random_releases(n: int, seed: int = 0, limit_share: float = 0.15) -> dict[str, np.ndarray]:
    """``n`` random releases: E_S, alpha0, F1, F2, c, m1, m2, L1 (SI), a share of them reaching pi/2.

    E_S log-uniform in [100 J, 100 kJ]; alpha0 uniform in [0.05, 1.3] rad; c in [0.5, 1.2]; m1, m2
    in [100, 2000] kg; L1 in [1, 5] m. The friction is drawn through the stop it causes: a target
    stop angle a fraction U(0.02, 1) of the way from alpha0 to pi/2 and a share of hinge friction
    U(0, 1) on the line of Eq. 13; a share ``limit_share`` of the cases instead gets the friction that
    would stop it exactly at pi/2, scaled down by a factor U(1, 1.44): the rhombus becomes flat first
    (the geometric limit), some just barely.
    """
    rng = np.random.default_rng(seed)
    L1 = rng.uniform(1.0, 5.0, n)
    m1 = rng.uniform(100.0, 2000.0, n)
    m2 = rng.uniform(100.0, 2000.0, n)
    c = rng.uniform(0.5, 1.2, n)
    alpha0 = rng.uniform(0.05, 1.3, n)
    E_S = np.exp(rng.uniform(np.log(100.0), np.log(1e5), n))
    frac = rng.uniform(0.02, 1.0, n)
    share = rng.uniform(0.0, 1.0, n)
    limit = rng.uniform(0.0, 1.0, n) < limit_share
    alpha_stop = np.where(limit, 0.5 * np.pi, alpha0 + np.minimum(frac, 0.999) * (0.5 * np.pi - alpha0))
    F1_max = E_S / (2.0 * L1 * (np.sin(alpha_stop) - np.sin(alpha0)))
    F2_max = E_S / (4.0 * L1 * (np.cos(alpha0) - np.cos(alpha_stop)))
    scale = np.where(limit, 1.0 / rng.uniform(1.0, 1.44, n), 1.0)
    F1 = share * F1_max * scale
    F2 = (1.0 - share) * F2_max * scale
    return {"E_S": E_S, "alpha0": alpha0, "F1": F1, "F2": F2, "c": c, "m1": m1, "m2": m2, "L1": L1}


def _log_uniform(rng, lo, hi, n):
    return np.exp(rng.uniform(np.log(lo), np.log(hi), n))


#: The strata of :func:`wide_releases`: (name, share of the cases, what it draws). Every stratum draws the
#: device (L1 in [0.5, 10] m, m2 log-uniform in [10, 1e4] kg, c in [0.3, 1.5]), E_S log-uniform in
#: [1 J, 10 MJ] and the share of the rail friction's work U(0, 1) unless it says otherwise, and the mass
#: ratio m1/m2 log-uniform in [0.01, 100].
WIDE_STRATA: tuple[tuple[str, float, str], ...] = (
    ("typical", 0.20, "alpha0 U(0.01, 1.5) rad, a stop U(0.02, 0.999) of the way to pi/2"),
    ("limit", 0.15, "friction that would stop exactly at pi/2 scaled down by 1 + 10^U(-13, 0): the rhombus "
                    "becomes flat first, many barely"),
    ("short of the limit", 0.10, "a stop 10^U(-10, -1) rad short of pi/2"),
    ("small mass factor", 0.15, "m1/m2 log-uniform in [1e-5, 1e-2], alpha0 log-uniform in [1e-3, 0.3] rad"),
    ("large mass factor", 0.05, "m1/m2 log-uniform in [100, 1e4]"),
    ("nearly flat or upright", 0.10, "alpha0 within 10^U(-6, -1) rad of pi/2, or log-uniform in [1e-4, 0.05] rad"),
    ("immediate stop", 0.10, "a stop 10^U(-8, -2) of the way from alpha0 to pi/2"),
    ("one force near zero", 0.10, "the rail friction's share of the work 10^U(-12, -2) or 1 - 10^U(-12, -2)"),
    ("both forces near zero", 0.05, "friction 10^U(-12, -2) times what would stop at pi/2: a nearly free "
                                    "flight to the limit"),
)


def wide_releases(n: int, seed: int = 0, strata: bool = False) -> dict[str, np.ndarray]:
    """``n`` random releases over the whole valid space, its hard corners over-weighted (the *wide sample*).

    Same keys as :func:`random_releases` (SI), so ``batch.stop_time(**wide_releases(n))`` works; with ``strata``
    also ``stratum`` (the index into :data:`WIDE_STRATA` each case was drawn from). The cases are drawn stratum
    by stratum in the shares of :data:`WIDE_STRATA` (a case's stratum is itself drawn: multinomial counts)
    and the friction again through the stop it causes (Eq. 8 and 13),
    so every case is valid: E_S > 0, alpha0 in (0, pi/2), F1, F2 >= 0, finite.
    """
    rng = np.random.default_rng(seed)
    shares = np.array([s for _, s, _ in WIDE_STRATA])
    stratum = rng.choice(len(WIDE_STRATA), size=n, p=shares / shares.sum())
    L1 = rng.uniform(0.5, 10.0, n)
    m2 = _log_uniform(rng, 10.0, 1e4, n)
    ratio = _log_uniform(rng, 0.01, 100.0, n)
    c = rng.uniform(0.3, 1.5, n)
    E_S = _log_uniform(rng, 1.0, 1e7, n)
    alpha0 = rng.uniform(0.01, 1.5, n)
    share = rng.uniform(0.0, 1.0, n)
    frac = rng.uniform(0.02, 0.999, n)
    alpha_stop = alpha0 + frac * (HALF_PI - alpha0)
    scale = np.ones(n)

    def pick(name):
        return stratum == [s for s, _, _ in WIDE_STRATA].index(name)

    s = pick("limit")
    alpha_stop[s] = HALF_PI
    scale[s] = 1.0 / (1.0 + 10.0 ** rng.uniform(-13.0, 0.0, s.sum()))
    s = pick("short of the limit")
    alpha0[s] = rng.uniform(0.01, 1.4, s.sum())
    alpha_stop[s] = HALF_PI - 10.0 ** rng.uniform(-10.0, -1.0, s.sum())
    s = pick("small mass factor")
    ratio[s] = _log_uniform(rng, 1e-5, 1e-2, s.sum())
    alpha0[s] = _log_uniform(rng, 1e-3, 0.3, s.sum())
    alpha_stop[s] = alpha0[s] + frac[s] * (HALF_PI - alpha0[s])
    s = pick("large mass factor")
    ratio[s] = _log_uniform(rng, 100.0, 1e4, s.sum())
    s = pick("nearly flat or upright")
    flat = rng.uniform(0.0, 1.0, n) < 0.5
    alpha0[s & flat] = HALF_PI - 10.0 ** rng.uniform(-6.0, -1.0, (s & flat).sum())
    alpha0[s & ~flat] = _log_uniform(rng, 1e-4, 0.05, (s & ~flat).sum())
    alpha_stop[s] = alpha0[s] + frac[s] * (HALF_PI - alpha0[s])
    s = pick("immediate stop")
    alpha_stop[s] = alpha0[s] + 10.0 ** rng.uniform(-8.0, -2.0, s.sum()) * (HALF_PI - alpha0[s])
    s = pick("one force near zero")
    tiny = 10.0 ** rng.uniform(-12.0, -2.0, s.sum())
    share[s] = np.where(rng.uniform(0.0, 1.0, s.sum()) < 0.5, tiny, 1.0 - tiny)
    s = pick("both forces near zero")
    alpha_stop[s] = HALF_PI
    scale[s] = 10.0 ** rng.uniform(-12.0, -2.0, s.sum())
    F1, F2 = _friction_for(E_S, alpha0, alpha_stop, share, L1)
    m1 = ratio * m2
    out = {"E_S": E_S, "alpha0": alpha0, "F1": F1 * scale, "F2": F2 * scale, "c": c, "m1": m1, "m2": m2, "L1": L1}
    if strata:
        out["stratum"] = stratum
    return out
