"""The engineering quantities of measured loops (issue 24, item 2): quickrelease.building.effective on a public
record of a real friction damper (tests/data/friction_damper: the banded rotary friction device of Coble,
Huggins, Cao, Ricles and Downey, sinusoidal tests at 1024 Hz, CC BY-SA 4.0; see the README there).

Every reference number is computed here from the file by another route than loop_cycles': the turning points
by a Schmitt trigger on the displacement, the loop's area as a closed polygon (shoelace) and as the work of
the force on the measured velocity (another channel), keff from the forces read on the approaching branches
near the extremes, Qd and Kd from a rigid-plastic idealisation of the plateaus."""

import math
from pathlib import Path

import numpy as np
import pytest

from quickrelease.building.effective import cycle_turns, loop_cycles

DATA = Path(__file__).resolve().parents[1] / "data" / "friction_damper"
RECORDS = ("brfd_0.5Hz_1in_30lb", "brfd_1Hz_1.5in_30lb")


def _record(name):
    t, x, f, v = np.loadtxt(DATA / f"{name}.csv.gz", delimiter=",", skiprows=1).T
    return t, x, f, v


def _noise(x):
    """The displacement's noise, written here: 1.4826 MAD of the second differences / sqrt(6)."""
    d2 = np.diff(x, 2)
    return 1.4826 * float(np.median(np.abs(d2 - np.median(d2)))) / math.sqrt(6.0)


def _schmitt_extremes(x, band):
    """The sample of the extreme of x between successive crossings of +band and -band (a Schmitt trigger),
    each excursion beyond the band one turning point; the first and last excursions too."""
    state, out, start = 0, [], 0
    for i, xi in enumerate(x):
        new = 1 if xi > band else -1 if xi < -band else state
        if new != state:
            if state != 0:
                seg = x[start:i]
                out.append(start + int(np.argmax(seg) if state > 0 else np.argmin(seg)))
            state, start = new, i
    return np.array(out)


def _shoelace(x, f):
    """The area of the polygon through the samples, closed from the last back to the first."""
    return 0.5 * abs(float(np.sum(x * np.roll(f, -1) - np.roll(x, -1) * f)))


def _approach(x, f, i, within):
    """The mean force over the samples that lead up to the extreme at sample i, from the last one farther than
    ``within`` from it (the branch before the reversal)."""
    j = i
    while j > 0 and abs(x[j - 1] - x[i]) <= within:
        j -= 1
    return float(np.mean(f[j:i + 1]))


def _cycles(name, qd_window=0.25):
    t, x, f, v = _record(name)
    return (t, x, f, v), loop_cycles(t, x, f, noise=_noise(x), qd_window=qd_window)


@pytest.mark.parametrize("name, n_turns", [(RECORDS[0], 14), (RECORDS[1], 14)])
def test_the_turning_points_of_a_measured_loop_are_its_reversals(name, n_turns):
    """The quantised displacement changes the sign of its increments tens or hundreds of times; with its noise
    level the turning points are the reversals, within two samples of the extremes a Schmitt trigger at a
    quarter of the stroke finds (the zigzag also sees the small first swings inside that band)."""
    t, x, _, _ = _record(name)
    assert cycle_turns(x).size > 3 * n_turns
    turns = cycle_turns(x, _noise(x))
    reference = _schmitt_extremes(x, 0.25 * np.max(np.abs(x)))
    common = [int(np.argmin(np.abs(turns - r))) for r in reference]
    assert np.max(np.abs(turns[common] - reference)) <= 2
    assert turns.size == n_turns  # seven commanded cycles: fourteen reversals


@pytest.mark.parametrize("name", RECORDS)
def test_the_measured_loops_area_is_the_closed_polygons_and_the_work_on_the_measured_velocity(name):
    """EDC of every cycle (ramp-up, steady, ramp-down: unequal cycles that do not close) against the shoelace
    area of the cycle's samples closed by the chord; for the steady cycles, which close, also against the
    work of the force on the record's velocity channel, the integral of F v dt over the cycle."""
    (t, x, f, v), cycles = _cycles(name)
    assert len(cycles) == 6  # fourteen turning points: cycles 0-2, 2-4, ..., 10-12
    big = max(c.amplitude_m for c in cycles)
    steady = 0
    for c in cycles:
        i0, i1 = np.searchsorted(t, [c.start_s, c.end_s])
        xs, fs = x[i0:i1 + 1], f[i0:i1 + 1]
        assert c.edc_J == pytest.approx(_shoelace(xs, fs), rel=1e-2)
        if c.amplitude_m > 0.99 * big and abs(xs[0] - xs[-1]) < 0.02 * c.amplitude_m:
            steady += 1
            assert c.edc_J == pytest.approx(np.trapezoid(fs * v[i0:i1 + 1], t[i0:i1 + 1]), rel=1e-2)
    assert steady >= 2  # of the six cycles, two steady ones close within 2 % of D


@pytest.mark.parametrize("name", RECORDS)
def test_keff_beta_qd_kd_of_the_friction_damper_against_its_idealisation(name):
    """Per steady cycle: keff from the forces on the approaching branch near each extreme (the mean over the
    samples within 2 % of the stroke before it), beta_eff = EDC / (2 pi keff D^2) with the shoelace area and
    that keff; Qd as half the gap between the plateaus (the up and down branches' mean force over
    |x| < D/2), Kd as the mean of the two plateaus' slopes beyond D/2 (np.polyfit here); EDC / (4 Qd D)
    below 1 (a rigid-plastic friction loop's is 1; the backlash at each reversal takes some area off) and
    above 0.8."""
    (t, x, f, _), cycles = _cycles(name)
    big = max(c.amplitude_m for c in cycles)
    steady = [c for c in cycles if c.amplitude_m > 0.99 * big]
    assert len(steady) >= 3
    for c in steady:
        i0, i1 = np.searchsorted(t, [c.start_s, c.end_s])
        xs, fs = x[i0:i1 + 1], f[i0:i1 + 1]
        up = np.r_[False, np.diff(xs) > 0]
        down = np.r_[False, np.diff(xs) < 0]
        ip, im = int(np.argmax(xs)), int(np.argmin(xs))
        stroke = xs[ip] - xs[im]
        keff = (_approach(x, f, i0 + ip, 0.02 * stroke) - _approach(x, f, i0 + im, 0.02 * stroke)) / stroke
        D = 0.5 * stroke
        assert c.amplitude_m == pytest.approx(D, rel=1e-9)
        assert c.keff_N_m == pytest.approx(keff, rel=0.03)
        assert c.beta_eff == pytest.approx(_shoelace(xs, fs) / (2 * math.pi * keff * D * D), rel=0.03)
        mid = np.abs(xs) < 0.5 * D
        qd = 0.5 * (fs[up & mid].mean() - fs[down & mid].mean())
        assert c.qd_N == pytest.approx(qd, rel=0.05)
        assert 0.8 < c.edc_J / (4.0 * c.qd_N * D) < 1.0
        plus, minus = up & (xs > 0.5 * D), down & (xs < -0.5 * D)
        kd = 0.5 * (np.polyfit(xs[plus], fs[plus], 1)[0] + np.polyfit(xs[minus], fs[minus], 1)[0])
        assert abs(c.kd_N_m - kd) < 0.05 * c.keff_N_m
    # the spread between the steady cycles (EN 15129 judges it): keff and EDC within 10 % of their means
    keffs = np.array([c.keff_N_m for c in steady])
    edcs = np.array([c.edc_J for c in steady])
    assert np.ptp(keffs) / keffs.mean() < 0.1 and np.ptp(edcs) / edcs.mean() < 0.1


def test_qd_of_a_ringing_force_needs_the_window():
    """The force rings after each reversal of the 1 Hz record (the device's backlash): the force at the single
    crossing of x = 0 scatters Qd between the steady cycles four times more than the branches' lines (17 %
    against 4 %, peak to peak)."""
    _, narrow = _cycles(RECORDS[1], qd_window=0.0)
    _, wide = _cycles(RECORDS[1], qd_window=0.25)
    big = max(c.amplitude_m for c in wide)

    def spread(cs):
        q = np.array([c.qd_N for c in cs if c.amplitude_m > 0.99 * big])
        return np.ptp(q) / q.mean()

    assert spread(wide) < 0.06 and spread(narrow) > 3 * spread(wide)


def test_bad_noise_and_window_are_one_line():
    from quickrelease.errors import ParameterError

    with pytest.raises(ParameterError, match="noise"):
        cycle_turns([0.0, 1.0, 0.0], noise=-1.0)
    with pytest.raises(ParameterError, match="qd_window"):
        loop_cycles([0, 1, 2], [0, 1, 0], [0, 1, 0], qd_window=2.0)
    assert cycle_turns(np.zeros(5), noise=1.0).size == 0  # nothing beyond the noise: no turning point
