"""Spikes in a building's record (issue 21, item 6): ``fit_isolation(exclude_spikes=True)`` / ``spikes =
"exclude"`` in ``[building.record]`` leaves out the samples whose residuals are spikes and fits the rest by
ordinary least squares, so the intervals keep their meaning.

The records come from the independent event-located solve_ivp of tests/building_reference.py; the spikes are
planted here at known samples, so the test knows which samples must go and which must stay.
"""

import json
import math

import numpy as np
import pytest
from building_reference import reference
from typer.testing import CliRunner

from quickrelease.building.isolation_fit import BuildingChannel, fit_isolation
from quickrelease.cli import app

M, T, ZETA, FS, D0 = 8.0e5, 2.5, 0.05, 0.008 * 8.0e5 * 9.81, 0.15
RELEASE, RATE = 2.0137, 200.0
NOISE_X, NOISE_A = 2e-4, 0.02
TRUTH = {"period": T, "damping_ratio": ZETA, "friction": FS, "d0": D0}


def _record(seed: int, spikes: int):
    """x and a of the reference with white noise, and ``spikes`` glitches a channel (10 to 250 noise levels,
    either sign) at random samples: (t, x, a, x's spiked samples, a's spiked samples)."""
    k = M * (2 * math.pi / T) ** 2
    t = np.arange(round(60.0 * RATE)) / RATE
    (x, _, a), _ = reference(M, k, k, math.inf, 2 * ZETA * math.sqrt(k * M), FS, D0, t - RELEASE, with_rates=True)
    rng = np.random.default_rng(seed)
    x = x + 0.002 + rng.normal(0, NOISE_X, t.size)
    a = a + 0.01 + rng.normal(0, NOISE_A, t.size)
    ix = np.sort(rng.choice(t.size, spikes, replace=False))
    ia = np.sort(rng.choice(t.size, spikes, replace=False))
    x[ix] += rng.choice([-1, 1], spikes) * rng.uniform(10, 250, spikes) * NOISE_X
    a[ia] += rng.choice([-1, 1], spikes) * rng.uniform(10, 150, spikes) * NOISE_A
    return t, x, a, t[ix], t[ia]


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1])
def test_planted_spikes_are_excluded_and_the_rest_fitted_honestly(seed):
    t, x, a, tx, ta = _record(seed, 30)
    channels = [BuildingChannel("x", "x", t, x), BuildingChannel("a", "a", t, a)]
    fit = fit_isolation(channels, M, exclude_spikes=True)
    # exactly the planted samples go (none of the 24000 clean ones)
    np.testing.assert_array_equal(fit.excluded["x"], tx)
    np.testing.assert_array_equal(fit.excluded["a"], ta)
    assert fit.samples == {"x": t.size - 30, "a": t.size - 30}
    assert any("60 sample(s) excluded as spikes (30 of x, 30 of a)" in w for w in fit.warnings)
    for name, truth in TRUTH.items():
        lo, hi = fit.ci95[name]
        assert lo <= truth <= hi, (name, fit.ci95[name], truth)
    assert fit.chi2_reduced == pytest.approx(1.0, abs=0.1)
    assert fit.summary()["excluded_samples"]["x"] == list(tx)


def test_a_clean_record_keeps_every_sample():
    t, x, a, _, _ = _record(2, 0)
    channels = [BuildingChannel("x", "x", t, x), BuildingChannel("a", "a", t, a)]
    fit = fit_isolation(channels, M, exclude_spikes=True, global_search=False)
    plain = fit_isolation(channels, M, global_search=False)
    assert fit.excluded == {} and "excluded_samples" not in fit.summary()
    assert fit.chi2 == plain.chi2 and fit.estimates == plain.estimates


@pytest.mark.slow
def test_the_case_file_asks_for_it(tmp_path):
    t, x, a, tx, ta = _record(3, 12)
    np.savetxt(tmp_path / "rec.csv", np.column_stack([t, x, a]), delimiter=",", header="t,x,a", comments="",
               fmt="%.12g")
    body = ('title = "spikes"\n[building]\nmass = "800 t"\n[building.record]\nfile = "rec.csv"\ntime = "t"\n'
            'spikes = "exclude"\n[building.record.channels]\nx = "x"\na = "a"\n')
    (tmp_path / "case.toml").write_text(body)
    out = CliRunner().invoke(app, ["building", str(tmp_path / "case.toml"), "--json"])
    assert out.exit_code == 0, out.output
    fit = json.loads(out.stdout)
    fit = fit.get("fit", fit)
    assert fit["excluded_samples"] == {"x": pytest.approx(list(tx)), "a": pytest.approx(list(ta))}
    (tmp_path / "bad.toml").write_text(body.replace('spikes = "exclude"', 'spikes = "drop"'))
    out = CliRunner().invoke(app, ["building", str(tmp_path / "bad.toml")])
    assert out.exit_code == 2
    assert "spikes = 'drop': expected 'keep' or 'exclude'" in out.output
