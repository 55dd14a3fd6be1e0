"""Argument groups shared by several sub-commands (aberration, pupil, wavelengths)."""

from __future__ import annotations

import argparse
import math

from vissim.errors import VissimInputError
from vissim.optics.prescription import Prescription
from vissim.optics.wavefront import Wavefront, parse_zernike_terms


def add_aberration_args(parser: argparse.ArgumentParser, *, required: bool = True) -> None:
    group = parser.add_argument_group("aberration (at least one of --rx / --zernike)")
    group.add_argument(
        "--rx",
        metavar="PRESCRIPTION",
        help="the correcting lens, e.g. '-2.00 -1.25 x 180', '+1.50 DS', 'plano' (TABO axis)",
    )
    group.add_argument(
        "--zernike",
        metavar="TERMS",
        help="OSA Zernike terms in µm, 'n,m=µm;n,m=µm' (e.g. '2,0=0.5;4,0=0.1'); adds to --rx",
    )
    group.add_argument(
        "--zernike-pupil-mm",
        type=float,
        metavar="D",
        help="pupil diameter the --zernike coefficients were measured over (default: --pupil-mm)",
    )
    group.add_argument("--pupil-mm", type=float, required=required, metavar="D", help="pupil diameter in mm")
    parser.set_defaults(_aberration_required=required)


def wavefront_from_args(args: argparse.Namespace) -> Wavefront:
    """The wavefront the user described, over the measurement pupil."""
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
