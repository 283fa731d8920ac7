"""
A building on lead-rubber bearings
==================================

``examples/lead_rubber_building.toml``: 800 t on lead-rubber bearings taken together as one Bouc-Wen element
(``model = "boucwen"``): post-yield stiffness Kd = 1.6 MN/m, characteristic strength Qd = 400 kN, yield
displacement dy = 25 mm, shape n = 1, 2 % viscous damping; pushed 200 mm and released. Its record is synthetic,
made by the tests' independent simulator (``examples/make_isolator_records.py``: solve_ivp with events, no code
of the package): an LVDT at 200 Hz and an accelerometer at 100 Hz on its own clock. The fit uses the first 16 s
of the 60 s record (nine cycles, the release's included: 65 mm down to 3.5 mm).

The fit gives Kd (from the post-yield period), Qd, dy, n and the damping with their 95% intervals, then the
quantities EN 15129 and ASCE 7 report per cycle (keff, EDC, beta_eff) against the amplitude, with bands.
"""

from pathlib import Path

from quickrelease.building.isolation_fit import BuildingChannel
from quickrelease.io.building_case import load_building
from quickrelease.io.case import load_case
from quickrelease.report.building_plots import effective_figure, fit_figure
from quickrelease.studies.building_analysis import analyse_building

# the case files of the repository's examples/ folder (the gallery runs this script in docs/examples/)
EXAMPLES = next((d / "examples" for d in (Path.cwd(), *Path.cwd().parents)
                 if (d / "examples" / "paper.toml").is_file()), None)
if EXAMPLES is None:  # a downloaded script or notebook, run outside a clone of the repository
    raise SystemExit("this example reads the case files and records of the quickrelease repository's examples/ "
                     "folder: run it from a clone of the repository, or from a folder that holds examples/")
CASE = "lead_rubber_building.toml"
data = load_building(load_case(EXAMPLES / CASE, require_test=False))
window = [BuildingChannel(c.name, c.kind, c.t[c.t < 16.0], c.values[c.t < 16.0], c.noise, c.offset)
          for c in data.channels]  # nine cycles, the release's included
result = analyse_building(data, channels=window)
summary = result.summary()
keys = ["Kd_N_m", "Qd_N", "dy_m", "shape"]
keys += (["damping_coefficient", "damping_exponent"] if result.fit.damping == "power" else ["damping_ratio"])
for key in keys:
    ci = summary[f"{key}_ci95"]
    print(f"{key:20s} {summary[key]:.5g}  95% interval "
          f"{'not identified' if ci is None else f'[{ci[0]:.5g}, {ci[1]:.5g}]'}")

# %%
# Per cycle of the identified model's loop along the record (keff, EDC, beta_eff), judged against the model's
# curve at each cycle's amplitude; then the curves against the amplitude with 95% bands (400 draws of the
# fitted parameters), the cycles as points
for c in result.effective:
    print(f"D {c.amplitude_m * 1e3:6.1f} mm: keff {c.keff_N_m / 1e3:7.1f} kN/m, EDC {c.edc_J / 1e3:6.2f} kJ, "
          f"beta_eff {c.beta_eff:.3f}, Teff {c.teff_s:.2f} s")
print(f"model: Qd = {summary['Qd_N'] / 1e3:.1f} kN, Kd = {summary['Kd_N_m'] / 1e3:.1f} kN/m")
for criterion in result.effective_judgement.criteria:
    worst = "-" if criterion["worst"] is None else f"{criterion['worst']:.3g}"
    print(f"{criterion['name']}: worst {worst}, limit {criterion['tolerance']}, "
          f"{'pass' if criterion['passed'] else 'FAIL'}")

fig = fit_figure(result)
fig2 = effective_figure(result.effective_curve, result.effective, release_time=result.fit.release_time)
