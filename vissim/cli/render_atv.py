"""``vissim render atv``: the retinal image of one lit phone pixel seen through the ATV tube.

Registered by `vissim.cli.render` through `add_atv_parser`.  Thin: parse, build an
`AtvConfig`, call `trace_atv` (default)
or `render_atv_camera`, write a float32 EXR (flux per arcmin²,
row 0 up, columns to the eye's right) whose provenance holds the inputs, the metrics and the
paraxial prediction, and print a summary (``--json``: one JSON object).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from vissim.checks import EYE_PUPIL_RANGE_MM, size_text
from vissim.cli._common import (add_json_arg, add_rx_arg, add_trial_lens_args, check_outputs_apart, print_json,
                                refuse_existing, trial_lens_powers)
from vissim.errors import VissimInputError
from vissim.optics.rx.conventions import CORNEA_TO_ENTRANCE_PUPIL_MM, EYE_VERTEX_DISTANCE_MM, SPECTACLE_VERTEX_DISTANCE_MM

__all__ = ["add_atv_parser", "run_atv"]


def add_atv_parser(subparsers) -> argparse.ArgumentParser:
    """Add the ``atv`` sub-command to ``subparsers`` (those of ``vissim render``) and return it."""
    parser = subparsers.add_parser(
        "atv",
        help="the ATV tube: one lit phone pixel through an 8 D lens (thesis 5.4)",
        description=(
            "Render what an eye sees of one lit 326 ppi phone pixel at the focus of an 8 D plano-convex lens "
            "in a 125 mm tube (thesis section 5.4), with an optional trial lens in the eyecup slot.  Writes the "
            "retinal image in visual angle (flux per arcmin^2, linear float32 EXR); the peak irradiance, spot "
            "diameter (FWHM of the radial profile) and total flux follow."
        ),
    )
    parser.add_argument("--scene", metavar="TOML", help="ATV scene file (see scenes/atv_tube.toml); options override it")
    lens = parser.add_argument_group("trial lens in the eyecup slot (default: none)")
    add_trial_lens_args(lens)
    lens.add_argument("--vertex-mm", type=float, metavar="MM",
                      help=f"vertex distance: trial lens back vertex to the eye's pupil (default "
                           f"{EYE_VERTEX_DISTANCE_MM:g}: a {SPECTACLE_VERTEX_DISTANCE_MM:g} mm spectacle vertex "
                           f"distance + {CORNEA_TO_ENTRANCE_PUPIL_MM:g} mm cornea to pupil)")
    eye = parser.add_argument_group("eye")
    eye.add_argument("--pupil-mm", type=float, metavar="MM",
                     help=f"pupil diameter, {EYE_PUPIL_RANGE_MM[0]:g}-{EYE_PUPIL_RANGE_MM[1]:g} mm (default 4)")
    add_rx_arg(eye, default_text=" (default: emmetropic)")
    eye.add_argument("--accommodation-diopters", type=float, metavar="A",
                     help="accommodation in dioptres, >= 0 (default 0: focused at infinity)")
    light = parser.add_argument_group("pixel intensity (default: linear radiance 1)")
    given = light.add_mutually_exclusive_group()
    given.add_argument("--pixel-intensity", type=float, metavar="L", help="linear radiance of the lit pixel (default 1)")
    given.add_argument("--display-code", type=float, metavar="C",
                       help="display code value in [0, 1] (the thesis's 'iPhone intensity'), decoded by --transfer (default none: --pixel-intensity)")
    light.add_argument("--transfer", choices=("srgb", "gamma2.2"), default="gamma2.2",
                       help="display transfer function for --display-code (default gamma2.2, as atv simulate)")
    light.add_argument("--white-radiance", type=float, default=1.0, metavar="L",
                       help="linear radiance of display code 1 (default 1)")
    method = parser.add_argument_group("method")
    method.add_argument("--method", choices=("trace", "camera"), default="trace",
                        help="trace: light tracing from the pixel (default); camera: thin-lens path tracing (noisy)")
    budget = method.add_mutually_exclusive_group()
    budget.add_argument("--rays", type=int, metavar="N", help="rays for --method trace (default 4194304)")
    budget.add_argument("--spp", type=int, metavar="N", help="samples per pixel for --method camera (default 1024)")
    method.add_argument("--seed", type=int, default=0, metavar="S", help="seed (default 0)")
    method.add_argument("--arcmin-per-px", type=float, metavar="S",
                        help="angular pixel size (default 0.5 for trace, 1 for camera)")
    method.add_argument("--size", type=int, metavar="N", help="image size, N x N pixels (default: holds the spot)")
    method.add_argument("--fresnel-loss", action="store_true",
                        help="uncoated lenses: Fresnel transmittance per surface")
    method.add_argument("--variant", metavar="V", help="Mitsuba variant (default: chosen by vissim)")
    parser.add_argument("-o", "--output", required=True, metavar="PATH", help="output .exr (linear float32)")
    add_json_arg(parser)
    parser.add_argument("--overwrite", action="store_true", help="replace an existing output")
    parser.set_defaults(func=run_atv)
    return parser


def _config(args: argparse.Namespace):
    """The scene file's configuration (or the defaults) with the given options applied."""
    from dataclasses import replace

    from vissim.bench.atv.tube import AtvConfig, atv_trial_lens, display_code_to_linear
    from vissim.bench.atv.scene_files import load_atv_toml
    from vissim.optics.rx.prescription import Prescription

    config = load_atv_toml(args.scene) if args.scene else AtvConfig()
    if args.display_code is not None:
        config = replace(config, tube=replace(config.tube, pixel_radiance=args.white_radiance
                                              * display_code_to_linear(args.display_code, args.transfer)))
    elif args.pixel_intensity is not None:
        config = replace(config, tube=replace(config.tube, pixel_radiance=args.pixel_intensity))
    powers = trial_lens_powers(args)
    if powers is not None:
        config = replace(config, trial_lens=atv_trial_lens(*powers))
    eye = config.eye
    if args.pupil_mm is not None:
        eye = replace(eye, pupil_diameter_mm=args.pupil_mm)
    if args.rx is not None:
        eye = replace(eye, refractive_error=Prescription.parse(args.rx))
    if args.accommodation_diopters is not None:
        eye = replace(eye, accommodation_diopters=args.accommodation_diopters)
    config = replace(config, eye=eye)
    if args.vertex_mm is not None:
        config = replace(config, trial_lens_distance_mm=args.vertex_mm)
    if args.fresnel_loss:
        config = replace(config, fresnel_loss=True)
    return config


def run_atv(args: argparse.Namespace) -> int:
    """Render, write the EXR and print the summary; returns the exit code."""
    from vissim.atv.predict import predicted_spot
    from vissim.imageio import write_image
    from vissim.provenance import make_provenance
    from vissim.render.atv_trace import DEFAULT_N_RAYS, render_atv_camera, trace_atv

    output = Path(args.output)
    check_outputs_apart([args.scene], [output])
    if output.suffix.lower() != ".exr":
        raise VissimInputError(f"render atv writes a linear float EXR; give an output ending in .exr, got {output}")
    refuse_existing(output, overwrite=args.overwrite)
    if args.method == "trace" and args.spp is not None:
        raise VissimInputError("--spp goes with --method camera; the light tracer takes --rays")
    if args.method == "camera" and args.rays is not None:
        raise VissimInputError("--rays goes with --method trace; the camera takes --spp (samples per pixel)")
    config = _config(args)
    step = args.arcmin_per_px if args.arcmin_per_px is not None else (0.5 if args.method == "trace" else 1.0)
    if args.method == "trace":
        result = trace_atv(config, n_rays=DEFAULT_N_RAYS if args.rays is None else args.rays, seed=args.seed,
                           arcmin_per_px=step, size_px=args.size, variant=args.variant)
    else:
        result = render_atv_camera(config, spp=1024 if args.spp is None else args.spp, seed=args.seed,
                                   arcmin_per_px=step, size_px=args.size, variant=args.variant)
    theory = predicted_spot(config, arcmin_per_px=step, size_px=result.image.shape[0])
    prediction = {
        "defocus_diopters": theory.defocus_diopters,
        "blur_diameter_arcmin": theory.blur_diameter_arcmin,
        "pixel_angle_arcmin": theory.pixel_angle_arcmin,
        "total_flux": theory.total_flux,
        "peak_irradiance_per_arcmin2": theory.peak,
        "spot_diameter_arcmin": theory.spot_diameter_arcmin,
    }
    summary = result.summary()
    provenance = make_provenance(
        command="render atv", config=config, summary=summary, prediction_geometric=prediction,
        units="flux per arcmin^2 = pixel radiance x m^2 x sr / arcmin^2",
        orientation="row 0 up, columns to the eye's right, straight ahead at [N//2, N//2]",
    )
    write_image(output, result.image, provenance=provenance, overwrite=args.overwrite, arcmin_per_px=result.arcmin_per_px)
    if args.json:
        print_json({**summary, "output": str(output), "prediction_geometric": prediction}, [output], provenance)
    else:
        print(f"wrote {output}: {size_text(result.image.shape)} at {result.arcmin_per_px:g} "
              f"arcmin/px, {result.method} ({result.n_rays} {'rays' if result.method == 'trace' else 'camera paths'}, "
              f"{result.variant}, {result.seconds:.1f} s)")
        print(f"peak {result.peak:.5g} per arcmin^2 (±{100 * result.peak_relative_std:.2g} %), spot diameter "
              f"{result.spot_diameter_arcmin:.3f}' (FWHM), total flux {result.total_flux:.5g}; theory: "
              f"blur {theory.blur_diameter_arcmin:.3f}', pixel {theory.pixel_angle_arcmin:.3f}', "
              f"flux {theory.total_flux:.5g}")
    return 0
