"""Zoomable record figures in the single-file HTML report (uPlot, inlined; no network at view time).

A record of 60 s at 200 Hz is unreadable as a static picture at the release and at the stick: the report
draws the record figure (each channel measured and fitted, with its residuals) a second time, in the page,
with `uPlot <https://github.com/leeoniya/uPlot>`_ (MIT licence, ``vendor/uplot/``: the minified library, its
stylesheet and its licence, inlined once per page). Drag a box across a panel to zoom the time axis, Shift +
drag to pan, Shift + wheel to zoom about the pointer, double click to see the whole record; every panel
follows the time axis of the others and the cursor of the others.

The static figure stays in the page as the fallback: shown without JavaScript, on paper (the print style
shows it and hides the interactive one) and wherever the script fails (it is hidden only once every panel is
drawn). The data sit in the page as JSON: every sample of every channel and its residual as little-endian
float32 in base64 (4 bytes a sample, 5.3 characters), a uniform time axis as ``t0, dt`` and its unbroken runs
(else float32 offsets from ``t0``, float64), the fitted model on its fine grid.
"""

from __future__ import annotations

import base64
import html
import json
import math
from functools import cache
from importlib.resources import files
from typing import Any

import numpy as np

from ._style import COLORS, unit_text

__all__ = ["zoom_figure", "device_fit_zoom", "building_fit_zoom", "zoom_assets", "ZOOM_MARK"]

#: The attribute that marks a zoomable figure's container in the page (:func:`zoom_assets` looks for it).
ZOOM_MARK = "data-qr-zoom"

#: How the page behaves, shown above the panels (the script writes it: without JavaScript it would be false).
_HINT = ("Drag across a panel to zoom the time axis; Shift + drag pans, Shift + wheel zooms about the pointer; "
         "double click shows the whole record. All panels share the time axis.")

_CSS = """
figure.qr-live > svg { display: none; }
.qr-zoom .qr-hint { font-size: 0.85rem; color: #555; margin: 0.2rem 0; }
.qr-zoom .uplot { margin-bottom: 0.2rem; } .qr-zoom .u-legend { font-size: 0.8rem; }
@media print { figure.qr-live > svg { display: inline; } .qr-zoom { display: none; } }
"""


@cache
def _vendored(name: str) -> str:
    """A file of the vendored uPlot (``vendor/uplot/<name>``) as text."""
    return files("quickrelease.report").joinpath("vendor", "uplot", name).read_text(encoding="utf-8")


@cache
def _driver() -> str:
    return files("quickrelease.report").joinpath("zoom.js").read_text(encoding="utf-8")


def zoom_assets(body: str) -> tuple[str, str]:
    """(style, scripts) the page needs for the zoomable figures in ``body``: uPlot's stylesheet and ours as CSS
    text for the page's ``<style>``, and ``<script>`` elements (uPlot, then the driver, :file:`zoom.js`) to put
    at the end of ``<body>``; two empty strings where ``body`` holds no zoomable figure (nothing inlined)."""
    if f'{ZOOM_MARK}="' not in body:  # the attribute, not user text naming it (its quotes escaped)
        return "", ""
    licence = "/*! uPlot v1.6.32, (c) 2022 Leon Sorokin, MIT licence (quickrelease/report/vendor/uplot/LICENSE) */"
    scripts = f"<script>{licence}\n{_vendored('uPlot.iife.min.js')}</script>\n<script>{_driver()}</script>"
    return _vendored("uPlot.min.css") + _CSS, scripts


def _f32(values) -> str:
    """Base64 of ``values`` as little-endian float32 (non-finite values stay NaN: a gap in the figure)."""
    return base64.b64encode(np.asarray(values, dtype="<f4").tobytes()).decode("ascii")


def _times(t) -> dict[str, Any]:
    """A time axis [s] for the page: ``{t0, dt, runs}`` where every sample lies on a uniform grid (within 1e-6
    of a step) with few gaps (a dropped sample, a spike left out; a run for two samples at most), ``runs`` the
    ``[first step, samples]`` of each unbroken run (sample times ``t0 + dt (first + j)``); else
    ``{t0, offsets}``, float32 offsets from t0 (4 us at 60 s)."""
    t = np.asarray(t, dtype=float)
    t0 = float(t[0]) if t.size else 0.0
    steps = np.diff(t)
    if t.size > 1 and np.all(steps > 0):
        k = np.rint((t - t0) / float(np.median(steps)))
        dt = (float(t[-1]) - t0) / k[-1]
        breaks = np.flatnonzero(np.diff(k) != 1) + 1
        if np.max(np.abs(t - (t0 + dt * k))) <= 1e-6 * dt and 2 * (breaks.size + 1) <= t.size:
            starts, ends = np.r_[0, breaks], np.r_[breaks, t.size]
            return {"t0": t0, "dt": dt, "runs": [[int(k[a]), int(b - a)] for a, b in zip(starts, ends, strict=True)]}
    return {"t0": t0, "offsets": _f32(t - t0)}


def zoom_figure(ident: str, channels: list[dict[str, Any]], markers: list[tuple[str, float]],
                model_label: str = "fitted model") -> str:
    """The HTML of a zoomable record figure: a container (``id="<ident>-zoom"``, marked :data:`ZOOM_MARK`)
    and its data as JSON in a ``<script type="application/json">``; the page's script draws it.

    ``channels``: one dict per channel with ``name``, ``unit`` (e.g. ``m/s^2``), ``t`` [s], ``values``,
    ``residual`` (measured - model, at ``t``), ``sigma`` (the noise level), ``model_t`` [s] and ``model`` (the
    fitted model on its grid), in the channel's SI unit. ``markers``: (label, record time [s]) drawn as
    vertical lines (the release, the stick); non-finite times are left out."""
    data = {
        "model_label": model_label,
        "hint": _HINT,
        "xlabel": "record time [s]",
        "markers": [{"label": label, "t": float(t)} for label, t in markers if t is not None and math.isfinite(t)],
        "colors": {"record": COLORS["d"], "model": COLORS["a"], "residual": COLORS["b"], "band": COLORS["c"]},
        "channels": [{"name": str(c["name"]), "unit": unit_text(c["unit"]),
                      "sigma": float(c["sigma"]) if math.isfinite(c["sigma"]) else None,
                      "t": _times(c["t"]), "values": _f32(c["values"]), "residual": _f32(c["residual"]),
                      "model_t": _times(c["model_t"]), "model": _f32(c["model"])} for c in channels],
    }
    # in a <script> element only "</script" would end it: "<" as \u003c keeps user text (names) inert
    text = json.dumps(data, separators=(",", ":"), allow_nan=False).replace("<", "\\u003c")
    ident = html.escape(ident, quote=True)
    return (f"<div class=\"qr-zoom\" id=\"{ident}-zoom\" {ZOOM_MARK}=\"{ident}-data\"></div>"
            f"<script type=\"application/json\" id=\"{ident}-data\">{text}</script>")


def device_fit_zoom(fit, ident: str = "fit_channels") -> str:
    """:func:`zoom_figure` of the device's fit to a record (:class:`~quickrelease.studies.fit.FitResult`):
    each channel, the model with offsets, the residuals; the release and the device's stop t_F marked.
    Empty without a record."""
    from ..io.records import CHANNELS

    if fit.record is None:
        return ""
    t_fine, curves = fit.model_curves()
    channels = [{"name": name, "unit": CHANNELS[name][1], "t": ch.t, "values": ch.values,
                 "residual": ch.values - fit.fitted[name], "sigma": fit.noise[name], "model_t": t_fine,
                 "model": curves[name]} for name, ch in fit.record.channels.items()]
    t_rel = fit.release_time
    markers = [] if t_rel is None else [("release", t_rel), ("stop t_F", t_rel + fit.stop_time)]
    return zoom_figure(ident, channels, markers)


def building_fit_zoom(result, ident: str = "building_fit") -> str:
    """:func:`zoom_figure` of the building's fit (:class:`~quickrelease.studies.building_analysis.BuildingResult`):
    each channel, the model curves the analysis carries, the residuals; the release and the stick (where the
    fitted model's sliders hold the building for good within the record) marked."""
    from ..building.isolation_fit import CHANNEL_KINDS

    fit = result.fit
    channels = [{"name": ch.name, "unit": CHANNEL_KINDS.get(ch.kind, ""), "t": ch.t, "values": ch.values,
                 "residual": result.curves[ch.name]["residual"], "sigma": fit.noise[ch.name],
                 "model_t": result.curves[ch.name]["t"], "model": result.curves[ch.name]["model"]}
                for ch in fit.channels]
    return zoom_figure(ident, channels, [("release", fit.release_time), ("stick", stick_time(fit))],
                       f"{fit.model} model")


def stick_time(fit) -> float:
    """Record time [s] where the fitted model's sliders hold the building for good, within the record's span
    (nan: still moving at the record's end, no friction, or a model without the closed form)."""
    from ..building.model import free_vibration
    from ..errors import QuickReleaseError

    span = max(float(np.max(c.t)) for c in fit.channels) - fit.release_time
    if not span > 0:
        return math.nan
    try:
        stop = free_vibration(fit.isolation(), fit.parameters["d0"], t_end=span).stop_time
    except (QuickReleaseError, TypeError, AttributeError):  # a model without the rigid closed form
        return math.nan
    return fit.release_time + stop if math.isfinite(stop) and stop <= span else math.nan
