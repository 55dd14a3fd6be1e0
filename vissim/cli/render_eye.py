"""``vissim render eye``: a letter chart at a distance seen through a schematic eye's traced optics.

Registered by `vissim.cli.render` through `add_eye_parser`.  Thin: read the scene file (``--scene``,
`vissim.render.eye_scene_files`) and the options over it into a `vissim.render.eye_render.EyeRender`
(options, then the file, then its defaults), render, write the EXR with provenance (the scene file's
path among its inputs), print a summary.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from vissim.atomic import check_outputs_apart
from vissim.checks import size_text
from vissim.cli._common import (EYE_ACCOMMODATION_HELP, FIELD_DEG_HELP, RX_HELP, add_eye_model_arg, add_json_arg,
                                print_result, add_trial_lens_args, field_deg_from_text,
                                refuse_existing, size_from_text, trial_lens_powers)
from vissim.errors import VissimInputError
from vissim.optics.eyes.defaults import DEFAULT_EYE_LIGHT_NM
from vissim.render.eye_render import EyeRender

_DEFAULT = {field.name: field.default for field in dataclasses.fields(EyeRender)}  # the one set of defaults

__all__ = ["add_eye_parser", "run_eye"]


def add_eye_parser(subparsers) -> argparse.ArgumentParser:
    """Add the ``eye`` sub-command to ``subparsers`` (those of ``vissim render``) and return it."""
    
    parser = subparsers.add_parser(
        "eye",
        help="a letter chart seen through a schematic eye, ray traced to its retina",
        description=(
            "Render a Sloan letter at a distance as a schematic eye sees it: each pixel is a direction in the "
            "visual field (columns to the observer's right, rows down), each sample a ray from the retina traced "
            "out through the eye's lens, iris and cornea (aspheric surfaces, the gradient-index lens where the "
            "model has one, each medium's dispersion).  A pixel's value is the mean radiance of the light that "
            "reaches that retinal point through the pupil (a uniform white scene gives 1 everywhere)."
        ),
    )
    parser.add_argument("--scene", metavar="TOML",
                        help="eye scene file (see scenes/eye.toml); the options below override its values")
    add_eye_model_arg(parser, f"the schematic eye, default {_DEFAULT['model']}")
    parser.add_argument("--accommodation-diopters", type=float, metavar="A",
                        help=f"the eye's accommodation, {EYE_ACCOMMODATION_HELP} "
                             f"(default {_DEFAULT['accommodation_diopters']:g})")
    pupil = parser.add_mutually_exclusive_group()
    pupil.add_argument("--pupil-mm", type=float, metavar="MM",
                       help=f"entrance-pupil diameter, mm (default {_DEFAULT['pupil_mm']:g})")
    pupil.add_argument("--iris-mm", type=float, metavar="MM", help="or the iris diameter, mm")
    parser.add_argument("--field-deg", metavar="X,Y",
                        help=f"where the chart lies: the eye turns so that the chart's centre is at this {FIELD_DEG_HELP}; "
                             "the image stays centred on the chart (default {:g},{:g})".format(*_DEFAULT["field_deg"]))
    colour = parser.add_mutually_exclusive_group()
    colour.add_argument("--wavelength-nm", type=float, metavar="NM",
                        help=f"monochromatic light of this wavelength (default {DEFAULT_EYE_LIGHT_NM:g})")
    colour.add_argument("--spectrum", choices=("photopic",),
                        help="photopic: white light over the visible spectrum, each ray at its own wavelength, the "
                             "image weighted by the eye's photopic sensitivity V(λ) (default none: one wavelength, --wavelength-nm)")
    parser.add_argument("--chart-distance-m", type=float, metavar="M",
                        help=f"chart distance (default {_DEFAULT['chart_distance_m']:g} m)")
    parser.add_argument("--letter", metavar="X", help=f"one Sloan letter (default {_DEFAULT['letter']})")
    parser.add_argument("--logmar", type=float, metavar="L",
                        help=f"letter size in LogMAR (default {_DEFAULT['logmar']:g})")
    parser.add_argument("--rx", metavar="PRESCRIPTION",
                        help=f"{RX_HELP}: render the eye that has it (axial length for its sphere, a toric cornea for "
                             "its cylinder), written at the spectacle plane --vertex-mm in front of the cornea, as "
                             "vissim eye --rx does (default: the scene file's, or none: the emmetropic model)")
    add_trial_lens_args(parser.add_argument_group("trial lens in front of the eye (replaces the scene file's)"),
                        none_given="the scene file's, or none")
    parser.add_argument("--vertex-mm", type=float, metavar="MM",
                        help="the spectacle plane, mm in front of the cornea: where --rx is written and the trial "
                             f"lens's back vertex sits (default {_DEFAULT['vertex_mm']:g})")
    parser.add_argument("--size", metavar="N|ROWSxCOLS",
                        help="image size in pixels: N (a square) or ROWSxCOLS (default {}x{})".format(*_DEFAULT["size_px"]))
    parser.add_argument("--arcmin-per-px", type=float, metavar="ARCMIN",
                        help=f"angular pixel size (default {_DEFAULT['arcmin_per_px']:g})")
    parser.add_argument("--spp", type=int, metavar="N", help=f"samples per pixel (default {_DEFAULT['spp']})")
    parser.add_argument("--seed", type=int, metavar="S", help=f"sampler seed (default {_DEFAULT['seed']}): the same "
                        "seed gives the same image")
    parser.add_argument("--variant", metavar="V", help="Mitsuba variant (default: chosen by vissim)")
    parser.add_argument("-o", "--output", required=True, type=Path, metavar="PATH", help="output .exr (linear)")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing output")
    add_json_arg(parser)
    parser.set_defaults(func=run_eye)
    return parser


def _settings(args: argparse.Namespace):
    """The scene file's values (or none), the given options over them, `EyeRender`'s defaults under both."""
    from vissim.render.eye_scene_files import eye_render_from_values, eye_scene_values

    values = {} if args.scene is None else eye_scene_values(args.scene)
    options = {"model": args.eye_model, "accommodation_diopters": args.accommodation_diopters,
               "chart_distance_m": args.chart_distance_m, "letter": args.letter, "logmar": args.logmar, "rx": args.rx,
               "vertex_mm": args.vertex_mm, "arcmin_per_px": args.arcmin_per_px, "spp": args.spp, "seed": args.seed,
               "field_deg": None if args.field_deg is None else field_deg_from_text(args.field_deg),
               "size_px": None if args.size is None else size_from_text(args.size, "64x64"),
               "lens": trial_lens_powers(args)}
    values.update({key: value for key, value in options.items() if value is not None})
    if args.pupil_mm is not None or args.iris_mm is not None:
        values.update(pupil_mm=args.pupil_mm, iris_mm=args.iris_mm)
    if args.wavelength_nm is not None:
        values.update(wavelength_nm=args.wavelength_nm, spectrum="mono")
    if args.spectrum is not None:
        values.update(wavelength_nm=None, spectrum=args.spectrum)
    return eye_render_from_values(values, "command line" if args.scene is None else f"{args.scene} with the options")


def run_eye(args: argparse.Namespace) -> int:
    from vissim.imageio import write_image
    from vissim.render.eye_render import render_eye

    check_outputs_apart([args.scene], [args.output])
    if args.output.suffix.lower() != ".exr":
        raise VissimInputError(f"render eye writes linear float EXR; give an output ending in .exr, got {args.output}")
    refuse_existing(args.output, overwrite=args.overwrite)
    settings = _settings(args)
    result = render_eye(settings, args.variant)
    provenance = dict(result.provenance)
    if args.scene is not None:
        provenance["inputs"] = dict(provenance["inputs"], scene_file=str(args.scene))
    write_image(args.output, result.pixels, provenance=provenance, overwrite=args.overwrite,
                arcmin_per_px=settings.arcmin_per_px)
    print_result(args, [f"wrote {args.output}: {size_text(result.pixels.shape)}, {result.spp} spp, {result.variant}, "
                        f"{result.seconds:.1f} s; {settings.model}"],
                 {"size_px": list(result.pixels.shape[:2]), "spp": result.spp, "variant": result.variant,
                  "seconds": result.seconds, "eye_model": settings.model}, [args.output], provenance)
    return 0
