"""Batch kernels on the bench and the wide sample vs scipy (solve_ivp; quad + brentq) in the same run, accuracy
vs mpmath, one core vs all cores, the targets of issue 12, uq 1e8 on Dask.

Run: python benchmarks/bench_batch.py [--quick]   (the same as: quickrelease bench [--quick] [--json])
"""

import json
import sys

from quickrelease.studies.bench import run_bench

if __name__ == "__main__":
    result = run_bench(quick="--quick" in sys.argv, log=lambda line: print(line, file=sys.stderr))
    print(json.dumps(result, indent=2))
