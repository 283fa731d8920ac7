"""``IsolationPrecision.physical()``: the predicted standard errors keyed as the building's JSON, for every model
(issue 24: the pendulum's R and friction law, the Bouc-Wen bearings' Kd, Qd, dy, n, the power-law damper's C and
alpha), against hand calculations written here from a covariance written here.

The derived rows by the delta method written out: R = g (T / 2 pi)^2 gives dR/dT = 2 R / T, so se(R) = 2 R / T
se(T); Kd = m (2 pi / T)^2 gives dKd/dT = -2 Kd / T, so se(Kd) = 2 Kd / T se(T) (functions of T alone: T's
correlations with the other parameters do not enter); k2 = r m (2 pi / T1)^2 gives var(k2) = (dk2/dT1)^2 var(T1)
+ k1^2 var(r) + 2 (dk2/dT1) k1 cov(T1, r) with dk2/dT1 = -2 k2 / T1 (the correlation enters).
"""

import math

import numpy as np
import pytest

from quickrelease.building.isolation_fit import IsolationPrecision

G = 9.80665


def precision(model, mass, truth, sd, corr_pairs, units, noise_scale=1.0):
    """An IsolationPrecision at ``truth`` whose covariance is written here: standard deviations ``sd`` (in the
    order of ``truth``) and correlations ``{(a, b): rho}``; like the real one, the covariance for the noise levels
    over ``noise_scale`` kept as ``unit_covariance``."""
    names = tuple(truth)
    corr = np.eye(len(names))
    for (a, b), rho in corr_pairs.items():
        i, j = names.index(a), names.index(b)
        corr[i, j] = corr[j, i] = rho
    s = np.array([sd[n] for n in names])
    cov = corr * np.outer(s, s)
    return IsolationPrecision(model=model, mass=mass, names=names, parameters=dict(truth), covariance=cov,
                              std_errors={n: float(sd[n]) for n in names}, correlation=corr,
                              condition_number=float(np.linalg.cond(corr)), units=units, noise_scale=noise_scale,
                              unit_covariance=cov / noise_scale**2)


def check(row, truth, se, unit, relative_se):
    """A row against its hand-calculated truth, standard error, unit and relative standard error."""
    assert row["unit"] == unit and set(row) == {"truth", "se", "unit", "relative_se"}
    assert row["truth"] == pytest.approx(truth, rel=1e-12)
    assert row["se"] == pytest.approx(se, rel=1e-12)
    assert row["relative_se"] == pytest.approx(relative_se, rel=1e-12)


PENDULUM_UNITS = {"period": "s", "damping_ratio": "-", "friction_slow": "-", "friction_fast": "-", "rate": "s/m",
                  "d0": "m", "release_time": "s", "offset_x": "m"}
PENDULUM_TRUTH = {"period": 3.2, "damping_ratio": 0.02, "friction_slow": 0.02, "friction_fast": 0.06, "rate": 30.0,
                  "d0": 0.2, "release_time": 1.5, "offset_x": 0.0}
PENDULUM_SD = {"period": 4e-4, "damping_ratio": 1e-3, "friction_slow": 5e-4, "friction_fast": 2e-3, "rate": 4.0,
               "d0": 3e-5, "release_time": 2e-4, "offset_x": 1e-5}
# T strongly correlated with the friction and d0: they must not leak into se(R)
PENDULUM_CORR = {("period", "friction_slow"): 0.7, ("period", "d0"): -0.5, ("friction_slow", "friction_fast"): -0.6,
                 ("friction_fast", "rate"): 0.8}


def test_pendulum_rows_radius_by_the_delta_method_and_the_friction_law():
    """R = g (3.2 / 2 pi)^2 = 2.5437 m; se(R) = 2 R / T se(T) = 2 * 2.5437 / 3.2 * 4e-4 = 6.36e-4 m, whatever
    T's correlations; the friction law's rows their own standard deviations, keyed as the building's JSON."""
    pred = precision("pendulum", 1.2e6, PENDULUM_TRUTH, PENDULUM_SD, PENDULUM_CORR, PENDULUM_UNITS, noise_scale=3e-5)
    rows = pred.physical()
    assert list(rows) == ["period_s", "radius_m", "friction_slow", "friction_fast", "rate_s_m", "damping_ratio",
                          "d0_m", "release_time_s", "offset_x"]
    R = G * 3.2**2 / (4 * math.pi**2)
    assert R == pytest.approx(2.5437, abs=1e-4)
    check(rows["radius_m"], R, 2 * R / 3.2 * 4e-4, "m", 2 * 4e-4 / 3.2)
    assert rows["radius_m"]["se"] == pytest.approx(6.359e-4, rel=1e-3)
    check(rows["friction_slow"], 0.02, 5e-4, "-", 0.025)
    check(rows["friction_fast"], 0.06, 2e-3, "-", 2e-3 / 0.06)
    check(rows["rate_s_m"], 30.0, 4.0, "s/m", 4 / 30)
    check(rows["period_s"], 3.2, 4e-4, "s", 4e-4 / 3.2)
    assert rows["release_time_s"]["relative_se"] is None  # a time on the record's clock
    assert "friction_N" not in rows  # the pendulum's friction is its law's, not a force


BOUCWEN_UNITS = {"period": "s", "damping_coefficient": "N (s/m)^alpha", "damping_exponent": "-", "friction": "N",
                 "characteristic_strength": "N", "yield_displacement": "m", "shape": "-", "d0": "m",
                 "release_time": "s"}
BOUCWEN_TRUTH = {"period": 4.0, "damping_coefficient": 3e5, "damping_exponent": 0.5, "friction": 1e4,
                 "characteristic_strength": 6e5, "yield_displacement": 0.025, "shape": 1.0, "d0": 0.25,
                 "release_time": 2.0}
BOUCWEN_SD = {"period": 2e-3, "damping_coefficient": 6e3, "damping_exponent": 0.02, "friction": 2e3,
              "characteristic_strength": 9e3, "yield_displacement": 1e-3, "shape": 0.05, "d0": 1e-4,
              "release_time": 1e-3}
BOUCWEN_CORR = {("period", "characteristic_strength"): -0.8, ("period", "shape"): 0.4,
                ("damping_coefficient", "damping_exponent"): 0.9, ("characteristic_strength", "yield_displacement"): 0.5}


def test_boucwen_rows_kd_by_the_delta_method_and_the_power_damper():
    """m = 1200 t, T = 4 s: Kd = m (2 pi / T)^2 = 1.2e6 pi^2 / 4 = 2.961e6 N/m; se(Kd) = 2 Kd / T se(T) =
    2 * 2.961e6 / 4 * 2e-3 = 2.961e3 N/m; Qd, dy, n, C, alpha their own standard deviations."""
    pred = precision("boucwen", 1.2e6, BOUCWEN_TRUTH, BOUCWEN_SD, BOUCWEN_CORR, BOUCWEN_UNITS)
    rows = pred.physical()
    assert list(rows) == ["period_s", "Kd_N_m", "Qd_N", "dy_m", "shape", "damping_coefficient", "damping_exponent",
                          "friction_N", "d0_m", "release_time_s"]
    Kd = 1.2e6 * math.pi**2 / 4
    check(rows["Kd_N_m"], Kd, Kd / 1000, "N/m", 1e-3)
    for key, truth, se, unit in [("Qd_N", 6e5, 9e3, "N"), ("dy_m", 0.025, 1e-3, "m"), ("shape", 1.0, 0.05, "-"),
                                 ("damping_coefficient", 3e5, 6e3, "N (s/m)^alpha"),
                                 ("damping_exponent", 0.5, 0.02, "-"), ("friction_N", 1e4, 2e3, "N")]:
        check(rows[key], truth, se, unit, se / truth)
    assert "damping_ratio" not in rows


def test_bilinear_k2_honours_the_correlation_of_t1_and_the_stiffness_ratio():
    """The same delta method with two parameters: k1 = m (2 pi / T1)^2, k2 = r k1; var(k2) = (2 k2 / T1)^2
    var(T1) + k1^2 var(r) - 2 (2 k2 / T1) k1 cov(T1, r) (with rho = 0.6: 1.2338e4 N/m, against 1.3240e4 N/m
    were the correlation ignored)."""
    m, T1, r = 4e5, 0.6, 0.1
    truth = {"period": T1, "damping_ratio": 0.03, "friction": 2e4, "stiffness_ratio": r, "yield_force": 8e4,
             "d0": 0.15, "release_time": 1.0}
    sd = {"period": 1e-4, "damping_ratio": 1e-3, "friction": 100.0, "stiffness_ratio": 3e-4, "yield_force": 500.0,
          "d0": 1e-5, "release_time": 1e-4}
    units = {"period": "s", "damping_ratio": "-", "friction": "N", "stiffness_ratio": "-", "yield_force": "N",
             "d0": "m", "release_time": "s"}
    rows = precision("bilinear", m, truth, sd, {("period", "stiffness_ratio"): 0.6}, units).physical()
    assert list(rows) == ["k1_N_m", "k2_N_m", "Fy_N", "damping_ratio", "friction_N", "d0_m", "release_time_s"]
    k1 = m * (2 * math.pi / T1) ** 2
    k2, dT = r * k1, 2 * r * k1 / T1
    var = dT**2 * 1e-8 + k1**2 * 9e-8 - 2 * dT * k1 * 0.6 * 1e-4 * 3e-4
    assert rows["k2_N_m"]["se"] == pytest.approx(math.sqrt(var), rel=1e-12)
    assert rows["k2_N_m"]["se"] == pytest.approx(1.2338e4, rel=1e-4)
    assert rows["k1_N_m"]["se"] == pytest.approx(2 * k1 / T1 * 1e-4, rel=1e-12)
    assert rows["k2_N_m"]["truth"] == pytest.approx(k2, rel=1e-12)


def test_a_period_the_record_cannot_see_leaves_r_not_determined_and_none_in_the_json():
    """se(T) infinite (no effect on the record): R is not determined either (inf; the JSON's None), and the rows
    T does not enter keep their standard errors."""
    pred = precision("pendulum", 1.2e6, PENDULUM_TRUTH, PENDULUM_SD, {}, PENDULUM_UNITS)
    pred.std_errors["period"] = math.inf  # as predicted_isolation_errors marks a parameter the record cannot see
    rows = pred.physical()
    assert rows["radius_m"]["se"] == math.inf and rows["period_s"]["se"] == math.inf
    assert rows["friction_slow"]["se"] == pytest.approx(5e-4, rel=1e-12)
    json_rows = pred.summary()["parameters"]
    assert json_rows["radius_m"]["se"] is None and json_rows["radius_m"]["truth"] == pytest.approx(2.5437, abs=1e-4)


def test_a_fixed_period_leaves_out_the_period_and_its_radius():
    truth = {n: v for n, v in PENDULUM_TRUTH.items() if n != "period"}
    pred = precision("pendulum", 1.2e6, truth, PENDULUM_SD, {}, PENDULUM_UNITS)
    pred.parameters["period"] = 3.2  # held fixed at the truth
    rows = pred.physical()
    assert "period_s" not in rows and "radius_m" not in rows and rows["friction_slow"]["se"] == 5e-4
