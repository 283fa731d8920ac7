"""
The paper's test: Fig. 13-15
============================

The release of the paper's test (Table 7): the friction identified from the observed final angle and stop
time, then the release simulated with it, as ``quickrelease run examples/paper.toml`` does. The three
figures are the paper's Fig. 13 (angle, its rate and acceleration against time), Fig. 14 (head retraction
u and hinge opening v with their velocities) and Fig. 15 (the state diagram: the Runge-Kutta and Table 6
solutions over the analytic curve of Eq. 10).
"""

from pathlib import Path

from quickrelease.io.case import load_case
from quickrelease.report import plots
from quickrelease.workflow import run_case

# the case files of the repository's examples/ folder (the gallery runs this script in docs/examples/)
EXAMPLES = next((d / "examples" for d in (Path.cwd(), *Path.cwd().parents)
                 if (d / "examples" / "paper.toml").is_file()), None)
if EXAMPLES is None:  # a downloaded script or notebook, run outside a clone of the repository
    raise SystemExit("this example reads the case files and records of the quickrelease repository's examples/ "
                     "folder: run it from a clone of the repository, or from a folder that holds examples/")
result = run_case(load_case(EXAMPLES / "paper.toml"))
ident = result.identification
print(f"identified: F1 = {ident.F1:.2f} N, F2 = {ident.F2:.2f} N")
print(f"release: t_F = {result.response.stop_time:.4f} s, alpha_F = {result.response.alpha_final:.4f} rad")

# %%
# Fig. 13: the bar angle alpha, its rate and its acceleration until the stop t_F.
fig = plots.fig13(result.response)

# %%
# Fig. 14: the head's retraction u along the rail and the central hinge's opening v, with their rates.
fig = plots.fig14(result.response)

# %%
# Fig. 15: the state diagram of every solver over the analytic curve of Eq. 10.
fig = plots.fig15(result.state_responses)

# %%
# The stored strain energy E_S by member and effect (Eq. 2 with Table 3's forces).
fig = plots.strain_energy_figure(result.strain)
