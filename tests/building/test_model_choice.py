"""Model choice (issue 24): ``analyse_building(compare=True)`` ranks linear, bilinear, Bouc-Wen and pendulum by BIC
(:func:`quickrelease.building.isolation_fit.compare_models`); on records of each, made by the independent solve_ivp
of isolator_reference.py (never the package's own model), it must choose the true model, or an honestly
equivalent simpler one, in at least 90% of the seeds.

Records like those of test_hysteretic_coverage.py: 200 Hz, the base displacement (LVDT, noise 0.2 mm) and the
acceleration on its own clock (1.3 ms later; noise 0.02 m/s^2, zero 0.01 m/s^2), one quiet second before an
unknown release instant, to 1.5 s after the layer sticks for good (12 s at most). The parameters are drawn per
seed over the ranges of the isolation systems in use (``draw``); the noise too. Each model is fitted as
``analyse_building(compare=True)`` fits the compared ones (``profile=False``, ``COMPARE_TOLERANCE``, no design
start values, the global stage on), and the lowest BIC is the choice.

The honest equivalences. A simpler model (fewer parameters) that is a limit of the true one counts as right
when the record holds no evidence against it: its BIC is no higher than the truth's own,
``chi2(truth) + p_true ln n``, with chi2(truth) the misfit of the true parameters and the true sensor zeros on
the noisy record, computed here from the noise drawn (the noise levels the fit used). Then even a fit that
reached the truth would lose: the record cannot tell the models apart and the simpler one is the right
answer. The limits: the pendulum with mu_fast -> mu_slow (or a rate so large the friction is constant) is linear
+ Coulomb with k = W / R, F_s = mu W; Bouc-Wen with n -> inf is bilinear (Kd = k2, Qd = F_y (1 - k2 / k1),
dy = F_y / k1), with Qd -> 0 linear; bilinear with k2 -> k1 or F_y -> inf is linear. A more complex model
chosen is never right.

Slow (a seed's four fits take 1-10 min of CPU here, the Bouc-Wen fit of another model's record the slowest):
``MATRIX_SEEDS`` per true model, 1 with -m slow, 50 with QUICKRELEASE_SLOW=1. Not in the default run either: the
constant-friction pendulum (the linear + Coulomb equivalence, two fits, 25 s) and the one-half-cycle pendulum.
"""

import math
import os
from dataclasses import dataclass, replace
from functools import cache

import numpy as np
import pytest

pytest.importorskip("quickrelease.building.hysteretic")

import isolator_reference as ref  # noqa: E402

from quickrelease.building.isolation_fit import BuildingChannel, compare_models, fit_isolation  # noqa: E402
from quickrelease.studies.building_analysis import COMPARE_TOLERANCE  # noqa: E402

SLOW = bool(os.environ.get("QUICKRELEASE_SLOW"))
RATE, PRE, RELEASE = 200.0, 1.0, 1.0137
NOISE_X, NOISE_A, OFFSET_A, CLOCK_A = 2e-4, 0.02, 0.01, 0.0013
MAX_DURATION, AFTER_STOP = 12.0, 1.5
#: The models compared (``analyse_building``'s, less 2dof: no superstructure mass).
CANDIDATES = ("linear", "bilinear", "boucwen", "pendulum")
#: The parameters of each model's fit (viscous damper, the physical ones only: d0, the release and the two sensor
#: zeros are common to all).
PARAMETERS = {"linear": 3, "bilinear": 5, "boucwen": 6, "pendulum": 5}
#: Simpler models that are limits of each true model (see the module docstring).
LIMITS = {"linear": (), "bilinear": ("linear",), "boucwen": ("bilinear", "linear"), "pendulum": ("linear",)}


@dataclass(frozen=True)
class Case:
    """One drawn isolation system and its record's settings."""

    model: str
    seed: int
    system: ref.System
    mass: float
    d0: float
    duration: float
    truth: dict


def _uniform(rng, lo, hi):
    return float(rng.uniform(lo, hi))


@cache
def draw(model: str, seed: int) -> Case:
    """A realistic isolation system of ``model`` for ``seed`` (SI), the record's duration from its stop.

    - linear (rubber bearings, dampers and flat sliders): T 2-3.5 s, zeta 3-12%, F_s 0.2-1% of the weight,
      d0 0.10-0.25 m;
    - bilinear (lead-rubber as the engineers' bilinear idealisation): post-yield period 2-3 s, k1 / k2 6-12,
      Qd 2-5% of the weight, zeta 1-3%, sliders 0-0.5% of the weight, d0 0.15-0.30 m;
    - boucwen (lead-rubber, high-damping rubber): post-yield period 2-3 s, Qd 2-5% of the weight, dy 10-30 mm,
      shape n 1-2.5, zeta 1-3%, d0 0.15-0.30 m;
    - pendulum (curved surface sliders): R 2-4 m, mu_slow 0.4-0.8%, mu_fast 1.5-3 times mu_slow, rate 20-60 s/m,
      zeta 0-2% (referred to W / R), d0 0.15-0.25 m; redrawn until the record holds three reversals before it
      sticks (with one half-cycle the LVDT's zero, d0 and the friction level trade: test_pendulum_one_half_cycle).
    """
    rng = np.random.default_rng([24, CANDIDATES.index(model), seed])
    mass = _uniform(rng, 3e5, 2e6)
    W = mass * ref.GRAVITY
    for _ in range(50):
        if model == "linear":
            T, zeta, fs, d0 = _uniform(rng, 2.0, 3.5), _uniform(rng, 0.03, 0.12), _uniform(rng, 0.002, 0.01), \
                _uniform(rng, 0.10, 0.25)
            k = mass * (2 * math.pi / T) ** 2
            system = ref.linear(mass, k, damping=2 * zeta * math.sqrt(k * mass), friction=fs * W)
            truth = {"period": T, "damping_ratio": zeta, "friction": fs * W}
        elif model == "bilinear":
            T2, ratio, qd, zeta, fs, d0 = (_uniform(rng, 2.0, 3.0), _uniform(rng, 6.0, 12.0),
                                           _uniform(rng, 0.02, 0.05), _uniform(rng, 0.01, 0.03),
                                           _uniform(rng, 0.0, 0.005), _uniform(rng, 0.15, 0.30))
            k2 = mass * (2 * math.pi / T2) ** 2
            k1 = ratio * k2
            Fy = qd * W / (1 - 1 / ratio)
            system = ref.bilinear(mass, k1, k2, Fy, damping=2 * zeta * math.sqrt(k1 * mass), friction=fs * W)
            truth = {"period": 2 * math.pi * math.sqrt(mass / k1), "stiffness_ratio": 1 / ratio, "yield_force": Fy,
                     "damping_ratio": zeta, "friction": fs * W}
        elif model == "boucwen":
            T, qd, dy, n, zeta, d0 = (_uniform(rng, 2.0, 3.0), _uniform(rng, 0.02, 0.05), _uniform(rng, 0.01, 0.03),
                                      _uniform(rng, 1.0, 2.5), _uniform(rng, 0.01, 0.03), _uniform(rng, 0.15, 0.30))
            kd = mass * (2 * math.pi / T) ** 2
            system = ref.boucwen(mass, kd, qd * W, dy, shape=n, damping=2 * zeta * math.sqrt(kd * mass))
            truth = {"period": T, "characteristic_strength": qd * W, "yield_displacement": dy, "shape": n,
                     "damping_ratio": zeta}
        else:
            R, slow, fast, a, zeta, d0 = (_uniform(rng, 2.0, 4.0), _uniform(rng, 0.004, 0.008),
                                          _uniform(rng, 1.5, 3.0), _uniform(rng, 20.0, 60.0),
                                          _uniform(rng, 0.0, 0.02), _uniform(rng, 0.15, 0.25))
            fast *= slow
            k = W / R
            system = ref.pendulum(mass, R, slow, fast, a, damping=2 * zeta * math.sqrt(k * mass))
            truth = {"period": 2 * math.pi * math.sqrt(R / ref.GRAVITY), "friction_slow": slow, "friction_fast": fast,
                     "rate": a, "damping_ratio": zeta}
        motion = ref.simulate(system, d0, np.array([0.0]), t_end=MAX_DURATION)
        if model != "pendulum" or motion.reversal_times.size >= 4:
            break
    duration = min(MAX_DURATION, motion.stop_time + AFTER_STOP)
    return Case(model, seed, system, mass, d0, duration, {**truth, "d0": d0, "release_time": RELEASE})


@cache
def _rows(model: str, seed: int):
    """The noise-free record (tx, x, ta, a) of ``draw(model, seed)`` by the independent reference."""
    case = draw(model, seed)
    tx = np.arange(round((PRE + case.duration) * RATE)) / RATE
    ta = tx + CLOCK_A
    horizon = case.duration + 1.0
    x = ref.simulate(case.system, case.d0, tx - RELEASE, t_end=horizon).x
    a = ref.simulate(case.system, case.d0, ta - RELEASE, t_end=horizon).a
    return tx, x, ta, a


def _noise(case: Case, size: int, noise_seed: int):
    rng = np.random.default_rng([noise_seed, CANDIDATES.index(case.model), case.seed])
    return rng.normal(0.0, NOISE_X, size), rng.normal(0.0, NOISE_A, size)


def record(case: Case, noise_seed: int = 0) -> tuple[list[BuildingChannel], dict[str, np.ndarray]]:
    """The channels (LVDT x, accelerometer a with its zero) and the noise drawn in each."""
    tx, x, ta, a = _rows(case.model, case.seed)
    ex, ea = _noise(case, x.size, noise_seed)
    return ([BuildingChannel("lvdt", "x", tx, x + ex), BuildingChannel("acc", "a", ta, a + OFFSET_A + ea)],
            {"lvdt": ex, "acc": ea})


def fit_all(channels, mass: float, models=CANDIDATES) -> dict:
    """Each model fitted as ``analyse_building(compare=True)`` fits the compared ones."""
    return {m: fit_isolation(channels, mass, m, profile=False, tolerance=COMPARE_TOLERANCE) for m in models}


def truth_chi2(fit, noise: dict[str, np.ndarray]) -> float:
    """The misfit of the true parameters and sensor zeros on the record: sum of (noise / sigma)^2 over the
    channels, sigma the noise levels ``fit`` used."""
    return float(sum(np.sum((e / fit.noise[name]) ** 2) for name, e in noise.items()))


@dataclass(frozen=True)
class Verdict:
    """The comparison's outcome on one record."""

    chosen: str
    outcome: str  # "right", "equivalent", "wrong minimum", "criterion"
    table: tuple
    truth_bic: float
    chi2: dict
    truth_chi2: float


def judge(case: Case, fits: dict, noise: dict[str, np.ndarray]) -> Verdict:
    """The chosen model (lowest BIC) and the outcome: right; an honest equivalence (a simpler limit of the true
    model whose BIC is no higher than the truth's); a wrong minimum (the true model's fit ends more than 10 above
    the truth's chi-square: the fit, not the criterion, failed); else the criterion."""
    table = compare_models(fits.values())
    chosen = table[0]["model"]
    true_fit = fits[case.model]
    n = sum(c.t.size for c in true_fit.channels)
    chi2_truth = truth_chi2(true_fit, noise)
    truth_bic = chi2_truth + len(true_fit.names) * math.log(n)
    chi2 = {m: f.chi2 for m, f in fits.items()}
    if chosen == case.model:
        outcome = "right"
    elif chosen in LIMITS[case.model] and fits[chosen].bic <= truth_bic:
        outcome = "equivalent"
    elif true_fit.chi2 > chi2_truth + 10.0:
        outcome = "wrong minimum"
    else:
        outcome = "criterion"
    return Verdict(chosen, outcome, tuple(table), truth_bic, chi2, chi2_truth)


# -- the matrix: each true model, seeds drawn over its realistic range -----------------------------------------------

#: Seeds per true model: 50 with QUICKRELEASE_SLOW=1, else 1 (a seed's four fits take 1-10 min of CPU here: the
#: Bouc-Wen fit of a record of another model is the slow one).
MATRIX_SEEDS = 50 if SLOW else 1
KNOWN: dict = {}


@pytest.mark.slow
@pytest.mark.skipif(not SLOW, reason="opt-in (QUICKRELEASE_SLOW=1): one seed's four fits take 1-10 min of CPU "
                    "(the Bouc-Wen fit of a record of another model: 40-750 s), more than CI's budget")
@pytest.mark.parametrize("model", [pytest.param(m, marks=KNOWN.get(m, ())) for m in CANDIDATES])
def test_model_choice_matrix(model):
    """The lowest BIC is the true model, or an honestly equivalent simpler one, in at least 90% of the seeds."""
    verdicts = []
    for seed in range(MATRIX_SEEDS):
        case = draw(model, seed)
        channels, noise = record(case)
        verdicts.append((seed, judge(case, fit_all(channels, case.mass), noise)))
    good = [s for s, v in verdicts if v.outcome in ("right", "equivalent")]
    bad = [(s, v.chosen, v.outcome, {r["model"]: round(r["delta_bic"], 1) for r in v.table}) for s, v in verdicts
           if v.outcome not in ("right", "equivalent")]
    assert len(good) >= math.ceil(0.9 * MATRIX_SEEDS), bad


def test_linear_fit_reaches_the_minimum_along_the_valley():
    """The linear record of seed 37 (the independent reference's): every start ended 0.9 ms after the true release,
    its chi-square 63 above the truth's, so the Bouc-Wen fit won the comparison; the lower piece lay 3.6 standard
    errors of the release time along its regression line (the fit's polish probes that line now). The fit must end
    at or below the truth's chi-square (plus the parameters' share, ~ p) and hold the truth within 3 standard
    errors."""
    case = draw("linear", 37)
    channels, noise = record(case)
    fit = fit_isolation(channels, case.mass, "linear", profile=False, tolerance=COMPARE_TOLERANCE)
    assert fit.chi2 <= truth_chi2(fit, noise) + 3.0, (fit.chi2, truth_chi2(fit, noise))
    z = {n: (fit.estimates[n] - v) / fit.std_errors[n] for n, v in case.truth.items()}
    assert all(abs(v) < 3.0 for v in z.values()), z


# -- the equivalence computed: the pendulum with constant friction is linear + Coulomb ------------------------------

@pytest.mark.slow
def test_constant_friction_pendulum_is_linear_coulomb_and_linear_is_chosen():
    """A pendulum whose friction does not depend on the speed (mu_fast = mu_slow): the reference's records of it and
    of linear + Coulomb with k = W / R, F_s = mu W agree to 1e-9 (the equivalence computed, not asserted); on its
    noisy record the comparison of linear and pendulum chooses linear (two parameters fewer), and that choice is
    honest: its BIC is no higher than the truth's."""
    mass, R, mu, zeta, d0 = 8.0e5, 3.0, 0.006, 0.01, 0.2
    W = mass * ref.GRAVITY
    k = W / R
    c = 2 * zeta * math.sqrt(k * mass)
    case = Case("pendulum", -1, ref.pendulum(mass, R, mu, mu, 0.0, damping=c), mass, d0, 6.0,
                {"period": 2 * math.pi * math.sqrt(R / ref.GRAVITY), "friction_slow": mu, "friction_fast": mu,
                 "d0": d0, "release_time": RELEASE})
    tx = np.arange(round((PRE + case.duration) * RATE)) / RATE
    x = ref.simulate(case.system, d0, tx - RELEASE, t_end=case.duration + 1).x
    same = ref.simulate(ref.linear(mass, k, damping=c, friction=mu * W), d0, tx - RELEASE, t_end=case.duration + 1).x
    assert np.max(np.abs(x - same)) < 1e-9 * d0
    ta = tx + CLOCK_A
    a = ref.simulate(case.system, d0, ta - RELEASE, t_end=case.duration + 1).a
    rng = np.random.default_rng(5)
    ex, ea = rng.normal(0.0, NOISE_X, x.size), rng.normal(0.0, NOISE_A, a.size)
    channels = [BuildingChannel("lvdt", "x", tx, x + ex), BuildingChannel("acc", "a", ta, a + OFFSET_A + ea)]
    fits = fit_all(channels, mass, ("linear", "pendulum"))
    verdict = judge(case, fits, {"lvdt": ex, "acc": ea})
    assert verdict.chosen == "linear" and verdict.outcome == "equivalent", verdict


# -- the pendulum that sticks after one half-cycle: an exact symmetry -------------------------------------------------

HALF = dict(mass=1.0e6, R=2.5, slow=0.02, fast=0.04, rate=30.0, d0=0.15, duration=4.0)


def _half_system(shift: float = 0.0) -> tuple[ref.System, float]:
    """The one-half-cycle pendulum, and the member of its family shifted by ``shift`` [m]: both friction
    coefficients less shift / R, d0 less shift (the LVDT's zero then reads shift more)."""
    h = HALF
    return (ref.pendulum(h["mass"], h["R"], h["slow"] - shift / h["R"], h["fast"] - shift / h["R"], h["rate"]),
            h["d0"] - shift)


def _half_family() -> tuple[float, float]:
    """The shifts [m] that keep the record unchanged, computed from the motion: while the layer moves one way,
    ``m x'' = -W x / R + mu(|v|) W`` is unchanged by x -> x - s, mu -> mu - s / R; the release needs
    ``|d0 - s| > R mu_slow - s`` (the same inequality), the stick at the turning point x_1 needs
    ``|x_1 - s| <= R mu_slow - s``, and the friction mu_slow - s / R >= 0. Returns (lowest, highest) shift
    within the fit's bound mu_fast - s / R <= 1."""
    system, d0 = _half_system()
    motion = ref.simulate(system, d0, np.array([0.0]), t_end=HALF["duration"])
    x1 = float(motion.turning_points[1])
    R, slow, fast = HALF["R"], HALF["slow"], HALF["fast"]
    assert motion.reversal_times.size == 2 and 0 < x1 <= R * slow  # one half-cycle, it stops short of 0
    # |x1 - s| <= R slow - s: for s <= x1 always; for s > x1, s <= (x1 + R slow) / 2; and s <= R slow
    highest = min((x1 + R * slow) / 2, R * slow)
    lowest = R * (fast - 1.0)
    return lowest, highest


@cache
def _half_fit(noise_seed: int = 0):
    system, d0 = _half_system()
    tx = np.arange(round((PRE + HALF["duration"]) * RATE)) / RATE
    ta = tx + CLOCK_A
    x = ref.simulate(system, d0, tx - RELEASE, t_end=HALF["duration"] + 1).x
    a = ref.simulate(system, d0, ta - RELEASE, t_end=HALF["duration"] + 1).a
    rng = np.random.default_rng(noise_seed)
    channels = [BuildingChannel("lvdt", "x", tx, x + rng.normal(0.0, NOISE_X, x.size)),
                BuildingChannel("acc", "a", ta, a + OFFSET_A + rng.normal(0.0, NOISE_A, a.size))]
    return fit_isolation(channels, HALF["mass"], "pendulum")


def test_one_half_cycle_pendulum_symmetry_is_exact():
    """The reference's records of members of the family (shifts inside ``_half_family``) differ from the
    original by the shift in x alone (the LVDT's zero) and not at all in the acceleration: to 1e-9."""
    lowest, highest = _half_family()
    t = np.linspace(-0.5, HALF["duration"], 900)
    base = ref.simulate(*_half_system(), t, t_end=HALF["duration"] + 1)
    for shift in (0.5 * highest, -0.02, 0.999 * highest):
        assert lowest < shift < highest
        other = ref.simulate(*_half_system(shift), t, t_end=HALF["duration"] + 1)
        assert np.max(np.abs(other.x + shift - base.x)) < 1e-9 * HALF["d0"]
        assert np.max(np.abs(other.a - base.a)) < 1e-9 * HALF["d0"] * ref.GRAVITY / HALF["R"]
    # and one beyond the family's edge: it no longer sticks at the first turning point
    beyond = ref.simulate(*_half_system(1.2 * highest), t, t_end=HALF["duration"] + 1)
    assert beyond.stop_time > base.stop_time and np.max(np.abs(beyond.x + 1.2 * highest - base.x)) > 10 * NOISE_X


def _shifted(fit, shift: float) -> dict[str, float]:
    """The fit's estimates moved along the family by ``shift`` [m] (R from the fitted period)."""
    est = fit.estimates
    R = ref.GRAVITY * (est["period"] / (2 * math.pi)) ** 2
    return {**est, "d0": est["d0"] - shift, "offset_lvdt": est["offset_lvdt"] + shift,
            "friction_slow": est["friction_slow"] - shift / R, "friction_fast": est["friction_fast"] - shift / R}


def _chi2_at(fit, estimates: dict[str, float]) -> float:
    """The fit's weighted misfit with its estimates replaced (the package's model, its noise levels)."""
    moved = replace(fit, estimates=estimates)
    return float(sum(np.sum(((c.values - moved.model_values(c)) / fit.noise[c.name]) ** 2) for c in fit.channels))


@pytest.mark.slow
@pytest.mark.skipif(not SLOW, reason="opt-in (QUICKRELEASE_SLOW=1): the one-half-cycle pendulum's fit, ~200 s of "
                    "CPU on one worker, beyond CI's 900 s budget")
def test_one_half_cycle_pendulum_fit_warns():
    """What the fit does today on such a record: it reaches the noise level and warns that the fit is
    ill-conditioned (measured: condition number of the correlations 3.1e11); the fitted point moved along the
    family to the true friction_slow has the same misfit (so the record cannot exclude it)."""
    fit = _half_fit()
    assert fit.chi2_reduced < 1.3
    assert any("ill-conditioned" in w for w in fit.warnings), fit.warnings
    shift = (fit.estimates["friction_slow"] - HALF["slow"]) * ref.GRAVITY * (fit.estimates["period"] / (2 * math.pi)) ** 2
    assert _chi2_at(fit, _shifted(fit, shift)) == pytest.approx(_chi2_at(fit, fit.estimates), rel=1e-8)


HALF_NOT_IDENTIFIED = ("friction_slow", "friction_fast", "d0", "offset_lvdt")


@pytest.mark.slow
@pytest.mark.skipif(not SLOW, reason="opt-in (QUICKRELEASE_SLOW=1): the one-half-cycle pendulum's fit, ~200 s of "
                    "CPU on one worker, beyond CI's 900 s budget")
@pytest.mark.xfail(strict=False, reason=(
    "issue 24, lead's isolation_fit.py: on a one-half-cycle pendulum record the shift family (d0, the LVDT's zero, "
    "friction_slow, friction_fast) is exact; since the profile's refits start along the correlations friction_slow's "
    "interval (0.0033, 0.80) holds the truth 0.02 (before: 0.0044-0.0083), but d0 and offset_lvdt keep Jacobian "
    "intervals +-2.2 m sized by the finite differences (the null eigenvalue 3e-12 is above _lsq.RCOND 1e-15) that "
    "do not reach the family's edges (profiling them cost 10 min of CPU): none is 'not identified'"))
def test_one_half_cycle_pendulum_reports_not_identified():
    """Each parameter of the family is reported not identified (no interval), or its interval holds the whole
    family (every shift in ``_half_family`` within the fit's bounds): never an interval that leaves out values
    that give the same record."""
    fit = _half_fit()
    lowest, highest = _half_family()
    R = HALF["R"]
    family = {"friction_slow": (HALF["slow"] - highest / R, min(1.0, HALF["slow"] - lowest / R)),
              "friction_fast": (HALF["fast"] - highest / R, 1.0),
              "d0": (HALF["d0"] - highest, HALF["d0"] - lowest), "offset_lvdt": (lowest, highest)}
    honest = {}
    for name in HALF_NOT_IDENTIFIED:
        lo, hi = fit.ci95[name]
        want_lo, want_hi = family[name]
        slack = 1e-3 * (want_hi - want_lo)  # the fitted point's family: R from the fitted period, not the true one
        honest[name] = (fit.interval_method[name] == "not identified"
                        or (lo <= want_lo + slack and hi >= want_hi - slack))
    assert all(honest.values()), {n: (fit.ci95[n], fit.interval_method[n], family[n]) for n in honest}


# -- a Bouc-Wen fit at one of its limits says so ----------------------------------------------------------------------

def _boucwen_start(case: Case) -> dict[str, float]:
    """Bouc-Wen start values from a drawn case's truth: its own, or a bilinear truth's limit (Kd = k2,
    Qd = F_y (1 - k2 / k1), dy = F_y / k1, n 20), the sensor zeros the record's."""
    t = case.truth
    if case.model == "bilinear":
        k1 = case.mass * (2 * math.pi / t["period"]) ** 2
        k2 = t["stiffness_ratio"] * k1
        zeta = t["damping_ratio"] * math.sqrt(k1 / k2)  # the same c referred to Kd
        t = {"period": 2 * math.pi * math.sqrt(case.mass / k2), "damping_ratio": zeta, "friction": t["friction"],
             "characteristic_strength": t["yield_force"] * (1 - k2 / k1), "yield_displacement": t["yield_force"] / k1,
             "shape": 20.0, "d0": t["d0"], "release_time": t["release_time"]}
    else:
        t = {"friction": 0.0, **t}
    return {**t, "offset_lvdt": 0.0, "offset_acc": OFFSET_A}


@pytest.mark.slow
@pytest.mark.parametrize("model, seed", [("bilinear", 0), ("boucwen", 0), pytest.param("linear", 1, marks=pytest.mark.skipif(
    not SLOW, reason="opt-in (QUICKRELEASE_SLOW=1): this record's Bouc-Wen fit takes ~50 s of CPU; linear-2 (2 s) checks "
    "the same warning (Qd's interval reaching 0)")), ("linear", 2)])
def test_boucwen_fit_says_when_it_is_at_a_limit(model, seed):
    """The Bouc-Wen fit of a bilinear record (the reference's) runs its shape to the bound and warns that it is the
    bilinear model's limit; of a linear record its Qd's interval reaches 0 (an element elastic over the whole
    swing, dy 0.2-0.8 m, or no Qd at all) and it warns that it is the linear model's limit; of a Bouc-Wen record
    (n 1-2.5) neither. Started near the truth (a linear record: Qd 0.1 % of the weight, dy 10 mm, n 2) without the
    global stage: what is tested is the verdict at the minimum, not the search. (Linear seed 0 ends at Qd 405 N +-
    46%, n 25: only the bilinear limit's warning.)"""
    case = draw(model, seed)
    channels, _ = record(case)
    start = _boucwen_start(case)
    if model == "linear":
        start.update(characteristic_strength=1e-3 * case.mass * ref.GRAVITY, yield_displacement=0.01, shape=2.0)
    fit = fit_isolation(channels, case.mass, "boucwen", start=start, global_search=False, profile=False,
                        tolerance=COMPARE_TOLERANCE)
    said = {limit for limit in ("bilinear", "linear") if any(f"{limit} model's limit" in w for w in fit.warnings)}
    assert ({"bilinear"} <= said if model == "bilinear" else "linear" in said if model == "linear" else not said), \
        (fit.parameters, fit.warnings)
    if model == "bilinear":
        assert fit.parameters["shape"] > 20.0
