#!/usr/bin/env python3
"""Fetch one real camera RAW file for the tests, check it, and cache it.

The file is ``_DSC2164.ARW`` (Sony ILCE-7RM3, 14-bit compressed ARW), a test image inside the
source distribution of libraw-cffi 0.19.0 on the Python package index (MIT licence).  pip is
the only way this reaches the network::

    python -m pip download --no-deps --no-binary libraw-cffi --require-hashes -r <libraw-cffi==0.19.0 --hash=...>

``--no-binary libraw-cffi`` (not ``:all:``) asks for the sdist alone: pip passes the option on
to the build environment it sets up to read the sdist's metadata, and ``:all:`` would compile
cffi there from source.  The sdist's sha256 is pinned (pip checks it before it builds anything,
and so does this script), then only the ARW is extracted, its size and sha256 are checked
against the pins, and it is moved into the cache in one rename, as
``$VISSIM_CACHE_DIR/real_raw/_DSC2164.ARW`` (default ``~/.cache/vissim``).  A cached file is
checked again on every use.

Usage: ``python scripts/fetch_real_raw.py`` prints the cached file's path (exit 0), says why
the package index could not be reached (exit 3), or reports a hash mismatch (exit 1).
Standard library only: tests import it without vissim.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

PACKAGE = "libraw-cffi"
VERSION = "0.19.0"
SDIST_NAME = "libraw_cffi-0.19.0.tar.gz"
SDIST_SHA256 = "c92b259c0a82a87e5e3636b8ffef84bcc3c0781c595994b09ceb9b87892ea930"
MEMBER = "libraw_cffi-0.19.0/libraw_cffi/tests/_DSC2164.ARW"
ARW_NAME = "_DSC2164.ARW"
ARW_SIZE_BYTES = 18_649_856
ARW_SHA256 = "42ec55eef6047c1bfbd1fd05fdcae78993f3513814138eff4cbcf9498c57d4e6"
PIP_TIMEOUT_S = 600


class FetchUnavailable(RuntimeError):
    """The package index could not be reached or pip failed: the caller may skip."""


class HashMismatch(RuntimeError):
    """A file differs from its pinned sha256 or size: never skip this."""


def cache_dir() -> Path:
    """``$VISSIM_CACHE_DIR`` when set, else ``~/.cache/vissim`` (the folder vissim's lens meshes use)."""
    root = os.environ.get("VISSIM_CACHE_DIR")
    return Path(root) if root else Path.home() / ".cache" / "vissim"


def sha256_of(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def check_sha256(path: Path, expected: str, what: str) -> None:
    actual = sha256_of(path)
    if actual != expected:
        raise HashMismatch(f"{what} has sha256 {actual}, expected {expected}")


def _pip_reason(output: str) -> str:
    """pip's last error line, and the network error behind it when pip printed one."""
    lines = [line.strip() for line in output.splitlines() if line.strip()]
    errors = [line for line in lines if line.startswith("ERROR")] or lines[-1:] or ["no output"]
    network = [line.split("after ", 1)[-1] for line in lines if "connection" in line.lower() and "WARNING" in line]
    return errors[-1] + (f" ({network[-1][:200]})" if network else "")


def download_sdist(into: Path) -> Path:
    """The libraw-cffi sdist, downloaded by pip into ``into`` and checked against its pinned sha256."""
    requirements = into / "requirements.txt"
    requirements.write_text(f"{PACKAGE}=={VERSION} --hash=sha256:{SDIST_SHA256}\n")
    command = [sys.executable, "-m", "pip", "download", "--no-deps", "--no-binary", PACKAGE, "--require-hashes",
               "--disable-pip-version-check", "--retries", "1", "--timeout", "20", "-r", str(requirements),
               "-d", str(into)]
    prefix = f"could not fetch {PACKAGE} {VERSION} sdist from the package index"
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=PIP_TIMEOUT_S, check=False)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise FetchUnavailable(f"{prefix}: {exc}") from None
    output = done.stdout + done.stderr
    if "DO NOT MATCH THE HASHES" in output:
        raise HashMismatch(f"pip: {PACKAGE} {VERSION} sdist does not match its pinned sha256 {SDIST_SHA256}")
    sdist = into / SDIST_NAME
    if done.returncode != 0 or not sdist.is_file():
        raise FetchUnavailable(f"{prefix}: pip exited with {done.returncode}: {_pip_reason(output)}")
    check_sha256(sdist, SDIST_SHA256, f"{PACKAGE} {VERSION} sdist {sdist}")
    return sdist


def extract_arw(sdist: Path, destination: Path) -> Path:
    """Copy the one ARW member of ``sdist`` to ``destination`` in one rename, after checking size and sha256."""
    destination.parent.mkdir(parents=True, exist_ok=True)
    with tarfile.open(sdist, "r:gz") as archive:
        try:
            member = archive.getmember(MEMBER)
        except KeyError:
            raise HashMismatch(f"{sdist} has no member {MEMBER}") from None
        if not member.isfile() or member.size != ARW_SIZE_BYTES:
            raise HashMismatch(f"{MEMBER} in {sdist} is {member.size} bytes, expected a {ARW_SIZE_BYTES}-byte file")
        handle, partial = tempfile.mkstemp(prefix=f".{ARW_NAME}.", dir=destination.parent)
        try:
            with os.fdopen(handle, "wb") as out, archive.extractfile(member) as source:
                for block in iter(lambda: source.read(1 << 20), b""):
                    out.write(block)
            check_sha256(Path(partial), ARW_SHA256, f"{MEMBER} in {sdist}")
            os.chmod(partial, 0o644)  # mkstemp made it private; it is a public test image
            os.replace(partial, destination)
        finally:
            if os.path.exists(partial):
                os.unlink(partial)
    return destination


def fetch_real_raw(cache: Path | None = None) -> Path:
    """The cached, checked ARW; fetched with pip on first use."""
    target = (cache or cache_dir()) / "real_raw" / ARW_NAME
    if target.exists():
        check_sha256(target, ARW_SHA256, f"the cached {target} (delete it to fetch it again)")
        return target
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="libraw-cffi-", dir=target.parent) as scratch:
        return extract_arw(download_sdist(Path(scratch)), target)


def main() -> int:
    try:
        path = fetch_real_raw()
    except FetchUnavailable as exc:
        print(f"fetch_real_raw: {exc}", file=sys.stderr)
        return 3
    except HashMismatch as exc:
        print(f"fetch_real_raw: hash mismatch: {exc}", file=sys.stderr)
        return 1
    print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
