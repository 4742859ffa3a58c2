"""logic.storage: atomic writes leave the old file or the new one, never a temporary file, whatever interrupts them."""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

import pytest

from groundlang.logic import storage
from groundlang.logic.storage import atomic_path, write_atomically


def _previous(tmp_path):
    target = tmp_path / "target.json"
    target.write_bytes(b"previous")
    return target


def _assert_untouched(tmp_path, target):
    assert sorted(p.name for p in tmp_path.iterdir()) == [target.name], "a temporary file was left behind"
    assert target.read_bytes() == b"previous"


def test_write_replaces_the_target_and_leaves_nothing_else(tmp_path):
    target = _previous(tmp_path)
    assert write_atomically(target, "new\n") == target
    assert target.read_bytes() == b"new\n"
    write_atomically(tmp_path / "sub" / "b.bin", b"\x00\x01")  # the folder is created
    assert (tmp_path / "sub" / "b.bin").read_bytes() == b"\x00\x01"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sub", target.name]


def test_temporary_file_is_next_to_the_target_with_plain_open_permissions(tmp_path):
    target = tmp_path / "out.gif"
    with atomic_path(target, suffix=".gif") as tmp:
        assert tmp.parent == tmp_path and tmp.name.startswith(".out.gif.") and tmp.name.endswith(".gif")
        assert tmp.exists()
        assert stat.S_IMODE(tmp.stat().st_mode) == 0o666 & ~storage._UMASK
        tmp.write_bytes(b"x")
    assert target.read_bytes() == b"x"


def test_interrupt_in_the_block_keeps_the_previous_target(tmp_path):
    target = _previous(tmp_path)
    with pytest.raises(KeyboardInterrupt):
        with atomic_path(target) as tmp:
            tmp.write_bytes(b"half of the new")
            raise KeyboardInterrupt
    _assert_untouched(tmp_path, target)


@pytest.mark.parametrize("where", ["open", "fchmod", "close"])
def test_interrupt_right_after_the_temporary_file_appears_leaves_nothing(tmp_path, monkeypatch, where):
    """Ctrl-C just after the temporary file is created (even before its name reaches atomic_path) is cleaned up."""
    target = _previous(tmp_path)
    real = getattr(os, where)
    created = []

    def interrupted(*args, **kwargs):
        real(*args, **kwargs)  # the temporary file exists now
        created.append(args[0])
        raise KeyboardInterrupt

    monkeypatch.setattr(os, where, interrupted)
    with pytest.raises(KeyboardInterrupt):
        write_atomically(target, b"new")
    monkeypatch.undo()
    assert created, f"os.{where} was not called"
    _assert_untouched(tmp_path, target)


def test_failed_write_keeps_the_previous_target(tmp_path, monkeypatch):
    target = _previous(tmp_path)

    def full_disk(fd):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", full_disk)
    with pytest.raises(OSError, match="No space"):
        write_atomically(target, b"new")
    _assert_untouched(tmp_path, target)


@pytest.mark.parametrize("durable, fsyncs", [(True, 1), (False, 0)])
def test_durable_decides_the_fsync(tmp_path, monkeypatch, durable, fsyncs):
    real = os.fsync
    calls = []

    def recording_fsync(fd):
        calls.append(fd)
        real(fd)

    monkeypatch.setattr(os, "fsync", recording_fsync)
    target = _previous(tmp_path)
    write_atomically(target, b"new", durable=durable)
    assert len(calls) == fsyncs
    assert target.read_bytes() == b"new"
    assert sorted(p.name for p in tmp_path.iterdir()) == [target.name]


def test_durable_is_keyword_only(tmp_path):
    with pytest.raises(TypeError):
        write_atomically(tmp_path / "a", b"1", False)


def test_cache_entries_are_not_fsynced(tmp_path, monkeypatch):
    """The behaviour-likelihood cache writes its entries with durable=False: a lost entry is recomputed."""
    from groundlang.inference import likelihoods

    calls = []
    monkeypatch.setattr(os, "fsync", lambda fd: calls.append(fd))
    path = tmp_path / "cache" / "behaviour" / "ab" / "abcd.json"
    likelihoods._write_entry(path, "abcd", -1.5, ["in(box, red)"])
    assert calls == []
    assert likelihoods._read_entry(path, "abcd") == -1.5


def test_the_temporary_file_mode_is_set_through_its_descriptor_not_its_name(tmp_path, monkeypatch):
    """A name-based chmod would follow a symlink swapped in for the temporary file."""
    called = []
    monkeypatch.setattr(os, "chmod", lambda *a, **k: called.append(a))
    write_atomically(tmp_path / "out.txt", "x")
    assert not called
    assert (tmp_path / "out.txt").read_text() == "x"


# ----------------------------------------------------------------- destinations that are not plain files
def _no_rename(monkeypatch):
    monkeypatch.setattr(os, "replace", lambda *a, **k: pytest.fail(f"renamed onto {a[1]}"))


def test_a_symlink_is_written_through_in_its_target_folder(tmp_path):
    """Before, the link itself was replaced by a regular file and its target kept the old contents."""
    (tmp_path / "real").mkdir()
    (tmp_path / "links").mkdir()
    target = _previous(tmp_path / "real")
    link = tmp_path / "links" / "result.json"
    link.symlink_to(target)
    with atomic_path(link) as tmp:
        assert tmp.parent == target.parent  # renamed within the target's folder: atomic
        tmp.write_bytes(b"new")
    assert link.is_symlink() and target.read_bytes() == b"new"
    assert sorted(p.name for p in (tmp_path / "real").iterdir()) == [target.name]
    assert sorted(p.name for p in (tmp_path / "links").iterdir()) == [link.name]


def test_a_fifo_is_written_into_not_replaced(tmp_path, monkeypatch):
    import threading

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    read = []
    reader = threading.Thread(target=lambda: read.append(fifo.read_bytes()), daemon=True)
    reader.start()
    _no_rename(monkeypatch)
    write_atomically(fifo, "through the pipe\n")  # durable: a FIFO cannot be fsynced, and is not
    reader.join(10)
    assert read == [b"through the pipe\n"]
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pipe"]


def test_a_character_device_is_written_into_never_renamed_onto(monkeypatch):
    """As root, ``evaluate --json /dev/full`` made /dev/full an ordinary file. /dev/null is written here only
    because the rename is made to fail first: the device cannot be replaced."""
    if not stat.S_ISCHR(os.stat("/dev/null").st_mode):
        pytest.skip("no /dev/null character device")
    _no_rename(monkeypatch)
    monkeypatch.setattr(os, "open", lambda *a, **k: pytest.fail("a temporary file was created"))
    assert storage.check_destination("/dev/null", "--json") == Path("/dev/null")
    with atomic_path("/dev/null") as path:
        assert path == Path("/dev/null")
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)


def test_a_full_device_is_one_error_naming_it(monkeypatch):
    if not os.path.exists("/dev/full") or not stat.S_ISCHR(os.stat("/dev/full").st_mode):
        pytest.skip("no /dev/full character device")
    _no_rename(monkeypatch)
    with pytest.raises(OSError) as caught:
        write_atomically("/dev/full", b"x" * 10)
    assert caught.value.errno == errno.ENOSPC and caught.value.filename == "/dev/full"
    assert stat.S_ISCHR(os.stat("/dev/full").st_mode)


def test_a_folder_or_a_socket_is_refused_naming_it(tmp_path):
    import socket

    with pytest.raises(IsADirectoryError) as caught:
        write_atomically(tmp_path, b"x")
    assert caught.value.filename == str(tmp_path)
    sock = tmp_path / "s"
    server = socket.socket(socket.AF_UNIX)
    try:
        server.bind(str(sock))
        with pytest.raises(storage.FileRefused, match=f"{sock}: a socket; expected the path of a file to write"):
            write_atomically(sock, b"x")
        with pytest.raises(ValueError, match=f"--json {sock}: a socket"):
            storage.check_destination(sock, "--json")
    finally:
        server.close()


# ----------------------------------------------------------------- errors name the path the caller gave
_PROC = Path("/proc/self").is_dir()


def test_an_error_naming_the_temporary_file_names_the_target(tmp_path):
    """``show --out /proc/x.png`` said "/proc/.x.png.7a3e....tmp: No such file or directory"."""
    target = tmp_path / "picture.png"
    with pytest.raises(OSError) as caught:
        with atomic_path(target) as tmp:
            raise OSError(errno.ENOSPC, "No space left on device", str(tmp))  # what a failed savefig raises
    assert caught.value.filename == str(target) and caught.value.errno == errno.ENOSPC
    assert isinstance(caught.value, OSError) and ".tmp" not in str(caught.value)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not _PROC, reason="needs /proc, where no file can be created")
def test_a_folder_that_takes_no_file_is_named_as_given():
    with pytest.raises(OSError) as caught:  # no such file (root) or permission denied
        with atomic_path("/proc/x.png") as tmp:
            tmp.write_bytes(b"x")
    assert caught.value.filename == "/proc/x.png" and caught.value.filename2 is None


# ----------------------------------------------------------------- destinations checked before the work
@pytest.mark.skipif(not _PROC, reason="needs /proc, where no file can be created")
@pytest.mark.parametrize("given", ["/proc/x.json", "/proc/new/folder/x.json"])
def test_a_destination_no_file_can_be_created_in_is_refused_by_check_destination(given):
    """Before, only folders and paths through a file were refused: /proc/x.json passed the check and the
    write failed after the whole evaluation."""
    with pytest.raises(ValueError, match=f"^--json {given}: cannot create a file in /proc "):
        storage.check_destination(given, "--json")


def test_check_destination_leaves_nothing_and_creates_no_folder(tmp_path):
    assert storage.check_destination(tmp_path / "a" / "b" / "r.json", "--json") == tmp_path / "a" / "b" / "r.json"
    assert list(tmp_path.iterdir()) == []  # probed in tmp_path, where the folders would be made
    write_atomically(tmp_path / "a" / "b" / "r.json", "{}")  # and the write makes them, as train -o does
    assert (tmp_path / "a" / "b" / "r.json").read_text() == "{}"


@pytest.mark.skipif(not _PROC, reason="needs /proc, where no file can be created")
def test_a_model_destination_no_file_can_be_created_in_is_refused():
    from groundlang.model_io import check_model_destination

    with pytest.raises(ValueError, match="^-o /proc/m: cannot create a file in /proc "):
        check_model_destination("/proc/m", "-o")


def test_dev_stdout_is_written_into_when_it_is_a_pipe():
    """/dev/stdout links to /proc/self/fd/1, whose link ends in a pipe no path names: the result is
    written into it by the name given (``--json /dev/stdout``), neither probed nor resolved."""
    import subprocess
    import sys

    script = ("from groundlang.logic.storage import check_destination, write_atomically; "
              "check_destination('/dev/stdout', '--json'); write_atomically('/dev/stdout', 'hello\\n')")
    done = subprocess.run([sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout == "hello\n"


def test_a_dangling_link_where_a_folder_goes_is_named_as_one(tmp_path):
    """GROUNDLANG_CACHE set to a link whose target is gone said "cannot be written (File exists)"."""
    (tmp_path / "cache").symlink_to(tmp_path / "gone")
    with pytest.raises(ValueError, match=f"^the cache folder: it is a link to {tmp_path / 'gone'}, which does not exist$"):
        storage.check_folder(tmp_path / "cache", "the cache folder")
    with pytest.raises(ValueError, match=f"^-o: {tmp_path / 'cache'} is a link to"):
        storage.check_folder(tmp_path / "cache" / "model", "-o")
    (tmp_path / "gone").mkdir()
    assert storage.check_folder(tmp_path / "cache" / "model", "-o") == tmp_path / "cache" / "model"
