"""What the whole test's report shows (issue 22, items 22 and 27): figures only where there is something to
draw (a histogram over friction samples, a chart of member checks made), legends that cover no curve and no
text, the period-vs-amplitude axis not squashed by one point, and the clearance note with units."""

from pathlib import Path

import numpy as np
import pytest
from quality import figure_faults, overlap_faults

from quickrelease import simulate
from quickrelease.device.parameters import load_device
from quickrelease.errors import QuickReleaseError
from quickrelease.io.case import load_case
from quickrelease.studies.planning import envelope_figure, member_checks, plan_case, plan_figures, utilisation_figure

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.fixture(scope="module")
def whole_test(tmp_path_factory):
    """``quickrelease run examples/building.toml`` (one friction value, a device file with no capacities)."""
    from quickrelease.workflow import run_case, write_results

    result = run_case(load_case(EXAMPLES / "building.toml"))
    out = tmp_path_factory.mktemp("whole") / "out"
    paths = write_results(result, out)
    return result, out, paths


@pytest.mark.slow
def test_one_friction_value_draws_no_histogram_and_no_unchecked_member_chart(whole_test):
    result, out, paths = whole_test
    assert result.plan.envelope.samples == 1
    assert all(c.utilisation is None for c in result.plan.members.checks)  # no capacity in the paper's file
    figures = {p.name for p in (out / "figures").iterdir()}
    assert "plan_envelope.png" not in figures and "plan_utilisation.png" not in figures
    assert "plan_gap.png" in figures  # the clearance is still drawn
    page = (out / "report.html").read_text(encoding="utf-8")
    assert "Release envelope over 1 friction samples" not in page and "skipped (no capacity given)" not in page
    assert "No member was checked: the device file gives no capacity" in page
    assert page.count("skipped: fy3 not in the device file") == 1  # in the table's note column, not again below
    assert "Building (linear): T = 2.00008 s," in page  # the identified period, not 2.0001
    assert "<th>5%</th>" not in page.split("<h3>Release envelope</h3>", 1)[1].split("<h3>", 1)[0]


@pytest.mark.slow
def test_a_figure_function_refuses_what_it_cannot_draw(whole_test):
    result, _, _ = whole_test
    with pytest.raises(QuickReleaseError, match="1 friction sample"):
        envelope_figure(result.plan.envelope)
    with pytest.raises(QuickReleaseError, match="no member was checked"):
        utilisation_figure(result.plan.members)


def test_with_samples_and_capacities_both_figures_are_drawn_and_nothing_collides():
    plan = plan_case(load_case(EXAMPLES / "plan.toml"))
    assert plan.envelope.samples > 1
    figs = plan_figures(plan)
    assert {"plan_envelope", "plan_utilisation"} <= set(figs)
    for name, fig in figs.items():
        assert figure_faults(fig) == [], name
        assert overlap_faults(fig) == [], name


def test_member_chart_values_are_not_under_its_legend():
    # E4 at utilisation 1 (its value printed right of the capacity line), a check skipped (E3)
    checks = member_checks(1598e3, 0.2, load_device(EXAMPLES / "device_checked.toml"), rupture_strength=610e6)
    fig = utilisation_figure(checks)
    assert [t.get_text() for t in fig.axes[0].texts][-1] == " 1.000"
    assert overlap_faults(fig) == []


def test_fig13_legends_cover_no_curve():
    from quickrelease.report.plots import fig13

    fig = fig13(simulate(2900.0, 0.2, 419.85, 804.57, mass_model="distributed"))
    assert overlap_faults(fig) == []
    d = fig.axes[3]
    assert [t.get_text() for t in d.get_legend().get_texts()] == ["kinetic $E_K$", "dissipated $W_F$",
                                                                  "$E_K + W_F$", "$E_S$"]


@pytest.mark.slow
def test_the_whole_tests_figures_have_no_legend_over_a_curve(whole_test):
    from quickrelease.report.building_plots import building_figures
    from quickrelease.report.plots import fig14, fig15

    result, _, _ = whole_test
    for name, fig in building_figures(result.building).items():
        assert overlap_faults(fig) == [], name
    for func in (fig14, fig15):
        assert overlap_faults(func(result.response)) == [], func.__name__


@pytest.mark.slow
def test_period_axis_is_not_squashed_by_one_point_and_its_label_is_mathtext(whole_test):
    from quickrelease.report.building_plots import amplitude_figure, off_scale

    result, _, _ = whole_test
    periods = np.asarray(result.building.decay.equivalent_period)
    assert periods.max() > 10.0  # the half-cycle that ends where the building sticks (15 s)
    fig = amplitude_figure(result.building)
    left = fig.axes[0]
    lo, hi = left.get_ylim()
    assert 1.9 < lo and hi < 2.1  # the swings' periods (about 2.0 s) fill the axis
    assert left.get_ylabel() == r"equivalent period $2\,(t_{n+1} - t_n)$ [s]"
    legend = [t.get_text() for t in left.get_legend().get_texts()]
    assert any(text.startswith("record off the axis: 15") for text in legend)
    assert figure_faults(fig) == [] and overlap_faults(fig) == []
    # the rule, on numbers written here: 2 s swings, a 15 s stop; a model range of 1.5 to 2.5 s
    assert off_scale([2.0, 2.01, 15.0]).tolist() == [False, False, True]
    assert off_scale([2.0, 0.5, 6.0], [1.5, 2.5]).tolist() == [False, True, True]
    assert off_scale([2.0, 4.9], [1.5, 2.5]).tolist() == [False, False]


@pytest.mark.slow
def test_the_clearance_note_has_units(whole_test):
    result, _, _ = whole_test
    note = next(n for n in result.plan.notes if n.startswith("clearance checked with"))
    assert "period T = 2.0000" in note and " s, damping ratio zeta = 0.0500" in note
    assert "slider friction F_s = 156.8" in note and " kN, mass = 800 t, pushed displacement d0 = 182.4" in note
    assert "mm), not the assumed" in note
    assert "= 800000" not in note and "friction = 156880," not in note
