"""Linear laws over a campaign's tests, shared by the device's campaign (:mod:`quickrelease.studies.campaign`)
and the building's (:mod:`quickrelease.studies.building_campaign`): weighted least squares of a straight line
with its intervals (``LinearLaw``, ``fit_line``, ``weights_or_none``), the tests of a campaign file
(``iter_tests``) and the panel that draws a law (``law_panel``). Both campaigns import it; neither imports the
other's module for it (the cycle campaign <-> building_campaign of issue 23)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import QuickReleaseError
from ..io.case import CaseFileError

__all__ = ["LinearLaw", "fit_line", "weights_or_none", "iter_tests", "law_panel"]


def _t_quantile(dof: int) -> float:
    from scipy.special import stdtrit

    return float(stdtrit(dof, 0.975))


def _p_value(t: float, dof: int) -> float:
    from scipy.special import stdtr

    return float(2.0 * stdtr(dof, -abs(t)))


@dataclass(frozen=True)
class LinearLaw:
    """``y = intercept + slope x`` fitted over the tests of a campaign by (weighted) least squares: a
    quantity (a friction force, a period, a damping ratio) against a variable (the push force, the angle,
    the release amplitude). The device's friction laws and the building's amplitude laws are both these."""

    quantity: str
    variable: str
    intercept: float
    slope: float
    covariance: np.ndarray
    """Of (intercept, slope)."""
    dof: int
    chi2_reduced: float
    """Weighted: chi-square over dof (above 1: more scatter than the standard errors explain, and the
    covariance is inflated by it); unweighted: the residual variance."""
    weighted: bool
    x_range: tuple[float, float]

    @property
    def intercept_se(self) -> float:
        return float(math.sqrt(self.covariance[0, 0]))

    @property
    def slope_se(self) -> float:
        return float(math.sqrt(self.covariance[1, 1]))

    @property
    def t_statistic(self) -> float:
        return self.slope / self.slope_se if self.slope_se > 0 else math.inf

    @property
    def p_value(self) -> float:
        """Two-sided p-value of slope = 0 (Student t, dof = tests - 2)."""
        return _p_value(self.t_statistic, self.dof)

    @property
    def significant(self) -> bool:
        """The slope differs from 0 at the 5% level."""
        return self.p_value < 0.05

    def band(self, x) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The law and its 95% confidence band (of the mean) at x: (mean, low, high), in y's unit."""
        x = np.asarray(x, dtype=float)
        mean = self.intercept + self.slope * x
        c = self.covariance
        var = c[0, 0] + 2.0 * c[0, 1] * x + c[1, 1] * x * x
        half = _t_quantile(self.dof) * np.sqrt(np.maximum(var, 0.0))
        return mean, mean - half, mean + half

    def summary(self) -> dict[str, Any]:
        return {"quantity": self.quantity, "variable": self.variable,
                "law": f"{self.quantity} = a + b {self.variable}", "a": self.intercept, "a_se": self.intercept_se,
                "b": self.slope, "b_se": self.slope_se, "t": self.t_statistic, "p_value": self.p_value,
                "significant_5pct": self.significant, "dof": self.dof, "chi2_reduced": self.chi2_reduced,
                "weighted": self.weighted, "x_range": list(self.x_range)}


def _wls(X: np.ndarray, y: np.ndarray, se: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, int, float]:
    """Coefficients, covariance, dof and reduced chi-square of (weighted) least squares."""
    n, p = X.shape
    dof = n - p
    w = np.ones(n) if se is None else 1.0 / se**2
    # least squares on the weighted rows, the columns scaled to unit norm (an SVD, not the normal equations:
    # a push force in N beside a constant column, or weights many decades apart, leave them near singular)
    A = X * np.sqrt(w)[:, None]
    norms = np.linalg.norm(A, axis=0)
    norms = np.where(norms > 0, norms, 1.0)
    beta = np.linalg.lstsq(A / norms, y * np.sqrt(w), rcond=None)[0] / norms
    r = y - X @ beta
    chi2 = float(np.sum(w * r * r))
    red = chi2 / dof if dof > 0 else float("nan")
    cov = np.linalg.pinv((A / norms).T @ (A / norms), hermitian=True) / np.outer(norms, norms)
    if se is None:
        cov = cov * red  # residual variance
    else:
        cov = cov * max(1.0, red)  # inflate when the scatter exceeds the standard errors (Birge ratio)
    return beta, cov, dof, red


def weights_or_none(se) -> np.ndarray | None:
    """The standard errors as an array when every one is positive and finite (a weighted law), else None
    (an unweighted law: one missing or zero standard error would otherwise take all the weight)."""
    se = list(se)
    if any(s is None or not (math.isfinite(s) and s > 0) for s in se):
        return None
    return np.array(se, dtype=float)


def fit_line(x, y, se=None, *, quantity: str = "y", variable: str = "x", law_type: type[LinearLaw] = LinearLaw
             ) -> LinearLaw:
    """Fit ``y = a + b x`` by least squares, weighted by ``1 / se^2`` when ``se`` is given (see
    :func:`weights_or_none`), with the covariance inflated by the reduced chi-square when it exceeds 1.

    Raises
    ------
    QuickReleaseError
        With fewer than three points (no degree of freedom for the scatter) or a constant x.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.ndim != 1 or x.shape != y.shape or x.size < 3:
        raise QuickReleaseError(f"{quantity} against {variable}: {x.size} point(s); a law needs at least 3")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise QuickReleaseError(f"{quantity} against {variable}: non-finite values")
    if np.ptp(x) == 0:
        raise QuickReleaseError(f"every test has the same {variable}: no law in {variable} can be fitted")
    se = None if se is None else np.asarray(se, dtype=float)
    beta, cov, dof, red = _wls(np.column_stack([np.ones_like(x), x]), y, se)
    return law_type(quantity=quantity, variable=variable, intercept=float(beta[0]), slope=float(beta[1]),
                    covariance=cov, dof=dof, chi2_reduced=red, weighted=se is not None,
                    x_range=(float(x.min()), float(x.max())))


def iter_tests(tests: list[Any], source: str, prefix: str):
    """Each ``[[tests]]`` table of a campaign file as (name, where, table): a table, named (default: prefix
    and its number; a string or an integer, not empty nor only spaces; line breaks and escapes are shown
    harmless where the name is written) once only; ``where`` names the file and the test for messages.
    CaseFileError else."""
    names = set()
    for i, entry in enumerate(tests):
        if not isinstance(entry, dict):
            raise CaseFileError(f"{source}: tests[{i}] is not a table")
        name = entry.get("name", f"{prefix}{i + 1}")
        if isinstance(name, bool) or not isinstance(name, str | int):
            raise CaseFileError(f"{source}: tests[{i}] name = {name!r}: expected a test name (a string), e.g. "
                                f"'{prefix}{i + 1}'")
        name = str(name)
        if not name.strip():  # the name heads the test's lines in messages, tables and the report: it is seen
            raise CaseFileError(f"{source}: tests[{i}] name = {name!r}: expected a test name with a character "
                                f"other than a space, e.g. '{prefix}{i + 1}'")
        where = f"{source}: test {name}"
        if name in names:
            raise CaseFileError(f"{where}: the name is used twice")
        names.add(name)
        yield name, where, entry


def law_panel(ax, law: LinearLaw, x, y, yerr, names, *, x_scale: float = 1.0, y_scale: float = 1.0,
              x_label: str = "", y_label: str = "", slope_unit: str = "", name: str | None = None) -> None:
    """One panel of a campaign figure: the tests (values ``y`` at ``x`` with error bars ``yerr``, one value
    or (low, high) rows of distances), the fitted law and its 95% band, the slope and its p-value in the
    title (under ``name``, default the law's quantity). ``x_scale`` and ``y_scale`` convert SI to the
    plotted units."""
    from ..report._style import STYLE
    from ..report.plots import _COLORS, user_label

    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    span = law.x_range[1] - law.x_range[0]
    grid = np.linspace(law.x_range[0] - 0.05 * span, law.x_range[1] + 0.05 * span, 100)
    mean, lo, hi = law.band(grid)
    ax.fill_between(grid * x_scale, lo * y_scale, hi * y_scale, color=_COLORS["a"], alpha=0.18, lw=0,
                    label="95% band")
    ax.plot(grid * x_scale, mean * y_scale, color=_COLORS["a"], label="fitted law")
    ax.errorbar(x * x_scale, y * y_scale, yerr=np.asarray(yerr, dtype=float) * y_scale, fmt="o", ms=4,
                color=_COLORS["b"], capsize=2, label="tests (95% interval)")
    for xi, yi, test in zip(x, y, names, strict=True):
        user_label(ax, "annotate", test, (xi * x_scale, yi * y_scale), textcoords="offset points", xytext=(4, 3),
                   fontsize=STYLE["legend.fontsize"])
    verdict = "significant" if law.significant else "not significant"
    factor = y_scale / x_scale
    ax.set_title(f"{name or law.quantity}: slope {law.slope * factor:.3g} ± {law.slope_se * factor:.2g} {slope_unit}\n"
                 f"(p = {law.p_value:.2g}, {verdict} at 5%)", fontsize=STYLE["legend.fontsize"])
    ax.set_xlabel(x_label)
    ax.set_ylabel(y_label)
