"""The file boundary: every file the program reads from a user goes through here.

=============  ================================================================================
module         concept
=============  ================================================================================
(this one)     reading: only regular files, at most :data:`~pendulum_lqg.util.limits.MAX_INPUT_BYTES`,
               UTF-8, JSON or TOML nested at most :data:`~pendulum_lqg.util.limits.MAX_NESTING` deep
``fields``     the kinds of one value (a string, an integer ≥ k, a finite number, a table…) as
               msgspec types; :class:`~pendulum_lqg.problem.errors.Where` names file and key
``schemas``    one schema per external format: score files, stable-baselines3 training records
=============  ================================================================================

Every error is one :class:`~pendulum_lqg.errors.ConfigError` line naming the file, and the key
where one is at fault: ``suite.toml: reference: expected …``. A FIFO or a device is refused before
it is read (opening it does not block: ``O_NONBLOCK``), so ``/dev/zero`` cannot grow the process and
a FIFO cannot hang it.
"""

from __future__ import annotations

import json
import os
import stat
import tomllib
from pathlib import Path
from typing import Any

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.util.files import file_kind
from pendulum_lqg.util.limits import MAX_INPUT_BYTES, MAX_NESTING


def read_bytes(path: str | os.PathLike[str], *, where: str) -> bytes:
    """The bytes of the regular file ``path``; anything else — missing, a folder, a FIFO, a
    device, larger than :data:`~pendulum_lqg.util.limits.MAX_INPUT_BYTES` — is one
    :class:`ConfigError` line starting with ``where``."""
    p = regular_file(path, where=where)
    try:
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise ConfigError(f"{where}: cannot read {p}: {exc.strerror or exc}") from None
    try:
        st = os.fstat(fd)               # the file opened, which may have been swapped since stat
        if not stat.S_ISREG(st.st_mode):
            raise ConfigError(f"{where}: {p} is {file_kind(st.st_mode)}; expected a regular file")
        _check_size(where, p, st.st_size)
        chunks, size = [], 0
        while size <= MAX_INPUT_BYTES:          # a file that grows while read stops at the ceiling
            chunk = os.read(fd, min(1 << 20, MAX_INPUT_BYTES + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
        _check_size(where, p, size)
        return b"".join(chunks)
    except OSError as exc:
        raise ConfigError(f"{where}: cannot read {p}: {exc.strerror or exc}") from None
    finally:
        os.close(fd)


def regular_file(path: str | os.PathLike[str], *, where: str) -> Path:
    """``path`` checked to be a regular file (a symbolic link followed) before a library that
    opens it by name reads it (an SB3 model, a pickle of statistics): missing, a folder, a FIFO (it
    would hang the reader) or a device (it would grow it) is one :class:`ConfigError` line
    starting with ``where``."""
    p = Path(path)
    try:
        mode = os.stat(p).st_mode
    except FileNotFoundError:
        raise ConfigError(f"{where}: no file {p}") from None
    except OSError as exc:
        raise ConfigError(f"{where}: cannot read {p}: {exc.strerror or exc}") from None
    if not stat.S_ISREG(mode):
        raise ConfigError(f"{where}: {p} is {file_kind(mode)}; expected a regular file")
    return p


def _check_size(where: str, path: Path, size: int) -> None:
    if size > MAX_INPUT_BYTES:
        raise ConfigError(f"{where}: {path} is larger than {MAX_INPUT_BYTES:,} bytes (the ceiling "
                          f"of a file read whole), got {size:,}")


def read_text(path: str | os.PathLike[str], *, where: str) -> str:
    """The UTF-8 text of the regular file ``path`` (see :func:`read_bytes`)."""
    data = read_bytes(path, where=where)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{where}: {path} is not UTF-8 text: byte {data[exc.start]:#04x} at "
                          f"offset {exc.start}") from None


def read_json(path: str | os.PathLike[str], *, where: str) -> Any:
    """The JSON value of the file ``path``, nested at most :data:`~pendulum_lqg.util.limits.MAX_NESTING`
    deep."""
    text = read_text(path, where=where)
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ConfigError(f"{where}: {path} is not valid JSON ({exc.msg} at line {exc.lineno}, "
                          f"column {exc.colno})") from None
    except RecursionError:
        raise ConfigError(_too_deep(where, path)) from None
    check_nesting(data, where=where, path=path)
    return data


def read_toml(path: str | os.PathLike[str], *, where: str) -> dict[str, Any]:
    """The TOML table of the file ``path``, nested at most :data:`~pendulum_lqg.util.limits.MAX_NESTING`
    deep."""
    text = read_text(path, where=where)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{where}: {path} is not valid TOML: {' '.join(str(exc).split())}"
                          ) from None
    except RecursionError:
        raise ConfigError(_too_deep(where, path)) from None
    check_nesting(data, where=where, path=path)
    return data


def _too_deep(where: str, path: object) -> str:
    return (f"{where}: {path} is nested deeper than {MAX_NESTING} levels (the ceiling of tables "
            "and lists in a file)")


def check_nesting(data: Any, *, where: str, path: object) -> None:
    """Tables and lists of ``data`` nest at most :data:`~pendulum_lqg.util.limits.MAX_NESTING` deep
    (walked without recursion)."""
    stack = [(data, 1)]
    while stack:
        value, depth = stack.pop()
        if isinstance(value, dict | list):
            if depth > MAX_NESTING:
                raise ConfigError(_too_deep(where, path))
            items = value.values() if isinstance(value, dict) else value
            stack.extend((v, depth + 1) for v in items if isinstance(v, dict | list))


__all__ = ["check_nesting", "file_kind", "read_bytes", "read_json", "read_text", "read_toml",
           "regular_file"]
