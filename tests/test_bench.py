"""quickrelease bench: both samples, the JSON schema, the status lines, the conditioning; tiny sizes (CI time)."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from quickrelease import bench
from quickrelease.cli import app
from quickrelease.sampling import WIDE_STRATA

TINY = bench.Sizes(cases=3000, stop_time=2, identify=1, repeat=1, strata_conditioning=False)


LOG: list[str] = []


@pytest.fixture(scope="module")
def result():
    return bench.run_bench(quick=True, sizes=TINY, log=LOG.append)


GROUP_KEYS = {"cases", "cases_per_s", "cpu_cases_per_s", "all_cores_cases_per_s", "all_cores_cpu_cases_per_s",
              "all_cores_ratio", "all_cores_identical", "accuracy_cases", "median_rel_error", "max_rel_error",
              "worst_case_sensitivity_1ulp"}


def test_json_schema_groups_both_samples(result):
    assert {"bench", "wide", "targets", "threads", "quick", "seed"} <= result.keys()
    assert "uq_dask" not in result  # quick: no Dask run
    from quickrelease._gpu import gpu_available

    assert "gpu" in result and (result["gpu"] is None) == (not gpu_available())  # the GPU section: null without one
    json.dumps(result, allow_nan=False)  # what --json prints: no NaN, no numpy scalars
    for sample, draw in (("bench", "sampling.random_releases"), ("wide", "sampling.wide_releases")):
        g = result[sample]
        assert g["sample"] == draw
        for kernel, base in (("stop_time", "solve_ivp"), ("identify", "quad_brentq")):
            assert GROUP_KEYS | {f"{base}_cases_per_s", f"speedup_vs_{base}", f"{base}_median_rel_error",
                                 f"{base}_max_rel_error", f"{base}_failures"} <= g[kernel].keys(), (sample, kernel)
            k = g[kernel]
            assert k["cases_per_s"] > 0 and k["all_cores_identical"] is True
            assert k["speedup_vs_" + base] == pytest.approx(k["cases_per_s"] / k[f"{base}_cases_per_s"])
            assert 0 <= k["median_rel_error"] <= k["max_rel_error"] < 1e-8
    assert result["bench"]["stop_time"]["cases"] == 3000
    assert result["bench"]["stop_time"]["accuracy_cases"] == 2


def test_wide_sample_reports_every_stratum_and_names_the_worst(result):
    st = result["wide"]["stop_time"]
    assert [row["stratum"] for row in st["strata"]] == [name for name, _, _ in WIDE_STRATA]
    assert all(row["cases"] == 2 for row in st["strata"])  # every stratum has stop times
    assert st["accuracy_cases"] == 2 * len(WIDE_STRATA)
    worst = max(st["strata"], key=lambda row: row["max_rel_error"])
    assert st["worst_stratum"] == worst["stratum"] and st["max_rel_error"] == worst["max_rel_error"]
    # the conditioning is given for the worst stratum (and, with these sizes, only there)
    assert worst["sensitivity_1ulp"] == st["worst_case_sensitivity_1ulp"] > 0
    assert all(row["sensitivity_1ulp"] is None for row in st["strata"] if row is not worst)
    ident = result["wide"]["identify"]
    limit = [row for row in ident["strata"] if row["stratum"] == "limit"][0]
    assert limit["cases"] == 0 and limit["max_rel_error"] is None  # the flat rhombus first: nothing to identify


def test_one_status_line_per_target(result):
    targets = {t["target"]: t for t in result["targets"]}
    expected = {key for key, *_ in bench.TARGETS} | {f"{k}_accuracy_{s}" for k in ("stop_time", "identify")
                                                     for s in ("bench", "wide")} | {"two_cores_bench", "two_cores_wide"}
    assert targets.keys() == expected
    assert all(t["status"] in ("met", "not met", "not measured") for t in targets.values())
    for key, _, sample, what, bound in bench.TARGETS:
        group, name = what.split(".")
        value = result[sample][group][name]
        assert targets[key]["value"] == value
        assert targets[key]["status"] == ("met" if value >= bound else "not met")
    acc = targets["stop_time_accuracy_wide"]
    med, worst = result["wide"]["stop_time"]["median_rel_error"], result["wide"]["stop_time"]["max_rel_error"]
    assert acc["status"] == ("met" if med <= 1e-12 and worst <= 1e-10 else "not met")
    assert f"in '{result['wide']['stop_time']['worst_stratum']}'" in acc["text"]
    ratio = min(result["bench"]["stop_time"]["all_cores_ratio"], result["bench"]["identify"]["all_cores_ratio"])
    two = targets["two_cores_bench"]
    assert two["value"] == ratio
    assert two["status"] == ("not measured" if result["threads"] < 2 else "met" if ratio >= 1.8 else "not met")


def test_status_follows_the_bounds():
    assert bench._status(1e7, 1e7, True) == "met" and bench._status(9.9e6, 1e7, True) == "not met"
    assert bench._status(None, 1.0, True) == "not measured"


def test_weighted_median_weighs_the_strata_by_their_shares():
    values = np.array([1.0, 2.0, 3.0, 100.0])
    assert bench._weighted_median(values, np.ones(4)) == 2.0
    assert bench._weighted_median(values, np.array([0.1, 0.1, 0.1, 0.7])) == 100.0
    # two strata of two cases each, shares 0.9 and 0.1: the median lies in the first stratum
    err = np.array([1e-16, 2e-16, 1e-11, 2e-11])
    shares = dict((name, s) for name, s, _ in WIDE_STRATA)
    stratum = np.array([0, 0, 1, 1])  # typical (0.20) and limit (0.15): the median is a typical case's
    assert shares["typical"] > shares["limit"]
    assert bench._stats(err, stratum, "wide") == (2e-16, 2e-11)


def test_sensitivity_of_an_ill_conditioned_stop():
    """A stop within ~1e-6 rad of pi/2 with almost no rail friction: one ulp of E_S moves t_F by more than 1e-7
    (tests/test_batch.py); a typical release by a few ulps."""
    hard = (2496.7064827214417, 0.9878228096162034, 2737.145215750118, 0.0005289992104389708, 0.2508887330655966,
            1839.7073266913917, 2.76125386875275)
    assert bench._stop_sensitivity(hard) > 1e-7
    assert bench._stop_sensitivity((2900.0, 0.2, 419.85, 804.57, 2 / 3 * 576.78 / 531.69, 531.69, 2.477)) < 1e-15


def test_progress_during_the_mpmath_phase(result):
    assert any("stop times against mpmath" in line for line in LOG)
    assert any("identifications against mpmath" in line for line in LOG)


def test_cli_bench_json_and_table(result, monkeypatch):
    """The command passes --quick and --threads on, prints the JSON object or the tables with one line per target,
    and the progress on stderr (the run itself: the fixture's, to keep the CI short)."""
    calls = []

    def spy(quick, threads, log):
        calls.append((quick, threads))
        log("progress line")
        return result

    monkeypatch.setattr(bench, "run_bench", spy)
    runner = CliRunner()
    r = runner.invoke(app, ["bench", "--quick", "--json", "--threads", "1"])
    assert r.exit_code == 0, r.output
    assert calls == [(True, 1)] and json.loads(r.stdout) == result
    assert r.stderr == "progress line\n"
    r = runner.invoke(app, ["bench"], env={"COLUMNS": "160"})
    assert r.exit_code == 0, r.output
    assert calls[-1] == (False, None)
    assert "wide sample by stratum" in r.stdout and "short of the limit" in r.stdout
    from quality import table_faults  # tables for people (issue 11)

    assert table_faults(r.stdout) == []
    lines = [line for line in r.stdout.splitlines() if line.strip().startswith(("met:", "not met:", "not measured:"))]
    assert len(lines) == len(result["targets"])
    if result["gpu"] is None:  # no GPU here: one line says so
        assert "GPU: none found" in r.stdout
    row = {"cases": 10, "stop_time_cases_per_s": 6.6e9, "stop_time_end_to_end_cases_per_s": 1e8, "identify_cases": 9,
           "identify_cases_per_s": 2e9, "identify_end_to_end_cases_per_s": 5e7, "stop_time_max_rel_diff": 4e-16,
           "alpha_final_max_rel_diff": 0.0, "stopped_by_identical": True, "identify_ends_max_rel_diff": 1e-15,
           "identify_F1_max_diff_over_tolerance": 0.2, "identify_status_identical": True}
    gpu = {"device": "NVIDIA H100 80GB HBM3", "cupy": "13.3.0", "bench": row, "wide": row}
    monkeypatch.setattr(bench, "run_bench", lambda quick, threads, log: {**result, "gpu": gpu})
    r = runner.invoke(app, ["bench"], env={"COLUMNS": "160"})
    assert r.exit_code == 0, r.output
    assert "gpu backend on NVIDIA H100 80GB HBM3" in r.stdout and "6,600,000,000" in r.stdout
    assert table_faults(r.stdout) == [] and "GPU: none found" not in r.stdout


def test_cli_bench_refuses_bad_threads():
    r = CliRunner().invoke(app, ["bench", "--quick", "--threads", "0"])
    assert r.exit_code == 2 and r.stderr.strip().startswith("error: --threads = 0 is outside integers in [1,")


def test_one_core_means_one_cpu_and_one_thread():
    import os

    import numba

    before = numba.get_num_threads()
    with bench._one_core():
        assert numba.get_num_threads() == 1
        if hasattr(os, "sched_getaffinity"):
            assert len(os.sched_getaffinity(0)) == 1
    assert numba.get_num_threads() == before


def test_same_bytes_means_bytes():
    from quickrelease.batch import BatchStop

    a = BatchStop(np.array([0.0, 1.0]), np.array([1.0, 1.5]), np.array([0, 1], dtype=np.int8))
    b = BatchStop(np.array([-0.0, 1.0]), np.array([1.0, 1.5]), np.array([0, 1], dtype=np.int8))  # equal, not same
    assert bench._same_bytes(a, a) and not bench._same_bytes(a, b)


def test_a_kernel_that_depends_on_the_thread_count_is_caught(monkeypatch):
    """The all-cores measurement compares its results with one core's byte for byte: a kernel whose last bit
    depends on the thread count is reported (here a planted one)."""
    import numba

    from quickrelease import batch
    from quickrelease.sampling import random_releases

    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("numba may use one thread only here")
    real = batch.stop_time

    def planted(*args, **kwargs):
        r = real(*args, **kwargs)
        if numba.get_num_threads() > 1:
            r.stop_time[0] = np.nextafter(r.stop_time[0], np.inf)
        return r

    monkeypatch.setattr(batch, "stop_time", planted)
    out = bench._throughput(random_releases(500, seed=1), 2, repeat=1)
    assert out["stop_time"]["all_cores_identical"] is False and out["identify"]["all_cores_identical"] is True
    assert out["stop_time"]["all_cores_ratio"] == pytest.approx(out["stop_time"]["all_cores_cases_per_s"]
                                                                / out["stop_time"]["cases_per_s"])
