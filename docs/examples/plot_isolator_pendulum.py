"""
A building on friction pendulums
================================

``examples/pendulum_building.toml``: 1000 t on curved surface sliders of radius R = 2.5 m, friction after
Constantinou's law ``mu(v) = mu_fast - (mu_fast - mu_slow) exp(-a |v|)`` (2 % at rest, 6 % at speed, a = 30 s/m),
1 % viscous damping, pushed 250 mm and released. Its record is synthetic, made by the tests' independent
simulator (``examples/make_isolator_records.py``: solve_ivp with events, no code of the package): an LVDT at
200 Hz and an accelerometer at 100 Hz on its own clock. A friction pendulum's snap-back is short: it swings back
once and sticks, so the fit uses the first 12 s of the 60 s record (the rest is the slider at rest).

The fit (``model = "pendulum"``) gives the period 2 pi sqrt(R / g), hence the radius, the friction law and the
damping with their 95% intervals; what the one swing cannot resolve is said so.
"""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from quickrelease.building.isolation_fit import BuildingChannel
from quickrelease.io.building_case import load_building
from quickrelease.io.case import load_case
from quickrelease.report.building_plots import fit_figure
from quickrelease.studies.building_analysis import analyse_building

# the case files of the repository's examples/ folder (the gallery runs this script in docs/examples/)
EXAMPLES = next((d / "examples" for d in (Path.cwd(), *Path.cwd().parents)
                 if (d / "examples" / "paper.toml").is_file()), None)
if EXAMPLES is None:  # a downloaded script or notebook, run outside a clone of the repository
    raise SystemExit("this example reads the case files and records of the quickrelease repository's examples/ "
                     "folder: run it from a clone of the repository, or from a folder that holds examples/")
data = load_building(load_case(EXAMPLES / "pendulum_building.toml", require_test=False))
window = [BuildingChannel(c.name, c.kind, c.t[c.t < 12.0], c.values[c.t < 12.0], c.noise, c.offset)
          for c in data.channels]  # the first 12 s: the release, the swing and the stick
result = analyse_building(data, channels=window, global_search=False)
summary = result.summary()
for key in ("period_s", "radius_m", "friction_slow", "friction_fast", "rate_s_m", "damping_ratio"):
    ci = summary[f"{key}_ci95"]
    print(f"{key:14s} {summary[key]:.5g}  95% interval "
          f"{'not identified' if ci is None else f'[{ci[0]:.5g}, {ci[1]:.5g}]'}")
print(f"Qd = {summary['Qd_N'] / 1e3:.1f} kN (mu_slow W), Kd = W / R = {summary['Kd_N_m'] / 1e3:.1f} kN/m")

fig = fit_figure(result)

# %%
# The engineering quantities against the amplitude
# ------------------------------------------------
# The record holds no whole cycle (the slider sticks after one swing), so the effective stiffness and damping
# come from the identified model: a pendulum cycled at amplitude D and speed carries W D / R + mu W, so
# keff = W / R + mu W / D, EDC = 4 mu W D and beta_eff = 2 mu / (pi (D / R + mu)), mu = mu_fast at speed. The
# bands: 400 draws of (T, mu_fast) from the fit's estimates, standard errors and correlation.
fit = result.fit
W = fit.mass * 9.80665
names = ["period", "friction_fast"]
mean = np.array([fit.estimates[n] for n in names])
se = np.array([fit.std_errors[n] for n in names])
se = np.where(np.isfinite(se), se, 0.0)  # a parameter the record does not identify: held at its estimate
rho = fit.correlation[np.ix_([fit.names.index(n) for n in names], [fit.names.index(n) for n in names])]
draws = np.random.default_rng(0).multivariate_normal(mean, rho * np.outer(se, se), 400)
D = np.linspace(0.05, 0.30, 51)  # m


def keff_beta(T, mu, D):
    """keff [N/m] and beta_eff [-] of a pendulum of period T [s] and friction mu at amplitude D [m]."""
    R = 9.80665 * (T / (2 * np.pi)) ** 2
    return W / R + mu * W / D, 2 * mu / (np.pi * (D / R + mu))


keff, beta = keff_beta(mean[0], mean[1], D)
drawn = [keff_beta(T, mu, D) for T, mu in draws]
k_lo, k_hi = np.percentile([k for k, _ in drawn], [2.5, 97.5], axis=0)
b_lo, b_hi = np.percentile([b for _, b in drawn], [2.5, 97.5], axis=0)
print(f"at D = 0.25 m: keff {np.interp(0.25, D, keff) / 1e3:.0f} kN/m, beta_eff {np.interp(0.25, D, beta):.1%}")

fig2, (left, right) = plt.subplots(1, 2, figsize=(7, 3), layout="constrained")
left.fill_between(1e3 * D, k_lo / 1e3, k_hi / 1e3, alpha=0.3, lw=0, label="95% band")
left.plot(1e3 * D, keff / 1e3, label="identified pendulum")
left.set_ylabel("keff [kN/m]")
right.fill_between(1e3 * D, 100 * b_lo, 100 * b_hi, alpha=0.3, lw=0, label="95% band")
right.plot(1e3 * D, 100 * beta, label="identified pendulum")
right.set_ylabel("beta_eff [%]")
for ax in (left, right):
    ax.set_xlabel("cycle amplitude D [mm]")
    ax.legend(fontsize="small")
