"""The Python API at the boundary (issue 11): pint Quantities and strings with units are converted, a
wrong dimension or an array where one number is expected is the package's own error, naming the parameter."""

import math

import numpy as np
import pint
import pytest

import quickrelease as qr
from quickrelease.errors import ParameterError, UnitError

ureg = pint.UnitRegistry()  # the user's own registry, not the package's


def test_simulate_takes_quantities_and_strings():
    ref = qr.simulate(2900.0, 0.2, 400.0, 800.0)
    q = qr.simulate(2.9 * ureg.kJ, 0.2 * ureg.rad, 400 * ureg.N, 0.8 * ureg.kN)
    s = qr.simulate("2.9 kJ", "0.2 rad", "400 N", "0.8 kN")
    for r in (q, s):
        assert r.stored_energy == 2900.0 and r.F2 == 800.0
        assert r.stop_time == ref.stop_time
    deg = qr.simulate(2900.0, (0.2 * 180 / math.pi) * ureg.deg, 400.0, 800.0)  # 11.459... deg is 0.2 rad
    assert deg.alpha0 == pytest.approx(0.2, rel=1e-15)
    assert qr.stop_time(2.9 * ureg.kJ, 0.2, 400 * ureg.N, 800.0) == pytest.approx(ref.stop_time, rel=1e-15)
    padded = qr.simulate(2900.0, 0.2, 400.0, 800.0, t_end=1500 * ureg.ms)
    assert padded.t[-1] == pytest.approx(1.5)


def test_numpy_scalars_are_numbers():
    r = qr.simulate(np.float32(2900.0), np.float64(0.2), np.int64(400), 800)
    assert r.stored_energy == 2900.0 and r.F1 == 400.0


@pytest.mark.parametrize("kwargs, name", [
    (dict(stored_energy=2.9 * ureg.kN), "E_S"),
    (dict(alpha0=0.2 * ureg.m), "alpha0"),
    (dict(F1=400 * ureg.J), "F1"),
    (dict(F2="800 kg"), "F2"),
])
def test_a_wrong_dimension_names_the_parameter(kwargs, name):
    args = dict(stored_energy=2900.0, alpha0=0.2, F1=400.0, F2=800.0) | kwargs
    with pytest.raises(UnitError, match=rf"^{name} = .*expected"):
        qr.simulate(**args)


@pytest.mark.parametrize("value", [[0.2, 0.3], np.array([0.2, 0.3]), None, np.array([0.2, 0.3]) * ureg.rad])
def test_an_array_where_one_number_is_expected(value):
    with pytest.raises(ParameterError, match=r"^alpha0 = .*single numbers"):
        qr.simulate(2900.0, value, 400.0, 800.0)


def test_identify_strain_energy_and_final_angle_take_quantities():
    ref = qr.identify_friction(0.2, 0.7378, 1.05, stored_energy=2900.0)
    q = qr.identify_friction(0.2 * ureg.rad, 0.7378, 1050 * ureg.ms, stored_energy=2.9 * ureg.kJ)
    assert q.F1 == ref.F1 and q.F2 == ref.F2
    dev = qr.preset("paper")
    assert qr.strain_energy(1598 * ureg.kN, 0.2, dev).total == qr.strain_energy(1598e3, 0.2, dev).total
    assert qr.final_angle(2.9 * ureg.kJ, 0.2, 0.4 * ureg.kN, 800.0, device=dev) == pytest.approx(
        qr.final_angle(2900.0, 0.2, 400.0, 800.0, device=dev), rel=1e-15)
    with pytest.warns(DeprecationWarning):  # the old trailing L1 still takes a Quantity
        assert qr.final_angle(2900.0, 0.2, 400.0, 800.0, dev.L1 * 1000 * ureg.mm) == pytest.approx(
            qr.final_angle(2900.0, 0.2, 400.0, 800.0, device=dev), rel=1e-15)


def test_one_vocabulary_old_names_still_work_with_a_warning():
    """stored_energy and push_force everywhere (as identify_friction, Case and the JSON keys); the old
    keyword names E_S= and push= still work, with a DeprecationWarning."""
    ref = qr.simulate(stored_energy=2900.0, alpha0=0.2, F1=400.0, F2=800.0)
    with pytest.warns(DeprecationWarning, match=r"simulate\(E_S=...\) is now simulate\(stored_energy=...\)"):
        old = qr.simulate(E_S=2900.0, alpha0=0.2, F1=400.0, F2=800.0)
    assert old.stop_time == ref.stop_time
    with pytest.warns(DeprecationWarning, match="push_force"):
        assert qr.strain_energy(push=1598e3, alpha0=0.2).total == qr.strain_energy(push_force=1598e3, alpha0=0.2).total
    with pytest.raises(TypeError, match="both"):
        qr.stop_time(E_S=1.0, stored_energy=1.0, alpha0=0.2, F1=0.0, F2=0.0)
    # the paper's device is the default device everywhere
    assert qr.strain_energy(1598e3, 0.2).total == qr.strain_energy(1598e3, 0.2, qr.preset("paper")).total
