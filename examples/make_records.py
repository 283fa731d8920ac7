"""Regenerate the synthetic records of the examples (examples/records/*.csv) with quickrelease.studies.synth.

    python examples/make_records.py

* ``paper_500Hz.csv`` (for ``fit.toml``): the paper's test (``paper.toml``: E_S = 2.90 kJ, alpha0 = 0.2 rad,
  friction identified from Table 7's stop observations), head retraction u and opening v (draw-wire
  sensors, 0.5 mm noise) and the head acceleration (0.05 m/s^2 noise) at 500 Hz, with 1 % jitter of the
  sampling instants, 0.4 % missing samples, offsets of +1.5 mm on u and -2.0 mm on v, released 0.62 s
  after the record starts. The same as
  ``quickrelease synth paper.toml --channels u,v,a_head --rate 500Hz --offset "u=1.5 mm,v=-2 mm"
  --release-time 0.62s --jitter 0.01 --missing 0.004 --seed 2024 --out records/paper_500Hz.csv``.
* ``campaign_T*.csv`` (for ``campaign.toml``): six tests of the paper's device at different push forces
  and angles, u and v at 200 Hz. The friction of these synthetic tests follows a law chosen for the
  demonstration, not measured: F1 = 150 N + 0.17 N/kN * P at the hinges, F2 = 805 N on the rail
  (independent of the load). ``quickrelease campaign campaign.toml`` recovers it.
* ``building_200Hz.csv`` and ``building_acc_100Hz.csv`` (for ``building.toml``): the building's free vibration
  after the release (``[building]`` of building.toml: 800 t, T = 2.0 s, zeta = 5 %, sliders at 2 % of the
  weight, d0 = 182.5 mm), released 2.05 s after the records start, 60 s long. The isolation layer's
  displacement (an LVDT: 0.05 mm noise, +0.8 mm offset, 0.1 % missing samples) in mm at 200 Hz; the base
  acceleration (an accelerometer on another logger: 0.002 g0 noise, +0.004 g0 offset) in g0 at 100 Hz with
  its own time column. Made with ``quickrelease.studies.synth.synthesize_building`` (``quickrelease synth
  building.toml --building``), the units converted here.
* ``building_R*.csv`` (for ``building_campaign.toml``): five releases of one isolated building (650 t,
  linear rubber bearings of period 2.0 s, viscous damping ratio 3 %, sliders) pushed to d0 = 6 to 18 cm:
  the isolation layer's displacement (LVDT, mm, 0.2 mm noise, a +2 mm zero) and the base acceleration
  (m/s^2, 0.02 m/s^2 noise, a 0.01 m/s^2 zero) at 100 Hz for 20 s, released about 2 s in
  (:func:`quickrelease.building.model.free_vibration`). The sliders' friction of these synthetic releases grows
  with the amplitude by a law chosen for the demonstration, F_s = 40 kN + 150 kN/m |d0|;
  ``quickrelease campaign building_campaign.toml`` finds it, and no amplitude effect on T or zeta.
"""

import math
from pathlib import Path

from quickrelease.device.statics import strain_energy
from quickrelease.io.case import load_case
from quickrelease.studies.synth import synthesize, synthesize_building

HERE = Path(__file__).parent
RECORDS = HERE / "records"

#: The synthetic campaign: name, push force [kN], alpha0 [rad], release instant [s].
CAMPAIGN = [("T1", 1000, 0.22, 0.41), ("T2", 1300, 0.18, 0.55), ("T3", 1600, 0.26, 0.47),
            ("T4", 1900, 0.20, 0.62), ("T5", 2200, 0.24, 0.38), ("T6", 1450, 0.28, 0.50)]
F1_LAW = (150.0, 0.17e-3)  # F1 = a + b P [N, N/N]
F2_CONSTANT = 805.0
G0 = 9.80665  # standard gravity [m/s^2]


def write_columns(path: Path, columns: dict[str, list[float]]) -> None:
    """A CSV with the given columns (10 significant digits; NaN as an empty cell)."""
    names = list(columns)
    rows = zip(*columns.values(), strict=True)
    text = ",".join(names) + "\n" + "".join(
        ",".join("" if v != v else f"{v:.10g}" for v in row) + "\n" for row in rows)
    path.write_text(text)


def building_records() -> None:
    case = load_case(HERE / "building.toml")
    common = {"release_time": 2.05, "duration": 60.0}
    lvdt = synthesize_building(case, ["x"], rate=200.0, noise={"x": 0.05e-3}, offsets={"x": 0.8e-3}, missing=0.001,
                               seed=7, **common)
    write_columns(RECORDS / "building_200Hz.csv", {"t_s": list(lvdt.t), "x_iso_mm": list(1e3 * lvdt.data["x"])})
    acc = synthesize_building(case, ["a"], rate=100.0, noise={"a": 0.002 * G0}, offsets={"a": 0.004 * G0}, seed=8,
                              **common)
    write_columns(RECORDS / "building_acc_100Hz.csv", {"t_acc_s": list(acc.t), "a_base_g": list(acc.data["a"] / G0)})
    print("building_200Hz.csv, building_acc_100Hz.csv", lvdt.truth)


#: The synthetic building campaign: name, pushed displacement d0 [m], release instant [s].
BUILDING_RELEASES = [("R1", 0.06, 2.134), ("R2", 0.09, 1.871), ("R3", 0.12, 2.417), ("R4", 0.15, 2.023),
                     ("R5", 0.18, 1.953)]
BUILDING = {"mass": 650e3, "period": 2.0, "damping_ratio": 0.03}
FS_LAW = (40e3, 150e3)  # F_s = a + b |d0| [N, N/m]


def building_record(d0: float, friction: float, release: float, seed: int, path: Path) -> float:
    """Write one release's record (t_s, x_mm, a_m_s2) and return the push force that held it [N]."""
    import numpy as np

    from quickrelease.building.model import Isolation, free_vibration, pushed_state

    iso = Isolation.linear(BUILDING["mass"], BUILDING["period"], BUILDING["damping_ratio"], friction)
    rng = np.random.default_rng(seed)
    t = np.round(np.arange(0.0, 20.0, 0.01), 6)
    x, _, a = free_vibration(iso, d0, t_end=20.0).state(t - release)
    x = x + 2e-3 + rng.normal(0.0, 2e-4, t.size)
    a = a + 0.01 + rng.normal(0.0, 0.02, t.size)
    with open(path, "w", encoding="utf-8", newline="") as fh:
        fh.write("t_s,x_mm,a_m_s2\n")
        for row in zip(t, x * 1e3, a, strict=True):
            fh.write(f"{row[0]:.2f},{row[1]:.4f},{row[2]:.5f}\n")
    return pushed_state(iso, d0)[2]


def main() -> None:
    RECORDS.mkdir(exist_ok=True)
    paper = load_case(HERE / "paper.toml")
    syn = synthesize(paper, ["u", "v", "a_head"], rate=500.0, offsets={"u": 1.5e-3, "v": -2.0e-3}, release_time=0.62,
                     jitter=0.01, missing=0.004, seed=2024)
    syn.write_csv(RECORDS / "paper_500Hz.csv")
    print("paper_500Hz.csv", syn.truth)
    for k, (name, force_kN, alpha0, release) in enumerate(CAMPAIGN):
        P = force_kN * 1e3
        case = paper.replace(push_force=P, alpha0=alpha0, energy_given=False, alpha_final=None, stop_time=None,
                             stored_energy=strain_energy(P, alpha0, paper.device).total,
                             F1=F1_LAW[0] + F1_LAW[1] * P, F2=F2_CONSTANT)
        syn = synthesize(case, ["u", "v"], rate=200.0, offsets={"u": 1e-3 * (k - 2), "v": -1e-3 * k},
                         release_time=release, seed=100 + k)
        syn.write_csv(RECORDS / f"campaign_{name}.csv")
        print(f"campaign_{name}.csv", {key: round(v, 6) for key, v in syn.truth.items()})
    building_records()
    for k, (name, d0, release) in enumerate(BUILDING_RELEASES):
        friction = FS_LAW[0] + FS_LAW[1] * d0
        force = building_record(d0, friction, release, 300 + k, RECORDS / f"building_{name}.csv")
        print(f"building_{name}.csv", {"d0_m": d0, "friction_N": round(friction, 3), "push_force_N": round(force, 1),
                                       "release_time_s": release, "T_s": BUILDING["period"],
                                       "zeta": BUILDING["damping_ratio"], "k_N_m": round(
                                           BUILDING["mass"] * (2 * math.pi / BUILDING["period"]) ** 2, 1)})


if __name__ == "__main__":
    main()
