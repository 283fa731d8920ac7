"""The paper's printed values and our reproduction of them (Table 7, Fig. 14).

The paper prints rounded numbers: E_S = 2.90 kJ, t_F = 1.05 s, alpha_F = 0.7378 rad,
F1 = 0.4056 kN, F2 = 0.8154 kN. This module keeps them as printed (in
``data/paper.toml``), derives each one's rounding interval from the digits
printed, and computes what quantifies every difference between the paper and
us. Nothing here is tuned to reach a printed value.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, fields
from functools import lru_cache
from importlib import resources
from typing import Any

from .._results import Summarised
from .._roots import brent
from ..units import parse_quantity
from . import dynamics
from .identify import identify_friction, stop_time_on_line
from .parameters import Device, preset
from .solvers import simulate
from .statics import strain_energy

__all__ = ["PrintedValue", "printed_table7", "PaperComparison", "reproduce_table7"]

_KINDS = {"P": "force", "alpha0": "angle", "alpha_final": "angle", "E_S": "energy",
          "t_F": "time", "F1": "force", "F2": "force"}


@dataclass(frozen=True)
class PrintedValue:
    """A value as printed in the paper, in SI, with its rounding interval."""

    name: str
    text: str
    """As printed, with its unit (``"2.90 kJ"``)."""
    value: float
    """In SI units."""
    half_unit: float
    """Half a unit of the last printed digit, in SI: the rounding error bound."""

    @property
    def interval(self) -> tuple[float, float]:
        """Every value that prints as ``text`` [SI]."""
        return (self.value - self.half_unit, self.value + self.half_unit)


@lru_cache(maxsize=1)
def _paper_data() -> dict[str, Any]:
    text = (resources.files("quickrelease") / "data" / "paper.toml").read_text(encoding="utf-8")
    return tomllib.loads(text)


def printed_table7() -> dict[str, PrintedValue]:
    """Table 7 as printed: P, alpha0, alpha_final, E_S, t_F, F1, F2."""
    out = {}
    for name, entry in _paper_data()["table7"].items():
        digits = entry["value"]
        decimals = len(digits.split(".")[1]) if "." in digits else 0
        unit = entry["unit"]
        value = parse_quantity(f"{digits} {unit}", _KINDS[name], name)
        half = parse_quantity(f"{0.5 * 10.0 ** -decimals!r} {unit}", _KINDS[name], name)
        out[name] = PrintedValue(name, f"{digits} {unit}", value, half)
    return out


#: SI unit suffix of each printed Table 7 value in :meth:`PaperComparison.summary` (``printed_F1_N``).
PRINTED_UNITS = {"P": "N", "alpha0": "rad", "alpha_final": "rad", "E_S": "J", "t_F": "s", "F1": "N", "F2": "N"}

#: The key of each comparison field in :meth:`PaperComparison.summary` (``quickrelease demo --json``,
#: ``table7.json``): the name with its SI unit, as every command's JSON; fields not named keep their name.
SUMMARY_KEYS = {
    "E_S_eq2": "E_S_eq2_J", "E_S_breakdown": "E_S_breakdown_J", "P_for_printed_E_S": "P_for_printed_E_S_N",
    "F1_printed_inputs": "F1_printed_inputs_N", "F2_printed_inputs": "F2_printed_inputs_N",
    "F1_max": "F1_max_N", "F2_max": "F2_max_N", "F1_eq2": "F1_eq2_N", "F2_eq2": "F2_eq2_N",
    "F1_range_t_F": "F1_range_t_F_N", "F1_range_all": "F1_range_all_N", "F2_range_all": "F2_range_all_N",
    "t_F_for_paper_F1": "t_F_for_paper_F1_s", "E_S_implied_by_paper_pair": "E_S_implied_by_paper_pair_J",
    "paper_pair_alpha_final": "paper_pair_alpha_final_rad", "paper_pair_stop_time": "paper_pair_stop_time_s",
    "paper_pair_stop_time_on_line": "paper_pair_stop_time_on_line_s",
    "lumped_feasible_stop_times": "lumped_feasible_stop_time_s", "feasible_stop_times": "feasible_stop_time_s",
    "peak_u_dot": "peak_u_dot_m_s", "peak_v_dot": "peak_v_dot_m_s", "u_final": "u_final_m", "v_final": "v_final_m",
    "alpha_dot0": "alpha_dot0_rad_s",
}


@dataclass(frozen=True, repr=False)
class PaperComparison(Summarised):
    """Our numbers beside the paper's for the Table 7 test, with what explains the gaps.

    All values SI. ``rows()`` gives the side-by-side table the CLI and README show.
    """

    printed: dict[str, PrintedValue]
    E_S_eq2: float
    """E_S from Eq. 2 with Table 2's data at P = 1598 kN, alpha0 = 0.2 rad [J]."""
    E_S_breakdown: dict[str, float]
    """The six terms of Eq. 2 [J]."""
    P_for_printed_E_S: float
    """The push force for which Eq. 2 gives exactly 2900 J [N]."""
    F1_printed_inputs: float
    """F1 identified from Table 7's printed inputs (E_S = 2900 J, t_F = 1.05 s) [N]."""
    F2_printed_inputs: float
    F1_max: float
    F2_max: float
    F1_eq2: float
    """F1 identified with E_S from Eq. 2 instead of the printed 2.90 kJ [N]."""
    F2_eq2: float
    F1_range_t_F: tuple[float, float]
    """F1 for t_F over its rounding interval [1.045, 1.055] s, E_S = 2900 J [N]."""
    F1_range_all: tuple[float, float]
    """F1 over the rounding box of E_S, t_F, alpha0 and alpha_F together [N]."""
    F2_range_all: tuple[float, float]
    t_F_for_paper_F1: float
    """The measured t_F that makes our identification return the paper's F1 [s]."""
    E_S_implied_by_paper_pair: float
    """E_S that puts the paper's (F1, F2) on the line of Eq. 13 (Eq. 8 at alpha_F = 0.7378) [J]."""
    line_sum_paper_pair: float
    """F1/F1* + F2/F2* of the paper's pair with the printed E_S (1 on the line of Eq. 13)."""
    paper_pair_alpha_final: float
    """alpha_F our model gives for the paper's (F1, F2) and E_S = 2900 J [rad]."""
    paper_pair_stop_time: float
    """t_F our model gives for the paper's (F1, F2) and E_S = 2900 J [s]."""
    paper_pair_stop_time_on_line: float
    """t_F our model gives for the paper's (F1, F2) with the E_S that puts them on Eq. 13 [s]."""
    lumped_feasible_stop_times: tuple[float, float]
    """What the lumped mass model (c = 1) can produce on the line of Eq. 13 [s]."""
    feasible_stop_times: tuple[float, float]
    """What the model of the comparison can produce on the line of Eq. 13, printed E_S [s]."""
    mass_factor: float
    """c of the model of the comparison (Eq. 3-6) [-]."""
    peak_u_dot: float
    """Peak head velocity of the identified release [m/s] (Fig. 14b)."""
    peak_v_dot: float
    """Peak opening velocity [m/s] (Fig. 14b)."""
    u_final: float
    v_final: float
    alpha_dot0: float

    def _t_F_note(self) -> str:
        """Whether the t_F that gives the paper's F1 prints as the paper's t_F (its rounding interval)."""
        t = self.printed["t_F"]
        lo, hi = t.interval
        where = "inside" if lo <= self.t_F_for_paper_F1 <= hi else "outside"
        return f"{where} the rounding of {t.text} ([{lo:.4g}, {hi:.4g}] s)"

    def _lumped_note(self) -> str:
        """Whether the printed t_F (any value that prints as it) is feasible with the lumped mass (c = 1), and
        with the distributed model (c = 2/3) the identification used, from the computed intervals."""
        t = self.printed["t_F"]
        lo, hi = t.interval
        a, b = self.lumped_feasible_stop_times
        if hi < a or lo > b:
            lumped = f"{t.text} is infeasible with c = 1"
        elif a <= lo and hi <= b:
            lumped = f"{t.text} is feasible with c = 1"
        else:
            lumped = f"part of the rounding of {t.text} is feasible with c = 1"
        c0, c1 = self.feasible_stop_times
        if c0 <= t.value <= c1:
            return f"{lumped}; feasible with c = {self.mass_factor:.4g} ([{c0:.4f}, {c1:.4f}] s)"
        return f"{lumped}; infeasible with c = {self.mass_factor:.4g} too"

    def summary(self) -> dict[str, Any]:
        """Every computed value (SI; intervals as two-element lists), the printed Table 7 values as
        ``printed_<name>`` (SI) and the side-by-side ``table7`` rows: what ``quickrelease demo --json`` prints
        and ``table7.json`` holds. Keys end in their SI unit as every other command's (``F1_eq2_N``,
        ``feasible_stop_time_s``; :data:`SUMMARY_KEYS`); ``line_sum_paper_pair`` and ``mass_factor`` are
        dimensionless."""
        out: dict[str, Any] = {}
        for k, v in self.printed.items():
            unit = PRINTED_UNITS.get(k, "")
            out[f"printed_{k}_{unit}" if unit else f"printed_{k}"] = v.value
        for f in fields(self):
            if f.name == "printed":
                continue
            value = getattr(self, f.name)
            out[SUMMARY_KEYS.get(f.name, f.name)] = list(value) if isinstance(value, tuple) else value
        out["table7"] = [dict(zip(("quantity", "paper", "quickrelease", "note"), row, strict=True))
                         for row in self.rows()]
        return out

    def rows(self) -> list[tuple[str, str, str, str]]:
        """(quantity, paper, ours, note) rows for a side-by-side table."""
        p = self.printed
        return [
            ("E_S (Eq. 2, P = 1598 kN)", p["E_S"].text, f"{self.E_S_eq2 / 1e3:.4f} kJ",
             f"+{100 * (self.E_S_eq2 / p['E_S'].value - 1):.2f}%; "
             f"{p['E_S'].text} needs P = {self.P_for_printed_E_S / 1e3:.1f} kN"),
            ("F1* (Eq. 11)", "-", f"{self.F1_max / 1e3:.4f} kN", "from printed E_S, alpha0, alpha_F"),
            ("F2* (Eq. 12)", "-", f"{self.F2_max / 1e3:.4f} kN", ""),
            ("F1 (Table 7 inputs)", p["F1"].text, f"{self.F1_printed_inputs / 1e3:.4f} kN",
             f"t_F in [{p['t_F'].interval[0]:.4g}, {p['t_F'].interval[1]:.4g}] s gives F1 in "
             f"[{self.F1_range_t_F[0] / 1e3:.4f}, {self.F1_range_t_F[1] / 1e3:.4f}] kN"),
            ("F2 (Table 7 inputs)", p["F2"].text, f"{self.F2_printed_inputs / 1e3:.4f} kN",
             f"all inputs' rounding: "
             f"[{self.F2_range_all[0] / 1e3:.4f}, {self.F2_range_all[1] / 1e3:.4f}] kN"),
            ("F1 (E_S from Eq. 2)", "-", f"{self.F1_eq2 / 1e3:.4f} kN", "E_S = our Eq. 2 value"),
            ("F2 (E_S from Eq. 2)", "-", f"{self.F2_eq2 / 1e3:.4f} kN", ""),
            ("t_F giving the paper's F1", p["t_F"].text, f"{self.t_F_for_paper_F1:.4f} s", self._t_F_note()),
            ("E_S on Eq. 13 for paper's pair", p["E_S"].text,
             f"{self.E_S_implied_by_paper_pair / 1e3:.4f} kJ",
             f"F1/F1* + F2/F2* = {self.line_sum_paper_pair:.4f} (1 on the line)"),
            ("alpha_F, t_F of paper's pair", f"{p['alpha_final'].text}, {p['t_F'].text}",
             f"{self.paper_pair_alpha_final:.4f} rad, {self.paper_pair_stop_time:.4f} s", "our model, E_S = 2900 J"),
            ("t_F of paper's pair on Eq. 13", p["t_F"].text, f"{self.paper_pair_stop_time_on_line:.4f} s",
             f"E_S = {self.E_S_implied_by_paper_pair:.1f} J, alpha_F = {p['alpha_final'].text}"),
            ("t_F range, lumped mass (c = 1)", p["t_F"].text,
             f"[{self.lumped_feasible_stop_times[0]:.4f}, {self.lumped_feasible_stop_times[1]:.4f}] s",
             self._lumped_note()),
            ("peak v_dot (Fig. 14b)", "2 to 3 m/s", f"{self.peak_v_dot:.3f} m/s", ""),
            ("peak u_dot (Fig. 14b)", "~1 m/s", f"{self.peak_u_dot:.3f} m/s", ""),
        ]


def reproduce_table7(device: Device | None = None, mass_model: str | float = "distributed") -> PaperComparison:
    """Reproduce Table 7 and quantify every difference by the paper's rounding.

    Runs the identification with the printed inputs, with E_S from Eq. 2, over the
    rounding intervals of the printed inputs, and checks the paper's own (F1, F2)
    against Eq. 8 and Eq. 13.
    """
    device = device or preset("paper")
    p = printed_table7()
    P, a0, aF, ES, tF = (p[k].value for k in ("P", "alpha0", "alpha_final", "E_S", "t_F"))
    se = strain_energy(P, a0, device)
    ident = identify_friction(a0, aF, tF, stored_energy=ES, device=device, mass_model=mass_model)
    ident_eq2 = identify_friction(a0, aF, tF, stored_energy=se.total, device=device, mass_model=mass_model)
    lo_t, hi_t = p["t_F"].interval
    F1_t = tuple(identify_friction(a0, aF, t, stored_energy=ES, device=device,
                                   mass_model=mass_model).F1 for t in (lo_t, hi_t))
    corners = []
    for E in p["E_S"].interval:
        for t in p["t_F"].interval:
            for x0 in p["alpha0"].interval:
                for xF in p["alpha_final"].interval:
                    r = identify_friction(x0, xF, t, stored_energy=E, device=device, mass_model=mass_model)
                    corners.append((r.F1, r.F2))
    F1s, F2s = [c[0] for c in corners], [c[1] for c in corners]
    paper_F1, paper_F2 = p["F1"].value, p["F2"].value
    t_paper = brent(lambda t: identify_friction(a0, aF, t, stored_energy=ES, device=device,
                                                mass_model=mass_model).F1 - paper_F1,
                    ident.feasible_stop_times[0] + 1e-9, ident.feasible_stop_times[1] - 1e-9, xtol=1e-12)
    E_implied = float(dynamics.dissipated_energy(aF, a0, paper_F1, paper_F2, device.L1))
    pair = simulate(ES, a0, paper_F1, paper_F2, device=device, mass_model=mass_model)
    pair_on_line = simulate(E_implied, a0, paper_F1, paper_F2, device=device, mass_model=mass_model)
    lumped_line = tuple(
        stop_time_on_line(F1, ES, a0, aF, device=device, mass_model="lumped") for F1 in (0.0, ident.F1_max)
    )
    release = simulate(ES, a0, ident.F1, ident.F2, device=device, mass_model=mass_model)
    summary = release.summary()
    return PaperComparison(
        printed=p,
        E_S_eq2=se.total,
        E_S_breakdown=se.terms(),
        P_for_printed_E_S=P * math.sqrt(ES / se.total),
        F1_printed_inputs=ident.F1, F2_printed_inputs=ident.F2,
        F1_max=ident.F1_max, F2_max=ident.F2_max,
        F1_eq2=ident_eq2.F1, F2_eq2=ident_eq2.F2,
        F1_range_t_F=(min(F1_t), max(F1_t)),
        F1_range_all=(min(F1s), max(F1s)), F2_range_all=(min(F2s), max(F2s)),
        t_F_for_paper_F1=float(t_paper),
        E_S_implied_by_paper_pair=E_implied,
        line_sum_paper_pair=paper_F1 / ident.F1_max + paper_F2 / ident.F2_max,
        paper_pair_alpha_final=pair.alpha_final, paper_pair_stop_time=pair.stop_time,
        paper_pair_stop_time_on_line=pair_on_line.stop_time, lumped_feasible_stop_times=lumped_line,
        feasible_stop_times=tuple(ident.feasible_stop_times), mass_factor=float(release.mass_factor),
        peak_u_dot=summary["peak_u_dot_m_s"], peak_v_dot=summary["peak_v_dot_m_s"],
        u_final=release.u_final, v_final=release.v_final, alpha_dot0=release.alpha_dot0,
    )
