"""Figures draw, analyses compute (issue 23, item 3): the building's figures draw the model curves, the model's
decay and the decay envelope the result carries, and compute none of them (the model and the decay analysis are
made to fail here: a figure that still computes one raises)."""

import numpy as np
import pytest

from quickrelease.building.decay import analyse_decay
from quickrelease.building.isolation_fit import BuildingChannel, IsolationFit
from quickrelease.report import building_plots
from quickrelease.studies.building_analysis import BuildingResult

#: A hand-made record: a damped cosine of period 2 s from 0.15 m, released at t = 0.5 s [m, s].
T = np.arange(0.0, 12.0, 0.01)
X = np.where(T < 0.5, 0.15, 0.15 * np.exp(-0.3 * (T - 0.5)) * np.cos(np.pi * (T - 0.5)))


def _hand_made_result() -> BuildingResult:
    names = ("period", "damping_ratio", "friction", "d0", "release_time")
    est = {"period": 2.0, "damping_ratio": 0.095, "friction": 0.0, "d0": 0.15, "release_time": 0.5}
    ch = BuildingChannel("lvdt", "x", T, X + 1e-4 * np.sin(7.0 * T), noise=1e-4)
    fit = IsolationFit(model="linear", mass=4.0e5, names=names, estimates=est, std_errors=dict.fromkeys(names, 0.0),
                       ci95={n: (v, v) for n, v in est.items()}, interval_method=dict.fromkeys(names, "jacobian"),
                       correlation=np.eye(5), condition_number=1.0, noise={"lvdt": 1e-4},
                       noise_source={"lvdt": "given"}, residual_rms={"lvdt": 7e-5}, samples={"lvdt": T.size},
                       chi2=1.0, dof=1, chi2_reduced=1.0, absolute_sigma=True, aic=0.0, bic=0.0,
                       whiteness_p={"lvdt": 0.5}, converged=True, nfev=1, channels=(ch,))
    t_fine = np.linspace(0.0, 12.0, 50)
    curves = {"lvdt": {"t": t_fine, "model": np.cos(t_fine), "residual": np.full(T.size, 3e-5)}}
    decay = analyse_decay(T, X, release_time=0.5, noise=1e-4)  # the analysis, done by the test
    n = np.arange(4.0)
    envelope = {"n": n, "amplitude": np.array([0.15, 0.11, 0.08, 0.06]), "coulomb": 0.15 - 0.03 * n,
                "viscous": 0.15 * 0.75**n, "combined": 0.16 * 0.74**n - 0.01}
    return BuildingResult(fit=fit, decay=decay, source="hand-made", curves=curves, model_decay=decay,
                          decay_envelope=envelope)


@pytest.fixture
def no_computing(monkeypatch):
    """The fit's model and the decay analysis raise: a figure may only draw what it receives."""
    def refuse(*args, **kwargs):
        raise AssertionError("a figure computed an analysis")

    monkeypatch.setattr(IsolationFit, "model_values", refuse)
    monkeypatch.setattr("quickrelease.building.decay.analyse_decay", refuse)
    monkeypatch.setattr("quickrelease.studies.building_analysis.analyse_decay", refuse)
    monkeypatch.setattr("quickrelease.studies.building_analysis.model_decay", refuse)
    monkeypatch.setattr("quickrelease.studies.building_analysis.model_curves", refuse)
    monkeypatch.setattr("quickrelease.studies.building_analysis.decay_envelope", refuse)


def _line(ax, label):
    return next(line for line in ax.get_lines() if line.get_label() == label)


def test_the_fit_figure_draws_the_carried_model_and_residuals(no_computing):
    result = _hand_made_result()
    fig = building_plots.fit_figure(result)
    top, bottom = fig.axes[0], fig.axes[1]
    model = _line(top, "linear model")
    assert np.array_equal(model.get_xdata(), np.linspace(0.0, 12.0, 50))  # the 50 points given, not 4000
    assert np.array_equal(model.get_ydata(), np.cos(np.linspace(0.0, 12.0, 50)))
    assert np.array_equal(_line(bottom, "residual").get_ydata(), np.full(T.size, 3e-5))


def test_the_decay_figures_draw_the_carried_envelope_and_model_decay(no_computing):
    result = _hand_made_result()
    figs = building_plots.building_figures(result)
    assert set(figs) == {"building_fit", "building_decay", "building_amplitude"}  # no loop carried
    ax = figs["building_decay"].axes[0]
    n = np.arange(4.0)
    expected = {"record (half swing)": [150.0, 110.0, 80.0, 60.0], "Coulomb: linear decay": 1e3 * (0.15 - 0.03 * n),
                "viscous: geometric decay": 150.0 * 0.75**n, "combined law (Feeny-Liang)": 1e3 * (0.16 * 0.74**n - 0.01)}
    for label, values in expected.items():
        assert np.allclose(_line(ax, label).get_ydata(), values, rtol=1e-12, atol=1e-12), label
    model = _line(ax, "fitted linear model")
    assert np.allclose(model.get_ydata(), 1e3 * result.decay.amplitude, rtol=1e-12)
    left = figs["building_amplitude"].axes[0]
    assert np.allclose(_line(left, "fitted linear model").get_ydata(), result.decay.equivalent_period, rtol=1e-12)
