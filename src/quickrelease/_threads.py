"""How many threads the compiled (numba) batch kernels use: :func:`using_threads`.

The kernels of :mod:`quickrelease.batch` run on numba's current thread count, which is every core of the
machine unless changed (``numba.config.NUMBA_NUM_THREADS``, set by the environment variable of that name).
``uq``, ``sweep`` and the release envelope take ``threads=`` and run their kernels inside
``using_threads(threads)``; their results do not depend on it (each case is computed alone, in the same
order of operations on any thread). The Dask backend runs each task on one thread instead (its parallelism
is the workers).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np

from .errors import ParameterError

__all__ = ["using_threads", "check_threads", "max_threads"]


def max_threads() -> int:
    """The most threads the kernels can use: ``numba.config.NUMBA_NUM_THREADS`` (all cores by default)."""
    import numba

    return int(numba.config.NUMBA_NUM_THREADS)


def check_threads(threads, name: str = "threads") -> int | None:
    """``threads`` as an int (None passes through: numba's current count); raise ParameterError naming
    ``name`` unless it is an integer in [1, :func:`max_threads`]."""
    if threads is None:
        return None
    top = max_threads()
    if isinstance(threads, bool) or not isinstance(threads, int | np.integer) or not 1 <= threads <= top:
        raise ParameterError(name, threads, f"integers in [1, {top}] (the cores numba may use: NUMBA_NUM_THREADS)")
    return int(threads)


def refuse_with_dask(threads, backend: str, name: str = "threads") -> None:
    """Raise ParameterError (naming ``name``) when ``threads`` is given with the Dask backend (whose tasks run on
    one thread) or the GPU backend (whose kernels run on the GPU: CPU threads would change nothing)."""
    if threads is not None and backend == "dask":
        raise ParameterError(name, threads, "the numpy backend (a Dask task runs on one thread: more "
                                                 "workers give more parallelism)")
    if threads is not None and backend == "gpu":
        raise ParameterError(name, threads, "the numpy backend (the gpu backend runs its kernels on the GPU: "
                                                 "CPU threads change nothing)")


@contextmanager
def using_threads(threads: int | None) -> Iterator[int]:
    """Run the block with the compiled kernels on ``threads`` threads; restore the previous count after.

    Parameters
    ----------
    threads : int or None
        Threads, 1 to ``numba.config.NUMBA_NUM_THREADS`` (the machine's cores unless the environment says
        otherwise); None leaves numba's current count (all cores unless changed).

    Yields
    ------
    int
        The thread count in force inside the block.

    Raises
    ------
    ParameterError
        ``threads`` not an integer in [1, NUMBA_NUM_THREADS] (before anything changes).

    Notes
    -----
    numba's thread count belongs to the calling thread, so two Python threads may use different counts.
    """
    import numba

    threads = check_threads(threads)
    old = numba.get_num_threads()
    if threads is None:
        yield old
        return
    numba.set_num_threads(threads)
    try:
        yield threads
    finally:
        numba.set_num_threads(old)
