"""Figures of the building's free vibration (:class:`~quickrelease.studies.building_analysis.BuildingResult`).

Same conventions as :mod:`quickrelease.report.plots`: object-oriented matplotlib, fixed margins, dense point clouds
rasterised (the SVG stays small at 1e5 samples), user text (channel names) drawn without mathtext. The
figures draw what the result carries (the model curves, the model's decay, the decay envelope: computed once by
:func:`~quickrelease.studies.building_analysis.analyse_building`); they compute no analysis.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..building.isolation_fit import CHANNEL_KINDS
from ._style import STYLE as _STYLE
from ._style import panels, styled, unit_text
from .plots import _COLORS, _joint_legend, headroom, record_axes, record_panels, user_label

__all__ = ["BUILDING_FIGURES", "building_figures", "fit_figure", "decay_figure", "amplitude_figure",
           "hysteresis_figure", "off_scale", "effective_figure"]

#: Figure stems of the building and what they show.
BUILDING_FIGURES = {
    "building_fit": "Building record and fitted isolation model, each channel with its residuals (±2σ shaded)",
    "building_decay": "Decay envelope: half-cycle amplitudes with the Coulomb (linear), viscous (geometric) and "
                      "combined decay laws, and the fitted model",
    "building_amplitude": "Equivalent period and equivalent viscous damping ratio against the amplitude: record "
                          "and fitted model",
    "building_hysteresis": "Hysteresis loop: the isolators' force -m a against the displacement, record and model",
    "building_effective": "Effective stiffness and effective damping against the cycle amplitude: the identified "
                          "model's curve with its 95% band, the cycles as points",
}

#: Above this many samples a point cloud is rasterised in the SVG.
_RASTER = 1000


def building_figures(result) -> dict[str, Any]:
    """The building's figures keyed by the stems of :data:`BUILDING_FIGURES` (the loop only with x and a)."""
    figs = {"building_fit": fit_figure(result)}
    if result.decay is not None:
        model = result.model_decay
        figs["building_decay"] = decay_figure(result, model)
        figs["building_amplitude"] = amplitude_figure(result, model)
    if result.loop is not None:
        figs["building_hysteresis"] = hysteresis_figure(result)
    curve = getattr(result, "effective_curve", None)
    if curve is not None and curve.amplitude_m.size:
        measured = getattr(result, "measured", None)
        if measured is not None:  # the record's own loop over the model's band
            figs["building_effective"] = effective_figure(curve, measured.cycles, release_time=result.fit.release_time,
                                                          label="cycles of the measured loop")
        else:
            figs["building_effective"] = effective_figure(curve, result.effective,
                                                          release_time=result.fit.release_time)
    return figs


def _unit(kind: str) -> str:
    return unit_text(CHANNEL_KINDS.get(kind, ""))


@styled
def fit_figure(result, fig=None, ax=None):
    """Each channel measured (points) and the fitted model (line), with the residuals below. ``ax``: two Axes
    per channel to draw into (the channel, then its residuals). Returns the figure."""
    fit = result.fit
    channels = list(fit.channels)
    n = len(channels)
    fig, given, grid = record_panels(n, 2.4, fig, ax, left=0.12)
    titled = given is None
    share = None
    bottom = None
    for k, ch in enumerate(channels):
        unit = _unit(ch.kind)
        top, bottom, share = record_axes(fig, given, grid, k, share)
        raster = ch.t.size > _RASTER
        top.plot(ch.t, ch.values, ".", ms=1.5, color=_COLORS["d"], alpha=0.6, label="record", rasterized=raster)
        curve = result.curves[ch.name]  # computed by the analysis (building_analysis.model_curves)
        top.plot(curve["t"], curve["model"], color=_COLORS["a"], lw=1.0, label=f"{fit.model} model")
        user_label(top, "set_ylabel", f"{ch.name} [{unit}]")
        sigma = fit.noise[ch.name]
        resid = curve["residual"]
        bottom.axhspan(-2 * sigma, 2 * sigma, color=_COLORS["c"], alpha=0.15, lw=0, label="±2σ (noise)")
        bottom.plot(ch.t, resid, ".", ms=1.2, color=_COLORS["b"], rasterized=raster, label="residual")
        bottom.set_ylabel(f"residual [{unit}]")
        for ax in (top, bottom):
            ax.axvline(fit.release_time, color=_COLORS["d"], lw=0.8, ls=":", label="release" if ax is top else None)
            if ax is not bottom or k < n - 1:
                ax.tick_params(labelbottom=False)
        headroom(top)
        _joint_legend(top, bottom, loc="upper right", ncol=3)
        user_label(top, "set_title", f"{ch.name}: rms residual {fit.residual_rms[ch.name]:.3g} {unit}, noise "
                                     f"{sigma:.3g} {unit} ({fit.noise_source[ch.name]})",
               fontsize=_STYLE["legend.fontsize"])
    bottom.set_xlabel("record time [s]")
    if titled:
        fig.suptitle(f"Building: {fit.model} isolation model fitted to the record "
                     f"({'converged' if fit.converged else 'NOT converged'})")
    return fig


@styled
def decay_figure(result, model=False, fig=None, ax=None):
    """Half-cycle amplitudes of the record with the two pure decay laws, the combined law and the model.
    ``ax``: an Axes to draw into. Returns the figure."""
    data = result.decay_envelope  # computed by the analysis (building_analysis.decay_envelope)
    fig, ax = panels(5.6, 3.6, fig=fig, ax=ax, left=0.14, bottom=0.14, top=0.88)
    ax.plot(data["n"], 1e3 * data["amplitude"], "o", ms=4, color=_COLORS["d"], label="record (half swing)")
    styles = {"coulomb": ("Coulomb: linear decay", _COLORS["b"], "--"),
              "viscous": ("viscous: geometric decay", _COLORS["c"], ":"),
              "combined": ("combined law (Feeny-Liang)", _COLORS["a"], "-")}
    for key, (label, color, ls) in styles.items():
        if key in data:
            ax.plot(data["n"], 1e3 * data[key], ls, color=color, lw=1.2, label=label)
    model = result.model_decay if model is False else model
    if model is not None and model.amplitude.size:
        ax.plot(np.arange(model.amplitude.size), 1e3 * model.amplitude, "x", ms=4, color=_COLORS["a"],
                label=f"fitted {result.fit.model} model")
    ax.set_xlabel("half-cycle n after the release [-]")
    from matplotlib.ticker import MaxNLocator

    ax.xaxis.set_major_locator(MaxNLocator(integer=True))  # a count of half-cycles
    ax.set_ylabel("amplitude (half swing) [mm]")
    ax.set_ylim(bottom=0.0)
    law = result.decay.law
    title = "Decay envelope"
    if law is not None:
        title += f": r = {law.ratio:.4g} per half-cycle, friction displacement {1e3 * law.friction_displacement:.3g} mm"
    ax.set_title(title)
    ax.legend(loc="upper right")
    return fig


@styled
def amplitude_figure(result, model=False, fig=None, ax=None):
    """Equivalent period and equivalent damping ratio against the amplitude, record and fitted model (a period
    far off the others, :func:`off_scale`, marked at the axis' edge and named in the legend). ``ax``: two Axes
    to draw into. Returns the figure."""
    a = result.decay
    fig, (left, right) = panels(7.0, 3.0, (1, 2), fig=fig, ax=ax, left=0.09, right=0.98, bottom=0.16, top=0.86,
                                wspace=0.3)
    left.plot(1e3 * a.amplitude, a.equivalent_period, "o", ms=4, color=_COLORS["d"], label="record")
    right.plot(1e3 * a.damping_amplitude, a.equivalent_damping, "o", ms=4, color=_COLORS["d"], label="record")
    model = result.model_decay if model is False else model
    if model is not None and model.amplitude.size:
        label = f"fitted {result.fit.model} model"
        left.plot(1e3 * model.amplitude, model.equivalent_period, "x-", ms=4, lw=0.8, color=_COLORS["a"], label=label)
        right.plot(1e3 * model.damping_amplitude, model.equivalent_damping, "x-", ms=4, lw=0.8, color=_COLORS["a"],
                   label=label)
    off = off_scale(a.equivalent_period, None if model is None else model.equivalent_period)
    if np.any(off):  # a period far off the others (a last half-cycle ending in the stop) would squash the axis
        shown = np.concatenate([np.asarray(a.equivalent_period)[~off],
                                [] if model is None else np.asarray(model.equivalent_period, dtype=float)])
        shown = shown[np.isfinite(shown)]
        lo, hi = float(np.min(shown)), float(np.max(shown))
        pad = 0.15 * max(hi - lo, 0.05 * hi)
        left.set_ylim(lo - pad, hi + pad)
        values = ", ".join(f"{v:.3g} s" for v in np.asarray(a.equivalent_period)[off])
        left.plot(1e3 * np.asarray(a.amplitude)[off], np.full(int(np.sum(off)), hi + 0.8 * pad), "^", ms=5,
                  mfc="none", color=_COLORS["d"], label=f"record off the axis: {values}")
    left.set_xlabel("amplitude [mm]")
    left.set_ylabel(r"equivalent period $2\,(t_{n+1} - t_n)$ [s]")
    right.set_xlabel("amplitude [mm]")
    right.set_ylabel("equivalent damping ratio [-]")
    left.set_title("Period against amplitude")
    right.set_title("Damping against amplitude")
    for ax in (left, right):
        ax.legend(loc="best")
    return fig


def off_scale(periods, model_periods=None, factor: float = 2.0) -> np.ndarray:
    """Which equivalent periods lie off the scale of the others (a half-cycle that ends where the building
    sticks lasts far longer than a swing): more than ``factor`` times above, or below 1/``factor`` of, the
    model's range (the record's median without a model). Boolean array like ``periods``."""
    p = np.asarray(periods, dtype=float)
    ref = np.asarray([] if model_periods is None else model_periods, dtype=float)
    ref = ref[np.isfinite(ref)]
    if ref.size == 0:
        finite = p[np.isfinite(p)]
        if finite.size < 3:
            return np.zeros(p.shape, dtype=bool)
        ref = np.array([np.median(finite)])
    with np.errstate(invalid="ignore"):
        return np.isfinite(p) & ((p > factor * ref.max()) | (p < ref.min() / factor))


@styled
def hysteresis_figure(result, fig=None, ax=None):
    """The isolators' force -m a against the displacement after the release: record and fitted model. ``ax``:
    an Axes to draw into. Returns the figure."""
    loop = result.loop
    fig, ax = panels(4.8, 3.8, fig=fig, ax=ax, left=0.16, bottom=0.13, top=0.9)
    ax.plot(1e3 * loop["x"], loop["force"] / 1e3, ".", ms=1.5, color=_COLORS["d"], alpha=0.6, label="record",
            rasterized=loop["x"].size > _RASTER)
    ax.plot(1e3 * loop["model_x"], loop["model_force"] / 1e3, color=_COLORS["a"], lw=1.0,
            label=f"fitted {result.fit.model} model")
    ax.set_xlabel("displacement of the isolation layer [mm]")
    ax.set_ylabel("isolators' force -m a [kN]")
    ax.set_title("Hysteresis loop")
    ax.legend(loc="best")
    return fig


@styled
def effective_figure(curve, cycles=(), *, release_time: float | None = None,
                     label: str = "cycles of the fitted model's loop", fig=None, ax=None):
    """keff and beta_eff against the cycle amplitude: the identified model's curve and its band
    (:class:`~quickrelease.studies.building_effective.EffectiveCurve`), and ``cycles`` (a sequence of
    :class:`~quickrelease.building.effective.CycleProperties`: measured, or the model's) as points, the one from
    the release (starting at ``release_time``, else the first) hollow: its F+ is the unloading branch's, off the
    curve by construction. ``ax``: two Axes to draw into. Returns the figure."""
    fig, (left, right) = panels(7.0, 3.0, (1, 2), fig=fig, ax=ax, left=0.1, right=0.98, bottom=0.16, top=0.86,
                                wspace=0.32)
    d = 1e3 * np.asarray(curve.amplitude_m)
    pct = round(100 * curve.level)
    for panel, q, scale in ((left, "keff_N_m", 1e-3), (right, "beta_eff", 1e2)):
        panel.fill_between(d, scale * curve.lower[q], scale * curve.upper[q], color=_COLORS["a"], alpha=0.25, lw=0,
                           label=f"{pct}% band ({curve.draws_used} draws)")
        panel.plot(d, scale * curve.curves[q], color=_COLORS["a"], lw=1.0, label=f"identified {curve.model} model")
        cycles = list(cycles)
        if cycles:
            first = [(c.start_s == release_time) if release_time is not None else i == 0
                     for i, c in enumerate(cycles)]
            x = np.array([1e3 * c.amplitude_m for c in cycles])
            y = np.array([scale * getattr(c, q) for c in cycles])
            mask = np.array(first, dtype=bool)
            panel.plot(x[~mask], y[~mask], "o", ms=4, color=_COLORS["d"], label=label)
            if mask.any():
                panel.plot(x[mask], y[mask], "o", ms=4, mfc="none", color=_COLORS["d"],
                           label="cycle from the release (not judged)")
        panel.set_xlabel("cycle amplitude D [mm]")
    left.set_ylabel("effective stiffness keff [kN/m]")
    right.set_ylabel("effective damping beta_eff [%]")
    left.set_title("Effective stiffness")
    right.set_title("Effective damping")
    left.legend(loc="best")
    return fig
