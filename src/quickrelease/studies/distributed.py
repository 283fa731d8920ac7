"""Running chunks of work on a Dask cluster (optional: ``pip install quickrelease[dask]``).

:func:`map_chunks` submits one task per chunk to a cluster (an existing scheduler, or a LocalCluster
of single-threaded worker processes) and yields results as they finish, so the caller can store each
one at once; no more than a few chunks are in flight beyond the workers' count, which bounds memory. Each task
runs its compiled kernels on one thread (:func:`quickrelease.using_threads`): the parallelism is the workers'.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from functools import partial
from pathlib import Path
from typing import Any

from ..errors import QuickReleaseError

__all__ = ["map_chunks", "check_optional", "OPTIONAL"]

#: The optional packages each backend or file type needs: key (a backend name, or a file suffix) ->
#: (importable packages, what to install).
OPTIONAL: dict[str, tuple[tuple[str, ...], str]] = {
    "dask": (("dask", "distributed"), "pip install 'quickrelease[dask]'"),
    ".zarr": (("zarr",), "pip install 'quickrelease[dask]'"),
    ".parquet": (("pyarrow",), "pip install 'quickrelease[dask]' (or pyarrow)"),
    ".feather": (("pyarrow",), "pip install 'quickrelease[dask]' (or pyarrow)"),
    ".xlsx": (("openpyxl",), "pip install openpyxl"),
    ".xls": (("xlrd",), "pip install xlrd"),
    ".h5": (("tables",), "pip install tables"),
    ".hdf5": (("tables",), "pip install tables"),
    "gpu": (("cupy",), "pip install 'quickrelease[gpu]'"),
}


def _installed(package: str) -> bool:
    from importlib.util import find_spec

    try:
        return find_spec(package) is not None
    except (ImportError, ValueError):  # a broken or half-installed package counts as missing
        return False


def check_optional(*, backend: str = "numpy", files: Iterable[str | Path] = ()) -> None:
    """Check, before any work, that the optional packages the ``backend`` and the ``files`` (read or written,
    by suffix: ``.zarr``, ``.parquet``, ``.xlsx``, ...) need are installed; else one
    :class:`~quickrelease.errors.QuickReleaseError` line naming what needs what and how to install it (the
    command line's exit 2), instead of a traceback after minutes of computing."""
    wants: list[tuple[str, str]] = []
    if backend in OPTIONAL:
        wants.append((f"the {backend} backend", backend))
    for file in files:
        suffix = Path(file).suffix.lower()
        if suffix in OPTIONAL:
            wants.append((str(file), suffix))
    for what, key in wants:
        packages, install = OPTIONAL[key]
        missing = [p for p in packages if not _installed(p)]
        if missing:
            raise QuickReleaseError(f"{what} needs {', '.join(missing)} (not installed): {install}")
    if backend == "gpu":  # CuPy installed: a CUDA device too
        from ..batch._gpu import require_gpu

        require_gpu()


def _client(scheduler: str | None, workers: int):
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise QuickReleaseError("the dask backend needs Dask: pip install 'quickrelease[dask]'") from None
    if scheduler:
        return Client(scheduler), None
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
                           memory_limit="1.5GiB")
    return Client(cluster), cluster


def map_chunks(func: Callable[..., Any], arguments: list[tuple], scheduler: str | None = None,
               workers: int = 2, in_flight: int | None = None) -> Iterator[Any]:
    """Run ``func(*args)`` for each tuple of ``arguments`` on Dask; yield the results as they finish."""
    if not arguments:
        return
    client, cluster = _client(scheduler, workers)
    from dask.distributed import as_completed

    func = partial(on_one_thread, func)

    try:
        limit = in_flight or 2 * max(workers, len(client.scheduler_info().get("workers", {})) or 1)
        pending = iter(arguments)
        futures = [client.submit(func, *args, pure=False) for args in _take(pending, limit)]
        queue = as_completed(futures)
        for future in queue:
            result = future.result()
            future.release()
            for args in _take(pending, 1):
                queue.add(client.submit(func, *args, pure=False))
            yield result
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def on_one_thread(func: Callable[..., Any], *args: Any) -> Any:
    """``func(*args)`` with the compiled kernels on one thread (what a Dask task runs)."""
    from .._threads import using_threads

    with using_threads(1):
        return func(*args)


def _take(iterator, n: int) -> list:
    out = []
    for _ in range(n):
        try:
            out.append(next(iterator))
        except StopIteration:
            break
    return out
