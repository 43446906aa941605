"""Files that are never half-written, outputs that only ever replace regular files, and the CSV
form of episode rows.

Kept apart from :mod:`pendulum_lqg.bench.results` (which knows experiments) so that everything that
writes files — sweeps, studies, reports, scores, boards — can use them without importing the
experiment layer. Reading files at the boundary is :mod:`pendulum_lqg.boundary`'s.
"""

from __future__ import annotations

import contextlib
import csv
import errno
import io
import os
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from pendulum_lqg.errors import ConfigError

FILE_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
          (stat.S_ISSOCK, "a socket"))


def file_kind(mode: int) -> str:
    """What a file of ``st_mode`` ``mode`` is, for a message ("a FIFO (named pipe)")."""
    return next((name for test, name in FILE_KINDS if test(mode)), "not a regular file")


def output_file(where: str, path: str | os.PathLike[str] | None, *, what: str = "file") -> Path:
    """``path`` checked as the target of an output file, before any work starts.

    A target that exists must be a regular file (a symbolic link is followed): a device, a FIFO, a
    socket or a folder is refused, so an output never replaces what is not ours. ``''`` is refused.
    The parent folder is created and must be writable. Errors are one :class:`ConfigError` line
    naming ``where`` (the option, e.g. ``--out``)."""
    text = "" if path is None else os.fspath(path)
    if not str(text).strip():
        raise ConfigError(f"{where}: expected a path for the {what}, got {text!r}")
    out = Path(text)
    target = regular_target(where, out, what=what)
    writable_folder(where, target.parent)
    return target


def writable_folder(where: str, folder: Path) -> Path:
    """``folder`` created (with its parents) if missing, and writable; else one
    :class:`ConfigError` line naming ``where``."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"{where}: cannot create the folder {folder}: "
                          f"{exc.strerror or exc}") from None
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ConfigError(f"{where}: the folder {folder} is not writable")
    return folder


def output_folder(where: str, path: str | os.PathLike[str] | None, *,
                  what: str = "outputs") -> Path:
    """``path`` checked as a folder to write into, before any work starts: absent (it is created,
    with its parents) or a folder (a symbolic link followed). A regular file, a device, a FIFO, a
    socket or a symbolic link that loops is one :class:`ConfigError` line naming ``where``, and is
    left as it is; so is ``''`` and a folder that cannot be written."""
    text = "" if path is None else os.fspath(path)
    if not str(text).strip():
        raise ConfigError(f"{where}: expected a folder for the {what}, got {text!r}")
    folder = Path(text)
    try:
        mode = os.stat(folder).st_mode
    except FileNotFoundError:
        mode = None
    except (OSError, RuntimeError) as exc:
        looping = getattr(exc, "errno", None) == errno.ELOOP
        raise ConfigError(f"{where}: {folder} " + ("is a symbolic link that loops" if looping else
                          f"cannot be inspected ({getattr(exc, 'strerror', None) or exc})")
                          + f"; expected a folder for the {what}") from None
    if mode is not None and not stat.S_ISDIR(mode):
        kind = "a regular file" if stat.S_ISREG(mode) else file_kind(mode)
        raise ConfigError(f"{where}: {folder} is {kind}; expected a folder for the {what} (it "
                          "is created if missing; the path is left as it is)")
    return writable_folder(where, folder)


def regular_target(where: str, path: Path, *, what: str = "file") -> Path:
    """The file ``path`` names (a symbolic link followed), which must be absent or a regular
    file; anything else — a device, a FIFO, a socket, a folder, a symbolic link that loops — is
    one :class:`ConfigError` line, and is left as it is."""
    try:
        target = path.resolve() if path.is_symlink() else path
        mode = os.stat(target).st_mode
    except FileNotFoundError:
        return target
    except (OSError, RuntimeError) as exc:     # pathlib reports a loop as RuntimeError (< 3.13)
        if isinstance(exc, RuntimeError) or exc.errno == errno.ELOOP:
            raise ConfigError(f"{where}: {path} is a symbolic link that loops (or a chain of "
                              f"too many links); expected a regular file or a new path for the "
                              f"{what} (it is left as it is)") from None
        raise ConfigError(f"{where}: cannot inspect {path}: "
                          f"{getattr(exc, 'strerror', None) or exc}") from None
    if not stat.S_ISREG(mode):
        raise ConfigError(f"{where}: {path} is {file_kind(mode)}; expected a regular file or a "
                          f"new path for the {what} (it is left as it is)")
    return target


def remove_entry(path: str | os.PathLike[str]) -> None:
    """Remove the name ``path`` from its folder: a symbolic link itself (never what it points to,
    a file or a folder outside), a file, or a folder tree (its own entries only: links inside it
    are removed as links). Absent: nothing. The one rule of ``--force`` for a folder of outputs
    (``bench``'s results folder, ``train``'s run files): a run replaces what it wrote, never
    the target of a link a user put there."""
    p = Path(path)
    try:
        mode = os.lstat(p).st_mode
    except FileNotFoundError:
        return
    if stat.S_ISDIR(mode):
        import shutil

        shutil.rmtree(p)
    else:
        p.unlink(missing_ok=True)


@contextlib.contextmanager
def replacing(path: str | os.PathLike[str], *, where: str = "out",
              what: str = "file") -> Iterator[Path]:
    """A new temporary path beside ``path`` to write to; when the block ends without error it
    replaces ``path`` atomically, so ``path`` is never half-written.

    The output rule of every file the package writes for a user (pictures, recordings, scores,
    boards, results): ``path`` must be absent or a regular file (:func:`regular_target`: a device,
    a FIFO, a socket, a folder or a looping symbolic link is one :class:`ConfigError` line naming
    ``where``, and is left as it is). The temporary file is created exclusively in the same folder
    and keeps ``path``'s suffix (writers that pick a format by the suffix — matplotlib, Rerun —
    see the right one); after the block it is fsynced and renamed over the target
    (``os.replace``), and the folder is fsynced so the new name survives a crash. On any error
    (a full disk, a file-size limit, a Ctrl-C) the temporary file is removed and ``path`` keeps
    its old content whole::

        with replacing(out, where="--plot", what="picture") as tmp:
            fig.savefig(tmp, format="png")
    """
    target = regular_target(where, Path(path), what=what)
    tmp = target.with_name(f".{target.name}.{os.getpid()}.{os.urandom(4).hex()}.tmp")
    os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
    try:
        yield tmp
        fd = os.open(tmp, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        os.replace(tmp, target)
    except BaseException as exc:
        tmp.unlink(missing_ok=True)
        if isinstance(exc, OSError) and exc.filename in (None, str(tmp)):
            # named after the user's file, not the hidden temporary one (same errno and class)
            raise OSError(exc.errno, exc.strerror, str(target)) from exc
        raise
    _fsync_folder(target.parent)


def atomic_write(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` so that ``path`` is never half-written and nothing is left behind
    (:func:`replacing`: only a new path or a regular file is ever replaced)."""
    with replacing(path) as tmp, open(tmp, "w", encoding="utf-8", newline="") as fh:
        fh.write(text)


def save_figure(fig: Any, path: str | os.PathLike[str], *, where: str = "out",
                what: str = "picture", dpi: float | None = None,
                bbox_inches: str | None = None) -> Path:
    """``fig.savefig(…)`` (a matplotlib ``Figure``) under the output rule (:func:`replacing`): the
    picture at ``path`` is replaced whole or not at all. The format is ``path``'s suffix
    (``.png``, ``.svg``, ``.pdf``); ``dpi`` and ``bbox_inches`` are ``Figure.savefig``'s (``None``:
    its default, ``rcParams["savefig.*"]``). Returns the path written (a symbolic link followed)."""
    target = regular_target(where, Path(path), what=what)
    fmt = target.suffix.lstrip(".").lower() or None
    with replacing(target, where=where, what=what) as tmp:
        options = {k: v for k, v in (("dpi", dpi), ("bbox_inches", bbox_inches)) if v is not None}
        fig.savefig(tmp, format=fmt, **options)
    return target


def _fsync_folder(folder: Path) -> None:
    """fsync a folder (its entries: a rename in it); a no-op where folders cannot be opened."""
    try:
        fd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        return
    try:
        with contextlib.suppress(OSError):     # some file systems refuse fsync on a folder
            os.fsync(fd)
    finally:
        os.close(fd)


def _cell(v: object) -> str:
    if isinstance(v, float):
        return repr(v)
    return str(v)


def rows_to_csv(rows: list[dict[str, object]]) -> str:
    if not rows:
        return ""
    buf = io.StringIO()
    fields = list(rows[0])
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(fields)
    for r in rows:
        w.writerow([_cell(r.get(f, "")) for f in fields])
    return buf.getvalue()


def _parse(v: str) -> object:
    if v in ("True", "False"):
        return v == "True"
    try:
        return int(v)
    except ValueError:
        pass
    try:
        return float(v)
    except ValueError:
        return v


def read_csv(path: Path) -> list[dict[str, object]]:
    with open(path, newline="", encoding="utf-8") as fh:
        return [{k: _parse(v) for k, v in row.items()} for row in csv.DictReader(fh)]


class FileLock:
    """An exclusive lock held by this process on the file ``path`` (a results folder's ``.lock``).

    ``flock`` on the open file: the kernel releases it when the process ends, however it ends, so a
    killed run leaves no lock to take over and two runs can never both hold it (the old PID-file
    lock could be taken by two runs that both saw a dead PID). The file holds the holder's PID for
    the message of a run that is refused. It is removed on release while still locked; a run that
    opened it just before and locks the removed file sees that the path no longer names what it
    locked and tries again. Where ``flock`` does not exist (Windows), the file is created
    exclusively instead and a crashed run's lock must be removed by hand (the message says so).
    """

    def __init__(self, path: Path, *, where: str) -> None:
        """``where`` begins the refusal's line (``out: results/lecture``)."""
        self.path, self.where = Path(path), where
        self._fd: int | None = None

    def acquire(self) -> None:
        """Take the lock, or raise a one-line :class:`ConfigError` naming the holder's PID."""
        try:
            import fcntl
        except ImportError:                     # no flock: an exclusive create
            self._fd = self._create_exclusive()
            return
        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = os.read(fd, 32).decode(errors="replace").strip() or "?"
                os.close(fd)
                raise ConfigError(f"{self.where} is being written by another run (pid {holder})"
                                  ) from None
            try:
                same = os.path.samestat(os.fstat(fd), os.stat(self.path))
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)                        # its holder removed it meanwhile: again
        os.ftruncate(fd, 0)
        os.write(fd, str(os.getpid()).encode())
        self._fd = fd

    def _create_exclusive(self) -> int:
        try:
            fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            raise ConfigError(f"{self.where} is being written by another run (or a crashed "
                              f"one: remove {self.path} if none runs)") from None
        os.write(fd, str(os.getpid()).encode())
        return fd

    def release(self) -> None:
        if self._fd is None:
            return
        self.path.unlink(missing_ok=True)       # removed while still held (see the class doc)
        os.close(self._fd)                      # closing the file drops the flock
        self._fd = None

    @property
    def held(self) -> bool:
        return self._fd is not None
