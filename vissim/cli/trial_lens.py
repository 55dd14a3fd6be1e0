"""``vissim trial-lens``: the power and magnification a trial lens adds in front of a camera."""

from __future__ import annotations

import argparse
import dataclasses
import logging
import math
from typing import TYPE_CHECKING

from vissim import __version__
from vissim.errors import VissimInputError
from vissim.optics.rx.conventions import CROWN_GLASS_INDEX, EYE_VERTEX_DISTANCE_MM
from vissim.thesis import THESIS_VERTEX_DISTANCE_MM
from vissim.cli import command_help
from vissim.cli._output import add_json_arg, print_json

if TYPE_CHECKING:
    from vissim.optics.rx.trial_lens import TrialLens

log = logging.getLogger(__name__)

_INFINITY_WORDS = ("inf", "infinity", "+inf", "∞")


def add_parser(subparsers) -> argparse.ArgumentParser:
    parser = subparsers.add_parser(
        "trial-lens",
        help=command_help("trial-lens"),
        description=(
            "Trace a trial lens in front of a camera (or an eye) by astigmatic ray transfer: the "
            "power it adds at the camera principal plane, the camera's resulting prescription and "
            "the spectacle magnification per principal meridian.  The thesis's Table 4.2 value "
            "P/(1-dP), right only for an object at infinity, is shown for comparison.  Every power is "
            "printed in minus-cylinder form (a plus-cylinder lens is transposed)."
        ),
    )
    parser.add_argument("--sphere", type=float, required=True, metavar="D",
                        help="marked sphere in dioptres (plus lens > 0); back vertex power if thick")
    parser.add_argument("--cylinder", type=float, default=0.0, metavar="D",
                        help="marked cylinder in dioptres (needs --axis)")
    parser.add_argument("--axis", type=float, default=None, metavar="DEG",
                        help="cylinder axis, TABO degrees 0-180 (required with a --cylinder; no default)")
    parser.add_argument("--vertex-mm", type=float, default=THESIS_VERTEX_DISTANCE_MM, metavar="MM",
                        help=f"vertex distance: back surface of the lens to the camera principal plane (default "
                             f"{THESIS_VERTEX_DISTANCE_MM:g}, the thesis's DSLR bench; an eye's is "
                             f"{EYE_VERTEX_DISTANCE_MM:g}, to its pupil)")
    parser.add_argument("--object-distance-m", default="inf", metavar="M|inf",
                        help="camera principal plane to the object, metres, or 'inf' (default)")
    parser.add_argument("--index", type=float, default=None, metavar="N",
                        help=f"refractive index of a thick lens (default {CROWN_GLASS_INDEX} when "
                             "--thickness-mm is given)")
    parser.add_argument("--thickness-mm", type=float, default=0.0, metavar="MM",
                        help="centre thickness; 0 (default) = thin lens")
    parser.add_argument("--back-surface-diopters", type=float, default=0.0, metavar="D",
                        help="power of the back (camera-side) surface of a thick lens; 0 (default) = plano")
    add_json_arg(parser)
    parser.set_defaults(func=run)
    return parser


def _object_distance_m(text: str) -> float:
    if text.strip().lower() in _INFINITY_WORDS:
        return math.inf
    try:
        return float(text)
    except ValueError:
        raise VissimInputError(
            f"--object-distance-m must be a distance in metres or 'inf', got {text!r}"
        ) from None


def _lens_from_args(args: argparse.Namespace) -> TrialLens:
    from vissim.optics.rx.trial_lens import TrialLens

    if args.cylinder != 0.0 and args.axis is None:
        raise VissimInputError(f"--cylinder {args.cylinder:g} D needs --axis in degrees (TABO, 0-180)")
    index = args.index
    if args.thickness_mm > 0.0 and index is None:
        index = CROWN_GLASS_INDEX
        log.info("no --index given: using crown glass, n = %g", index)
    return TrialLens(sphere_diopters=args.sphere, cylinder_diopters=args.cylinder,
                     axis_deg=180.0 if args.axis is None else args.axis, refractive_index=index,
                     center_thickness_mm=args.thickness_mm, back_surface_diopters=args.back_surface_diopters)


def run(args: argparse.Namespace) -> int:
    from vissim.optics.rx.trial_lens import TrialLensSetup, thesis_table_4_2_power, trial_lens_effect

    lens = _lens_from_args(args)
    setup = TrialLensSetup(lenses=(lens,), vertex_distance_mm=args.vertex_mm,
                           object_distance_m=_object_distance_m(args.object_distance_m))
    effect = trial_lens_effect(setup)
    marked = lens.marked_power.minus_cylinder()  # the meridians in the order the added power lists them
    lens_meridians = (marked.axis_deg, (marked.axis_deg + 90.0) % 180.0 or 180.0)
    thesis = [
        {"meridian_deg": m,
         "power_diopters": thesis_table_4_2_power(marked.meridian_power(m), args.vertex_mm)}
        for m in lens_meridians
    ]
    result = effect.to_json_dict()
    if args.json:
        result.update(
            lens={**dataclasses.asdict(lens), "marked_power": str(marked), "sphere_diopters": marked.sphere_diopters,
                  "cylinder_diopters": marked.cylinder_diopters, "axis_deg": marked.axis_deg},
            cylinder_form="minus",
            thesis_table_4_2=thesis,
            vissim_version=__version__,
        )
        print_json(result)
        return 0

    kind = "thin" if lens.is_thin else f"{lens.center_thickness_mm:g} mm thick, n = {lens.refractive_index:g}"
    where = "infinity" if result["object_distance_m"] is None else f"{setup.object_distance_m:g} m"
    print(f"trial lens {marked} ({kind}) at {setup.vertex_distance_mm:g} mm, object at {where}; "
          "powers in minus-cylinder form")
    print(f"added power at the camera:   {effect.added_power.minus_cylinder().format(4)}")
    print("  per meridian:              " + ",  ".join(
        f"{row['meridian_deg']:g}: {row['power_diopters']:+.4f} D"
        for row in result["added_power_meridians"]))
    print(f"camera prescription:         {effect.camera_prescription.minus_cylinder().format(4)}")
    print(f"magnification:               {effect.magnification:.4f}  (" + ",  ".join(
        f"{meridian:g}: {mag:.4f}" for mag, meridian in effect.magnification_principal) + ")")
    print("thesis Table 4.2, P/(1-dP):  " + ",  ".join(
        f"{row['meridian_deg']:g}: {row['power_diopters']:+.4f} D" for row in thesis)
        + "  (object at infinity only)")
    return 0
