"""Argument checks shared by the physics and solvers (arrays or floats)."""

from __future__ import annotations

import math
import os

import numpy as np

from .errors import ParameterError

HALF_PI = 0.5 * math.pi


def _first_bad(value, bad_mask):
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        return float(arr)
    return float(arr[bad_mask][0])


def check_positive(name: str, value, unit: str = ""):
    """Raise ParameterError unless every element of ``value`` is finite and > 0."""
    arr = np.asarray(value, dtype=float)
    bad = ~(np.isfinite(arr) & (arr > 0.0))
    if np.any(bad):
        raise ParameterError(name, _first_bad(value, bad), "(0, inf)", unit)
    return value


def check_nonnegative(name: str, value, unit: str = ""):
    """Raise ParameterError unless every element of ``value`` is finite and >= 0."""
    arr = np.asarray(value, dtype=float)
    bad = ~(np.isfinite(arr) & (arr >= 0.0))
    if np.any(bad):
        raise ParameterError(name, _first_bad(value, bad), "[0, inf)", unit)
    return value


def finite_positive(name: str, value: float, unit: str = "") -> float:
    """``float(value)``; ParameterError (naming ``name``, range (0, inf)) unless it is finite and > 0 [unit]."""
    value = float(value)
    if not (math.isfinite(value) and value > 0.0):
        raise ParameterError(name, value, "(0, inf)", unit)
    return value


def finite_nonnegative(name: str, value: float, unit: str = "") -> float:
    """``float(value)``; ParameterError (naming ``name``, range [0, inf)) unless it is finite and >= 0 [unit]."""
    value = float(value)
    if not (math.isfinite(value) and value >= 0.0):
        raise ParameterError(name, value, "[0, inf)", unit)
    return value


def check_angle(name: str, value):
    """Raise ParameterError unless every element of ``value`` lies in (0, pi/2) [rad]."""
    arr = np.asarray(value, dtype=float)
    bad = ~(np.isfinite(arr) & (arr > 0.0) & (arr < HALF_PI))
    if np.any(bad):
        raise ParameterError(name, _first_bad(value, bad), "(0, pi/2)", "rad")
    return value


#: Share of the available memory one computation may plan to use (the rest is for the writers, figures and
#: whatever else runs on the machine).
MEMORY_SHARE = 0.5
#: Bytes per sample used in the size checks, measured with tracemalloc and rounded up about threefold for
#: the writers: a time sample of a response (98 B energy, 144 B rk, 123 B explicit), a Monte Carlo sample
#: of uq (141 B), a point of a sweep or of the release envelope (the batch kernels' inputs and outputs).
BYTES_PER_SAMPLE = 400
#: Most workers of a local Dask cluster per CPU core (more only queue for the cores and exhaust memory).
WORKERS_PER_CPU = 4


def available_memory() -> int:
    """Memory available to new allocations [bytes]: MemAvailable of /proc/meminfo, else free pages."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover - non-POSIX
        return 8 * 2**30


def check_size(name: str, value, count: float, what: str = "samples", bytes_each: int = BYTES_PER_SAMPLE) -> None:
    """Raise ParameterError (naming ``name`` and its ``value``) when ``count`` items of ``bytes_each`` bytes
    would need more than :data:`MEMORY_SHARE` of the memory available now; said before any work starts."""
    have = MEMORY_SHARE * available_memory()
    need = float(count) * bytes_each
    if not (math.isfinite(need) and need <= have):
        raise ParameterError(name, value, f"what this machine can hold: {float(count):.3g} {what} need about "
                                          f"{need / 2**30:.3g} GiB, and {have / 2**30:.3g} GiB (half the memory "
                                          "available now) may be used")


def check_workers(name: str, workers) -> int:
    """Raise ParameterError unless ``workers`` is an integer in [1, WORKERS_PER_CPU x CPU cores]."""
    cap = WORKERS_PER_CPU * (os.cpu_count() or 1)
    if isinstance(workers, bool) or not isinstance(workers, int | np.integer) or not 1 <= workers <= cap:
        raise ParameterError(name, workers, f"integers in [1, {cap}] ({WORKERS_PER_CPU} per CPU core)")
    return int(workers)


def check_seed(name: str, seed) -> int:
    """Raise ParameterError unless ``seed`` is an integer in [0, 2^63) (numpy's SeedSequence takes any
    integer >= 0; the bound keeps a seed storable as int64 in manifests, NetCDF and JSON readers)."""
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or not 0 <= seed < 2**63:
        raise ParameterError(name, seed, "integers in [0, 2^63)")
    return int(seed)


def check_integer(name: str, value, least: int, most: int | None = None, odd: bool = False) -> int:
    """``int(value)``; ParameterError (naming ``name``, its value and the range) unless it is a whole number (an
    int, a numpy integer or an integral float; not a bool) in [least, most], odd where ``odd``."""
    whole = (not isinstance(value, bool) and isinstance(value, int | np.integer | float | np.floating)
             and math.isfinite(value) and float(value) == int(value))
    n = int(value) if whole else None
    if n is None or n < least or (most is not None and n > most) or (odd and n % 2 == 0):
        kind = "odd integers" if odd else "integers"
        raise ParameterError(name, value, f"{kind} in [{least}, {'inf' if most is None else most}]")
    return n


def check_real(name: str, value, valid: str, unit: str = "", test=math.isfinite) -> float:
    """``float(value)``; ParameterError (naming ``name``, its value and ``valid``) unless ``value`` is a real number
    (an int, float or numpy scalar; not a bool, a string or an array) for which ``test`` holds."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise ParameterError(name, value if isinstance(value, int | float | str) or value is None
                             else type(value).__name__, valid, unit)
    number = float(value)
    if not test(number):
        raise ParameterError(name, number, valid, unit)
    return number


def check_samples(name: str, value, ndim: int = 1, unit: str = "", finite: bool = True) -> np.ndarray:
    """``value`` as a float array of ``ndim`` dimensions with at least one element; ParameterError naming ``name``
    unless it is one (a string, a nested list, a value that is not a number, an empty array), or, where ``finite``,
    unless every element is finite."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(name, type(value).__name__, f"a {ndim}-D array of numbers", unit) from None
    raw = np.asarray(value).dtype  # bools, and objects (None converts to nan), are not numbers here
    if isinstance(value, str | bytes | bool) or raw.kind in "bO" or arr.ndim != ndim or arr.size == 0:
        shown = f"{arr.size} value(s) in {arr.ndim} dimension(s)" if not isinstance(value, str | bytes) else value
        raise ParameterError(name, shown, f"a {ndim}-D array of one or more numbers", unit)
    if finite and not np.all(np.isfinite(arr)):
        raise ParameterError(name, _first_bad(arr, ~np.isfinite(arr)), "finite numbers", unit)
    return arr


def renamed(**old_to_new: str):
    """Decorator: keyword arguments renamed for one vocabulary across the API (``E_S=`` is now
    ``stored_energy=``) still work, with a DeprecationWarning naming the new name."""
    import functools
    import warnings

    def decorate(func):
        @functools.wraps(func)
        def wrapper(*args, **kwargs):
            for old, new in old_to_new.items():
                if old in kwargs:
                    if new in kwargs:
                        raise TypeError(f"{func.__name__}() got both {old}= (its old name) and {new}=")
                    warnings.warn(f"{func.__name__}({old}=...) is now {func.__name__}({new}=...); the old name "
                                  "will be removed", DeprecationWarning, stacklevel=2)
                    kwargs[new] = kwargs.pop(old)
            return func(*args, **kwargs)

        return wrapper

    return decorate
