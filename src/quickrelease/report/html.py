"""A self-contained HTML report of a case: inputs, strain energy, identification, release, figures.

One file, no network fetches: figures are embedded as inline SVG and the style is inline; the record figures
also zoom in the page (:mod:`quickrelease.report.zoom`: the vendored uPlot and the data inlined).
Every piece of user-provided text (title, notes, names) is escaped. It reads as a test report: the date,
the package version and the input file (name, SHA-256, its text in a collapsible block) at the top, a table
of contents, and a sign-off block naming who ran the test (the case file's ``[report]`` table) at the end.
The date is today's, or ``SOURCE_DATE_EPOCH``'s where that is set (reproducible builds); it is the only
thing in the output folder that depends on when it was written.
"""

from __future__ import annotations

import datetime
import html
import math
import os
import re
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, Any

from ..device.parameters import DEVICE_KEYS
from .display import half_width, key_for, number, plus_minus, same_places, unit_text
from .zoom import building_fit_zoom, device_fit_zoom, zoom_assets

if TYPE_CHECKING:  # the workflow's result type annotates render_report; the report imports no workflow
    from ..workflow import CaseResult

#: Figure stems and what they show.
FIGURES = {
    "fig13_response": "Fig. 13: position angle, angular velocity, angular acceleration, energy balance",
    "fig14_displacements": "Fig. 14: longitudinal and transverse displacements and velocities",
    "fig15_state_diagram": "Fig. 15: state diagram, numerical solutions over the analytic curve (Eq. 10)",
    "identification": "Stop time along the line of Eq. 13, with the measured t_F and the identified point",
    "strain_energy": "Strain energy stored before release by term (Eq. 2)",
    "fit_channels": "Fit to the measured record: each channel measured and fitted, with its residuals",
    "plan_choices": "Fuse and angle choices: push force at rupture (Eq. 1), the target range outlined",
    "plan_utilisation": "Member checks at the planned push (Table 3's internal forces)",
    "plan_envelope": "Release envelope over the friction estimate: stroke, opening, time to stop, peak head velocity",
    "plan_gap": "Clearance: head retraction, the building's approach and the gap between them",
    "building_fit": "Building record and fitted isolation model, each channel with its residuals",
    "building_decay": "Decay envelope with the Coulomb, viscous and combined decay laws",
    "building_amplitude": "Equivalent period and damping ratio of the building against the amplitude",
    "building_hysteresis": "Hysteresis loop of the isolators: -m a against the displacement",
}

__all__ = ["render_report", "render_campaign_report", "render_building_report", "building_section", "FIGURES"]

_CSS = """
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; margin: 2rem auto; max-width: 980px;
       color: #1a1a1a; line-height: 1.45; padding: 0 1rem; }
h3 { font-size: 1.05rem; margin-top: 1.4rem; }
h1 { font-size: 1.6rem; margin-bottom: 0.2rem; } h2 { font-size: 1.2rem; border-bottom: 2px solid #1f4e79;
     padding-bottom: 0.2rem; margin-top: 2rem; }
.meta { color: #555; font-size: 0.9rem; } .notes { white-space: pre-wrap; background: #f4f6f8; padding: 0.8rem;
     border-left: 4px solid #1f4e79; }
table { border-collapse: collapse; margin: 0.6rem 0; font-size: 0.92rem; }
th, td { border: 1px solid #c8ccd0; padding: 0.25rem 0.6rem; text-align: left; }
th { background: #e8edf2; } td.num { text-align: right; font-variant-numeric: tabular-nums; }
figure { margin: 1rem 0; } figure svg { max-width: 100%; height: auto; }  /* own size: one font scale */
figcaption { font-size: 0.9rem; color: #444; }
.flag { color: #a00; font-weight: bold; }
nav.toc { background: #f4f6f8; padding: 0.4rem 1rem; margin: 1rem 0; } nav.toc ol { margin: 0.3rem 0; }
pre.input { white-space: pre-wrap; font-size: 0.85rem; background: #f4f6f8; padding: 0.6rem; overflow-x: auto; }
table.signoff td { min-width: 14rem; height: 1.6rem; }
"""


def _e(text: Any) -> str:
    return html.escape(str(text), quote=True)


def _num(value: float | None, fmt: str | None = None) -> str:
    """A number of the report: 5 significant digits (as the command line's tables), or ``fmt``; a dash for
    None and non-finite values."""
    if value is None:
        return "&ndash;"
    if isinstance(value, float) and not math.isfinite(value):
        return "&ndash;"
    if fmt is None:
        return number(float(value))
    return format(value, fmt).replace("e+0", "e").replace("e-0", "e-").replace("e+", "e")  # 2.5e-8, not 2.5e-08


def _se(value: float | None) -> str:
    """An uncertainty of the report: 2 significant digits (``0.40``), as the command line's tables."""
    if value is None or not math.isfinite(value):
        return "&ndash;"
    return number(float(value), 2, zeros=True)


def _estimate(value: float, se: float | None, ci: Sequence[float | None] | None, scale: float = 1.0) \
        -> tuple[str, str, str]:
    """(estimate, standard error, interval) cells of one estimate, times ``scale`` (the unit printed beside
    them), all rounded to one decimal place: where the error (else the interval's half-width) shows two
    significant digits (:func:`quickrelease.report.display.same_places`)."""
    ends = None if ci is None or any(b is None for b in ci) else [float(b) * scale for b in ci]
    err = None if se is None or not math.isfinite(se) or se <= 0 else float(se) * scale
    width = err if err is not None else half_width(ends)
    texts = same_places([float(value) * scale, err, *(ends or [])], width)
    interval = f"[{texts[2]}, {texts[3]}]" if ends is not None else "&ndash;"
    return texts[0], "&ndash;" if err is None else texts[1], interval


def _html_table(headers: Sequence[str] | None, rows: Iterable[Sequence[Any]], *, num: Iterable[int] = (),
                cls: str | None = None, row_headers: bool = False) -> str:
    """The report's one table builder. ``headers``: column titles (text, escaped here; None: no head row);
    ``rows``: cells as HTML (escape text with :func:`_e`; a cell ``(html, id)`` carries an id); the columns in
    ``num`` are numbers (right-aligned, class ``num``); ``row_headers``: each row's first cell is its header."""
    numeric = set(num)

    def cell(k: int, value: Any) -> str:
        text, ident = value if isinstance(value, tuple) else (value, None)
        attrs = (" class=\"num\"" if k in numeric else "") + (f" id=\"{_e(ident)}\"" if ident else "")
        if row_headers and k == 0:
            return f"<th scope=\"row\"{attrs}>{text}</th>"
        return f"<td{attrs}>{text}</td>"

    head = "" if headers is None else "<thead><tr>" + "".join(f"<th>{_e(h)}</th>" for h in headers) + "</tr></thead>"
    body = "".join("<tr>" + "".join(cell(k, v) for k, v in enumerate(row)) + "</tr>" for row in rows)
    klass = "" if cls is None else f" class=\"{_e(cls)}\""
    return f"<table{klass}>{head}<tbody>{body}</tbody></table>"


def _table(rows: list[tuple[str, str, str]], headers: tuple[str, str, str] = ("quantity", "value", "unit")) -> str:
    """A (quantity, value, unit) table: the quantity and unit as text, the value as HTML."""
    return _html_table(headers, [(_e(a), b, _e(c)) for a, b, c in rows], num=(1,))


def _svg_inline(svg: str, prefix: str) -> str:
    """The SVG ready to sit inside HTML: XML prolog and DOCTYPE stripped, and every id (with the references
    to it: ``url(#id)``, ``href="#id"``) given the figure's ``prefix``, so that figures that draw the same
    clip path or marker do not repeat an id in the page (HTML ids are unique)."""
    svg = re.sub(r"<\?xml[^>]*\?>", "", svg)
    svg = re.sub(r"<!DOCTYPE[^>]*>", "", svg, flags=re.S)
    svg = re.sub(r'\bid="([^"]+)"', lambda m: f'id="{prefix}-{m.group(1)}"', svg)
    svg = re.sub(r"url\(#([^)]+)\)", lambda m: f"url(#{prefix}-{m.group(1)})", svg)
    svg = re.sub(r'href="#([^"]+)"', lambda m: f'href="#{prefix}-{m.group(1)}"', svg)
    return svg.strip()


_DEVICE_UNITS = {"mass": "kg", "length": "m", "area": "m²", "second_moment": "m⁴", "pressure": "Pa",
                 "dimensionless": "–"}


def report_date() -> str:
    """The report's date (ISO 8601, UTC): ``SOURCE_DATE_EPOCH`` where set, else today."""
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    if epoch is not None and epoch.strip().isdigit():
        when = datetime.datetime.fromtimestamp(int(epoch), datetime.UTC)
    else:
        when = datetime.datetime.now(datetime.UTC)
    return when.date().isoformat()


def _front(title: str, prov: dict[str, Any], what: str, extra: list[tuple[str, str]] = ()) -> list[str]:
    """The report's head: title, date, version, the input file (name, SHA-256, text) and a place for the
    table of contents."""
    entry = prov.get("input")
    rows = [("report date", _e(report_date())), ("quickrelease version", _e(prov["quickrelease"]))]
    if entry:
        rows += [(what, _e(entry["name"])), ("SHA-256 of the " + what, f"<code>{_e(entry['sha256'])}</code>")]
    else:
        rows.append((what, "none (built in Python)"))
    rows += list(extra)
    parts = [f"<h1>{_e(title)}</h1>", _html_table(None, [(_e(k), v) for k, v in rows], cls="front", row_headers=True)]
    if entry:
        parts.append(f"<details id=\"input-text\"><summary>The {_e(what)} as read</summary>"
                     f"<pre class=\"input\">{_e(entry['text'])}</pre></details>")
    parts.append(_TOC)
    return parts


_TOC = "<!--quickrelease-toc-->"


def _signoff(info: dict[str, str] | None, prov: dict[str, Any]) -> str:
    """The sign-off block: who ran the test (the case file's ``[report]`` table), and lines to sign."""
    info = info or {}
    rows = [("test identifier", info.get("test_id")), ("operator", info.get("operator")),
            ("organisation", info.get("organisation")),
            ("analysed with", f"quickrelease {prov['quickrelease']} on {report_date()}"),
            ("checked by", None), ("signature and date", None)]
    table = _html_table(None, [(_e(k), "" if v is None else _e(v)) for k, v in rows], cls="signoff", row_headers=True)
    note = "" if info else ("<p class=\"meta\">Give a <code>[report]</code> table (operator, organisation, test_id) "
                            "in the case file to fill this block.</p>")
    return f"<h2 id=\"sign-off\">Sign-off</h2>{table}{note}"


def _paper_section(cmp) -> str:
    """Table 7 of the paper beside ours (:class:`~quickrelease.device.paper.PaperComparison`)."""
    table = _html_table(("quantity", "paper", "quickrelease", "note"),
                        [tuple(_e(c) for c in row) for row in cmp.rows()], num=(1, 2))
    return ("<h2 id=\"table7\">The paper and quickrelease (Table 7)</h2>" + table +
            "<p>The paper's values as printed (rounded); ours computed for the same device and test, with what "
            "explains each difference.</p>")


def render_report(result: CaseResult, svgs: dict[str, str]) -> str:
    """The HTML text of the report for a case result, with the given SVG figures embedded."""
    from ..io.runfolder import provenance

    case = result.case
    r = result.response
    s = r.summary()
    prov = provenance(case)
    parts: list[str] = _front(case.title, prov, "case file", [("device", _e(case.device.name))])
    if case.notes:
        parts.append(f"<div class=\"notes\">{_e(case.notes)}</div>")

    # inputs
    parts.append("<h2>Inputs</h2>")
    rows = [
        ("push force P", _num(case.push_force / 1e3 if case.push_force else None), "kN"),
        ("stored energy E_S" + (" (given)" if case.energy_given else " (Eq. 2)"), _num(case.stored_energy), "J"),
        ("initial angle α0", f"{_num(case.alpha0)} ({_num(math.degrees(case.alpha0))}°)", "rad"),
        ("mass model", f"{_e(case.mass_model)} (c = {_num(case.mass_factor)})", ""),
        ("solver", _e(case.method), ""),
    ]
    if case.has_friction:
        rows += [("friction F1 (case file)", _num(case.F1), "N"), ("friction F2 (case file)", _num(case.F2), "N")]
    if case.has_observations:
        rows += [("observed final angle α_F", _num(case.alpha_final), "rad"),
                 ("observed stop time t_F", _num(case.stop_time), "s")]
    parts.append(_table(rows))
    dev_rows = [(f"{k}: {desc.rsplit(' [', 1)[0]}", _num(getattr(case.device, k)), _DEVICE_UNITS[kind])
                for k, (kind, desc) in DEVICE_KEYS.items()]
    parts.append("<details><summary>Device data (Table 2)</summary>" + _table(dev_rows) + "</details>")

    # statics
    if result.strain is not None:
        st = result.strain
        f = st.forces
        parts.append("<h2>Statics before release</h2>")
        parts.append(_table([
            ("fuse force N4 = P tan α0 (Table 3)", _num(f.N4 / 1e3), "kN"),
            ("fuse stress N4 / A4", _num(f.N4 / case.device.A4 / 1e6), "MPa"),
            ("bar force N1 = P / (2 cos α0)", _num(f.N1 / 1e3), "kN"),
            ("head bending moment M2 = P L2 / 4", _num(f.M2 / 1e3), "kN m"),
        ]))
        terms = [(name.replace("_", " "), _num(value), "J") for name, value in st.terms().items()]
        terms.append(("total E_S (Eq. 2)", _num(st.total), "J"))
        parts.append(_table(terms, ("term of Eq. 2", "energy", "unit")))
        if case.energy_given:
            parts.append(f"<p>The case gives E_S = {_num(case.stored_energy)} J; Eq. 2 at this P gives "
                         f"{_num(st.total)} J ({_num(100 * (st.total / case.stored_energy - 1), '+.2f')}%). "
                         "The release uses the given value.</p>")
        parts.append(_figure(svgs, "strain_energy"))

    # identification
    if result.identification is not None:
        i = result.identification
        parts.append("<h2>Identified friction (Eq. 11-13)</h2>")
        parts.append(_table([
            ("F1 (central hinges)", f"<strong id=\"F1\">{_num(i.F1)}</strong>", "N"),
            ("F2 (rail supports)", f"<strong id=\"F2\">{_num(i.F2)}</strong>", "N"),
            ("F1* (Eq. 11)", _num(i.F1_max), "N"),
            ("F2* (Eq. 12)", _num(i.F2_max), "N"),
            ("F2 / F2*", _num(i.F2_ratio), "–"),
            ("stop-time residual (model − observed)", _num(i.stop_time_residual, ".3g"), "s"),
            ("feasible t_F on Eq. 13", f"[{_num(i.feasible_stop_times[0])}, {_num(i.feasible_stop_times[1])}]", "s"),
        ]))
        parts.append(_figure(svgs, "identification"))
    if getattr(result, "paper", None) is not None:
        parts.append(_paper_section(result.paper))

    if result.fit is not None:
        parts.append(_fit_section(result.fit, svgs))

    # release
    parts.append("<h2>Release</h2>")
    stopped = "friction stopped the device (Eq. 8)" if r.stopped_by == "friction" else \
        "<span class=\"flag\">the device reached the geometric limit α = π/2 with kinetic energy left</span>"
    parts.append(f"<p>Friction used: F1 = {_num(r.F1)} N, F2 = {_num(r.F2)} N. End of motion: {stopped}.</p>")
    parts.append(_table([
        ("stop time t_F", _num(s["stop_time_s"]), "s"),
        ("final angle α_F", _num(s["alpha_final_rad"]), "rad"),
        ("head stroke u_F", _num(s["u_final_m"]), "m"),
        ("hinge opening v_F", _num(s["v_final_m"]), "m"),
        ("initial angular velocity (Eq. 6)", _num(s["alpha_dot0_rad_s"]), "rad/s"),
        ("peak head velocity", _num(s["peak_u_dot_m_s"]), "m/s"),
        ("peak hinge velocity", _num(s["peak_v_dot_m_s"]), "m/s"),
        ("peak head acceleration", _num(s["peak_u_ddot_m_s2"]), "m/s²"),
        ("peak hinge acceleration", _num(s["peak_v_ddot_m_s2"]), "m/s²"),
    ]))
    for stem in ("fig13_response", "fig14_displacements", "fig15_state_diagram"):
        parts.append(_figure(svgs, stem))
    building = getattr(result, "building", None)
    if building is not None:
        parts.append(building_section(building, svgs))
    if result.plan is not None:
        parts.append(_plan_section(result.plan, svgs))
    parts.append(_signoff(case.report, prov))
    return _page(case.title, parts)


_PARAM_UNITS = {"F1": "N", "F2": "N", "energy": "J", "mass_factor": "–", "release_time": "s"}


def _fit_section(fit, svgs: dict[str, str]) -> str:
    """The fit to a measured record: estimates with uncertainty, channels, diagnostics, figure."""
    from ..io.records import CHANNELS

    parts = ["<h2>Fit to the measured record</h2>"]
    if fit.record is not None:
        parts.append(f"<p>Record: {_e(fit.record.file.name)}, {fit.record.t.size} rows, "
                     f"{_num(fit.record.t[0])} to {_num(fit.record.t[-1])} s. Weighted least squares "
                     f"(each channel by its noise level); {'converged' if fit.converged else 'NOT converged'} after "
                     f"{fit.nfev} evaluations; reduced chi-square {_num(fit.chi2_reduced)} "
                     f"({fit.dof} degrees of freedom). Start values: {_e(fit.start_source)}.</p>")
    rows = []
    for name in fit.names:
        unit = _PARAM_UNITS.get(name) or CHANNELS[name.removeprefix("offset_")][1]
        ident = {"F1": "fit-F1", "F2": "fit-F2"}.get(name)
        value, se, interval = _estimate(fit.estimates[name], fit.std_errors[name], fit.ci95[name])
        if not math.isfinite(fit.std_errors[name]):
            value, interval = _num(fit.estimates[name]), "not identified"
        rows.append((_e(name), (value, ident), se, interval, _e(unit)))
    parts.append(_html_table(("parameter", "estimate", "standard error", "95% interval", "unit"), rows,
                             num=(1, 2, 3)))
    i1, i2 = fit.names.index("F1"), fit.names.index("F2")
    parts.append(f"<p>Correlation of F1 and F2: {_num(float(fit.correlation[i1, i2]), '+.4f')}; condition number of "
                 f"the correlation matrix {_num(fit.condition_number, '.3g')}.</p>")
    if fit.residual_rms:
        parts.append(_html_table(("channel", "samples", "noise σ", "from", "rms residual", "unit"), [
            (_e(n), str(fit.samples[n]), _num(fit.noise[n], ".3g"), _e(fit.noise_source[n]),
             _num(fit.residual_rms[n], ".3g"), _e(unit_text(CHANNELS[n][1]))) for n in fit.residual_rms],
            num=(1, 2, 4)))
    for text in fit.warnings:
        parts.append(f"<p class=\"flag\">Warning: {_e(text)}</p>")
    for text in fit.notes:
        parts.append(f"<p class=\"meta\">{_e(text)}</p>")
    parts.append(_figure(svgs, "fit_channels", zoom=lambda: device_fit_zoom(fit)))
    return "\n".join(parts)


_BUILDING_PARAMS = {  # fit parameter: label, unit, scale to the unit shown
    "period": ("period T (linear, 2dof) or initial period T1 = 2π √(m / k1) (bilinear)", "s", 1.0),
    "damping_ratio": ("viscous damping ratio ζ", "–", 1.0),
    "friction": ("slider friction F_s", "kN", 1e-3),
    "stiffness_ratio": ("stiffness ratio k2 / k1", "–", 1.0),
    "yield_force": ("yield force F_y", "kN", 1e-3),
    "d0": ("pushed displacement d0", "mm", 1e3),
    "release_time": ("release instant (record time)", "s", 1.0),
}
_ENGINEERING = {"period_s": ("period T", "s", 1.0), "k1_N_m": ("initial stiffness k1", "kN/m", 1e-3),
                "k2_N_m": ("post-yield stiffness k2", "kN/m", 1e-3), "Fy_N": ("yield force F_y", "kN", 1e-3),
                "radius_m": ("radius of the sliding surface R", "m", 1.0),
                "friction_coefficient": ("friction coefficient μ (constant)", "–", 1.0),
                "friction_slow": ("friction coefficient at low speed μ_slow", "–", 1.0),
                "friction_fast": ("friction coefficient at speed μ_fast", "–", 1.0),
                "rate_s_m": ("friction's rate a (Constantinou)", "s/m", 1.0),
                "damping_ratio": ("viscous damping ratio ζ", "–", 1.0),
                "friction_N": ("slider friction F_s", "kN", 1e-3)}


def building_section(result, svgs: dict[str, str]) -> str:
    """The building's free vibration: model, estimates with 95% intervals, model comparison, the decay
    cross-check, warnings and the four figures (:mod:`quickrelease.report.building_plots`)."""
    from ..building.isolation_fit import CHANNEL_KINDS
    from .building_plots import BUILDING_FIGURES

    fit = result.fit
    s = result.summary()
    parts = ["<h2 id=\"building\">The building: isolation system from its free vibration</h2>"]
    names = ", ".join(f"{c.name} ({c.kind})" for c in fit.channels)
    converged = "converged" if fit.converged else "<span class=\"flag\">NOT converged</span>"
    parts.append(f"<p>Record: {_e(result.source or 'channels given directly')}; channels "
                 f"{_e(names)}; mass {_num(fit.mass / 1e3)} t. "
                 f"Model: <strong id=\"building-model\">{_e(fit.model)}</strong>; weighted least squares "
                 f"{converged} after {fit.nfev} "
                 f"evaluations; reduced chi-square {_num(fit.chi2_reduced)} ({fit.dof} degrees of freedom); "
                 f"AIC {_num(fit.aic)}, BIC {_num(fit.bic)}.</p>")
    rows = []
    for key, (label, unit, scale) in _ENGINEERING.items():
        if key not in s or s[key] is None:
            continue
        value, _, interval = _estimate(s[key], None, s.get(f"{key}_ci95") or None, scale)
        if key in s.get("not_identified", ()):
            value, interval = _num(s[key] * scale), "not identified"
        rows.append((_e(label), (value, f"building-{key}"), interval, _e(unit)))
    parts.append(_html_table(("isolation system", "estimate", "95% interval", "unit"), rows, num=(1, 2)))
    rows = []
    for name in fit.names:
        label, unit, scale = _BUILDING_PARAMS.get(name, (name, "", 1.0))
        if name.startswith("offset_"):
            ch = name.removeprefix("offset_")
            kind = next((c.kind for c in fit.channels if c.name == ch), "")
            label, unit, scale = f"offset of {ch}", CHANNEL_KINDS.get(kind, ""), 1.0
        value, se, interval = _estimate(fit.estimates[name], fit.std_errors[name], fit.ci95[name], scale)
        if fit.interval_method[name] == "not identified":
            value, se, interval = _num(fit.estimates[name] * scale), _se(fit.std_errors[name] * scale), \
                "not identified"
        rows.append((_e(name), _e(label), value, se, interval, _e(fit.interval_method[name]), _e(unit)))
    table = _html_table(("parameter", "", "estimate", "standard error", "95% interval", "interval", "unit"), rows,
                        num=(2, 3, 4))
    parts.append(f"<details><summary>Every fitted parameter</summary>{table}"
                 f"<p>Condition number of the correlations {_num(fit.condition_number, '.3g')}.</p></details>")
    parts.append(_html_table(("channel", "samples", "noise σ", "from", "rms residual", "whiteness p (Ljung-Box)",
                              "unit"), [
        (_e(c.name), str(fit.samples[c.name]), _num(fit.noise[c.name], ".3g"), _e(fit.noise_source[c.name]),
         _num(fit.residual_rms[c.name], ".3g"), _num(fit.whiteness_p[c.name], ".3g"),
         _e(unit_text(CHANNEL_KINDS.get(c.kind, "")))) for c in fit.channels], num=(1, 2, 4, 5)))
    if result.comparison:
        parts.append("<h3>Model comparison</h3>")
        def white(r):
            return ", ".join(f"{k}: {_num(v, '.3g')}" for k, v in r["whiteness_p"].items())

        parts.append(_html_table(("model", "parameters", "χ²", "AIC", "ΔAIC", "BIC", "ΔBIC", "whiteness p"), [
            (_e(r["model"]), str(r["parameters"]), _num(r["chi2"]), _num(r["aic"]), _num(r["delta_aic"]),
             _num(r["bic"]), _num(r["delta_bic"]), _e(white(r))) for r in result.comparison], num=range(1, 7)))
        parts.append("<p>Lowest BIC first; a difference above about 10 is strong support for the lower one. Small "
                     "whiteness p-values: the residuals keep structure the model does not explain.</p>")
    parts.append("<h3>Decay cross-check (model-free)</h3>")
    if result.decay is not None:
        d = result.decay
        law = d.law
        text = (f"{max(d.peaks.size - 1, 0)} half-cycles; damped period {_num(d.period)} s (natural "
                f"{_num(d.natural_period)} s).")
        if law is not None:
            text += (" Combined decrement law (Feeny and Liang 1996): amplitude ratio "
                     f"r = {_num(law.ratio)} per half-cycle (ζ = {_num(law.damping_ratio)}), "
                     "friction displacement δ = F_s / k = "
                     f"{_num(1e3 * law.friction_displacement)} mm; rms residual of the peaks: combined "
                     f"{_num(1e3 * law.rms, '.3g')} mm, viscous only {_num(1e3 * law.rms_viscous_only, '.3g')} mm, "
                     f"Coulomb only {_num(1e3 * law.rms_friction_only, '.3g')} mm.")
        parts.append(f"<p>{text}</p>")
    rows = result.decay_check.get("rows", [])
    if rows:
        parts.append(_html_table(("parameter", "fit", "decay analysis", "decay SE", "difference [SE]", "unit"), [
            (_e(key_for(r["parameter"])[0]), *same_places([r["fit"], r["decay"], r["decay_se"]], r["decay_se"]),
             _num(r["difference_in_se"], "+.3g"), _e(key_for(r["parameter"])[1])) for r in rows], num=(1, 2, 3, 4)))
        parts.append("<p>The combined decrement law is exact for the linear model with sliders: a few standard errors "
                     "of difference are expected (fit and decay share the record); tens mean the record and the model "
                     "disagree.</p>")
    for text in result.warnings:
        parts.append(f"<p class=\"flag\">Warning: {_e(text)}</p>")
    for text in result.notes:
        parts.append(f"<p class=\"meta\">{_e(text)}</p>")
    parts.append(_effective_section(result))
    for stem, caption in BUILDING_FIGURES.items():
        parts.append(_figure(svgs, stem, caption,
                             zoom=(lambda: building_fit_zoom(result)) if stem == "building_fit" else None))
    return "\n".join(parts)


def render_building_report(result, svgs: dict[str, str], title: str = "Building free-vibration test", *,
                           provenance: dict[str, Any] | None = None, origin: Any = None) -> str:
    """The HTML report of ``quickrelease building``: the building section alone. ``origin`` is the case
    (its file and its ``[report]`` table); without it the record is the input named."""
    from ..io.runfolder import provenance as _provenance

    prov = provenance or _provenance(origin if origin is not None else result.source)
    parts = [*_front(title, prov, "case file" if origin is not None else "record",
                     [("record", _e(result.source))]),
             building_section(result, svgs), _signoff(getattr(origin, "report", None), prov)]
    return _page(title, parts)


def _building_design(b, period: float) -> str:
    """The assumed building's design values as the clearance check used them (HTML): the period, the damper's
    and the isolators' friction, each model in its own terms."""
    from .display import describe_isolation

    def pendulum(radius, period, friction_slow, friction_fast, rate):
        mu = (f"friction {_num(friction_slow, '.3g')}" if friction_fast in (None, friction_slow) or not rate
              else f"friction {_num(friction_slow, '.3g')} to {_num(friction_fast, '.3g')} "
                   f"(rate {_num(rate, '.3g')} s/m)")
        return f"R = {_num(radius, '.4g')} m (T = 2π√(R/g) = {_e(number(period, 6))} s), {mu} of the weight"

    render = {
        "pendulum": pendulum,
        "boucwen": lambda post_yield_stiffness, period, characteristic_strength, yield_displacement, shape: (
            f"K<sub>d</sub> = {_num(post_yield_stiffness / 1e3)} kN/m (T = {_e(number(period, 6))} s), "
            f"Q<sub>d</sub> = {_num(characteristic_strength / 1e3)} kN, d<sub>y</sub> = "
            f"{_num(1e3 * yield_displacement, '.4g')} mm, n = {_num(shape or 1.0, '.3g')}"),
        "period": lambda period: f"T = {_e(number(period, 6))} s",
        "power": lambda damping_coefficient, damping_exponent: (
            f"dampers C = {_num(damping_coefficient / 1e3)} kN (s/m)<sup>α</sup>, α = {_num(damping_exponent, '.3g')}"),
        "viscous": lambda damping_ratio: f"ζ = {_num(damping_ratio, '.3g')}",
        "friction": lambda friction: f"isolator friction {_num(friction / 1e3)} kN",
    }
    return describe_isolation(b.model, render, period=period if b.model in ("pendulum", "boucwen")
                              else b.initial_period, radius=b.radius, friction_slow=b.friction_slow,
                              friction_fast=b.friction_fast, rate=b.rate, post_yield_stiffness=b.post_yield_stiffness,
                              characteristic_strength=b.characteristic_strength,
                              yield_displacement=b.yield_displacement, shape=b.shape, power=b.damping == "power",
                              damping_coefficient=b.damping_coefficient, damping_exponent=b.damping_exponent,
                              damping_ratio=b.damping_ratio, friction=b.friction_force)


def _plan_section(plan, svgs: dict[str, str]) -> str:
    """Test planning: fuse and angle, member checks, release envelope, clearance with the building."""
    from ..studies.planning import ENVELOPE_QUANTITIES

    parts = ["<h2>Test planning</h2>",
             f"<p>Planned push: P = {_num(plan.push_force / 1e3)} kN at α0 = {_num(plan.alpha0)} rad, "
             f"E_S = {_num(plan.stored_energy)} J.</p>"]
    if plan.fuse is not None:
        ft = plan.fuse
        best = ft.best
        parts.append("<h3>Fuse and angle (Eq. 1: P = S / tan α0, S = f_u π d² / 4)</h3>")
        parts.append(f"<p>Target {_num(ft.target[0] / 1e3)} to {_num(ft.target[1] / 1e3)} kN; rupture "
                     f"strength {_num(ft.rupture_strength / 1e6)} ± "
                     f"{_num(ft.rupture_strength_std / 1e6, '.3g')} MPa. Most likely inside the target: "
                     f"d = {_num(1e3 * best.diameter)} mm at α0 = "
                     f"{_num(best.alpha0)} rad, P = {_num(best.push_force / 1e3)} ± "
                     f"{_num(best.push_force_std / 1e3, '.3g')} kN "
                     f"({_num(100 * best.probability_within, '.3g')}% inside).</p>")
        rows = [(f"d = {1e3 * c.diameter:.4g} mm, α0 = {c.alpha0:.4g} rad",
                 f"{_num(c.push_force / 1e3)} ± {_num(c.push_force_std / 1e3, '.3g')}",
                 f"{c.stored_energy:.5g} J; {100 * c.probability_within:.3g}%") for c in ft.choices if c.within]
        parts.append(_table(rows, ("choice inside the target", "push force [kN]", "E_S; chance inside the target")))
        for text in ft.warnings:
            parts.append(f"<p class=\"flag\">{_e(text)}</p>")
        parts.append(_figure(svgs, "plan_choices"))
    m = plan.members
    parts.append("<h3>Member checks</h3>")
    parts.append(_html_table(("member", "check", "demand", "capacity", "unit", "utilisation", "note"), [
        (_e(c.member), _e(c.check), _num(c.demand / (1e6 if c.unit == "Pa" else 1e3)),
         _num(None if c.capacity is None else c.capacity / (1e6 if c.unit == "Pa" else 1e3)),
         "MPa" if c.unit == "Pa" else "kN", _num(c.utilisation, ".3f"), _e(c.note)) for c in m.checks],
        num=(2, 3, 5)))
    over = [k for k, v in m.utilisation().items() if v is not None and v > 1]
    if over:
        parts.append(f"<p class=\"flag\">Over capacity: {_e(', '.join(over))}.</p>")
    if all(c.utilisation is None for c in m.checks):
        parts.append("<p class=\"meta\">No member was checked: the device file gives no capacity (yield "
                     "strengths, I1, W2, the fuse's rupture strength); the table above lists the demands.</p>")
    parts.append(_figure(svgs, "plan_utilisation"))
    env = plan.envelope
    parts.append("<h3>Release envelope</h3>")
    if env.samples > 1:
        parts.append(f"<p>Friction: {_e(env.friction)}; nominal F1 = {_num(env.F1)} N, "
                     f"F2 = {_num(env.F2)} N; {env.samples:,} samples; "
                     f"{_num(100 * env.geometric_limit_share, '.3g')}% reach the flat rhombus.</p>")
        parts.append(_html_table(("quantity", "nominal", "5%", "95%", "max", "unit"), [
            (_e(label), _num(env.nominal[k]), _num(env.ranges[k]["p5"]), _num(env.ranges[k]["p95"]),
             _num(env.ranges[k]["max"]), _e(unit_text(unit))) for k, (unit, label) in ENVELOPE_QUANTITIES.items()],
            num=(1, 2, 3, 4)))
    else:  # one friction value: no distribution, no percentiles, no histogram
        parts.append(f"<p>Friction: {_e(env.friction)}; F1 = {_num(env.F1)} N, F2 = {_num(env.F2)} N, one value "
                     "(no scatter given, so no distribution: give F1, F2 a scatter in [friction], or [friction] "
                     "case naming observations with one, for the envelope's ranges).</p>")
        parts.append(_html_table(("quantity", "value", "unit"), [
            (_e(label), _num(env.nominal[k]), _e(unit_text(unit))) for k, (unit, label) in ENVELOPE_QUANTITIES.items()],
            num=(1,)))
    parts.append(_figure(svgs, "plan_envelope"))
    if plan.clearance is not None:
        c = plan.clearance
        b = plan.case.building
        parts.append("<h3>Clearance with the building</h3>")
        verdict = ("<span class=\"flag\">CONTACT: the building reaches the front head "
                   f"(first at {_num(c.first_contact_time, '.3g')} s); {_num(1e3 * c.margin_needed)} mm more "
                   "room is needed</span>" if c.contact else "no contact: the head stays clear of the building")
        parts.append(f"<p>Building ({_e(b.model)}): {_building_design(b, c.building_period)}; pushed displacement d0 = "
                     f"{_num(1e3 * c.d0)} mm; {_e(c.describe_minimum())}; "
                     f"largest approach {_num(1e3 * c.max_approach)} mm. "
                     f"{verdict}.</p>")
        if plan.clearance_spread is not None:
            sp = plan.clearance_spread
            parts.append(f"<p>Over {sp['clearance_samples']} friction samples: 5% of the minimum gaps below "
                         f"{_num(sp['min_gap_p5_m'] and 1e3 * sp['min_gap_p5_m'])} mm; contact in "
                         f"{_num(100 * sp['contact_share'], '.3g')}% of them.</p>")
        parts.append(_figure(svgs, "plan_gap"))
    for text in plan.notes:
        if text not in plan.members.notes:  # those are in the member table's note column
            parts.append(f"<p class=\"meta\">{_e(text)}</p>")
    return "\n".join(parts)


def _figure(svgs: dict[str, str], stem: str, caption: str | None = None, zoom: Any = None) -> str:
    """The figure ``stem`` (its SVG from ``svgs``; nothing where it has none) with its caption; ``zoom``: a
    function giving its zoomable twin's HTML (:mod:`quickrelease.report.zoom`), drawn in its place on screen."""
    if stem not in svgs:
        return ""
    live = "" if zoom is None else zoom()
    return (f"<figure id=\"{stem}\">{_svg_inline(svgs[stem], stem)}{live}"
            f"<figcaption>{_e(caption or FIGURES[stem])}</figcaption></figure>")


def _slug(text: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", html.unescape(re.sub(r"<[^>]+>", "", text)).lower()).strip("-") or "section"


def _contents(body: str) -> str:
    """Give every ``<h2>`` an id (when it has none) and put a table of contents linking to them where
    :data:`_TOC` stands."""
    entries: list[tuple[str, str]] = []
    used = set(re.findall(r'\bid="([^"]+)"', body))

    def number(m: re.Match[str]) -> str:
        attrs, inner = m.group(1) or "", m.group(2)
        found = re.search(r'\bid="([^"]+)"', attrs)
        if found:
            ident = found.group(1)
        else:
            ident, k = f"sec-{_slug(inner)}", 2
            while ident in used:
                ident, k = f"sec-{_slug(inner)}-{k}", k + 1
            used.add(ident)
            attrs = f' id="{ident}"{attrs}'
        entries.append((ident, re.sub(r"<[^>]+>", "", inner)))
        return f"<h2{attrs}>{inner}</h2>"

    body = re.sub(r"<h2((?:\s[^>]*)?)>(.*?)</h2>", number, body, flags=re.S)
    items = "".join(f'<li><a href="#{ident}">{text}</a></li>' for ident, text in entries)
    toc = f'<nav class="toc" id="contents"><strong>Contents</strong><ol>{items}</ol></nav>' if entries else ""
    return body.replace(_TOC, toc, 1)


def _page(title: str, parts: list[str]) -> str:
    body = _contents("\n".join(p for p in parts if p))
    css, scripts = zoom_assets(body)  # uPlot inlined once, where a figure zooms
    return (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
            f"<title>{_e(title)} – quickrelease report</title><style>{_CSS}{css}</style></head>\n"
            f"<body>\n{body}\n{scripts}</body></html>\n")


def render_campaign_report(result, svgs: dict[str, str]) -> str:
    """The HTML report of a campaign: the tests, the friction laws with their significance, the figure."""
    from ..io.runfolder import provenance
    from ..studies.campaign import VARIABLES

    prov = provenance(result)
    signoff = _signoff(None, prov)
    parts = _front(result.title, prov, "campaign file")
    if result.notes:
        parts.append(f"<div class=\"notes\">{_e(result.notes)}</div>")
    if getattr(result, "kind", "device") == "building":
        parts += _building_campaign_section(result, svgs)
        parts.append(signoff)
        return _page(f"{result.title}", parts)
    parts.append("<h2>Friction per test</h2>")
    parts.append(_html_table(("test", "P [kN]", "α0 [rad]", "E_S [J]", "F1 [N] (± SE)", "F2 [N] (± SE)", "from"), [
        (_e(t.name), _num((t.case.push_force or math.nan) / 1e3), _num(t.case.alpha0), _num(t.case.stored_energy),
         _e(plus_minus(t.F1, t.F1_se)), _e(plus_minus(t.F2, t.F2_se)), _e(t.method)) for t in result.tests],
        num=range(1, 6)))
    parts.append("<h2>Friction laws F = a + b x</h2>")
    rows = []
    for law in result.laws.values():
        _, label, _, scale, unit = VARIABLES[law.variable]
        verdict = "<strong>yes</strong>" if law.significant else "no"
        rows.append((_e(law.friction), _e(label), _e(plus_minus(law.intercept, law.intercept_se)),
                     _e(plus_minus(law.slope / scale, law.slope_se / scale, f"N/{unit}")), _num(law.p_value, ".2g"),
                     verdict, _num(law.chi2_reduced, ".3g")))
    parts.append(_html_table(("friction", "x", "a [N]", "b", "p (b = 0)", "slope significant at 5%", "reduced χ²"),
                             rows, num=(2, 3, 4, 6)))
    parts.append("<p>Weighted by the tests' standard errors when every test has one; a reduced χ² above 1 (more "
                 "scatter about the line than the standard errors explain) inflates the law's covariance.</p>")
    for friction, joint in result.joint.items():
        terms = joint.summary()["terms"]
        units = {n: VARIABLES[n][3:] if n in VARIABLES else (1.0, "") for n in terms}
        text = ", ".join(f"{_e(n)}: {_e(plus_minus(v['value'] / units[n][0], v['se'] / units[n][0]))} "
                         f"N{'/' + units[n][1] if units[n][1] else ''} (p = {_num(v['p_value'], '.2g')})"
                         for n, v in terms.items())
        parts.append(f"<p>Joint law for {friction}: {text}.</p>")
    parts.append(_figure(svgs, "campaign_friction", "Friction against each variable: tests with 95% error bars, "
                                                    "the fitted law and its 95% confidence band"))
    parts.append(signoff)
    return _page(f"{result.title}", parts)


def _building_campaign_section(result, svgs: dict[str, str]) -> list[str]:
    """The building campaign's part of the report: each release's estimates with 95% intervals, the laws in
    the amplitude with their significance, the figure."""
    from ..studies.building_campaign import BUILDING_VARIABLES, QUANTITIES

    parts = [f"<h2>The isolation system per release ({_e(result.model)} model, mass "
             f"{_num(result.mass / 1e3)} t)</h2>"]
    head = [f"{QUANTITIES[q][4]} [{QUANTITIES[q][3]}] (95% interval)" for q in result.columns]
    rows = []
    for r in result.releases:
        cells = []
        for q in result.columns:
            scale = QUANTITIES[q][2]
            lo, hi = r.ci95[q]
            if not r.identified(q):  # no interval the record supports: left out of the laws
                cells.append(f"{_num(r.values[q] * scale)} (not identified)")
                continue
            cells.append(f"{_num(r.values[q] * scale)} [{_num(lo * scale)}, {_num(hi * scale)}]")
        force = "&ndash;" if r.force is None else _num(r.force / 1e3)
        warn = "; ".join(([f"refitted from {r.restarted_from}'s estimates"] if r.restarted_from else [])
                         + list(r.fit.warnings))
        rows.append((_e(r.name), _num(abs(r.d0) * 1e2), force, *cells, _e(warn)))
    parts.append(_html_table(("release", "|d0| [cm]", "P [kN]", *head, "warnings"), rows,
                             num=range(1, 3 + len(head))))
    parts.append("<h2>Laws in the amplitude q = a + b x</h2>")
    rows = []
    for law in result.laws.values():
        _, _, y_scale, y_unit, symbol = QUANTITIES[law.quantity]
        x_label, _, x_scale, x_unit = BUILDING_VARIABLES[law.variable]
        per = f"/{x_unit}" if x_unit != "-" else ""
        verdict = "<strong>yes</strong>" if law.significant else "no"
        rows.append((_e(symbol), _e(x_label), _e(plus_minus(law.intercept * y_scale, law.intercept_se * y_scale,
                                                             y_unit)),
                     _e(plus_minus(law.slope * y_scale / x_scale, law.slope_se * y_scale / x_scale, y_unit + per)),
                     _num(law.p_value, ".2g"), verdict, _num(law.chi2_reduced, ".3g")))
    parts.append(_html_table(("quantity", "x", "a", "b", "p (b = 0)", "slope significant at 5%", "reduced χ²"), rows,
                             num=(2, 3, 4, 6)))
    for q, names in getattr(result, "left_out", {}).items():
        parts.append(f"<p>{_e(QUANTITIES[q][4])}: release(s) {_e(', '.join(names))} left out of its laws (their "
                     "records do not identify it)" + ("" if any(k[0] == q for k in result.laws) else
                                                      "; fewer than three releases identify it: no law") + ".</p>")
    parts.append("<p>Each release fitted on its own; the laws weighted by the releases' standard errors (a "
                 "reduced χ² above 1 inflates the law's covariance). A linear spring with viscous damping and "
                 "Coulomb sliders keeps T, ζ and F_s constant, while its equivalent damping ζ_eq (the cycle's "
                 "dissipated energy over 4π times its strain energy) falls with the amplitude as 2 F_s / (π k d0): "
                 "a significant slope of T, ζ or F_s says the isolators depart from that model.</p>")
    parts.append(_figure(svgs, "campaign_building", "The isolation system against each variable: releases with "
                                                    "their 95% intervals, the fitted law and its 95% confidence band"))
    parts.extend(_cycle_laws_section(result))
    return parts


def _cycle_laws_section(result) -> list[str]:
    """keff and beta_eff of the releases' cycles pooled, and their laws in the cycle amplitude (none for 2dof)."""
    laws = getattr(result, "cycle_laws", {})
    if not laws:
        return []
    from ..studies.building_campaign import CYCLE_QUANTITIES

    rows = []
    for law in laws.values():
        _, _, y_scale, y_unit, symbol = CYCLE_QUANTITIES[law.quantity]
        x = "cycle amplitude D [m]" if law.variable == "displacement" else "ln(D / 1 m)"
        per = "/m" if law.variable == "displacement" else ""
        rows.append((_e(symbol), _e(x), _e(plus_minus(law.intercept * y_scale, law.intercept_se * y_scale, y_unit)),
                     _e(plus_minus(law.slope * y_scale, law.slope_se * y_scale, y_unit + per)),
                     _num(law.p_value, ".2g"), "<strong>yes</strong>" if law.significant else "no"))
    return ["<h2 id=\"campaign-cycles\">Engineering quantities of the cycles against their amplitude</h2>",
            f"<p>{len(result.cycles)} cycles of the releases' fitted models (each from a reversal to the turning "
            "point two half-cycles later; the cycle from the release left out), pooled: keff and beta_eff against "
            "the cycle's amplitude D, unweighted least squares (the cycles of one release share its fit's "
            "errors).</p>",
            _html_table(("quantity", "x", "a", "b", "p (b = 0)", "slope significant at 5%"), rows, num=(2, 3, 4))]


def _effective_section(result) -> str:
    """The engineering quantities per cycle beside the identified model's curve and band at each cycle's amplitude,
    and the spread of the cycles as the standards judge it (empty without a curve: 2dof)."""
    from .display import EFFECTIVE_HEADERS, effective_cycle_rows

    judgement = getattr(result, "effective_judgement", None)
    judged = None if judgement is None else judgement.summary()
    if not judged or not judged.get("cycles"):
        return ""
    curve = result.effective_curve
    parts = ["<h3 id=\"building-effective\">Engineering quantities per cycle</h3>",
             "<p>Per cycle of the fitted model's loop (a cycle runs from a turning point to the one two half-cycles "
             "later): amplitude D = (D+ - D-)/2, keff = (F+ - F-)/(D+ - D-), EDC the loop's area, beta_eff = EDC / "
             "(2 π keff D²), beside the identified model's value at the cycle's amplitude and its "
             f"{round(100 * curve.level)}% band.</p>",
             _html_table(EFFECTIVE_HEADERS, [tuple(_e(c) for c in row) for row in effective_cycle_rows(judged)],
                         num=range(1, 8))]
    rows = []
    for c in judged["criteria"]:
        verdict = "no cycle judged" if c["passed"] is None else ("pass" if c["passed"] else "FAIL")
        rows.append((_e(c["name"]), _e(c["demand"]), _num(c["worst"], ".3g"),
                     "-" if c["cycle"] is None else str(c["cycle"] + 1), _num(c["tolerance"], ".3g"),
                     verdict if verdict != "FAIL" else "<span class=\"flag\">FAIL</span>", _e(c["source"])))
    parts.append("<p>The spread of the cycles as the standards judge it: a free decay runs each cycle at its own "
                 "amplitude, so each cycle is judged against the model's curve at its amplitude, and the cycles' "
                 "ratios to it against their mean. The tolerances are parameters "
                 "(<code>judge_cycles(keff_tolerance=, edc_fraction=)</code>).</p>")
    parts.append(_html_table(("criterion", "demand", "worst", "at cycle", "limit", "verdict", "after"), rows,
                             num=(2, 3, 4)))
    for text in curve.notes:
        parts.append(f"<p class=\"meta\">{_e(text)}</p>")
    return "\n".join(parts)
