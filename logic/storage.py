"""Atomic files: everything groundlang writes appears whole or not at all; bounded reads.

A writer gets a temporary path next to the target and the temporary file is
renamed onto the target only when writing succeeded, so an interruption or
a crash leaves the previous file (or none), never half of one. Temporary
files are created private to the owner and then get the permissions a
plain ``open`` would give. Every OS error raised while writing names the
path the caller gave (a full disk says which file it was writing, never
the temporary file's name). A symlink is written through: its target is
replaced, in the target's folder. A character device or a FIFO
(``/dev/null``, a pipe) is written into as ``>`` would, since renaming onto
it would replace the device itself; a folder, a socket or a block device
is refused.

:func:`read_limited` is how groundlang reads a file a user names: regular
files only (a FIFO would hang, ``/dev/zero`` would fill memory) and at most
a byte limit per kind of file, refused in one line naming the path.
"""

from __future__ import annotations

import errno
import os
import secrets
import stat
from collections.abc import Iterable, Iterator
from contextlib import contextmanager, suppress
from pathlib import Path

__all__ = ["FileRefused", "as_path", "atomic_path", "check_destination", "check_folder", "check_writable", "file_kind",
           "read_limited", "write_atomically"]


class FileRefused(ValueError):
    """A file that is not a regular file, or larger than its kind may be; the message names the path."""


def as_path(value, what: str) -> Path:
    """``value`` as a Path; TypeError naming ``what`` (the function and argument) for anything that is not a
    str or os.PathLike. pathlib's own message ("expected str, bytes or os.PathLike object, not int") names
    no argument, and bytes would become a path of their repr."""
    if not isinstance(value, (str, os.PathLike)):
        raise TypeError(f"{what} must be a path (a str or os.PathLike), got {type(value).__name__}")
    try:  # a lone surrogate ("\ud800") is no file name: the first open had raised UnicodeEncodeError
        os.fsencode(value)
    except UnicodeEncodeError:
        raise ValueError(f"{what}: {os.fspath(value)!r} is not a file name on this system "
                         "(a character the file system's encoding cannot hold)") from None
    return Path(value)


def file_kind(mode: int) -> str:
    """What a file that is not a regular one is, as an error names it ("a FIFO (named pipe)", "a folder")."""
    if stat.S_ISDIR(mode):
        return "a folder"
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
        raise FileRefused(f"{path}: {file_kind(info.st_mode)}, not a regular file; expected {what}")
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


def _target(path: Path) -> tuple[Path, os.stat_result | None]:
    """Where writing ``path`` lands (a symlink's target, as ``open`` follows it) and its status (None if it
    does not exist yet); refused where no file can be written: a folder, a socket, a block device."""
    try:
        info = os.stat(path)  # through symlinks, as open goes
    except (FileNotFoundError, NotADirectoryError):  # below a file: check_folder or mkdir says so
        info = None
    except OSError as exc:  # a symlink loop: name what the user gave
        raise OSError(exc.errno, exc.strerror, str(path)) from None
    if info is None or stat.S_ISREG(info.st_mode):
        return (Path(os.path.realpath(path)) if path.is_symlink() else path), info
    if stat.S_ISDIR(info.st_mode):
        raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))
    if stat.S_ISSOCK(info.st_mode) or stat.S_ISBLK(info.st_mode):  # overwriting a disk is never what was meant
        raise FileRefused(f"{path}: {file_kind(info.st_mode)}; expected the path of a file to write")
    return path, info  # written into by the name given: /dev/stdout's link ends in a pipe no path names


def _naming(exc: BaseException, given: Path, names: set[str]) -> BaseException:
    """``exc`` naming ``given`` where it names one of ``names`` (the temporary file, a symlink's target) or
    no file at all (a failed write or fsync: a full disk); other exceptions as they are."""
    if not isinstance(exc, OSError) or exc.errno is None:
        return exc
    if exc.filename is not None and str(exc.filename) not in names:
        return exc
    return OSError(exc.errno, exc.strerror or str(exc), str(given))  # the subclass its errno gives


@contextmanager
def atomic_path(path: str | os.PathLike, suffix: str = ".tmp", *, follow: bool = True) -> Iterator[Path]:
    """Yield a temporary path in ``path``'s folder; rename it onto ``path`` if the block succeeds.

    The folder is created if needed. On any exception (KeyboardInterrupt
    included) the temporary file is removed and ``path`` is left untouched;
    an OSError naming the temporary file (or no file) is raised naming
    ``path``. A symlink ``path`` is resolved and its target replaced; an
    existing character device or FIFO is yielded itself, to be written into
    (no rename). The temporary file is named before it is created and
    created inside the guarded region, so an interrupt arriving at any
    point, even right after the file appears, cannot leave it behind (one
    interrupt landing between the system call's return and the assignment
    of its descriptor leaks that descriptor until the process ends; Python
    gives no way to close it). The caller writes the yielded path by name:
    whoever can write to the folder could swap it for a symlink before that
    (the file's own mode is set through its descriptor, never by name).
    ``follow=False`` is for the program's own files (cache entries, a
    model's files): whatever is at ``path``, a symlink or a FIFO planted in
    a cache included, is replaced, never written through or into, so it can
    neither hang the write nor send it elsewhere.
    """
    given = Path(path)
    path, info = _target(given) if follow else (given, None)
    if info is not None and not stat.S_ISREG(info.st_mode):
        try:
            yield path
        except BaseException as exc:
            renamed = _naming(exc, given, {str(path)})
            if renamed is exc:
                raise
            raise renamed from exc
        return
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
    except BaseException as exc:
        if fd is not None:
            with suppress(OSError):
                os.close(fd)
        if tmp is not None:
            with suppress(OSError):
                tmp.unlink(missing_ok=True)
        renamed = _naming(exc, given, {str(path), *([str(tmp)] if tmp is not None else [])})
        if renamed is exc:
            raise
        raise renamed from exc


def write_atomically(path: str | os.PathLike, data: bytes | str, *, durable: bool = True,
                     follow: bool = True) -> Path:
    """Write bytes, or text as UTF-8 with ``\\n`` line ends, to ``path`` atomically; returns the path.

    The rename is atomic either way: readers see the old file or the new
    one, never part of one. ``durable`` (the default) also fsyncs the data
    before the rename, so that after a power cut or an OS crash ``path``
    holds the new contents rather than possibly an empty file. Models,
    corpora, results and discovered libraries are written durably; the
    behaviour-likelihood cache passes ``durable=False``, since an entry lost
    in a power cut is recomputed (and one that comes back empty is logged
    and recomputed) while a model is not, and an fsync per entry is slow.
    A device or FIFO (see :func:`atomic_path`, also for ``follow``) is
    written into, not synced.
    """
    path = Path(path)
    payload = data.encode("utf-8") if isinstance(data, str) else data
    with atomic_path(path, follow=follow) as tmp:
        with open(tmp, "wb") as handle:
            handle.write(payload)
            if durable and stat.S_ISREG(os.fstat(handle.fileno()).st_mode):  # fsync of /dev/null is EINVAL
                handle.flush()
                os.fsync(handle.fileno())
    return path


def check_folder(path: str | os.PathLike, what: str, named: str | os.PathLike | None = None) -> Path:
    """``path`` as a folder to create or use, refused (ValueError starting with ``what``) if it, or the
    nearest existing folder above it, is a file. ``named``: the path ``what`` names (default ``path``),
    called "it" in the message."""
    path = Path(path)
    named = path if named is None else Path(named)
    for step in (path, *path.parents):
        it = "it" if step == named else step
        if step.exists():
            if not step.is_dir():
                raise ValueError(f"{what}: {it} is a file, not a folder")
            break
        if step.is_symlink():  # a dangling link: creating the folder would fail with "File exists"
            raise ValueError(f"{what}: {it} is a link to {os.readlink(step)}, which does not exist")
    return path


def check_writable(folder: str | os.PathLike, name: str, what: str) -> Path:
    """``folder`` as one a file ``name`` can be created in, found out by creating and removing a probe file
    there (a permission bit says nothing to root, nor about /proc or a read-only mount); ValueError starting
    with ``what`` if it cannot. A folder that does not exist yet is probed in its nearest existing folder,
    where writing would create it."""
    folder = Path(folder)
    existing = next((step for step in (folder, *folder.parents) if step.is_dir()), Path("."))
    # Named like atomic_path's temporary files, so a probe left by a kill -9 is a leftover they clean up.
    probe = existing / f".{name}.{secrets.token_hex(8)}.tmp"
    try:
        fd = os.open(probe, _CREATE_FLAGS, 0o600)
    except OSError as exc:
        raise ValueError(f"{what}: cannot create a file in {existing} ({exc.strerror or exc})") from None
    try:
        os.close(fd)
    finally:
        probe.unlink(missing_ok=True)
    return folder


# What a folder given as input is read for: a new file of these kinds written into it would be read as one of
# its own by the next run (a corpus's demonstrations, pairs, states).
READ_IN_FOLDERS = (".txt", ".bdm", ".state")


def _check_not_read(path: Path, option: str, reads: Iterable[tuple[str, str | os.PathLike]]) -> None:
    with suppress(OSError):
        if (path.resolve().parent / "model.json").is_file():  # a model folder holds one model's files only
            raise ValueError(f"{option} {path}: inside a model folder ({path.resolve().parent} holds a model.json); "
                             "write it elsewhere")
    for what, given in reads:
        source = Path(given)
        with suppress(OSError):
            if not path.exists():  # a new file replaces nothing, but one a corpus folder reads joins the corpus
                if (path.suffix in READ_IN_FOLDERS and source.is_dir()
                        and path.resolve().is_relative_to(source.resolve())):
                    raise ValueError(f"{option} {path}: inside {what} {given}, which the command reads: a "
                                     f"{path.suffix} file there would be read as part of it next time; write it elsewhere")
                continue
            if os.path.samefile(path, source) or (source.is_dir() and path.resolve().is_relative_to(source.resolve())):
                raise ValueError(f"{option} {path}: the command reads it ({what} {given}); writing the result "
                                 "there would replace its input: name another file")


def check_destination(path: str | os.PathLike, option: str,
                      reads: Iterable[tuple[str, str | os.PathLike]] = ()) -> Path:
    """``path`` as a file to write later, refused now (naming ``option``) if it cannot be: an existing
    folder, socket or block device, a path through a file, or a folder no file can be created in
    (missing folders are created when writing, as ``train -o`` creates its model's). Commands check their
    outputs before the work, so a long run is not lost to a typo at the end. A device or FIFO is written
    into and needs no probe (opening a FIFO here would wait for a reader).

    ``reads``: ``(option, path)`` of what the command reads; writing over one of those files, or over a
    file inside one of those folders (a corpus's), is refused: the result would replace its own input."""
    path = Path(path)
    _check_not_read(path, option, reads)
    if path.is_dir():
        raise ValueError(f"{option} {path}: is a folder; expected the path of a file to write")
    try:
        target, info = _target(path)
    except FileRefused as exc:
        raise ValueError(f"{option} {exc}") from None
    except OSError as exc:
        raise ValueError(f"{option} {path}: {exc.strerror or exc}") from None
    if info is None or stat.S_ISREG(info.st_mode):
        check_folder(target.parent, f"{option} {path}", named=path)
        check_writable(target.parent, target.name, f"{option} {path}")
    return path
