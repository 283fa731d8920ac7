"""
A sweep over push force and angle
=================================

The release envelope (stop time, final angle, head stroke, hinge opening, peak velocities) over a grid of
push forces and initial angles, with the friction of the paper's test, computed by the batch kernels as
``quickrelease sweep`` does. The white line is the boundary beyond which the device reaches the flat
rhombus (the geometric limit) before friction stops it.
"""

from pathlib import Path

import numpy as np

from quickrelease.io.case import load_case
from quickrelease.studies.sweep import heatmap_figure, sweep

# the case files of the repository's examples/ folder (the gallery runs this script in docs/examples/)
EXAMPLES = next((d / "examples" for d in (Path.cwd(), *Path.cwd().parents)
                 if (d / "examples" / "paper.toml").is_file()), None)
if EXAMPLES is None:  # a downloaded script or notebook, run outside a clone of the repository
    raise SystemExit("this example reads the case files and records of the quickrelease repository's examples/ "
                     "folder: run it from a clone of the repository, or from a folder that holds examples/")
case = load_case(EXAMPLES / "larger_push.toml")
ds = sweep(case, {"force": np.linspace(500e3, 3000e3, 26), "alpha0": np.linspace(0.1, 0.5, 41)})
print(f"t_F from {float(ds.stop_time.min()):.3f} to {float(ds.stop_time.max()):.3f} {ds.stop_time.attrs['units']}; "
      f"{float((ds.stopped_by == 1).mean()):.1%} of the grid reaches the geometric limit (stopped_by = 1)")

fig = heatmap_figure(ds)
