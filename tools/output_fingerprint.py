"""Fingerprints of what the shipped examples write: proof that a refactoring changed no output.

Runs the command line (``python -m quickrelease``, the interpreter running this script) on the shipped
examples (demo, run, building, fit, uq with a fixed seed, sweep, plan, campaign, synth, simulate and
identify) in a temporary folder and prints one line per output: the sha256 of the JSON summaries (files and
``--json`` stdout), the CSV tables and the NetCDF time histories, after removing only what legitimately
changes from one run to the next:

- JSON: keys naming a time of day or a duration of the run (``created``, ``timestamp``, ``date``,
  ``elapsed*``, ``wall*``), and the temporary folder's path inside any string (replaced by ``<TMP>``; the
  repository's path by ``<REPO>``);
- CSV: lines starting with ``#`` that carry a version, a path or a time (none are written today);
- NetCDF: opened with xarray; the hash covers every variable's and coordinate's name, dtype, shape, bytes
  and attributes, and the global attributes less the keys above.

Figures (PNG/SVG) and report.html are not compared (matplotlib writes its version and dates into them).

Usage::

    python tools/output_fingerprint.py > before.txt       # on main
    python tools/output_fingerprint.py > after.txt        # on the branch
    diff before.txt after.txt                             # nothing: the outputs are bit-identical
"""

from __future__ import annotations

import hashlib
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
EX = REPO / "examples"

#: keys whose values change from run to run (times, durations, versions, the machine)
VOLATILE = re.compile(r"^(created|timestamp|date|elapsed.*|wall.*|.*_elapsed.*|.*_wall_s)$")

#: (name, arguments; OUT is replaced by the output path in the temporary folder)
COMMANDS: list[tuple[str, list[str]]] = [
    ("demo", ["demo", "--out", "OUT"]),
    ("demo-json", ["demo", "--out", "OUT", "--json"]),
    ("run-paper", ["run", str(EX / "paper.toml"), "--out", "OUT"]),
    ("run-paper-json", ["run", str(EX / "paper.toml"), "--out", "OUT", "--json"]),
    ("run-whole-test", ["run", str(EX / "building.toml"), "--out", "OUT"]),
    ("run-larger-push", ["run", str(EX / "larger_push.toml"), "--out", "OUT"]),
    ("fit-stop-scatter", ["fit", str(EX / "stop_scatter.toml"), "--out", "OUT", "--json"]),
    ("building", ["building", str(EX / "building.toml"), "--out", "OUT", "--json"]),
    ("fit", ["fit", str(EX / "fit.toml"), "--out", "OUT", "--json"]),
    ("uq", ["uq", str(EX / "uq_paper.toml"), "--samples", "20000", "--seed", "7", "--out", "OUT", "--json"]),
    ("sweep", ["sweep", str(EX / "larger_push.toml"), "--grid", "force=500 kN:3000 kN:6",
               "--grid", "alpha0=0.1:0.5:5", "--out", "OUT/sweep.nc", "--json"]),
    ("plan", ["plan", str(EX / "plan.toml"), "--out", "OUT", "--json"]),
    ("campaign", ["campaign", str(EX / "campaign.toml"), "--out", "OUT", "--json"]),
    ("synth", ["synth", str(EX / "paper.toml"), "--channels", "u,v", "--rate", "500Hz", "--seed", "3",
               "--out", "OUT/rec.csv"]),
    ("simulate", ["simulate", "--force", "1598 kN", "--alpha0", "11.46 deg", "--f1", "0.42 kN", "--f2", "0.80 kN",
                  "--method", "rk", "--json"]),
    ("identify", ["identify", "--energy", "2.90 kJ", "--alpha0", "0.2", "--alpha-final", "0.7378",
                  "--stop-time", "1.05 s", "--json"]),
]

#: heavier: the building campaign (five building fits); run with --all
HEAVY: list[tuple[str, list[str]]] = [
    ("building-campaign", ["campaign", str(EX / "building_campaign.toml"), "--out", "OUT", "--json"]),
]


def _clean(value, tmp: str):
    if isinstance(value, dict):
        return {k: _clean(v, tmp) for k, v in value.items() if not VOLATILE.match(str(k))}
    if isinstance(value, list):
        return [_clean(v, tmp) for v in value]
    if isinstance(value, str):
        return value.replace(tmp, "<TMP>").replace(str(REPO), "<REPO>")
    return value


def _hash_json(text: str, tmp: str) -> str:
    data = _clean(json.loads(text), tmp)
    return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()


def _hash_csv(path: Path, tmp: str) -> str:
    lines = path.read_bytes().decode().splitlines(keepends=True)
    keep = [ln.replace(tmp, "<TMP>") for ln in lines
            if not (ln.startswith("#") and re.search(r"version|created|\d{4}-\d\d-\d\dT", ln))]
    return hashlib.sha256("".join(keep).encode()).hexdigest()


def _hash_nc(path: Path, tmp: str) -> str:
    import numpy as np
    import xarray as xr

    h = hashlib.sha256()
    with xr.open_dataset(path) as ds:
        ds.load()
        for name in sorted(ds.variables):
            var = ds.variables[name]
            values = np.ascontiguousarray(var.values)
            h.update(f"{name}|{values.dtype}|{values.shape}|".encode())
            h.update(values.tobytes() if values.dtype != object else repr(values.tolist()).encode())
            h.update(json.dumps(_clean({k: _plain(v) for k, v in var.attrs.items()}, tmp), sort_keys=True).encode())
        h.update(json.dumps(_clean({k: _plain(v) for k, v in ds.attrs.items()}, tmp), sort_keys=True).encode())
    return h.hexdigest()


def _plain(v):
    import numpy as np

    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, np.generic):
        return v.item()
    return v


def fingerprints(commands: list[tuple[str, list[str]]]) -> list[str]:
    """One line per output: ``<command>/<file> <sha256>`` (``stdout`` for a --json command's output)."""
    lines = []
    with tempfile.TemporaryDirectory(prefix="qr_fp_") as tmp:
        for name, args in commands:
            out = Path(tmp) / name
            argv = [a.replace("OUT", str(out)) for a in args]
            if any(a.endswith((".nc", ".csv")) for a in argv):
                out.mkdir(parents=True)
            proc = subprocess.run([sys.executable, "-m", "quickrelease", *argv], cwd=tmp, capture_output=True,
                                  text=True, env={"PYTHONHASHSEED": "0", "MPLBACKEND": "Agg",
                                                  "PATH": "/usr/bin:/bin", "HOME": tmp})
            if proc.returncode != 0:
                lines.append(f"{name}/EXIT {proc.returncode} {proc.stderr.strip().splitlines()[-1:]}")
                continue
            if "--json" in argv:
                lines.append(f"{name}/stdout {_hash_json(proc.stdout, tmp)}")
            if out.exists():
                for path in sorted(out.rglob("*")):
                    rel = f"{name}/{path.relative_to(out)}"
                    if path.suffix == ".json":
                        lines.append(f"{rel} {_hash_json(path.read_text(), tmp)}")
                    elif path.suffix == ".csv":
                        lines.append(f"{rel} {_hash_csv(path, tmp)}")
                    elif path.suffix == ".nc":
                        lines.append(f"{rel} {_hash_nc(path, tmp)}")
    return lines


def main() -> None:
    commands = COMMANDS + (HEAVY if "--all" in sys.argv[1:] else [])
    for line in fingerprints(commands):
        print(line, flush=True)


if __name__ == "__main__":
    main()
