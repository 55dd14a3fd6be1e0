"""Image files in and out, and the one place that converts to and from linear light.

Inside vissim every image is ``float32`` *linear light* (proportional to radiance), of
shape ``(H, W)`` (mono, channel ``Y``) or ``(H, W, 3)`` (channels ``R, G, B``), indexed
``[row, col]``.  Encoded files are converted here and nowhere else:

* ``.exr`` stores linear float32 as-is (ZIP compression); round trips are bit-exact.
  Provenance rides in one string header attribute, ``vissim_provenance`` (JSON).
* ``.png`` / ``.tif`` / ``.tiff`` store 8- or 16-bit integers, by default sRGB-encoded
  (IEC 61966-2-1); provenance goes to a sidecar ``<file>.json`` (``out.png.json``).
  Float TIFFs are read as linear.  16-bit PNG other than grey without alpha (colour, or
  grey + alpha) is refused both ways, because Pillow silently truncates it to 8 bits;
  use TIFF or EXR for that.

An alpha channel (PNG/TIFF extra sample, EXR ``A``) is read into `Image.alpha`
(coverage in [0, 1], never light: stored linearly, no transfer function) and written back
when ``write_image(..., alpha=...)`` is given: vissim blurs the colour and carries alpha
through unchanged.  `Image.bit_depth` is the integer depth a PNG/TIFF was stored at
(8 or 16; ``None`` for float data), so that a command can write its result at the depth of
its input (`output_bit_depth`).

Images carry their angular sampling: ``write_image(..., arcmin_per_px=S)`` records it in
the provenance record's top-level key ``"arcmin_per_px"`` (`SAMPLING_KEY`; the EXR
header attribute or the sidecar, as above), and `read_image` returns it as
`Image.arcmin_per_px` (``None`` when the file does not say).  Files written before
that key existed are read from where their writer put it (`sampling_from_provenance`).

Every write goes through `vissim.atomic.atomic_output` and refuses to replace an
existing file unless ``overwrite=True``.  Anything wrong with a file raises one
`VissimInputError` naming the file.
"""

from __future__ import annotations

import contextlib
import ctypes
import dataclasses
import io
import logging
import math
import os
import struct
import sys
import tempfile
import threading
from pathlib import Path
from typing import Any

import numpy as np
import OpenEXR
import tifffile
from PIL import Image as _PILImage

from vissim.atomic import atomic_output, output_transaction, refuse_existing, remove_output, write_text_atomic
from vissim.checks import arcmin_per_px as check_arcmin_per_px
from vissim.errors import VissimInputError
from vissim.provenance import from_json, to_json

logger = logging.getLogger(__name__)

__all__ = ["Image", "image_files", "output_bit_depth", "read_data_map", "read_image", "sampling_from_provenance", "srgb_decode",
           "srgb_encode", "to_preview_png", "write_data_map", "write_image", "write_png_bytes", "encode_png",
           "PNG_COMPRESS_LEVEL"]

PROVENANCE_ATTRIBUTE = "vissim_provenance"
#: Top-level provenance key holding an image's angular sampling, arcmin per pixel.
SAMPLING_KEY = "arcmin_per_px"
#: Where each command's provenance inputs record the sampling, in the order looked at: the
#: fallback for a file without `SAMPLING_KEY` (one written without ``arcmin_per_px``, or by an older vissim).
_INPUT_SAMPLING_PATHS = (
    ("inputs", "arcmin_per_px"),             # blur, blur-depth, demo chart, render depth
    ("inputs", "options", "arcmin_per_px"),  # vissim chart
    ("inputs", "bench", "arcmin_per_px"),    # render bench; campaign renders
    ("inputs", "render", "arcmin_per_px"),   # campaign renders (the render spec)
    ("inputs", "settings", "arcmin_per_px"),  # campaign items
    ("inputs", "summary", "arcmin_per_px"),  # render atv
    ("inputs", "psf", "arcmin_per_px"),      # psf; demo PSFs
)
MONO_CHANNELS = ("Y",)
RGB_CHANNELS = ("R", "G", "B")
_SUFFIX_KIND = {".exr": "exr", ".png": "png", ".tif": "tiff", ".tiff": "tiff"}
#: The eight bytes every PNG file begins with.
_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
#: zlib's level for every PNG written: 3 takes 40 % less time than Pillow's default 6 for files 6 % larger.
PNG_COMPRESS_LEVEL = 3

# IEC 61966-2-1:1999 sRGB transfer function constants.
_SRGB_LINEAR_THRESHOLD = 0.0031308
_SRGB_ENCODED_THRESHOLD = 0.04045
_SRGB_SLOPE = 12.92
_SRGB_SCALE = 1.055
_SRGB_OFFSET = 0.055
_SRGB_GAMMA = 2.4


def _float_array(x: Any) -> np.ndarray:
    arr = np.asarray(x)
    return arr if np.issubdtype(arr.dtype, np.floating) else arr.astype(np.float64)


def srgb_encode(linear: Any) -> Any:
    """Linear light in [0, 1] -> sRGB-encoded values in [0, 1] (IEC 61966-2-1).

    Input is clipped to [0, 1] first: values above 1 (highlights) become 1 and negative
    values become 0.  Float dtypes are preserved; other dtypes are computed in float64.
    """
    x = np.clip(_float_array(linear), 0.0, 1.0)
    curve = _SRGB_SCALE * np.power(x, 1.0 / _SRGB_GAMMA) - _SRGB_OFFSET
    return np.where(x <= _SRGB_LINEAR_THRESHOLD, _SRGB_SLOPE * x, curve).astype(x.dtype, copy=False)[()]


def srgb_decode(encoded: Any) -> Any:
    """sRGB-encoded values in [0, 1] -> linear light in [0, 1] (IEC 61966-2-1).

    Input is clipped to [0, 1] first.  Float dtypes are preserved; other dtypes are
    computed in float64 (pass integer codes already divided by 255 or 65535).
    """
    v = np.clip(_float_array(encoded), 0.0, 1.0)
    curve = np.power((v + _SRGB_OFFSET) / _SRGB_SCALE, _SRGB_GAMMA)
    return np.where(v <= _SRGB_ENCODED_THRESHOLD, v / _SRGB_SLOPE, curve).astype(v.dtype, copy=False)[()]


@dataclasses.dataclass(frozen=True)
class Image:
    """Linear-light pixels with their channel names, provenance and angular sampling.

    ``pixels`` is float32 of shape ``(H, W)`` with ``channel_names == ("Y",)`` or
    ``(H, W, 3)`` with ``("R", "G", "B")``.  ``arcmin_per_px`` is the angular pixel size,
    or ``None`` when the file does not record one.  ``alpha`` is the file's alpha channel,
    float32 ``(H, W)`` in [0, 1], or ``None``; ``bit_depth`` the integer depth the file
    stored (8 or 16), ``None`` for float data.
    """

    pixels: np.ndarray
    channel_names: tuple[str, ...]
    provenance: dict = dataclasses.field(default_factory=dict, repr=False)
    arcmin_per_px: float | None = None
    alpha: np.ndarray | None = dataclasses.field(default=None, repr=False)
    bit_depth: int | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.pixels, np.ndarray) or self.pixels.dtype != np.float32:
            raise VissimInputError(
                "Image.pixels must be a float32 ndarray, got "
                f"{getattr(self.pixels, 'dtype', type(self.pixels))}"
            )
        n = 1 if self.pixels.ndim == 2 else (self.pixels.shape[-1] if self.pixels.ndim == 3 else -1)
        if n < 0 or len(self.channel_names) != n:
            raise VissimInputError(
                f"Image.channel_names {self.channel_names} do "
                f"not match pixels of shape {self.pixels.shape}"
            )
        if self.alpha is not None and (not isinstance(self.alpha, np.ndarray) or self.alpha.dtype != np.float32
                                       or self.alpha.shape != self.pixels.shape[:2]):
            raise VissimInputError(f"Image.alpha must be a float32 ndarray of shape {self.pixels.shape[:2]} or None, got "
                                   f"{getattr(self.alpha, 'dtype', type(self.alpha))} {getattr(self.alpha, 'shape', '')}")
        if self.arcmin_per_px is not None:
            step = _sampling_value(self.arcmin_per_px)
            if step is None:
                raise VissimInputError(f"Image.arcmin_per_px must be a positive number or None, got {self.arcmin_per_px!r}")
            object.__setattr__(self, "arcmin_per_px", step)


def _sampling_value(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    value = float(value)
    return value if math.isfinite(value) and value > 0 else None


def sampling_from_provenance(provenance: Any) -> float | None:
    """The angular sampling (arcmin per pixel) a provenance record states, or ``None``.

    The top-level `SAMPLING_KEY` first; then where the writing command's inputs record it
    (`_INPUT_SAMPLING_PATHS`: chart options, bench parameters, campaign settings ...).
    """
    if not isinstance(provenance, dict):
        return None
    found = _sampling_value(provenance.get(SAMPLING_KEY))
    if found is not None:
        return found
    for keys in _INPUT_SAMPLING_PATHS:
        node: Any = provenance
        for key in keys:
            node = node.get(key) if isinstance(node, dict) else None
        found = _sampling_value(node)
        if found is not None:
            return found
    return None


def _with_sampling(provenance: dict | None, arcmin_per_px: Any, path: Path) -> dict | None:
    """``provenance`` with the sampling at `SAMPLING_KEY` (unchanged when ``arcmin_per_px`` is None)."""
    if arcmin_per_px is None:
        return provenance
    try:
        step = check_arcmin_per_px(arcmin_per_px)
    except VissimInputError as exc:
        raise VissimInputError(f"cannot write {path}: {exc}") from None
    return {**(provenance or {}), SAMPLING_KEY: step}


# ---------------------------------------------------------------- reading


def read_image(path: str | os.PathLike[str], *, encoding: str = "auto") -> Image:
    """Read an image file into linear light.

    Parameters
    ----------
    path:
        ``.exr``, ``.png``, ``.tif`` or ``.tiff``.
    encoding:
        How PNG/TIFF values are encoded: ``"auto"`` (integers are sRGB, floats linear),
        ``"srgb"`` or ``"linear"``.  EXR is always linear; ``"srgb"`` is refused for it.
    """
    path = Path(path)
    if encoding not in ("auto", "srgb", "linear"):
        raise VissimInputError(f"encoding must be 'auto', 'srgb' or 'linear', got {encoding!r}")
    kind = _kind(path)
    if not path.is_file():
        raise VissimInputError(f"{path}: no such file")
    if kind == "exr":
        if encoding == "srgb":
            raise VissimInputError(f"{path}: EXR files hold linear light; encoding='srgb' does not apply")
        pixels, names, provenance, alpha = _read_exr(path)
        bits = None
    else:
        raw, alpha = _split_alpha(_read_png(path) if kind == "png" else _read_tiff(path))
        bits = 8 * raw.dtype.itemsize if np.issubdtype(raw.dtype, np.integer) else None
        pixels = _to_linear(raw, encoding)
        alpha = None if alpha is None else _to_linear(alpha, "linear")
        names, provenance = (MONO_CHANNELS if pixels.ndim == 2 else RGB_CHANNELS), None
    for what, plane in (("pixel", pixels), ("alpha", alpha)):
        if plane is not None and not np.all(np.isfinite(plane)):
            raise VissimInputError(f"{path}: contains {int(np.sum(~np.isfinite(plane)))} NaN or infinite {what} values")
    provenance = _read_sidecar(path) if provenance is None else provenance  # read after the pixel check
    return Image(pixels, names, provenance, sampling_from_provenance(provenance), alpha, bits)


def _split_alpha(data: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """(colour, alpha | None) of PNG/TIFF samples: grey + alpha has 2 samples, RGB + alpha 4."""
    if data.ndim == 3 and data.shape[-1] in (2, 4):
        return data[..., :-1] if data.shape[-1] == 4 else data[..., 0], data[..., -1]
    return data, None


def _png_16_bit_loss(colour: bool, alpha: bool) -> str | None:
    """The kind of 16-bit PNG whose bits Pillow would lose (``"colour"``, ``"grey + alpha"``), or None.

    Grey without alpha is the one 16-bit PNG Pillow reads and writes; it truncates any other to 8 bits.
    """
    if colour:
        return "colour"
    return "grey + alpha" if alpha else None


def output_bit_depth(image: Image, path: str | os.PathLike[str]) -> int:
    """The integer depth to write ``image``'s result at ``path`` with: its own (8 or 16), else 8.

    A 16-bit colour or alpha source written to PNG (which Pillow cannot write at 16 bits) gets
    8 bits and one warning naming .tif and .exr, which keep them.
    """
    bits = image.bit_depth if image.bit_depth in (8, 16) else 8
    what = _png_16_bit_loss(image.pixels.ndim == 3, image.alpha is not None)
    if bits == 16 and Path(path).suffix.lower() == ".png" and what:
        logger.warning("%s: 16-bit %s PNG cannot be written; writing 8 bits (use .tif or .exr to keep 16)", path, what)
        return 8
    return bits


def _kind(path: Path) -> str:
    if path.is_dir():
        raise VissimInputError(f"{path} is a folder, not an image file (.exr, .png, .tif or .tiff)")
    kind = _SUFFIX_KIND.get(path.suffix.lower())
    if kind is None:
        raise VissimInputError(f"{path}: unsupported image suffix {path.suffix!r} (expected .exr, .png, .tif or .tiff)")
    return kind


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _flush_all() -> None:
    """Flush Python's streams and the C library's (native code's buffered output lands before a redirect ends)."""
    sys.stdout.flush()
    sys.stderr.flush()
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):  # pragma: no cover - no C library to flush
        pass


_CAPTURE_LOCK = threading.Lock()


@contextlib.contextmanager
def _native_output_captured():
    """Collect what native code writes to file descriptors 1 and 2 (OpenEXR prints its own errors there).

    Yields a list that holds the captured lines once the block ends; Python's own streams are
    flushed first, so nothing of vissim's is caught.  One capture at a time (a lock): interleaved
    ones would leave descriptors 1 and 2 on a dead file.
    """
    lines: list[str] = []
    python_side = io.StringIO()  # what the binding may print through sys.stdout
    with _CAPTURE_LOCK, tempfile.TemporaryFile() as sink:
        _flush_all()
        saved = [os.dup(fd) for fd in (1, 2)]
        try:
            for fd in (1, 2):
                os.dup2(sink.fileno(), fd)
            with contextlib.redirect_stdout(python_side), contextlib.redirect_stderr(python_side):
                yield lines
        finally:
            _flush_all()
            for fd, copy in zip((1, 2), saved):
                os.dup2(copy, fd)
                os.close(copy)
            sink.seek(0)
            text = sink.read().decode("utf-8", "replace") + python_side.getvalue()
            lines.extend(line.strip() for line in text.splitlines() if line.strip())


def _exr_reason(path: Path, exc: BaseException, printed: list[str]) -> str:
    """Why OpenEXR could not read ``path``: its first printed message (without the file name), else the exception."""
    for line in printed:
        message = line.removeprefix(f"{path}:").strip()
        if message and not message.startswith("Warning:"):
            return message
    return str(exc).replace(f"'{path}'", "the file").strip() or type(exc).__name__


def _open_exr(path: Path) -> tuple[dict[str, np.ndarray], dict]:
    """The first part's channels ``{name: pixels}`` and provenance; one clean error for a file that is no EXR.

    OpenEXR's own messages are kept off the terminal; the first of them names the fault.
    """
    try:
        with _native_output_captured() as printed:
            exr = OpenEXR.File(str(path), separate_channels=True)
            n_parts = len(exr.parts)
            header = exr.parts[0].header
            channels = {name: ch.pixels for name, ch in exr.parts[0].channels.items()}
    except Exception as exc:  # OpenEXR raises RuntimeError, ValueError, IndexError ...
        size = path.stat().st_size
        raise VissimInputError(
            f"{path}: cannot read as OpenEXR (truncated, corrupt or not an EXR file; {size} bytes): "
            f"{_exr_reason(path, exc, printed)}"
        ) from exc
    if printed:
        logger.debug("OpenEXR said, reading %s: %s", path, " | ".join(printed))
    if n_parts > 1:
        logger.info("%s has %d parts; reading only the first", path, n_parts)
    prov_text = header.get(PROVENANCE_ATTRIBUTE)
    return channels, _parse_provenance(path, prov_text) if isinstance(prov_text, str) else {}


def _read_exr(path: Path) -> tuple[np.ndarray, tuple[str, ...], dict, np.ndarray | None]:
    channels, provenance = _open_exr(path)
    names = set(channels)
    if set(RGB_CHANNELS) <= names:
        wanted = RGB_CHANNELS
    elif "Y" in names:
        wanted = MONO_CHANNELS
    else:
        raise VissimInputError(
            f"{path}: EXR channels {sorted(names)} are not supported (need 'Y' for mono or 'R', 'G', 'B' for colour)"
        )
    if names - set(wanted) - {"A"}:
        logger.info("%s: ignoring EXR channels %s", path, sorted(names - set(wanted) - {"A"}))
    planes = [channels[c] for c in wanted]
    for name, plane in zip(wanted, planes):
        if plane.dtype not in (np.float16, np.float32):
            raise VissimInputError(f"{path}: EXR channel {name!r} has pixel type {plane.dtype}; expected half or float")
        if plane.shape != planes[0].shape:
            raise VissimInputError(f"{path}: EXR channel {name!r} is subsampled ({plane.shape} vs {planes[0].shape})")
    pixels = planes[0] if len(planes) == 1 else np.stack(planes, axis=-1)
    alpha = channels.get("A")
    if alpha is not None and alpha.shape != planes[0].shape:
        raise VissimInputError(f"{path}: EXR channel 'A' is subsampled ({alpha.shape} vs {planes[0].shape})")
    alpha = None if alpha is None else np.ascontiguousarray(alpha, dtype=np.float32)
    return np.ascontiguousarray(pixels, dtype=np.float32), wanted, provenance, alpha


def _parse_provenance(path: Path, text: str) -> dict:
    try:
        return from_json(text)
    except VissimInputError as exc:
        raise VissimInputError(f"{path}: {exc}") from exc


def _read_sidecar(path: Path) -> dict:
    sidecar = _sidecar_path(path)
    if not sidecar.is_file():
        return {}
    return _parse_provenance(sidecar, sidecar.read_text(encoding="utf-8"))


def _read_png(path: Path) -> np.ndarray:
    with open(path, "rb") as fh:
        head = fh.read(33)
    if len(head) < 33 or head[:8] != _PNG_SIGNATURE or head[12:16] != b"IHDR":
        raise VissimInputError(f"{path}: not a PNG file (bad signature or header)")
    bit_depth, colour_type = struct.unpack(">BB", head[24:26])
    if colour_type != 3 and bit_depth not in (8, 16):
        raise VissimInputError(f"{path}: PNG bit depth {bit_depth} is not supported (expected 8 or 16)")
    colour, alpha = bool(colour_type & 2), bool(colour_type & 4)  # the PNG colour type's bits
    lost = _png_16_bit_loss(colour, alpha) if bit_depth == 16 else None
    if lost:
        raise VissimInputError(f"{path}: 16-bit {lost} PNG is not supported (Pillow truncates it to 8 bits); "
                               "use 16-bit TIFF or EXR")
    try:
        with _PILImage.open(path) as im:
            im.load()
            if im.mode == "P":
                im = im.convert("RGBA" if "transparency" in im.info else "RGB")
            mode = im.mode
            data = np.asarray(im)
    except Exception as exc:  # Pillow raises OSError, SyntaxError, ValueError ...
        raise VissimInputError(f"{path}: cannot read as PNG (truncated or corrupt): {_one_line(exc)}") from exc
    if mode in ("I;16", "I;16B", "I"):
        return data.astype(np.uint16)
    if mode in ("L", "RGB"):
        return data
    if mode in ("LA", "RGBA"):
        return data  # the alpha channel last; split by _split_alpha
    raise VissimInputError(f"{path}: PNG mode {mode!r} is not supported (expected greyscale or RGB, 8 or 16 bit)")


def _read_tiff(path: Path) -> np.ndarray:
    try:
        with tifffile.TiffFile(path) as tif:
            series = tif.series[0]
            axes = series.axes
            photometric = tif.pages[0].photometric
            data = series.asarray()
    except Exception as exc:  # tifffile raises TiffFileError, ValueError, struct.error ...
        raise VissimInputError(
            f"{path}: cannot read as TIFF (truncated, "
            f"corrupt or not a TIFF file): {_one_line(exc)}"
        ) from exc
    if axes == "SYX":
        data, axes = np.moveaxis(data, 0, -1), "YXS"
    if axes not in ("YX", "YXS"):
        raise VissimInputError(
            f"{path}: TIFF layout {axes!r} is not supported "
            "(expected a single greyscale or RGB image)"
        )
    samples = 1 if axes == "YX" else data.shape[-1]
    if not ((photometric == tifffile.PHOTOMETRIC.MINISBLACK and samples in (1, 2))
            or (photometric == tifffile.PHOTOMETRIC.RGB and samples in (3, 4))):
        raise VissimInputError(
            f"{path}: TIFF with photometric {getattr(photometric, 'name', photometric)} and {samples} samples "
            "is not supported (expected greyscale or RGB)"
        )
    if data.dtype not in (np.uint8, np.uint16) and not np.issubdtype(data.dtype, np.floating):
        raise VissimInputError(
            f"{path}: TIFF sample type {data.dtype} is not "
            "supported (expected uint8, uint16 or float)"
        )
    return data


def _to_linear(raw: np.ndarray, encoding: str) -> np.ndarray:
    if np.issubdtype(raw.dtype, np.integer):
        values = raw.astype(np.float64) / np.iinfo(raw.dtype).max
        decode = encoding != "linear"
    else:
        values = raw.astype(np.float64)
        decode = encoding == "srgb"
    out = srgb_decode(values) if decode else values
    return np.ascontiguousarray(out, dtype=np.float32)


# ---------------------------------------------------------------- writing


def _sidecar_path(path: Path) -> Path:
    return path.with_name(path.name + ".json")


def image_files(path: str | os.PathLike[str]) -> tuple[Path, ...]:
    """Every file an image path stands for: the image, and for PNG/TIFF its provenance sidecar."""
    path = Path(path)
    if not path.name or path.suffix.lower() in (".exr", ".npy"):  # '.', '/': no file, no sidecar (a reader says so)
        return (path,)
    return path, _sidecar_path(path)


def _validated_alpha(path: Path, alpha: Any, shape: tuple[int, ...]) -> np.ndarray | None:
    """``alpha`` as float32 of the image's ``(H, W)`` with finite values, or None (PNG/TIFF clip it to [0, 1])."""
    if alpha is None:
        return None
    plane = np.asarray(alpha, dtype=np.float32)
    if plane.shape != tuple(shape):
        raise VissimInputError(f"cannot write {path}: alpha has shape {plane.shape}; expected the image's {tuple(shape)}")
    if not np.all(np.isfinite(plane)):
        raise VissimInputError(f"cannot write {path}: {int(np.sum(~np.isfinite(plane)))} alpha values are NaN or infinite")
    return plane


def _validated_pixels(path: Path, pixels: Any, channel_names: Any) -> np.ndarray:
    arr = np.asarray(pixels)
    if arr.dtype == bool or not (np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)):
        raise VissimInputError(f"cannot write {path}: pixels must be real numbers, got dtype {arr.dtype}")
    if arr.ndim == 3 and arr.shape[-1] == 1:
        arr = arr[..., 0]
    if arr.ndim not in (2, 3):
        raise VissimInputError(f"cannot write {path}: pixels must have shape (H, W) or (H, W, 3), got {arr.shape}")
    if arr.ndim == 3 and arr.shape[-1] != 3:
        raise VissimInputError(f"cannot write {path}: pixels have {arr.shape[-1]} channels; expected 1 or 3")
    if arr.size == 0:
        raise VissimInputError(f"cannot write {path}: pixels are empty, shape {arr.shape}")
    arr = arr.astype(np.float32)
    if not np.all(np.isfinite(arr)):
        raise VissimInputError(
            f"cannot write {path}: {int(np.sum(~np.isfinite(arr)))} "
            "pixel values are NaN or infinite (as float32)"
        )
    expected = MONO_CHANNELS if arr.ndim == 2 else RGB_CHANNELS
    if channel_names is not None and tuple(channel_names) != expected:
        raise VissimInputError(
            f"cannot write {path}: channel_names {tuple(channel_names)} do "
            f"not match pixels of shape {arr.shape}; expected {expected}"
        )
    return arr


def write_image(
    path: str | os.PathLike[str],
    pixels: Any,
    *,
    provenance: dict | None = None,
    overwrite: bool = False,
    channel_names: Any = None,
    encoding: str = "srgb",
    bit_depth: int = 8,
    arcmin_per_px: float | None = None,
    alpha: Any = None,
) -> Path:
    """Write linear-light ``pixels`` to ``path``; the format follows the suffix.

    Parameters
    ----------
    pixels:
        Linear light, shape ``(H, W)`` or ``(H, W, 3)``; finite values only.
    provenance:
        JSON-safe-able dict; EXR stores it as the string attribute ``vissim_provenance``,
        PNG/TIFF in the sidecar ``<path>.json``.
    channel_names:
        Optional check: must be ``("Y",)`` for mono or ``("R", "G", "B")`` for colour.
    arcmin_per_px:
        The image's angular sampling, stored at the provenance record's top-level key
        ``"arcmin_per_px"`` (a record is written even without ``provenance``); read back as
        `Image.arcmin_per_px`.  ``None`` (default) records none.
    encoding
        PNG/TIFF only: ``"srgb"`` (default) encodes with IEC 61966-2-1, ``"linear"`` does
        not.  EXR always stores linear float32.
    bit_depth
        PNG/TIFF only: values are clipped to [0, 1] and rounded to this many bits (8 or 16).
    alpha
        Optional alpha channel, shape ``(H, W)``, values in [0, 1]: written as the last
        sample of a PNG/TIFF (linearly quantised, no transfer function) or as EXR ``A``.
        8-bit only for PNG (Pillow writes no 16-bit alpha PNG).
    """
    path = Path(path)
    kind = _kind(path)
    if encoding not in ("srgb", "linear"):
        raise VissimInputError(f"cannot write {path}: encoding must be 'srgb' or 'linear', got {encoding!r}")
    if bit_depth not in (8, 16):
        raise VissimInputError(f"cannot write {path}: bit_depth must be 8 or 16 bits, got {bit_depth!r}")
    arr = _validated_pixels(path, pixels, channel_names)
    alpha_plane = _validated_alpha(path, alpha, arr.shape[:2])
    lost = _png_16_bit_loss(arr.ndim == 3, alpha_plane is not None) if kind == "png" and bit_depth == 16 else None
    if lost:
        raise VissimInputError(f"cannot write {path}: 16-bit {lost} PNG is not supported (Pillow cannot write it); "
                               "use .tif or .exr")
    provenance = _with_sampling(provenance, arcmin_per_px, path)
    if kind == "exr":
        planes = arr if alpha_plane is None else np.dstack([arr, alpha_plane])
        names = None if alpha_plane is None else (*(MONO_CHANNELS if arr.ndim == 2 else RGB_CHANNELS), "A")
        _write_exr(path, planes, provenance, overwrite, names=names)
        return path

    sidecar = _sidecar_path(path)
    refuse_existing(path, sidecar, overwrite=overwrite)
    codes = _quantise(path, arr, encoding, bit_depth)
    extra: dict[str, Any] = {}
    if alpha_plane is not None:
        codes = np.dstack([codes, _quantise(path, alpha_plane, "linear", bit_depth)])
        extra["extrasamples"] = ["unassalpha"]

    def encode(tmp) -> None:
        if kind == "png":
            _save_png(codes, tmp)
        else:
            photometric = "minisblack" if arr.ndim == 2 else "rgb"
            tifffile.imwrite(tmp, codes, photometric=photometric, compression="zlib", **extra)

    return _write_with_sidecar(path, sidecar, encode, provenance, overwrite)


def encode_png(codes: np.ndarray) -> bytes:
    """8-bit codes, (H, W) or (H, W, 3), as the bytes of a PNG file in memory (zlib at `PNG_COMPRESS_LEVEL`, as
    `write_image` writes one): a figure's, put in a file later by `write_png_bytes`."""
    buffer = io.BytesIO()
    _save_png(codes, buffer)
    return buffer.getvalue()


def _save_png(codes: np.ndarray, target) -> None:
    """8-bit codes (grey, RGB or with alpha) saved as PNG into ``target`` (a path or a binary file object)."""
    _PILImage.fromarray(np.ascontiguousarray(codes)).save(target, format="PNG", compress_level=PNG_COMPRESS_LEVEL)


def write_png_bytes(path: str | os.PathLike[str], png: bytes, *, provenance: dict | None = None,
                    overwrite: bool = False) -> Path:
    """An already encoded PNG (a report figure) written as it is, atomically, with its provenance sidecar."""
    path = Path(path)
    if _kind(path) != "png" or not bytes(png[:8]) == _PNG_SIGNATURE:
        raise VissimInputError(f"cannot write {path}: expected PNG bytes for a .png file")
    sidecar = _sidecar_path(path)
    refuse_existing(path, sidecar, overwrite=overwrite)
    return _write_with_sidecar(path, sidecar, lambda tmp: Path(tmp).write_bytes(png), provenance, overwrite)


def _write_with_sidecar(path: Path, sidecar: Path, write, provenance: dict | None, overwrite: bool) -> Path:
    """``write(tmp)`` put in place at ``path`` with its provenance ``sidecar``, together or neither (checked before)."""
    with output_transaction():
        with atomic_output(path, overwrite=overwrite) as tmp:
            write(tmp)
        if provenance is not None:
            write_text_atomic(sidecar, to_json(provenance) + "\n", overwrite=overwrite)
    if provenance is None:
        remove_output(sidecar)  # a stale provenance sidecar: gone once the image is in place
    return path


def _quantise(path: Path, arr: np.ndarray, encoding: str, bit_depth: int) -> np.ndarray:
    lin = arr.astype(np.float64)
    n_out = int(np.count_nonzero((lin < 0.0) | (lin > 1.0)))
    if n_out:
        logger.warning("%s: clipping %d of %d pixel values outside [0, 1]", path, n_out, lin.size)
    encoded = srgb_encode(lin) if encoding == "srgb" else np.clip(lin, 0.0, 1.0)
    dtype = np.uint8 if bit_depth == 8 else np.uint16
    return np.round(encoded * np.iinfo(dtype).max).astype(dtype)


def _write_exr(path: Path, arr: np.ndarray, provenance: dict | None, overwrite: bool, names=None) -> None:
    names = names or (MONO_CHANNELS if arr.ndim == 2 else RGB_CHANNELS)
    planes = [arr] if arr.ndim == 2 else [arr[..., i] for i in range(arr.shape[-1])]
    # OpenEXR.Channel ignores strides: a non-contiguous view is written scrambled.
    channels = {n: OpenEXR.Channel(np.ascontiguousarray(p, dtype=np.float32)) for n, p in zip(names, planes)}
    header: dict[str, Any] = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    if provenance is not None:
        header[PROVENANCE_ATTRIBUTE] = to_json(provenance, compact=True)  # one str -> one EXR string attribute
    with atomic_output(path, overwrite=overwrite) as tmp:
        OpenEXR.File(header, channels).write(str(tmp))


#: Channel names a single-channel data map (depth in metres) may carry, in order of preference.
DATA_MAP_CHANNELS = ("Z", "depth", "Y")


def read_data_map(path: str | os.PathLike[str]) -> Image:
    """A single-channel data map (e.g. depth in metres) from an EXR or ``.npy`` file.

    EXR: the only channel, or the first of ``Z``, ``depth``, ``Y``.  Values are not light: no
    transfer function applies.  NaN is refused; +inf is allowed (sky, at infinity).
    """
    path = Path(path)
    if not path.is_file():
        raise VissimInputError(f"{path}: no such file")
    if path.suffix.lower() == ".npy":
        try:
            data, provenance, name = np.load(path, allow_pickle=False), {}, "Z"
        except Exception as exc:  # numpy raises ValueError, OSError, ...
            raise VissimInputError(f"{path}: cannot read as a .npy array: {_one_line(exc)}") from exc
    elif path.suffix.lower() == ".exr":
        channels, provenance = _open_exr(path)
        names = list(channels) if len(channels) == 1 else [n for n in DATA_MAP_CHANNELS if n in channels][:1]
        if not names:
            raise VissimInputError(f"{path}: EXR channels {sorted(channels)}: a data map needs one channel, or one named Z, depth or Y")
        name, data = names[0], channels[names[0]]
    else:
        raise VissimInputError(f"{path}: data maps must be .exr or .npy, got {path.suffix!r}")
    if data.dtype.kind != "f" or data.ndim != 2:
        raise VissimInputError(f"{path}: a data map must be a 2-D float array, got {data.dtype} of shape {data.shape}")
    if np.any(np.isnan(data)):
        raise VissimInputError(f"{path}: contains {int(np.sum(np.isnan(data)))} NaN values")
    return Image(np.ascontiguousarray(data, dtype=np.float32), (name,), provenance, sampling_from_provenance(provenance))


def write_data_map(path: str | os.PathLike[str], data: Any, *, channel: str = "Z", provenance: dict | None = None,
                   overwrite: bool = False, arcmin_per_px: float | None = None) -> Path:
    """Write a single-channel float32 EXR data map (e.g. depth in metres, channel ``Z``).

    ``arcmin_per_px`` is recorded as in `write_image`.
    """
    path = Path(path)
    if path.suffix.lower() != ".exr":
        raise VissimInputError(f"{path}: data maps are written as .exr")
    arr = np.asarray(data, dtype=np.float32)
    if arr.ndim != 2 or np.any(np.isnan(arr)):
        raise VissimInputError(f"{path}: a data map must be a 2-D array without NaN, got shape {arr.shape}")
    _write_exr(path, arr, _with_sampling(provenance, arcmin_per_px, path), overwrite, names=(channel,))
    return path


def to_preview_png(
    path: str | os.PathLike[str],
    pixels: Any,
    *,
    overwrite: bool = False,
    provenance: dict | None = None,
    arcmin_per_px: float | None = None,
) -> Path:
    """Write an 8-bit sRGB PNG preview (e.g. of a PSF), scaled so its maximum is 1.

    ``arcmin_per_px`` is recorded as in `write_image`.
    """
    path = Path(path)
    arr = _validated_pixels(path, pixels, None)
    peak = float(arr.max())
    if peak <= 0.0:
        raise VissimInputError(
            f"cannot write {path}: cannot normalise pixels "
            f"whose maximum is {peak} (must be > 0)"
        )
    arr = arr / np.float32(peak)
    return write_image(path, arr, provenance=provenance, overwrite=overwrite, encoding="srgb", bit_depth=8,
                       arcmin_per_px=arcmin_per_px)
