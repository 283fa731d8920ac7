"""Issue 22, item 7: a record stamped with Unix time (t + 1.7e9 s) fits to the same friction as the same record
from 0 (the fit works in record-relative time), and a record that starts after the release is refused in one
line instead of giving F1 1004 N, F2 410 N without a word.

The record is made here, independently of the package: alpha(t) of the paper's device integrated with
solve_ivp from the energy balance (written below), sampled at 200 Hz with seeded noise, at rest before the
release. The fit must find the friction it was made with (within 4 standard errors) with and without the
epoch offset, and the two fits must agree to far below a standard error.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from quickrelease.device.parameters import preset
from quickrelease.io.case import load_case
from quickrelease.io.records import RecordError
from quickrelease.studies.fit import fit_record

TRUTH = {"F1": 420.0, "F2": 805.0}
E_S, ALPHA0, C = 2900.0, 0.2, 2.0 / 3.0
RELEASE, RATE, NOISE = 0.5, 200.0, 1e-3
EPOCH = 1.7e9


def _alpha_history():
    """alpha(t) after the release: T = m2 L1^2 (k + sin^2 a) a'^2 (Eq. 6's kinetic energy, k = c m1 / m2) falls by
    the friction work, dT/dt = -(2 F1 L1 cos a + 4 F2 L1 sin a) a', which gives
    a'' = -(F1 cos a + 2 F2 sin a) / (m2 L1 (k + sin^2 a)) - sin a cos a a'^2 / (k + sin^2 a); until a' = 0."""
    d = preset("paper")
    k = C * d.m1 / d.m2
    rate0 = math.sqrt(E_S / (d.m2 * d.L1**2 * (k + math.sin(ALPHA0) ** 2)))

    def rhs(_t, y):
        s, c = math.sin(y[0]), math.cos(y[0])
        den = k + s * s
        return [y[1], -(TRUTH["F1"] * c + 2.0 * TRUTH["F2"] * s) / (d.m2 * d.L1 * den) - s * c * y[1] ** 2 / den]

    def stop(_t, y):
        return y[1]

    stop.terminal, stop.direction = True, -1
    sol = solve_ivp(rhs, (0.0, 10.0), [ALPHA0, rate0], method="DOP853", rtol=1e-12, atol=1e-14, events=stop,
                    dense_output=True)
    return sol, float(sol.t_events[0][0])


@pytest.fixture(scope="module")
def history():
    return _alpha_history()


def _write(tmp_path, history, shift=0.0, start=0.0, name="rec", release_time=None):
    sol, t_F = history
    t = np.arange(0.0, RELEASE + t_F + 0.5, 1.0 / RATE)
    s = np.clip(t - RELEASE, 0.0, t_F)
    alpha = np.where(t <= RELEASE, ALPHA0, sol.sol(s)[0])
    alpha = alpha + np.random.default_rng(7).normal(0.0, NOISE, t.size)
    keep = t >= start
    lines = ["t_s,alpha_rad"] + [f"{a:.17g},{b:.17g}" for a, b in zip(t[keep] + shift, alpha[keep], strict=True)]
    (tmp_path / f"{name}.csv").write_text("\n".join(lines) + "\n")
    (tmp_path / f"{name}.toml").write_text(f"""[device]
preset = "paper"
[test]
energy = "{E_S} J"
alpha0 = "{ALPHA0} rad"
mass_model = "distributed"
[record]
file = "{name}.csv"
time = "t_s"
{"" if release_time is None else f'release_time = "{release_time!r} s"'}
[record.channels]
alpha = {{ column = "alpha_rad", unit = "rad", noise = "{NOISE} rad" }}
""")
    return load_case(tmp_path / f"{name}.toml")


def test_an_epoch_clock_gives_the_same_friction(tmp_path, history):
    plain = fit_record(_write(tmp_path, history, name="plain"))
    epoch = fit_record(_write(tmp_path, history, shift=EPOCH, name="epoch"))
    for f in ("F1", "F2"):  # the truth the record was made with
        assert abs(plain.estimates[f] - TRUTH[f]) < 4 * plain.std_errors[f], (f, plain.estimates[f])
        assert abs(epoch.estimates[f] - TRUTH[f]) < 4 * epoch.std_errors[f], (f, epoch.estimates[f])
        # the same record on another clock: the same answer (the clock's rounding, 2.4e-7 s, moves it little)
        assert abs(epoch.estimates[f] - plain.estimates[f]) < 0.02 * plain.std_errors[f], f
        assert epoch.std_errors[f] == pytest.approx(plain.std_errors[f], rel=1e-3)
    assert epoch.converged and not epoch.warnings
    # the release instant is reported on the record's own clock
    assert epoch.release_time - EPOCH == pytest.approx(plain.release_time, abs=1e-6)
    assert plain.release_time == pytest.approx(RELEASE, abs=3.0 / RATE)
    lo, hi = epoch.ci95["release_time"]
    assert lo < epoch.release_time < hi and lo > EPOCH


def test_a_record_that_starts_after_the_release_is_refused(tmp_path, history):
    """Given the release instant (0.5 s) of a record that starts at 0.75 s: refused where the record loads
    (io.records.check_release_time), naming the key, its value, the record and its time span."""
    case = _write(tmp_path, history, start=RELEASE + 0.25, name="late", release_time=RELEASE)
    with pytest.raises(RecordError, match=r"release_time = 0.5 s: expected a release instant within the time span "
                                          r"of the record late.csv, \[0.75, "):
        fit_record(case)
    case = _write(tmp_path, history, start=RELEASE + 0.25, name="late", release_time=RELEASE + EPOCH, shift=EPOCH)
    with pytest.raises(RecordError, match=r"release_time = 1\.7\d*e\+09 s: .* late.csv, \[1\.7\d*e\+09, "):
        fit_record(case)


def test_the_example_record_cut_after_the_release_is_refused(tmp_path):
    """The issue's case: the example record of u, v and the head acceleration from 0.75 s on (the release is at
    0.62 s) gave F1 1504 N, F2 0 N, converged; now one line."""
    from pathlib import Path

    examples = Path(__file__).parents[2] / "examples"
    lines = (examples / "records" / "paper_500Hz.csv").read_text().splitlines()
    keep = [lines[0]] + [row for row in lines[1:] if float(row.split(",", 1)[0]) > 0.75]
    (tmp_path / "records").mkdir()
    (tmp_path / "records" / "paper_500Hz.csv").write_text("\n".join(keep) + "\n")
    (tmp_path / "fit.toml").write_text((examples / "fit.toml").read_text())
    with pytest.raises(RecordError, match=r"paper_500Hz.csv: the record starts at 0.752006 s in motion: channel u moves"):
        fit_record(load_case(tmp_path / "fit.toml"))


def test_a_record_from_just_before_the_release_is_fitted(tmp_path, history):
    """The edge: 0.1 s (20 samples) of rest before the release is enough."""
    fit = fit_record(_write(tmp_path, history, start=RELEASE - 0.1, name="short"))
    assert abs(fit.estimates["F1"] - TRUTH["F1"]) < 4 * fit.std_errors["F1"]
