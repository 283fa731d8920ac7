"""Regenerate the synthetic records of the friction-pendulum and lead-rubber examples (issue 24).

    python examples/make_isolator_records.py

The motions come from the independent reference simulator of the tests (tests/building/isolator_reference.py:
scipy's solve_ivp, DOP853 at rtol 1e-12, every reversal, stick and z = 0 crossing located as an event; it shares
no code with quickrelease's models), so a fit of these records by quickrelease is a check of its models.

Each building has two records, 60 s long, released at ``RELEASE`` = 2.05 s on the LVDT's clock:

* ``*_200Hz.csv``: the isolation layer's displacement from an LVDT, in mm, at 200 Hz (column ``x_iso_mm``,
  time ``t_s``): Gaussian noise 0.05 mm, a zero offset of +0.8 mm, 0.1 % of the samples missing (empty cells);
* ``*_acc_100Hz.csv``: the base acceleration from an accelerometer on another logger, in g0, at 100 Hz with its
  own time column ``t_acc_s`` (its clock starts 3.7 ms after the LVDT's): noise 0.002 g0, offset +0.004 g0.

The truth of each record (SI), also written in the case files' comments:

* ``pendulum_*`` (examples/pendulum_building.toml): 1000 t on curved surface sliders of radius R = 2.5 m
  (T = 2 pi sqrt(R / g) = 3.17 s), Constantinou's friction mu_slow = 0.02, mu_fast = 0.06, a = 30 s/m, a
  viscous damping ratio of 1 % referred to W / R (c = 2 zeta sqrt(m W / R)), pushed 250 mm. Seeds 24 (LVDT)
  and 25 (accelerometer). One reversal (1.800 s after the release, at x = 46.0 mm) where it sticks: a
  snap-back of a friction pendulum is short, its friction 0.02-0.06 W against a restoring force of
  0.1 W at 250 mm. (Pushed 150 mm with mu_slow = 0.03, mu_fast = 0.07, it would creep back to rest without a
  single reversal: the friction's growth with speed, W (mu_fast - mu_slow) a = 1.2e7 N s/m, is 3 times the
  critical damping 2 m sqrt(g / R).)
* ``lead_rubber_*`` (examples/lead_rubber_building.toml): 800 t on lead-rubber bearings as one Bouc-Wen element,
  Kd = 1.6 MN/m (post-yield period 4.44 s), Qd = 400 kN (5.1 % of the weight), dy = 25 mm (k1 = Kd + Qd / dy
  = 17.6 MN/m = 11 Kd), shape n = 1, a viscous damping ratio of 2 % referred to Kd, no sliders, pushed
  200 mm. Seeds 26 and 27. It never sticks: the loops shrink about a residual displacement.
* ``lead_rubber_damper_*`` (examples/lead_rubber_damper_building.toml): the same bearings with fluid viscous
  dampers instead of the 2 % viscous damping: F = C |v|^alpha sign(v), C = 200 kN (s/m)^alpha, alpha = 0.5
  (exponents of 0.3 to 0.5 are usual for buildings). Seeds 28 and 29. Five reversals, then it creeps to rest
  (the damper's force C |v|^0.5 outgrows any viscous one as v vanishes).
* ``fluid_damper_*`` (examples/fluid_damper_building.toml): 800 t on rubber bearings (linear, isolation period
  T = 2.5 s) and flat sliders (friction 0.5 % of the weight) with fluid viscous dampers in parallel,
  F = C |v|^alpha sign(v), C = 100 kN (s/m)^alpha, alpha = 0.4, pushed 200 mm. Seeds 30 and 31. Six
  reversals (200 mm, then -159, 120, -84, 51, -22 mm), stuck 7.52 s after the release at -1.9 mm.
* ``pendulum_campaign_R1.csv`` ... ``_R4.csv`` (examples/pendulum_campaign.toml): a campaign of four releases of
  one building on friction pendulums with a constant friction coefficient: 1000 t, R = 2.5 m (T = 3.17 s),
  mu = 0.5 % (constant: no growth with speed), a viscous damping ratio of 1 %
  referred to W / R, pushed 100, 150, 200 and 250 mm. One LVDT record each (the LVDT above, at 100 Hz, 12 s,
  released at ``CAMPAIGN_RELEASE`` = 1.05 s); seeds 40-43.
"""

import math
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).parent
RECORDS = HERE / "records"
sys.path.insert(0, str(HERE.parent / "tests" / "building"))

import isolator_reference as ref  # noqa: E402

G0 = 9.80665  # standard gravity [m/s^2]
RELEASE = 2.05  # s after the LVDT's first sample
DURATION = 60.0  # s
ACC_CLOCK = 0.0037  # s: the accelerometer's first sample after the LVDT's
LVDT = {"rate": 200.0, "noise": 0.05e-3, "offset": 0.8e-3, "missing": 0.001}  # m
ACC = {"rate": 100.0, "noise": 0.002, "offset": 0.004}  # g0

PENDULUM = {"mass": 1.0e6, "radius": 2.5, "friction_slow": 0.02, "friction_fast": 0.06, "rate": 30.0,
            "damping_ratio": 0.01, "d0": 0.25}
LEAD_RUBBER = {"mass": 8.0e5, "post_yield_stiffness": 1.6e6, "characteristic_strength": 4.0e5,
               "yield_displacement": 0.025, "shape": 1.0, "damping_ratio": 0.02, "d0": 0.2}
DAMPER = {"damping_coefficient": 2.0e5, "damping_exponent": 0.5}
FLUID_DAMPER = {"mass": 8.0e5, "period": 2.5, "friction_coefficient": 0.005, "damping_coefficient": 1.0e5,
                "damping_exponent": 0.4, "d0": 0.2}


PENDULUM_CAMPAIGN = {"mass": 1.0e6, "radius": 2.5, "friction_coefficient": 0.005, "damping_ratio": 0.01,
                     "d0": (0.10, 0.15, 0.20, 0.25), "rate": 100.0, "duration": 12.0, "seeds": (40, 41, 42, 43)}
CAMPAIGN_RELEASE = 1.05  # s after the LVDT's first sample


def systems() -> dict[str, tuple[ref.System, float, tuple[int, int]]]:
    """name -> (the reference's system, d0 [m], (seed of the LVDT, seed of the accelerometer))."""
    p, b = PENDULUM, LEAD_RUBBER
    k = p["mass"] * G0 / p["radius"]
    pendulum = ref.pendulum(p["mass"], p["radius"], p["friction_slow"], p["friction_fast"], p["rate"],
                            damping=2.0 * p["damping_ratio"] * math.sqrt(k * p["mass"]))
    c = 2.0 * b["damping_ratio"] * math.sqrt(b["post_yield_stiffness"] * b["mass"])
    bearings = (b["mass"], b["post_yield_stiffness"], b["characteristic_strength"], b["yield_displacement"])
    lead = ref.boucwen(*bearings, shape=b["shape"], damping=c)
    damper = ref.boucwen(*bearings, shape=b["shape"], damping=DAMPER["damping_coefficient"],
                         damping_exponent=DAMPER["damping_exponent"])
    f = FLUID_DAMPER
    fluid = ref.linear(f["mass"], f["mass"] * (2.0 * math.pi / f["period"]) ** 2, damping=f["damping_coefficient"],
                       damping_exponent=f["damping_exponent"], friction=f["friction_coefficient"] * f["mass"] * G0)
    return {"pendulum": (pendulum, p["d0"], (24, 25)), "lead_rubber": (lead, b["d0"], (26, 27)),
            "lead_rubber_damper": (damper, b["d0"], (28, 29)), "fluid_damper": (fluid, f["d0"], (30, 31))}


def write_columns(path: Path, columns: dict[str, np.ndarray]) -> None:
    """A CSV with the given columns (10 significant digits; NaN as an empty cell)."""
    rows = zip(*columns.values(), strict=True)
    text = ",".join(columns) + "\n" + "".join(
        ",".join("" if v != v else f"{v:.10g}" for v in row) + "\n" for row in rows)
    path.write_text(text)


def records(name: str, system: ref.System, d0: float, seeds: tuple[int, int]) -> ref.Motion:
    """Write the two records of one building; return the reference motion on the LVDT's samples."""
    tx = np.arange(round(DURATION * LVDT["rate"])) / LVDT["rate"]
    ta = np.arange(round(DURATION * ACC["rate"])) / ACC["rate"] + ACC_CLOCK
    t_end = DURATION - RELEASE + 1.0
    motion = ref.simulate(system, d0, tx - RELEASE, t_end=t_end)
    accel = ref.simulate(system, d0, ta - RELEASE, t_end=t_end).a
    rng = np.random.default_rng(seeds[0])
    x = motion.x + LVDT["offset"] + rng.normal(0.0, LVDT["noise"], tx.size)
    x[rng.random(tx.size) < LVDT["missing"]] = np.nan
    write_columns(RECORDS / f"{name}_200Hz.csv", {"t_s": tx, "x_iso_mm": 1e3 * x})
    rng = np.random.default_rng(seeds[1])
    a = accel / G0 + ACC["offset"] + rng.normal(0.0, ACC["noise"], ta.size)
    write_columns(RECORDS / f"{name}_acc_100Hz.csv", {"t_acc_s": ta, "a_base_g": a})
    return motion


def campaign_records() -> list[ref.Motion]:
    """Write the pendulum campaign's records (one LVDT record per release); return the reference motions."""
    c = PENDULUM_CAMPAIGN
    k = c["mass"] * G0 / c["radius"]
    system = ref.pendulum(c["mass"], c["radius"], c["friction_coefficient"],
                          damping=2.0 * c["damping_ratio"] * math.sqrt(k * c["mass"]))
    tx = np.arange(round(c["duration"] * c["rate"])) / c["rate"]
    motions = []
    for i, (d0, seed) in enumerate(zip(c["d0"], c["seeds"], strict=True)):
        motion = ref.simulate(system, d0, tx - CAMPAIGN_RELEASE, t_end=c["duration"])
        rng = np.random.default_rng(seed)
        x = motion.x + LVDT["offset"] + rng.normal(0.0, LVDT["noise"], tx.size)
        x[rng.random(tx.size) < LVDT["missing"]] = np.nan
        write_columns(RECORDS / f"pendulum_campaign_R{i + 1}.csv", {"t_s": tx, "x_iso_mm": 1e3 * x})
        motions.append(motion)
    return motions


def main() -> None:
    RECORDS.mkdir(exist_ok=True)
    for name, (system, d0, seeds) in systems().items():
        motion = records(name, system, d0, seeds)
        print(f"{name}: d0 = {d0} m, reversals at {np.round(motion.reversal_times[:6], 4)} s "
              f"({motion.reversal_times.size - 1} in all), stop {motion.stop_time:.4f} s, "
              f"turning points {np.round(motion.turning_points[:6], 5)} m, seeds {seeds}")
    for d0, motion in zip(PENDULUM_CAMPAIGN["d0"], campaign_records(), strict=True):
        print(f"pendulum campaign: d0 = {d0} m, {motion.reversal_times.size - 1} reversals, stop "
              f"{motion.stop_time:.4f} s, turning points {np.round(motion.turning_points[:8], 5)} m")


if __name__ == "__main__":
    main()
