"""Validation of inputs: one clear error naming the bad value and its unit; memory refused before it is asked for."""

from __future__ import annotations

import math
import numbers
import os
import unicodedata
from pathlib import Path

from vissim.errors import VissimInputError, VissimTypeError
from vissim.units import CYC_PER_DEG_PER_CYC_PER_RAD, nm_to_mm

__all__ = ["number_within", "range_text", "MAX_FIELD_DEG", "NAVARRO_ACCOMMODATION_RANGE_DIOPTERS", "ARIZONA_ACCOMMODATION_RANGE_DIOPTERS", "finite_number", "positive_number", "arcmin_per_px", "MAX_ARCMIN_PER_PX", "pupil_diameter_mm",
           "eye_pupil_diameter_mm", "ENTRANCE_PUPIL_RANGE_MM", "EYE_PUPIL_RANGE_MM", "size_px", "size_text", "counted",
           "samples_per_pixel", "MAX_SPP", "WAVELENGTH_RANGE_NM", "EYE_RENDER_WAVELENGTH_RANGE_NM", "CIE_YBAR_RANGE_NM",
           "EYE_RENDER_MAX_THETA_DEG", "eye_field_deg", "MAX_TRACE_FIELD_DEG", "EYE_MTF_RANGE_CYC_PER_DEG",
           "mtf_cyc_per_deg", "eye_prescription_meridians", "LOGMAR_STEP_RANGE", "PRINT_DPI_RANGE",
           "BENCH_LENGTH_RANGE_MM", "DISPLAY_PPI_RANGE",
           "ATV_PARABOLA_WINDOW_RANGE_DIOPTERS", "SUMMATION_RANGE_ARCMIN", "TEXELS_PER_PX_RANGE",
           "PANEL_PADDING_RANGE_ARCMIN", "GUESS_LAPSE_RANGE", "MAX_WHOLE_NUMBER", "sampler_seed",
           "ATCHISON_SMITH_RANGE_NM", "DEFAULT_WAVELENGTH_NM", "wavelength_nm",
           "VERTEX_DISTANCE_RANGE_MM", "vertex_distance_mm", "DEFAULT_MAX_LAYERS", "ATV_PARABOLA_WINDOW_DIOPTERS",
           "DEFAULT_LAYER_SPACING_FRACTION", "MAX_FIELD_NODES", "EYE_WAVELENGTH_RANGE_NM", "EYE_LIGHT_RANGE_NM", "eye_wavelength_nm", "ACCOMMODATION_RANGE_DIOPTERS",
           "accommodation_diopters", "trial_lens_diopters", "F_NUMBER_RANGE", "FOCAL_LENGTH_RANGE_MM",
           "OBJECT_DISTANCE_RANGE_M", "MAX_SAMPLER_SEED", "MAX_POWER_DIOPTERS", "available_memory_bytes",
           "format_bytes", "check_allocation", "instance_of", "describe", "MAX_NAME_CHARS", "MAX_DESCRIPTION_CHARS",
           "name_problem", "path_arg", "number_array", "ARCMIN_PER_PX_RANGE", "MIN_ARCMIN_PER_PX",
           "MAX_CAMPAIGN_SEED", "TRIAL_LENS_RANGE_DIOPTERS", "AXIS_RANGE_DEG", "AUTOREFRACTOR_SPHERE_RANGE_DIOPTERS",
           "AUTOREFRACTOR_CYLINDER_RANGE_DIOPTERS", "AUTOREFRACTOR_VERTEX_RANGE_MM", "PUPIL_DISTANCE_RANGE_MM",
           "DISPLAY_CODE_RANGE", "TRIAL_TIME_RANGE_S", "EXAMINATION_DURATION_RANGE_S", "ILLUMINANCE_RANGE_LX",
           "LOGMAR_RANGE", "REFRACTIVE_INDEX_RANGE", "DATA_RANGE_RANGE", "TILE_RANGE_PX", "MARGIN_RANGE_PX",
           "LAYER_SPACING_FRACTION_RANGE", "OVERSAMPLE_RANGE", "COLLIMATOR_POWER_RANGE_DIOPTERS",
           "MAX_PIXEL_RADIANCE", "FIT_POWER_RANGE_DIOPTERS", "MODEL_ERROR_RANGE_DIOPTERS", "MAX_WORKERS",
           "VIEWING_DISTANCE_RANGE_M", "LENS_GAP_RANGE_MM", "MAX_PSF_SIZE_PX"]


def describe(value) -> str:
    """A short account of ``value`` for an error line: "str '-2.00 DS'", "a PSF", "ndarray of shape (4, 4)"."""
    if isinstance(value, (str, bytes, int, float, complex, type(None), list, tuple, dict)):
        text = repr(value)
        return f"{type(value).__name__} {text if len(text) <= 40 else text[:37] + '...'}"
    if hasattr(value, "shape") and hasattr(value, "dtype"):
        return f"{type(value).__name__} of shape {tuple(value.shape)}"
    return f"a {type(value).__name__}"


def instance_of(value, types, name: str, accepted: str):
    """``value`` if it is an instance of ``types``; else a `VissimTypeError` saying what ``name`` accepts."""
    if isinstance(value, types):
        return value
    raise VissimTypeError(f"{name} must be {accepted}, got {describe(value)}")


def path_arg(value, name: str) -> Path:
    """``value`` as a `Path` if it is a ``str`` or path-like; else what ``name`` accepts."""
    if isinstance(value, (str, os.PathLike)) and not isinstance(value, bytes):
        return Path(value)
    raise VissimTypeError(f"{name} must be a path (str or pathlib.Path), got {describe(value)}")


def number_array(value, name: str, unit: str):
    """``value`` as a float ndarray; something that is no number (a str, an object) refused with what is accepted."""
    import numpy as np  # here: checks stays importable without numpy's start-up cost

    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise VissimTypeError(f"{name} must be a number or a sequence of numbers in {unit}, got {describe(value)}") from None


def finite_number(value, name: str, unit: str, *, allow_inf: bool = False) -> float:
    """``value`` as a float; NaN (and infinity unless ``allow_inf``) refused."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise VissimInputError(f"{name} must be a number in {unit}, got {value!r}") from None
    if math.isnan(number) or (math.isinf(number) and not allow_inf):
        raise VissimInputError(f"{name} must be finite (in {unit}), got {value!r}")
    return number


def positive_number(value, name: str, unit: str, *, allow_inf: bool = False) -> float:
    """A finite (or, with ``allow_inf``, infinite) number > 0."""
    number = finite_number(value, name, unit, allow_inf=allow_inf)
    if number <= 0.0:
        raise VissimInputError(f"{name} must be a positive number of {unit}, got {value!r}")
    return number


#: Wavelengths a PSF may be computed at (nm): the near UV to the near IR.
WAVELENGTH_RANGE_NM = (200.0, 2000.0)
#: Wavelengths the schematic-eye renderer traces (its media's index tables, nm).
EYE_RENDER_WAVELENGTH_RANGE_NM = (350.0, 850.0)
#: Wavelengths a schematic eye is traced at (nm): the span of the reference lines its media's dispersion is
#: written through (Navarro 1985: 365 and 1014 nm; `vissim.optics.eyes.dispersion`); outside it the formulas
#: extrapolate (at 200 nm Navarro's eye has 290 D of myopia).
EYE_WAVELENGTH_RANGE_NM = (365.0, 1014.0)
#: One wavelength an eye is rendered and simulated in (an eye campaign's ``light``, ``render eye --wavelength-nm``,
#: scene files): where the renderer's tables and the media's dispersion both hold.
EYE_LIGHT_RANGE_NM = (max(EYE_WAVELENGTH_RANGE_NM[0], EYE_RENDER_WAVELENGTH_RANGE_NM[0]),
                      min(EYE_WAVELENGTH_RANGE_NM[1], EYE_RENDER_WAVELENGTH_RANGE_NM[1]))
#: Where CIE 1931 ȳ(λ) is tabulated (nm): a monochromatic spectral render divides it out.
CIE_YBAR_RANGE_NM = (360.0, 830.0)
#: The schematic-eye renderer: the image's widest direction at most this far from the eye's optical axis (deg; its
#: tables' reach). A chart's field angle is held to `MAX_FIELD_DEG`, which keeps a chart's image within it.
EYE_RENDER_MAX_THETA_DEG = 60.0
#: A depth scene needing more layers is refused unless its ``max_layers`` is raised (or None: no limit).
DEFAULT_MAX_LAYERS = 256
#: The eye campaign (validation/eye): its image's side, px (each item renders and simulates it several times),
#: and the rays across the iris of its self-check's trace.
EYE_BENCH_SIZE_RANGE_PX = (16, 512)
EYE_BENCH_RAYS_ACROSS_RANGE = (21, 1001)
#: Where Atchison & Smith's 2005 fit of the eye's chromatic aberration holds (their data: 400-900 nm).
ATCHISON_SMITH_RANGE_NM = (380.0, 1000.0)
#: The wavelength every command and function uses when none is given, nm: the thesis's, near the
#: photopic peak (docs/conventions.md, "Defaults"). The bench's wave truth alone differs: it is
#: traced at the glass's d line, where the lenses have the index Mitsuba renders.
DEFAULT_WAVELENGTH_NM = 550.0


def number_within(value, name: str, unit: str, bounds: tuple[float, float], what: str = "") -> float:
    """A finite number within ``bounds`` (inclusive), or one error naming it, the range and ``unit``."""
    number = finite_number(value, name, unit)
    low, high = bounds
    if not low <= number <= high:
        raise VissimInputError(f"{name} must be {range_text(bounds, unit)}{what}, got {number:g} {unit}")
    return number + 0.0  # -0.0 as 0.0


def range_text(bounds: tuple[float, float], unit: str) -> str:
    """How a refusal names the values ``bounds`` (inclusive) allows: ``within 0-10 dioptres``,
    ``within -5 to 5 mm``, or, for a range of one value, ``0 dioptres only``."""
    low, high = bounds
    if low == high:
        return f"{low:g} {unit} only"
    span = f"{low:g} to {high:g}" if low < 0 else f"{low:g}-{high:g}"
    return f"within {span} {unit}"


def wavelength_nm(value, name: str = "wavelength") -> float:
    """A wavelength within `WAVELENGTH_RANGE_NM`."""
    return number_within(value, name, "nm", WAVELENGTH_RANGE_NM)


def eye_wavelength_nm(value, name: str = "wavelength") -> float:
    """A wavelength a schematic eye is traced at, within `EYE_WAVELENGTH_RANGE_NM`."""
    return number_within(value, name, "nm", EYE_WAVELENGTH_RANGE_NM, " (where the eye's media are described)")


#: Trial-lens vertex distances, mm (the last lens's back vertex to the camera's or eye's principal
#: plane): the thesis's bench used 10, spectacles sit at 12-15; past 20 cm a lens is no trial lens.
VERTEX_DISTANCE_RANGE_MM = (0.0, 200.0)
#: The accommodation an eye exerts, dioptres: from relaxed to beyond a child's amplitude
#: (about 15 D at 8 years, Duane 1922). Every eye a user describes takes it: campaigns, scene files, the ATV.
ACCOMMODATION_RANGE_DIOPTERS = (0.0, 20.0)
#: Navarro's accommodation formulas are used over 0-10 D: ISET3d's ``convertToNavarroAccomm.m``
#: samples the model (in Zemax) from 0 to 10 D and notes the formulas were fitted at 5 and 10 D;
#: beyond 10 D they extrapolate a lens no source describes.
NAVARRO_ACCOMMODATION_RANGE_DIOPTERS = (0.0, 10.0)
#: The Arizona eye's formulas are linear in A, and its lens index, 1.42 + 0.00256A − 0.00022A²,
#: peaks at A ≈ 5.8 D and falls beyond: we accept 0-6 D, the range over which it rises (the
#: Field Guide gives no range; the FRED example accommodates to 4 D).
ARIZONA_ACCOMMODATION_RANGE_DIOPTERS = (0.0, 6.0)
#: A field angle through an eye that a user gives, degrees per axis (x, y): the chart's centre or a PSF's field, for
#: every command and file that takes one (`eye`, `psf`, `blur`, `render eye`, `population`, eye and population
#: campaigns, `EyeBench`); an image around it reaches to `EYE_RENDER_MAX_THETA_DEG` from the optical axis. The schematic
#: models are built for 0-40 deg and the measured eyes go to 40 (Jaeken & Artal 2012: -40 to 40 horizontally); every
#: model traces a 6 mm pupil to (+-45, +-45), and the renderer's tables keep a chart there in view. Beyond, the
#: widest pupils' rays start to miss the cornea (a 9.9 mm pupil already at -45 deg in Navarro's eye: that trace
#: refuses, naming the surface and the pupil); from 55-80 deg every model's do.
MAX_FIELD_DEG = 45.0
#: The widest direction a trace takes, degrees per axis from the eye's axis (90 is grazing): a pixel of an image about
#: a field at `MAX_FIELD_DEG` lies beyond it; rays that miss a surface there are refused by the trace, naming it.
MAX_TRACE_FIELD_DEG = 89.0
#: A field-dependent blur's PSF nodes (each a trace and a PSF, 0.2-0.4 s on 2 cores, with progress shown): at most
#: this many per image (the default 2 deg step over a 4K image at 1 arcmin/px needs 627).
MAX_FIELD_NODES = 1600


#: Viewing distances a chart (or a depth panel's chart) may be made for, m; far beyond, its sizes in mm overflow.
VIEWING_DISTANCE_RANGE_M = (1e-3, 1e6)
#: Gap between trial lenses in the holder, mm: touching to a metre (the vertex distance: `VERTEX_DISTANCE_RANGE_MM`).
LENS_GAP_RANGE_MM = (0.0, 1000.0)
#: A camera's f-number, focal length (mm) and distance to what it images (m), as bench files take them.
F_NUMBER_RANGE = (0.5, 128.0)
FOCAL_LENGTH_RANGE_MM = (1.0, 1000.0)
OBJECT_DISTANCE_RANGE_M = (0.01, 1000.0)


def eye_field_deg(value, name: str = "field angle") -> tuple[float, float]:
    """An eye's field angle (x, y), degrees, each within +-`MAX_FIELD_DEG`."""
    try:
        x, y = value
    except (TypeError, ValueError):
        raise VissimInputError(f"{name} must be two angles (x, y) in degrees, got {describe(value)}") from None
    limit = (-MAX_FIELD_DEG, MAX_FIELD_DEG)
    return (number_within(x, f"{name} x", "deg", limit, " (an eye's field)"),
            number_within(y, f"{name} y", "deg", limit, " (an eye's field)"))


def accommodation_diopters(value, name: str = "accommodation") -> float:
    """An accommodation exerted within `ACCOMMODATION_RANGE_DIOPTERS`."""
    return number_within(value, name, "dioptres", ACCOMMODATION_RANGE_DIOPTERS)


def trial_lens_diopters(value, name: str = "trial lens power") -> float:
    """A trial lens's sphere or cylinder within `TRIAL_LENS_RANGE_DIOPTERS`."""
    return number_within(value, name, "dioptres", TRIAL_LENS_RANGE_DIOPTERS, " (a trial lens)")


def eye_prescription_meridians(sphere_diopters, cylinder_diopters, name: str) -> None:
    """An eye's prescription (sphere, cylinder) lies, in each principal meridian, within `TRIAL_LENS_RANGE_DIOPTERS`:
    the trial lenses that would correct it (every eye a user describes: `build_eye`, depth viewers, campaigns)."""
    for meridian in (sphere_diopters, sphere_diopters + cylinder_diopters):
        trial_lens_diopters(meridian, f"the principal meridian of {name}")


def vertex_distance_mm(value, name: str = "vertex distance") -> float:
    """A vertex distance within `VERTEX_DISTANCE_RANGE_MM`."""
    return number_within(value, name, "mm", VERTEX_DISTANCE_RANGE_MM)


def available_memory_bytes() -> int:
    """Memory this process may still allocate, bytes: Linux's MemAvailable, else physical memory."""
    try:
        with open("/proc/meminfo", encoding="ascii") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (OSError, ValueError, AttributeError):  # pragma: no cover - not Linux
        return 1 << 62


def format_bytes(n_bytes: float) -> str:
    """``n_bytes`` in binary units: '1.66 TiB'."""
    value = float(n_bytes)
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"):
        if value < 1024.0 or unit == "EiB":
            return f"{value:.3g} {unit}"
        value /= 1024.0
    raise AssertionError("unreachable")  # pragma: no cover


def check_allocation(n_bytes: float, what: str) -> None:
    """Refuse, before allocating, a request whose estimated peak memory the machine cannot hold.

    ``what`` names the request and its size ('a 100000 x 100000 px render'); the error says
    how much memory it would need and how much is available.
    """
    try:
        needed = float(n_bytes)
    except OverflowError:  # an integer estimate beyond any float
        needed = math.inf
    available = available_memory_bytes()
    if not math.isfinite(needed) or needed > available:
        shown = f"{format_bytes(needed)} of memory" if math.isfinite(needed) else "more memory than any machine has"
        raise VissimInputError(f"{what} would need {shown}; this machine has {format_bytes(available)} available")


#: Angular samplings vissim takes, arcmin per pixel (the thesis's is 1): finer ones need more
#: memory than any machine has (checked by `check_allocation`), coarser ones are no image.
ARCMIN_PER_PX_RANGE = MIN_ARCMIN_PER_PX, MAX_ARCMIN_PER_PX = 1e-6, 60.0


def arcmin_per_px(value, name: str = "angular sampling") -> float:
    """An angular pixel size within [`MIN_ARCMIN_PER_PX`, `MAX_ARCMIN_PER_PX`] (1 degree)."""
    step = positive_number(value, name, "arcmin per pixel")
    if not MIN_ARCMIN_PER_PX <= step <= MAX_ARCMIN_PER_PX:
        raise VissimInputError(
            f"{name} must be {range_text((MIN_ARCMIN_PER_PX, MAX_ARCMIN_PER_PX), 'arcmin per pixel')}, got {step:g}")
    return step


#: Entrance pupils of any optics (a camera, a telescope, an eye), mm: the thesis camera's is 3.6
#: (18 mm at f/5); a 50 mm f/1.4 lens's 36.
ENTRANCE_PUPIL_RANGE_MM = MIN_PUPIL_MM, MAX_PUPIL_MM = 0.01, 1000.0
#: A human eye's pupil, mm: about 1.5 in bright light to 8-9 dark-adapted in the young, with a margin.
#: Commands whose viewer is an eye (render atv, atv simulate, blur-depth, render depth's eye) take these.
EYE_PUPIL_RANGE_MM = 1.0, 10.0


#: Spatial frequencies an eye's MTF is asked at, cycles per degree: from 0 to the incoherent cutoff of the widest eye
#: pupil in the shortest light an eye is traced in (`EYE_PUPIL_RANGE_MM` over `EYE_WAVELENGTH_RANGE_NM`: 10 mm / 365 nm,
#: 478 cycles/deg); beyond, every eye's MTF is 0.
EYE_MTF_RANGE_CYC_PER_DEG = (0.0, EYE_PUPIL_RANGE_MM[1] / nm_to_mm(EYE_WAVELENGTH_RANGE_NM[0]) * CYC_PER_DEG_PER_CYC_PER_RAD)


def mtf_cyc_per_deg(values, name: str = "MTF frequency") -> list[float]:
    """Frequencies an eye's MTF is asked at, each within `EYE_MTF_RANGE_CYC_PER_DEG`."""
    return [number_within(v, name, "cycles/deg", EYE_MTF_RANGE_CYC_PER_DEG, " (to the widest eye pupil's cutoff)")
            for v in values]


def pupil_diameter_mm(value, name: str = "pupil diameter") -> float:
    """An entrance pupil diameter within `ENTRANCE_PUPIL_RANGE_MM` mm."""
    return _pupil_within(value, name, ENTRANCE_PUPIL_RANGE_MM, "")


def eye_pupil_diameter_mm(value, name: str = "pupil diameter") -> float:
    """An eye's pupil diameter within `EYE_PUPIL_RANGE_MM` mm."""
    return _pupil_within(value, name, EYE_PUPIL_RANGE_MM, " (a human eye's pupil)")


def _pupil_within(value, name: str, bounds: tuple[float, float], what: str) -> float:
    pupil = positive_number(value, name, "mm")
    low, high = bounds
    if not low <= pupil <= high:
        raise VissimInputError(f"{name} must be {range_text(bounds, 'mm')}{what}, got {pupil:g} mm")
    return pupil


def counted(count: int, noun: str, plural: str | None = None) -> str:
    """``count`` and its noun in number, as messages write them: ``1 ray``, ``4 rays``, ``2 keys``."""
    return f"{count} {noun if count == 1 else plural or noun + 's'}"


def size_text(shape, unit: str = "px") -> str:
    """An image size as users read it, width x height: ``(480, 640)`` (rows, cols) -> '640 × 480 px (width × height)'.

    ``shape`` is in array order, ``(rows, cols, ...)`` (a NumPy shape; channels are ignored). Every
    message that states a size goes through here, so a size always reads width first; a square
    needs no legend ('64 × 64 px').
    """
    rows, cols = (float(v) for v in tuple(shape)[:2])
    width, height = (f"{int(v)}" if v.is_integer() else f"{v:.4g}" for v in (cols, rows))
    text = f"{width} × {height} {unit}"
    return text if rows == cols else f"{text} (width × height)"


def size_px(value, name: str = "size_px") -> tuple[int, int]:
    """An image size (rows, cols) in whole pixels >= 1."""
    try:
        size = tuple(int(v) for v in value)
    except (TypeError, ValueError):
        size = ()
    if len(size) != 2 or min(size) < 1 or tuple(value) != size:
        raise VissimInputError(f"{name} must be (rows, cols) in whole pixels >= 1, got {value!r}")
    return size  # type: ignore[return-value]


#: A chart's row step, LogMAR: more than 0, at most the whole `LOGMAR_RANGE`.
LOGMAR_STEP_RANGE = (0.0, 3.0)
#: A printed chart's resolution, dots per inch: 1 to beyond any printer's (photo printers 4800, imagesetters 5080).
PRINT_DPI_RANGE = (1.0, 10000.0)

#: A bench part's length, mm (the ATV's tube, eye relief, a lens's thickness and clear aperture): within a metre,
#: the scale of any bench (the thesis's tube is 125 mm).
BENCH_LENGTH_RANGE_MM = (0.0, 1000.0)
#: A display's resolution, pixels per inch: to beyond microdisplays' (about 3000-5000; the thesis's phone 326).
DISPLAY_PPI_RANGE = (1.0, 10000.0)

#: The ATV analysis's local parabola window, dioptres: more than 0 (a parabola needs neighbouring lenses) to the whole
#: trial set (`TRIAL_LENS_RANGE_DIOPTERS`: 60 D).
ATV_PARABOLA_WINDOW_RANGE_DIOPTERS = (0.0, 60.0)
#: Spatial summation (Ricco's area) diameter, arcmin: more than 0 to 10 deg, beyond the 1-2 deg of the dark-adapted
#: periphery (the thesis takes 10 arcmin).
SUMMATION_RANGE_ARCMIN = (0.0, 600.0)

#: A chart texture's texels per image pixel (per axis): from a texture as coarse as 4 pixels a texel to 64 (the
#: benches take 4; beyond 16 a texel is finer than any sample lands on).
TEXELS_PER_PX_RANGE = (0.25, 64.0)

#: Blank paper around a depth panel's chart, arcmin: none to 90 deg (a panel seen from its front fills at most the half
#: of the view before it).
PANEL_PADDING_RANGE_ARCMIN = (0.0, 90.0 * 60.0)

#: A psychometric function's guess and lapse rates: at least 0, below one half (at 0.5 the observer's "yes" is a coin).
GUESS_LAPSE_RANGE = (0.0, 0.5)

#: The largest whole number (a count, a size, an index) a user may type: 2^53, beyond which floats skip whole numbers.
MAX_WHOLE_NUMBER = 2**53

#: Largest PSF field a user may ask for, pixels (``psf --size``, `compute_psf`): 16384² complex doubles take 4 GiB.
MAX_PSF_SIZE_PX = 16384
#: Most samples per pixel a render takes (Mitsuba counts them in 32 bits; 65536 spp of the
#: thesis bench takes hours on 2 cores).
MAX_SPP = 1 << 16


#: Sampler seeds are 32-bit.
MAX_SAMPLER_SEED = 2**32 - 1
#: Campaign seeds: the no-lens render uses seed_a + seed_b + 1, which must stay a sampler seed.
MAX_CAMPAIGN_SEED = (MAX_SAMPLER_SEED - 1) // 2


def sampler_seed(value, name: str = "seed") -> int:
    """A render's seed: a whole number within 0-`MAX_SAMPLER_SEED` (the samplers' 32-bit state)."""
    is_number = isinstance(value, numbers.Real) and not isinstance(value, bool)  # NumPy's integers too
    if not is_number or not math.isfinite(value) or not 0 <= value <= MAX_SAMPLER_SEED or value != int(value):
        raise VissimInputError(f"{name} must be a whole number within 0-{MAX_SAMPLER_SEED} (the samplers' 32-bit "
                               f"state), got {value!r}")
    return int(value)


def samples_per_pixel(value, name: str = "spp") -> int:
    """A whole number of samples per pixel in 1-`MAX_SPP`; a number out of range is told so first."""
    is_number = isinstance(value, (int, float)) and not isinstance(value, bool)
    if is_number and not 1 <= value <= MAX_SPP:  # NaN and infinity too
        raise VissimInputError(f"{name} must be 1-{MAX_SPP} samples per pixel, got {value!r}")
    if not is_number or value != int(value):
        raise VissimInputError(f"{name} must be a whole number of samples per pixel in 1-{MAX_SPP}, got {value!r}")
    return int(value)


#: Longest name a campaign or configuration may have, characters: a label in tables, figures and the
#: report (never part of a file name), so one line of printable text of a readable length.
MAX_NAME_CHARS = 100
#: Longest campaign description, characters: a paragraph or two, shown at the top of the report.
MAX_DESCRIPTION_CHARS = 2000


def name_problem(value: str) -> str | None:
    """Why ``value`` cannot be a campaign or configuration name (too long, a control character), or None."""
    if not value.strip():
        return f"a name is at least one visible character, got {value!r}"
    if len(value) > MAX_NAME_CHARS:
        return (f"a name is at most {MAX_NAME_CHARS} characters, got {len(value)} "
                f"({value[:24]!r}...)")
    control = next((c for c in value if unicodedata.category(c).startswith("C")), None)
    if control is not None:
        return f"a name is one line of printable text, got the control character {control!r} in {describe(value)}"
    return None


#: Largest lens power vissim reads from a user, dioptres (a 1 mm focal length: far beyond any
#: eye or trial lens). Results computed from inputs may exceed it.
MAX_POWER_DIOPTERS = 1000.0


# -- ranges of the values campaign, scene and subject files give (docs/conventions.md, "Input ranges") --
#: A trial lens's sphere or cylinder, dioptres: trial sets go to +-20; beyond +-30 a lens is no trial lens.
TRIAL_LENS_RANGE_DIOPTERS = (-30.0, 30.0)
#: A cylinder axis, degrees (TABO): 0 and 180 are the same meridian.
AXIS_RANGE_DEG = (0.0, 180.0)
#: An autorefractor's printed sphere (and spherical equivalent) and cylinder, dioptres: what instruments measure.
AUTOREFRACTOR_SPHERE_RANGE_DIOPTERS = (-30.0, 30.0)
AUTOREFRACTOR_CYLINDER_RANGE_DIOPTERS = (-10.0, 10.0)
#: The vertex distance an autorefractor reports its reading at, mm: 0 (cornea) or a spectacle's 12-14, with a margin.
AUTOREFRACTOR_VERTEX_RANGE_MM = (0.0, 25.0)
#: Interpupillary distance, mm: a small child's ~40 to a large adult's ~75, with a margin.
PUPIL_DISTANCE_RANGE_MM = (30.0, 90.0)
#: A display code value (ATV thresholds): 0 black to 1 the display's white.
DISPLAY_CODE_RANGE = (0.0, 1.0)
#: One ATV trial, seconds: at most an hour.
TRIAL_TIME_RANGE_S = (0.0, 3600.0)
#: One ATV examination, seconds: at most a day.
EXAMINATION_DURATION_RANGE_S = (0.0, 86400.0)
#: Ambient illuminance, lux: darkness to twice direct sunlight (~100000 lx).
ILLUMINANCE_RANGE_LX = (0.0, 200000.0)
#: A letter's size, LogMAR: -1 (20/2) to 2 (20/2000), beyond any chart's -0.3 to 1.0.
LOGMAR_RANGE = (-1.0, 2.0)
#: A lens's refractive index: above air (an index of 1 is no lens) to beyond any optical glass (~2).
REFRACTIVE_INDEX_RANGE = (1.01, 3.0)
#: The value range SSIM and PSNR take, linear reflectance: the chart's white is 1.
DATA_RANGE_RANGE = (1e-3, 1e3)
#: A campaign tile's rows or columns, pixels: a few letter strokes to 2**20 (memory is checked besides).
TILE_RANGE_PX = (16, 1 << 20)
#: Depth-region margin, pixels: none to far beyond any blur radius.
MARGIN_RANGE_PX = (0.0, 1000.0)
#: Depth layers' spacing, as a fraction of a blur-free depth step: finer is no faster, coarser blurs wrongly.
LAYER_SPACING_FRACTION_RANGE = (1e-3, 1.0)
#: The ATV analysis's local parabola: lenses within this many dioptres of the least value, unless told otherwise.
ATV_PARABOLA_WINDOW_DIOPTERS = 2.5
#: Neighbouring depth layers' blur discs differ by at most this many pixels unless told otherwise.
DEFAULT_LAYER_SPACING_FRACTION = 0.5
#: Sub-pixels per pixel per axis a render or a wave truth takes: 16 x 16 costs 256 times one.
OVERSAMPLE_RANGE = (1, 16)
#: The ATV's collimator power, dioptres (> 0): the thesis's is 8; 40 is a 25 mm focal length.
COLLIMATOR_POWER_RANGE_DIOPTERS = (0.0, 40.0)
#: Brightest display pixel, linear radiance units: keeps the float32 retinal image finite.
MAX_PIXEL_RADIANCE = 1e30
#: The sphere search range ``fit-rx --max-power-diopters`` takes, dioptres: from a blur the fit can still
#: resolve to a trial set's strongest lens.
FIT_POWER_RANGE_DIOPTERS = (0.5, 20.0)
#: The model error ``fit-rx`` adds to its intervals, dioptres.
MODEL_ERROR_RANGE_DIOPTERS = (0.0, 10.0)
#: Most local worker processes a campaign runs (``validate --workers``): far beyond any machine's cores.
MAX_WORKERS = 1024
