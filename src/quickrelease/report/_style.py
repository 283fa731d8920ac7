"""The figures' style, applied per figure: the user's matplotlib settings are never changed.

Every figure function of the package is wrapped in :func:`styled`, which draws it inside
``matplotlib.rc_context(STYLE)``; :func:`figure` makes the Figure (the user's own one when given).
Nothing here imports matplotlib until a figure is drawn.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import wraps
from typing import Any, TypeVar

STYLE: dict[str, Any] = {
    "font.size": 9, "axes.titlesize": 9, "axes.labelsize": 9, "legend.fontsize": 8,
    "xtick.labelsize": 8, "ytick.labelsize": 8, "figure.titlesize": 10, "axes.grid": True, "grid.alpha": 0.3,
    "lines.linewidth": 1.4, "svg.hashsalt": "quickrelease", "figure.dpi": 100,
    "svg.fonttype": "none",  # text stays text: searchable, smaller, no glyph definitions (ids) repeated
}
COLORS = {"a": "#1f4e79", "b": "#c0504d", "c": "#4f8a3c", "d": "#7f7f7f"}
#: The font sizes a figure may use: every text of every figure is one of these (no figure sets its own).
FONT_SIZES = frozenset(v for k, v in STYLE.items() if k.endswith("size"))

_POWERS = {"^2": "²", "^3": "³", "^4": "⁴", "^-1": "⁻¹", "^-2": "⁻²"}


def unit_text(unit: str) -> str:
    """A unit as figures and reports write it: powers as superscripts (``m/s^2`` -> ``m/s²``), ``-`` for a
    dimensionless quantity kept; one way everywhere."""
    for plain, sup in _POWERS.items():
        unit = unit.replace(plain, sup)
    return unit


def per(y_unit: str, x_unit: str) -> str:
    """The unit of a slope dy/dx: ``N/kN``, ``%/cm``; a dimensionless numerator gives ``1/cm``, a
    dimensionless denominator the numerator's unit."""
    y_unit, x_unit = unit_text(y_unit), unit_text(x_unit)
    if x_unit in ("-", ""):
        return y_unit
    return f"{'1' if y_unit in ('-', '') else y_unit}/{x_unit}"

F = TypeVar("F", bound=Callable[..., Any])


def styled(func: F) -> F:
    """``func`` (a figure function) run inside ``matplotlib.rc_context(STYLE)``: the package's fonts, grid
    and line widths for its figures, and the user's ``rcParams`` exactly as they were afterwards."""

    @wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        import matplotlib

        with matplotlib.rc_context(STYLE):
            return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]


def figure(width: float, height: float, fig: Any = None, **margins: float):
    """A Figure of ``width`` x ``height`` inches with fixed margins (fractions of the figure; much cheaper
    to save than a layout engine), or the user's ``fig`` (a Figure or SubFigure, e.g. from
    ``plt.figure()`` or ``fig.subfigures()``), drawn into with the same margins and its own size."""
    if fig is None:
        from matplotlib.figure import Figure

        fig = Figure(figsize=(width, height))
    fig.subplots_adjust(**{"left": 0.12, "right": 0.97, "bottom": 0.14, "top": 0.9, **margins})
    return fig


def panels(width: float, height: float, shape: tuple[int, int] = (1, 1), *, fig: Any = None, ax: Any = None,
           subplots: dict[str, Any] | None = None, **margins: float):
    """A figure function's figure and panels: ``(figure, axes)``.

    Without ``ax``: :func:`figure` (a new Figure of ``width`` x ``height`` inches, or the user's ``fig``) and
    ``fig.subplots(*shape, **subplots)``. With ``ax``, the user's own axes, drawn into as they are (no size, no
    margins, no sharing set): one Axes for a one-panel figure, else a sequence (or array) of
    ``shape[0] * shape[1]`` Axes in reading order; the figure returned is the one holding them. ``axes`` comes
    back shaped as ``subplots`` would give it: an Axes for (1, 1), a 1-D array for one row or column, else 2-D.
    """
    import numpy as np

    from ..errors import QuickReleaseError

    count = shape[0] * shape[1]
    if ax is None:
        fig = figure(width, height, fig, **margins)
        return fig, fig.subplots(*shape, **(subplots or {}))
    if fig is not None:
        raise QuickReleaseError("give fig (a Figure to fill) or ax (axes to draw into), not both")
    given = [ax] if hasattr(ax, "plot") else list(np.ravel(np.asarray(ax, dtype=object)))
    if len(given) != count or not all(hasattr(a, "plot") for a in given):
        raise QuickReleaseError(f"ax: {len(given)} object(s) given; this figure draws {count} panel(s): give "
                                f"{count} matplotlib Axes")
    if count == 1:
        return given[0].figure, given[0]
    axes = np.empty(count, dtype=object)
    axes[:] = given
    return given[0].figure, axes if 1 in shape else axes.reshape(shape)

