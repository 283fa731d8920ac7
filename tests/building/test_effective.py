"""The engineering quantities of an isolator's loop (issue 24, item 2): keff, EDC, beta_eff, Qd, Kd, Teff, mu per
cycle (quickrelease.building.effective), against closed forms written here and the independent solve_ivp of
tests/building_reference.py."""

import math

import numpy as np
import pytest
from building_reference import reference

from quickrelease.building.effective import G0, loop_cycles
from quickrelease.errors import ParameterError

pytestmark = pytest.mark.usefixtures("few_band_draws")  # the bands' width is not looked at here


def _bilinear_force(x, k1, k2, fy):
    """A bilinear spring's force along a displacement history, written here: the elastic-plastic part
    (stiffness k1 - k2, yield force fy (1 - k2/k1)) with kinematic return, plus k2 x."""
    kp, fp = k1 - k2, fy * (1.0 - k2 / k1)
    out, z = np.empty_like(x), 0.0
    prev = x[0]
    for i, xi in enumerate(x):
        z = min(max(z + kp * (xi - prev), -fp), fp)
        prev = xi
        out[i] = z + k2 * xi
    return out


def test_a_bilinear_loop_gives_its_closed_forms():
    """Steady cycles of amplitude D on a bilinear spring: EDC = 4 Qd (D - Dy), keff = F(D) / D, Kd = k2,
    Qd = F_y - k2 D_y, beta_eff = EDC / (2 pi keff D^2)."""
    k1, k2, fy, D = 20e6, 2e6, 100e3, 0.2
    t = np.linspace(0.0, 6.0, 60001)
    x = D * np.sin(2 * math.pi * t / 2.0 - math.pi / 2)  # starts at -D: every cycle whole
    f = _bilinear_force(x, k1, k2, fy)
    cycles = loop_cycles(t, x, f, mass=8e5)
    # turning points at 1, 2, ..., 5 s (the virgin rise from -D before the first): two cycles, 1-3 s and 3-5 s
    assert [(c.start_s, c.end_s) for c in cycles] == [(1.0, 3.0), (3.0, 5.0)]
    dy = fy / k1
    qd = fy - k2 * dy
    keff = qd / D + k2
    edc = 4.0 * qd * (D - dy)
    for c in cycles:
        assert c.amplitude_m == pytest.approx(D, rel=1e-6)
        assert c.keff_N_m == pytest.approx(keff, rel=1e-4)
        assert c.edc_J == pytest.approx(edc, rel=1e-4)
        assert c.beta_eff == pytest.approx(edc / (2 * math.pi * keff * D * D), rel=1e-4)
        assert c.qd_N == pytest.approx(qd, rel=1e-4)
        assert c.kd_N_m == pytest.approx(k2, rel=1e-6)
        assert c.teff_s == pytest.approx(2 * math.pi * math.sqrt(8e5 / keff), rel=1e-4)
        assert c.mu == pytest.approx(qd / (8e5 * G0), rel=1e-4)


def _through_peaks(peaks, samples=2000):
    """A displacement history from 0 through the given peaks, each half-cycle a half cosine of ``samples``
    samples, 1 s long; and its times."""
    pts = [0.0, *peaks]
    s = 0.5 * (1.0 - np.cos(np.pi * np.arange(1, samples + 1) / samples))
    x = np.concatenate([[0.0], *[a + (b - a) * s for a, b in zip(pts[:-1], pts[1:], strict=True)]])
    return np.arange(x.size) / samples, x


def test_a_bilinear_decay_about_a_drifting_centre_gives_each_cycles_closed_form():
    """A bilinear spring taken through shrinking peaks on the pushed side and peaks drifting away on the other
    (as a lead-rubber building's loops shrink about a residual displacement that creeps back). Each cycle runs
    from a pushed-side peak P to the next, P' < P, through the trough V between them; its loop closed by the
    chord along the loading branch (the spring is yielded at both ends) is the steady loop between V and P, so
    EDC = 4 Qd (D - Dy) with D = (P - V) / 2, keff = Qd / D + k2, F+ = k2 P + Qd, F- = k2 V - Qd. The cycles
    follow each other (eight half-cycles and one more: four cycles); cycles from the troughs would add three more, whose
    loops end beyond their start (V' < V)."""
    k1, k2, fy = 20e6, 2e6, 100e3
    peaks = [0.20, -0.12, 0.17, -0.125, 0.14, -0.13, 0.11, -0.135, 0.08]
    t, x = _through_peaks([*peaks, -0.05])  # the last peak a reversal, the half-cycle after it no cycle
    f = _bilinear_force(x, k1, k2, fy)
    cycles = loop_cycles(t, x, f, mass=8e5)
    assert [(c.start_s, c.end_s) for c in cycles] == [(1.0, 3.0), (3.0, 5.0), (5.0, 7.0), (7.0, 9.0)]
    dy = fy / k1
    qd = fy - k2 * dy
    for j, c in enumerate(cycles):
        top, trough = peaks[2 * j], peaks[2 * j + 1]
        D = 0.5 * (top - trough)
        assert c.amplitude_m == pytest.approx(D, rel=1e-9)
        assert c.f_plus_N == pytest.approx(k2 * top + qd, rel=1e-9)
        assert c.f_minus_N == pytest.approx(k2 * trough - qd, rel=1e-9)
        assert c.keff_N_m == pytest.approx(qd / D + k2, rel=1e-9)
        assert c.edc_J == pytest.approx(4.0 * qd * (D - dy), rel=1e-5)
        assert c.qd_N == pytest.approx(qd, rel=1e-6)
        assert c.kd_N_m == pytest.approx(k2, rel=1e-6)


def test_a_viscous_ellipse_dissipates_pi_c_omega_d2():
    """F = k x + c x' along x = D sin(w t): EDC = pi c w D^2, keff = k (the force at the displacement's
    extremes, where x' = 0), beta_eff = c w / (2 k), Qd = c w D (the branches at x = 0)."""
    k, c, D, w = 5e6, 2e5, 0.15, 2 * math.pi / 2.5
    t = np.linspace(0.0, 10.0, 100001)
    x, v = D * np.sin(w * t), D * w * np.cos(w * t)
    cycles = loop_cycles(t, x, k * x + c * v)
    # eight turning points (1.25 s apart from 0.625 s): three cycles, each starting where the one before ended
    assert [cyc.start_s for cyc in cycles] == pytest.approx([0.625, 3.125, 5.625], abs=1e-4)
    assert [cyc.end_s for cyc in cycles] == pytest.approx([3.125, 5.625, 8.125], abs=1e-4)
    for cyc in cycles:
        assert cyc.edc_J == pytest.approx(math.pi * c * w * D**2, rel=1e-6)
        # F+ is the largest force within two samples of D+: c x' there adds 2 c w^2 D dt (5e-5 of k here)
        assert cyc.keff_N_m == pytest.approx(k, rel=1e-4)
        assert cyc.beta_eff == pytest.approx(c * w / (2 * k), rel=1e-4)
        assert cyc.qd_N == pytest.approx(c * w * D, rel=1e-6)
        assert math.isnan(cyc.teff_s) and math.isnan(cyc.mu)


def test_a_free_decay_on_sliders_gives_back_the_spring_and_the_friction():
    """The independent solve_ivp of a linear isolator with Coulomb sliders and light viscous damping: per cycle
    the loop's area is the energy the cycle dissipated (the spring's energy lost between its turning points),
    keff the spring plus the friction over the amplitude (F at D+ is k D+ + F_s, before the slider's force
    flips), Kd = k, Qd = F_s plus the damper's force at x = 0, mu = F_s / W."""
    M, T, zeta, Fs, d0 = 8e5, 2.5, 0.0, 0.01 * 8e5 * G0, 0.2
    k = M * (2 * math.pi / T) ** 2
    t = np.arange(0.0, 12.0, 1.0 / 2000.0)
    (x, _, a), t_stop = reference(M, k, k, math.inf, 2 * zeta * math.sqrt(k * M), Fs, d0, t, with_rates=True)
    moving = t < t_stop
    cycles = loop_cycles(t[moving], x[moving], -M * a[moving], mass=M)
    assert len(cycles) >= 2
    for cyc in cycles:
        start, end = np.interp([cyc.start_s, cyc.end_s], t, x)
        assert cyc.edc_J == pytest.approx(0.5 * k * (start**2 - end**2), rel=2e-3)
        d = 0.5 * (cyc.d_plus_m - cyc.d_minus_m)
        assert cyc.keff_N_m == pytest.approx(k + Fs / d, rel=2e-3)
        assert cyc.kd_N_m == pytest.approx(k, rel=1e-3)
        assert cyc.qd_N == pytest.approx(Fs, rel=2e-3)
        assert cyc.mu == pytest.approx(0.01, rel=2e-3)


def test_bad_loops_are_one_line():
    with pytest.raises(ParameterError, match="force"):
        loop_cycles([0, 1, 2], [0, 1, 0], [0, 1])
    with pytest.raises(ParameterError, match="mass"):
        loop_cycles([0, 1, 2], [0, 1, 0], [0, 1, 0], mass=-1.0)
    with pytest.raises(ParameterError, match="non-finite"):
        loop_cycles([0, 1, 2], [0, math.nan, 0], [0, 1, 0])
    assert loop_cycles([0, 1, 2, 3], [0, 1, 2, 3], [0, 1, 2, 3]) == ()  # no turning point: no cycle


@pytest.mark.slow
def test_the_building_analysis_reports_the_fitted_isolators_cycles():
    """analyse_building on an independent record of a linear isolator on sliders (no dampers): per cycle of
    the fitted model's loop after the first (which starts at the release, on the unloading branch), keff =
    k + F_s / D and Kd = k, Qd = F_s (the truth's, within the fit's interval scale); the JSON's `effective`
    and top-level `Qd_N`, `Kd_N_m`."""
    from quickrelease.building.isolation_fit import BuildingChannel
    from quickrelease.studies.building_analysis import analyse_building

    M, T, Fs, d0 = 8e5, 2.5, 0.006 * 8e5 * G0, 0.15
    k = M * (2 * math.pi / T) ** 2
    t = np.arange(0.0, 40.0, 1.0 / 200.0)
    (x, _, a), _ = reference(M, k, k, math.inf, 0.0, Fs, d0, t - 2.0, with_rates=True)
    rng = np.random.default_rng(11)
    channels = [BuildingChannel("x", "x", t, x + rng.normal(0, 1e-4, t.size)),
                BuildingChannel("a", "a", t, a + rng.normal(0, 0.01, t.size))]
    result = analyse_building(channels=channels, mass=M, global_search=False)
    summary = result.summary()
    assert summary["Qd_N"] == pytest.approx(Fs, rel=0.01) and summary["Kd_N_m"] == pytest.approx(k, rel=1e-3)
    cycles = summary["effective"]
    assert len(cycles) >= 3
    assert {"amplitude_m", "keff_N_m", "edc_J", "beta_eff", "teff_s"} <= set(cycles[0])
    for c in cycles[1:]:
        assert c["keff_N_m"] == pytest.approx(k + Fs / c["amplitude_m"], rel=0.01)
        assert c["kd_N_m"] == pytest.approx(k, rel=0.01)
        assert c["qd_N"] == pytest.approx(Fs, rel=0.02)
        assert c["teff_s"] == pytest.approx(2 * math.pi * math.sqrt(M / c["keff_N_m"]), rel=1e-12)
