"""Files written so that a reader never sees half of one: atomically, or not at all.

Every output a user keeps (maps, reports, sweep tables, replays, trajectories) is written with
``write_atomic``: the bytes go to a temporary file in the same folder, are flushed to disk, and
the temporary file is then renamed over the target (``os.replace``, atomic on POSIX and
Windows within one file system). A run stopped at any moment, Ctrl-C included, leaves either the
old file or the new one, never a truncated mix; the temporary file is removed on any error.
"""

from __future__ import annotations

import contextlib
import os
import signal
import tempfile
import threading
from pathlib import Path

from drake_sim.base.errors import ConfigError


def write_atomic(path: Path | str, data: str | bytes, what: str = "file") -> Path:
    """Writes ``data`` (text as UTF-8, or bytes) to ``path`` atomically, making its folder.

    Returns:
        ``path`` as a ``Path``.

    Raises:
        ConfigError: the file cannot be written (one line naming it and why); the target is then
            as it was.
    """
    return write_atomic_many([(path, data)], what)[0]


def write_atomic_many(items, what: str = "file") -> list[Path]:
    """Writes several files as one: each ``(path, data)`` of ``items`` goes to a temporary file
    beside its target first; only when all are written are they renamed into place, one after
    the other, with Ctrl-C and SIGTERM held back until the last rename (a map's ``.pgm`` and
    ``.yaml`` are never left from two different runs).

    Returns:
        The paths, in order.

    Raises:
        ConfigError: a file cannot be written (one line naming it and why); the targets are then
            as they were (a failed rename, after the others were written, leaves only its own).
    """
    items = [(Path(path), data) for path, data in items]
    staged: list[tuple[str, Path]] = []
    current = None
    try:
        for path, data in items:
            current = path
            payload = data.encode("utf-8") if isinstance(data, str) else bytes(data)
            path.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp_name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
            staged.append((tmp_name, path))
            with os.fdopen(fd, "wb") as f:
                f.write(payload)
                f.flush()
                os.fsync(f.fileno())
            os.chmod(tmp_name, file_mode(path))
        with signals_held():
            while staged:
                tmp_name, current = staged[0]
                os.replace(tmp_name, current)
                staged.pop(0)
    except OSError as e:
        raise ConfigError(f"{what} cannot be written: {current} ({e.strerror or e})") from None
    finally:
        for tmp_name, _ in staged:
            with contextlib.suppress(OSError):
                os.unlink(tmp_name)
    return [path for path, _ in items]


def file_mode(path: Path) -> int:
    """The permission bits a write in place of ``path`` would leave: its own if it exists,
    else a new file's under the process's umask."""
    return path.stat().st_mode & 0o7777 if path.exists() else 0o666 & ~_UMASK


@contextlib.contextmanager
def signals_held():
    """Within the block, SIGINT and SIGTERM are recorded instead of handled; at its end the
    previous handlers come back and each recorded signal is raised again through them. (A signal
    mask would not do: the kernel hands a process's signal to any thread that does not block it,
    and Meshcat's and the planner's threads do not.) Outside the main thread, nothing is held."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    previous = {}
    for signum in (signal.SIGINT, signal.SIGTERM):
        previous[signum] = signal.signal(signum, lambda s, _frame: caught.append(s))
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler if handler is not None else signal.SIG_DFL)
        for signum in caught:
            signal.raise_signal(signum)


def _read_umask() -> int:
    """The process's umask (read by setting and restoring it: done once, at import)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask


_UMASK = _read_umask()
