"""Running a case file: identify (if observed), simulate, and write every result.

``run_case`` answers what a case file asks; ``write_results`` writes the time
histories (CSV, NetCDF), the summaries (JSON), the figures (PNG, SVG) and the HTML
report into a folder, each file atomically.
"""

from __future__ import annotations

import dataclasses
import io
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ._results import Summarised
from ._threads import check_threads
from .device.identify import Identification, identify_friction
from .device.response import Response
from .device.solvers import simulate
from .device.statics import StrainEnergy
from .io.case import Case
from .report.html import FIGURES
from .studies.fit import FitResult, case_friction, fit_record
from .studies.planning import PlanResult, plan_case, plan_figures

__all__ = ["CaseResult", "run_case", "write_results", "write_campaign_results", "render_figures", "FIGURES",
           "results_folder", "campaign_folder", "building_folder", "write_building_results", "identified_building"]


@dataclass(frozen=True, repr=False)
class CaseResult(Summarised):
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
    fit: FitResult | None = None
    """The fit to the measured record (when the case has a ``[record]``)."""
    plan: PlanResult | None = None
    """The test plan (when the case has ``[fuse]`` or ``[building]``, or it was asked for)."""
    building: Any = None
    """The building's analysis (:class:`~quickrelease.studies.building_analysis.BuildingResult`), when the case has a
    ``[building.record]``."""
    paper: Any = None
    """The Table 7 comparison (:class:`~quickrelease.device.paper.PaperComparison`), for the paper's case (``demo``):
    the report shows it, ``table7.json`` holds it."""

    def summary(self) -> dict[str, Any]:
        """The release summary: the keys of ``quickrelease simulate --json``."""
        return self.response.summary()

    def identification_summary(self) -> dict[str, Any] | None:
        """The identification: the keys of ``quickrelease identify --json``."""
        if self.identification is None:
            return None
        return {**self.identification.summary(), "push_force_N": self.case.push_force}


def run_case(case: Case, *, state_diagram: bool = True, plan: bool | None = None,
             threads: int | None = None) -> CaseResult:
    """Do what the case asks: fit a measured record, identify F1, F2 from stop observations, then simulate.

    With a ``[record]``, the fitted friction (and E_S, c when estimated) drives the simulation; else with
    observations, the identified friction; a ``[friction]`` table, if also present, is then only
    reported in the inputs. The test plan (:func:`quickrelease.studies.planning.plan_case`) is made when ``plan``
    is true, or by default when the case has a ``[fuse]`` or ``[building]`` table. ``threads``: threads of the
    plan's release envelope (1 to ``numba.config.NUMBA_NUM_THREADS``; default all cores), checked first.
    """
    check_threads(threads)
    ident = fit = None
    E_S, mass_model = case.stored_energy, case.mass_model
    if case.has_observations:
        ident = identify_friction(case.alpha0, case.alpha_final, case.stop_time, stored_energy=case.stored_energy,
                                  device=case.device, mass_model=case.mass_model)
        F1, F2 = ident.F1, ident.F2
    if case.record is not None:
        fit = fit_record(case)
        F1, F2, E_S, mass_model = fit.F1, fit.F2, fit.energy, fit.mass_factor
    elif ident is None:
        F1, F2, _ = case_friction(case)
    common = dict(device=case.device, mass_model=mass_model, push_force=case.push_force)
    response = simulate(E_S, case.alpha0, F1, F2, method=case.method, dt=case.dt,
                        n_points=case.n_points, t_end=case.t_end, rk_method=case.rk_method, **common)
    states: list[Response] = []
    if state_diagram:
        states.append(response if case.method == "rk" else
                      simulate(E_S, case.alpha0, F1, F2, method="rk", **common))
        states.append(response if case.method == "explicit" else
                      simulate(E_S, case.alpha0, F1, F2, method="explicit", dt=case.dt, **common))
    building = None
    if _has_building_record(case):
        from .io.building_case import load_building
        from .studies.building_analysis import analyse_building

        building = analyse_building(load_building(case))
    plan = _wants_plan(case, plan)
    planned = None
    if plan:  # the friction found above (fitted or identified) is not searched for again
        plan_input = case if case.has_friction or case.friction_case is not None else case.replace(F1=F1, F2=F2)
        note = None
        if building is not None and case.building is not None:
            spec, note = identified_building(case.building, building)
            plan_input = plan_input.replace(building=spec)
        planned = plan_case(plan_input, threads=threads)
        if note is not None:
            planned = dataclasses.replace(planned, notes=(*planned.notes, note))
    return CaseResult(case=case, response=response, strain=case.strain(), identification=ident,
                      state_responses=states, fit=fit, plan=planned, building=building)


def _has_building_record(case: Case) -> bool:
    """Whether the case file has a ``[building.record]`` (the whole test: the building is analysed too)."""
    return case.building is not None and getattr(case.building, "record", None) is not None


def identified_building(spec, building) -> tuple[Any, str]:
    """The ``[building]`` spec with the identified isolation in place of the assumed values, for the clearance
    check, and a note saying which values the check used.

    The linear fit gives the period, damping ratio and slider friction (the mass is the case's; the pushed
    displacement d0 is the one measured in the record). Where the spec cannot carry the fitted model (a
    bilinear or 2-DOF fit on a spec that only knows the linear building), the assumed values stay and the
    note says so.
    """
    from .studies.building_analysis import holds_constant_friction

    fit = building.fit
    flexible = getattr(fit, "flexible", False) and fit.model != "2dof"  # a layer under a flexible superstructure
    est = fit.parameters
    d0 = abs(float(fit.parameters["d0"])) if "d0" in fit.parameters else spec.displacement
    changes: dict[str, Any] = {"damping_ratio": est.get("damping_ratio", spec.damping_ratio),
                               "friction": est.get("friction", spec.friction_force), "friction_coefficient": None,
                               "mass": fit.mass, "displacement": d0}
    fields = {f.name for f in dataclasses.fields(spec)}
    if fit.model == "linear":
        changes.update(period=est["period"], k1=None, k2=None, yield_force=None)
    elif fit.model == "bilinear" and {"k1", "k2", "yield_force"} <= fields:
        iso = fit.isolation().rigid() if flexible else fit.isolation()  # (a flexible fit: its layer)
        changes.update(period=None, k1=iso.stiffness, k2=iso.k2, yield_force=float(iso.yield_force))
    elif fit.model == "2dof" and "period" in est:  # the clearance takes the superstructure as rigid on the layer
        changes.update(period=est["period"], k1=None, k2=None, yield_force=None)
    elif fit.model == "pendulum" and "radius" in fields:  # W x / R and mu(v) W: the sliders' mu_slow W holds the push
        iso = fit.isolation().rigid() if flexible else fit.isolation()  # (a flexible fit: its layer)
        changes.update(period=None, radius=float(iso.radius), friction_slow=float(iso.friction_slow),
                       friction_fast=float(iso.friction_fast), rate=float(iso.rate), friction=None,
                       friction_coefficient=float(iso.friction_slow))
        if holds_constant_friction(fit):  # one coefficient mu, as a case's friction_coefficient reads
            changes.update(friction_fast=None, rate=None)
    elif fit.model == "boucwen" and "post_yield_stiffness" in fields:
        iso = fit.isolation().rigid() if flexible else fit.isolation()  # (a flexible fit: its layer)
        changes.update(period=None, post_yield_stiffness=float(iso.k2),
                       characteristic_strength=float(iso.characteristic_strength),
                       yield_displacement=float(iso.yield_displacement), shape=float(iso.shape),
                       friction=float(iso.friction))
    else:
        return spec, (f"clearance checked with the assumed [building] values: the identified {fit.model} "
                      "isolation cannot be carried into the clearance check")
    if "model" in fields:
        changes["model"] = fit.model
    if fit.damping == "power":  # the fluid dampers' law, not a damping ratio
        changes.pop("damping_ratio")
        changes.update(damping="power", damping_coefficient=float(est["damping_coefficient"]),
                       damping_exponent=float(est["damping_exponent"]))
    changes = {k: v for k, v in changes.items() if k in fields}
    identified = dataclasses.replace(spec, **changes)
    # the pendulum's friction named once: mu for a constant coefficient, else Constantinou's mu_slow (to mu_fast)
    shown = {k: v for k, v in changes.items() if fit.model != "pendulum" or k != ("friction_slow" if
             holds_constant_friction(fit) else "friction_coefficient")}
    words = clearance_words(shown, fit.std_errors)
    return identified, (f"clearance checked with the building identified from its record ({fit.model} model: "
                        f"{words}), not the assumed [building] values")


#: The building values the clearance note names: spec field -> (name, fit parameter, unit shown, scale to it).
_NOTE_VALUES = {
    "period": ("period T", "period", "s", 1.0), "damping_ratio": ("damping ratio zeta", "damping_ratio", "", 1.0),
    "friction": ("slider friction F_s", "friction", "kN", 1e-3), "k1": ("initial stiffness k1", None, "kN/m", 1e-3),
    "k2": ("post-yield stiffness k2", None, "kN/m", 1e-3), "yield_force": ("yield force F_y", None, "kN", 1e-3),
    "radius": ("radius R", None, "m", 1.0), "friction_slow": ("friction mu_slow", "friction_slow", "", 1.0),
    "friction_coefficient": ("friction coefficient mu", "friction_slow", "", 1.0),
    "friction_fast": ("friction mu_fast", "friction_fast", "", 1.0), "rate": ("rate a", "rate", "s/m", 1.0),
    "post_yield_stiffness": ("post-yield stiffness Kd", None, "kN/m", 1e-3),
    "characteristic_strength": ("characteristic strength Qd", "characteristic_strength", "kN", 1e-3),
    "yield_displacement": ("yield displacement dy", "yield_displacement", "mm", 1e3),
    "shape": ("shape n", "shape", "", 1.0),
    "damping_coefficient": ("damper coefficient C", "damping_coefficient", "kN (s/m)^alpha", 1e-3),
    "damping_exponent": ("damper exponent alpha", "damping_exponent", "", 1.0),
    "mass": ("mass", None, "t", 1e-3), "displacement": ("pushed displacement d0", "d0", "mm", 1e3),
}


def clearance_words(values: dict[str, Any], std_errors: dict[str, float]) -> str:
    """The identified building values of the clearance note, each with its unit: ``period T = 2.000080 s,
    damping ratio zeta = 0.050009, slider friction F_s = 156.881 kN, mass = 800 t, pushed displacement d0 =
    182.496 mm``; a fitted value rounded where its standard error shows two digits, another to 5 significant
    digits."""
    from .report.display import number, same_places

    parts = []
    for key, (name, param, unit, scale) in _NOTE_VALUES.items():
        value = values.get(key)
        if not isinstance(value, float):
            continue
        se = std_errors.get(param) if param is not None else None
        se = None if se is None else abs(float(se)) * scale
        shown = abs(value) * scale if key == "displacement" else value * scale
        text = number(shown) if se is None or not se > 0 else same_places([shown], se)[0]
        parts.append(f"{name} = {text} {unit}".rstrip())
    return ", ".join(parts)


def _wants_plan(case: Case, plan: bool | None) -> bool:
    return plan if plan is not None else (case.fuse is not None or case.building is not None)


def results_folder(case: Case, out: str | Path, *, plan: bool | None = None, figures: bool = True,
                   report: bool = True, data: bool = True, overwrite: bool = False):
    """The :class:`~quickrelease.io.runfolder.RunFolder` that :func:`write_results` writes a case's results
    through; making it checks ``out`` before the work (pre-flight) and writes nothing."""
    from .io.runfolder import RunFolder, case_inputs

    inputs = {"case": case_inputs(case), "plan": _wants_plan(case, plan), "figures": figures, "report": report,
              "data": data}
    return RunFolder(out, "case results", inputs, overwrite=overwrite)


def render_figures(result: CaseResult) -> dict[str, Any]:
    """The figures of a case result as matplotlib Figures, keyed by the stems of :data:`FIGURES`."""
    from .report import plots

    figs: dict[str, Any] = {
        "fig13_response": plots.fig13(result.response),
        "fig14_displacements": plots.fig14(result.response),
        "fig15_state_diagram": plots.fig15(result.state_responses or [result.response]),
    }
    if result.identification is not None:
        figs["identification"] = plots.identification_figure(result.identification)
    if result.strain is not None:
        figs["strain_energy"] = plots.strain_energy_figure(result.strain)
    if result.fit is not None and result.fit.record is not None:
        figs["fit_channels"] = plots.fit_figure(result.fit)
    if result.plan is not None:
        figs.update(plan_figures(result.plan))
    if result.building is not None:
        from .report.building_plots import building_figures

        figs.update(building_figures(result.building))
    return figs


def _svg_text(fig: Any) -> str:
    import matplotlib

    from .report._style import STYLE

    buf = io.StringIO()
    with matplotlib.rc_context(STYLE):  # the svg settings (text as text, stable ids) are read at save time
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
                  data: bool = True, overwrite: bool = False) -> dict[str, Path]:
    """Write a case's results into the folder ``out`` (created if needed); returns the paths by name.

    Files: ``summary.json`` (the ``simulate --json`` keys), ``identification.json`` (the ``identify
    --json`` keys, when identified), ``timeseries.csv`` and ``timeseries.nc`` (the time histories),
    ``figures/<stem>.png`` and ``.svg`` for each figure, the self-contained ``report.html``, and
    ``manifest.json`` (the fingerprint of the inputs). The whole folder is written beside ``out`` and moved
    into place at the end (:class:`~quickrelease.io.runfolder.RunFolder`): a failure leaves the previous
    result; a folder holding another run's results is refused unless ``overwrite``, and then replaced.
    """
    folder = results_folder(result.case, out, plan=result.plan is not None, figures=figures, report=report,
                            data=data, overwrite=overwrite)
    with folder.staged() as work:
        paths = _write_results_into(result, work, figures=figures, report=report, data=data)
    return {name: folder.final(path) for name, path in paths.items()}


def _write_results_into(result: CaseResult, out: Path, *, figures: bool, report: bool,
                        data: bool) -> dict[str, Path]:
    from .io.export import write_csv, write_json, write_netcdf, write_text
    from .io.runfolder import provenance

    paths: dict[str, Path] = {}
    prov = provenance(result.case)
    if data:
        paths["summary"] = write_json(result.summary(), out / "summary.json", prov)
        ident = result.identification_summary()
        if ident is not None:
            paths["identification"] = write_json(ident, out / "identification.json", prov)
        if result.fit is not None:
            paths["fit"] = write_json(result.fit.summary(), out / "fit.json", prov)
        if result.plan is not None:
            paths["plan"] = write_json(result.plan.summary(), out / "plan.json", prov)
        if result.building is not None:
            paths["building"] = write_json(result.building.summary(), out / "building.json", prov)
        if result.paper is not None:
            paths["table7"] = write_json(result.paper.summary(), out / "table7.json", prov)
        paths["timeseries_csv"] = write_csv(result.response, out / "timeseries.csv")
        paths["timeseries_nc"] = write_netcdf(result.response, out / "timeseries.nc",
                                              attrs={"case": result.case.title}, provenance=prov)
    svgs: dict[str, str] = {}
    if figures or report:
        from .io.export import atomic_path

        figs = render_figures(result)
        pngs = {stem: out / "figures" / f"{stem}.png" for stem in figs} if figures else {}

        def write_pngs() -> None:
            import matplotlib

            from .report._style import STYLE

            for stem, path in pngs.items():
                with atomic_path(path) as tmp, matplotlib.rc_context(STYLE):
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
        from .report.html import render_report

        paths["report"] = write_text(render_report(result, svgs), out / "report.html")
    return paths


def building_folder(result_or_data, out: str | Path, *, model: str | None = None, compare: bool = False,
                    overwrite: bool = False):
    """The :class:`~quickrelease.io.runfolder.RunFolder` of ``quickrelease building`` (pre-flight: writes nothing).

    The fingerprint holds what the analysis depends on: the channels (their samples by SHA-256, not the
    record's path), the mass, the model, the start values and the release time given, and ``compare``.
    """
    from .io.runfolder import RunFolder

    data = result_or_data
    inputs = {"channels": list(data.channels), "mass": data.mass, "model": model or data.model,
              "start": dict(data.start or {}), "release_time": data.release_time, "compare": bool(compare)}
    return RunFolder(out, "building results", inputs, overwrite=overwrite)


def write_building_results(result, data, out: str | Path, *, model: str | None = None, compare: bool = False,
                           title: str = "Building free-vibration test", overwrite: bool = False,
                           origin: Any = None) -> dict[str, Path]:
    """Write ``quickrelease building``'s results into ``out``: ``summary.json`` (the ``--json`` keys), the
    record, the fitted model and the residuals as a time series (``timeseries.csv``, ``timeseries.nc`` on the
    time coordinate ``t``: :func:`quickrelease.io.frames.fit_columns`), the building figures
    (``figures/<stem>.png``/``.svg``), ``report.html`` and ``manifest.json``, staged and moved into place as
    :func:`write_results` does; returns the paths by name. ``origin`` (the case) is what the files' provenance
    names (:func:`~quickrelease.io.runfolder.provenance`; by default the record)."""
    from .io.export import write_columns, write_dataset, write_json, write_text
    from .io.frames import fit_columns, fit_dataset
    from .io.runfolder import provenance
    from .report.building_plots import building_figures
    from .report.html import render_building_report
    from .report.plots import save_figure

    prov = provenance(origin if origin is not None else result.source)
    folder = building_folder(data, out, model=model, compare=compare, overwrite=overwrite)
    with folder.staged() as work:
        paths = {"summary": write_json(result.summary(), work / "summary.json", prov),
                 "timeseries_csv": write_columns(fit_columns(result.fit), work / "timeseries.csv"),
                 "timeseries_nc": write_dataset(fit_dataset(result.fit), work / "timeseries.nc", prov)}
        svgs = {}
        for stem, fig in building_figures(result).items():
            for fmt, path in save_figure(fig, work / "figures", stem).items():
                paths[f"{stem}.{fmt}"] = path
            svgs[stem] = paths[f"{stem}.svg"].read_text(encoding="utf-8")
        paths["report"] = write_text(render_building_report(result, svgs, title, provenance=prov, origin=origin),
                                     work / "report.html")
    return {name: folder.final(path) for name, path in paths.items()}


def campaign_folder(campaign_file: str | Path, out: str | Path, *, overwrite: bool = False):
    """The :class:`~quickrelease.io.runfolder.RunFolder` of a campaign's results (pre-flight: writes nothing).

    Its inputs are the campaign file and every file its tests name (``record``, ``case``) by their SHA-256:
    an edited record is another run."""
    import tomllib

    from .io.runfolder import RunFolder, _file_digest

    path = Path(campaign_file)
    files = {}
    try:
        tests = tomllib.loads(path.read_text(encoding="utf-8")).get("tests", [])
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        tests = []  # reported by the campaign's own reading
    for i, test in enumerate(tests if isinstance(tests, list) else []):
        for key in ("record", "case"):
            name = test.get(key) if isinstance(test, dict) else None
            if isinstance(name, str):
                file = Path(name) if Path(name).is_absolute() else path.parent / name
                files[f"tests[{i}].{key}"] = _file_digest(file)
    return RunFolder(out, "campaign results", {"campaign_file": _file_digest(path), "files": files},
                     overwrite=overwrite)


def write_campaign_results(result, out: str | Path, *, overwrite: bool = False) -> dict[str, Path]:
    """Write a campaign's results into ``out``: ``campaign.json``, ``figures/campaign_friction.png``/``.svg``
    (a building campaign: ``figures/campaign_building``) and the self-contained ``report.html`` (staged and
    moved into place as :func:`write_results` does); returns the paths by name."""
    from .io.export import write_json, write_text
    from .io.runfolder import provenance
    from .report.html import render_campaign_report
    from .report.plots import save_figure

    if getattr(result, "kind", "device") == "building":
        from .studies.building_campaign import building_campaign_figure as figure
        stem = "campaign_building"
    else:
        from .studies.campaign import campaign_figure as figure
        stem = "campaign_friction"
    folder = campaign_folder(result.source, out, overwrite=overwrite)
    with folder.staged() as work:
        paths = {"campaign": write_json(result.summary(), work / "campaign.json", provenance(result))}
        fig = figure(result)
        for fmt, path in save_figure(fig, work / "figures", stem).items():
            paths[f"{stem}.{fmt}"] = path
        svg = paths[f"{stem}.svg"].read_text(encoding="utf-8")
        paths["report"] = write_text(render_campaign_report(result, {stem: svg}), work / "report.html")
    return {name: folder.final(path) for name, path in paths.items()}
