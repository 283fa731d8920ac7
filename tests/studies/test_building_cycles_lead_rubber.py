"""The cycles of a lead-rubber building's loop (issue 24, item 5: measured cycles came in pairs with equal D and
keff, one of each pair with a negative EDC) against the independent reference simulator
(tests/building/isolator_reference.py: solve_ivp with events, no package code).

The building is the lead-rubber example's (examples/lead_rubber_building.toml): 800 t on one Bouc-Wen element,
Kd = 1.6 MN/m, Qd = 400 kN, dy = 25 mm, n = 1, 2 % viscous damping on Kd, pushed 200 mm. Its loops shrink about a
residual displacement that creeps back towards 0: the peaks on the pushed side come down, those on the other side
move away (down) too. The reference's cycles are read here on its own noise-free motion at 10 kHz: each cycle two
half-cycles, from the release and then from every second reversal (the pushed side's peaks), its EDC the area of
its loop by the trapezoid rule over the samples closed by the chord back to the start, D and keff from the force
-m a at its extremes.
"""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("quickrelease.building.hysteretic")

from quickrelease.building.effective import G0  # noqa: E402
from quickrelease.building.isolation_fit import BuildingChannel, fit_isolation  # noqa: E402
from quickrelease.studies.building_cycles import measured_cycles  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "building"))
import isolator_reference as ref  # noqa: E402

M, KD, QD, DY, ZETA, D0 = 8e5, 1.6e6, 4e5, 0.025, 0.02, 0.2
RELEASE, SPAN = 2.05, 16.0  # s: the release on the LVDT's clock, the record's length


def system():
    return ref.boucwen(M, KD, QD, DY, 1.0, damping=2.0 * ZETA * math.sqrt(KD * M))


def record(seed):
    """Sampled as the example: LVDT 200 Hz (0.05 mm noise, +0.8 mm zero), accelerometer 100 Hz on its own clock
    3.7 ms late (0.002 g0 noise, +0.004 g0 zero)."""
    tx = np.arange(0.0, SPAN, 1 / 200)
    ta = np.arange(0.0037, SPAN, 1 / 100)
    rng = np.random.default_rng(seed)
    x = ref.simulate(system(), D0, tx - RELEASE).x
    a = ref.simulate(system(), D0, ta - RELEASE).a
    return [BuildingChannel("lvdt", "x", tx, x + 0.8e-3 + rng.normal(0, 0.05e-3, tx.size)),
            BuildingChannel("acc", "a", ta, a + 0.004 * G0 + rng.normal(0, 0.002 * G0, ta.size))]


def reference_cycles():
    """The reference's cycles on its noise-free motion (module docstring): start [s, record clock], D, keff,
    the loop's area [J], and the energy the hysteresis and the damper dissipated in the cycle [J]."""
    t = np.arange(0.0, SPAN - RELEASE, 1e-4)
    motion = ref.simulate(system(), D0, t)
    force = -M * motion.a
    times = motion.reversal_times[motion.reversal_times < t[-1]]
    turns = np.searchsorted(t, times - 0.5e-4)  # the nearest sample (v = 0 there: x is off by a dt^2 / 8)
    dissipated = motion.hysteretic + motion.viscous
    out = []
    for k in range(0, turns.size - 2, 2):
        i0, i1 = int(turns[k]), int(turns[k + 2])
        xs = np.r_[motion.x[i0:i1 + 1], motion.x[i0]]
        fs = np.r_[force[i0:i1 + 1], force[i0]]
        area = float(np.sum(0.5 * (fs[1:] + fs[:-1]) * np.diff(xs)))
        ends = turns[k:k + 3]
        ip, im = ends[np.argmax(motion.x[ends])], ends[np.argmin(motion.x[ends])]
        span = motion.x[ip] - motion.x[im]
        out.append({"start": RELEASE + times[k], "amplitude_m": 0.5 * span,
                    "keff_N_m": (force[ip] - force[im]) / span, "edc_J": area,
                    "dissipated": float(dissipated[i1] - dissipated[i0])})
    return out


@pytest.fixture(scope="module")
def cycles_true():
    return reference_cycles()


def test_the_reference_cycles_are_positive_and_shrink(cycles_true):
    """The reference itself: every cycle's loop area positive, the amplitudes strictly decreasing (the loops
    shrink); the area is not the energy the cycle dissipated (the chord does not measure the hysteresis's stored
    energy): 1.7 times it for the release's cycle."""
    assert len(cycles_true) >= 9
    assert all(c["edc_J"] > 0 for c in cycles_true)
    assert np.all(np.diff([c["amplitude_m"] for c in cycles_true]) < 0)
    assert cycles_true[0]["edc_J"] / cycles_true[0]["dissipated"] == pytest.approx(1.70, abs=0.01)


def test_the_measured_cycles_of_a_lead_rubber_record_are_the_references_loops(cycles_true):
    """The record's own cycles (measured_cycles: -m a of the accelerometer against the LVDT's x) one for one with
    the reference's, each starting within 30 ms of its; every EDC positive and within 3.5 standard errors of the
    reference's loop area, D and keff too; no two cycles with the same D. The fit is only the vehicle of the
    mass, the release (held at the truth: a correct fit's), the channels' zeros (the loop's area and keff do not
    depend on them) and noise levels: a linear one, cheap."""
    channels = record(seed=26)
    fit = fit_isolation(channels, M, "linear", release_time=RELEASE, fit_release_time=False, global_search=False)
    result = measured_cycles(fit, draws=40)
    assert result.force_source == "accelerometer" and len(result.cycles) >= len(cycles_true) - 1
    assert all(c.edc_J > 0 for c in result.cycles)
    amplitudes = [c.amplitude_m for c in result.cycles]
    assert len(set(amplitudes)) == len(amplitudes)
    for i, (c, se) in enumerate(zip(result.cycles, result.std_errors, strict=True)):
        tr = cycles_true[i]
        assert abs(c.start_s - tr["start"]) < 0.03, i
        for key in ("edc_J", "amplitude_m", "keff_N_m"):
            assert abs(getattr(c, key) - tr[key]) < 3.5 * se[key], (i, key, getattr(c, key), tr[key], se[key])


def test_the_smoothing_window_is_the_loops_own_not_the_models_period(cycles_true):
    """A correct Bouc-Wen fit's period is the post-yield stiffness's, 2 pi sqrt(m / Kd) = 4.44 s, while the loops
    run at 1.5 to 3 s: its eighth, 57 samples at 100 Hz, is most of a half-cycle, and the quadratics extrapolated
    to the turning points overshot them (D 28 standard errors high on average). The default window is an eighth of
    the record's own period (19 samples here), whatever the model's: with the period of the fit set to 4.44 s the
    cycles are read as before, D, keff and EDC within 3.5 standard errors of the reference's."""
    from dataclasses import replace

    channels = record(seed=27)
    fit = fit_isolation(channels, M, "linear", release_time=RELEASE, fit_release_time=False, global_search=False)
    post_yield = replace(fit, estimates={**fit.estimates, "period": 2.0 * math.pi * math.sqrt(M / KD)})
    result = measured_cycles(post_yield, draws=40)
    assert result.window <= 25 and len(result.cycles) >= len(cycles_true) - 1
    for i, (c, se) in enumerate(zip(result.cycles, result.std_errors, strict=True)):
        for key in ("edc_J", "amplitude_m", "keff_N_m"):
            assert abs(getattr(c, key) - cycles_true[i][key]) < 3.5 * se[key], (i, key)


def test_the_models_cycles_of_the_lead_rubber_isolator_are_the_references_loops(cycles_true):
    """The identified model's cycles (studies.building_effective.model_cycles, the curves' input) of the true
    Bouc-Wen isolator, one for one with the reference's: start, D and keff to 1e-4, EDC to 1e-3 (the reference's
    trapezoids at 10 kHz), every EDC positive and the amplitudes strictly decreasing (the curves interpolate over
    them: with the overlapping cycles they came in equal pairs and every curve was nan)."""
    from quickrelease.building.hysteretic import BoucWen
    from quickrelease.studies.building_effective import model_cycles

    iso = BoucWen(M, KD, QD, DY, 1.0, damping=2.0 * ZETA * math.sqrt(KD * M))
    cyc = model_cycles(iso, D0, SPAN - RELEASE)
    assert cyc["start_s"].size == len(cycles_true)
    assert np.all(cyc["edc_J"] > 0) and np.all(np.diff(cyc["amplitude_m"]) < 0)
    for i, tr in enumerate(cycles_true):
        assert cyc["start_s"][i] + RELEASE == pytest.approx(tr["start"], abs=1e-4)
        assert cyc["amplitude_m"][i] == pytest.approx(tr["amplitude_m"], rel=1e-4)
        assert cyc["edc_J"][i] == pytest.approx(tr["edc_J"], rel=1e-3)
        assert cyc["keff_N_m"][i] == pytest.approx(tr["keff_N_m"], rel=1e-4)  # the release's: F+ leaving d0
