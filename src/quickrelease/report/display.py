"""Quantities for people: the names and rounded values the command line's tables print.

Results travel as dictionaries keyed the way JSON needs them (``push_force_N``, ``stop_time_s``: the SI
unit is the key's suffix). A table for a person shows ``push force P`` and ``1598 kN`` instead. This module
maps one to the other and nothing else; every key not known here is still shown, with its underscores
as spaces and its unit taken from the suffix.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

from .._results import register_formatters

#: (key suffix, unit as printed, whether SI prefixes k/M/G apply), longest suffix first.
UNIT_SUFFIXES: tuple[tuple[str, str, bool], ...] = (
    ("_per_s", "/s", False),  # a rate: cases per second (bench)
    ("_rad_s2", "rad/s²", False),
    ("_rad_s", "rad/s", False),
    ("_m_s2", "m/s²", False),
    ("_m_s", "m/s", False),
    ("_N_m", "N/m", True),
    ("_N_s_m", "N·s/m", True),
    ("_s_m", "s/m", False),  # a slowness: Constantinou's rate of the friction pendulum
    ("_rad", "rad", False),
    ("_deg", "°", False),
    ("_kg", "kg", False),
    ("_Hz", "Hz", False),
    ("_Pa", "Pa", True),
    ("_N", "N", True),
    ("_J", "J", True),
    ("_s", "s", False),
    ("_m", "m", False),
)

#: Human names of the keys the summaries use (without the unit suffix).
NAMES: dict[str, str] = {
    "push_force": "push force P",
    "stored_energy": "stored energy E_S",
    "alpha0": "release angle alpha0",
    "alpha_dot0": "initial rate alpha_dot0",
    "alpha_final": "final angle alpha_F",
    "stop_time": "stop time t_F",
    "stopped_by": "stopped by",
    "mass_factor": "mass factor c",
    "F1": "hinge friction F1",
    "F2": "rail friction F2",
    "F1_max": "largest hinge friction F1*",
    "F2_max": "largest rail friction F2*",
    "u_final": "head travel u_F",
    "v_final": "opening v_F",
    "peak_alpha_dot": "peak rate alpha_dot",
    "peak_u_dot": "peak head velocity u_dot",
    "peak_v_dot": "peak opening velocity v_dot",
    "peak_u_ddot": "peak head acceleration u_ddot",
    "peak_v_ddot": "peak opening acceleration v_ddot",
    "feasible_stop_time": "feasible stop times",
    "samples": "samples",
    "method": "method",
    "device": "device",
}

_PREFIXES = ((1e9, "G"), (1e6, "M"), (1e3, "k"))

#: Units whose values take the SI prefixes k, M, G in tables (forces, energies, stresses, stiffnesses).
PREFIXABLE = frozenset({"N", "J", "Pa", "N/m", "N·s/m", "W"})

#: Parameters known by a bare name (a fit's unknowns, the building's estimates): name -> (human name, unit).
#: A name not here is shown with its underscores as spaces; ``offset_<channel>`` is "offset of <channel>".
PARAMETERS: dict[str, tuple[str, str]] = {
    "force": ("push force P", "N"),
    "push_force": ("push force P", "N"),
    "alpha0": ("release angle alpha0", "rad"),
    "F1": ("hinge friction F1", "N"),
    "F2": ("rail friction F2", "N"),
    "energy": ("stored energy E_S", "J"),
    "stored_energy": ("stored energy E_S", "J"),
    "mass_factor": ("mass factor c", ""),
    "release_time": ("release instant", "s"),
    "period": ("period T", "s"),
    "k1": ("initial stiffness k1", "N/m"),
    "k2": ("post-yield stiffness k2", "N/m"),
    "Fy": ("yield force F_y", "N"),
    "damping_ratio": ("damping ratio zeta", ""),
    "friction": ("slider friction F_s", "N"),
    "friction_coefficient": ("friction coefficient mu", ""),
    "d0": ("initial displacement d0", "m"),
    "superstructure_period": ("superstructure period T_s", "s"),
    "superstructure_damping_ratio": ("superstructure damping ratio zeta_s", ""),
    "alpha_final": ("final angle alpha_F", "rad"),
    "stop_time": ("stop time t_F", "s"),
}


def split_key(key: str) -> tuple[str, str, bool]:
    """(name, unit, prefixable) of a summary key: ``"push_force_N"`` -> ``("push_force", "N", True)``;
    a key without a unit suffix has unit ``""``."""
    for suffix, unit, prefixable in UNIT_SUFFIXES:
        if key.endswith(suffix) and len(key) > len(suffix):
            return key[: -len(suffix)], unit, prefixable
    return key, "", False


def label(key: str) -> str:
    """The name a person reads for a summary key: ``"push_force_N"`` -> ``"push force P"``."""
    name, _, _ = split_key(key)
    return NAMES.get(name, name.replace("_", " "))


def number(value: float, digits: int = 5, zeros: bool = False) -> str:
    """``value`` rounded to ``digits`` significant digits, without a trailing exponent where it fits;
    ``zeros``: keep trailing zeros (``0.40``, an uncertainty's two digits)."""
    if not math.isfinite(value):
        return str(value)
    if value == 0.0:
        return "0"
    text = f"{value:#.{digits}g}".rstrip(".") if zeros else f"{value:.{digits}g}"
    return text.replace("e+0", "e").replace("e-0", "e-").replace("e+", "e")


def _scale(values: list[float], prefixable: bool) -> tuple[float, str]:
    """The SI prefix for a group of values: the largest step below the largest magnitude (k for 1598e3)."""
    if not prefixable:
        return 1.0, ""
    big = max((abs(v) for v in values if math.isfinite(v)), default=0.0)
    for factor, prefix in _PREFIXES:
        if big >= 10 * factor:
            return factor, prefix
    return 1.0, ""


def value_text(key: str, value: Any, digits: int = 5) -> str:
    """``value`` for a person, with the unit of ``key``: ``("push_force_N", 1.598e6)`` -> ``"1598 kN"``;
    intervals as ``"[0.9906, 1.1243] s"``; ``None`` as ``"-"``; booleans as yes/no."""
    _, unit, prefixable = split_key(key)
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        factor, prefix = _scale([float(value)], prefixable)
        text = str(value) if isinstance(value, int) and not unit else number(float(value) / factor, digits)
        return f"{text} {prefix}{unit}".rstrip()
    if isinstance(value, (list, tuple)) and value and all(isinstance(v, (int, float)) for v in value):
        factor, prefix = _scale([float(v) for v in value], prefixable)
        inner = ", ".join(number(float(v) / factor, digits) for v in value)
        return f"[{inner}] {prefix}{unit}".rstrip()
    return str(value)


def unit_text(unit: str) -> str:
    """A unit as a person reads it: ``"m/s^2"`` -> ``"m/s²"``; ``"-"`` (dimensionless) -> ``""``."""
    return "" if unit in ("-", "1") else unit.replace("^2", "²").replace("^3", "³")


def key_for(name: str, unit: str | None = None) -> tuple[str, str]:
    """(human name, unit) of a parameter known by a bare name: ``"F1"`` -> ``("hinge friction F1", "N")``;
    ``unit`` (SI, e.g. a record channel's) overrides the table's; ``offset_u`` -> ``("offset of u", unit)``."""
    human, known = PARAMETERS.get(name, (None, ""))
    if human is None and name.startswith("offset_"):
        human = f"offset of {name.removeprefix('offset_')}"
    if human is None and name.startswith("drift_"):
        human = f"drift of {name.removeprefix('drift_')}'s zero"
    return human or name.replace("_", " "), unit_text(known if unit is None else unit)


def quantity(value: float | None, unit: str = "", digits: int = 5) -> str:
    """``value`` [SI ``unit``] for a person: ``(1.598e6, "N")`` -> ``"1598 kN"``; ``None`` -> ``"-"``."""
    if value is None:
        return "-"
    unit = unit_text(unit)
    factor, prefix = _scale([float(value)], unit in PREFIXABLE)
    return f"{number(float(value) / factor, digits)} {prefix}{unit}".rstrip()


def _decimals(se: float, digits: int) -> int:
    """Decimal places that show ``se`` with ``digits`` significant digits."""
    return max(0, digits - 1 - math.floor(math.log10(abs(se))))


def plus_minus(value: float | None, se: float | None, unit: str = "", se_digits: int = 2) -> str:
    """``value ± se`` with the unit once, ``value`` rounded where ``se`` is (``se`` to two significant digits),
    as a result is quoted: ``(420.023, 0.398, "N")`` -> ``"420.02 ± 0.40 N"``; ``(1.598e6, 3.9e4, "N")``
    -> ``"1598 ± 39 kN"``. Without a finite, positive ``se``: the value alone (5 significant digits)."""
    if value is None:
        return "-"
    if se is not None and math.isinf(se) and math.isfinite(value):  # a parameter the record does not see
        return f"{quantity(value, unit)} (not identified)"
    if se is None or not math.isfinite(se) or se <= 0 or not math.isfinite(value):
        return quantity(value, unit)
    unit = unit_text(unit)
    factor, prefix = _scale([float(value)], unit in PREFIXABLE)
    v, e = float(value) / factor, float(se) / factor
    if abs(v) >= 1e6 or (v != 0 and abs(v) < 1e-3) or e < 1e-4:  # far from 1: both in the exponent form
        text = f"{number(v)} ± {number(e, se_digits)}"
    else:
        e = float(f"{e:.{se_digits}g}")  # the error to its digits first: 996 -> 1000 (then hundreds, not tens)
        places = min(se_digits - 1 - math.floor(math.log10(e)), 8)
        if places >= 0:
            text = f"{v:.{places}f} ± {e:.{places}f}"
        else:  # an error of hundreds or more: both rounded to its two digits (223 ± 996 -> 200 ± 1000)
            text = f"{round(v, places):.0f} ± {round(e, places):.0f}"
    return f"{text} {prefix}{unit}".rstrip()


def interval(bounds: Iterable[float] | None, unit: str = "", digits: int = 5) -> str:
    """``[lo, hi] unit`` with one SI prefix for both ends; ``None`` -> ``"-"``."""
    if bounds is None:
        return "-"
    values = [float(b) for b in bounds]
    unit = unit_text(unit)
    factor, prefix = _scale(values, unit in PREFIXABLE)
    inner = ", ".join(number(v / factor, digits) for v in values)
    return f"[{inner}] {prefix}{unit}".rstrip()


def places_for(width: float, digits: int = 2) -> int:
    """Decimal places that show ``width`` (a standard error, or an interval's half-width) to ``digits``
    significant digits, the width rounded first (``0.996`` -> ``1.0``: one place, not two); negative for
    tens, hundreds (``996`` -> ``-2``). ``width`` must be finite and positive."""
    rounded = float(f"{abs(width):.{digits}g}")
    return digits - 1 - math.floor(math.log10(rounded))


def fixed(value: float, places: int) -> str:
    """``value`` rounded to ``places`` decimal places (negative: to tens, hundreds), as text: ``(2.0000802,
    6)`` -> ``"2.000080"``, ``(223.0, -2)`` -> ``"200"``; ``-0`` is written ``0``."""
    if places >= 0:
        text = f"{value:.{places}f}"
    else:
        text = f"{round(value, places):.0f}"
    return text[1:] if text.startswith("-") and float(text) == 0.0 else text


def same_places(values: Iterable[float | None], width: float | None, digits: int = 2, sig: int = 5) -> list[str]:
    """``values`` (an estimate, its error, its interval's ends) all rounded to one decimal place: where
    ``width`` (the standard error, else the interval's half-width) shows ``digits`` significant digits, so
    that the digits printed are the ones the uncertainty supports (2.0000802 with an interval half-width of
    5.7e-5 is ``2.000080``, not ``2.0001``). Without a finite positive ``width``: ``sig`` significant digits of
    the first value. Far from 1 (|value| < 1e-3 or >= 1e6) in the exponent form, to the same last digit.
    ``None`` -> ``"-"``."""
    values = list(values)
    finite = [float(v) for v in values if v is not None and math.isfinite(float(v))]
    lead = finite[0] if finite else 0.0

    def far(v: float) -> bool:
        return v != 0.0 and not 1e-3 <= abs(v) < 1e6

    out = []
    good = width is not None and math.isfinite(width) and width > 0
    for v in values:
        if v is None:
            out.append("-")
        elif not math.isfinite(float(v)):
            out.append(str(float(v)))
        elif not good:
            out.append(_alike([float(v)], lead, sig)[0])
        elif far(lead) or places_for(width, digits) > 9:  # the last digit kept is 10^-places
            exponent = math.floor(math.log10(abs(float(v)))) if float(v) != 0.0 else 0
            out.append(number(float(v), max(1, min(exponent + places_for(width, digits) + 1, 15)), zeros=True))
        else:
            out.append(fixed(float(v), places_for(width, digits)))
    return out


def _alike(values: list[float], lead: float, digits: int = 5) -> list[str]:
    """``values`` with the decimal places that show ``lead`` to ``digits`` significant digits (an interval
    printed like its estimate: ``[2.0000, 2.0001]``, not ``[2, 2.0001]``); exponent form far from 1. Used
    only where no uncertainty is known (:func:`same_places` otherwise)."""
    if not math.isfinite(lead) or lead == 0.0 or not 1e-3 <= abs(lead) < 1e6 \
            or not all(math.isfinite(v) for v in values):
        return [number(v, digits) for v in values]
    places = min(_decimals(lead, digits), 9)
    return [f"{v:.{places}f}" for v in values]


def half_width(ci: Iterable[float | None] | None) -> float | None:
    """Half the width of an interval ``[lo, hi]`` (None when an end is missing or not finite)."""
    if ci is None:
        return None
    ends = list(ci)
    if len(ends) != 2 or any(b is None or not math.isfinite(float(b)) for b in ends):
        return None
    return 0.5 * abs(float(ends[1]) - float(ends[0]))


def estimate_row(name: str, value: float | None, se: float | None = None, ci: Iterable[float] | None = None,
                 unit: str | None = None) -> tuple[str, str, str, str]:
    """(parameter, estimate, standard error, 95% interval) of one estimate for the tables of fits: the
    parameter's human name (:func:`key_for`); the error to 2 significant digits and the value and the
    interval's ends rounded to the same decimal place (:func:`same_places`; without an error, to the
    interval's half-width; without either, 5 significant digits), all with the unit and the SI prefix of the
    value (``12.35 MN/m``, ``0.23 MN/m``, ``[12.00, 13.00] MN/m``)."""
    human, u = key_for(name, unit)
    if value is None:
        return human, "-", "-", "-"
    factor, prefix = _scale([float(value)], u in PREFIXABLE)
    suffix = f" {prefix}{u}".rstrip()
    lead = float(value) / factor
    if se is not None and math.isinf(se):  # a parameter the record does not see: no error, no interval
        return human, _alike([lead], lead)[0] + suffix, "not identified", "not identified"
    ci = None if ci is None else list(ci)
    has_ci = ci is not None and not any(b is None for b in ci)
    scaled_ci = [float(b) / factor for b in ci] if has_ci else []
    se_scaled = None if se is None or not math.isfinite(se) or se <= 0 else float(se) / factor
    width = se_scaled if se_scaled is not None else half_width(scaled_ci if has_ci else None)
    texts = same_places([lead, *scaled_ci, se_scaled], width)
    se_text = "-" if se_scaled is None else texts[-1] + suffix
    ci_text = "[" + ", ".join(texts[1:-1]) + "]" + suffix if has_ci else "-"
    return human, texts[0] + suffix, se_text, ci_text


def quantity_rows(summary: Mapping[str, Any], skip: Iterable[str] = ()) -> list[tuple[str, str]]:
    """(name, value with unit) rows of a summary dictionary for a two-column table."""
    left_out = set(skip)
    return [(label(k), value_text(k, v)) for k, v in summary.items() if k not in left_out]


def _shown(value: Any) -> bool:
    """Whether a summary value fits a one-line repr: a scalar, a string, or a short list of numbers."""
    if value is None or isinstance(value, (bool, int, float, str)):
        return True
    return isinstance(value, (list, tuple)) and len(value) <= 4 and all(isinstance(v, (int, float)) for v in value)


def short_repr(name: str, summary: Mapping[str, Any], keys: Iterable[str] = ()) -> str:
    """``Name(F1=419.85 N, F2=804.57 N, ...)``: the chosen (else the first five) scalar entries of a summary,
    rounded, with units; never the whole device or the arrays."""
    chosen = [k for k in keys if k in summary] or [k for k, v in summary.items() if _shown(v)][:5]
    inner = ", ".join(f"{split_key(k)[0]}={value_text(k, summary[k])}" for k in chosen)
    return f"{name}({inner})"


def summary_html(name: str, summary: Mapping[str, Any]) -> str:
    """An HTML table of a summary for notebooks (``_repr_html_``): human names and values with units;
    nested entries (per-channel tables, lists of tests) summarised by their size."""
    import html

    rows = []
    for key, value in summary.items():
        text = value_text(key, value) if _shown(value) else f"({len(value)} entries)" \
            if isinstance(value, (dict, list, tuple)) else str(value)
        rows.append(f"<tr><th style=\"text-align:left\">{html.escape(label(key))}</th>"
                    f"<td style=\"text-align:left\">{html.escape(text)}</td></tr>")
    return f"<table><caption style=\"text-align:left\"><b>{html.escape(name)}</b></caption>{''.join(rows)}</table>"


#: Headers of :func:`effective_cycle_rows` (the per-cycle table of the building's engineering quantities).
EFFECTIVE_HEADERS = ("cycle", "D [mm]", "keff [kN/m]", "model keff (95% band) [kN/m]", "EDC [kJ]",
                     "model EDC (95% band) [kJ]", "beta_eff [%]", "model beta_eff (95% band) [%]", "judged")


def _band(value: float | None, lo: float | None, hi: float | None, scale: float, digits: int = 5) -> str:
    """``value (lo .. hi)`` scaled, the three with the same decimals (the band's width sets them); "-"
    without a value."""
    if value is None:
        return "-"
    if lo is None or hi is None:
        return number(value * scale, digits)
    a, b, c = same_places([value * scale, lo * scale, hi * scale], (hi - lo) * scale, 2, digits)
    return f"{a} ({b} .. {c})"


def effective_cycle_rows(judgement: Mapping[str, Any]) -> list[tuple[str, ...]]:
    """The per-cycle table of a building's engineering quantities (:data:`EFFECTIVE_HEADERS`) from the summary of
    a :class:`~quickrelease.studies.building_effective.CycleJudgement`: each cycle's amplitude, keff, EDC and
    beta_eff beside the identified model's value and 95% band at that amplitude, and whether it is judged."""
    rows = []
    for r in judgement.get("cycles", ()):
        note = "yes" if r["judged"] else ("no: from the release" if r["from_release"] else "no: outside the curve")
        rows.append((str(r["cycle"] + 1), number(r["amplitude_m"] * 1e3, 4), number(r["keff_N_m"] / 1e3, 5),
                     _band(r["keff_model_N_m"], r["keff_lo_N_m"], r["keff_hi_N_m"], 1e-3),
                     number(r["edc_J"] / 1e3, 4), _band(r["edc_model_J"], r["edc_lo_J"], r["edc_hi_J"], 1e-3),
                     number(r["beta_eff"] * 1e2, 4),
                     _band(r["beta_model"], r["beta_lo"], r["beta_hi"], 1e2), note))
    return rows


#: Headers of :func:`effective_quantity_rows`.
CYCLE_HEADERS = ("cycle", "start [s]", "D [mm]", "keff [kN/m]", "EDC [kJ]", "beta_eff [%]", "Teff [s]", "judged")


def _judged_text(r: Mapping[str, Any]) -> str:
    return "yes" if r["judged"] else ("release" if r["from_release"] else "outside")


def effective_quantity_rows(judgement: Mapping[str, Any], cycles: Iterable[Mapping[str, Any]]) -> list[tuple[str, ...]]:
    """Per cycle (the summaries of :class:`~quickrelease.building.effective.CycleProperties`, in the order of the
    judgement's rows): start, amplitude, keff, EDC, beta_eff, Teff and whether the cycle is judged
    (:data:`CYCLE_HEADERS`)."""
    rows = []
    for r, c in zip(judgement.get("cycles", ()), cycles, strict=False):
        teff = c.get("teff_s")
        rows.append((str(r["cycle"] + 1), number(c["start_s"], 5), number(c["amplitude_m"] * 1e3, 4),
                     number(c["keff_N_m"] / 1e3, 5), number(c["edc_J"] / 1e3, 4), number(c["beta_eff"] * 1e2, 4),
                     "-" if teff is None else number(teff, 4), _judged_text(r)))
    return rows


#: Headers of :func:`effective_deviation_rows`.
DEVIATION_HEADERS = ("cycle", "keff - model [%]", "band [%]", "EDC - model [%]", "band [%]", "beta_eff - model [%]",
                     "band [%]")


def effective_deviation_rows(judgement: Mapping[str, Any]) -> list[tuple[str, ...]]:
    """Per cycle: its keff, EDC and beta_eff against the identified model's at its amplitude, in percent of the
    model's, each beside the half-width of the model's band there (percent of the model); "-" where the cycle's
    amplitude is outside the model's curve (:data:`DEVIATION_HEADERS`)."""
    rows = []
    for r in judgement.get("cycles", ()):
        cells = [str(r["cycle"] + 1)]
        for short, sfx in (("keff", "_N_m"), ("edc", "_J"), ("beta", "")):
            model, lo, hi = r[f"{short}_model{sfx}"], r[f"{short}_lo{sfx}"], r[f"{short}_hi{sfx}"]
            ratio = r[f"{short}_ratio"]
            if model is None or ratio is None:
                cells += ["-", "-"]
                continue
            half = None if lo is None or hi is None else 50.0 * (hi - lo) / model
            dev = 100.0 * (ratio - 1.0)
            text = fixed(dev, min(places_for(half, 2), 6)) if half else number(dev, 3)
            cells += [text if text.startswith("-") else "+" + text, "-" if half is None else "±" + number(half, 2)]
        rows.append(tuple(cells))
    return rows


#: Headers of :func:`spread_rows`.
SPREAD_HEADERS = ("criterion", "worst", "at cycle", "limit", "verdict")


def spread_rows(judgement: Mapping[str, Any]) -> list[tuple[str, ...]]:
    """The spread of the cycles about the model's curve as the standards judge it, one row per criterion (from
    a :class:`~quickrelease.studies.building_effective.CycleJudgement`'s summary)."""
    rows = []
    for c in judgement.get("criteria", ()):
        verdict = "no cycle judged" if c["passed"] is None else ("pass" if c["passed"] else "FAIL")
        rows.append((c["name"], "-" if c["worst"] is None else number(c["worst"], 3),
                     "-" if c["cycle"] is None else str(c["cycle"] + 1), number(c["tolerance"], 3), verdict))
    return rows


# The result protocol (quickrelease._results) formats reprs and notebook tables with these two.
register_formatters(short_repr, summary_html)


def describe_isolation(model: str, render: Mapping[str, Any], *, period: float, radius: float | None = None,
                       friction_slow: float | None = None, friction_fast: float | None = None,
                       rate: float | None = None, post_yield_stiffness: float | None = None,
                       characteristic_strength: float | None = None, yield_displacement: float | None = None,
                       shape: float | None = None, power: bool = False, damping_coefficient: float | None = None,
                       damping_exponent: float | None = None, damping_ratio: float = 0.0,
                       friction: float = 0.0) -> str:
    """An isolation system's design in its model's terms, for a person: one describer for the synthetic truth
    (:func:`quickrelease.studies.synth.describe_truth`, text) and the planned building (the report's HTML).

    The terms, in order: the model's stiffness (``"pendulum"``: radius R [m], period T [s], friction_slow,
    friction_fast [-] and rate [s/m]; ``"boucwen"``: Kd [N/m], T, Qd [N], dy [m], shape n; otherwise ``"period"``:
    T), then the damper (``"power"``: C [N (s/m)^alpha] and alpha; ``"viscous"``: zeta), then, but for the
    pendulum whose friction is in its own term, the sliders' ``"friction"`` [N]. ``render`` maps each term's name
    to a function of its values (keyword arguments as above) giving its text; the texts are joined by ", "."""
    if model == "pendulum":
        terms = [("pendulum", dict(radius=radius, period=period, friction_slow=friction_slow,
                                   friction_fast=friction_fast, rate=rate))]
    elif model == "boucwen":
        terms = [("boucwen", dict(post_yield_stiffness=post_yield_stiffness, period=period,
                                  characteristic_strength=characteristic_strength,
                                  yield_displacement=yield_displacement, shape=shape))]
    else:
        terms = [("period", dict(period=period))]
    terms.append(("power", dict(damping_coefficient=damping_coefficient, damping_exponent=damping_exponent))
                 if power else ("viscous", dict(damping_ratio=damping_ratio)))
    if model != "pendulum":
        terms.append(("friction", dict(friction=friction)))
    return ", ".join(render[name](**values) for name, values in terms)
