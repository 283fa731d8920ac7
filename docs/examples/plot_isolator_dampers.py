"""
Lead-rubber bearings with fluid viscous dampers
===============================================

``examples/lead_rubber_damper_building.toml``: the lead-rubber building of the previous example with fluid
viscous dampers in parallel instead of the 2 % viscous damping (``damping = "power"``): F = C |v|^alpha sign(v),
C = 200 kN (s/m)^alpha, alpha = 0.5. Pushed 200 mm, it turns five times and creeps to rest. The synthetic record
is made as the previous one's (``examples/make_isolator_records.py``, the tests' independent simulator). The
fit uses the first 12 s of the 60 s record and gives Kd, Qd, dy, n and the damper's C and alpha with their 95%
intervals; then keff, EDC and beta_eff against the amplitude, with bands (the dampers' share of beta_eff falls
with the amplitude as |v|^(alpha - 1)).
"""

from pathlib import Path

from quickrelease.building.isolation_fit import BuildingChannel, fit_isolation
from quickrelease.io.building_case import load_building
from quickrelease.io.case import load_case
from quickrelease.report.building_plots import effective_figure, fit_figure
from quickrelease.studies.building_analysis import (
    BuildingResult,
    characteristic_strength,
    effective_cycles,
    model_curves,
    physical_estimates,
)
from quickrelease.studies.building_effective import effective_curves

# the case files of the repository's examples/ folder (the gallery runs this script in docs/examples/)
EXAMPLES = next((d / "examples" for d in (Path.cwd(), *Path.cwd().parents)
                 if (d / "examples" / "paper.toml").is_file()), None)
if EXAMPLES is None:  # a downloaded script or notebook, run outside a clone of the repository
    raise SystemExit("this example reads the case files and records of the quickrelease repository's examples/ "
                     "folder: run it from a clone of the repository, or from a folder that holds examples/")
data = load_building(load_case(EXAMPLES / "lead_rubber_damper_building.toml", require_test=False))
window = [BuildingChannel(c.name, c.kind, c.t[c.t < 12.0], c.values[c.t < 12.0], c.noise, c.offset)
          for c in data.channels]  # the release and two turns
# the fit alone, from the case's design values (no global search) to keep the example short; `quickrelease
# building examples/lead_rubber_damper_building.toml` runs the whole analysis
fit = fit_isolation(window, data.mass, "boucwen", start=data.start, damping="power", global_search=False)
summary = physical_estimates(fit)
for key in ("Kd_N_m", "Qd_N", "dy_m", "shape", "damping_coefficient", "damping_exponent"):
    ci = summary[f"{key}_ci95"]
    print(f"{key:20s} {summary[key]:.5g}  95% interval "
          f"{'not identified' if ci is None else f'[{ci[0]:.5g}, {ci[1]:.5g}]'}")
print("model's Qd and Kd:", {k: round(v) for k, v in characteristic_strength(fit).items()})

# %%
# Per cycle of the identified model's loop along the record (keff, EDC, beta_eff, Teff), then the curves
# against the amplitude with 95% bands (100 draws of the fitted parameters), the cycles as points
cycles = effective_cycles(fit)
for c in cycles:
    print(f"D {c.amplitude_m * 1e3:6.1f} mm: keff {c.keff_N_m / 1e3:7.1f} kN/m, EDC {c.edc_J / 1e3:6.2f} kJ, "
          f"beta_eff {c.beta_eff:.3f}, Teff {c.teff_s:.2f} s")
curve = effective_curves(fit, draws=100)

fig = fit_figure(BuildingResult(fit=fit, curves=model_curves(fit)))
fig2 = effective_figure(curve, cycles, release_time=fit.release_time)
