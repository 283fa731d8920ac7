"""The one setup of the friction identification (issue 23, item 4): sines, cosines, F1*, F2*, the tier ratios.

:func:`quickrelease.batch._identify_setup.identify_setup` is the setup of the three back-ends of the identification (the
compiled kernel ``_fast._identify_one``, the numpy reference ``batch._identify_chunk`` and the GPU back-end
``_gpu._identify_chunk``, run here on numpy). Checked here:

* the function, in each of its forms (Python floats, compiled by numba, elementwise on numpy arrays), against the
  paper's formulas written in this file and evaluated by mpmath: Eq. 11 and 12 as the paper writes them (differences
  of sines and cosines, where the function writes products), the tier ratios and the prefactor from their
  definitions;
* each back-end that runs here, end to end, on a handful of observations written in this file, one or two in each
  tier (the 16-node rule, the 24-node rule, the graded one; reached by alpha_F near pi/2 and by a small mass factor
  near the start), against mpmath (:func:`quickrelease.device.reference.line_time_mpf`, another substitution and another
  quadrature): F1* and F2*, the stop times at both ends of the line of Eq. 13, and lambda = F1/F1* of an observation
  whose t_F is mpmath's at lambda = 1/2;
* that each back-end calls the one function and states no setup of its own (no sine or cosine in its source), and
  that the compiled kernels' cache is stamped with the function's file.
"""

from __future__ import annotations

import ast
import inspect
import math
import textwrap
import types

import numpy as np
import pytest

from quickrelease import batch
from quickrelease.batch import _fast, _gpu, _identify_setup
from quickrelease.batch._identify_setup import identify_setup
from quickrelease.device.reference import line_time_mpf

mpmath = pytest.importorskip("mpmath")

EPS = np.finfo(float).eps
NAMES = ("sA", "cA", "sm", "c1", "c2", "F1max", "F2max", "ratio", "msq", "pref")

#: (alpha0 [rad], alpha_F [rad], E_S [J], c [-], m1 [kg], m2 [kg], L1 [m]), and the tier each exercises: the first is
#: Table 7's observation on the paper's device (Table 2); ratio = cos aF / cos((aF + a0) / 2), msq = (k + sin^2 a0) /
#: (aF - a0)^2, the tiers' thresholds those of ``_kernels`` (ratio 0.3 and 0.05, msq 1 and 1/16).
CASES = [
    (0.2, 0.7378, 2900.0, 2.0 / 3.0, 576.78, 531.69, 2.477),  # tier 0: ratio 0.83, msq 2.6
    (0.7, 1.0, 20000.0, 1.0, 1500.0, 1500.0, 2.0),  # tier 0, lumped mass: msq 16
    (0.3, 1.45, 5000.0, 0.4, 800.0, 800.0, 1.2),  # tier 1 by the ratio (0.19): alpha_F near pi/2
    (0.05, 0.5, 3000.0, 0.05, 900.0, 900.0, 1.5),  # tier 1 by the mass factor: msq 0.26
    (0.3, 1.55, 5000.0, 0.4, 800.0, 800.0, 1.2),  # tier 2 by the ratio (0.035)
    (0.02, 0.6, 3000.0, 0.005, 900.0, 900.0, 1.5),  # tier 2 by the mass factor: msq 0.016
]


def _k(case):
    a0, aF, E, c, m1, m2, L1 = case
    return c * m1 / m2  # as batch.identify computes it


def _paper(a0, aF, E, k, m2, L1):
    """The setup's quantities from the paper's formulas and their definitions, by mpmath (30 digits), the floats
    taken exactly."""
    mp = mpmath.mp
    mp.dps = 30
    a0, aF, E, k, m2, L1 = (mp.mpf(float(v)) for v in (a0, aF, E, k, m2, L1))
    mid, half = (aF + a0) / 2, (aF - a0) / 2
    return {
        "sA": mp.sin(aF), "cA": mp.cos(aF), "sm": mp.sin(half), "c1": mp.cos(mid), "c2": mp.sin(mid),
        "F1max": E / (2 * L1 * (mp.sin(aF) - mp.sin(a0))),  # Eq. 11
        "F2max": E / (4 * L1 * (mp.cos(a0) - mp.cos(aF))),  # Eq. 12
        # the remaining energy of pure hinge friction, (sin aF - sin alpha) / (sin aF - sin a0) over w^2 with
        # alpha = aF - (aF - a0) w^2, at the stop (w -> 0): (aF - a0) cos aF / (sin aF - sin a0) over (aF - a0) /
        # (2 sin((aF - a0)/2)), i.e. cos aF / cos((aF + a0)/2)
        "ratio": mp.cos(aF) / mp.cos(mid),
        "msq": (k + mp.sin(a0) ** 2) / (aF - a0) ** 2,
        "pref": 4 * mp.sin(half) * L1 * mp.sqrt(m2 / E),
    }


def _close(got, want, ulps: float) -> bool:
    return abs(float(got) - float(want)) <= ulps * EPS * abs(float(want))


# -- the function, in each form -------------------------------------------------------------------------------------

def _python(cases):
    return [identify_setup(case[0], case[1], case[2], _k(case), case[5], case[6]) for case in cases]


def _compiled(cases):
    return [_fast._identify_setup_one(case[0], case[1], case[2], _k(case), case[5], case[6]) for case in cases]


def _numpy(cases):
    a0, aF, E, c, m1, m2, L1 = (np.array(v) for v in zip(*cases, strict=True))
    out = _identify_setup.for_arrays(np)(a0, aF, E, c * m1 / m2, m2, L1)
    return [tuple(v[i] for v in out) for i in range(len(cases))]


@pytest.mark.parametrize("form", [_python, _compiled, _numpy], ids=["python", "numba", "numpy"])
def test_setup_as_the_papers_formulas(form):
    """Every quantity within 8 ulps of the paper's formula (the products the function takes lose no digits: the two
    terms of c1 have one sign, those of c2 cancel by at most a factor 2 on these cases)."""
    for case, got in zip(CASES, form(CASES), strict=True):
        want = _paper(case[0], case[1], case[2], _k(case), case[5], case[6])
        for name, value in zip(NAMES, got, strict=True):
            assert _close(value, want[name], 8), (case, name, float(value), float(want[name]))


def test_setup_forms_give_the_same_bits_for_the_same_library():
    """The compiled form is the Python one compiled (``math``'s sine and cosine in both): the same bits."""
    for py, nb in zip(_python(CASES), _compiled(CASES), strict=True):
        assert py == nb


# -- every back-end that runs here, end to end -----------------------------------------------------------------------

@pytest.fixture(scope="module")
def references():
    """(t(0), t(1/2), t(1)) on the line of Eq. 13, by mpmath, for each case [s] (about 1 s a case)."""
    return [tuple(line_time_mpf(lam, case[0], case[1], case[2], _k(case), case[5], case[6])[0]
                  for lam in (0, mpmath.mpf(1) / 2, 1)) for case in CASES]


def _compiled_back_end(a0, aF, tF, E, c, m1, m2, L1):
    r = batch.identify(a0, aF, tF, E, c, m1, m2, L1)
    return {key: getattr(r, key) for key in ("F1", "F1_max", "F2_max", "stop_time_min", "stop_time_max", "status")}


def _numpy_back_end(a0, aF, tF, E, c, m1, m2, L1):
    return batch._identify_chunk(a0, aF, tF, E, c * m1 / m2, m2, L1, 1e-14, 40)


def _gpu_back_end(a0, aF, tF, E, c, m1, m2, L1):
    r = _gpu.identify_arrays(np, a0, aF, tF, E, c * m1 / m2, m2, L1)
    r["F1"] = r["lam"] * r["F1_max"]
    return r


@pytest.mark.parametrize("back_end", [_compiled_back_end, _numpy_back_end, _gpu_back_end],
                         ids=["compiled", "numpy", "gpu-on-numpy"])
def test_back_end_against_mpmath_in_every_tier(back_end, references):
    """F1*, F2* within 8 ulps; the stop times at both ends of the line within 1e-13 relative and lambda within 1e-13
    (these observations are well conditioned: the rules, converged, leave a few ulps; measured at most 5e-16 and
    3e-15; a case given a coarser rule than its tier, a tier ratio off by 4, is 2e-12 off)."""
    a0, aF, E, c, m1, m2, L1 = (np.array(v) for v in zip(*CASES, strict=True))
    tF = np.array([float(ref[1]) for ref in references])
    got = back_end(a0, aF, tF, E, c, m1, m2, L1)
    assert np.all(got["status"] == 0)
    for i, case in enumerate(CASES):
        want = _paper(case[0], case[1], case[2], _k(case), case[5], case[6])
        t_lo, _, t_hi = references[i]
        assert _close(got["F1_max"][i], want["F1max"], 8), (case, "F1*")
        assert _close(got["F2_max"][i], want["F2max"], 8), (case, "F2*")
        assert abs(got["stop_time_min"][i] / float(t_lo) - 1.0) <= 1e-13, (case, "t(F1 = 0)")
        assert abs(got["stop_time_max"][i] / float(t_hi) - 1.0) <= 1e-13, (case, "t(F1 = F1*)")
        assert abs(got["F1"][i] / got["F1_max"][i] - 0.5) <= 1e-13, (case, "lambda")


# -- one function, called by every back-end --------------------------------------------------------------------------

def _source_tree(fn) -> ast.AST:
    return ast.parse(textwrap.dedent(inspect.getsource(getattr(fn, "py_func", fn))))


def _called(tree: ast.AST) -> set[str]:
    """The names of the functions called in ``tree`` (``a.b(...)``: ``b``; ``a.b(...)(...)``: ``b``)."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            func = node.func.func if isinstance(node.func, ast.Call) else node.func
            out.add(func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", ""))
    return out


@pytest.mark.parametrize("fn, call", [(_fast._identify_one, "_identify_setup_one"),
                                      (batch._identify_chunk, "for_arrays"), (_gpu._identify_chunk, "for_arrays")],
                         ids=["compiled", "numpy", "gpu"])
def test_each_back_end_calls_the_one_setup_and_states_none_of_its_own(fn, call):
    called = _called(_source_tree(fn))
    assert call in called
    assert not called & {"sin", "cos"}, called  # no sine or cosine of its own: the setup is the shared one's


def test_the_compiled_setup_is_the_one_function_and_stamps_the_cache():
    assert _fast._identify_setup_one.py_func is identify_setup
    # an edit of the setup alone must recompile the kernels that inline it (a stale cache would keep the old one)
    assert _identify_setup in _fast._DEPENDENCIES


def test_the_setup_is_arithmetic_and_three_library_functions():
    """What numba, numpy and CuPy all take: the only global names the function reads are sin, cos and sqrt."""
    assert set(identify_setup.__code__.co_names) == {"sin", "cos", "sqrt"}
    assert (_identify_setup.sin, _identify_setup.cos, _identify_setup.sqrt) == (math.sin, math.cos, math.sqrt)


def test_array_back_ends_run_the_setup_on_their_array_module(monkeypatch):
    """numpy's reference and the GPU code call the one function, bound to the array module they run on (a stand-in
    module here, that records its sine, cosine and square-root calls)."""
    seen = []

    def spy(xp):
        seen.append(xp)
        return bound(xp)

    bound = _identify_setup.for_arrays
    monkeypatch.setattr(_identify_setup, "for_arrays", spy)
    case = CASES[0]
    args = [np.array([v]) for v in (case[0], case[1], 1.0, case[2], _k(case), case[5], case[6])]
    batch._identify_chunk(*args, 1e-14, 40)
    assert seen == [np]
    calls = []

    def recorded(name):
        def call(x):
            calls.append(name)
            return getattr(np, name)(x)
        return call

    xp = types.SimpleNamespace(sin=recorded("sin"), cos=recorded("cos"), sqrt=recorded("sqrt"))
    got = spy(xp)(*(args[i] for i in (0, 1, 3, 4, 5, 6)))
    assert seen[-1] is xp and sorted(calls) == ["cos", "cos", "sin", "sin", "sin", "sqrt"]
    assert all(np.array_equal(g, w) for g, w in zip(got, bound(np)(*(args[i] for i in (0, 1, 3, 4, 5, 6))),
                                                     strict=True))
    seen.clear()
    _gpu.identify_arrays(np, *args)
    assert seen == [np]
