"""Argument groups and checks shared by several sub-commands (aberration, pupil, wavelengths, sampling, outputs)."""

from __future__ import annotations

import argparse
import logging
import math
from pathlib import Path
from typing import TYPE_CHECKING

from vissim.atomic import check_outputs_apart, refuse_existing  # noqa: F401  (the commands' one door)
from vissim.cli._output import JSON_HELP, add_json_arg, print_json, print_result  # noqa: F401  (likewise)
from vissim.checks import (ARIZONA_ACCOMMODATION_RANGE_DIOPTERS, AXIS_RANGE_DEG, ENTRANCE_PUPIL_RANGE_MM,
                           NAVARRO_ACCOMMODATION_RANGE_DIOPTERS, eye_field_deg, number_within, trial_lens_diopters)
from vissim.errors import VissimInputError
from vissim.optics.eyes.models import LE_GRAND_ACCOMMODATED_DIOPTERS
from vissim.optics.eyes.defaults import DEFAULT_SPECTACLE_VERTEX_MM
from vissim.optics.rx.prescription import Prescription

if TYPE_CHECKING:  # imageio loads OpenEXR; the image only lends its recorded sampling here
    from vissim.imageio import Image
    from vissim.optics.pupil.wavefront import Wavefront

log = logging.getLogger(__name__)


#: What ``--rx`` is, in every command that takes it (docs/conventions.md, "Prescriptions").
RX_HELP = "the eye's prescription: its correcting lens, not worn (myope < 0)"
#: What ``--accommodation-diopters`` takes, model by model (`vissim.optics.eyes.models`).
EYE_ACCOMMODATION_HELP = (f"dioptres: 0-{NAVARRO_ACCOMMODATION_RANGE_DIOPTERS[1]:g} navarro-1985 and "
                          f"escudero-sanz-1999, 0-{ARIZONA_ACCOMMODATION_RANGE_DIOPTERS[1]:g} arizona, 0 or "
                          f"{LE_GRAND_ACCOMMODATED_DIOPTERS:g} le-grand (relaxed, or its accommodated eye), "
                          "0 liou-brennan-1997")


def add_rx_arg(parser, *, required: bool = False, default_text: str = "") -> None:
    """``--rx PRESCRIPTION``: the eye's own prescription (the lens that would correct it; not worn)."""
    parser.add_argument("--rx", required=required, metavar="PRESCRIPTION",
                        help=f"{RX_HELP}, e.g. '-2.00 -0.50 x 180'{default_text}")


def add_trial_lens_args(group, *, none_given: str = "no trial lens") -> None:
    """``--sphere`` / ``--cylinder`` / ``--axis``: one trial lens (read with `trial_lens_powers`); ``none_given``
    says what there is when none of them is given (a scene's own lenses)."""
    group.add_argument("--sphere", type=float, metavar="D",
                       help=f"trial lens sphere in dioptres (plus lens > 0; default 0 with --cylinder, else {none_given})")
    group.add_argument("--cylinder", type=float, metavar="D", help="trial lens cylinder in dioptres (needs --axis)")
    group.add_argument("--axis", type=float, metavar="DEG",
                       help="trial lens cylinder axis, TABO degrees 0-180 (required with a --cylinder; no default)")


def trial_lens_powers(args: argparse.Namespace) -> tuple[float, float, float] | None:
    """(sphere D, cylinder D, axis deg) of the trial lens the options describe, or None when none is given."""
    if args.sphere is None and args.cylinder is None:
        if args.axis is not None:
            raise VissimInputError("--axis needs --cylinder (dioptres)")
        return None
    sphere = trial_lens_diopters(args.sphere or 0.0, "--sphere")
    cylinder = trial_lens_diopters(args.cylinder or 0.0, "--cylinder")
    if cylinder != 0.0 and args.axis is None:
        raise VissimInputError(f"--cylinder {cylinder:g} D needs --axis in degrees (TABO, 0-180)")
    axis = 180.0 if args.axis is None else number_within(args.axis, "--axis", "degrees", AXIS_RANGE_DEG, " (TABO)")
    return sphere, cylinder, axis


def add_aberration_args(parser: argparse.ArgumentParser, *, required: bool = True) -> None:
    group = parser.add_argument_group("aberration (at least one of --rx / --zernike)")
    group.add_argument("--rx", metavar="PRESCRIPTION",
                       help=RX_HELP + ", e.g. '-2.00 -1.25 x 180', '+1.50 DS', 'plano' (TABO axis; default none)")
    group.add_argument("--zernike", metavar="TERMS",
                       help="OSA Zernike terms in µm, 'n,m=µm;n,m=µm' (e.g. '2,0=0.5;4,0=0.1'); adds to --rx "
                            "(default none)")
    group.add_argument("--zernike-pupil-mm", type=float, metavar="MM",
                       help="pupil diameter the --zernike coefficients were measured over (default: --pupil-mm)")
    group.add_argument("--pupil-mm", type=float, required=required, metavar="MM",
                       help="entrance pupil diameter in mm, an eye's or a camera's "
                            f"({ENTRANCE_PUPIL_RANGE_MM[0]:g}-{ENTRANCE_PUPIL_RANGE_MM[1]:g})")
    parser.set_defaults(_aberration_required=required)


def check_zernike_pupil(args: argparse.Namespace) -> None:
    """``--zernike-pupil-mm`` belongs to ``--zernike``: alone it would be ignored, so it is refused."""
    if getattr(args, "zernike_pupil_mm", None) is not None and args.zernike is None:
        raise VissimInputError(f"--zernike-pupil-mm {args.zernike_pupil_mm:g} mm is the pupil the --zernike "
                               "coefficients were measured over, and no --zernike is given: add it, or drop "
                               "--zernike-pupil-mm")


def wavefront_from_args(args: argparse.Namespace) -> Wavefront:
    """The wavefront the user described, over the measurement pupil."""
    from vissim.optics.pupil.wavefront import Wavefront, parse_zernike_terms

    if args.rx is None and args.zernike is None:
        raise VissimInputError("give the aberration with --rx '<prescription>' and/or --zernike 'n,m=µm;...'")
    pupil = args.pupil_mm
    if pupil is None or not math.isfinite(pupil) or pupil <= 0:
        raise VissimInputError(f"--pupil-mm must be a positive diameter in mm, got {pupil!r}")
    measured = args.zernike_pupil_mm if args.zernike_pupil_mm is not None else pupil
    front = Wavefront.zero(max(pupil, measured))
    if args.zernike is not None:
        front = Wavefront(parse_zernike_terms(args.zernike), measured)
    if args.rx is not None:
        front = front + Wavefront.from_prescription(Prescription.parse(args.rx), front.pupil_diameter_mm)
    return front


#: What ``--field-deg`` means, in every command that takes it.
FIELD_DEG_HELP = ("field angle, degrees, x (examiner's right: the observer's left; nasal for the right eyes the "
                  "models are) and y (up), from the eye's visual axis for a model that has one (liou-brennan-1997: "
                  "0,0 is where it fixates, 5 deg nasal of its optical axis), else from its optical axis")


def add_eye_model_arg(parser, help_text: str, **extra) -> None:
    """``--eye-model MODEL``: one of `EYE_MODELS`, or a measured eye (``jaeken-artal-2012:17:right``,
    ``polans-2015:3``); refused by the parser otherwise."""
    from vissim.optics.eyes.defaults import MEASURED_EYE_SPELLING
    from vissim.optics.eyes.models import EYE_MODELS

    parser.add_argument("--eye-model", type=_eye_name, metavar="EYE",
                        help=f"{help_text} (one of {', '.join(EYE_MODELS)}; or a measured eye, "
                             f"{MEASURED_EYE_SPELLING})", **extra)


def _eye_name(text: str) -> str:
    """A schematic model's name or a measured eye's, checked (argparse reports the refusal on one line)."""
    from vissim.optics.eyes.measured.measured_eye import MEASURED_EYE_SPELLING, is_measured_name, parse_measured_eye
    from vissim.optics.eyes.models import EYE_MODELS

    if is_measured_name(text):
        try:
            parse_measured_eye(text)
        except VissimInputError as error:
            raise argparse.ArgumentTypeError(str(error)) from None
        return text
    if text not in EYE_MODELS:
        raise argparse.ArgumentTypeError(f"invalid choice: {text!r} (choose from {', '.join(EYE_MODELS)}, or a "
                                         f"measured eye: {MEASURED_EYE_SPELLING})")
    return text


#: What ``--rx`` means with ``--eye-model``, in every command that takes both.
EYE_RX_HELP = ("with --eye-model, --rx is the prescription the eye has (the model eye made ametropic: its axial "
               f"length and a toric cornea, measured at the spectacle plane {DEFAULT_SPECTACLE_VERTEX_MM:g} mm in front "
               "of the cornea)")


def eye_from_args(args, rx_text: str | None):
    """The `Eye` ``--eye-model``, ``--accommodation-diopters``, ``--pupil-mm`` and ``rx_text`` describe: the one
    place the command line's words become an eye (`build_eye`)."""
    from vissim.optics.eyes.eye import build_eye  # the trace's imports, when used

    rx = None if rx_text is None else Prescription.parse(rx_text)  # plano: the eye solved to be exactly plano
    accommodation = 0.0 if args.accommodation_diopters is None else args.accommodation_diopters
    return build_eye(args.eye_model, accommodation_diopters=accommodation, pupil_diameter_mm=args.pupil_mm, rx=rx)


def field_deg_from_text(text: str) -> tuple[float, float]:
    """``--field-deg X,Y``: a field angle's (x, y) in degrees; an eye's within `checks.MAX_FIELD_DEG`."""
    values = parse_float_list(text, "--field-deg", "degrees", positive=False)
    if len(values) != 2:
        raise VissimInputError(f"--field-deg must be two angles X,Y in degrees, got {text!r}")
    return eye_field_deg(values, "--field-deg")


def size_from_text(text: str, example: str = "133x113") -> tuple[int, int]:
    """``--size N`` (a square, as every command's ``--size N``) or ``--size ROWSxCOLS``: an image size (rows,
    columns) in pixels, each at least 1."""
    try:
        parts = [int(v) for v in text.lower().replace("×", "x").split("x")]
        rows, cols = parts * 2 if len(parts) == 1 else parts
    except ValueError:
        raise VissimInputError(f"--size must be N (a square) or ROWSxCOLS in pixels, e.g. {example}, "
                               f"got {text!r}") from None
    if rows < 1 or cols < 1:
        raise VissimInputError(f"--size must be at least 1x1 px, got {text!r}")
    return rows, cols


def parse_float_list(text: str, name: str, unit: str, *, positive: bool = True) -> list[float]:
    """Comma-separated finite numbers, positive unless ``positive=False`` (wavelengths; lens powers)."""
    try:
        values = [float(part) for part in text.split(",") if part.strip()]
    except ValueError:
        raise VissimInputError(f"{name} must be comma-separated numbers in {unit}, got {text!r}") from None
    if not values:
        raise VissimInputError(f"{name} is empty; expected numbers in {unit}")
    if not all(math.isfinite(v) and (v > 0 or not positive) for v in values):
        raise VissimInputError(f"{name} must be {'positive ' if positive else ''}finite numbers in {unit}, got {text!r}")
    return values


def image_sampling(image: Image, given: float | None, path: Path) -> float:
    """``--arcmin-per-px`` if given, else the sampling the image file records (``Image.arcmin_per_px``).

    When both exist and differ, the option wins and one warning names both.
    """
    recorded = image.arcmin_per_px
    if given is not None and recorded is not None and not math.isclose(given, recorded, rel_tol=1e-9):
        log.warning("--arcmin-per-px %g overrides the %g arcmin/px that %s records", given, recorded, path)
    step = given if given is not None else recorded
    if step is None:
        raise VissimInputError(f"{path} carries no angular sampling; give --arcmin-per-px (arcmin per pixel)")
    return step
