"""The friction-pendulum and lead-rubber examples (examples/*_building.toml, issue 24): each case file's
[building] is the truth its synthetic records were made with (examples/make_isolator_records.py, by the
independent reference of tests/building/isolator_reference.py), and the records hold that motion plus the
documented sensor noise and offsets."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("quickrelease.building.hysteretic")

from quickrelease.io.building_case import spec_isolation  # noqa: E402
from quickrelease.io.case import load_case  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "building"))
import isolator_reference as ref  # noqa: E402

CASES = {"pendulum_building.toml": "pendulum", "lead_rubber_building.toml": "lead_rubber",
         "lead_rubber_damper_building.toml": "lead_rubber_damper", "fluid_damper_building.toml": "fluid_damper"}
G0, RELEASE = 9.80665, 2.05


def _reference_system(system):
    if type(system).__name__ == "Isolation":  # linear bearings and sliders (the fluid dampers' building)
        assert system.post_yield_stiffness is None
        return ref.linear(system.mass, system.stiffness, system.damping, system.damping_exponent, system.friction)
    if type(system).__name__ == "Pendulum":
        return ref.pendulum(system.mass, system.radius, system.friction_slow, system.friction_fast, system.rate,
                            system.damping, system.damping_exponent)
    return ref.boucwen(system.mass, system.post_yield_stiffness, system.characteristic_strength,
                       system.yield_displacement, system.shape, system.damping, system.damping_exponent,
                       system.friction)


def _table(path):
    names = path.read_text().splitlines()[0].split(",")
    data = np.genfromtxt(path, delimiter=",", skip_header=1)
    return {n: data[:, i] for i, n in enumerate(names)}


@pytest.mark.parametrize("case_file, stem", list(CASES.items()))
def test_example_records_are_the_case_files_truth(case_file, stem):
    case = load_case(ROOT / "examples" / case_file, require_test=False)
    spec = case.building
    system = _reference_system(spec_isolation(spec))
    lvdt = _table(ROOT / "examples" / "records" / f"{stem}_200Hz.csv")
    acc = _table(ROOT / "examples" / "records" / f"{stem}_acc_100Hz.csv")
    t = lvdt["t_s"]
    assert t.size == 12000 and acc["t_acc_s"].size == 6000
    assert t[1] - t[0] == pytest.approx(0.005) and acc["t_acc_s"][1] - acc["t_acc_s"][0] == pytest.approx(0.01)
    # one simulation sampled at both clocks (the reference's integration does not depend on the sample times)
    both = ref.simulate(system, spec.displacement, np.concatenate([t, acc["t_acc_s"]]) - RELEASE, t_end=60.0)
    x, a = both.x[:t.size], both.a[t.size:]
    r = lvdt["x_iso_mm"] - 1e3 * x - 0.8  # the LVDT's noise alone (mm): 0.05 mm, some samples missing
    ok = np.isfinite(r)
    assert 0.0005 < 1 - ok.mean() < 0.002
    assert abs(np.mean(r[ok])) < 0.005 and 0.048 < np.std(r[ok]) < 0.052
    ra = acc["a_base_g"] - a / G0 - 0.004
    assert abs(np.mean(ra)) < 1e-4 and 0.0019 < np.std(ra) < 0.0021
    assert math.isfinite(spec.displacement)
