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

The output-safety rules (docs/conventions.md, "Outputs") are decided here:

* a write that fails (a full disk, no permission, a writer's own error) raises one
  `VissimInputError` naming the final path, and leaves no temporary file;
* inside `output_transaction` every final rename waits for the end, so a command's
  files all appear, or none does;
* `refuse_existing` is the one refusal to replace an existing file;
* `check_outputs_apart` refuses an output that is one of the command's inputs (by
  resolved path or by inode, so ``./a/../in.png``, symlinks and hard links count), and an
  output folder that holds an input, with or without ``--overwrite``.
"""

from __future__ import annotations

import contextlib
import contextvars
import dataclasses
import errno
import json
import logging
import os
import secrets
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

from vissim.errors import VissimInputError

logger = logging.getLogger(__name__)

__all__ = ["atomic_output", "cache_output", "check_outputs_apart", "existing_output_error", "output_transaction",
           "refuse_existing", "remove_output", "write_json_atomic", "write_text_atomic"]

_NAME_ATTEMPTS = 16


@dataclasses.dataclass
class _Pending:
    """What an open `output_transaction` holds: renames to do, folders its writes created."""

    renames: list[tuple[Path, Path, bool]] = dataclasses.field(default_factory=list)  # (tmp, final, overwrite)
    folders: list[Path] = dataclasses.field(default_factory=list)  # in the order they were made
    removals: list[Path] = dataclasses.field(default_factory=list)  # stale files to delete once all is in place


#: The open `output_transaction` of this context, if any.
_PENDING: contextvars.ContextVar[_Pending | None] = contextvars.ContextVar("vissim_pending_outputs", default=None)


def _make_parents(folder: Path) -> list[Path]:
    """Create ``folder`` and its missing parents; return the ones made, outermost first."""
    missing = []
    while not folder.exists() and folder != folder.parent:
        missing.append(folder)
        folder = folder.parent
    if missing:
        missing[0].mkdir(parents=True, exist_ok=True)
    return missing[::-1]


def _remove_empty(folders: list[Path]) -> None:
    """Remove the folders a failed write made, innermost first, where they are still empty."""
    for folder in reversed(folders):
        with contextlib.suppress(OSError):
            folder.rmdir()


def existing_output_error(path: str | os.PathLike[str]) -> VissimInputError:
    """The one wording of the refusal to replace an existing file."""
    return VissimInputError(f"{path} already exists; pass --overwrite (overwrite=True in Python) to replace it")


def _refuse_existing(path: Path) -> None:
    raise existing_output_error(path)


def refuse_existing(*paths: str | os.PathLike[str] | None, overwrite: bool) -> None:
    """Stop before any work when an output (``None``: not asked for) exists and ``overwrite`` is False."""
    for path in paths:
        if path is not None and Path(path).exists() and not overwrite:
            _refuse_existing(Path(path))


def _real(path: str | os.PathLike[str]) -> str:
    return os.path.realpath(os.path.abspath(path))


def _same_file(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    """One file under two spellings: the same resolved path, or the same inode (hard links)."""
    try:
        if os.path.samefile(a, b):
            return True
    except OSError:  # one of them does not exist (yet)
        pass
    return _real(a) == _real(b)


def _holds(folder: str | os.PathLike[str], path: str | os.PathLike[str]) -> bool:
    """``path`` is ``folder`` or lies inside it, once both are resolved."""
    inner, outer = _real(path), _real(folder)
    return inner == outer or os.path.commonpath([inner, outer]) == outer


def check_outputs_apart(inputs: Iterable[str | os.PathLike[str] | None],
                        outputs: Iterable[str | os.PathLike[str] | None] = (), *,
                        folders: Iterable[str | os.PathLike[str] | None] = ()) -> None:
    """Refuse, before any work, an output file that is an input or another output, or an output
    folder that holds an input.

    ``inputs`` are every file (or folder) the command reads, ``outputs`` every file it writes
    (sidecars included), ``folders`` the folders it writes into; ``None`` entries are skipped.
    Holds with or without ``--overwrite``: an output never replaces an input or another output.
    """
    inputs = [Path(p) for p in inputs if p is not None]
    outputs = [Path(p) for p in outputs if p is not None]
    for k, out in enumerate(outputs):
        for other in outputs[:k]:
            if _same_file(out, other):
                raise VissimInputError(f"outputs {other} and {out} are the same file; give each output its own path")
        for source in inputs:
            if _same_file(out, source):
                raise VissimInputError(f"output {out} is the same file as input {source}; an output never "
                                       "replaces an input: choose another output path")
    for folder in (Path(p) for p in folders if p is not None):
        for source in inputs:
            if _same_file(folder, source) or _holds(folder, source):
                raise VissimInputError(f"output folder {folder} holds input {source}; an output never "
                                       "replaces an input: choose a folder of its own")


#: System errors a writer may report only inside its own message (OpenEXR's RuntimeError does).
_WRITE_ERRNOS = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS, errno.EACCES, errno.EIO)


def _write_failure(path: Path, tmp: Path, exc: BaseException) -> VissimInputError:
    """One line naming ``path`` for a write that failed (OSError: a full disk; RuntimeError: OpenEXR's)."""
    text = " ".join(str(exc).split())
    known = [os.strerror(code) for code in _WRITE_ERRNOS if os.strerror(code) in text]
    if isinstance(exc, OSError) and exc.strerror:
        reason = exc.strerror
    elif known:
        reason = known[0]
    else:
        reason = text.replace(str(tmp), str(path)).rstrip(".") or type(exc).__name__
    return VissimInputError(f"cannot write {path}: {reason}; nothing there was changed")


@contextlib.contextmanager
def cache_output() -> Iterator[None]:
    """Writes inside this block land at once, even within an `output_transaction`.

    For cache files (lens meshes) that are read back as soon as they are written; they are
    no command's output, and a complete one is as good as a missing one.
    """
    token = _PENDING.set(None)
    try:
        yield
    finally:
        _PENDING.reset(token)


@contextlib.contextmanager
def output_transaction() -> Iterator[None]:
    """Hold back every `atomic_output` rename until the block ends: all the files appear, or none.

    On success every refusal to overwrite is checked again, then the files are renamed into
    place in the order they were written; on any error every temporary file is removed and
    no final path changes.  Writers inside must not read back what they wrote.  Nested
    transactions join the outer one.
    """
    if _PENDING.get() is not None:
        yield
        return
    pending = _Pending()
    token = _PENDING.set(pending)
    try:
        yield
        for _, path, overwrite in pending.renames:
            if path.exists() and not overwrite:
                _refuse_existing(path)
        for done, (tmp, path, _) in enumerate(pending.renames):
            try:
                os.replace(tmp, path)
            except OSError as exc:
                if done:  # the rename of one file failed after others were in place: say which
                    placed = ", ".join(str(p) for _, p, _ in pending.renames[:done])
                    raise VissimInputError(f"cannot write {path}: {exc.strerror or exc}; already written: "
                                           f"{placed}") from exc
                raise _write_failure(path, tmp, exc) from exc
            logger.debug("wrote %s", path)
        for path in pending.removals:
            _unlink_stale(path)
    except BaseException:
        for tmp, _, _ in pending.renames:
            with contextlib.suppress(OSError):
                tmp.unlink(missing_ok=True)
        _remove_empty(pending.folders)
        raise
    finally:
        _PENDING.reset(token)


def remove_output(path: str | os.PathLike[str]) -> None:
    """Delete a stale file a command's write makes obsolete (a sidecar): at once, or, inside an
    `output_transaction`, only once every file of it is in place."""
    pending = _PENDING.get()
    if pending is not None:
        pending.removals.append(Path(path))
    else:
        _unlink_stale(Path(path))


def _unlink_stale(path: Path) -> None:
    if path.exists():
        path.unlink()
        logger.info("removed stale %s", path)


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
    pending = _PENDING.get()
    if pending is not None and any(_same_file(path, target) for _, target, _ in pending.renames):
        raise VissimInputError(f"{path} is written twice by one command; give each output its own path")
    created: list[Path] = []
    try:
        created = _make_parents(path.parent)
        tmp = _reserve_temp_path(path)
    except OSError as exc:
        _remove_empty(created)
        raise _write_failure(path, path, exc) from exc
    if pending is not None:
        pending.folders += created

    try:
        yield tmp
        if not tmp.exists():
            raise VissimInputError(f"cannot write {path}: the writer removed its temporary file {tmp.name}")
        if pending is not None:  # output_transaction renames it with the others
            pending.renames.append((tmp, path, overwrite))
            return
        if path.exists() and not overwrite:
            _refuse_existing(path)
        os.replace(tmp, path)
    except (OSError, RuntimeError) as exc:  # a full disk, no permission; OpenEXR raises RuntimeError
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)
        _remove_empty(created)
        raise _write_failure(path, tmp, exc) from exc
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)
        _remove_empty(created)
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
