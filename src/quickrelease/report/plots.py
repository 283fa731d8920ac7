"""Figures: the paper's Fig. 13, 14 and 15, the identification curve, the strain-energy breakdown.

Every function takes results and returns a matplotlib ``Figure`` (never calls ``show``);
:func:`save_figure` writes it as PNG and SVG, atomically. The ``*_data`` functions return
the numbers behind a figure, so tests can check them without reading pixels.
Uses the object-oriented API (no pyplot state); matplotlib is imported on first use.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..device.identify import Identification
from ..device.response import Response
from ..device.statics import StrainEnergy
from ._style import COLORS, STYLE, figure, panels, styled, unit_text

__all__ = [
    "fig13", "fig14", "fig15", "identification_figure", "strain_energy_figure", "fit_figure", "save_figure",
    "user_text", "user_label",
]

_STYLE, _COLORS, _figure = STYLE, COLORS, figure  # the names the figure modules import


#: Control characters but newline and tab: no glyph draws them, and XML (the SVG) forbids them.
_CONTROL = dict.fromkeys([*range(0x00, 0x09), *range(0x0B, 0x20), *range(0x7F, 0xA0)], "?")


def user_text(text: Any) -> str:
    """User text (a title, a test name) made safe to draw: control characters shown as '?'.

    Draw it with ``parse_math=False`` (see :func:`user_label`): a ``$`` in a name is a dollar sign, not
    the start of matplotlib mathtext (an unbalanced or invalid formula would stop the figure)."""
    return str(text).translate(_CONTROL)


def user_label(ax_or_fig, method: str, text: Any, *args: Any, **kwargs: Any):
    """``ax_or_fig.<method>(text, ...)`` for user text: cleaned by :func:`user_text`, mathtext off."""
    return getattr(ax_or_fig, method)(user_text(text), *args, parse_math=False, **kwargs)


def _mark_stop(ax, response: Response) -> None:
    ax.axvline(response.stop_time, color=_COLORS["d"], lw=0.8, ls="--",
               label=f"stop $t_F$ = {response.stop_time:.4f} s")


@styled
def fig13(response: Response, fig=None, ax=None):
    """Fig. 13: (a) position angle, (b) angular velocity, (c) angular acceleration, (d) energy balance vs time.

    ``fig``: a Figure or SubFigure to fill; ``ax``: four Axes to draw into instead (a 2 x 2 array or a list in
    reading order; no title over them). Returns the figure."""
    fig, axes = panels(7.0, 5.0, (2, 2), fig=fig, ax=ax, subplots={"sharex": True}, left=0.09, right=0.98,
                       bottom=0.09, top=0.88, wspace=0.28, hspace=0.28)
    titled = ax is None  # the user's axes get no title over them (``ax`` is reused below)
    r = response
    (a, b), (c, d) = axes
    a.plot(r.t, r.alpha, color=_COLORS["a"])
    a.set_ylabel(r"$\alpha$ [rad]")
    a.set_title("(a) position angle")
    b.plot(r.t, r.alpha_dot, color=_COLORS["a"])
    b.set_ylabel(r"$\dot\alpha$ [rad/s]")
    b.set_title("(b) angular velocity")
    c.plot(r.t, r.alpha_ddot, color=_COLORS["a"])
    c.set_ylabel(r"$\ddot\alpha$ [rad/s$^2$]")
    c.set_title("(c) angular acceleration")
    d.plot(r.t, r.kinetic_energy / 1e3, color=_COLORS["a"], label="kinetic $E_K$")
    d.plot(r.t, r.dissipated_energy / 1e3, color=_COLORS["b"], label="dissipated $W_F$")
    d.plot(r.t, (r.kinetic_energy + r.dissipated_energy) / 1e3, color=_COLORS["c"], ls="--",
           label="$E_K + W_F$")
    d.axhline(r.stored_energy / 1e3, color=_COLORS["d"], lw=0.8, ls=":", label="$E_S$")
    d.set_ylabel("energy [kJ]")
    d.set_title("(d) energy balance")
    for ax in (c, d):
        ax.set_xlabel("time $t$ [s]")
    for ax in axes.flat:
        _mark_stop(ax, r)
        if ax is not d:
            ax.legend(loc="best")
    # (d): every curve lies between 0 and E_S and crosses the panel; the legend goes in room made above E_S
    # (two columns, the stop line named in the other panels), where it covers no curve
    handles, labels = d.get_legend_handles_labels()
    keep = [k for k, text in enumerate(labels) if not text.startswith("stop")]
    headroom(d)
    d.legend([handles[k] for k in keep], [labels[k] for k in keep], loc="upper left", ncol=2)
    if titled:
        fig.suptitle(f"Release response ({r.method}, c = {r.mass_factor:.4g}): "
                     f"$t_F$ = {r.stop_time:.4f} s, $\\alpha_F$ = {r.alpha_final:.4f} rad")
    return fig


@styled
def fig14(response: Response, fig=None, ax=None):
    """Fig. 14: (a) retraction u and opening v, (b) their velocities, vs time. ``ax``: two Axes to draw into.
    Returns the figure."""
    fig, (a, b) = panels(7.0, 2.8, (1, 2), fig=fig, ax=ax, subplots={"sharex": True}, left=0.08, right=0.98,
                         bottom=0.16, top=0.9, wspace=0.28)
    r = response
    a.plot(r.t, r.u, color=_COLORS["a"], label="longitudinal $u$")
    a.plot(r.t, r.v, color=_COLORS["b"], label="transverse $v$")
    a.set_ylabel("displacement [m]")
    a.set_title("(a) linear displacement")
    b.plot(r.t, r.u_dot, color=_COLORS["a"], label=r"longitudinal $\dot u$")
    b.plot(r.t, r.v_dot, color=_COLORS["b"], label=r"transverse $\dot v$")
    b.set_ylabel("velocity [m/s]")
    b.set_title("(b) linear velocity")
    for ax in (a, b):
        ax.set_xlabel("time $t$ [s]")
        _mark_stop(ax, r)
        headroom(ax, 0.38)
        ax.legend(loc="upper left")
    return fig


@styled
def fig15(responses: Response | list[Response], n_markers: int = 40, fig=None, ax=None):
    """Fig. 15: state diagram, numerical solutions (markers) with the analytic curve of Eq. 10 (a line drawn
    on top of them, so that it stays visible where the markers lie on it).

    Each response's legend entry gives its largest distance from the curve, as the energy residual relative
    to the stored energy, ``max |E_K + W_F - E_S| / E_S`` (dimensionless; see
    :meth:`quickrelease.device.response.Response.state_diagram`, which computes what this draws).
    ``ax``: an Axes to draw into. Returns the figure.
    """
    responses = [responses] if isinstance(responses, Response) else list(responses)
    fig, ax = panels(4.6, 3.4, fig=fig, ax=ax, left=0.14, bottom=0.14)
    diagrams = [resp.state_diagram() for resp in responses]  # computed by the response (device.response)
    ax.plot(diagrams[0]["curve_alpha"], diagrams[0]["curve_alpha_dot"], color="black", lw=0.9, zorder=3,
            label="analytic, Eq. 10")
    markers = [("o", _COLORS["b"]), ("x", _COLORS["a"]), ("s", _COLORS["c"])]
    for k, (resp, data) in enumerate(zip(responses, diagrams, strict=True)):
        step = max(1, data["alpha"].size // n_markers)
        name = {"rk": f"Runge-Kutta ({resp.stats.get('rk_method', 'DOP853')})",
                "explicit": f"Table 6, dt = {1e3 * resp.stats.get('dt', 0.0):g} ms",
                "energy": "energy solution"}[resp.method]
        marker, color = markers[k % len(markers)]
        idx = np.arange(k * step // max(len(responses), 1), data["alpha"].size, step)
        residual = np.max(data["energy_residual"]) / resp.stored_energy
        ax.plot(data["alpha"][idx], data["alpha_dot"][idx], marker, ms=4.5, mfc="none", color=color, zorder=2,
                label=f"{name}: {residual:.1e}")
    ax.set_xlabel(r"position angle $\alpha$ [rad]")
    ax.set_ylabel(r"angular velocity $\dot\alpha$ [rad/s]")
    ax.set_title("Response state diagram")
    ax.legend(loc="lower left", title=r"distance from Eq. 10: max $|E_K + W_F - E_S|\,/\,E_S$ [-]",
              title_fontsize=_STYLE["legend.fontsize"])
    return fig


@styled
def identification_figure(ident: Identification, fig=None, ax=None):
    """Stop time along the line of Eq. 13, with the measured t_F and the identified point. ``ax``: an Axes
    to draw into. Returns the figure."""
    data = ident.line_curve()  # computed by the identification (device.identify)
    fig, ax = panels(4.6, 3.4, fig=fig, ax=ax, left=0.14, bottom=0.15)
    ax.plot(data["F2_ratio"], data["stop_time"], color=_COLORS["a"], label="model $t_F$ on Eq. 13")
    ax.axhline(ident.stop_time, color=_COLORS["d"], ls="--", lw=0.9, label=f"measured $t_F$ = {ident.stop_time:g} s")
    ax.plot([ident.F2_ratio], [ident.stop_time + ident.stop_time_residual], "o", color=_COLORS["b"],
            label=f"identified: $F_1$ = {ident.F1:.1f} N, $F_2$ = {ident.F2:.1f} N")
    ax.set_xlabel(r"$F_2 / F_2^*$ [-]   ($F_1 = F_1^* (1 - F_2/F_2^*)$)")
    ax.set_ylabel("stop time $t_F$ [s]")
    ax.set_title("Identification of the friction forces")
    ax.legend(loc="best")
    return fig


@styled
def strain_energy_figure(strain: StrainEnergy, fig=None, ax=None):
    """Bar chart of the six terms of Eq. 2, grouped by member and coloured by effect. ``ax``: an Axes to draw
    into. Returns the figure."""
    terms = strain.terms()
    labels = {"axial_E1": "E1 axial", "axial_E2": "E2 axial", "axial_E3": "E3 axial", "axial_E4": "E4 (fuse) axial",
              "bending_E2": "E2 bending", "shear_E2": "E2 shear"}
    colors = {"axial": _COLORS["a"], "bending": _COLORS["b"], "shear": _COLORS["c"]}
    fig, ax = panels(5.6, 3.2, fig=fig, ax=ax, left=0.2, right=0.98, bottom=0.14, top=0.84)
    names = list(terms)
    values = [terms[n] for n in names]
    bars = ax.barh([labels[n] for n in names], values, color=[colors[n.split("_")[0]] for n in names])
    for bar, value in zip(bars, values, strict=True):
        label = f" {value:.0f} J ({100 * value / strain.total:.1f}%)"
        ax.text(bar.get_width(), bar.get_y() + bar.get_height() / 2, label, va="center",
                fontsize=_STYLE["legend.fontsize"])
    ax.invert_yaxis()
    ax.set_xlabel("strain energy [J]")
    ax.set_xlim(0, max(values) * 1.35)
    ax.set_title(f"Stored strain energy (Eq. 2): $E_S$ = {strain.total:.1f} J\n"
                 f"at P = {strain.forces.P / 1e3:.0f} kN, $\\alpha_0$ = {strain.forces.alpha0:.4g} rad")
    return fig


@styled
def fit_figure(result, fig=None, ax=None):
    """Measured and fitted channels of a fit to a record, each with its residuals (the band shaded is +-2 sigma,
    sigma the channel's noise level: about 95% of the residuals of a good fit lie inside it).

    ``result`` is a :class:`quickrelease.studies.fit.FitResult` with a record. ``ax``: two Axes per channel to draw
    into (the channel, then its residuals, channel after channel). Returns the figure.
    """
    from ..io.records import CHANNELS

    names = list(result.record.channels)
    n = len(names)
    fig, given, grid = record_panels(n, 2.6, fig, ax, left=0.11)
    titled = given is None
    t_fine, curves = result.model_curves()
    share = None
    t_rel = result.release_time
    for k, name in enumerate(names):
        ch = result.record.channels[name]
        unit = unit_text(CHANNELS[name][1])
        top, bottom, share = record_axes(fig, given, grid, k, share)
        top.plot(ch.t, ch.values, ".", ms=1.6, color=_COLORS["d"], alpha=0.6, label="measured")
        top.plot(t_fine, curves[name], color=_COLORS["a"], lw=1.2, label="fitted model")
        top.set_ylabel(f"{name} [{unit}]")
        sigma = result.noise[name]
        resid = ch.values - result.fitted[name]
        bottom.axhspan(-2 * sigma, 2 * sigma, color=_COLORS["c"], alpha=0.15, lw=0, label="±2σ (noise)")
        bottom.plot(ch.t, resid, ".", ms=1.4, color=_COLORS["b"], label="residual")
        bottom.set_ylabel(f"residual [{unit}]")
        for ax in (top, bottom):
            ax.axvline(t_rel, color=_COLORS["d"], lw=0.8, ls=":", label="release" if ax is top else None)
            ax.axvline(t_rel + result.stop_time, color=_COLORS["d"], lw=0.8, ls="--",
                       label="stop $t_F$" if ax is top else None)
            if ax is not bottom or k < n - 1:
                ax.tick_params(labelbottom=False)
        headroom(top)
        _joint_legend(top, bottom, loc="upper right", ncol=3)
        top.set_title(f"{name}: rms residual {result.residual_rms[name]:.3g} {unit}, noise {sigma:.3g} {unit} "
                      f"({result.noise_source[name]})", fontsize=_STYLE["legend.fontsize"])
    bottom.set_xlabel("record time [s]")
    if titled:
        fig.suptitle(f"Fit to the record: $F_1$ = {result.F1:.1f} ± {result.std_errors['F1']:.2g} N, "
                     f"$F_2$ = {result.F2:.1f} ± {result.std_errors['F2']:.2g} N")
    return fig


def record_panels(n: int, per_channel: float, fig, ax, left: float):
    """The layout of a record figure of ``n`` channels, each a panel of the channel over a panel of its
    residuals (7 in wide, ``per_channel`` in of height each): (fig, the user's axes or None, the grid to add
    the panels to or None where the user gave the axes)."""
    height = 1.0 + per_channel * n
    fig, given = _channel_axes(7.0, height, n, fig, ax, left=left, right=0.98, bottom=0.5 / height,
                               top=1.0 - 0.55 / height)
    grid = None if given is not None else \
        fig.add_gridspec(3 * n - 1, 1, height_ratios=([3, 1.2, 0.5] * n)[:-1], hspace=0.1)
    return fig, given, grid


def record_axes(fig, given, grid, k: int, share):
    """The axes of channel ``k`` of a record figure (:func:`record_panels`' layout) and of its residuals, and the
    axes whose time axis the panels share: the user's (``given``) or two new panels on ``grid``."""
    if given is not None:
        return given[2 * k], given[2 * k + 1], share
    top = fig.add_subplot(grid[3 * k], sharex=share)
    share = share or top
    return top, fig.add_subplot(grid[3 * k + 1], sharex=share), share


def _channel_axes(width: float, height: float, n: int, fig, ax, **margins):
    """(figure, the user's 2 n axes or None) of a figure of ``n`` channels, each above its residuals."""
    if ax is None:
        return _figure(width, height, fig=fig, **margins), None
    fig, axes = panels(width, height, (2 * n, 1), fig=fig, ax=ax)
    return fig, list(np.ravel(axes))


def headroom(ax, share: float = 0.42) -> None:
    """Make room for a legend above the curves of ``ax``: the y axis extended so that its top ``share`` holds
    no data (the curves span the rest), for a legend placed ``upper ...`` that covers no curve."""
    import numpy as np

    ys = [np.asarray(line.get_ydata(), dtype=float) for line in ax.lines
          if line.get_transform() == ax.transData and np.size(line.get_ydata()) > 2]
    ys = [y[np.isfinite(y)] for y in ys]
    ys = [y for y in ys if y.size]
    if not ys:
        return
    lo, hi = min(float(y.min()) for y in ys), max(float(y.max()) for y in ys)
    span = (hi - lo) or abs(hi) or 1.0
    lo -= 0.05 * span
    ax.set_ylim(lo, lo + (hi + 0.02 * span - lo) / (1.0 - share))


def _joint_legend(top, bottom, **kwargs) -> None:
    """One legend in ``top`` for the lines of ``top`` and of the small residual axes ``bottom`` below it
    (a legend of its own would cover the residuals)."""
    handles, labels = top.get_legend_handles_labels()
    more, more_labels = bottom.get_legend_handles_labels()
    top.legend(handles + more, labels + more_labels, **kwargs)


def save_figure(fig: Any, folder: str | Path, stem: str, formats: tuple[str, ...] = ("png", "svg"),
                dpi: int = 150) -> dict[str, Path]:
    """Write ``fig`` as ``folder/stem.png`` and ``.svg`` (atomically); returns the paths by format."""
    import matplotlib

    from ..io.export import atomic_path

    out = {}
    for fmt in formats:
        path = Path(folder) / f"{stem}.{fmt}"
        with atomic_path(path) as tmp, matplotlib.rc_context(_STYLE):  # svg settings are read at save time
            fig.savefig(tmp, format=fmt, dpi=dpi, metadata={"Date": None} if fmt == "svg" else None)
        out[fmt] = path
    return out
