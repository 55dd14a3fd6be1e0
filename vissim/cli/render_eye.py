"""``vissim render eye``: a letter chart at a distance seen through a schematic eye's traced optics.

Registered by `vissim.cli.render` through `add_eye_parser`.  Thin: read the options into a
`vissim.render.eye_render.EyeRender`, render, write the EXR with provenance, print a summary.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from vissim.checks import size_text
from vissim.cli._common import (RX_HELP, add_trial_lens_args, field_deg_from_text, refuse_existing, size_from_text,
                                trial_lens_powers)
from vissim.errors import VissimInputError

__all__ = ["add_eye_parser", "run_eye"]


def add_eye_parser(subparsers) -> argparse.ArgumentParser:
    """Add the ``eye`` sub-command to ``subparsers`` (those of ``vissim render``) and return it."""
    from vissim.optics.eyes.models import EYE_MODELS

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
    parser.add_argument("--eye-model", choices=tuple(EYE_MODELS), default="navarro-1985", metavar="MODEL",
                        help="the schematic eye: " + ", ".join(EYE_MODELS) + " (default navarro-1985)")
    parser.add_argument("--accommodation-diopters", type=float, default=0.0, metavar="A",
                        help="the eye's accommodation, dioptres, within the model's range (default 0)")
    pupil = parser.add_mutually_exclusive_group()
    pupil.add_argument("--pupil-mm", type=float, metavar="D", help="entrance-pupil diameter, mm (default 3)")
    pupil.add_argument("--iris-mm", type=float, metavar="D", help="or the iris diameter, mm")
    parser.add_argument("--field-deg", metavar="X,Y", default="0,0",
                        help="where the chart lies in the visual field: the eye turns so that the chart's centre "
                             "is at this field angle from its optical axis, degrees, x (examiner's right: the "
                             "observer's left) and y (up), as vissim eye and psf count it; the image stays "
                             "centred on the chart (default 0,0)")
    colour = parser.add_mutually_exclusive_group()
    colour.add_argument("--wavelength-nm", type=float, metavar="NM",
                        help="monochromatic light of this wavelength (default: the model's reference wavelength)")
    colour.add_argument("--spectrum", choices=("photopic",),
                        help="photopic: white light over the visible spectrum, each ray at its own wavelength, the "
                             "image weighted by the eye's photopic sensitivity V(λ)")
    parser.add_argument("--distance-m", type=float, default=6.0, metavar="M", help="chart distance (default 6 m)")
    parser.add_argument("--letter", default="K", metavar="X", help="one Sloan letter (default K)")
    parser.add_argument("--logmar", type=float, default=0.5, metavar="L", help="letter size in LogMAR (default 0.5)")
    parser.add_argument("--rx", metavar="PRESCRIPTION",
                        help=f"{RX_HELP}: render the eye that has it (axial length for its sphere, a toric cornea for "
                             "its cylinder), written at the spectacle plane --vertex-mm in front of the cornea, as "
                             "vissim eye --rx does")
    add_trial_lens_args(parser.add_argument_group("trial lens in front of the eye"))
    parser.add_argument("--vertex-mm", type=float, default=12.0, metavar="MM",
                        help="the spectacle plane, mm in front of the cornea: where --rx is written and the trial "
                             "lens's back vertex sits (default 12)")
    parser.add_argument("--size", metavar="ROWSxCOLS", default="64x64", help="image size (default 64x64)")
    parser.add_argument("--arcmin-per-px", type=float, default=1.0, metavar="ARCMIN",
                        help="angular pixel size (default 1)")
    parser.add_argument("--spp", type=int, default=64, metavar="N", help="samples per pixel (default 64)")
    parser.add_argument("--seed", type=int, default=0, metavar="S", help="sampler seed (default 0): the same seed "
                        "gives the same image")
    parser.add_argument("--variant", metavar="V", help="Mitsuba variant (default: chosen by vissim)")
    parser.add_argument("-o", "--output", required=True, type=Path, metavar="PATH", help="output .exr (linear)")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing output")
    parser.set_defaults(func=run_eye)
    return parser


def run_eye(args: argparse.Namespace) -> int:
    from vissim.imageio import write_image
    from vissim.render.eye_render import EyeRender, render_eye

    if args.output.suffix.lower() != ".exr":
        raise VissimInputError(f"render eye writes linear float EXR; give an output ending in .exr, got {args.output}")
    if args.spp < 1:
        raise VissimInputError(f"--spp must be a positive number of samples per pixel, got {args.spp}")
    refuse_existing(args.output, overwrite=args.overwrite)
    pupil = 3.0 if args.pupil_mm is None and args.iris_mm is None else args.pupil_mm
    settings = EyeRender(model=args.eye_model, accommodation_diopters=args.accommodation_diopters, pupil_mm=pupil,
                         iris_mm=args.iris_mm, field_deg=field_deg_from_text(args.field_deg),
                         wavelength_nm=args.wavelength_nm, spectrum=args.spectrum or "mono",
                         size_px=size_from_text(args.size, "64x64"), arcmin_per_px=args.arcmin_per_px, spp=args.spp, seed=args.seed,
                         chart_distance_m=args.distance_m, letter=args.letter, logmar=args.logmar,
                         lens=trial_lens_powers(args), vertex_mm=args.vertex_mm, rx=args.rx)
    result = render_eye(settings, args.variant)
    write_image(args.output, result.pixels, provenance=result.provenance, overwrite=args.overwrite,
                arcmin_per_px=args.arcmin_per_px)
    print(f"wrote {args.output}: {size_text(result.pixels.shape)}, {result.spp} spp, {result.variant}, "
          f"{result.seconds:.1f} s; {args.eye_model}")
    return 0
