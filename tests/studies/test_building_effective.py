"""The identified isolator's keff, EDC, beta_eff and Teff against the cycle amplitude with 95% bands, and the
cycles judged against them (issue 24, item 2: quickrelease.studies.building_effective).

References written here: the closed forms of a linear spring on Coulomb sliders with viscous dampers (a
half-cycle from rest at A ends at ``delta - (A - delta) r``, ``delta = F_s / k``, ``r = exp(-zeta pi /
sqrt(1 - zeta^2))``; F at an extreme is ``k X +- F_s`` before the slider's flip, so keff = k + F_s / D; EDC is
the spring's energy lost between the cycle's ends), the independent solve_ivp of tests/building_reference.py
for the records, and the delta method on those closed forms for the bands' widths.
"""

import math

import numpy as np
import pytest
from building_reference import reference

from quickrelease.building.effective import G0, CycleProperties
from quickrelease.building.isolation_fit import BuildingChannel, fit_isolation
from quickrelease.building.model import Isolation
from quickrelease.errors import ParameterError
from quickrelease.studies.building_effective import EffectiveCurve, effective_curves, judge_cycles, model_cycles

M, T, ZETA, FS, D0 = 8e5, 2.5, 0.03, 0.004 * 8e5 * G0, 0.15


def truth(D, period=T, zeta=ZETA, friction=FS, mass=M):
    """keff, EDC, beta_eff, Teff of the cycle of amplitude D (from a reversal), in closed form (module doc)."""
    k = mass * (2 * math.pi / period) ** 2
    r = math.exp(-zeta * math.pi / math.sqrt(1 - zeta * zeta))
    dl = friction / k
    A = dl + 2 * D / (1 + r)  # D = (A + |B|) / 2 with |B| = (A - delta) r - delta
    B = (A - dl) * r - dl
    C = (B - dl) * r - dl  # the cycle's end, back on A's side
    keff = k + friction / D
    edc = 0.5 * k * (A * A - C * C)
    return np.array([keff, edc, edc / (2 * math.pi * keff * D * D), 2 * math.pi * math.sqrt(mass / keff)])


def record(seed, span=30.0, rate=200.0, sx=1e-4, sa=0.01):
    t = np.arange(0.0, span, 1.0 / rate)
    k = M * (2 * math.pi / T) ** 2
    # the release between two samples (on a sample the misfit has a kink in the release time: its Jacobian
    # interval, and so the band, is too narrow on some records)
    (x, _, a), _ = reference(M, k, k, math.inf, 2 * ZETA * math.sqrt(k * M), FS, D0, t - 2.0 - 0.37 / rate,
                             with_rates=True)
    rng = np.random.default_rng(seed)
    return [BuildingChannel("x", "x", t, x + rng.normal(0, sx, t.size)),
            BuildingChannel("a", "a", t, a + rng.normal(0, sa, t.size))]


@pytest.fixture(scope="module")
def fitted():
    return fit_isolation(record(4), M, "linear", global_search=False)


def test_the_model_cycles_are_the_closed_forms():
    """Every cycle after the release's: keff = k + F_s / D, EDC the spring's energy lost, to rounding; the
    release's cycle reads F+ on the unloading branch: keff = k there."""
    iso = Isolation.linear(M, T, ZETA, FS)
    cyc = model_cycles(iso, D0, 40.0)
    assert cyc["from_release"][0] and not cyc["from_release"][1:].any()
    assert cyc["amplitude_m"].size >= 4
    for i in range(1, cyc["amplitude_m"].size):
        want = truth(cyc["amplitude_m"][i])
        got = [cyc[q][i] for q in ("keff_N_m", "edc_J", "beta_eff", "teff_s")]
        assert got == pytest.approx(want, rel=1e-8)
    k = M * (2 * math.pi / T) ** 2
    assert cyc["keff_N_m"][0] == pytest.approx(k, rel=1e-8)


def test_the_model_cycles_of_a_loop_without_sliders_follow_the_solve_ivp_energy():
    """A viscous isolator (no sliders, no stop): each cycle's EDC is the energy lost between its ends, read
    off the independent solve_ivp solution (k x^2 / 2 at the turning points), keff = k."""
    k = M * (2 * math.pi / T) ** 2
    iso = Isolation.linear(M, T, 0.05, 0.0)
    cyc = model_cycles(iso, D0, 12.0)
    t = np.linspace(0.0, 12.0, 240001)
    x = reference(M, k, k, math.inf, 2 * 0.05 * math.sqrt(k * M), 0.0, D0, t)[0]
    for i in range(1, cyc["amplitude_m"].size):
        t0 = cyc["start_s"][i]
        x0, x2 = np.interp([t0, t0 + T / math.sqrt(1 - 0.05**2)], t, x)
        assert cyc["edc_J"][i] == pytest.approx(0.5 * k * (x0**2 - x2**2), rel=1e-6)
        assert cyc["keff_N_m"][i] == pytest.approx(k, rel=1e-9)


def test_the_band_covers_the_true_curve_and_has_the_delta_methods_width(fitted):
    """One record (a seed whose bands hold the truth: one record in 20 has a stretch outside, which is what a 95%
    band means; the slow test counts): the fitted curve within its 95% band, the true curve (closed form) inside it, and the band's
    half-width that of the delta method on the closed forms with the fit's covariance (correlations included)
    within 12% (1000 draws: the quantiles' sampling error is about 3%)."""
    curve = effective_curves(fitted, draws=1000, seed=1)
    d = curve.amplitude_m
    assert d.size == 41 and curve.draws_used == 1000
    names = ["period", "damping_ratio", "friction"]
    est = np.array([fitted.estimates[n] for n in names])
    se = np.array([fitted.std_errors[n] for n in names])
    idx = [fitted.names.index(n) for n in names]
    cov = fitted.correlation[np.ix_(idx, idx)] * np.outer(se, se)
    for j, q in enumerate(("keff_N_m", "edc_J", "beta_eff", "teff_s")):
        lo, hi, mid = curve.lower[q], curve.upper[q], curve.curves[q]
        assert np.all(np.isfinite(lo)) and np.all(lo < mid) and np.all(mid < hi)
        true = np.array([truth(D)[j] for D in d])
        assert np.all((lo <= true) & (true <= hi)), q
        for i in (0, 20, 40):
            grad = np.array([(truth(d[i], *(est + h))[j] - truth(d[i], *(est - h))[j]) / (2 * h[n])
                             for n, h in enumerate(np.diag(se * 1e-3))])
            half = 1.959964 * math.sqrt(grad @ cov @ grad)
            assert 0.5 * (hi[i] - lo[i]) == pytest.approx(half, rel=0.12), (q, i)
            assert mid[i] == pytest.approx(truth(d[i], *est)[j], rel=1e-7)


@pytest.mark.slow  # 2000 draws; the quick run reaches effective_curves' bands in the test above
def test_the_level_sets_the_bands_width(fitted):
    """The same draws at level 0.5: half-widths 0.6745 / 1.96 of the 95% band's (normal quantiles) within 15%."""
    wide = effective_curves(fitted, draws=1000, seed=2)
    narrow = effective_curves(fitted, level=0.5, draws=1000, seed=2)
    ratio = (narrow.upper["keff_N_m"] - narrow.lower["keff_N_m"]) / (wide.upper["keff_N_m"] - wide.lower["keff_N_m"])
    assert np.median(ratio) == pytest.approx(0.674490 / 1.959964, rel=0.15)


def test_parameters_the_record_does_not_identify_are_held(fitted):
    from dataclasses import replace

    blind = replace(fitted, interval_method={**fitted.interval_method, "damping_ratio": "not identified"})
    curve = effective_curves(blind, draws=40)  # held by its interval method, whatever its standard error
    assert "damping_ratio" in curve.held and "damping_ratio" not in curve.drawn
    lost = replace(fitted, std_errors={**fitted.std_errors, "friction": math.inf})
    assert "friction" in effective_curves(lost, draws=40).held  # no finite standard error: held too
    assert any("not identified" in n for n in curve.notes)


def test_the_model_cycles_pass_and_a_cycle_off_the_curve_fails(fitted):
    """The fitted model's cycles lie on its curve (all criteria pass); one cycle's keff 20% high and another's
    EDC at 70% fail the keff and EDC criteria with those numbers; the release's cycle is shown, not judged."""
    curve = effective_curves(fitted, draws=100)
    cyc = model_cycles(fitted.isolation(), fitted.parameters["d0"], 28.0)
    cycles = [CycleProperties(start_s=s, end_s=s + 1, amplitude_m=D, d_plus_m=D, d_minus_m=-D, f_plus_N=0.0,
                              f_minus_N=0.0, keff_N_m=k, edc_J=e, beta_eff=b, qd_N=math.nan, kd_N_m=math.nan)
              for s, D, k, e, b in zip(cyc["start_s"], cyc["amplitude_m"], cyc["keff_N_m"], cyc["edc_J"],
                                       cyc["beta_eff"], strict=True)]
    ok = judge_cycles(cycles, curve)
    assert ok.passed is True
    assert not ok.rows[0]["judged"] and ok.rows[0]["from_release"]
    assert all(c["worst"] == pytest.approx(0.0 if "keff" in c["name"] else 1.0, abs=1e-6) for c in ok.criteria)
    from dataclasses import replace

    bad = list(cycles)
    bad[2] = replace(bad[2], keff_N_m=1.2 * bad[2].keff_N_m)
    bad[3] = replace(bad[3], edc_J=0.7 * bad[3].edc_J)
    verdict = {c["name"]: c for c in judge_cycles(bad, curve).criteria}
    assert verdict["keff_vs_model"]["worst"] == pytest.approx(0.2, rel=1e-6)
    assert verdict["keff_vs_model"]["cycle"] == 2 and verdict["keff_vs_model"]["passed"] is False
    assert verdict["edc_vs_model"]["worst"] == pytest.approx(0.7, rel=1e-6)
    assert verdict["edc_vs_model"]["cycle"] == 3 and verdict["edc_vs_model"]["passed"] is False
    judged = [r for r in judge_cycles(bad, curve).rows if r["judged"]]
    r = np.array([row["keff_ratio"] for row in judged])
    assert verdict["keff_spread"]["worst"] == pytest.approx(np.max(np.abs(r / r.mean() - 1)), rel=1e-9)
    assert verdict["keff_spread"]["passed"] is (verdict["keff_spread"]["worst"] <= 0.15)
    loose = {c["name"]: c["passed"] for c in judge_cycles(bad, curve, keff_tolerance=0.25, edc_fraction=0.6).criteria}
    assert loose == {"keff_vs_model": True, "keff_spread": True, "edc_vs_model": True, "edc_spread": True}


def test_bad_arguments_are_one_line(fitted):
    with pytest.raises(ParameterError, match="level"):
        effective_curves(fitted, level=1.0)
    with pytest.raises(ParameterError, match="draws"):
        effective_curves(fitted, draws=5)
    with pytest.raises(ParameterError, match="amplitudes"):
        effective_curves(fitted, amplitudes=[-0.1])
    with pytest.raises(ParameterError, match="keff_tolerance"):
        judge_cycles([], effective_curves(fitted, draws=20), keff_tolerance=0.0)


def test_a_summary_is_json():
    import json

    fit = fit_isolation(record(5, span=20.0, rate=100.0), M, "linear", global_search=False)
    curve = effective_curves(fit, amplitudes=[0.02, 0.05, 0.5], draws=20)
    s = json.loads(json.dumps(curve.summary()))
    assert s["amplitude_m"] == [0.02, 0.05, 0.5] and s["keff_N_m"][2] is None and s["keff_N_m"][1] > 0


@pytest.mark.slow
def test_the_bands_cover_the_true_curves_95_percent_of_the_time():
    """40 independent records fitted: at three amplitudes across each record's curve, the 95% bands of keff,
    EDC and beta_eff hold the true value (closed form) in 90-99% of the 360 (seed, amplitude, quantity) cases
    (the cases within one record are correlated: the binomial's 2-sigma band of 40 records is wider, +-7%)."""
    hits = []
    for seed in range(100, 140):
        fit = fit_isolation(record(seed, span=24.0, rate=100.0, sx=3e-4, sa=0.03), M, "linear", global_search=False)
        curve = effective_curves(fit, draws=200, seed=seed)
        for i in (5, 20, 35):
            D = curve.amplitude_m[i]
            true = truth(D)
            for j, q in enumerate(("keff_N_m", "edc_J", "beta_eff")):
                hits.append(curve.lower[q][i] <= true[j] <= curve.upper[q][i])
    assert 0.88 <= np.mean(hits) <= 0.995, np.mean(hits)


def test_the_analysis_cycles_agree_with_the_exact_model_cycles(fitted):
    """effective_cycles (the model's loop sampled, read by loop_cycles) against model_cycles (exact) for every
    cycle after the release's, the last one (ending where the sliders stop) included: keff, EDC to 1e-4."""
    from quickrelease.studies.building_analysis import effective_cycles

    sampled = effective_cycles(fitted)
    exact = model_cycles(fitted.isolation(), fitted.parameters["d0"], 28.0)
    assert len(sampled) == exact["amplitude_m"].size >= 4
    for i, c in enumerate(sampled[1:], start=1):
        assert c.amplitude_m == pytest.approx(exact["amplitude_m"][i], rel=1e-6)
        assert c.keff_N_m == pytest.approx(exact["keff_N_m"][i], rel=1e-4)
        assert c.edc_J == pytest.approx(exact["edc_J"][i], rel=1e-4)


def test_the_tables_rows():
    """The command's per-cycle rows from a judgement written here: differences in % of the model beside the band's
    half-width (% of the model), the release's cycle shown without a comparison; the criteria's verdicts."""
    from quickrelease.report.display import effective_deviation_rows, spread_rows

    cyc = {"cycle": 1, "amplitude_m": 0.1, "from_release": False, "judged": True,
           "keff_N_m": 1.0123e6, "keff_model_N_m": 1.0e6, "keff_lo_N_m": 0.9995e6, "keff_hi_N_m": 1.0005e6,
           "keff_ratio": 1.0123, "edc_J": 990.0, "edc_model_J": 1000.0, "edc_lo_J": 980.0, "edc_hi_J": 1020.0,
           "edc_ratio": 0.99, "beta_eff": 0.05, "beta_model": 0.05, "beta_lo": 0.049, "beta_hi": 0.051,
           "beta_ratio": 1.0}
    first = {**cyc, "cycle": 0, "from_release": True, "judged": False, "keff_model_N_m": None, "keff_ratio": None,
             "edc_model_J": None, "edc_ratio": None, "beta_model": None, "beta_ratio": None}
    rows = effective_deviation_rows({"cycles": [first, cyc]})
    assert rows[0] == ("1", "-", "-", "-", "-", "-", "-")
    assert rows[1] == ("2", "+1.230", "±0.05", "-1.0", "±2", "+0.0", "±2")
    crit = [{"name": "keff_vs_model", "worst": 0.0123, "cycle": 1, "tolerance": 0.15, "passed": True},
            {"name": "edc_vs_model", "worst": 0.7, "cycle": 1, "tolerance": 0.8, "passed": False},
            {"name": "edc_spread", "worst": None, "cycle": None, "tolerance": 0.8, "passed": None}]
    assert spread_rows({"criteria": crit}) == [("keff_vs_model", "0.0123", "2", "0.15", "pass"),
                                              ("edc_vs_model", "0.7", "2", "0.8", "FAIL"),
                                              ("edc_spread", "-", "-", "0.8", "no cycle judged")]


def test_a_bilinear_isolators_model_cycles_follow_the_solve_ivp_loop():
    """A bilinear spring on sliders with dampers (yielding inside the half-cycles): model_cycles against the loop of
    the independent solve_ivp, sampled at 2e5 points a period and read by loop_cycles at the reference's own
    turning points, to 1e-4 (keff, EDC) for the two cycles after the release's (74 and 6.5 mm)."""
    from quickrelease.building.effective import loop_cycles

    k1, k2, fy, zeta, fs, d0 = 12e6, 2.4e6, 60e3, 0.01, 3e3, 0.2  # D_y = 5 mm
    iso = Isolation.bilinear(M, k1, k2, fy, zeta, fs)
    cyc = model_cycles(iso, d0, 9.0)
    assert cyc["amplitude_m"].size == 3
    t = np.linspace(0.0, 9.0, 9 * 200000 // 2 + 1)
    c = 2 * zeta * math.sqrt(k1 * M)
    (x, v, a), t_stop = reference(M, k1, k2, fy * (1 - k2 / k1), c, fs, d0, t, with_rates=True)
    turns = [0] + [int(i) + 1 for i in np.nonzero(np.sign(v[1:-1]) * np.sign(v[2:]) < 0)[0]]
    got = loop_cycles(t, x, -M * a, turns=turns)
    assert len(got) == 3 and t_stop == math.inf
    for i in range(1, 3):
        assert cyc["amplitude_m"][i] == pytest.approx(got[i].amplitude_m, rel=1e-6)
        assert cyc["keff_N_m"][i] == pytest.approx(got[i].keff_N_m, rel=1e-4)
        assert cyc["edc_J"][i] == pytest.approx(got[i].edc_J, rel=1e-4)


def test_a_motion_of_fewer_than_two_half_cycles_has_no_cycles_and_no_curve(fitted):
    """Sliders that stop the layer within one half-cycle: no cycle, and the curve of such a fit is empty with a
    note (not an error)."""
    from dataclasses import replace

    iso = Isolation.linear(M, T, 0.0, 0.3 * M * G0)
    cyc = model_cycles(iso, D0, 10.0)
    assert all(v.size == 0 for v in cyc.values()) and cyc["from_release"].dtype == bool
    stuck = replace(fitted, estimates={**fitted.estimates, "friction": 0.3 * M * G0})
    curve = effective_curves(stuck, draws=20)
    assert curve.amplitude_m.size == 0 and "fewer than two cycles" in curve.notes[0]
    assert curve.summary()["amplitude_m"] == []


BAD_REALS = [float("nan"), float("inf"), -1.0, 0.0, "x", None, True, [], np.array([0.1, 0.2]), 1e308]


@pytest.mark.parametrize("name, value", [("level", v) for v in BAD_REALS]
                         + [("draws", v) for v in (float("nan"), float("inf"), -1, 0, "x", None, 20.5, True, [],
                                                   1e308, 10**7)]
                         + [("seed", v) for v in (float("nan"), -1, "x", None, 2.5, True)]
                         + [("amplitudes", v) for v in (float("nan"), -0.1, 0.0, "x", [], [[0.1, 0.2]], ["a"],
                                                        True, [0.1, float("inf")])],
                         ids=lambda v: repr(v)[:12])
def test_every_bad_argument_of_effective_curves_is_a_parameter_error_naming_it(fitted, name, value):
    """Before: level='x' or draws='x' a bare ValueError, draws=inf an OverflowError, draws=1e308 numpy's 'Maximum
    allowed dimension exceeded', seed=-1 numpy's error, amplitudes=['a'] a bare ValueError."""
    with pytest.raises(ParameterError) as info:
        effective_curves(fitted, **{"draws": 20, name: value})
    assert info.value.name == name and " is outside " in str(info.value)


@pytest.mark.parametrize("name, value", [("keff_tolerance", v) for v in BAD_REALS]
                         + [("edc_fraction", v) for v in BAD_REALS]
                         + [("release_time", v) for v in (float("nan"), float("inf"), "x", True, [1.0])]
                         + [("cycles", v) for v in (1.5, None, "x", [1.0, 2.0])] + [("curve", None)],
                         ids=lambda v: repr(v)[:12])
def test_every_bad_argument_of_judge_cycles_is_a_parameter_error_naming_it(fitted, name, value):
    curve = EffectiveCurve("linear", M, np.empty(0), {}, {}, {}, 0.95, 20, 0, ())
    args = {"cycles": [], "curve": curve, name: value}
    with pytest.raises(ParameterError) as info:
        judge_cycles(**args)
    assert info.value.name == name


@pytest.mark.parametrize("name, value", [("d0", v) for v in (float("nan"), 0.0, "x", None, True, [0.1])]
                         + [("horizon", v) for v in (float("nan"), float("inf"), -1.0, 0.0, "x", None, [5.0])],
                         ids=lambda v: repr(v)[:12])
def test_every_bad_argument_of_model_cycles_is_a_parameter_error_naming_it(name, value):
    from quickrelease.building.model import Isolation

    args = {"isolation": Isolation.linear(M, T, ZETA, FS), "d0": D0, "horizon": 10.0, name: value}
    with pytest.raises(ParameterError) as info:
        model_cycles(**args)
    assert info.value.name == name


@pytest.mark.parametrize("value", ["x", [[0.1, 0.2]], ["a"], None, {"a": 1}])
def test_the_curve_at_what_is_not_an_amplitude_is_a_parameter_error(fitted, value):
    curve = effective_curves(fitted, draws=20)
    with pytest.raises(ParameterError) as info:
        curve.at(value)
    assert info.value.name == "amplitude"
    assert curve.at([])["keff_N_m"].shape == (0,)
