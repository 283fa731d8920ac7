"""
Lead-rubber bearings with fluid viscous dampers
===============================================

``examples/lead_rubber_damper_building.toml``: the lead-rubber building of the previous example (800 t, one
Bouc-Wen element: Kd = 1.6 MN/m, Qd = 400 kN, dy = 25 mm, n = 1) with fluid viscous dampers in parallel instead of
its 2 % viscous damping, ``F = C |v|^alpha sign(v)``: C = 200 kN (s/m)^alpha, alpha = 0.5 (``model = "boucwen"``,
``damping = "power"``); pushed 200 mm and released. Its record is synthetic, made by the tests' independent
simulator (``examples/make_isolator_records.py``: solve_ivp with events, no code of the package): an LVDT at
200 Hz and an accelerometer at 100 Hz on its own clock. It turns five times, then creeps back towards its rest
for the rest of the minute: as the velocity vanishes the damper's force, ``C |v|^0.5``, outgrows any viscous
one, and the layer moves on the damper's slow manifold (the integrator follows it there, its speed with two
corrections for inertia). The fit uses the first 16 s.

The fit gives the bearings' Kd, Qd, dy and n and the dampers' C and alpha with their 95% intervals (each truth
printed beside them), then the quantities EN 15129 and ASCE 7 report per cycle (keff, EDC, beta_eff) against the
amplitude, with bands: the bearings' hysteresis and the dampers' dissipation together, as a test measures them.
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
data = load_building(load_case(EXAMPLES / "lead_rubber_damper_building.toml", require_test=False))
window = [BuildingChannel(c.name, c.kind, c.t[c.t < 16.0], c.values[c.t < 16.0], c.noise, c.offset)
          for c in data.channels]  # the release, five turns and the start of the creep
result = analyse_building(data, channels=window)  # the case's model (boucwen) and damping (power)
summary = result.summary()
truth = {"Kd_N_m": 1.6e6, "Qd_N": 4.0e5, "dy_m": 0.025, "shape": 1.0, "damping_coefficient": 2.0e5,
         "damping_exponent": 0.5}  # the values the record was made with
for key, value in truth.items():
    ci = summary[f"{key}_ci95"]
    print(f"{key:20s} {summary[key]:.5g}  95% interval "
          f"{'not identified' if ci is None else f'[{ci[0]:.5g}, {ci[1]:.5g}]'}  (truth {value:.5g})")
print(f"reduced chi-square {result.fit.chi2_reduced:.3g}; global minimum "
      f"{'confirmed' if result.fit.global_minimum_confirmed else 'not confirmed'}")

fig = fit_figure(result)

# %%
# The engineering quantities per cycle
# ------------------------------------
# Per cycle of the identified model's loop along the record (keff, EDC, beta_eff), judged against the model's
# curve at each cycle's amplitude; then the curves against the amplitude with 95% bands (400 draws of the
# fitted parameters), the cycles as points. The bearings' loop gives Qd and Kd; the dampers add a dissipation
# that grows as D^(1 + alpha) and no stiffness, so their share of beta_eff grows as the amplitude falls. The
# dampers end the swing after two cycles: too few to judge their spread between cycles as EN 15129 does (the
# release's cycle and at least two more), which the report then says.
for c in result.effective:
    print(f"D {c.amplitude_m * 1e3:6.1f} mm: keff {c.keff_N_m / 1e3:7.1f} kN/m, EDC {c.edc_J / 1e3:6.2f} kJ, "
          f"beta_eff {c.beta_eff:.3f}, Teff {c.teff_s:.2f} s")
print(f"model: Qd = {summary['Qd_N'] / 1e3:.1f} kN, Kd = {summary['Kd_N_m'] / 1e3:.1f} kN/m")
if result.effective_judgement is None:  # the dampers end the swing after two cycles
    print(f"{len(result.effective)} cycles: too few after the release's to judge their spread as the standards do")
else:
    for criterion in result.effective_judgement.criteria:
        worst = "-" if criterion["worst"] is None else f"{criterion['worst']:.3g}"
        print(f"{criterion['name']}: worst {worst}, limit {criterion['tolerance']}, "
              f"{'pass' if criterion['passed'] else 'FAIL'}")

fig2 = effective_figure(result.effective_curve, result.effective, release_time=result.fit.release_time)
