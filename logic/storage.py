"""Atomic files: everything groundlang writes appears whole or not at all; bounded reads.

A writer gets a temporary path next to the target and the temporary file is
renamed onto the target only when writing succeeded, so an interruption or
a crash leaves the previous file (or none), never half of one. Temporary
files are created private to the owner and then get the permissions a
plain ``open`` would give. Every OS error raised while writing names the
path it concerns (a full disk says which file it was writing).

:func:`read_limited` is how groundlang reads a file a user names: regular
files only (a FIFO would hang, ``/dev/zero`` would fill memory) and at most
a byte limit per kind of file, refused in one line naming the path.
"""

from __future__ import annotations

import errno
import os
import secrets
import stat
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path

__all__ = ["FileRefused", "atomic_path", "check_destination", "check_folder", "read_limited", "write_atomically"]


class FileRefused(ValueError):
    """A file that is not a regular file, or larger than its kind may be; the message names the path."""


def _kind(mode: int) -> str:
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def read_limited(path: str | os.PathLike, limit: int, what: str) -> bytes:
    """The bytes of ``path``, a regular file of at most ``limit`` bytes; FileRefused otherwise (``what``
    names the kind of file expected, e.g. "a labels CSV"), OSError (naming the path) when unreadable.
    The kind is read from the open descriptor (opened non-blocking, so a FIFO cannot hang the open), and
    no more than ``limit + 1`` bytes are ever read, even from a file that grows meanwhile."""
    path = Path(path)
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
    try:
        info = os.fstat(fd)
    except BaseException:
        os.close(fd)
        raise
    if not stat.S_ISREG(info.st_mode):
        os.close(fd)
        if stat.S_ISDIR(info.st_mode):  # what reading a folder has always said
            raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))
        raise FileRefused(f"{path}: {_kind(info.st_mode)}, not a regular file; expected {what}")
    with os.fdopen(fd, "rb") as handle:
        if info.st_size > limit:
            raise FileRefused(f"{path}: {info.st_size:,} bytes, more than the {limit:,} allowed for {what}")
        data = handle.read(limit + 1)
    if len(data) > limit:
        raise FileRefused(f"{path}: more than the {limit:,} bytes allowed for {what}")
    return data


def _read_umask() -> int:
    mask = os.umask(0)  # the only way to read it is to set it: once, at import
    os.umask(mask)
    return mask


_UMASK = _read_umask()

# What tempfile.mkstemp opens with: new file only, never through a symlink.
_CREATE_FLAGS = os.O_RDWR | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_BINARY", 0)
_ATTEMPTS = 100


@contextmanager
def atomic_path(path: str | os.PathLike, suffix: str = ".tmp") -> Iterator[Path]:
    """Yield a temporary path in ``path``'s folder; rename it onto ``path`` if the block succeeds.

    The folder is created if needed. On any exception (KeyboardInterrupt
    included) the temporary file is removed and ``path`` is left untouched.
    The temporary file is named before it is created and created inside the
    guarded region, so an interrupt arriving at any point, even right after
    the file appears, cannot leave it behind (one interrupt landing between
    the system call's return and the assignment of its descriptor leaks that
    descriptor until the process ends; Python gives no way to close it).
    The caller writes the yielded path by name: whoever can write to the
    folder could swap it for a symlink before that (the file's own mode is
    set through its descriptor, never by name).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp: Path | None = None  # set before the file is created: cleanup must know the name
    fd: int | None = None
    try:
        for _ in range(_ATTEMPTS):
            tmp = path.parent / f".{path.name}.{secrets.token_hex(8)}{suffix}"
            try:
                fd = os.open(tmp, _CREATE_FLAGS, 0o600)
            except FileExistsError:  # someone else's file (64 random bits: practically never); not ours to remove
                tmp = None
                continue
            break
        else:
            raise FileExistsError(f"{path.parent}: no free temporary name for {path.name} in {_ATTEMPTS} tries")
        os.fchmod(fd, 0o666 & ~_UMASK)  # what a plain open() gives, set on the file itself, not by name
        opened, fd = fd, None  # forgotten before closing: never closed twice (the number may be reused)
        os.close(opened)
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        if fd is not None:
            with suppress(OSError):
                os.close(fd)
        if tmp is not None:
            tmp.unlink(missing_ok=True)
        raise


def write_atomically(path: str | os.PathLike, data: bytes | str, *, durable: bool = True) -> Path:
    """Write bytes, or text as UTF-8 with ``\\n`` line ends, to ``path`` atomically; returns the path.

    The rename is atomic either way: readers see the old file or the new
    one, never part of one. ``durable`` (the default) also fsyncs the data
    before the rename, so that after a power cut or an OS crash ``path``
    holds the new contents rather than possibly an empty file. Models,
    corpora, results and discovered libraries are written durably; the
    behaviour-likelihood cache passes ``durable=False``, since an entry lost
    in a power cut is recomputed (and one that comes back empty is logged
    and recomputed) while a model is not, and an fsync per entry is slow.
    """
    path = Path(path)
    payload = data.encode("utf-8") if isinstance(data, str) else data
    try:
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as handle:
                handle.write(payload)
                if durable:
                    handle.flush()
                    os.fsync(handle.fileno())
    except OSError as exc:
        # A failed write or fsync (a full disk) names no file, and one in a folder that cannot take a file
        # names the temporary file next to the target: name the target, which is what the user gave.
        if exc.filename is None or Path(exc.filename).parent == path.parent and Path(exc.filename).name != path.name:
            raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from exc
        raise
    return path


def check_folder(path: str | os.PathLike, what: str, named: str | os.PathLike | None = None) -> Path:
    """``path`` as a folder to create or use, refused (ValueError starting with ``what``) if it, or the
    nearest existing folder above it, is a file. ``named``: the path ``what`` names (default ``path``),
    called "it" in the message."""
    path = Path(path)
    named = path if named is None else Path(named)
    for step in (path, *path.parents):
        if step.exists():
            if not step.is_dir():
                raise ValueError(f"{what}: {'it' if step == named else step} is a file, not a folder")
            break
    return path


def check_destination(path: str | os.PathLike, option: str) -> Path:
    """``path`` as a file to write later, refused now (naming ``option``) if it cannot be: an existing
    folder, or a path through a file. Commands check their outputs before the work, so a long run is
    not lost to a typo at the end."""
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"{option} {path}: is a folder; expected the path of a file to write")
    check_folder(path.parent, f"{option} {path}", named=path)
    return path
