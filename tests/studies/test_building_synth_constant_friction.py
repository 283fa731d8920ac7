"""`synth --building` of a friction pendulum of constant friction (``[building] friction_coefficient``) predicts the
precision of the fit `quickrelease building` makes of it (io.building_case.constant_friction_fixed: the rate held
at 0 and mu_fast at mu): one ``friction_coefficient`` row, not Constantinou's friction_slow, friction_fast and a
rate "not determined".

Two checks of the predicted standard errors: the Cramer-Rao bound written here, on the independent reference
simulator (tests/building/isolator_reference.py: solve_ivp with events, no package code), ``(J^T J)^-1`` of its
central differences in (T, zeta, mu, d0, release instant, offset) over the noise; and the identity of issue 24, a
constant-friction pendulum IS the linear model with k = W / R and F_s = mu W, so se(mu) W equals the linear
model's se(F_s) for the same record (to rounding; the package solves that pendulum by the linear closed form, so
this one checks the parametrization and the parameters held, the first the solution)."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from quickrelease.io.case import load_case
from quickrelease.studies.synth import predicted_building_errors, synthesize_building

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "building"))
import isolator_reference as ref  # noqa: E402

G = ref.GRAVITY
M, R, MU, ZETA, D0, RELEASE = 1.2e6, 2.5, 0.03, 0.02, 0.25, 1.0  # kg, m, -, -, m, s
T = 2 * math.pi * math.sqrt(R / G)
W = M * G
PENDULUM = (f'model = "pendulum"\nmass = "1200 t"\nradius = "2.5 m"\nfriction_coefficient = {MU}\n'
            f'damping_ratio = {ZETA}\n')
LINEAR = f'model = "linear"\nmass = "1200 t"\nperiod = "{T!r} s"\nfriction = "{MU * W!r} N"\ndamping_ratio = {ZETA}\n'


def _synth(tmp_path, building: str):
    path = tmp_path / "b.toml"
    path.write_text("[building]\n" + building + f'displacement = "{D0 * 1e3:g} mm"\n', encoding="utf-8")
    # 8 s at 50 Hz of an LVDT (0.05 mm): it sticks 3.17 s after the release
    return synthesize_building(load_case(path, require_test=False), ["x"], rate=50.0, release_time=RELEASE,
                               duration=8.0)


def _reference_bound(t: np.ndarray, noise: float) -> dict[str, float]:
    """The Cramer-Rao standard errors of (T, zeta, mu, d0, release instant, offset) for an LVDT at times t [s] with
    noise [m]: central differences (step 1e-5 of each value) of the reference simulator (rtol 1e-12)."""

    def x(period, zeta, mu, d0, release):
        radius = G * (period / (2 * math.pi)) ** 2
        k = W / radius
        system = ref.pendulum(M, radius, mu, damping=2 * zeta * math.sqrt(k * M))
        return ref.simulate(system, d0, t - release).x

    truth = [T, ZETA, MU, D0, RELEASE]
    columns = []
    for i, value in enumerate(truth):
        h = 1e-5 * value
        up, down = list(truth), list(truth)
        up[i] += h
        down[i] -= h
        columns.append((x(*up) - x(*down)) / (2 * h))
    J = np.column_stack([*columns, np.ones(t.size)]) / noise
    se = np.sqrt(np.diag(np.linalg.inv(J.T @ J)))
    return dict(zip(("period_s", "damping_ratio", "friction_coefficient", "d0_m", "release_time_s", "offset_x"),
                    se, strict=True))


def test_the_constant_friction_precision_is_the_one_coefficient_fit_s(tmp_path):
    syn = _synth(tmp_path, PENDULUM)
    pred = predicted_building_errors(syn)
    assert "rate" not in pred.names and "friction_fast" not in pred.names  # held, as the fit holds them
    rows = pred.physical()
    assert list(rows) == ["period_s", "radius_m", "friction_coefficient", "damping_ratio", "d0_m", "release_time_s",
                          "offset_x"]
    assert rows["friction_coefficient"]["truth"] == MU
    assert math.isfinite(rows["friction_coefficient"]["se"]) and not pred.warnings
    assert pred.summary()["parameters"]["friction_coefficient"] == pytest.approx(rows["friction_coefficient"])
    # the independent bound: the reference simulator's information on the same samples and noise
    bound = _reference_bound(syn.t, syn.noise["x"])
    for key, se in bound.items():
        assert rows[key]["se"] == pytest.approx(se, rel=1e-4), key
    # the linear model with k = W / R, F_s = mu W: the same record, the same information
    linear = predicted_building_errors(_synth(tmp_path, LINEAR)).physical()
    assert linear["friction_N"]["truth"] == pytest.approx(MU * W, rel=1e-15)
    assert rows["friction_coefficient"]["se"] * W == pytest.approx(linear["friction_N"]["se"], rel=1e-9)
    for key in ("period_s", "damping_ratio", "d0_m", "release_time_s", "offset_x"):
        assert rows[key]["se"] == pytest.approx(linear[key]["se"], rel=1e-9), key


def test_constantinou_s_law_keeps_its_three_rows(tmp_path):
    law = PENDULUM.replace(f"friction_coefficient = {MU}", "friction_slow = 0.03\nfriction_fast = 0.06\nrate = 30.0")
    rows = predicted_building_errors(_synth(tmp_path, law)).physical()
    assert {"friction_slow", "friction_fast", "rate_s_m"} <= set(rows) and "friction_coefficient" not in rows


def test_the_json_truth_is_the_one_coefficient_the_case_says(tmp_path):
    """`synth --building --json` of a constant-friction pendulum: its truth is what the case says and the fit
    reports (studies.building_analysis.physical_estimates): ``constant_friction`` True and one
    ``friction_coefficient`` mu, not Constantinou's friction_slow, friction_fast and a rate of 0. The case file it
    writes says so too (read back by the case grammar: a constant friction coefficient mu); Constantinou's law keeps
    its three."""
    import json

    from typer.testing import CliRunner

    from quickrelease.cli import app
    from quickrelease.io.building_case import constant_friction

    runner = CliRunner()
    args = ["--building", "--channels", "x", "--rate", "50 Hz", "--release-time", "1 s", "--duration", "4 s",
            "--overwrite", "--json"]
    law = PENDULUM.replace(f"friction_coefficient = {MU}", "friction_slow = 0.03\nfriction_fast = 0.06\nrate = 30.0")
    for name, building in (("constant", PENDULUM), ("law", law)):
        path = tmp_path / f"{name}.toml"
        path.write_text("[building]\n" + building + f'displacement = "{D0 * 1e3:g} mm"\n', encoding="utf-8")
        r = runner.invoke(app, ["synth", str(path), *args, "--out", str(tmp_path / f"{name}.csv"), "--case-out",
                                str(tmp_path / f"{name}_case.toml")])
        assert r.exit_code == 0, r.output
        truth = json.loads(r.stdout)["truth"]
        assert truth["model"] == "pendulum" and truth["radius_m"] == R and truth["friction_N"] == pytest.approx(
            {"constant": MU, "law": 0.03}[name] * W, rel=1e-15)
        spec = load_case(tmp_path / f"{name}_case.toml", require_test=False).building
        if name == "constant":
            assert truth["constant_friction"] is True and truth["friction_coefficient"] == MU
            assert not {"friction_slow", "friction_fast", "rate_s_m"} & set(truth)
            assert constant_friction(spec) and spec.friction_coefficient == MU
        else:
            assert "friction_coefficient" not in truth and "constant_friction" not in truth
            assert (truth["friction_slow"], truth["friction_fast"], truth["rate_s_m"]) == (0.03, 0.06, 30.0)
            assert not constant_friction(spec) and spec.friction_fast == 0.06
