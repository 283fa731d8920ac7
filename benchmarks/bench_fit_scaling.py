"""Cost of the release model and of a whole fit against the record length (issue 9, item 11).

Run: python benchmarks/bench_fit_scaling.py [--full] [--fit] [--rows N]

Records of 1e5, 1e6 (and with --full 1e7) rows are made here by the package's synth (examples/paper.toml,
channels u, v, a_head; the sampling rate set so the record has the number of rows). Printed per size:
seconds per model evaluation (the tabulated path of ``release_channels``, and the exact path that inverts
the time map at every time, for the 1e5 record only) and, with --fit, seconds per whole fit; each also per
row, and as a ratio against the 1e5 record measured in the same run. Linear cost: the ratio per row stays
near 1 as the record grows.

Each whole fit runs in a process of its own (``--rows N``: make the record, fit it once) so that its peak
resident memory is its own: printed are the peak RSS after making the record (the record and the package)
and at the end of the fit (the fit's own memory is the difference). synth's size check is lifted for these
in-memory records: it budgets 400 B per sample and column for writing files (1e7 rows of 3 channels: 15 GiB),
while the record in memory takes about 130 B per row (1e7 rows: 1.4 GB peak RSS).
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

from quickrelease.device.solvers import FirstIntegral
from quickrelease.io.case import load_case
from quickrelease.io.records import release_channels
from quickrelease.studies.fit import fit_record
from quickrelease.studies.synth import synthesize

EXAMPLES = Path(__file__).parent.parent / "examples"


def timed(func, repeat: int = 3) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        func()
        best = min(best, time.perf_counter() - t0)
    return best


def peak_rss() -> float:
    """Peak resident memory of this process so far [GB] (Linux: ru_maxrss in KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 / 1e9


def make_record(case, n: int, duration: float):
    import quickrelease.studies.synth as synth

    synth.check_size = lambda *args, **kwargs: None  # see the module docstring
    return synthesize(case, ["u", "v", "a_head"], rate=n / duration, duration=duration, seed=1).record()


def one_fit(case, n: int, duration: float) -> None:
    """Make the record of n rows, fit it once; print a JSON line: rows, seconds, evaluations, peak RSS."""
    record = make_record(case, n, duration)
    rss_record = peak_rss()
    t0 = time.perf_counter()
    result = fit_record(case, record)
    seconds = time.perf_counter() - t0
    print(json.dumps({"rows": int(record.t.size), "seconds": seconds, "nfev": result.nfev,
                      "rss_record_GB": rss_record, "rss_peak_GB": peak_rss()}))


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--full", action="store_true", help="also 1e7 rows")
    parser.add_argument("--fit", action="store_true", help="also time whole fits")
    parser.add_argument("--rows", type=float, help="only: one whole fit of this many rows, as a JSON line")
    args = parser.parse_args()
    case = load_case(EXAMPLES / "paper.toml")
    duration = 2.2  # release at 0.5 s, t_F ~ 1.05 s, then at rest
    if args.rows:
        one_fit(case, int(args.rows), duration)
        return
    sizes = [10**5, 10**6] + ([10**7] if args.full else [])
    base = {}
    print(f"{'rows':>10s} {'what':34s} {'seconds':>10s} {'us/row':>9s} {'per row vs 1e5':>15s}")
    for n in sizes:
        record = make_record(case, n, duration)
        d = case.device
        F1, F2 = 419.85, 804.57
        fi = FirstIntegral(case.stored_energy, case.alpha0, F1, F2, d.m1, d.m2, d.L1, case.mass_factor)
        names, t, window = list(record.channels), record.t, record.sampling_interval()

        def model(fi=fi, names=names, t=t, window=window, exact=False):
            # a fresh release per evaluation, as in a fit (its tables are built per parameter vector)
            f = FirstIntegral(fi.E_S, fi.alpha0, fi.F1, fi.F2, fi.m1, fi.m2, fi.L1, fi.c)
            return release_channels(names, t, 0.5, f, window, exact=exact)

        rows = [("model evaluation", timed(model))]
        if n == sizes[0]:
            rows.append(("model evaluation, exact path", timed(lambda: model(exact=True), repeat=1)))
        del record
        fitted = None
        if args.fit:  # in a process of its own: see the module docstring
            out = subprocess.run([sys.executable, __file__, "--rows", str(n)], check=True, capture_output=True,
                                 text=True)
            fitted = json.loads(out.stdout.strip().splitlines()[-1])
            rows.append((f"whole fit ({fitted['nfev']} evaluations)", fitted["seconds"]))
        for what, seconds in rows:
            per_row = seconds / t.size
            key = what.split(" (")[0]
            base.setdefault(key, per_row)
            print(f"{t.size:10d} {what:34s} {seconds:10.3f} {1e6 * per_row:9.3f} {per_row / base[key]:14.2f}x",
                  flush=True)
        if fitted:
            print(f"{'':10s} {'  peak RSS: record / whole fit':34s} {fitted['rss_record_GB']:8.2f} GB "
                  f"{fitted['rss_peak_GB']:6.2f} GB", flush=True)


if __name__ == "__main__":
    main()
