"""The model comparison of the building analysis under the fit's damper law (analyse_building(compare=True), issue
24): a power-damped case ranks every model with the power-law damper, and a model that takes no such damper
(2dof: viscous only) is left out with a one-line note.

The record: a linear isolator (T = 2.5 s) with a fluid viscous damper F = C |v|^0.3 sign(v), C = 150 kN
(s/m)^0.3, no sliders, pushed 150 mm, from the independent reference simulator (tests/building/isolator_reference.py,
solve_ivp with events): 8 s at 100 Hz, released at 2 s, LVDT noise 0.1 mm and accelerometer noise 0.01 m/s^2.
"""

import math
import os
import sys
from pathlib import Path

import numpy as np
import pytest

from quickrelease.building.isolation_fit import BuildingChannel
from quickrelease.errors import QuickReleaseError
from quickrelease.studies import building_analysis

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "building"))
import isolator_reference as ref  # noqa: E402

pytestmark = pytest.mark.usefixtures("few_band_draws")  # the bands and the bootstrap are not looked at here

M, T, C, ALPHA, D0 = 8e5, 2.5, 1.5e5, 0.3, 0.15


def record(seed=1, span=8.0):
    k = M * (2 * math.pi / T) ** 2
    t = np.arange(0.0, span, 0.01)
    motion = ref.simulate(ref.linear(M, k, damping=C, damping_exponent=ALPHA), D0, t - 2.0)
    rng = np.random.default_rng(seed)
    return [BuildingChannel("x", "x", t, motion.x + rng.normal(0, 1e-4, t.size)),
            BuildingChannel("a", "a", t, motion.a + rng.normal(0, 0.01, t.size))]


@pytest.mark.slow  # (1.1-1.5 s of fits: the README's quick run stays under 3 minutes; CI runs it)
def test_the_compared_models_get_the_fits_damper_law(monkeypatch):
    """Each other model's fit, 2dof's too (its linear layer with fluid dampers under the superstructure, on the
    flexible integrator), is asked for with damping = "power" and the dampers' start values (C and alpha are the
    dampers', whatever the bearings); a model whose fit fails is named in a note of one line. (The other models'
    fits are stopped here after the call: their cost is the slow test's.)"""
    calls = {}
    real = building_analysis.fit_isolation

    def spy(channels, mass, model, **kw):
        if model == "linear":  # the chosen model's fit, the real fit's own
            return real(channels, mass, model, **kw)
        calls[model] = kw
        raise QuickReleaseError(f"{model} skipped by the test")

    monkeypatch.setattr(building_analysis, "fit_isolation", spy)
    start = {"d0": D0, "damping_coefficient": C, "damping_exponent": ALPHA}
    result = building_analysis.analyse_building(channels=record(), mass=M, model="linear", damping="power",
                                                start=start, compare=True, superstructure_mass=2e5,
                                                global_search=False)
    assert result.fit.damping == "power"
    others = set(building_analysis.MODELS) - {"linear"}
    assert set(calls) == others
    for model, kw in calls.items():
        assert kw.get("damping", "viscous") == "power", model
        assert kw["start"] == start, model
    notes = [n for n in result.notes if n.startswith("model 2dof not compared")]
    assert notes == ["model 2dof not compared: 2dof skipped by the test"]
    assert 'every model compared with the same damper law: damping = "power"' in result.notes


def test_a_viscous_case_compares_viscous_fits(monkeypatch):
    """The default law is unchanged: viscous for every model, no note about the law, 2dof fitted."""
    calls = {}

    def spy(channels, mass, model, **kw):
        calls[model] = kw
        raise QuickReleaseError(f"{model} skipped by the test")

    real = building_analysis.fit_isolation
    monkeypatch.setattr(building_analysis, "fit_isolation",
                        lambda channels, mass, model, **kw: (real(channels, mass, model, **kw) if model == "linear"
                                                             else spy(channels, mass, model, **kw)))
    result = building_analysis.analyse_building(channels=record(), mass=M, model="linear", compare=True,
                                                superstructure_mass=2e5, global_search=False)
    assert set(calls) == set(building_analysis.MODELS) - {"linear"}
    assert all(kw.get("damping", "viscous") == "viscous" for kw in calls.values())
    assert not any("damper law" in n or "power-law damper" in n for n in result.notes)


@pytest.mark.slow
@pytest.mark.skipif(not os.environ.get("QUICKRELEASE_SLOW"), reason="opt-in (QUICKRELEASE_SLOW=1): four power-law "
                    "fits, beyond CI's budget; the spy tests above check the wiring")
def test_a_power_damped_record_ranks_the_models_under_its_law(monkeypatch):
    """The whole comparison (linear, bilinear, 2dof, pendulum; no Bouc-Wen, whose fit of another model's record
    takes minutes): every compared fit has the power-law damper; bilinear and pendulum, which nest the linear
    isolator, fit the record to its noise (reduced chi-square below 1.2); 2dof, which nests it only as its storey
    stiffens without bound, ends at the storey period's lower bound (SUPERSTRUCTURE_PERIOD_MIN, 0.02 s) with the
    layer's period and the dampers' law at the truth (its reduced chi-square 1.34: the 0.02 s storey still rings
    after the release); and the linear model, the truth with the fewest parameters, ranks first by BIC. Viscous fits
    of this record, as the comparison made them before, ranked the bearings by the damper's misfit: reduced
    chi-square 36.9 (linear), 7.47 (bilinear), 1.14 (pendulum, whose friction rising with the speed mimics the
    damper's C |v|^0.3), 41.1 (2dof)."""
    from quickrelease.building.isolation_fit import SUPERSTRUCTURE_PERIOD_MIN

    monkeypatch.setattr(building_analysis, "MODELS", ("linear", "bilinear", "2dof", "pendulum"))
    result = building_analysis.analyse_building(channels=record(), mass=M, model="linear", damping="power",
                                                compare=True, superstructure_mass=2e5, global_search=False)
    assert [f.model for f in result.compared] == ["linear", "bilinear", "2dof", "pendulum"]
    for f in result.compared:
        assert f.damping == "power", f.model
        if f.model != "2dof":
            assert f.chi2 / f.dof < 1.2, (f.model, f.chi2 / f.dof)
        else:
            assert abs(f.estimates["superstructure_period"] / SUPERSTRUCTURE_PERIOD_MIN - 1) < 1e-9 and f.chi2 / f.dof < 1.5
            assert abs(f.estimates["period"] / T - 1) < 1e-3 and abs(f.estimates["damping_exponent"] - ALPHA) < 0.01
    assert result.comparison[0]["model"] == "linear"
    assert not any(" not compared" in n for n in result.notes)
