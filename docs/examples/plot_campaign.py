"""
A friction campaign: friction against load and angle
====================================================

``quickrelease campaign examples/campaign.toml``: six releases of the paper's device at different push
forces and angles, each fitted to its record, then the laws F = a + b x fitted by weighted least squares
with their 95% confidence bands. The records are synthetic, made with F1 = 150 N + 0.17 N/kN P and
F2 = 805 N (a law chosen for the demonstration, not a measurement).
"""

from pathlib import Path

from quickrelease.studies.campaign import campaign_figure, run_campaign

# the case files of the repository's examples/ folder (the gallery runs this script in docs/examples/)
EXAMPLES = next((d / "examples" for d in (Path.cwd(), *Path.cwd().parents)
                 if (d / "examples" / "paper.toml").is_file()), None)
if EXAMPLES is None:  # a downloaded script or notebook, run outside a clone of the repository
    raise SystemExit("this example reads the case files and records of the quickrelease repository's examples/ "
                     "folder: run it from a clone of the repository, or from a folder that holds examples/")
camp = run_campaign(EXAMPLES / "campaign.toml")
law = camp.laws[("F1", "force")]
print(f"F1 against the push force: p = {law.p_value:.2g}")

fig = campaign_figure(camp)
