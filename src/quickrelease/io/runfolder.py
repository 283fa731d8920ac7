"""Output folders that never lie: fingerprints, staging and pre-flight checks, shared by every command.

A command that writes results (``run``, ``report``, ``plan``, ``fit``, ``demo``, ``campaign``, ``uq``, the
Zarr store of ``sweep``) writes through a :class:`RunFolder`:

* **Fingerprint.** ``manifest.json`` records a SHA-256 of a canonical JSON of everything that determines
  the result (the resolved case with its device values, grids, seed, samples, chunking, the package
  version), and the inputs themselves, so a refusal can name what differs. It does not record what the
  result does not depend on (the backend, the number of workers, the case file's path).
* **Staging.** The whole result is written into a hidden sibling folder (``.NAME.partial-PID``, or
  ``.NAME.partial`` for runs that can be resumed) and moved into place at the end: on Linux an atomic
  exchange of the two folders (``renameat2(RENAME_EXCHANGE)``), elsewhere two renames. Until then the
  previous complete result stays in place, so a failure or a kill leaves nothing new, the previous
  complete result, or (``uq``, ``sweep``) a resumable state.
* **Exactly what the run wrote.** A folder holding another run's results is refused unless ``overwrite``
  is given, and then replaced as a whole (no stale file survives); a folder holding files that quickrelease
  did not write is refused even then (the command will not delete a user's files).
* **Pre-flight.** Before any work: ``--out`` naming a file where a folder is expected (or the reverse), a
  path under a file, a place that cannot be written. At write time an ``OSError`` (a full disk, a lost
  permission) becomes one line (:class:`OutputError`) and the staging folder is removed.
"""

from __future__ import annotations

import contextlib
import dataclasses
import errno
import hashlib
import json
import math
import os
import shutil
import stat
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from .._files import file_kind, staging_name
from .._version import provenance_attrs
from ..errors import OutputError

__all__ = ["OutputError", "RunFolder", "canonical", "fingerprint", "case_inputs", "differences", "check_target",
           "MANIFEST", "output_error", "commit_files", "staging_name", "provenance", "provenance_attrs",
           "check_output_file"]

MANIFEST = "manifest.json"
_FORMAT = "quickrelease-run/1"


# -- fingerprints -----------------------------------------------------------------------------------------------

def canonical(obj: Any) -> Any:
    """A JSON-ready, canonical form of ``obj`` (dataclasses, dicts, arrays, paths, floats exactly)."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: canonical(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, dict):
        return {str(k): canonical(v) for k, v in sorted(obj.items(), key=lambda kv: str(kv[0]))}
    if isinstance(obj, list | tuple):
        return [canonical(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return {"shape": list(obj.shape), "dtype": str(obj.dtype),
                "sha256": hashlib.sha256(np.ascontiguousarray(obj).tobytes()).hexdigest(),
                "first": canonical(obj.flat[0].item()) if obj.size else None,
                "last": canonical(obj.flat[-1].item()) if obj.size else None}
    if isinstance(obj, bool | np.bool_):
        return bool(obj)
    if isinstance(obj, int | np.integer):
        return int(obj)
    if isinstance(obj, float | np.floating):
        value = float(obj)
        return value if math.isfinite(value) else repr(value)  # JSON has no nan/inf; repr keeps them apart
    if isinstance(obj, Path):
        return str(obj)
    if obj is None or isinstance(obj, str):
        return obj
    return repr(obj)


def fingerprint(inputs: dict[str, Any]) -> str:
    """SHA-256 of the canonical JSON of ``inputs`` (sorted keys, floats by their shortest exact repr)."""
    text = json.dumps(canonical(inputs), sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _file_digest(path: Path) -> str | None:
    """SHA-256 of a regular file's bytes (read in pieces); None for what cannot be read or is no regular file (a
    FIFO, opened without blocking: reading it waited for a writer forever, before the reader of the records could
    refuse it in one line; a folder; a device node)."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except (OSError, ValueError):
        return None
    try:  # before open(): a folder's descriptor made open() raise IsADirectoryError naming the descriptor, 3
        regular = stat.S_ISREG(os.fstat(fd).st_mode)
    except OSError:
        regular = False
    if not regular:
        os.close(fd)
        return None
    with open(fd, "rb") as f:
        try:
            digest = hashlib.sha256()
            for piece in iter(lambda: f.read(1 << 20), b""):
                digest.update(piece)
        except OSError:
            return None
    return digest.hexdigest()


def case_inputs(case: Any) -> dict[str, Any]:
    """The resolved case as fingerprint inputs: every value (device included), not where the file was.

    The case file's path (``source``) is left out (moving a file does not change a result); a measured
    record enters by the SHA-256 of its file, so an edited record is a different run.
    """
    data = canonical(case)

    def strip(d: Any) -> Any:
        if isinstance(d, dict):
            return {k: strip(v) for k, v in d.items() if k not in ("source", "source_text")}
        if isinstance(d, list):
            return [strip(v) for v in d]
        return d

    data = strip(data)
    _digest_record(getattr(case, "record", None), data.get("record"))
    building = getattr(case, "building", None)  # the building's record ([building.record]) likewise
    if building is not None:
        _digest_record(getattr(building, "record", None), data["building"].get("record"))
    return data


def _digest_record(record: Any, data: dict[str, Any] | None) -> None:
    """Replace the record's file paths in ``data`` (its canonical form) by their names and SHA-256."""
    if record is None or data is None:
        return
    data["file"] = {"name": Path(record.file).name, "sha256": _file_digest(record.file)}
    for name, ch in (getattr(record, "channels", None) or {}).items():
        file = getattr(ch, "file", None)
        if file is not None:
            data["channels"][name]["file"] = {"name": Path(file).name, "sha256": _file_digest(file)}


# -- provenance -------------------------------------------------------------------------------------------------

def provenance(origin: Any) -> dict[str, Any]:
    """What made an output: the package version and the input file (its name, SHA-256 and text), the same in
    every file a command writes (JSON under the key ``provenance``, NetCDF global attributes through
    :func:`provenance_attrs`, the report's header).

    ``origin`` is a :class:`~quickrelease.io.case.Case` (its file's text as read by ``load_case``), a result with a
    ``source`` (a campaign), or a path. Nothing here depends on the time or the folder the file lies in, so a
    resumed run writes the same bytes as an uninterrupted one. ``input`` is None for inputs not read from a file
    (a case built in Python).
    """
    source = getattr(origin, "source", origin)
    text = getattr(origin, "source_text", None)
    raw = None
    if text is not None:
        raw = text.encode("utf-8")
    elif isinstance(source, str | Path) and str(source) and not str(source).startswith("<"):
        try:
            raw = Path(source).read_bytes()
        except OSError:
            raw = None
    entry = None
    if raw is not None:
        entry = {"name": Path(str(source)).name, "sha256": hashlib.sha256(raw).hexdigest(),
                 "text": raw.decode("utf-8", errors="replace")}
    return {"quickrelease": _version(), "input": entry}


def _flatten(data: Any, prefix: str = "") -> dict[str, Any]:
    if isinstance(data, dict):
        out: dict[str, Any] = {}
        for k, v in data.items():
            out.update(_flatten(v, f"{prefix}.{k}" if prefix else str(k)))
        return out or {prefix: {}}
    if isinstance(data, list):
        out = {}
        for i, v in enumerate(data):
            out.update(_flatten(v, f"{prefix}[{i}]"))
        return out or {prefix: []}
    return {prefix: data}


def differences(old: dict[str, Any], new: dict[str, Any], limit: int = 3) -> str:
    """What differs between two sets of inputs, in words (the first ``limit`` entries)."""
    a, b = _flatten(old), _flatten(new)
    keys = [k for k in sorted(set(a) | set(b)) if a.get(k, "<absent>") != b.get(k, "<absent>")]
    words = [f"{k} {_short(a.get(k, '<absent>'))} -> {_short(b.get(k, '<absent>'))}" for k in keys[:limit]]
    more = f" (and {len(keys) - limit} more)" if len(keys) > limit else ""
    return ", ".join(words) + more if words else "nothing recorded (a different fingerprint)"


def _short(value: Any) -> str:
    text = json.dumps(value) if not isinstance(value, str) else value
    return text if len(text) <= 40 else text[:37] + "..."


def _version() -> str:
    from .._version import __version__

    return __version__


# -- pre-flight -------------------------------------------------------------------------------------------------


#: The longest path (bytes) the system takes (Linux PATH_MAX, with its terminating zero).
PATH_MAX = 4095


def check_target(out: str | Path, kind: str, option: str = "--out") -> Path:
    """Check before the work that ``out`` can take a ``kind`` ("folder" or "file") result; returns its
    absolute path. Raises :class:`OutputError` (one line) when it cannot: an empty name, a name or path longer
    than the system allows, a file where a folder is expected (or the reverse), a path under a file, a place
    that cannot be written."""
    if not os.fspath(out).strip():
        raise OutputError(f"{option} is empty: give a {kind} name")
    path = Path(os.path.abspath(os.fspath(out)))
    shown = _short_path(out)
    if len(os.fsencode(str(path))) > PATH_MAX:
        raise OutputError(f"{option} {shown}: the path is {len(os.fsencode(str(path)))} bytes long, over the "
                          f"{PATH_MAX} the system allows")
    for part in path.parts:
        if len(os.fsencode(part)) > 255:
            raise OutputError(f"{option} {shown}: a name in it is {len(os.fsencode(part))} bytes long, over the "
                              "255 the file system allows")
    try:
        if path.exists() or path.is_symlink():
            if kind == "folder" and not path.is_dir():
                raise OutputError(f"{option} {shown}: is a file; expected a folder (choose another {option})")
            if kind == "file" and path.is_dir():
                raise OutputError(f"{option} {shown}: is a folder; expected a file name (choose another {option})")
        anc = path.parent
        while not anc.exists() and not anc.is_symlink():
            if anc.parent == anc:
                break
            anc = anc.parent
        if not anc.is_dir():
            raise OutputError(f"{option} {shown}: {_short_path(anc)} is a file, not a folder")
        fd, probe = tempfile.mkstemp(prefix=".quickrelease-probe-", dir=anc)  # a real test (os.access says yes
        os.close(fd)  # to root on a read-only file system)
        os.unlink(probe)
    except OSError as exc:
        raise OutputError(f"{option} {shown}: cannot write there: {_reason(exc)}") from None
    return path


def _short_path(path: str | Path | int, limit: int = 120) -> str:
    """A path for a message: long ones cut in the middle (an OSError's file descriptor as such)."""
    if isinstance(path, int):
        return f"file descriptor {path}"
    text = os.fspath(path)
    return text if len(text) <= limit else f"{text[:limit // 2 - 2]}...{text[-(limit // 2 - 2):]}"


def _reason(exc: OSError) -> str:
    """An OSError in words, without a traceback (a full disk said plainly)."""
    if exc.errno == errno.ENOSPC:
        return "no space left on the device"
    if exc.errno == errno.EROFS:
        return "read-only file system"
    return exc.strerror or type(exc).__name__


def output_error(exc: OSError, out: str | Path) -> OutputError:
    """One line for an ``OSError`` met while writing ``out`` (a full disk, a lost permission)."""
    return OutputError(f"cannot write {_short_path(out)}: {_reason(exc)}; nothing was written there")


# -- the staged folder ------------------------------------------------------------------------------------------

def _read_manifest(folder: Path) -> dict[str, Any] | None:
    """The manifest of ``folder``: a dict, None when there is none; raises OutputError when damaged."""
    path = folder / MANIFEST
    if not path.exists():
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise _Damaged(path, str(exc).splitlines()[0] if str(exc) else type(exc).__name__) from None
    if not isinstance(data, dict) or "fingerprint" not in data:
        raise _Damaged(path, "not a quickrelease manifest")
    return data


class _Damaged(Exception):
    def __init__(self, path: Path, reason: str) -> None:
        super().__init__(f"{path}: damaged ({reason})")
        self.path = path
        self.reason = reason


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True


def _exchange(a: Path, b: Path) -> bool:
    """Atomically exchange two paths (Linux renameat2 RENAME_EXCHANGE); False where not available."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        fn = libc.renameat2
    except (OSError, AttributeError):
        return False
    fn.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    at_fdcwd, rename_exchange = -100, 2
    if fn(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP, errno.EXDEV):
        return False
    raise OSError(err, os.strerror(err), str(a))


class RunFolder:
    """A result folder written through a staging sibling, guarded by a fingerprint.

    Parameters
    ----------
    out : path
        The folder the result goes to.
    what : str
        What the folder holds (``"run"``, ``"uq"``, ``"sweep"``, ``"campaign"``), recorded in the manifest.
    inputs : dict
        Everything the result depends on (see :func:`case_inputs`); its fingerprint guards the folder.
    overwrite : bool
        Replace a folder holding another run's results.
    resume : bool
        Continue the resumable state of the same run (``resumable`` folders only).
    resumable : bool
        The work folder keeps a fixed name (``.NAME.partial``) and survives a failure.

    The constructor only checks (pre-flight: nothing is written). :meth:`open` makes the staging folder
    (a resumable one continued, or seeded from the complete result when resuming it), :meth:`commit`
    moves it into place, :meth:`abandon` removes it (a resumable one is kept).
    """

    def __init__(self, out: str | Path, what: str, inputs: dict[str, Any], *, overwrite: bool = False,
                 resume: bool = False, resumable: bool = False, option: str = "--out") -> None:
        self.given = out
        self.out = check_target(out, "folder", option)
        self.what = what
        self.inputs = canonical({"what": what, "quickrelease": _version(), **inputs})
        self.fingerprint = fingerprint(self.inputs)
        self.overwrite = overwrite
        self.resume = resume
        self.resumable = resumable
        self.notes: list[str] = []
        name, parent = self.out.name, self.out.parent
        self.partial = self.out.with_name(staging_name(name, "partial", _existing(parent)))
        self.work = self.partial if resumable else \
            self.out.with_name(staging_name(name, f"partial-{os.getpid()}", _existing(parent)))
        self._prefix = staging_name(name, "partial-", _existing(parent))  # of other runs' staging folders
        self._old = staging_name(name, "old-", _existing(parent))
        self._seed_from_out = False
        self._continue = False
        self._check()

    # what is there now, and may this run go into it?
    def _check(self) -> None:
        out = self.out
        if self.resumable and self.partial.is_dir():
            try:
                old = _read_manifest(self.partial)
            except _Damaged as exc:
                if not self.resume and not self.overwrite:
                    raise OutputError(f"{self.given}: an unfinished run is beside it with a damaged {exc.path.name} "
                                      f"({exc.reason}); pass --resume to check and continue it, or --overwrite "
                                      "to start again") from None
                old = None
                if self.resume:
                    self.notes.append(f"{exc.path} was damaged ({exc.reason}): rewritten; every chunk is checked "
                                      "against its own fingerprint")
            if old is not None and old.get("complete"):
                if not out.exists():  # killed between the two renames of a commit: finish it
                    os.replace(self.partial, out)
            elif self.overwrite and not self.resume:
                pass  # removed in open()
            elif not self.resume:
                raise OutputError(f"{self.given}: an unfinished run of this folder is in {self.partial.name}; "
                                  "pass --resume to continue it, or --overwrite to start again")
            elif old is not None and old["fingerprint"] != self.fingerprint:
                raise OutputError(f"{self.given}: cannot resume: the unfinished run has other inputs: "
                                  f"{differences(old.get('inputs', {}), self.inputs)}")
            else:
                self._continue = True
        if not out.exists():
            return
        entries = [p for p in out.iterdir()]
        if not entries:
            return
        try:
            old = _read_manifest(out)
        except _Damaged as exc:
            if self.overwrite:
                return
            raise OutputError(f"{self.given}: {exc.path.name} is damaged ({exc.reason}); pass --overwrite to "
                              "replace the folder") from None
        if old is None:
            raise OutputError(f"{self.given}: holds files that quickrelease did not write; choose another --out "
                              "or empty it")
        if old["fingerprint"] == self.fingerprint:
            if self.resume and self.resumable and not self._continue:
                self._seed_from_out = True  # resuming a finished run: nothing left to compute
            return
        if self.resume:
            raise OutputError(f"{self.given}: cannot resume: it holds a run with other inputs: "
                              f"{differences(old.get('inputs', {}), self.inputs)}")
        if not self.overwrite:
            raise OutputError(f"{self.given}: holds the results of another run "
                              f"({differences(old.get('inputs', {}), self.inputs)}); pass --overwrite to replace "
                              "them, or choose another --out")

    def _manifest(self, complete: bool) -> dict[str, Any]:
        return {"format": _FORMAT, "what": self.what, "fingerprint": self.fingerprint, "complete": complete,
                "inputs": self.inputs}

    def _write_manifest(self, complete: bool) -> None:
        from .export import write_json

        write_json(self._manifest(complete), self.work / MANIFEST)

    def _clean_leftovers(self) -> None:
        """Staging folders of runs that died (their process is gone), and a finished commit's leftovers."""
        parent = self.out.parent
        if not parent.is_dir():
            return
        prefix = self._prefix
        for p in parent.iterdir():
            if p.name.startswith(prefix) and p.name[len(prefix):].isdigit() and p != self.work:
                if not _pid_alive(int(p.name[len(prefix):])):
                    shutil.rmtree(p, ignore_errors=True)
            elif p.name.startswith(self._old):
                shutil.rmtree(p, ignore_errors=True)

    def open(self) -> Path:
        """Make the staging folder and return it (a resumable one is continued)."""
        try:
            self.out.parent.mkdir(parents=True, exist_ok=True)
            self._clean_leftovers()
            if self.resumable and self.partial.is_dir():
                try:
                    old = _read_manifest(self.partial)
                except _Damaged:
                    old = None
                if old is not None and old.get("complete"):
                    shutil.rmtree(self.partial)  # an exchange happened, the old result was not yet removed
                elif not self._continue:
                    shutil.rmtree(self.partial)
            if not self.work.exists():
                if self._seed_from_out and self.out.is_dir():
                    shutil.copytree(self.out, self.work, symlinks=True)
                else:
                    self.work.mkdir()
            self._write_manifest(False)
        except OSError as exc:
            self.abandon(force=True)
            raise output_error(exc, self.given) from None
        return self.work

    def commit(self) -> None:
        """Mark the staging folder complete and move it into place (the previous result goes only now)."""
        try:
            self._write_manifest(True)
            _fsync_dir(self.work)
            if self.out.exists():
                if self.out.is_dir() and _exchange(self.work, self.out):
                    trash = self.out.with_name(f"{self._old}{os.getpid()}")
                    os.replace(self.work, trash)
                else:
                    trash = self.out.with_name(f"{self._old}{os.getpid()}")
                    os.replace(self.out, trash)
                    os.replace(self.work, self.out)
                _fsync_dir(self.out.parent)
                shutil.rmtree(trash, ignore_errors=True)
            else:
                os.replace(self.work, self.out)
                _fsync_dir(self.out.parent)
        except OSError as exc:
            self.abandon(force=True)  # a full disk at the end: complete or absent
            raise output_error(exc, self.given) from None

    def abandon(self, force: bool = False) -> None:
        """Remove the staging folder after a failure (a resumable one is kept, it can be resumed, unless
        ``force``: after a write error such as a full disk; one this run continued is kept even then)."""
        if self.resumable and not force:
            return
        if self.work.exists() and (not self.resumable or not self._continue):
            shutil.rmtree(self.work, ignore_errors=True)

    @contextlib.contextmanager
    def staged(self) -> Iterator[Path]:
        """``with folder.staged() as work:`` write into ``work``; committed on success, else abandoned;
        an OSError while writing becomes one line (:class:`OutputError`)."""
        work = self.open()
        try:
            yield work
        except OSError as exc:
            self.abandon()
            raise output_error(exc, self.given) from None
        except BaseException:
            self.abandon()
            raise
        self.commit()

    def final(self, path: Path) -> Path:
        """Where a file written into the staging folder lies after the commit."""
        return Path(self.given) / Path(path).relative_to(self.work)


def _existing(path: Path) -> Path:
    """``path`` or its nearest existing ancestor (to ask its file system for its limits)."""
    while not path.exists() and path.parent != path:
        path = path.parent
    return path


def _fsync_dir(path: Path) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def commit_files(pairs: list[tuple[Path, Path]]) -> None:
    """Rename written temporary files into place, in order (each rename atomic)."""
    for tmp, dest in pairs:
        os.replace(tmp, dest)


def check_output_file(path: str | Path, option: str, overwrite: bool = False) -> Path:
    """Check before the work that the file ``path`` may be written (by a rename of a finished temporary file
    over it); returns its absolute path.

    Refused (:class:`OutputError`, one line): a device node, FIFO, socket or folder at
    ``path`` (never replaced, even with ``overwrite``: a rename over a device node removes the device), an
    existing file without ``overwrite`` (the program cannot know it wrote it), a name or path longer than the
    system allows, a folder in the path that is a file, and a place that cannot be written.
    """
    given = path
    full = check_target(path, "file", option)
    try:
        st = os.stat(full)  # through a symbolic link: what a write would reach
    except FileNotFoundError:
        st = None
    except OSError as exc:
        raise OutputError(f"{option} {given}: {exc.strerror or exc}") from None
    if st is not None:
        if not stat.S_ISREG(st.st_mode):
            raise OutputError(f"{option} {given}: is {file_kind(st.st_mode)}, not a regular file; it is never "
                              f"replaced (choose another {option})")
        if not overwrite:
            raise OutputError(f"{option} {given}: the file exists; pass --overwrite to replace it, or choose "
                              f"another {option}")
    return full
