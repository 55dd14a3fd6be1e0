"""Mitsuba 3 / Dr.Jit import and variant choice (the door of `vissim.render`).

`vissim.bench` builds plain scene dicts; only `vissim.render` imports Mitsuba, and
always through `mitsuba` here, which chooses the variant:

1. ``VISSIM_MITSUBA_VARIANT`` (or the ``variant=`` argument) when given;
2. ``cuda_ad_*`` when a CUDA device works;
3. ``llvm_ad_*`` when a usable LLVM shared library is found (LLVM >= 16: Debian's 14/15 crash
   Dr.Jit 1.5 with "Cannot select fminimum");
4. ``scalar_*`` otherwise, with a one-line warning.

The LLVM library must be known to Dr.Jit *before* it is imported, so `mitsuba` sets
``DRJIT_LIBLLVM_PATH`` from `find_libllvm` the first time it is called.
"""

from __future__ import annotations

import functools
import glob
import logging
import os
import re
from dataclasses import dataclass

from vissim.errors import VissimInputError

__all__ = ["find_libllvm", "mitsuba", "choose_variant", "VariantChoice", "MIN_LLVM_MAJOR"]

log = logging.getLogger(__name__)

#: Oldest LLVM that Dr.Jit 1.5 runs on here (14 and 15 fail with "Cannot select fminimum").
MIN_LLVM_MAJOR = 16
_LLVM_GLOBS = (
    "/lib/*-linux-gnu/libLLVM.so.*",
    "/usr/lib/*-linux-gnu/libLLVM.so.*",
    "/lib/*-linux-gnu/libLLVM-*.so",
    "/usr/lib/*-linux-gnu/libLLVM-*.so",
    "/usr/lib/llvm-*/lib/libLLVM.so*",
    "/usr/lib/llvm-*/lib/libLLVM-*.so",
    "/usr/local/lib/libLLVM*.so*",
    "/opt/homebrew/opt/llvm/lib/libLLVM.dylib",
    "/usr/local/opt/llvm/lib/libLLVM.dylib",
)


def _llvm_major(path: str) -> int | None:
    name = os.path.basename(path)
    match = re.search(r"libLLVM[-.]?(?:so\.)?(\d+)", name) or re.search(r"llvm-(\d+)", path)
    return int(match.group(1)) if match else None


def find_libllvm() -> str | None:
    """Path of the newest LLVM shared library (>= ``MIN_LLVM_MAJOR``), or None.

    ``DRJIT_LIBLLVM_PATH``, when set by the user, wins if the file exists.
    """
    user = os.environ.get("DRJIT_LIBLLVM_PATH")
    if user and os.path.exists(user):
        return user
    candidates = []
    for pattern in _LLVM_GLOBS:
        for path in glob.glob(pattern):
            major = _llvm_major(path)
            if major is not None and major >= MIN_LLVM_MAJOR and os.path.isfile(path):
                candidates.append((major, len(path), path))
    return min(candidates, key=lambda c: (-c[0], c[1]))[2] if candidates else None


@dataclass(frozen=True)
class VariantChoice:
    variant: str
    reason: str


_KINDS = ("mono", "rgb", "spectral")


def _variant_works(mi, backend: str) -> bool:
    """Whether ``<backend>_ad_mono`` sets and computes (``backend``: "cuda" or "llvm")."""
    try:
        mi.set_variant(f"{backend}_ad_mono")
        import drjit as dr

        return bool(dr.allclose(getattr(dr, backend).Float([1.0, 2.0]) * 2, [2.0, 4.0]))
    except Exception as exc:  # no driver, no device, no usable library
        log.debug("%s variant unavailable: %s", backend.upper(), exc)
        return False


def _cuda_works(mi) -> bool:
    if not any(v.startswith("cuda_") for v in mi.variants()):
        return False
    if not (glob.glob("/usr/lib/*-linux-gnu/libcuda.so*") or glob.glob("/usr/lib64/libcuda.so*")
            or glob.glob("/usr/local/nvidia/lib64/libcuda.so*") or os.environ.get("CUDA_VISIBLE_DEVICES")):
        return False
    return _variant_works(mi, "cuda")


@functools.lru_cache(maxsize=None)
def _backend_kind(requested: str | None) -> VariantChoice:
    mi = _import_mitsuba()
    if requested:
        if requested not in mi.variants():
            raise VissimInputError(f"Mitsuba variant {requested!r} is not available; choose from {', '.join(mi.variants())}")
        return VariantChoice(requested, "requested")
    if _cuda_works(mi):
        return VariantChoice("cuda", "a CUDA device works")
    if os.environ.get("DRJIT_LIBLLVM_PATH") and _variant_works(mi, "llvm"):
        return VariantChoice("llvm", f"LLVM at {os.environ['DRJIT_LIBLLVM_PATH']}")
    log.warning(
        "no usable LLVM >= %d found (install Debian's libllvm19); Mitsuba renders on its slow scalar variants",
        MIN_LLVM_MAJOR,
    )
    return VariantChoice("scalar", "no CUDA device and no usable LLVM")


def _import_mitsuba():
    if "DRJIT_LIBLLVM_PATH" not in os.environ:
        path = find_libllvm()
        if path:
            os.environ["DRJIT_LIBLLVM_PATH"] = path
    import mitsuba as mi

    return mi


def choose_variant(kind: str = "mono", variant: str | None = None) -> VariantChoice:
    """The Mitsuba variant for ``kind`` ('mono', 'rgb' or 'spectral'), by the rules above."""
    if kind not in _KINDS:
        raise VissimInputError(f"render kind must be one of {', '.join(_KINDS)}, got {kind!r}")
    if variant is not None and not str(variant).strip():
        raise VissimInputError("the Mitsuba variant '' is empty; name one (e.g. llvm_ad_mono) or leave --variant out")
    requested = variant or os.environ.get("VISSIM_MITSUBA_VARIANT") or None
    base = _backend_kind(requested)
    if base.reason == "requested":
        return base
    mi = _import_mitsuba()
    if base.variant == "scalar":
        # The PyPI wheel has no scalar_mono: render RGB and read one channel.
        name = "scalar_spectral" if kind == "spectral" else "scalar_rgb"
    else:
        name = f"{base.variant}_ad_{kind}"
    if name not in mi.variants():
        raise VissimInputError(f"Mitsuba variant {name} is not in this build ({', '.join(mi.variants())})")
    return VariantChoice(name, base.reason)


def mitsuba(kind: str = "mono", variant: str | None = None):
    """Import Mitsuba, set the chosen variant, and return the ``mitsuba`` module."""
    choice = choose_variant(kind, variant)
    mi = _import_mitsuba()
    if mi.variant() != choice.variant:
        mi.set_variant(choice.variant)
        log.info("Mitsuba variant %s (%s)", choice.variant, choice.reason)
    # Mitsuba's own warnings go straight to the terminal; vissim reports what matters through
    # its logging (e.g. the sampler's rounded sample count), so keep only Mitsuba's errors.
    mi.set_log_level(mi.LogLevel.Error)
    return mi
