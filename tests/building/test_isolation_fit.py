"""The isolation-system fit (isolation_fit.py) on records made by an independent simulation (solve_ivp with
events, tests/building_reference.py): displacement and acceleration channels on their own time axes, with
sensor zeros, noise, a pre-release segment and an unknown release instant."""

import math

import numpy as np
import pytest
from building_reference import reference

from quickrelease.building.isolation_fit import BuildingChannel, compare_models, decay_check, fit_isolation, ljung_box
from quickrelease.errors import ParameterError

M = 4.0e5


def _record(k1, k2, fp, c, Fs, d0, seed, t_release=0.731, duration=12.0):
    rng = np.random.default_rng(seed)
    tx = np.arange(-2.0, duration, 1 / 100)  # LVDT at 100 Hz
    ta = np.arange(-2.0, duration, 1 / 200) + 0.0013  # accelerometer at 200 Hz on its own clock
    x = reference(M, k1, k2, fp, c, Fs, d0, tx - t_release)[0]
    a = reference(M, k1, k2, fp, c, Fs, d0, ta - t_release, with_rates=True)[0][2]
    return [BuildingChannel("lvdt", "x", tx, x + 0.004 + rng.normal(0, 2e-4, x.size)),
            BuildingChannel("acc", "a", ta, a + 0.01 + rng.normal(0, 0.02, a.size))]


def _within(fit, truth, z=4.0):
    for name, value in truth.items():
        assert abs(fit.estimates[name] - value) < z * fit.std_errors[name], (name, fit.estimates[name], value,
                                                                             fit.std_errors[name])


@pytest.mark.slow
def test_linear_isolation_recovered_with_calibrated_errors():
    """Six records: every estimate within 4.5 standard errors, and the pooled z-scores of the 42 estimates
    have an RMS near 1 (a chi-square with 42 degrees of freedom: RMS in [0.7, 1.35] with probability above
    0.99), so standard errors twice or half their size are caught."""
    T, zeta, Fs, d0 = 2.0, 0.04, 1.2e4, 0.15
    k = M * (2 * math.pi / T) ** 2
    truth = {"period": T, "damping_ratio": zeta, "friction": Fs, "d0": d0, "release_time": 0.731,
             "offset_lvdt": 0.004, "offset_acc": 0.01}
    z = []
    for seed in range(1, 7):
        channels = _record(k, k, math.inf, 2 * zeta * math.sqrt(k * M), Fs, d0, seed, duration=9.0)
        fit = fit_isolation(channels, M, "linear")
        assert fit.noise_source == {"lvdt": "pre-release segment", "acc": "pre-release segment"}
        assert 0.8 < fit.chi2_reduced < 1.25 and not fit.warnings
        _within(fit, truth, 4.5)
        z += [(fit.estimates[n] - v) / fit.std_errors[n] for n, v in truth.items()]
        lo, hi = fit.ci95["friction"]
        assert lo < fit.estimates["friction"] < hi and fit.interval_method["friction"] == "jacobian"
        if seed == 1:  # the model-free decay agrees with the fit (the combined law is exact for this model)
            check = decay_check(fit)
            assert [r["parameter"] for r in check["rows"]] == ["period", "damping_ratio", "friction"]
            assert all(abs(r["difference_in_se"]) < 10 for r in check["rows"]), check["rows"]
            assert abs(check["rows"][0]["decay"] - T) < 0.01 * T
    rms = float(np.sqrt(np.mean(np.square(z))))
    assert 0.7 < rms < 1.35, rms
    assert fit.isolation().period == pytest.approx(fit.estimates["period"], rel=1e-12)


def test_no_friction_gives_a_profile_interval_from_zero():
    """F_s = 0 sits at its bound: the interval is the profile likelihood's, from 0 to a finite upper end."""
    T, zeta, d0 = 2.0, 0.05, 0.15
    k = M * (2 * math.pi / T) ** 2
    channels = _record(k, k, math.inf, 2 * zeta * math.sqrt(k * M), 0.0, d0, 3, duration=8.0)
    fit = fit_isolation(channels, M, "linear", fixed={"release_time": 0.731})
    assert fit.interval_method["friction"] == "profile"
    lo, hi = fit.ci95["friction"]
    assert lo == 0.0 and 0.0 < hi < 0.01 * k * d0
    _within(fit, {"period": T, "damping_ratio": zeta})


@pytest.mark.slow
def test_bilinear_from_design_values_and_model_choice():
    k1, k2, Fy, zeta, Fs, d0 = 4.0e7, 4.0e6, 8.0e4, 0.03, 8.0e3, 0.2
    T1 = 2 * math.pi * math.sqrt(M / k1)
    channels = _record(k1, k2, Fy * (1 - k2 / k1), 2 * zeta * math.sqrt(k1 * M), Fs, d0, 3, duration=10.0)
    design = {"period": 1.15 * T1, "damping_ratio": 0.05, "friction": 0.7 * Fs, "stiffness_ratio": 0.13,
              "yield_force": 0.8 * Fy}
    bilinear = fit_isolation(channels, M, "bilinear", start=design, profile=False)
    _within(bilinear, {"period": T1, "damping_ratio": zeta, "friction": Fs, "stiffness_ratio": k2 / k1,
                       "yield_force": Fy, "d0": d0})
    linear = fit_isolation(channels, M, "linear", profile=False)
    table = compare_models([linear, bilinear])
    assert table[0]["model"] == "bilinear" and table[1]["delta_bic"] > 100
    assert any("does not support" in w for w in linear.warnings)
    assert "no decay law" in decay_check(bilinear)["notes"][0]


def test_ljung_box_white_and_coloured():
    rng = np.random.default_rng(0)
    white = rng.normal(size=4000)
    coloured = np.convolve(white, np.ones(5) / 5, mode="same")
    assert ljung_box(white) > 0.01
    assert ljung_box(coloured) < 1e-10


def test_bad_input():
    t = np.linspace(0, 1, 50)
    with pytest.raises(ParameterError, match="kind"):
        BuildingChannel("x", "displacement", t, t)
    with pytest.raises(ParameterError, match="noise"):
        BuildingChannel("x", "x", t, t, noise=-1.0)
    with pytest.raises(ParameterError, match="finite"):
        BuildingChannel("x", "x", t, np.where(t > 0.5, np.inf, 0.0))
    ch = BuildingChannel("x", "x", t, np.cos(t))
    with pytest.raises(ParameterError, match="model"):
        fit_isolation([ch], M, "trilinear")
    with pytest.raises(ParameterError, match="mass"):
        fit_isolation([ch], float("nan"))
    with pytest.raises(ParameterError, match="fixed"):
        fit_isolation([ch], M, fixed={"stiffness": 1.0}, release_time=0.5)


def test_the_guarded_difference_takes_the_smaller_quotient_where_the_two_disagree():
    """The Jacobian's column from two difference quotients (``_guarded``): their smooth combination, but where they
    differ by more than half their mean magnitude (a jump inside the stencil) the smaller of the two; written out
    here element by element."""
    from quickrelease.building.isolation_fit import _guarded

    rng = np.random.default_rng(4)
    d1 = rng.normal(size=400)
    d2 = d1 * (1.0 + 0.1 * rng.normal(size=400))
    jumps = rng.random(400) < 0.2
    d2[jumps] = d1[jumps] * rng.choice([-3.0, 40.0, 0.01], size=int(jumps.sum()))
    d1[:3], d2[:3] = [np.nan, 0.0, -0.0], [1.0, 0.0, 5.0]
    smooth = 0.5 * (d1 + d2)
    want = []
    for p, q, s in zip(d1, d2, smooth, strict=True):
        if abs(p - q) > 0.5 * (abs(p) + abs(q)):
            want.append(p if abs(p) < abs(q) else q)
        else:
            want.append(s)
    got = _guarded(d1.copy(), d2.copy(), smooth.copy())
    np.testing.assert_array_equal(got, np.array(want))
    assert 20 < int(np.sum(got != smooth)) and np.isnan(got[0]) and got[2] == -0.0


def test_the_jacobian_at_a_bound_agrees_with_the_central_difference():
    """A parameter at its bound takes the one-sided second-order difference into the feasible side: on a smooth
    misfit (no sliders) its column agrees with the central difference's away from the bound to O(h^2), far
    closer than the first-order quotient's O(h)."""
    from quickrelease.building import isolation_fit as F

    k = M * (2 * math.pi / 2.0) ** 2
    channels = _record(k, k, math.inf, 2 * 0.04 * math.sqrt(k * M), 0.0, 0.15, 1, duration=4.0)
    noise = {"lvdt": 2e-4, "acc": 0.02}
    lower, upper = F._bounds(channels, 0.731, 2.0)
    names = ["period", "damping_ratio", "d0", "release_time", "offset_lvdt", "offset_acc"]
    base = {"period": 2.0, "damping_ratio": 0.04, "friction": 0.0, "d0": 0.15, "release_time": 0.731,
            "offset_lvdt": 0.004, "offset_acc": 0.01}
    theta = np.array([base[n] for n in names])
    free = F._Misfit(channels, noise, M, "linear", None, lower, {**upper, "period": math.inf})
    bound = F._Misfit(channels, noise, M, "linear", None, lower, {**upper, "period": 2.0})
    central, one_sided = free.jacobian(theta, names, base)[:, 0], bound.jacobian(theta, names, base)[:, 0]
    h = free.step("period", 2.0)
    first = (bound.residuals(theta - [h, 0, 0, 0, 0, 0], names, base) - bound.residuals(theta, names, base)) / -h
    scale = np.linalg.norm(central)
    # (4e-6 and 5e-4 of the column's norm)
    assert np.linalg.norm(one_sided - central) < 2e-5 * scale and np.linalg.norm(first - central) > 1e-4 * scale


def test_the_jacobian_reuses_the_residuals_only_at_the_same_point():
    """The Jacobian's centre is the last residual evaluation where that was the same point (parameters, free names
    and fixed values: the solvers ask for the Jacobian where they have just evaluated the residuals); anywhere else
    it is evaluated. Each Jacobian equals that of a fresh misfit, bit for bit."""
    from quickrelease.building import isolation_fit as F

    k = M * (2 * math.pi / 2.0) ** 2
    channels = _record(k, k, math.inf, 2 * 0.04 * math.sqrt(k * M), 1.2e4, 0.15, 1, duration=4.0)
    noise = {"lvdt": 2e-4, "acc": 0.02}
    lower, upper = F._bounds(channels, 0.731, 2.0)
    names = ["period", "damping_ratio", "friction", "d0", "release_time", "offset_lvdt", "offset_acc"]
    base = {"period": 2.0, "damping_ratio": 0.04, "friction": 1.2e4, "d0": 0.15, "release_time": 0.731,
            "offset_lvdt": 0.004, "offset_acc": 0.01}
    a = np.array([base[n] for n in names])
    b = a * (1.0 + 1e-3)

    def fresh(theta, free=names, at=base):
        return F._Misfit(channels, noise, M, "linear", None, lower, upper).jacobian(theta, free, at)

    m = F._Misfit(channels, noise, M, "linear", None, lower, upper)
    m.residuals(a, names, base)
    np.testing.assert_array_equal(m.jacobian(b, names, base), fresh(b))  # another point
    m.residuals(b, names, base)
    np.testing.assert_array_equal(m.jacobian(b, names, base), fresh(b))  # the same point: reused
    moved = {**base, "offset_acc": 0.02}  # the same free values, another fixed value
    m.residuals(b[:-1], names[:-1], base)
    np.testing.assert_array_equal(m.jacobian(b[:-1], names[:-1], moved), fresh(b[:-1], names[:-1], moved))
    swapped = names[:-2] + names[:-3:-1]  # the same values for other free names (the two zeros swapped)
    m.residuals(b, names, base)
    np.testing.assert_array_equal(m.jacobian(b, swapped, base), fresh(b, swapped, base))


def test_the_covariance_leaves_out_a_sample_that_alone_holds_a_direction():
    """``_covariance_without_cusps``: scale (J^T J)^-1 (numpy's inverse here), except that a sample whose leverage
    (the hat matrix's diagonal) exceeds 0.5 is left out (a model's cusp parked on it, whose infinite slope the
    Jacobian reads as information): in a block where ten samples see the third parameter with slope 1 and one more
    with slope a, that one's leverage is a^2 / (10 + a^2): kept at 0.45, left out at 0.55. Ordinary samples (400
    of 3 parameters, leverages ~0.0075) are all kept; a parameter that only one sample sees keeps that sample (left
    out, the parameter would not be identified)."""
    from quickrelease.building.isolation_fit import _covariance_without_cusps

    rng = np.random.default_rng(7)
    J = rng.normal(size=(400, 3))
    cov, blind = _covariance_without_cusps(J, 2.0)
    np.testing.assert_allclose(cov, 2.0 * np.linalg.inv(J.T @ J), rtol=1e-9)
    assert not blind.any()
    for share, left_out in ((0.45, False), (0.55, True)):
        block = J.copy()
        block[:11, :2] = 0.0
        block[:, 2] = 0.0
        block[:10, 2] = 1.0
        block[10, 2] = math.sqrt(10.0 * share / (1.0 - share))
        kept = np.delete(block, 10, axis=0) if left_out else block
        cov, blind = _covariance_without_cusps(block, 3.0)
        np.testing.assert_allclose(cov, 3.0 * np.linalg.inv(kept.T @ kept), rtol=1e-9)
    cusp = J.copy()
    cusp[17] = [0.0, 300.0, 5.0]  # one sample moving 300 times as fast as the others with the second parameter
    rest = np.delete(cusp, 17, axis=0)
    np.testing.assert_allclose(_covariance_without_cusps(cusp, 1.0)[0], np.linalg.inv(rest.T @ rest), rtol=1e-9)
    alone = J.copy()
    alone[:, 2] = 0.0
    alone[5, 2] = 4.0
    cov, blind = _covariance_without_cusps(alone, 1.0)
    np.testing.assert_allclose(cov, np.linalg.inv(alone.T @ alone), rtol=1e-9)
    assert not blind.any()


def test_a_solve_stopped_at_a_sample_instant_is_bounded_there():
    """``_Misfit.release_edge``: a release time within the Jacobian's release step of a sample instant t_k (a solve
    stopped against the step the chi-square takes there) is bounded at t_k on the side where it ended: above by t_k
    (the sample on the released motion: the acceleration there -(k d0 - F_s) / m, the closed form at rest after the
    release) or below by the next float after it (the sample at rest: 0); the other bounds as they were. Farther
    than the step from every sample, or with the release not free: None."""
    from quickrelease.building import isolation_fit as F

    T, Fs, d0 = 2.0, 1.2e4, 0.15
    k = M * (2 * math.pi / T) ** 2
    channels = _record(k, k, math.inf, 0.0, Fs, d0, 1, duration=4.0)
    lower, upper = F._bounds(channels, 0.731, T)
    m = F._Misfit(channels, {"lvdt": 2e-4, "acc": 0.02}, M, "linear", None, lower, upper)
    free = ["period", "release_time", "d0"]
    lo = np.array([lower.get(n, -math.inf) for n in free])
    hi = np.array([upper.get(n, math.inf) for n in free])
    acc = channels[1]
    j = int(np.argmin(np.abs(acc.t - 0.731)))
    t_k = float(acc.t[j])  # an accelerometer's sample (its clock 1.3 ms off the LVDT's)
    h = F.RELEASE_STEP * max(1.0, t_k - float(channels[0].t[0]))
    rows = slice(channels[0].t.size, None)
    for offset in (-0.9 * h, -1e-12, 0.0, 1e-12, 0.9 * h):
        new_lo, new_hi = m.release_edge(np.array([T, t_k + offset, d0]), free, lo, hi)
        edge = new_hi[1] if offset <= 0.0 else new_lo[1]
        base = {"period": T, "damping_ratio": 0.0, "friction": Fs, "d0": d0, "release_time": edge}
        a = m.model_vector(base)[rows][j]
        if offset <= 0.0:
            assert edge == t_k and new_lo[1] == lo[1]
            assert a == pytest.approx(-(k * d0 - Fs) / M, rel=1e-12)
        else:
            assert edge == np.nextafter(t_k, math.inf) and new_hi[1] == hi[1]
            assert a == 0.0
        np.testing.assert_array_equal(np.delete(new_lo, 1), np.delete(lo, 1))
        np.testing.assert_array_equal(np.delete(new_hi, 1), np.delete(hi, 1))
    assert m.release_edge(np.array([T, t_k + 1.1 * h, d0]), free, lo, hi) is None
    assert m.release_edge(np.array([T, d0]), ["period", "d0"], lo[[0, 2]], hi[[0, 2]]) is None


@pytest.mark.parametrize("model", ["linear", "pendulum", "boucwen"])
def test_the_release_time_column_is_that_of_the_motion_integrated_again(model):
    """The Jacobian's release-time column evaluates the centre's motion at shifted times (the motion does not depend
    on when it starts, and its steps not on the horizon): bit for bit the column of the motions integrated again
    with the release moved, on the whole record and on the coarse steps of the thinned one."""
    from quickrelease.building import isolation_fit as F

    k = M * (2 * math.pi / 2.0) ** 2
    channels = _record(k, k, math.inf, 2 * 0.04 * math.sqrt(k * M), 1.2e4, 0.15, 1, duration=4.0)
    noise = {"lvdt": 2e-4, "acc": 0.02}
    lower, upper = F._bounds(channels, 0.731, 2.0)
    base = {"d0": 0.15, "release_time": 0.731, "offset_lvdt": 0.004, "offset_acc": 0.01, "damping_ratio": 0.04,
            "period": 2.0, "friction": 1.2e4}
    if model == "pendulum":
        base.update(friction_slow=0.01, friction_fast=0.02, rate=30.0)
    if model == "boucwen":
        base.update(period=2.5, characteristic_strength=0.04 * M * 9.81, yield_displacement=0.01, shape=1.3)
    names = ["d0", "release_time", "period", "offset_acc"]
    theta = np.array([base[n] for n in names])
    for coarse in (False, True):
        m = F._Misfit(channels, noise, M, model, None, lower, upper, coarse_steps=coarse)
        J = m.jacobian(theta, names, base)
        again = F._Misfit(channels, noise, M, model, None, lower, upper, coarse_steps=coarse)
        again._evaluated_at = lambda th, fr, ba, again=again: (again.residuals(th, fr, ba), None)
        np.testing.assert_array_equal(J, again.jacobian(theta, names, base))
        assert np.count_nonzero(J[:, 1]) > 0.5 * J.shape[0]


@pytest.mark.slow
def test_a_refit_given_the_memo_solves_only_what_its_start_changes(monkeypatch):
    """fit_isolation(memo=...): a refit of the same record from other start values takes the global stage and the
    solves its start leaves as they were from the memo (no global search; one least-squares solve, its start's on
    the thinned record, where the start leads into the basin the first fit found) and is the fit computed without
    the memo, to the last bit. An acceleration record's d0 comes from the start (no displacement to read it
    from): a start with another d0 changes the record's own starts and the search's, which then run again."""
    import quickrelease.building.isolation_fit as isf

    T, zeta, Fs, d0 = 2.0, 0.04, 1.2e4, 0.15
    k = M * (2 * math.pi / T) ** 2
    t = np.arange(-1.0, 4.0, 1 / 50) + 0.0013  # an accelerometer at 50 Hz, 4 s after the release: cheap, enough
    a = reference(M, k, k, math.inf, 2 * zeta * math.sqrt(k * M), Fs, d0, t - 0.731, with_rates=True)[0][2]
    channels = [BuildingChannel("acc", "a", t, a + 0.01 + np.random.default_rng(3).normal(0, 0.02, t.size))]
    counts = {"search": 0, "solve": 0}

    def counted(name, real):
        def run(*args, **kwargs):
            counts[name] += 1
            return real(*args, **kwargs)
        return run

    monkeypatch.setattr(isf, "global_candidates", counted("search", isf.global_candidates))
    monkeypatch.setattr(isf, "bounded_least_squares", counted("solve", isf.bounded_least_squares))
    memo = isf.FitMemo()
    first = fit_isolation(channels, M, "linear", memo=memo)
    assert counts["search"] == 1 and memo.hits == 0
    for start, searches in (({"period": 1.05 * T, "damping_ratio": 0.05, "friction": 1.0e4}, 0),
                            ({"period": T, "d0": 1.3 * d0}, 1)):
        before = dict(counts)
        refit = fit_isolation(channels, M, "linear", start=start, memo=memo)
        assert counts["search"] - before["search"] == searches, start
        assert abs(refit.chi2 - first.chi2) < 1.0  # the same minimum
        if not searches:
            assert counts["solve"] - before["solve"] == 1
        again = fit_isolation(channels, M, "linear", start=start)
        assert refit.chi2 == again.chi2 and refit.estimates == again.estimates and refit.ci95 == again.ci95
        assert refit.search.summary() == again.search.summary() and refit.warnings == again.warnings
    # the friction held at two values: the solves from the same start points differ in what they hold
    fit_isolation(channels, M, "linear", fixed={"friction": 1.0e4}, global_search=False, memo=memo)
    held = fit_isolation(channels, M, "linear", fixed={"friction": 1.4e4}, global_search=False, memo=memo)
    again = fit_isolation(channels, M, "linear", fixed={"friction": 1.4e4}, global_search=False)
    assert held.chi2 == again.chi2 and held.estimates == again.estimates


@pytest.mark.parametrize("model", ["pendulum", "boucwen"])
def test_the_release_column_reaches_past_a_record_that_ends_at_a_step(model):
    """The motion runs ``RELEASE_REACH`` release steps past the record's last sample: the Jacobian's release column
    evaluates it there with the release one step earlier (the integrated motions are NaN past their last step). A
    record whose last sample lies 1e-7 s before one of the integration's step ends (its steps do not depend on the
    horizon): without the reach that step would be the motion's last, and the column's last entry past it. The
    column of an LVDT is ``-v(t - t_r) / sigma``: the independent reference's velocity, to 1e-6 of its largest."""
    import isolator_reference as ref

    from quickrelease.building import isolation_fit as F
    from quickrelease.building.model import free_vibration

    t_r, d0, sigma = 0.731, 0.15, 2e-4
    p = {"period": 2.5, "damping_ratio": 0.03, "d0": d0, "release_time": t_r, "offset_x": 0.0}
    if model == "pendulum":
        p.update(friction_slow=0.01, friction_fast=0.02, rate=30.0)
    else:
        p.update(friction=1.2e4, characteristic_strength=0.04 * M * 9.81, yield_displacement=0.01, shape=1.3)
    k = M * (2 * math.pi / p["period"]) ** 2
    c = 2 * p["damping_ratio"] * math.sqrt(k * M)
    system = ref.pendulum(M, 9.80665 / k * M, 0.01, 0.02, rate=30.0, damping=c) if model == "pendulum" else \
        ref.boucwen(M, k, p["characteristic_strength"], 0.01, 1.3, damping=c, friction=1.2e4)
    steps = free_vibration(F._isolation(model, M, p), d0, t_end=6.0)._grid[0]
    end = float(steps[np.searchsorted(steps, 1.5)])  # (the motion still moving: it sticks at 2.5 s, 3.5 s)
    t = t_r + end - 1e-7 - 0.01 * np.arange(400)[::-1]  # 100 Hz, the last sample 1e-7 s before the step's end
    x = ref.simulate(system, d0, t - t_r, t_end=float(t[-1] - t_r) + 1e-3).x
    channels = [BuildingChannel("lvdt", "x", t, x, sigma)]
    lower, upper = F._bounds(channels, t_r, p["period"])
    misfit = F._Misfit(channels, {"lvdt": sigma}, M, model, None, lower, upper)
    assert misfit.motion(p)._grid[0][-1] > end  # the reach: past the step that ends just after the record
    J = misfit.jacobian(np.array([d0, t_r]), ["d0", "release_time"], p)
    v = ref.simulate(system, d0, t - t_r, t_end=float(t[-1] - t_r) + 1e-3).v
    assert np.all(np.isfinite(J[:, 1]))
    np.testing.assert_allclose(J[:, 1], -v / sigma, rtol=0, atol=1e-6 * np.max(np.abs(v)) / sigma)


@pytest.mark.slow
def test_a_refit_with_other_weights_computes_again():
    """A memo of one record fitted with the accelerometer's noise at 0.02 m/s^2, then the same samples weighted with
    it at 0.2 (the LVDT's alone rules): the refit with the memo is the fit without one, to the last bit (the
    record's key holds its weights: the searches and solves of the first fit are not the second's), and the two
    weightings' estimates differ."""
    import quickrelease.building.isolation_fit as isf

    T, zeta, Fs, d0 = 2.0, 0.04, 1.2e4, 0.15
    k = M * (2 * math.pi / T) ** 2
    raw = _record(k, k, math.inf, 2 * zeta * math.sqrt(k * M), Fs, d0, 5, duration=4.0)

    def weighted(acc):
        return [BuildingChannel(c.name, c.kind, c.t, c.values, 2e-4 if c.kind == "x" else acc) for c in raw]

    memo = isf.FitMemo()
    first = fit_isolation(weighted(0.02), M, "linear", memo=memo)
    refit = fit_isolation(weighted(0.2), M, "linear", memo=memo)
    again = fit_isolation(weighted(0.2), M, "linear")
    assert refit.chi2 == again.chi2 and refit.estimates == again.estimates and refit.ci95 == again.ci95
    assert refit.estimates["period"] != first.estimates["period"]


def test_a_refinement_from_another_point_has_another_key():
    """The memo's key of a refinement (the polish, the step search) holds the point it starts from: two solves of
    the same record, cost and count of evaluations (what a refit from other start values can end at: the same
    piece of a staircase) that differ in one parameter have different keys; the same solve, the same key."""
    from scipy.optimize import OptimizeResult

    import quickrelease.building.isolation_fit as isf

    k = M * (2 * math.pi / 2.0) ** 2
    channels = _record(k, k, math.inf, 0.0, 1.2e4, 0.15, 1, duration=2.0)
    lower, upper = isf._bounds(channels, 0.731, 2.0)
    misfit = isf._Misfit(channels, {"lvdt": 2e-4, "acc": 0.02}, M, "linear", None, lower, upper)
    names, values = ["period", "d0"], {"period": 2.0, "d0": 0.15, "friction": 1.2e4}

    def key(x):
        res = OptimizeResult(x=np.array(x), cost=1234.5, nfev=17)
        return isf._refinement_key("polish", misfit, names, values, res, 0, 1e-8)

    assert key([2.0, 0.15]) == key([2.0, 0.15])
    assert key([2.0, 0.15]) != key([2.0, 0.15 + 1e-9])
