"""Fixtures shared by every test folder (tests/<subpackage>/ mirrors src/quickrelease/<subpackage>/).

The helpers beside this file (``building_reference``, ``quality``) are imported by tests in the subfolders:
this folder goes on ``sys.path`` first.
"""

import sys
from functools import cache
from pathlib import Path

import pytest

from quickrelease import preset

if str(Path(__file__).resolve().parent) not in sys.path:
    sys.path.insert(0, str(Path(__file__).resolve().parent))

#: matplotlib's settings when the session started: what every test, and every fixture of any scope, must leave.
_RC_BASELINE: dict = {}


def _rc_now() -> dict:
    """matplotlib's settings as stored (``dict.items``: no validation, no backend resolution, no sorting of the
    keys: 0.04 ms instead of 2 ms through ``rcParams.items()``; every setting goes through ``__setitem__`` into
    the stored dict, so a change shows here as it does there)."""
    import matplotlib

    return dict(dict.items(matplotlib.rcParams))


def _rc_changed(before: dict) -> list[str]:
    now = _rc_now()
    if now == before:
        return []
    return sorted(k for k in now.keys() | before.keys() if before.get(k, _MISSING) != now.get(k, _MISSING))


_MISSING = object()


@pytest.fixture(autouse=True, scope="session")
def _matplotlib_settings_unchanged_by_the_session():
    """Taken before any other session fixture: the baseline; checked again after the last teardown."""
    import matplotlib

    matplotlib.rcParams["backend"]  # resolved now (the first read of an automatic backend picks one), not by a test
    _RC_BASELINE.clear()
    _RC_BASELINE.update(_rc_now())
    yield
    changed = _rc_changed(_RC_BASELINE)
    assert not changed, f"rcParams changed by the end of the session (a session-scoped fixture?): {changed}"


@pytest.fixture(autouse=True, scope="module")
def _matplotlib_settings_unchanged_by_the_module(_matplotlib_settings_unchanged_by_the_session):
    """A module's fixtures (set up after this one, torn down before it) leave the settings as they were."""
    before = _rc_now()
    yield
    changed = _rc_changed(before)
    assert not changed, f"rcParams changed by this module (a module-scoped fixture?): {changed}"


@pytest.fixture(autouse=True)
def _matplotlib_settings_unchanged(_matplotlib_settings_unchanged_by_the_module):
    """Every test: the package's figure functions draw in their own style and leave the user's matplotlib
    settings (rcParams) exactly as they found them (issue 11), and so did every fixture set up before the test
    (module- and session-scoped ones included: those run before this check's own snapshot)."""
    changed = _rc_changed(_RC_BASELINE)
    assert not changed, f"rcParams changed before this test, by a fixture of a wider scope: {changed}"
    before = _rc_now()
    yield
    changed = _rc_changed(before)
    assert not changed, f"rcParams changed: {changed}"


@pytest.fixture(autouse=True)
def _no_progress_lines(monkeypatch):
    """In-process CLI runs print no ``progress:`` lines (a run on a loaded machine passes PROGRESS_AFTER, and
    the one-line error contracts would see them); the test of those lines sets its own PROGRESS_AFTER."""
    import math

    from quickrelease import cli

    monkeypatch.setattr(cli, "PROGRESS_AFTER", math.inf)


@pytest.fixture(scope="session")
def paper_device():
    return preset("paper")


#: The release identified from Table 7's printed inputs (E_S = 2900 J, t_F = 1.05 s), rounded to 0.01 N:
#: a realistic friction pair for solver tests (the solvers do not depend on how it was found).
PAPER_CASE = dict(stored_energy=2900.0, alpha0=0.2, F1=419.85, F2=804.57)


#: The uq case of the paper's test (scattered push force, angles and stop time): used by the uq, output-folder
#: and fault-injection tests.
UQ_CASE = """
title = "uq"
[test]
force = { value = "1598 kN", std = "16 kN" }
alpha0 = { value = "0.2 rad", std = "0.005 rad" }
[observations]
alpha_final = { value = "0.7378 rad", std = "0.01 rad" }
stop_time = { low = "1.04 s", high = "1.06 s" }
"""

#: Table 2 of the paper: bar and head masses [kg], bar length [m] (the paper device).
TABLE2_M1, TABLE2_M2, TABLE2_L1 = "576.78", "531.69", "2.477"


def mp_dissipated(a, alpha0, F1, F2, L1):
    """W_F(alpha) of Eq. 7 in mpmath, written out: 2 F1 L1 (sin a - sin a0) + 4 F2 L1 (cos a0 - cos a) [J]."""
    import mpmath

    return 2 * F1 * L1 * (mpmath.sin(a) - mpmath.sin(alpha0)) + 4 * F2 * L1 * (mpmath.cos(alpha0) - mpmath.cos(a))


def mp_alpha_final(E_S, alpha0, F1, F2, L1=TABLE2_L1):
    """The stop angle of Eq. 8 (at least 20 digits), W_F(alpha_F) = E_S, by mpmath's root finder (bisection-safe Anderson) [rad]."""
    import mpmath

    with mpmath.workdps(max(mpmath.mp.dps, 20)):
        E_S, alpha0, F1, F2, L1 = (mpmath.mpf(x) for x in (E_S, alpha0, F1, F2, L1))
        return +mpmath.findroot(lambda a: mp_dissipated(a, alpha0, F1, F2, L1) - E_S, (alpha0, mpmath.pi / 2),
                                solver="anderson")


def mp_stop_time(E_S, alpha0, alpha_final, F1, F2, c=(2, 3), m1=TABLE2_M1, m2=TABLE2_M2, L1=TABLE2_L1):
    """Eq. 10, t_F = int_alpha0^alpha_F sqrt(M(a) / (E_S - W_F(a))) da (M alpha_dot^2 the kinetic energy,
    M = m2 L1^2 (c m1/m2 + sin^2 a), Eq. 5), by tanh-sinh quadrature. E_S - W_F near the stop is written
    as W_F(alpha_F) - W_F(a) by sum-to-product so that it keeps its digits where tanh-sinh puts its nodes;
    the caller's E_S only fixes alpha_F."""
    import mpmath

    with mpmath.workdps(max(mpmath.mp.dps, 20)):
        a0, aF, F1, F2, m1, m2, L1 = (mpmath.mpf(x) for x in (alpha0, alpha_final, F1, F2, m1, m2, L1))
        k = mpmath.mpf(c[0]) / c[1] * m1 / m2

        def rest(a):
            m = (aF + a) / 2
            return 2 * mpmath.sin((aF - a) / 2) * (2 * F1 * L1 * mpmath.cos(m) + 4 * F2 * L1 * mpmath.sin(m))

        return +mpmath.quad(lambda a: mpmath.sqrt(m2 * L1**2 * (k + mpmath.sin(a) ** 2) / rest(a)), [a0, aF])


@cache
def mp_identify(E_S, alpha0, alpha_final, stop_time, c=(2, 3), dps=20):
    """(F1, F2) from the observations by mpmath: F2 from F1 by Eq. 8 at alpha_F, F1 the secant root of
    Eq. 10 = t_F (tanh-sinh quadrature), on the paper device. Floats, accurate to ~1e-15 relative."""
    import mpmath

    with mpmath.workdps(dps):
        E, a0, aF, tF, L1 = (mpmath.mpf(x) for x in (E_S, alpha0, alpha_final, stop_time, TABLE2_L1))
        s, co = mpmath.sin(aF) - mpmath.sin(a0), mpmath.cos(a0) - mpmath.cos(aF)

        def f2(F1):
            return (E - 2 * F1 * L1 * s) / (4 * L1 * co)

        F1_star = E / (2 * L1 * s)
        F1 = mpmath.findroot(lambda F1: mp_stop_time(E, a0, aF, F1, f2(F1), c) - tF,
                             (F1_star / 3, F1_star / 2), solver="secant")
        return float(F1), float(f2(F1))


#: Parameter draws of the bands (studies.building_effective.DRAWS: 400) and copies of the measured-cycle bootstrap
#: (studies.building_cycles.measured_cycles: 100) in the building analyses of the tests that use ``few_band_draws``.
FEW_BAND_DRAWS, FEW_CYCLE_DRAWS = 40, 20


@pytest.fixture(scope="module")
def few_band_draws():
    """analyse_building (and the ``building`` command in this process) with 40 band draws and 20 bootstrap copies
    of the measured cycles instead of 400 and 100, for a module whose tests do not look at the bands' width or the
    cycles' standard errors: the same code runs, in a tenth of the time. The defaults users get are unchanged."""
    from functools import partial

    from quickrelease.studies import building_analysis, building_cycles

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(building_analysis, "effective_curves",
                   partial(building_analysis.effective_curves, draws=FEW_BAND_DRAWS))
        mp.setattr(building_cycles, "measured_cycles", partial(building_cycles.measured_cycles, draws=FEW_CYCLE_DRAWS))
        yield
