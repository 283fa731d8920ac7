"""Digits follow the uncertainty (issue 22, item 23): an estimate, its standard error and its interval are
printed to one decimal place, where the error (else the interval's half-width) shows two significant digits.
Every expected string below is written by hand from that rule."""

import pytest

from quickrelease.report.display import estimate_row, fixed, places_for, same_places

#: The building's period of examples/building.toml: 2.00008 s, 95% interval [2.00002, 2.00014] s.
T, LO, HI = 2.000080211619833, 2.0000236160448783, 2.0001368071947874


def test_places_follow_two_digits_of_the_width():
    assert places_for(5.66e-5) == 6      # 5.7e-5: the 7 is in the 6th place
    assert places_for(0.398) == 2        # 0.40
    assert places_for(0.996) == 1        # 1.0 after rounding: one place, not two
    assert places_for(996.0) == -2       # 1000: hundreds
    assert places_for(24.0) == 0
    assert fixed(223.0, -2) == "200" and fixed(-0.0001, 2) == "0.00" and fixed(2.0000802, 6) == "2.000080"


def test_the_building_period_is_not_printed_as_2_0001_in_an_interval_of_2_0000_and_2_0001():
    # half-width (HI - LO) / 2 = 5.66e-5 -> 5.7e-5 -> 6 decimal places
    assert estimate_row("period", T, None, (LO, HI), "s") == (
        "period T", "2.000080 s", "-", "[2.000024, 2.000137] s")
    # with a standard error of 2.9e-5 s: the same 6 places, the error written with them
    assert estimate_row("period", T, 2.9e-5, (LO, HI), "s") == (
        "period T", "2.000080 s", "0.000029 s", "[2.000024, 2.000137] s")


@pytest.mark.parametrize("args, expected", [
    (("F1", 420.023, 0.398, (419.243, 420.803)), ("420.02 N", "0.40 N", "[419.24, 420.80] N")),
    (("friction", 156880.5, 24.0, (156833.1, 156927.9)), ("156.881 kN", "0.024 kN", "[156.833, 156.928] kN")),
    (("F1", 223.0, 996.0, (-1700.0, 2200.0)), ("200 N", "1000 N", "[-1700, 2200] N")),
    (("damping_ratio", 0.05000903, None, (0.04997054, 0.05004752)), ("0.050009", "-", "[0.049971, 0.050048]")),
    (("offset_x", 0.00079942, 1.9e-6, (0.00079563, 0.00080321), "m"),
     ("0.0007994 m", "1.9e-6 m", "[0.0007956, 0.0008032] m")),
])
def test_estimate_rows(args, expected):
    assert estimate_row(*args)[1:] == expected


def test_without_an_uncertainty_five_significant_digits():
    assert same_places([2.000080211619833], None) == ["2.0001"]
    assert same_places([2.0, None], 0.05) == ["2.000", "-"]


def test_the_report_tables_follow_the_interval(tmp_path):
    from quickrelease.report.html import _estimate

    assert _estimate(T, None, [LO, HI]) == ("2.000080", "&ndash;", "[2.000024, 2.000137]")
    assert _estimate(156880.5, 24.0, [156833.1, 156927.9], 1e-3) == ("156.881", "0.024", "[156.833, 156.928]")


def test_the_clearance_note_names_its_units():
    from quickrelease.workflow import clearance_words

    words = clearance_words({"damping_ratio": 0.05000903, "friction": 156880.5, "mass": 800000.0,
                             "displacement": 0.1824962791574022, "period": T},
                            {"period": 2.9e-5, "damping_ratio": 2.0e-5, "friction": 24.0, "d0": 2.8e-6})
    assert words == ("period T = 2.000080 s, damping ratio zeta = 0.050009, slider friction F_s = 156.881 kN, "
                     "mass = 800 t, pushed displacement d0 = 182.4963 mm")
