"""One campaign run at a time per run folder: an exclusive lock on ``RUN/.vissim-run.lock``.

The lock file holds the process id of the run that owns the folder.  A second run into the
same folder is refused at once with one line naming that process; nothing of its own is
written.  The lock is an ``flock`` on the open file, so the kernel drops it when the owner
exits for any reason (an error, Ctrl-C, a crash); on a clean exit the file is removed too.
"""

from __future__ import annotations

import contextlib
import logging
import os
from collections.abc import Iterator
from pathlib import Path

from vissim.errors import VissimInputError

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX: runs are not locked
    fcntl = None

__all__ = ["LOCK_FILE_NAME", "run_folder_lock"]

log = logging.getLogger(__name__)

LOCK_FILE_NAME = ".vissim-run.lock"
_ATTEMPTS = 8


def _holder(fd: int) -> str:
    """The process id the lock file records, as text ('an unknown process' when it records none)."""
    with contextlib.suppress(OSError, UnicodeDecodeError):
        text = os.pread(fd, 64, 0).decode().strip()
        if text.isdigit():
            return f"process {text}"
    return "an unknown process"


def _acquire(path: Path, run_dir: Path) -> int:
    """An open descriptor holding the lock on ``path``, or one VissimInputError naming its holder."""
    for _ in range(_ATTEMPTS):
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _holder(fd)
            os.close(fd)
            raise VissimInputError(f"run folder {run_dir} is in use by {holder} (another vissim run); wait for it "
                                   "to finish, or use another run folder") from None
        try:
            on_disk = os.stat(path)
        except FileNotFoundError:
            on_disk = None
        held = os.fstat(fd)
        if on_disk is not None and (on_disk.st_dev, on_disk.st_ino) == (held.st_dev, held.st_ino):
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
            return fd
        os.close(fd)  # the holder removed the file as it finished: lock the new one
    raise VissimInputError(f"run folder {run_dir}: cannot take its lock {path.name} (it keeps changing)")


@contextlib.contextmanager
def run_folder_lock(run_dir: str | os.PathLike[str]) -> Iterator[Path]:
    """Hold ``run_dir`` for this process (created if missing) for the duration of the block.

    Raises `VissimInputError` at once when another process holds it.  A folder this
    call created and that is still empty when the block ends is removed again.
    """
    run_dir = Path(run_dir)
    created = not run_dir.exists()
    try:
        run_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise VissimInputError(f"cannot write {run_dir}: {exc.strerror or exc}") from exc
    if fcntl is None:  # pragma: no cover
        yield run_dir
        return
    path = run_dir / LOCK_FILE_NAME
    try:
        fd = _acquire(path, run_dir)
    except OSError as exc:
        raise VissimInputError(f"cannot write {path}: {exc.strerror or exc}") from exc
    try:
        yield run_dir
    finally:
        with contextlib.suppress(OSError):
            path.unlink()  # while still locked: a waiting run then locks a fresh file
        os.close(fd)
        if created:
            with contextlib.suppress(OSError):
                run_dir.rmdir()  # only when empty: a run that wrote nothing leaves nothing
