"""Atomic file output: a file appears complete at its final path, or not at all.

Every file vissim writes goes through `atomic_output`.  The writer is handed a
temporary path in the same directory as the target (so the final `os.replace` is a
rename on one filesystem); the temporary name keeps the real suffix, e.g.
``.out.png.3f9c1a2b.tmp.png``, so libraries that choose a format from the suffix still
work.  If anything goes wrong inside the ``with`` block -- including ``KeyboardInterrupt``
-- the temporary file is removed and whatever was at the target path is left untouched.

The check that refuses to overwrite happens on entry and again just before the rename;
a file created by another process in between those moments can still be replaced.
Nothing is ``fsync``-ed: the guarantee is against crashes of this process and against
readers seeing half-written files, not against power loss.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import secrets
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from vissim.errors import VissimInputError

logger = logging.getLogger(__name__)

__all__ = ["atomic_output", "write_json_atomic", "write_text_atomic"]

_NAME_ATTEMPTS = 16


def _refuse_existing(path: Path) -> None:
    raise VissimInputError(f"{path} already exists; pass overwrite=True (--overwrite) to replace it")


def _reserve_temp_path(path: Path) -> Path:
    """Create an empty, uniquely named temporary file next to ``path`` and return its path.

    Created with mode 0o666 filtered by the process umask, so the final file gets the
    same permissions as one opened with plain ``open(path, "w")``.
    """
    for _ in range(_NAME_ATTEMPTS):
        tmp = path.with_name(f".{path.name}.{secrets.token_hex(4)}.tmp{path.suffix}")
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        except FileExistsError:
            continue
        os.close(fd)
        return tmp
    raise VissimInputError(f"cannot create a temporary file next to {path}: too many name collisions")


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike[str], *, overwrite: bool = False) -> Iterator[Path]:
    """Yield a temporary path to write to; on success move it onto ``path``.

    Parameters
    ----------
    path:
        Final destination.  Missing parent directories are created.
    overwrite:
        If False (default) and ``path`` exists, raise `VissimInputError` before
        anything is written.

    Yields
    ------
    Path
        An existing, empty temporary file in the same directory as ``path`` whose name
        ends with ``path``'s suffix.  The writer may replace or truncate it.
    """
    path = Path(path)
    if path.is_dir():
        raise VissimInputError(f"{path} is a directory; expected a file path")
    if path.exists() and not overwrite:
        _refuse_existing(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = _reserve_temp_path(path)
    except OSError as exc:
        raise VissimInputError(f"cannot write {path}: {exc.strerror or exc}") from exc

    try:
        yield tmp
        if not tmp.exists():
            raise VissimInputError(f"cannot write {path}: the writer removed its temporary file {tmp.name}")
        if path.exists() and not overwrite:
            _refuse_existing(path)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)
        raise
    logger.debug("wrote %s", path)


def write_text_atomic(path: str | os.PathLike[str], text: str, overwrite: bool = False) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; return the path."""
    path = Path(path)
    with atomic_output(path, overwrite=overwrite) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path


def write_json_atomic(path: str | os.PathLike[str], obj: Any, overwrite: bool = False) -> Path:
    """Write ``obj`` as JSON (indent=2, sorted keys, finite floats only) to ``path`` atomically.

    The object is serialised before any file is touched, so a value JSON cannot hold
    (NaN, infinity, an arbitrary object) raises `VissimInputError` and writes nothing.
    """
    path = Path(path)
    try:
        text = json.dumps(obj, indent=2, sort_keys=True, allow_nan=False) + "\n"
    except ValueError as exc:  # NaN or infinity with allow_nan=False; circular reference
        raise VissimInputError(f"cannot write {path} as JSON: {exc} (JSON allows only finite numbers)") from exc
    except TypeError as exc:
        raise VissimInputError(f"cannot write {path} as JSON: {exc}") from exc
    return write_text_atomic(path, text, overwrite=overwrite)
