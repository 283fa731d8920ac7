"""The predicted precision of a fit to a synthetic building record (issue 10, item 5: planning the building's
instrumentation), and the building's channel table.

``predicted_isolation_errors`` is the Cramer-Rao bound ``(J^T W J)^-1`` at the truth from the fit's own channel
model and Jacobian. References: the empirical spread of fits to independent noisy records (seeded, with a
stated band and its power); a hand calculation (the analytic Fisher information of an undamped cosine, and the
textbook frequency bound of a sinusoid); a finite-difference Fisher information of the independent solve_ivp
simulation of tests/building_reference.py.
"""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from building_reference import reference
from scipy import stats
from typer.testing import CliRunner

from quickrelease.building.isolation_fit import (
    CHANNEL_KINDS,
    BuildingChannel,
    fit_isolation,
    predicted_isolation_errors,
)
from quickrelease.building.model import RECORD_CHANNELS, Isolation, TwoDOF, free_vibration
from quickrelease.cli import app
from quickrelease.io.building_case import BUILDING_CHANNELS
from quickrelease.io.case import load_case
from quickrelease.studies.synth import BUILDING_NOISE, predicted_building_errors, synthesize_building

runner = CliRunner()

COULOMB = """[building]
mass = "650 t"
period = "2.0 s"
damping_ratio = 0.03
friction_coefficient = 0.005
displacement = "0.1 m"
"""
BILINEAR = """[building]
model = "bilinear"
mass = "400 t"
k1 = "40 MN/m"
k2 = "4 MN/m"
yield_force = "80 kN"
damping_ratio = 0.03
friction = "20 kN"
displacement = "150 mm"
"""


def _case(tmp_path, text, name="case.toml"):
    path = tmp_path / name
    path.write_text(text)
    return load_case(path, require_test=False)


@pytest.mark.slow
def test_prediction_matches_the_spread_of_fits_over_noisy_records(tmp_path):
    """30 independent records of a linear + Coulomb building (x and v, different noise levels and offsets, the
    release between samples), each fitted with the noise levels given; the spread of the estimates about the
    truth against the predicted covariance C.

    If the prediction is right (and the fit efficient), each parameter's ``Q_i = sum_seeds (est - truth)^2 /
    se_i^2`` is chi-square with 30 degrees of freedom, and the Mahalanobis sum ``sum_seeds d^T C^-1 d`` over
    the 7 parameters chi-square with 210. Bands: the 0.1% and 99.9% quantiles, so five tests together fail
    a right prediction with probability <= 1%. Power (computed below): a per-parameter band catches a standard
    error wrong by a factor 2 either way with probability >= 0.97; the joint band a covariance wrong by a
    factor 1.75 (standard errors by 1.32) either way with probability >= 0.99.
    """
    n_seeds = 30
    case = _case(tmp_path, COULOMB)
    kw = dict(rate=50.0, release_time=1.0037, duration=9.0, noise={"x": 0.5e-3, "v": 2e-3},
              offsets={"x": 1e-3, "v": -4e-3})
    pred = predicted_building_errors(synthesize_building(case, ["x", "v"], seed=0, **kw))
    names = list(pred.names)
    assert names == ["period", "damping_ratio", "friction", "d0", "release_time", "offset_x", "offset_v"]
    truth = pred.parameters
    start = {n: truth[n] for n in ("period", "damping_ratio", "friction", "d0")}  # the design values
    dev = []
    for seed in range(1, n_seeds + 1):
        syn = synthesize_building(case, ["x", "v"], seed=seed, **kw)
        fit = fit_isolation(syn.building_channels(), 650e3, "linear", release_time=1.0037, start=start,
                            profile=False)
        assert fit.converged and fit.chi2_reduced < 1.3
        dev.append([fit.estimates[n] - truth[n] for n in names])
    dev = np.array(dev)
    lo, hi = stats.chi2.ppf([0.001, 0.999], n_seeds)
    # the power of the per-parameter band against a standard error off by a factor 2 (the variance by 4)
    assert stats.chi2.cdf(lo * 4, n_seeds) + stats.chi2.sf(hi * 4, n_seeds) >= 0.97
    assert stats.chi2.cdf(lo / 4, n_seeds) + stats.chi2.sf(hi / 4, n_seeds) >= 0.97
    for n in ("period", "damping_ratio", "friction", "release_time"):
        q = float(np.sum(dev[:, names.index(n)] ** 2)) / pred.std_errors[n] ** 2
        print(f"Q / dof: {n} {q / n_seeds:.3f}")
        assert lo < q < hi, (n, q / n_seeds)
    dof = n_seeds * len(names)
    lo_j, hi_j = stats.chi2.ppf([0.001, 0.999], dof)
    assert stats.chi2.cdf(lo_j * 1.75, dof) + stats.chi2.sf(hi_j * 1.75, dof) >= 0.99
    assert stats.chi2.cdf(lo_j / 1.75, dof) + stats.chi2.sf(hi_j / 1.75, dof) >= 0.99
    q_joint = float(np.einsum("si,ij,sj->", dev, np.linalg.inv(pred.covariance), dev))
    print(f"Q / dof: joint {q_joint / dof:.3f}")
    assert lo_j < q_joint < hi_j, q_joint / dof


def test_the_period_of_an_undamped_record_against_the_hand_calculation():
    """x(t) = d0 cos(w (t - t_r)) + c after the release, d0 + c before; white displacement noise sigma; T, d0,
    t_r and c free (damping and friction held at 0). The Fisher information from the analytic derivatives
    (dx/dT = d0 w tau sin(w tau) / T, dx/dd0 = cos(w tau), dx/dt_r = d0 w sin(w tau), dx/dc = 1) gives every
    standard error; and for many cycles the period's is the textbook bound of a sinusoid's frequency with
    unknown amplitude and phase, var(w) = 24 sigma^2 / (d0^2 Delta^2 N (N^2 - 1)) (N samples after the
    release, Delta apart), times dT/dw = -T^2 / (2 pi)."""
    T, d0, t_r, c, sigma, rate = 2.0, 0.1, 1.0037, 2e-3, 1e-3, 50.0
    t = np.arange(int(41.0 * rate) + 1) / rate  # 20 cycles after the release
    ch = BuildingChannel("x", "x", t, np.zeros_like(t), noise=sigma)
    pred = predicted_isolation_errors([ch], 650e3, "linear",
                                      {"period": T, "damping_ratio": 0.0, "friction": 0.0, "d0": d0,
                                       "release_time": t_r, "offset_x": c}, fixed=("damping_ratio", "friction"))
    assert pred.names == ("period", "d0", "release_time", "offset_x")
    w, tau = 2 * math.pi / T, t - t_r
    moving = tau >= 0
    sin = np.where(moving, np.sin(w * tau), 0.0)
    J = np.column_stack([np.where(moving, d0 * w * tau * sin / T, 0.0), np.where(moving, np.cos(w * tau), 1.0),
                         np.where(moving, d0 * w * sin, 0.0), np.ones_like(t)]) / sigma
    se = np.sqrt(np.diag(np.linalg.inv(J.T @ J)))
    for n, ref in zip(pred.names, se, strict=True):
        assert pred.std_errors[n] == pytest.approx(ref, rel=2e-4), n
    N = int(np.count_nonzero(moving))
    se_w = math.sqrt(24 * sigma**2 / (d0**2 * (1 / rate) ** 2 * N * (N**2 - 1)))
    assert pred.std_errors["period"] == pytest.approx(T**2 / (2 * math.pi) * se_w, rel=0.01)
    assert pred.physical()["period_s"] == {"truth": T, "se": pred.std_errors["period"], "unit": "s",
                                           "relative_se": pred.std_errors["period"] / T}


def test_bilinear_prediction_against_a_finite_difference_fisher_of_solve_ivp():
    """A bilinear + Coulomb building recorded on x and v: the standard errors of k1, k2 (the delta method from
    the fit's T1 and k2/k1), F_y, zeta, F_s, d0, t_r and the offsets against the Fisher information of the
    independent solve_ivp reference, differentiated by central differences in (k1, k2, F_y, zeta, F_s, d0)
    directly (d/dt_r from its own rates, the offsets exact)."""
    m, k1, k2, Fy, zeta, Fs, d0, t_r = 4e5, 4e7, 4e6, 8e4, 0.03, 2e4, 0.15, 1.0037
    sx, sv, rate = 0.05e-3, 1e-3, 100.0
    t = np.arange(int(4.0 * rate) + 1) / rate  # the building sticks 2.6 s after the release
    p = dict(k1=k1, k2=k2, Fy=Fy, zeta=zeta, Fs=Fs, d0=d0)

    def sim(q):
        out, _ = reference(m, q["k1"], q["k2"], q["Fy"] * (1 - q["k2"] / q["k1"]),
                           2 * q["zeta"] * math.sqrt(q["k1"] * m), q["Fs"], q["d0"], t - t_r, with_rates=True)
        return out

    cols = []
    for n in p:
        h = 1e-6 * p[n]
        cols.append((sim({**p, n: p[n] + h})[:2] - sim({**p, n: p[n] - h})[:2]) / (2 * h))
    cols.append(-sim(p)[1:3])  # x(t - t_r): d/dt_r = -x_dot, -x_ddot
    zero, one = np.zeros(t.size), np.ones(t.size)
    J = np.column_stack([np.concatenate([c[0] / sx, c[1] / sv]) for c in cols]
                        + [np.concatenate([one / sx, zero]), np.concatenate([zero, one / sv])])
    se = np.sqrt(np.diag(np.linalg.inv(J.T @ J)))
    chs = [BuildingChannel("x", "x", t, zero, noise=sx), BuildingChannel("v", "v", t, zero, noise=sv)]
    pred = predicted_isolation_errors(chs, m, "bilinear", {
        "period": 2 * math.pi * math.sqrt(m / k1), "stiffness_ratio": k2 / k1, "yield_force": Fy,
        "damping_ratio": zeta, "friction": Fs, "d0": d0, "release_time": t_r})
    phys = pred.physical()
    keys = ["k1_N_m", "k2_N_m", "Fy_N", "damping_ratio", "friction_N", "d0_m", "release_time_s", "offset_x",
            "offset_v"]
    assert list(phys) == keys
    for key, ref in zip(keys, se, strict=True):
        assert phys[key]["se"] == pytest.approx(ref, rel=1e-3), key
    assert phys["k1_N_m"]["truth"] == pytest.approx(k1, rel=1e-12) and phys["Fy_N"]["unit"] == "N"
    assert not pred.warnings


def test_missing_samples_cost_precision(tmp_path):
    """Half the samples missing: the prediction uses the samples the record has, so the offsets' standard
    errors (sigma / sqrt(n) for a constant seen on n samples, to first order) grow by sqrt(n_all / n_kept)."""
    case = _case(tmp_path, COULOMB)
    kw = dict(rate=50.0, release_time=1.0037, duration=9.0, offsets={"x": 1e-3})
    full = predicted_building_errors(synthesize_building(case, ["x", "v"], seed=2, **kw))
    syn = synthesize_building(case, ["x", "v"], seed=2, missing=0.5, **kw)
    half = predicted_building_errors(syn)
    for name in ("x", "v"):
        kept = np.count_nonzero(np.isfinite(syn.data[name]))
        ratio = half.std_errors[f"offset_{name}"] / full.std_errors[f"offset_{name}"]
        assert ratio == pytest.approx(math.sqrt(syn.t.size / kept), rel=0.05), name
    assert half.std_errors["period"] > 1.3 * full.std_errors["period"]


def test_the_device_prediction_also_uses_the_samples_the_record_has():
    """The same fault class on the device's synth: its prediction (a fit to the noise-free record) took every
    sample, as if none were missing (F1's standard error identical with half the samples gone)."""
    from quickrelease.studies.synth import predicted_errors, synthesize

    case = load_case(Path(__file__).parents[2] / "examples" / "building.toml")
    kw = dict(rate=500.0, seed=2)
    full = predicted_errors(case, synthesize(case, ["u", "v"], **kw))
    syn = synthesize(case, ["u", "v"], missing=0.5, **kw)
    half = predicted_errors(case, syn)
    kept = sum(np.count_nonzero(np.isfinite(v)) for v in syn.data.values()) / (2 * syn.t.size)
    for key in ("F1_se_N", "F2_se_N"):  # white noise on every channel alike: the information scales with n
        assert half[key] / full[key] == pytest.approx(math.sqrt(1 / kept), rel=0.05), key


def test_synth_cli_prints_and_writes_the_prediction(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "b.toml").write_text(BILINEAR)
    r = runner.invoke(app, ["synth", "b.toml", "--channels", "x,a", "--rate", "100 Hz", "--release-time", "1.0037 s",
                            "--duration", "4 s", "--out", "r.csv", "--json"])
    assert r.exit_code == 0, r.output
    pred = json.loads(r.stdout)["predicted"]
    assert list(pred["parameters"]) == ["k1_N_m", "k2_N_m", "Fy_N", "damping_ratio", "friction_N", "d0_m",
                                        "release_time_s", "offset_x", "offset_a"]
    row = pred["parameters"]["k1_N_m"]
    assert row["truth"] == pytest.approx(4e7) and row["unit"] == "N/m" and 0 < row["relative_se"] < 0.05
    assert pred["parameters"]["release_time_s"]["relative_se"] is None
    assert set(pred["std_errors"]) == {"period", "stiffness_ratio", "yield_force", "damping_ratio", "friction", "d0",
                                       "release_time", "offset_x", "offset_a"}
    # the same numbers as the library's, on the record as written
    syn = synthesize_building(_case(tmp_path, BILINEAR, "b2.toml"), ["x", "a"], rate=100.0, release_time=1.0037,
                              duration=4.0)
    lib = predicted_building_errors(syn).summary()
    for key, row in lib["parameters"].items():
        assert pred["parameters"][key]["se"] == pytest.approx(row["se"], rel=1e-12), key
    r = runner.invoke(app, ["synth", "b.toml", "--channels", "x,a", "--rate", "100 Hz", "--duration", "4 s",
                            "--out", "r2.csv"])
    assert r.exit_code == 0, r.output
    assert "Precision of a bilinear fit to it (Cramer-Rao bound)" in r.stdout
    for label in ("initial stiffness k1", "post-yield stiffness k2", "yield force F_y", "damping ratio zeta",
                  "slider friction F_s", "release instant", "offset of a"):
        assert label in r.stdout, label


def test_the_building_channels_come_from_one_table():
    """The record reader's, the fit's and synth's channel tables and the motion's channels are one table's."""
    assert BUILDING_CHANNELS is RECORD_CHANNELS
    assert list(CHANNEL_KINDS) == list(BUILDING_NOISE) == list(RECORD_CHANNELS)
    assert CHANNEL_KINDS == {"x": "m", "v": "m/s", "a": "m/s^2", "x_roof": "m", "v_roof": "m/s", "a_roof": "m/s^2"}
    t = np.linspace(-1.0, 3.0, 9)
    rigid = free_vibration(Isolation.linear(1e5, 2.0, 0.05, 1e3), 0.1, t_end=3.0)
    two = free_vibration(TwoDOF(2e5, 1e5, 2.0, 0.5, 0.05, 1e3, 0.02), 0.1, t_end=3.0)
    assert list(rigid.channels(t)) == list(two.channels(t)) == list(RECORD_CHANNELS)


def test_a_parameter_such_a_record_cannot_see_is_not_determined():
    """A bilinear building pushed below its yield displacement (d0 = 10 mm < F_y / k1 = 25 mm) never yields:
    F_y has no effect on its record, so its standard error is infinite (the pseudo-inverse alone says 0, a
    false precision), with a warning naming it; None in JSON."""
    m, k1 = 4e5, 4e7
    t = np.arange(401) / 100.0
    ch = [BuildingChannel("x", "x", t, np.zeros_like(t), noise=5e-5)]
    pred = predicted_isolation_errors(ch, m, "bilinear", {
        "period": 2 * math.pi * math.sqrt(m / k1), "stiffness_ratio": 0.1, "yield_force": 1e6,
        "damping_ratio": 0.03, "friction": 2e4, "d0": 0.01, "release_time": 1.0037})
    assert pred.std_errors["yield_force"] == math.inf and pred.physical()["Fy_N"]["se"] == math.inf
    assert "yield_force has no effect on such a record: it is not determined" in pred.warnings
    assert pred.summary()["parameters"]["Fy_N"]["se"] is None and pred.summary()["std_errors"]["yield_force"] is None
    json.dumps(pred.summary(), allow_nan=False)


@pytest.mark.parametrize("factor", [1e-250, 1e250])
def test_standard_errors_scale_with_the_noise_over_the_float_range(factor):
    """The covariance is proportional to the noise variance (W = 1 / sigma^2): every standard error scales with
    sigma, for noise levels near either end of the float range too (no overflow or underflow on the way)."""
    t = np.arange(451) / 50.0
    params = {"period": 2.0, "damping_ratio": 0.03, "friction": 3e4, "d0": 0.1, "release_time": 1.0037}

    def chans(f):
        return [BuildingChannel("x", "x", t, np.zeros_like(t), noise=5e-4 * f),
                BuildingChannel("v", "v", t, np.zeros_like(t), noise=2e-3 * f)]

    ref = predicted_isolation_errors(chans(1.0), 650e3, "linear", params)
    far = predicted_isolation_errors(chans(factor), 650e3, "linear", params)
    for n in ref.names:
        assert far.std_errors[n] == pytest.approx(factor * ref.std_errors[n], rel=1e-9), n
    for key, row in far.physical().items():
        assert row["se"] == pytest.approx(factor * ref.physical()[key]["se"], rel=1e-9), key


@pytest.mark.parametrize("name, value", [("rate", 0.0), ("rate", float("nan")), ("release_time", -1.0),
                                         ("release_time", float("inf")), ("jitter", 1.0), ("jitter", -0.1),
                                         ("jitter", float("nan")), ("missing", 1.0), ("missing", float("nan"))])
def test_the_sampling_of_a_synthetic_record_outside_its_range_is_refused_naming_it(tmp_path, name, value):
    """rate and release_time in (0, inf), jitter and missing in [0, 1): the device's synthesize and the building's
    share these checks (studies.synth._sampling)."""
    from quickrelease.errors import ParameterError
    from quickrelease.studies.synth import synthesize

    args = {"rate": 200.0, "release_time": 2.0, "jitter": 0.0, "missing": 0.0, name: value}
    with pytest.raises(ParameterError) as info:
        synthesize_building(_case(tmp_path, COULOMB), ["x"], **args)
    assert info.value.name == name
    device = load_case(Path(__file__).resolve().parents[2] / "examples" / "fit.toml")
    with pytest.raises(ParameterError) as info:
        synthesize(device, ["u"], **args)
    assert info.value.name == name


@pytest.mark.parametrize("noise", [0.0, -1e-3, float("nan"), float("inf")])
def test_a_noise_that_is_not_positive_is_refused_naming_the_channel(tmp_path, noise):
    from quickrelease.errors import ParameterError

    with pytest.raises(ParameterError, match="noise of x"):
        synthesize_building(_case(tmp_path, COULOMB), ["x"], rate=200.0, noise={"x": noise})
