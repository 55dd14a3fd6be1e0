"""``vissim rx``: read a prescription and show its power vector and Zernike coefficients."""

from __future__ import annotations

import argparse

from vissim.errors import VissimInputError
from vissim.optics.rx.prescription import Prescription
from vissim.cli import command_help
from vissim.cli._output import add_json_arg, print_json


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "rx",
        help=command_help("rx"),
        description="Parse a prescription (the correcting lens, TABO axis) and print it in minus "
        "cylinder, its spherical equivalent, power vector (M, J0, J45) and, with --pupil-mm, the "
        "OSA Zernike coefficients c(2,-2), c(2,0), c(2,2) in µm of the eye it corrects.",
    )
    parser.add_argument("prescription", help="e.g. '-2.00 -1.25 x 180', '-2.00/-1.25x180', 'plano -0.75 x 90'")
    parser.add_argument("--pupil-mm", type=float, metavar="MM", help="pupil diameter in mm for Zernike coefficients (default none: no Zernike coefficients)")
    add_json_arg(parser)
    parser.set_defaults(func=run)


def describe(rx: Prescription, pupil_mm: float | None) -> dict:
    from vissim.optics.pupil.wavefront import prescription_to_zernike_um

    minus = rx.minus_cylinder()
    m, j0, j45 = rx.power_vector()
    out = {
        "prescription": str(minus),
        "plus_cylinder_form": str(rx.plus_cylinder()),
        "sphere_diopters": minus.sphere_diopters,
        "cylinder_diopters": minus.cylinder_diopters,
        "axis_deg": minus.axis_deg,
        "spherical_equivalent_diopters": rx.spherical_equivalent_diopters,
        "M_diopters": m,
        "J0_diopters": j0,
        "J45_diopters": j45,
    }
    if pupil_mm is not None:
        coefficients = prescription_to_zernike_um(rx, pupil_mm)
        out["pupil_diameter_mm"] = pupil_mm
        out["zernike_um"] = {f"{n},{mm}": value + 0.0 for (n, mm), value in coefficients.items()}  # no -0.0
    return out


def run(args: argparse.Namespace) -> int:
    if args.pupil_mm is not None and not args.pupil_mm > 0:
        raise VissimInputError(f"--pupil-mm must be a positive diameter in mm, got {args.pupil_mm!r}")
    info = describe(Prescription.parse(args.prescription), args.pupil_mm)
    if args.json:
        print_json(info)
        return 0
    print(f"prescription (minus cyl): {info['prescription']}")
    print(f"plus-cylinder form:       {info['plus_cylinder_form']}")
    print(f"spherical equivalent:     {info['spherical_equivalent_diopters']:+.3f} D")
    print(
        f"power vector:             M {info['M_diopters']:+.3f} D, J0 {info['J0_diopters']:+.3f} D, "
        f"J45 {info['J45_diopters']:+.3f} D"
    )
    if "zernike_um" in info:
        z = info["zernike_um"]
        print(
            f"Zernike over {args.pupil_mm:g} mm (µm): c(2,-2) {z['2,-2']:+.4f}, c(2,0) {z['2,0']:+.4f}, "
            f"c(2,2) {z['2,2']:+.4f}"
        )
    return 0
