"""
Friction from a measured record
===============================

``quickrelease fit examples/fit.toml``: F1 and F2 (with the release instant and the sensors' zero
offsets) fitted by weighted least squares to a 500 Hz record of the head retraction u, the hinge opening
v and the head acceleration. The record is synthetic (``examples/make_records.py``), made with
F1 = 419.85 N and F2 = 804.57 N.
"""

from pathlib import Path

from quickrelease.io.case import load_case
from quickrelease.report import plots
from quickrelease.studies.fit import fit_record

# the case files of the repository's examples/ folder (the gallery runs this script in docs/examples/)
EXAMPLES = next((d / "examples" for d in (Path.cwd(), *Path.cwd().parents)
                 if (d / "examples" / "paper.toml").is_file()), None)
if EXAMPLES is None:  # a downloaded script or notebook, run outside a clone of the repository
    raise SystemExit("this example reads the case files and records of the quickrelease repository's examples/ "
                     "folder: run it from a clone of the repository, or from a folder that holds examples/")
fit = fit_record(load_case(EXAMPLES / "fit.toml"))
for name in ("F1", "F2"):
    low, high = fit.ci95[name]
    print(f"{name} = {getattr(fit, name):.2f} N, 95% interval [{low:.2f}, {high:.2f}] N")

fig = plots.fit_figure(fit)  # a matplotlib Figure: fig.savefig(...) to keep it
