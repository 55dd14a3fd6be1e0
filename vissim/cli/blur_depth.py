"""``vissim blur-depth``: blur an image whose pixels lie at different depths (RGB-D), with occlusion.

Inputs from ``vissim render depth`` cover a margin beyond the frame (``margin_px`` in their
provenance, ``inputs.margin_px``): the blur runs on the whole input, so the frame's pixels see
what lies beyond it, and the output is cropped by that margin (``--crop-px`` overrides).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import TYPE_CHECKING

from vissim.checks import DEFAULT_WAVELENGTH_NM, EYE_PUPIL_RANGE_MM, eye_pupil_diameter_mm, size_text
from vissim.cli._common import (EYE_RX_HELP, FIELD_DEG_HELP, add_eye_model_arg, add_json_arg, add_rx_arg,
                                check_outputs_apart, print_result,
                                eye_from_args, field_deg_from_text, image_sampling)
from vissim.cli._parser import Number
from vissim.errors import VissimInputError
from vissim.checks import DEFAULT_LAYER_SPACING_FRACTION, DEFAULT_MAX_LAYERS
from vissim.optics.rx.prescription import Prescription
from vissim.progress import terminal_progress
from vissim.provenance import make_provenance
from vissim.cli import command_help

if TYPE_CHECKING:
    from vissim.optics.rx.viewing_setup import DepthViewer


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "blur-depth",
        help=command_help("blur-depth"),
        description="Blur a linear-light image through an uncorrected eye, each pixel with the defocus "
        "of its depth (effective prescription = eye Rx + 1/d - accommodation), in depth layers "
        "composited with occlusion so that edges neither glow nor leak (see vissim.optics.depth.depth_map).",
    )
    parser.add_argument("input", type=Path, help="image file (.exr, .png, .tif)")
    parser.add_argument("depth", type=Path, help="depth in metres: .npy, or .exr with one channel (Z/depth/Y); inf = sky")
    parser.add_argument("-o", "--output", required=True, type=Path, help="output image (.exr, .png, .tif)")
    add_rx_arg(parser, required=True)
    parser.add_argument("--pupil-mm", required=True, type=float, metavar="MM",
                        help=f"the eye's pupil diameter, {EYE_PUPIL_RANGE_MM[0]:g}-{EYE_PUPIL_RANGE_MM[1]:g} mm")
    focus = parser.add_argument_group(
        "accommodation (none of these options: relaxed, 0 D exerted)",
        "Give the accommodation exerted (--accommodation-diopters), or let the eye focus a target as far as "
        "its amplitude allows: any of --focus-distance-m (the target; if omitted, the depth at the image "
        "centre), --age (amplitude by Hofstetter 1950's mean) or --accommodation-amplitude-diopters (if neither, unlimited).",
    )
    focus.add_argument("--accommodation-diopters", type=float, metavar="A",
                       help="accommodation exerted, dioptres (default none: see above)")
    focus.add_argument("--age", type=float, metavar="Y", help="age in years: amplitude 18.5 - 0.3 Y D (Hofstetter 1950; default none)")
    focus.add_argument("--accommodation-amplitude-diopters", type=float, metavar="A", help="amplitude of accommodation, dioptres (default none: see above)")
    focus.add_argument("--focus-distance-m", type=float, metavar="F", help="distance the eye tries to focus, metres (default none: see above)")
    eye = parser.add_argument_group(
        "schematic eye (in place of the reduced eye)",
        "With --eye-model the eye is a traced schematic eye at one field point (--field-deg, default 0,0): its spherical aberration and its own defocus at --wavelength-nm and at the accommodation "
        "exerted (--accommodation-diopters, physical: its lens changes shape), over the --pupil-mm entrance pupil; "
        + EYE_RX_HELP + "; each depth adds its defocus as for the reduced eye, and the eye is in "
        "focus where its whole wavefront says. The focus-target options (--age, --accommodation-amplitude-diopters, "
        "--focus-distance-m) are the reduced eye's and are refused with it.")
    add_eye_model_arg(eye, "a schematic eye (default none: the reduced eye)")
    eye.add_argument("--field-deg", metavar="X,Y",
                     help=f"with --eye-model: the {FIELD_DEG_HELP}, where the eye is traced (default 0,0)")
    parser.add_argument("--arcmin-per-px", type=float, metavar="S", help="angular sampling (default: the one the image file records)")
    parser.add_argument("--wavelength-nm", type=float, default=DEFAULT_WAVELENGTH_NM, metavar="NM",
                        help=f"wavelength, nm (default {DEFAULT_WAVELENGTH_NM:g})")
    parser.add_argument("--mode", choices=("wave", "geometric"), default="wave", help="PSF optics (default wave)")
    parser.add_argument("--layer-spacing-fraction", type=float, default=DEFAULT_LAYER_SPACING_FRACTION, metavar="F",
                        help="the most neighbouring layers' blur discs may differ, in pixels (a fraction of one; "
                             f"default {DEFAULT_LAYER_SPACING_FRACTION:g})")
    parser.add_argument("--max-layers", type=Number(int, positive=True), default=DEFAULT_MAX_LAYERS, metavar="N",
                        help=f"refuse scenes that need more depth layers (default {DEFAULT_MAX_LAYERS})")
    parser.add_argument("--coarse-blur-px", type=float, metavar="B",
                        help="blur layers whose blur is at least B px wide on a grid twice as coarse (faster; at "
                             "B = 14 within 44 dB of the fine grid on white noise; default: off)")
    parser.add_argument("--device", choices=("cpu", "cuda", "auto"), default="cpu",
                        help="where to blur the layers: cpu (default), cuda (a GPU through CuPy, the gpu extra), "
                             "auto (cuda when present)")
    parser.add_argument("--crop-px", type=int, metavar="M",
                        help="crop M px from every side of the output (default: the margin_px the input's "
                             "provenance records, as render depth writes it; else 0)")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing output")
    add_json_arg(parser)
    parser.set_defaults(func=run)


def recorded_margin_px(provenance: dict | None) -> int:
    """The frame margin an input records (``render depth``: ``inputs.margin_px``), else 0."""
    value = ((provenance or {}).get("inputs") or {}).get("margin_px", 0)
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise VissimInputError(f"the input's provenance records margin_px = {value!r}; expected whole pixels >= 0")
    return value


def read_depth_m(path: Path):
    """A depth map in metres from ``.npy`` or a single-channel (or Z/depth/Y) EXR."""
    import numpy as np  # the numerical code, when the command runs

    from vissim.imageio import read_data_map

    return read_data_map(path).pixels.astype(np.float64)


def _accommodation(args: argparse.Namespace, eye: Prescription, depth) -> tuple[float, dict]:
    from vissim.optics.rx.accommodation import Accommodation, accommodation_for_target

    targeted = args.age is not None or args.accommodation_amplitude_diopters is not None or args.focus_distance_m is not None
    if args.accommodation_diopters is not None:
        if targeted:
            raise VissimInputError("give --accommodation-diopters alone, or a focus target (--focus-distance-m/--age/--accommodation-amplitude-diopters)")
        return args.accommodation_diopters, {"accommodation_diopters": args.accommodation_diopters}
    if not targeted:
        return 0.0, {"accommodation_diopters": 0.0, "note": "relaxed"}
    if args.age is not None and args.accommodation_amplitude_diopters is not None:
        raise VissimInputError("give --age or --accommodation-amplitude-diopters, not both")
    if args.age is not None:
        amplitude = Accommodation.from_age(args.age)
    else:
        amplitude = Accommodation(math.inf if args.accommodation_amplitude_diopters is None else args.accommodation_amplitude_diopters, "given")
    centre = float(depth[depth.shape[0] // 2, depth.shape[1] // 2])  # the default target
    target = centre if args.focus_distance_m is None else args.focus_distance_m
    exerted = accommodation_for_target(eye, target, amplitude.amplitude_diopters)
    return exerted, {
        "accommodation_diopters": exerted,
        "focus_distance_m": target,
        "amplitude_diopters": amplitude.amplitude_diopters,
        "amplitude_source": amplitude.source,
    }


def _schematic_eye(args: argparse.Namespace) -> tuple[DepthViewer, float, dict]:
    """The traced eye's `DepthViewer` (`vissim.optics.eyes.depth_eye.traced_depth_eye`), its accommodation and its
    record."""
    from vissim.optics.eyes.depth_eye import traced_depth_eye  # the trace's imports, when used

    targets = [name for name, value in (("--age", args.age), ("--accommodation-amplitude-diopters", args.accommodation_amplitude_diopters),
                                        ("--focus-distance-m", args.focus_distance_m)) if value is not None]
    if targets:
        raise VissimInputError(f"{' and '.join(targets)} {'does' if len(targets) == 1 else 'do'} not go with "
                               "--eye-model: give the accommodation the schematic eye exerts with --accommodation-diopters")
    accommodation = 0.0 if args.accommodation_diopters is None else args.accommodation_diopters
    field = field_deg_from_text(args.field_deg) if args.field_deg is not None else (0.0, 0.0)
    the_eye = eye_from_args(args, args.rx)
    eye = traced_depth_eye(the_eye, wavelength_nm=args.wavelength_nm, field_deg=field)
    info = {**the_eye.as_json(), "field_deg": list(field),
            "in_focus_proximity_diopters": eye.in_focus_proximity_diopters,
            "eye_wavefront_um": {f"{n},{m}": c for (n, m), c in eye.extra_wavefront.coefficients_um.items()}}
    return eye, accommodation, info


def run(args: argparse.Namespace) -> int:
    from vissim.imageio import image_files, output_bit_depth, read_image, write_image
    from vissim.optics.depth.depth_map import blur_depth
    from vissim.optics.rx.viewing_setup import DepthViewer

    check_outputs_apart((*image_files(args.input), args.depth), image_files(args.output))
    image = read_image(args.input)
    step = image_sampling(image, args.arcmin_per_px, args.input)
    crop = recorded_margin_px(image.provenance) if args.crop_px is None else args.crop_px
    if crop < 0 or 2 * crop >= min(image.pixels.shape[:2]):
        raise VissimInputError(f"cannot crop {crop} px from every side of a {size_text(image.pixels.shape)} image "
                               "(--crop-px)")
    eye_pupil_diameter_mm(args.pupil_mm, "--pupil-mm")
    depth = read_depth_m(args.depth)
    eye = Prescription.parse(args.rx)
    if args.eye_model is None:
        if args.field_deg is not None:
            raise VissimInputError("--field-deg needs --eye-model (the reduced eye has one PSF over the field)")
        accommodation, focus_info = _accommodation(args, eye, depth)
        depth_eye = DepthViewer(eye, args.pupil_mm, accommodation)
    else:
        depth_eye, accommodation, focus_info = _schematic_eye(args)
    with terminal_progress() as progress:
        result = blur_depth(
            image.pixels, depth, eye=depth_eye, arcmin_per_px=step,
            wavelength_nm=args.wavelength_nm, mode=args.mode,
            layer_spacing_fraction=args.layer_spacing_fraction, max_layers=args.max_layers, crop_px=crop,
            coarse_blur_px=args.coarse_blur_px, device=args.device, progress=progress,
        )
    provenance = make_provenance(command="blur-depth", input=str(args.input), depth=str(args.depth),
                                 input_provenance=image.provenance, eye=eye.format(),
                                 pupil_diameter_mm=args.pupil_mm, arcmin_per_px=step,
                                 wavelength_nm=args.wavelength_nm, mode=args.mode, focus=focus_info, crop_px=crop,
                                 coarse_blur_px=args.coarse_blur_px, eye_model=args.eye_model or "reduced",
                                 depth_blur=result.as_json())
    rows, cols = image.pixels.shape[:2]
    alpha = None if image.alpha is None else image.alpha[crop:rows - crop, crop:cols - crop]  # carried, not blurred
    written = write_image(args.output, result.image, provenance=provenance, overwrite=args.overwrite, arcmin_per_px=step,
                          alpha=alpha, bit_depth=output_bit_depth(image, args.output))
    print_result(args, [f"wrote {written} ({result.n_layers} depth layers, {len(result.layers)} non-empty, "
                        f"accommodation {accommodation:.3f} D)"],
                 {"depth_layers": result.n_layers, "non_empty_layers": len(result.layers),
                  "accommodation_diopters": accommodation, "arcmin_per_px": step}, [written], provenance)
    return 0
