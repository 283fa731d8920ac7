"""Random cases over the valid parameter space, for tests and benchmarks (seeded, reproducible)."""

from __future__ import annotations

import numpy as np

__all__ = ["random_releases"]


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
