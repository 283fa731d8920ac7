"""
Planning a test: fuse, envelope and clearance
=============================================

``quickrelease plan examples/plan.toml``: which fuse diameter and angle give the wanted push, how far the
device travels over the uncertainty of its friction, and whether it gets out of the way of the building
springing back.
"""

from pathlib import Path

from quickrelease.io.case import load_case
from quickrelease.studies.planning import choices_figure, gap_figure, plan_case

# the case files of the repository's examples/ folder (the gallery runs this script in docs/examples/)
EXAMPLES = next((d / "examples" for d in (Path.cwd(), *Path.cwd().parents)
                 if (d / "examples" / "paper.toml").is_file()), None)
if EXAMPLES is None:  # a downloaded script or notebook, run outside a clone of the repository
    raise SystemExit("this example reads the case files and records of the quickrelease repository's examples/ "
                     "folder: run it from a clone of the repository, or from a folder that holds examples/")
plan = plan_case(load_case(EXAMPLES / "plan.toml"))
print(f"minimum gap {plan.clearance.min_gap * 1000:.1f} mm, contact: {plan.clearance.contact}")

# %%
# The push each fuse and angle releases, with the scatter of the steel's rupture strength.
fig = choices_figure(plan.fuse)

# %%
# The gap between the device's head and the building after the release.
fig = gap_figure(plan.clearance)
