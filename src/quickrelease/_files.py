"""Files the user names, read and written safely: inputs must be regular files of a bounded size, outputs never
replace anything but a regular file (and one not the program's only with ``--overwrite``).

Reading a character device (the zero or random device) would never end, and opening a FIFO would wait for a
writer forever: every input file is opened without blocking and checked with ``fstat`` first
(:func:`check_input`, :func:`read_input`). An output is checked before the work (:func:`check_output_file`):
a device node, a FIFO, a socket or a folder at the path is refused (a rename over it would remove it), and an
existing file is replaced only with ``overwrite``.
"""

from __future__ import annotations

import hashlib
import os
import stat
from pathlib import Path

__all__ = ["TOML_MAX_BYTES", "RECORD_MAX_BYTES", "file_kind", "check_input", "read_input", "staging_name"]

#: The largest TOML file read (case, device, campaign files are a few kB).
TOML_MAX_BYTES = 16 * 2**20
#: The largest record file read (a 1 kHz record of 8 channels over a day is about 10 GB as CSV; a record
#: of a release is seconds to minutes long).
RECORD_MAX_BYTES = 8 * 2**30


def file_kind(mode: int) -> str:
    """What a ``st_mode`` is, in words (``"a character device"``, ``"a FIFO"``, ...)."""
    for test, words in ((stat.S_ISDIR, "a folder"), (stat.S_ISCHR, "a character device"),
                        (stat.S_ISBLK, "a block device"), (stat.S_ISFIFO, "a FIFO"),
                        (stat.S_ISSOCK, "a socket"), (stat.S_ISLNK, "a symbolic link")):
        if test(mode):
            return words
    return "a regular file" if stat.S_ISREG(mode) else "not a file"


def _size_words(n: int) -> str:
    return f"{n / 2**30:.3g} GiB" if n >= 2**30 else f"{n / 2**20:.3g} MiB"


def _open_regular(path: Path, what: str, error: type[Exception], limit: int) -> tuple[int, int]:
    """Open ``path`` for reading without blocking (a FIFO opens at once); ``(fd, size)`` of a regular file not
    over ``limit`` bytes, else ``error`` naming the file."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        reason = "not found" if isinstance(exc, FileNotFoundError) else exc.strerror or type(exc).__name__
        raise error(f"{path}: cannot read the {what} ({reason})") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise error(f"{path}: not a regular file ({file_kind(st.st_mode)}); the {what} must be a file")
        if st.st_size > limit:
            raise error(f"{path}: the {what} is {_size_words(st.st_size)}, over the {_size_words(limit)} read at "
                        "most")
    except BaseException:
        os.close(fd)
        raise
    return fd, st.st_size


def check_input(path: str | Path, what: str, error: type[Exception], limit: int = RECORD_MAX_BYTES) -> None:
    """Raise ``error`` (one line naming the file) unless ``path`` is a regular file of at most ``limit`` bytes."""
    fd, _ = _open_regular(Path(path), what, error, limit)
    os.close(fd)


def read_input(path: str | Path, what: str, error: type[Exception], limit: int = TOML_MAX_BYTES) -> bytes:
    """The bytes of the regular file ``path`` (at most ``limit``); ``error`` naming the file when it is not one
    (a device, a FIFO, a folder), cannot be read or is larger."""
    path = Path(path)
    fd, size = _open_regular(path, what, error, limit)
    try:
        with os.fdopen(fd, "rb", closefd=True) as fh:
            data = fh.read(limit + 1)
    except OSError as exc:
        raise error(f"{path}: cannot read the {what} ({exc.strerror or type(exc).__name__})") from None
    if len(data) > limit:  # grew while read
        raise error(f"{path}: the {what} is over the {_size_words(limit)} read at most")
    return data


def _name_max(folder: Path) -> int:
    """The longest file name (bytes) the file system of ``folder`` allows (255 where it cannot say)."""
    try:
        return int(os.pathconf(folder, "PC_NAME_MAX"))
    except (OSError, ValueError, AttributeError):
        return 255


#: Bytes a staging name may add after ``.NAME.``: its tag (``partial-PID``, ``old-PID``) and, for a temporary
#: file, the random part and ``.part``.
_TAG_ROOM = 40


def staging_name(name: str, tag: str, folder: Path | None = None) -> str:
    """The hidden name ``.NAME.TAG`` of a staging file or folder beside ``NAME`` (``TAG`` up to 40 bytes with
    what a temporary file adds). When NAME is too long for that (a legal 240-character NAME), it is cut and a
    hash of the whole keeps the name unique; the cut does not depend on the tag, so every staging name of one
    NAME starts alike."""
    limit = _name_max(folder) if folder is not None else 255
    raw = os.fsencode(name)
    if len(raw) + 2 + _TAG_ROOM <= limit:
        return f".{name}.{tag}"
    digest = hashlib.sha256(raw).hexdigest()[:16]
    room = max(limit - len(f".~{digest}.") - _TAG_ROOM, 1)
    head = raw[:room].decode("utf-8", errors="ignore")
    return f".{head}~{digest}.{tag}"
