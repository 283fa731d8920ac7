"""Running a case file: identify (if observed), simulate, and write every result.

``run_case`` answers what a case file asks; ``write_results`` writes the time
histories (CSV, NetCDF), the summaries (JSON), the figures (PNG, SVG) and the HTML
report into a folder, each file atomically.
"""

from __future__ import annotations

import io
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .case import Case
from .errors import QuickReleaseError
from .identify import Identification, identify_friction
from .response import Response
from .solvers import simulate
from .statics import StrainEnergy

__all__ = ["CaseResult", "run_case", "write_results", "render_figures", "FIGURES"]

#: Figure stems and what they show.
FIGURES = {
    "fig13_response": "Fig. 13: position angle, angular velocity, angular acceleration, energy balance",
    "fig14_displacements": "Fig. 14: longitudinal and transverse displacements and velocities",
    "fig15_state_diagram": "Fig. 15: state diagram, numerical solutions over the analytic curve (Eq. 10)",
    "identification": "Stop time along the line of Eq. 13, with the measured t_F and the identified point",
    "strain_energy": "Strain energy stored before release by term (Eq. 2)",
}


@dataclass(frozen=True)
class CaseResult:
    """Everything a case produced."""

    case: Case
    response: Response
    """The release with the case's (or the identified) friction, by the case's method."""
    strain: StrainEnergy | None = None
    """Eq. 2 breakdown (when the push force is known)."""
    identification: Identification | None = None
    """The identified friction (when the case has observations)."""
    state_responses: list[Response] = field(default_factory=list)
    """Numerical solutions checked against Eq. 10 in Fig. 15 (Runge-Kutta and Table 6)."""

    def summary(self) -> dict[str, Any]:
        """The release summary: the keys of ``quickrelease simulate --json``."""
        return {"push_force_N": self.case.push_force, **self.response.summary(), "device": self.case.device.name}

    def identification_summary(self) -> dict[str, Any] | None:
        """The identification: the keys of ``quickrelease identify --json``."""
        if self.identification is None:
            return None
        return {**self.identification.summary(), "push_force_N": self.case.push_force,
                "device": self.case.device.name}


def run_case(case: Case, *, state_diagram: bool = True) -> CaseResult:
    """Do what the case asks: identify F1, F2 when observations are given, then simulate the release.

    With observations, the identified friction is used for the simulation (a [friction] table, if
    also present, is then only reported in the inputs).
    """
    ident = None
    if case.has_observations:
        ident = identify_friction(case.alpha0, case.alpha_final, case.stop_time, stored_energy=case.stored_energy,
                                  device=case.device, mass_model=case.mass_model)
        F1, F2 = ident.F1, ident.F2
    elif case.has_friction:
        F1, F2 = case.F1 or 0.0, case.F2 or 0.0
    else:
        raise QuickReleaseError(f"{case.source}: nothing to do: give [friction] to simulate or [observations] "
                                "to identify")
    common = dict(device=case.device, mass_model=case.mass_model)
    response = simulate(case.stored_energy, case.alpha0, F1, F2, method=case.method, dt=case.dt,
                        n_points=case.n_points, t_end=case.t_end, rk_method=case.rk_method, **common)
    states: list[Response] = []
    if state_diagram:
        states.append(response if case.method == "rk" else
                      simulate(case.stored_energy, case.alpha0, F1, F2, method="rk", **common))
        states.append(response if case.method == "explicit" else
                      simulate(case.stored_energy, case.alpha0, F1, F2, method="explicit", dt=case.dt, **common))
    return CaseResult(case=case, response=response, strain=case.strain(), identification=ident,
                      state_responses=states)


def render_figures(result: CaseResult) -> dict[str, Any]:
    """The figures of a case result as matplotlib Figures, keyed by the stems of :data:`FIGURES`."""
    from . import plots

    figs: dict[str, Any] = {
        "fig13_response": plots.fig13(result.response),
        "fig14_displacements": plots.fig14(result.response),
        "fig15_state_diagram": plots.fig15(result.state_responses or [result.response]),
    }
    if result.identification is not None:
        figs["identification"] = plots.identification_figure(result.identification)
    if result.strain is not None:
        figs["strain_energy"] = plots.strain_energy_figure(result.strain)
    return figs


def _svg_text(fig: Any) -> str:
    buf = io.StringIO()
    fig.savefig(buf, format="svg", metadata={"Date": None})
    return buf.getvalue()


def _start_in_child(work) -> int | None:
    """Run ``work`` in a forked child process (a second core renders while this one goes on).

    Returns the child's pid, or None where forking is not available or there is one core only.
    """
    if not hasattr(os, "fork") or (os.cpu_count() or 1) < 2:
        return None
    pid = os.fork()
    if pid == 0:  # pragma: no cover - runs in the child
        code = 1
        try:
            work()
            code = 0
        finally:
            os._exit(code)
    return pid


def _child_succeeded(pid: int | None) -> bool:
    if pid is None:
        return False
    _, status = os.waitpid(pid, 0)
    return os.waitstatus_to_exitcode(status) == 0


def write_results(result: CaseResult, out: str | Path, *, figures: bool = True, report: bool = True,
                  data: bool = True) -> dict[str, Path]:
    """Write a case's results into the folder ``out`` (created if needed); returns the paths by name.

    Files: ``summary.json`` (the ``simulate --json`` keys), ``identification.json`` (the ``identify
    --json`` keys, when identified), ``timeseries.csv`` and ``timeseries.nc`` (the time histories),
    ``figures/<stem>.png`` and ``.svg`` for each figure, and the self-contained ``report.html``.
    """
    from .export import write_csv, write_json, write_netcdf, write_text

    out = Path(out)
    paths: dict[str, Path] = {}
    if data:
        paths["summary"] = write_json(result.summary(), out / "summary.json")
        ident = result.identification_summary()
        if ident is not None:
            paths["identification"] = write_json(ident, out / "identification.json")
        paths["timeseries_csv"] = write_csv(result.response, out / "timeseries.csv")
        paths["timeseries_nc"] = write_netcdf(result.response, out / "timeseries.nc",
                                              attrs={"case": result.case.title})
    svgs: dict[str, str] = {}
    if figures or report:
        from .export import atomic_path

        figs = render_figures(result)
        pngs = {stem: out / "figures" / f"{stem}.png" for stem in figs} if figures else {}

        def write_pngs() -> None:
            for stem, path in pngs.items():
                with atomic_path(path) as tmp:
                    figs[stem].savefig(tmp, format="png", dpi=150)

        child = _start_in_child(write_pngs) if pngs else None
        for stem, fig in figs.items():
            svgs[stem] = _svg_text(fig)
            if figures:
                paths[f"{stem}.svg"] = write_text(svgs[stem], out / "figures" / f"{stem}.svg")
        if pngs and not _child_succeeded(child):
            write_pngs()  # no second core, no fork, or the child failed: do it here
        paths.update({f"{stem}.png": path for stem, path in pngs.items()})
    if report:
        from .report import render_report

        paths["report"] = write_text(render_report(result, svgs), out / "report.html")
    return paths
