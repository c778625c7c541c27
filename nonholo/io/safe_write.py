"""Writing a file without destroying what is at its path.

Every file the package writes for a user (plan files, CSV, figures, sweep outputs) goes
through this module. The target ``path`` (a symbolic link is followed to its target) is:

- absent or a regular file: written *atomically* — the data goes to a new temporary file
  in the same directory, flushed and synced, which then replaces ``path`` by a rename (a
  replaced file keeps its permission bits); if anything fails the temporary file is
  removed and ``path`` is untouched;
- a character device or a FIFO (``/dev/null``, ``/dev/stdout``, a named pipe the user
  made on purpose): written *in place* — opened for writing and written to, never replaced,
  never truncated (a write to ``/dev/full`` raises ``OSError``; opening a FIFO waits for
  its reader, as any writer of a FIFO does);
- anything else (a directory, a socket, a block device): refused with a ``ValueError``
  naming the argument, before anything is written.

:func:`write_bytes` and :func:`write_text` write data held in memory;
:func:`replacing` is for writers that want a path of their own (a Parquet or image
library): it yields a temporary path to write, then puts that file in place the same way.
:func:`check_target` is the check alone, for a caller that wants to refuse a bad path
before doing any work.
"""
from __future__ import annotations

import contextlib
import os
import secrets
import stat
from pathlib import Path

__all__ = ["check_target", "write_bytes", "write_text", "replacing", "REPLACE", "IN_PLACE"]

#: how a target is written: by an atomic rename (absent or regular file) ...
REPLACE = "replace"
#: ... or by writing into it (character device, FIFO)
IN_PLACE = "in place"


def _kind(mode: int) -> str:
    for test, name in ((stat.S_ISDIR, "a directory"), (stat.S_ISSOCK, "a socket"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISFIFO, "a FIFO"), (stat.S_ISLNK, "a symbolic link")):
        if test(mode):
            return name
    return "not a regular file"


def check_target(path, argument: str = "path") -> tuple[Path, str]:
    """The file ``path`` names and how it is written (see the module).

    Parameters
    ----------
    path : str or os.PathLike
        The target.
    argument : str
        The name the errors give the path (``"--out"``).

    Returns
    -------
    target : pathlib.Path
        The file ``path`` names (a symbolic link followed).
    how : str
        :data:`REPLACE` or :data:`IN_PLACE`.

    Raises
    ------
    ValueError
        Naming ``argument``, for a path that exists and is neither a regular file, a
        character device nor a FIFO, or that is empty or ends in a separator.
    TypeError
        For a path that is not a string or path-like.
    """
    if isinstance(path, bytes) or not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"{argument} must be a file path (str or path-like), got {type(path).__name__}")
    text = os.fspath(path)
    if not isinstance(text, str):
        raise TypeError(f"{argument} must be a file path (str or path-like), got {type(path).__name__}")
    if not text or "\0" in text:
        raise ValueError(f"{argument} must be a file path, got {text!r}")
    if text.endswith(("/", os.sep)):
        raise ValueError(f"{argument} {text!r} names a directory (it ends in a separator), not a file")
    p = Path(text)
    target = Path(os.path.realpath(p)) if p.is_symlink() else p
    try:
        st = os.stat(target)
    except OSError:
        return target, REPLACE           # absent (or unreachable: the write says why)
    if stat.S_ISREG(st.st_mode):
        return target, REPLACE
    if stat.S_ISCHR(st.st_mode) or stat.S_ISFIFO(st.st_mode):
        return target, IN_PLACE
    raise ValueError(f"{argument} {text!r} is {_kind(st.st_mode)}, not a regular file: "
                     "refusing to replace it")


def _in_place(target: Path, data: bytes) -> None:
    """Write ``data`` into the device or FIFO ``target`` (no creation, no truncation)."""
    fd = os.open(target, os.O_WRONLY | getattr(os, "O_NOCTTY", 0))
    try:
        st = os.fstat(fd)
        if not (stat.S_ISCHR(st.st_mode) or stat.S_ISFIFO(st.st_mode)):
            # replaced between the check and the open: a regular file is not written in place
            raise OSError(f"{target} changed while it was being written")
        view = memoryview(data)
        while view:
            n = os.write(fd, view)
            view = view[n:]
    finally:
        os.close(fd)


def _temporary(directory: Path, name: str) -> tuple[int, Path]:
    for _ in range(100):
        tmp = directory / f".{name}.{secrets.token_hex(4)}.tmp"
        try:
            # mode 0o666 less the umask, as a file created by open(path, "w")
            return os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666), tmp
        except FileExistsError:
            continue
    raise FileExistsError(f"no free temporary file name in {directory}")


def _put_in_place(tmp: Path, target: Path, argument: str) -> None:
    """Rename the synced ``tmp`` over ``target`` (re-checked just before), keeping the
    replaced file's permission bits; make the rename durable."""
    _, how = check_target(target, argument)
    if how == IN_PLACE:                  # became a device or FIFO meanwhile: write into it
        _in_place(target, tmp.read_bytes())
        os.unlink(tmp)
        return
    with contextlib.suppress(OSError):
        mode = stat.S_IMODE(os.stat(target).st_mode)
        os.chmod(tmp, mode)              # replacing a file keeps its permissions
    os.replace(tmp, target)
    # make the rename itself durable (POSIX; where a directory cannot be opened, skip)
    with contextlib.suppress(OSError, AttributeError):
        dfd = os.open(target.parent, os.O_RDONLY)
        try:
            os.fsync(dfd)
        finally:
            os.close(dfd)


def write_bytes(path, data: bytes, argument: str = "path") -> Path:
    """Write ``data`` to ``path`` safely (see the module).

    Parameters
    ----------
    path : str or os.PathLike
        The target.
    data : bytes
        What to write.
    argument : str
        The name the errors give the path (``"--out"``).

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    ValueError
        Naming ``argument``, for a path :func:`check_target` refuses.
    OSError
        If the write fails (``path`` is then untouched, unless written in place).
    """
    target, how = check_target(path, argument)
    data = bytes(data)
    if how == IN_PLACE:
        _in_place(target, data)
        return Path(path)
    fd, tmp = _temporary(target.parent, target.name)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        _put_in_place(tmp, target, argument)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    return Path(path)


def write_text(path, text: str, argument: str = "path") -> Path:
    """Write ``text`` as UTF-8 to ``path`` safely (:func:`write_bytes`).

    Parameters
    ----------
    path : str or os.PathLike
        The target.
    text : str
        What to write.
    argument : str
        The name the errors give the path.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    return write_bytes(path, text.encode("utf-8"), argument)


@contextlib.contextmanager
def replacing(path, argument: str = "path"):
    """A temporary path for a writer to write ``path``'s new content to.

    When the block ends without an exception the file is synced and put in place as
    :func:`write_bytes` would (renamed over a regular file, copied into a device or FIFO),
    else removed and ``path`` left untouched.

    Parameters
    ----------
    path : str or os.PathLike
        The target, checked (:func:`check_target`) before the block runs.
    argument : str
        The name the errors give the path.

    Yields
    ------
    pathlib.Path
        The temporary file, ``.name.<random>.tmp`` beside the target.

    Raises
    ------
    ValueError
        Naming ``argument``, for a path :func:`check_target` refuses.

    Examples
    --------
    ::

        with replacing(out, "--out") as tmp:
            table.to_parquet(tmp)
    """
    target, _ = check_target(path, argument)
    fd, tmp = _temporary(target.parent, target.name)
    os.close(fd)
    try:
        yield tmp
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())
        _put_in_place(tmp, target, argument)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
