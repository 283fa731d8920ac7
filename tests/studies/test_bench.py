"""quickrelease bench: both samples, the JSON schema, the status lines, the conditioning; tiny sizes (CI time)."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from quickrelease.batch.sampling import WIDE_STRATA
from quickrelease.cli import app
from quickrelease.studies import bench

TINY = bench.Sizes(cases=3000, stop_time=2, identify=1, repeat=1, strata_conditioning=False,
                   case_conditioning=False)


LOG: list[str] = []


@pytest.fixture(scope="module")
def result():
    return bench.run_bench(quick=True, sizes=TINY, log=LOG.append)


GROUP_KEYS = {"cases", "cases_per_s", "cpu_cases_per_s", "all_cores_cases_per_s", "all_cores_cpu_cases_per_s",
              "all_cores_ratio", "all_cores_identical", "accuracy_cases", "median_rel_error", "max_rel_error",
              "worst_case_sensitivity_1ulp", "worst_case_condition_1ulp", "backward_median_ulps", "backward_max_ulps",
              "max_error_over_allowed"}


def test_json_schema_groups_both_samples(result):
    assert {"bench", "wide", "targets", "threads", "quick", "seed"} <= result.keys()
    assert "uq_dask" not in result  # quick: no Dask run
    from quickrelease.batch._gpu import gpu_available

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
    g = result["wide"]["stop_time"]
    med, over = g["median_rel_error"], g["max_error_over_allowed"]
    assert acc["status"] == ("met" if med <= 1e-12 and over <= 1 else "not met")
    assert acc["value"] == [med, g["max_rel_error"], over]
    # without the condition number of every case (TINY): no backward error, the target still decided
    assert g["backward_max_ulps"] is None and 0 <= over <= g["max_rel_error"] / 1e-10
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
    (tests/batch/test_batch.py); a typical release by a few ulps."""
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
    from quickrelease.batch.sampling import random_releases

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


def _synthetic_summary(case_conditioning, calls):
    """_accuracy_summary on made-up errors and 1-ulp changes: two cases a stratum of the wide sample."""
    n = 2 * len(WIDE_STRATA)
    stratum = np.repeat(np.arange(len(WIDE_STRATA)), 2)
    err = np.full(n, 2e-16)
    err[0], err[1] = 0.0, 5e-11  # typical: exact, and 5e-11 on a well-conditioned case (under the 1e-10 floor)
    err[2], err[3] = 3e-10, 1e-9  # limit: 3e-10 and 1e-9 (the worst)
    err[5] = np.nan  # no reference for it: left out
    # per input one-ulp changes: 1e-16 on each of 7 inputs (condition 7e-16); the limit's cases condition 2e-10
    sens = {i: np.full(7, 1e-16) for i in range(n)}
    sens[2] = np.array([1e-10, 0, 0, 0, 0, 0, 1e-10])  # 3e-10 is 1.5 ulps, allowed 4 x 2e-10
    sens[3] = np.array([2e-10, 0, 0, 0, 0, 0, 0])  # 1e-9 is 5 ulps, allowed 8e-10: 1.25 times too much

    def sensitivities(i):
        calls.append(i)
        return sens[i]

    sizes = bench.Sizes(cases=1, stop_time=2, identify=2, strata_conditioning=False, case_conditioning=case_conditioning)
    return bench._accuracy_summary("wide", stratum, err, np.full(n, 1e-8), np.full(n, 1e-3), "solve_ivp",
                                   sensitivities, sizes, lambda line: None)


def test_backward_error_is_the_error_over_the_1ulp_condition_number():
    """Backward error in ulps = error / (sum over the inputs of the change one ulp of each makes), and the target's
    allowance max(1e-10, 4 x that sum), by hand."""
    calls = []
    out = _synthetic_summary(True, calls)
    assert sorted(calls) == [i for i in range(2 * len(WIDE_STRATA)) if i != 5]  # every case with an error
    assert out["worst_case_sensitivity_1ulp"] == 2e-10 and out["worst_case_condition_1ulp"] == 2e-10
    rows = {row["stratum"]: row for row in out["strata"]}
    assert rows["limit"]["backward_max_ulps"] == pytest.approx(5.0)
    assert rows["limit"]["backward_median_ulps"] == pytest.approx(0.5 * (1.5 + 5.0))
    assert rows["typical"]["backward_max_ulps"] == pytest.approx(5e-11 / 7e-16)
    assert rows["typical"]["backward_median_ulps"] == pytest.approx(0.5 * (0.0 + 5e-11 / 7e-16))
    assert rows["small mass factor"]["backward_median_ulps"] == pytest.approx(2 / 7)
    assert rows["short of the limit"]["cases"] == 1  # the case without a reference is left out
    assert rows["limit"]["sensitivity_1ulp"] == 2e-10  # the most over the inputs, at the stratum's worst
    assert out["backward_max_ulps"] == pytest.approx(5e-11 / 7e-16)
    assert out["backward_median_ulps"] == pytest.approx(2 / 7)  # most of the weight: the 2e-16 cases
    # allowed max(1e-10, 4 x condition): 5e-11 of 1e-10, 3e-10 of 8e-10, 1e-9 of 8e-10 (not met)
    assert out["max_error_over_allowed"] == pytest.approx(1.25)
    assert bench._accuracy_status(out["median_rel_error"], out["max_error_over_allowed"]) == "not met"
    assert bench._accuracy_status(2e-16, 0.5) == "met" and bench._accuracy_status(2e-16, 1.0) == "met"
    assert bench._accuracy_status(2e-12, 0.5) == "not met" and bench._accuracy_status(None, 0.5) == "not measured"


def test_without_every_condition_number_only_the_worst_and_those_above_1e10():
    calls = []
    out = _synthetic_summary(False, calls)
    assert sorted(calls) == [2, 3]  # the worst (3) and the other case above the 1e-10 floor (2)
    assert out["backward_median_ulps"] is None and out["backward_max_ulps"] is None
    assert out["max_error_over_allowed"] == pytest.approx(1.25)  # the target is decided all the same
    assert all(row["backward_max_ulps"] is None for row in out["strata"])


def test_stop_sensitivities_one_per_input_and_exact_in_m2():
    """t_F is proportional to sqrt(m2) (Eq. 10): one ulp of m2 moves it by half of m2's relative ulp, exactly."""
    args = (2900.0, 0.2, 419.85, 804.57, 2 / 3 * 576.78 / 531.69, 531.69, 2.477)
    s = bench._stop_sensitivities(args)
    assert s.shape == (7,) and np.all(s > 0)
    assert s[5] == pytest.approx(0.5 * (np.nextafter(531.69, np.inf) - 531.69) / 531.69, rel=1e-9, abs=0)


@pytest.mark.slow
def test_identify_sensitivities_agree_with_solving_again():
    """The first-order change of (F1, F2) per input against mpmath's identification solved again with that input one
    ulp up: on a typical case (every input; lambda and F1*, F2* move by a few 1e-16 alike) and on a nearly immediate
    stop (one ulp of alpha_F moves F1 by ~1e-7 of F1*; the three inputs that matter most)."""
    from quickrelease import batch
    from quickrelease.batch.sampling import wide_releases
    from quickrelease.device.reference import identify_lambda_mp

    draw = wide_releases(400, seed=3, strata=True)
    st = batch.stop_time(*(draw[k] for k in bench._KEYS))
    names = [s for s, _, _ in WIDE_STRATA]
    for stratum, inputs, least in (("typical", range(7), 0.0), ("immediate stop", (1, 2, 3), 1e-9)):
        i = int(np.flatnonzero((draw["stratum"] == names.index(stratum)) & (st.stopped_by == 0))[0])
        args = (float(draw["alpha0"][i]), float(st.alpha_final[i]), float(st.stop_time[i]), float(draw["E_S"][i]),
                bench._k(draw, i), float(draw["m2"][i]), float(draw["L1"][i]))
        lam, F1s, F2s = identify_lambda_mp(*args)
        got = bench._identify_sensitivities(args, lam)
        for j in inputs:
            moved = list(args)
            moved[j] = float(np.nextafter(args[j], np.inf))
            lm, F1m, F2m = identify_lambda_mp(*moved, start=float(lam * F1s))
            want = max(float(abs(lm * F1m - lam * F1s) / F1s), float(abs((1 - lm) * F2m - (1 - lam) * F2s) / F2s))
            assert got[j] == pytest.approx(want, rel=1e-3, abs=0), (stratum, j)
        assert got.max() > least  # the immediate stop ill-conditioned: far above the 1e-16 of a typical case


def test_cli_bench_tables_readable_at_80_columns(result, monkeypatch):
    """At 80 columns (a terminal's default, and what a pipe gets): no line wider, no cell cut short with an
    ellipsis, every stratum's numbers whole (the ten-column table by stratum cut every cell), every target line
    there (wrapped, indented)."""
    monkeypatch.setattr(bench, "run_bench", lambda quick, threads, log: result)
    r = CliRunner().invoke(app, ["bench"], env={"COLUMNS": "80"})
    assert r.exit_code == 0, r.output
    lines = r.stdout.splitlines()
    assert max(len(line) for line in lines) <= 80
    assert "…" not in r.stdout
    for key in ("stop_time", "identify"):
        for row in result["wide"][key]["strata"]:
            value = row["median_rel_error"]
            if value is not None:
                text = f"{value:.1e}".replace("e-0", "e-").replace("e+0", "e").replace("e+", "e")
                assert text in r.stdout, (key, row["stratum"], text)
    starts = [line for line in lines if line.strip().startswith(("met:", "not met:", "not measured:"))]
    assert len(starts) == len(result["targets"])
