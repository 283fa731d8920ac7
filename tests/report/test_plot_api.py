"""Figures a user composes and results as tables (issue 22, item 24): every figure function draws into the
user's own axes (``ax=``) and returns the figure; ``Response.plot()``; ``to_pandas()``/``to_xarray()`` on the
identification and the building fit, with the column names and units written here; ``quickrelease building
--out`` writes the record, the model and the residuals as a time series that parses back."""

import math
from pathlib import Path

import numpy as np
import pytest
from analysis_capture import invoke_keeping_analysis
from matplotlib.figure import Figure

from quickrelease import simulate
from quickrelease.errors import QuickReleaseError

pytestmark = pytest.mark.usefixtures("few_band_draws")  # the bands' width is not looked at here

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.fixture(scope="module")
def response():
    return simulate(2900.0, 0.2, 419.85, 804.57, mass_model="distributed")


@pytest.fixture(scope="module")
def building_run(tmp_path_factory):
    """``quickrelease building examples/building.toml --out <tmp>/b`` and the analysis behind it (analyse_building's
    return, taken on its way to the command: the fit made once)."""
    out = tmp_path_factory.mktemp("building") / "b"
    r, made = invoke_keeping_analysis(["building", str(EXAMPLES / "building.toml"), "--out", str(out)])
    assert r.exit_code == 0, r.output
    (result,) = made
    return out, r, result


def _axes(n):
    fig = Figure()
    return fig, list(fig.subplots(1, n).flat) if n > 1 else fig.subplots()


def test_device_figures_draw_into_the_users_axes(response):
    from quickrelease.device.identify import identify_friction
    from quickrelease.device.statics import strain_energy
    from quickrelease.report import plots

    cases = [(plots.fig13, (response,), 4), (plots.fig14, (response,), 2), (plots.fig15, (response,), 1),
             (plots.identification_figure, (identify_friction(0.2, 0.7378, 1.05, stored_energy=2900.0),), 1),
             (plots.strain_energy_figure, (strain_energy(1598e3, 0.2),), 1)]
    for func, args, n in cases:
        mine, axes = _axes(n)
        assert func(*args, ax=axes) is mine, func.__name__
        assert len(mine.axes) == n, func.__name__  # no axes added: drawn into the user's
        assert all(a.has_data() for a in np.atleast_1d(axes)), func.__name__
        assert mine._suptitle is None  # the user's figure keeps its own title


def test_own_figures_keep_their_titles(response, building_run):
    """Without ``ax`` each figure keeps the title it draws over its panels (a loop reusing the name ``ax``
    once dropped them)."""
    from quickrelease.report import building_plots, plots

    _, _, result = building_run
    assert plots.fig13(response)._suptitle.get_text().startswith("Release response (energy, c = 0.6667)")
    assert building_plots.fit_figure(result)._suptitle.get_text().startswith("Building: linear isolation model")


def test_response_plot(response):
    assert len(response.plot().axes) == 4
    mine, axes = _axes(2)
    assert response.plot("fig14", ax=axes) is mine
    mine, ax = _axes(1)
    assert response.plot("state", ax=ax) is mine
    with pytest.raises(QuickReleaseError, match="kind = 'fig99'"):
        response.plot("fig99")


def test_ax_of_the_wrong_count_or_with_fig_is_refused(response):
    from quickrelease.report import plots

    mine, axes = _axes(3)
    with pytest.raises(QuickReleaseError, match="4 matplotlib Axes"):
        plots.fig13(response, ax=axes)
    with pytest.raises(QuickReleaseError, match="fig"):
        plots.fig15(response, fig=Figure(), ax=axes[0])


def test_planning_and_building_figures_draw_into_the_users_axes(building_run):
    from quickrelease.io.case import load_case
    from quickrelease.report import building_plots
    from quickrelease.studies.planning import choices_figure, envelope_figure, gap_figure, plan_case, utilisation_figure

    plan = plan_case(load_case(EXAMPLES / "plan.toml"))
    _, _, result = building_run
    n_fit = 2 * len(result.fit.channels)
    cases = [(choices_figure, (plan.fuse,), 1), (utilisation_figure, (plan.members,), 1),
             (envelope_figure, (plan.envelope,), 4), (gap_figure, (plan.clearance,), 1),
             (building_plots.fit_figure, (result,), n_fit), (building_plots.decay_figure, (result,), 1),
             (building_plots.amplitude_figure, (result,), 2), (building_plots.hysteresis_figure, (result,), 1)]
    for func, args, n in cases:
        mine, axes = _axes(n)
        assert func(*args, ax=axes) is mine, func.__name__
        assert len(mine.axes) == n, func.__name__


def test_identification_to_pandas_and_xarray():
    from quickrelease.device.identify import identify_friction

    ident = identify_friction(0.2, 0.7378, 1.05, stored_energy=2900.0)
    df = ident.to_pandas()
    assert list(df.columns) == ["F1_N", "F2_N", "F1_max_N", "F2_max_N", "F2_ratio", "stored_energy_J", "push_force_N",
                                "alpha0_rad", "alpha_final_rad", "stop_time_s", "stop_time_residual_s",
                                "feasible_stop_time_min_s", "feasible_stop_time_max_s", "mass_factor", "boundary",
                                "device"]
    assert len(df) == 1 and df["F1_N"][0] == ident.F1 and df["feasible_stop_time_max_s"][0] == \
        ident.feasible_stop_times[1]
    ds = ident.to_xarray()
    units = {name: ds[name].attrs["units"] for name in ds.data_vars}
    assert units == {"F1": "N", "F2": "N", "F1_max": "N", "F2_max": "N", "F2_ratio": "1", "stored_energy": "J",
                     "alpha0": "rad", "alpha_final": "rad", "stop_time": "s", "stop_time_residual": "s",
                     "feasible_stop_time_min": "s", "feasible_stop_time_max": "s", "mass_factor": "1"}
    assert float(ds["F2"]) == ident.F2 and ds.attrs["device"] == ident.device.name
    assert ds["F1"].attrs["long_name"] == "hinge friction F1"


def test_building_fit_to_pandas_and_xarray(building_run):
    _, _, result = building_run
    fit = result.fit
    df = fit.to_pandas()
    assert df.index.name == "t_s"
    assert list(df.columns) == ["x_record_m", "x_model_m", "x_residual_m", "a_record_m_s2", "a_model_m_s2",
                                "a_residual_m_s2"]
    x = next(c for c in fit.channels if c.kind == "x")
    a = next(c for c in fit.channels if c.kind == "a")
    # every sample of each channel is on the time axis, at its own time, once; NaN where a channel has none
    assert np.array_equal(df["x_record_m"].dropna().to_numpy(), x.values)
    assert np.array_equal(df["x_record_m"].dropna().index.to_numpy(), x.t)
    assert np.array_equal(df["a_record_m_s2"].dropna().index.to_numpy(), a.t)
    assert df["x_model_m"].notna().all()
    assert np.allclose(df["x_residual_m"].dropna(), x.values - fit.model_values(x), rtol=0, atol=1e-15)
    # the residuals are the noise: 0.05 mm (x) and 0.002 g0 (a) in make_records.py
    assert np.nanstd(df["x_residual_m"]) == pytest.approx(5e-5, rel=0.15)
    assert np.nanstd(df["a_residual_m_s2"]) == pytest.approx(0.002 * 9.80665, rel=0.15)
    ds = fit.to_xarray()
    assert ds["t"].attrs["units"] == "s" and ds["t"].attrs["axis"] == "T"
    assert {k: v.attrs["units"] for k, v in ds.data_vars.items()} == {
        "x_record": "m", "x_model": "m", "x_residual": "m", "a_record": "m/s^2", "a_model": "m/s^2",
        "a_residual": "m/s^2"}
    assert ds["a_residual"].attrs["long_name"] == "a: acceleration, residual, measured minus model"
    assert ds.attrs["model"] == "linear" and ds.attrs["estimate_period"] == fit.estimates["period"]


def test_building_out_writes_the_time_series_that_parses_back(building_run):
    import pandas as pd
    import xarray as xr

    out, r, result = building_run
    for name in ("timeseries.csv", "timeseries.nc", "summary.json", "report.html", "manifest.json"):
        assert (out / name).is_file(), name
    csv = pd.read_csv(out / "timeseries.csv")
    assert list(csv.columns) == ["t_s", "x_record_m", "x_model_m", "x_residual_m", "a_record_m_s2", "a_model_m_s2",
                                 "a_residual_m_s2"]
    frame = result.fit.to_pandas()
    assert np.array_equal(csv["t_s"].to_numpy(), frame.index.to_numpy())  # full precision, read back exactly
    assert np.array_equal(csv["x_record_m"].isna().to_numpy(), frame["x_record_m"].isna().to_numpy())
    with xr.open_dataset(out / "timeseries.nc") as ds:
        assert ds["x_model"].attrs["units"] == "m" and ds["t"].size == csv.shape[0]
        assert np.allclose(ds["x_model"].values, csv["x_model_m"].to_numpy(), rtol=1e-12)
        assert ds.attrs["input_file"] == "building.toml"
    listed = [line.strip() for line in r.stdout.splitlines() if line.startswith("  ")]
    on_disk = sorted(str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert sorted(listed) == on_disk and f"Wrote {len(on_disk)} files" in r.stdout


def test_free_vibration_as_tables():
    from quickrelease.building.model import Isolation, free_vibration
    from quickrelease.io.frames import free_vibration_dataset, free_vibration_frame

    iso = Isolation.linear(mass=8e5, period=2.0, damping_ratio=0.0, friction=0.0)
    motion = free_vibration(iso, 0.1, t_end=4.0)
    t = np.linspace(0.0, 3.0, 7)
    df = free_vibration_frame(motion, t)
    assert list(df.columns) == ["x_m", "v_m_s", "a_m_s2"] and df.index.name == "t_s"
    w = 2.0 * math.pi / 2.0  # undamped, frictionless: x = d0 cos(w t)
    assert np.allclose(df["x_m"], 0.1 * np.cos(w * t), atol=1e-12)
    assert np.allclose(df["a_m_s2"], -0.1 * w**2 * np.cos(w * t), atol=1e-10)
    ds = free_vibration_dataset(motion, t)
    assert {k: v.attrs["units"] for k, v in ds.data_vars.items()} == {"x": "m", "v": "m/s", "a": "m/s^2"}


def test_study_figures_draw_into_the_users_axes():
    from quickrelease.io.case import load_case
    from quickrelease.studies.sweep import heatmap_figure, sweep
    from quickrelease.studies.uq import corner_figure, run_uq

    ds = sweep(load_case(EXAMPLES / "larger_push.toml"), {"alpha0": np.linspace(0.1, 0.5, 3),
                                                          "F1": np.linspace(100.0, 400.0, 3)})
    mine = Figure()
    axes = mine.subplots(2, 3)
    assert heatmap_figure(ds, ax=axes) is mine and len(mine.axes) == 6 + 6  # and one colour bar a panel
    u = run_uq(load_case(EXAMPLES / "uq_paper.toml"), 2000, seed=1, chunk=2000)
    mine = Figure()
    assert corner_figure(u, ax=mine.subplots(2, 2)) is mine and len(mine.axes) == 4


@pytest.mark.slow
def test_campaign_figures_draw_into_the_users_axes():
    from quickrelease.studies.building_campaign import building_campaign_figure
    from quickrelease.studies.campaign import campaign_figure, run_campaign

    result = run_campaign(EXAMPLES / "campaign.toml")
    mine = Figure()
    assert campaign_figure(result, ax=mine.subplots(2, len(result.variables))) is mine
    assert len(mine.axes) == 2 * len(result.variables)
    result = run_campaign(EXAMPLES / "building_campaign.toml")
    mine = Figure()
    axes = mine.subplots(len(result.variables), len(result.quantities))
    assert building_campaign_figure(result, ax=axes) is mine
    assert len(mine.axes) == len(result.variables) * len(result.quantities)


def test_a_record_figures_channel_sits_above_its_residuals_on_one_time_axis():
    """report.plots.record_axes (the device's and the building's fit figures): the user's axes in their order,
    channel then residuals; else two new panels per channel, every panel sharing the first's time axis."""
    from quickrelease.report.plots import record_axes

    fig = Figure()
    grid = fig.add_gridspec(5, 1)
    top0, bottom0, share = record_axes(fig, None, grid, 0, None)
    top1, bottom1, share1 = record_axes(fig, None, grid, 1, share)
    assert share is top0 and share1 is top0 and len(fig.axes) == 4
    for ax in (bottom0, top1, bottom1):
        assert ax.get_shared_x_axes().joined(ax, top0)
    assert top0.get_subplotspec().rowspan.start == 0 and bottom0.get_subplotspec().rowspan.start == 1
    assert top1.get_subplotspec().rowspan.start == 3 and bottom1.get_subplotspec().rowspan.start == 4
    mine = [object() for _ in range(4)]
    assert record_axes(fig, mine, None, 1, None) == (mine[2], mine[3], None)
