"""Test campaigns: friction identified test by test, and how it depends on the load and the angle.

The paper closes: "It may be interesting to see in future experiments how the friction forces are
influenced by the amplitude of the applied load and by the initial configuration angle." A campaign
file lists several tests of one device (different P and alpha0); each test is fitted to its record
(:func:`quickrelease.studies.fit.fit_record`, with standard errors), or identified from its stop observations
(with standard errors when they are given with a scatter). Then for each friction force and each
variable x (the push force P, the angle alpha0, or E_S) the linear law ``F = a + b x`` is fitted by
weighted least squares (weights 1/SE^2 when every test has a standard error), with its 95% confidence
band and a t test of ``b = 0``; when the campaign has four tests or more, also the joint law
``F = a + b P + c alpha0``, which separates the two effects when P and alpha0 vary together.

Campaign file::

    title = "..."
    variables = ["force", "alpha0"]    # optional; also "energy"

    [device]                           # shared by every test (as in a case file)
    preset = "paper"
    [test]                             # defaults for every test (e.g. mass_model)
    mass_model = "distributed"
    [record]                           # template: time column and channel mapping of the records
    time = "t_s"
    [record.channels]
    u = "u_m"
    [fit]                              # options of every fit

    [[tests]]
    name = "T1"
    force = "1000 kN"
    alpha0 = "0.22 rad"
    record = "records/T1.csv"          # fit this record; or alpha_final and stop_time (stop
                                       # observations, optionally {value, std}); or case = "t1.toml"
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._results import Summarised
from ..device.parameters import read_toml
from ..errors import ParameterError, QuickReleaseError
from ..io.case import Case, CaseFileError, case_from_mapping, load_case
from ..io.records import Record
from ..report._style import styled
from ._laws import LinearLaw, _p_value, _wls, fit_line, iter_tests, law_panel, weights_or_none
from .fit import FitResult, fit_record, load_case_record, observation_sigma

__all__ = ["CampaignTest", "LinearLaw", "Law", "JointLaw", "CampaignResult", "load_campaign", "run_campaign",
           "fit_law", "fit_line", "weights_or_none", "law_panel", "VARIABLES"]

#: Regressors of the friction laws: (attribute of Case, label, unit, scale for plots, plot unit).
VARIABLES = {
    "force": ("push_force", "push force P", "N", 1e-3, "kN"),
    "alpha0": ("alpha0", "initial angle alpha0", "rad", 1.0, "rad"),
    "energy": ("stored_energy", "stored energy E_S", "J", 1e-3, "kJ"),
}
_TEST_KEYS = {"name", "case", "record", "release_time", "force", "energy", "alpha0", "mass_model", "alpha_final",
              "stop_time"}
_TOP_KEYS = {"title", "notes", "variables", "device", "test", "record", "fit", "simulation", "tests"}


@dataclass(frozen=True, eq=False)
class CampaignTest:
    """One test of a campaign and the friction found for it."""

    name: str
    case: Case
    F1: float
    F2: float
    F1_se: float | None
    """Standard error of F1 [N]; None for an exact identification from stop observations."""
    F2_se: float | None
    method: str
    """``"fit to record"``, ``"stop observations with scatter"`` or ``"stop observations"``."""
    fit: FitResult | None = field(default=None, repr=False)

    def value(self, variable: str) -> float:
        attr = VARIABLES[variable][0]
        v = getattr(self.case, attr)
        if v is None:
            raise QuickReleaseError(f"{self.case.source}: test {self.name} has no {VARIABLES[variable][1]} "
                                    f"(give it, or drop {variable!r} from variables)")
        return float(v)

    def summary(self) -> dict[str, Any]:
        return {"name": self.name, "push_force_N": self.case.push_force, "alpha0_rad": self.case.alpha0,
                "stored_energy_J": self.case.stored_energy, "F1_N": self.F1, "F2_N": self.F2,
                "F1_se_N": self.F1_se, "F2_se_N": self.F2_se, "method": self.method,
                "warnings": list(self.fit.warnings) if self.fit is not None else []}


@dataclass(frozen=True)
class Law(LinearLaw):
    """A friction law of the device campaign, ``F = intercept + slope x`` [N]."""

    @property
    def friction(self) -> str:
        return self.quantity

    def summary(self) -> dict[str, Any]:
        unit = VARIABLES[self.variable][2]
        return {"friction": self.friction, "variable": self.variable, "law": f"{self.friction} = a + b {self.variable}",
                "a_N": self.intercept, "a_se_N": self.intercept_se, f"b_N_per_{unit}": self.slope,
                f"b_se_N_per_{unit}": self.slope_se, "t": self.t_statistic, "p_value": self.p_value,
                "significant_5pct": self.significant, "dof": self.dof, "chi2_reduced": self.chi2_reduced,
                "weighted": self.weighted}


@dataclass(frozen=True)
class JointLaw:
    """``F = a + b P + c alpha0`` (with the variables of the campaign), by (weighted) least squares."""

    friction: str
    variables: tuple[str, ...]
    coefficients: np.ndarray
    covariance: np.ndarray
    dof: int
    chi2_reduced: float
    weighted: bool

    def summary(self) -> dict[str, Any]:
        se = np.sqrt(np.diag(self.covariance))
        names = ["intercept", *self.variables]
        out = {"friction": self.friction, "law": f"{self.friction} = a + " + " + ".join(
            f"b_{v} {v}" for v in self.variables), "dof": self.dof, "chi2_reduced": self.chi2_reduced,
            "weighted": self.weighted, "terms": {}}
        for i, n in enumerate(names):
            t = self.coefficients[i] / se[i] if se[i] > 0 else math.inf
            out["terms"][n] = {"value": float(self.coefficients[i]), "se": float(se[i]), "t": float(t),
                               "p_value": _p_value(t, self.dof), "significant_5pct": _p_value(t, self.dof) < 0.05}
        return out


def _standard_errors(tests: list[CampaignTest], friction: str) -> np.ndarray | None:
    return weights_or_none(getattr(t, f"{friction}_se") for t in tests)


def fit_law(tests: list[CampaignTest], friction: str, variable: str) -> Law:
    """Fit ``friction = a + b variable`` over the tests (weighted when every test has a standard error)."""
    x = np.array([t.value(variable) for t in tests])
    y = np.array([getattr(t, friction) for t in tests])
    if np.ptp(x) == 0:
        raise QuickReleaseError(f"every test has the same {VARIABLES[variable][1]}: no law in {variable} can be fitted")
    return fit_line(x, y, _standard_errors(tests, friction), quantity=friction, variable=variable, law_type=Law)


def fit_joint(tests: list[CampaignTest], friction: str, variables: tuple[str, ...]) -> JointLaw:
    X = np.column_stack([np.ones(len(tests))] + [np.array([t.value(v) for t in tests]) for v in variables])
    y = np.array([getattr(t, friction) for t in tests])
    se = _standard_errors(tests, friction)
    beta, cov, dof, red = _wls(X, y, se)
    return JointLaw(friction=friction, variables=variables, coefficients=beta, covariance=cov, dof=dof,
                    chi2_reduced=red, weighted=se is not None)


@dataclass(frozen=True, eq=False, repr=False)
class CampaignResult(Summarised):
    """Friction per test and the laws fitted over the campaign."""

    title: str
    source: str
    tests: list[CampaignTest]
    laws: dict[tuple[str, str], Law]
    """(friction, variable) -> law."""
    joint: dict[str, JointLaw]
    """friction -> joint law in all variables (four tests or more)."""
    variables: tuple[str, ...]
    notes: str = ""

    def summary(self) -> dict[str, Any]:
        """JSON-ready: the keys of ``quickrelease campaign --json``."""
        return {"title": self.title, "campaign": self.source, "variables": list(self.variables),
                "tests": [t.summary() for t in self.tests],
                "laws": [law.summary() for law in self.laws.values()],
                "joint": {k: v.summary() for k, v in self.joint.items()}}


def _campaign_cases(path: Path) -> tuple[dict[str, Any], list[tuple[str, Case]]]:
    data = read_toml(path, "campaign file", CaseFileError)
    source = str(path)
    unknown = sorted(set(data) - _TOP_KEYS)
    if unknown:
        raise CaseFileError(f"{source}: unknown key {unknown[0]!r}; valid: {', '.join(sorted(_TOP_KEYS))}")
    tests = data.get("tests")
    if not isinstance(tests, list) or not tests:
        raise CaseFileError(f"{source}: missing [[tests]]: give one table per test (name, force, alpha0, record, "
                            "...)")
    template = {k: data[k] for k in ("device", "test", "record", "fit", "simulation") if k in data}
    cases = []
    for name, where, entry in iter_tests(tests, source, "T"):
        bad = sorted(set(entry) - _TEST_KEYS)
        if bad:
            raise CaseFileError(f"{where}: unknown key {bad[0]!r}; valid: {', '.join(sorted(_TEST_KEYS))}")
        if "case" in entry:
            extra = sorted(set(entry) - {"name", "case"})
            if extra:
                raise CaseFileError(f"{where}: {extra[0]!r} beside case: a test is a case file or inline keys")
            file = Path(str(entry["case"]))
            cases.append((name, load_case(file if file.is_absolute() else path.parent / file)))
            continue
        mapping = copy.deepcopy(template)
        mapping["title"] = name
        test = mapping.setdefault("test", {})
        for key in ("force", "energy", "alpha0", "mass_model"):
            if key in entry:
                test[key] = entry[key]
        if "record" in entry:
            record = mapping.setdefault("record", {})
            record["file"] = entry["record"]
            if "release_time" in entry:
                record["release_time"] = entry["release_time"]
        else:
            mapping.pop("record", None)
        obs = {k: entry[k] for k in ("alpha_final", "stop_time") if k in entry}
        if obs:
            mapping["observations"] = obs
        if "record" not in mapping and not obs:
            raise CaseFileError(f"{where}: give record (a file to fit) or alpha_final and stop_time")
        cases.append((name, case_from_mapping(mapping, source=where, base=path.parent)))
    return data, cases


def load_campaign(path: str | Path) -> tuple[str, str, tuple[str, ...], list[tuple[str, Case]]]:
    """Read a campaign file: (title, notes, variables, [(test name, Case)])."""
    path = Path(path)
    data, cases = _campaign_cases(path)
    variables = data.get("variables", ["force", "alpha0"])
    if not isinstance(variables, list) or not variables or any(v not in VARIABLES for v in variables):
        raise CaseFileError(f"{path}: variables = {variables!r}: expected a list of {', '.join(VARIABLES)}")
    return str(data.get("title", path.stem)), str(data.get("notes", "")), tuple(variables), cases


def _identify_test(name: str, case: Case, record: Record | None = None) -> CampaignTest:
    if case.record is not None or observation_sigma(case):
        fit = fit_record(case, record)
        method = "fit to record" if case.record is not None else "stop observations with scatter"
        return CampaignTest(name=name, case=case, F1=fit.F1, F2=fit.F2, F1_se=fit.std_errors["F1"],
                            F2_se=fit.std_errors["F2"], method=method, fit=fit)
    from ..device.identify import identify_friction

    ident = identify_friction(case.alpha0, case.alpha_final, case.stop_time, stored_energy=case.stored_energy,
                              device=case.device, mass_model=case.mass_model)
    return CampaignTest(name=name, case=case, F1=ident.F1, F2=ident.F2, F1_se=None, F2_se=None,
                        method="stop observations")


def _named(exc: QuickReleaseError, path, name: str) -> QuickReleaseError:
    """``exc`` with the campaign file and the test in front of its message (once: a test's inline keys already
    name them, as the source of its case)."""
    where, text = f"{path}: test {name}", str(exc)
    if text.startswith(where):
        return exc
    if isinstance(exc, ParameterError):  # its own arguments (type(exc)(message) is a TypeError: a traceback)
        return type(exc)(f"{where}: {exc.name}", exc.value, exc.valid, exc.unit)
    try:
        return type(exc)(f"{where}: {text}")
    except TypeError:  # an error of other arguments (InfeasibleObservationError): the message kept
        return QuickReleaseError(f"{where}: {text}")


def run_campaign(path: str | Path):
    """Identify every test of a campaign file and fit the friction laws.

    A campaign file with a ``[building]`` table is a campaign of releases of one building: its releases
    are fitted and the laws in the amplitude returned as a
    :class:`~quickrelease.studies.building_campaign.BuildingCampaignResult`
    (:func:`quickrelease.studies.building_campaign.run_building_campaign`); else a :class:`CampaignResult`.

    Raises
    ------
    CaseFileError
        For a malformed campaign file or test.
    QuickReleaseError
        With fewer than three tests (a law needs a degree of freedom), or a variable that is missing or
        constant over the tests.
    """
    data = read_toml(Path(path), "campaign file", CaseFileError)
    if "building" in data:
        from .building_campaign import run_building_campaign

        return run_building_campaign(path, data)
    title, notes, variables, cases = load_campaign(path)
    from ..io.records import record_files
    from .distributed import check_optional

    check_optional(files=[f for _, case in cases for f in record_files(case.record)])  # before the first fit
    if len(cases) < 3:
        raise QuickReleaseError(f"{path}: {len(cases)} test(s): a friction law needs at least 3")
    records = {}
    for name, case in cases:  # every record read before the first fit: a record's problem at once, with its test
        try:
            records[name] = load_case_record(case)
        except QuickReleaseError as exc:
            raise _named(exc, path, name) from None
    tests = []
    for name, case in cases:
        try:
            tests.append(_identify_test(name, case, records[name]))
        except QuickReleaseError as exc:
            raise _named(exc, path, name) from None
    laws = {(f, v): fit_law(tests, f, v) for f in ("F1", "F2") for v in variables}
    joint = {}
    if len(variables) > 1 and len(tests) >= len(variables) + 2:
        joint = {f: fit_joint(tests, f, variables) for f in ("F1", "F2")}
    return CampaignResult(title=title, source=str(path), tests=tests, laws=laws, joint=joint, variables=variables,
                          notes=notes)


@styled
def campaign_figure(result: CampaignResult, fig=None, ax=None):
    """Friction against each variable: the tests (95% error bars), the fitted law and its 95% band. ``ax``:
    2 x (number of variables) Axes to draw into (F1's row, then F2's). Returns the figure."""
    from ..report._style import panels, per
    from ..report.plots import user_label

    nv = len(result.variables)
    fig, axes = panels(3.4 * nv + 0.6, 5.8, (2, nv), fig=fig, ax=ax, subplots={"squeeze": False}, left=0.1,
                       right=0.98, bottom=0.1, top=0.86, wspace=0.3, hspace=0.48)
    axes = np.asarray(axes, dtype=object).reshape(2, nv)
    for row, friction in enumerate(("F1", "F2")):
        for col, var in enumerate(result.variables):
            panel = axes[row, col]
            _, label, _, scale, unit = VARIABLES[var]
            se = np.array([getattr(t, f"{friction}_se") or 0.0 for t in result.tests])
            law_panel(panel, result.laws[(friction, var)], [t.value(var) for t in result.tests],
                      [getattr(t, friction) for t in result.tests], 1.96 * se, [t.name for t in result.tests],
                      x_scale=scale, x_label=f"{label} [{unit}]", y_label=f"${friction[0]}_{friction[1]}$ [N]",
                      slope_unit=per("N", unit))
            if row == 0 and col == 0:
                panel.legend(loc="best")
    if ax is None:
        user_label(fig, "suptitle", f"{result.title}: friction against load and angle")
    return fig
