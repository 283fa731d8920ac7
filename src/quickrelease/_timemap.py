"""The time map of one release, t(w), as a piecewise Chebyshev series, and its inverse w(t).

The energy solution (Eq. 9-10) gives time as an integral over the angle; after the substitution of
:mod:`quickrelease.device._kernels` the integrand ``f(w) = dt/dw`` is smooth on ``w in [0, 1]`` (w = 1 at
release, w = 0 at the end of the motion) and ``t(w) = int_w^1 f(s) ds``. Interpolating f at Chebyshev
points and integrating the series term by term gives t(w) to rounding error everywhere at once, so the
state at any set of times costs a few Newton steps on a polynomial instead of a quadrature per time.

Panels: one Chebyshev series of degree 32 suffices for ordinary cases; where the integrand has a nearly
singular factor close to the interval (a stop close to the flat rhombus with little rail friction), the
interval is bisected until every panel's series has converged (its last coefficients below ``tol`` of
its largest), which refines towards the near-singularity geometrically.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.polynomial import chebyshev as C

__all__ = ["TimeMap"]

DEGREE = 32
TOL = 1e-14
MAX_PANELS = 256


def _newton_step(x, g, c, h, target) -> tuple[np.ndarray, float]:
    """One Newton step on G(x) = target within a panel; returns the new x and the largest step."""
    slope = h * C.chebval(x, c)
    # f = dt/dw vanishes at w = 0 when the motion ends at the flat rhombus with speed left: no step there
    with np.errstate(divide="ignore", invalid="ignore"):
        step = np.where(slope > 0.0, (C.chebval(x, g) - target) / slope, 0.0)
    return np.clip(x - step, -1.0, 1.0), float(np.max(np.abs(step))) if step.size else 0.0


class TimeMap:
    """t(w) for w in [0, 1] from the smooth integrand f = dt/dw (positive on the interval).

    Parameters
    ----------
    f : callable
        Vectorized integrand dt/dw [s].
    degree : int
        Degree of each panel's Chebyshev series.
    tol : float
        A panel is accepted when its last three coefficients are below ``tol`` times its largest.
    """

    def __init__(self, f: Callable[[np.ndarray], np.ndarray], degree: int = DEGREE, tol: float = TOL,
                 max_panels: int = MAX_PANELS) -> None:
        leaves: list[tuple[float, float, np.ndarray]] = []
        stack = [(0.0, 1.0)]
        while stack:
            a, b = stack.pop()
            half = 0.5 * (b - a)
            coef = C.chebinterpolate(lambda x, a=a, half=half: f(a + half * (x + 1.0)), degree)
            scale = float(np.max(np.abs(coef)))
            tail = float(np.max(np.abs(coef[-3:])))
            if tail <= tol * scale or len(leaves) + len(stack) >= max_panels or b - a < 1e-12:
                leaves.append((a, b, coef))
            else:
                mid = a + half
                stack.extend([(mid, b), (a, mid)])
        leaves.sort(key=lambda leaf: leaf[0])
        self.edges = np.array([leaf[0] for leaf in leaves] + [1.0])
        """Panel edges in w, ascending (edges[0] = 0, edges[-1] = 1)."""
        self.coef = [leaf[2] for leaf in leaves]
        """Chebyshev coefficients of f on each panel (local variable x in [-1, 1])."""
        self.half = 0.5 * np.diff(self.edges)
        # G_i(x) = int_{1}^{x} f half dx' (<= 0): minus the time from the point x to the panel's right end
        self.integral_coef = [C.chebint(c, lbnd=1.0, scl=h) for c, h in zip(self.coef, self.half, strict=True)]
        duration = np.array([-C.chebval(-1.0, g) for g in self.integral_coef])
        # time at the panel edges: t(1) = 0, accumulated from the right
        self.edge_times = np.concatenate([np.cumsum(duration[::-1])[::-1], [0.0]])
        """t at each edge [s]; ``edge_times[0]`` is the time to the end of the motion."""

    @property
    def total(self) -> float:
        """t(0): the time from release to the end of the motion [s]."""
        return float(self.edge_times[0])

    @property
    def panels(self) -> int:
        return len(self.coef)

    def _panel_of_w(self, w: np.ndarray) -> np.ndarray:
        return np.clip(np.searchsorted(self.edges, w, side="right") - 1, 0, self.panels - 1)

    def time(self, w) -> np.ndarray:
        """t(w), the time from release to the angle at w [s]."""
        w = np.asarray(w, dtype=float)
        out = np.empty(w.shape)
        idx = self._panel_of_w(w)
        for i in np.unique(idx):
            m = idx == i
            x = (w[m] - self.edges[i]) / self.half[i] - 1.0
            out[m] = self.edge_times[i + 1] - C.chebval(x, self.integral_coef[i])
        return out

    def invert(self, t) -> np.ndarray:
        """w at the times t (clipped to [0, t(0)]): Newton's method on each panel's series."""
        t = np.clip(np.asarray(t, dtype=float), 0.0, self.total)
        w = np.empty(t.shape)
        # edge_times is decreasing: panel i holds times in [edge_times[i+1], edge_times[i]]
        idx = np.clip(self.panels - np.searchsorted(self.edge_times[::-1], t, side="left"), 0, self.panels - 1)
        for i in np.unique(idx):
            m = idx == i
            target = self.edge_times[i + 1] - t[m]  # G_i(x) = -(time from x to the right end)
            g, c = self.integral_coef[i], self.coef[i]
            h = self.half[i]
            # start from a table of the panel's own series, then Newton (quadratic: once a step is below
            # 1e-9, one more gives rounding level)
            x_table = np.linspace(-1.0, 1.0, 65)
            x = np.interp(target, C.chebval(x_table, g), x_table)
            for _ in range(20):
                x, size = _newton_step(x, g, c, h, target)
                if size <= 1e-9:
                    x, _ = _newton_step(x, g, c, h, target)
                    break
            w[m] = self.edges[i] + h * (x + 1.0)
        return w
