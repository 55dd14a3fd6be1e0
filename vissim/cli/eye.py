"""``vissim eye``: a schematic eye traced at one field point and one wavelength (`vissim.optics.eyes.report`)."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from vissim import __version__
from vissim.cli._common import (EYE_ACCOMMODATION_HELP, FIELD_DEG_HELP, RX_HELP, add_eye_model_arg, add_json_arg,
                                add_trial_lens_args, field_deg_from_text, parse_float_list, print_json,
                                trial_lens_powers)
from vissim.errors import VissimInputError
from vissim.optics.rx.prescription import Prescription
from vissim.optics.eyes.models import EYE_MODELS
from vissim.optics.eyes.defaults import DEFAULT_EYE_MODEL, DEFAULT_SPECTACLE_VERTEX_MM
from vissim.spectra import SPECTRA, SPECTRUM_START_NM, SPECTRUM_STEP_NM, SPECTRUM_STOP_NM, named_spectrum
from vissim.cli import command_help

if TYPE_CHECKING:
    from vissim.optics.eyes.report import EyeReport


def add_parser(subparsers) -> argparse.ArgumentParser:
    parser = subparsers.add_parser(
        "eye",
        help=command_help("eye"),
        description=(
            "Trace a schematic eye surface by surface at one field point and one wavelength: its power and "
            "image-space focal length f' (n'/P, in the vitreous), its entrance pupil (diameter: real rays on "
            "axis, the pupil the OSA Zernikes are over; "
            "position: paraxial, behind the corneal vertex), the Zernikes and RMS of its wavefront in µm, "
            "its refraction (paraxial: the wavefront's curvature at the pupil centre; minimum RMS: the "
            "second-order terms), in minus-cylinder form, and the MTF of its wave PSF (diffraction "
            "included; the radial average on axis, tangential and sagittal off axis: tangential along "
            "the field's meridian); with --spectrum or several --wavelength-nm, the MTF of that light, the eye "
            "traced at each wavelength. Models: " + ", ".join(EYE_MODELS) + "."),
    )
    add_eye_model_arg(parser, f"the schematic eye (default {DEFAULT_EYE_MODEL})", default=DEFAULT_EYE_MODEL)
    parser.add_argument("--accommodation-diopters", type=float, default=0.0, metavar="A",
                        help=f"accommodation exerted, {EYE_ACCOMMODATION_HELP} (default 0, relaxed)")
    pupil = parser.add_mutually_exclusive_group(required=True)
    pupil.add_argument("--pupil-mm", type=float, metavar="MM", help="entrance pupil diameter, mm (a clinician's; this or --iris-mm is required)")
    pupil.add_argument("--iris-mm", type=float, metavar="MM", help="iris (stop) diameter, mm (optical design's; this or --pupil-mm is required)")
    parser.add_argument("--wavelength-nm", default=None, metavar="NM[,NM...]",
                        help="wavelength, nm (default: the model's reference wavelength); several: the MTF is of "
                             "their light (see --spectrum), all else at the model's reference wavelength")
    parser.add_argument("--weights", metavar="W[,W...]",
                        help="with several --wavelength-nm: relative weight per wavelength (default equal)")
    parser.add_argument("--spectrum", metavar="NAME",
                        help="the MTF of a named light, the eye traced at each of its wavelengths (its own defocus, "
                             "aberrations and, off axis, transverse chromatic aberration): " + ", ".join(SPECTRA) +
                             f" ({SPECTRUM_START_NM:g}-{SPECTRUM_STOP_NM:g} nm every {SPECTRUM_STEP_NM:g} nm; "
                             "photopic: weighted by the CIE 1924 V(λ)); the Zernikes, refraction and pupils stay at "
                             "--wavelength-nm (default the model's reference)")
    parser.add_argument("--field-deg", default="0,0", metavar="X,Y",
                        help=f"the {FIELD_DEG_HELP} (default 0,0)")
    parser.add_argument("--rx", metavar="PRESCRIPTION",
                        help=f"{RX_HELP}: trace the eye that has it (axial length for its sphere, a toric cornea "
                             "for its cylinder), written at the spectacle plane --vertex-mm in front of the cornea (default "
                             "none: the emmetropic model)")
    lens = parser.add_argument_group(
        "trial or spectacle lens (traced with the eye)",
        "Crown glass of realistic centre thickness "
        "(1 mm at edge and centre over 22 mm, as the ATV tube's trial lenses), plano back, its back vertex "
        "--vertex-mm in front of the cornea; the refraction is then the over-refraction at its front surface")
    add_trial_lens_args(lens)
    parser.add_argument("--vertex-mm", type=float, default=None, metavar="MM",
                        help="spectacle plane, mm in front of the corneal vertex: where --rx is written, the lens's "
                             f"back vertex sits and the refraction is stated (default {DEFAULT_SPECTACLE_VERTEX_MM:g} "
                             "with --rx or a lens; without them and --vertex-mm the refraction is at the corneal vertex)")
    parser.add_argument("--mtf-cyc-per-mm", metavar="F1,F2,...",
                        help="MTF at these retinal frequencies, cycles per mm (>= 0; default none)")
    parser.add_argument("--mtf-cyc-per-deg", metavar="F1,F2,...",
                        help="MTF at these frequencies, cycles per degree of visual angle (>= 0; default none)")
    parser.add_argument("--lca", action="store_true",
                        help="add the eye's longitudinal chromatic aberration over 400-700 nm in 10 nm steps: its "
                             "refraction at each wavelength minus that at --wavelength-nm (default the model's "
                             "reference), traced over the pupil given at --field-deg, beside the paraxial value, "
                             "Thibos's chromatic eye (1992) and Atchison & Smith's fit to measured eyes (2005)")
    add_json_arg(parser)
    parser.set_defaults(func=run)
    return parser


def _frequencies(text: str | None, name: str, unit: str) -> list[float]:
    if text is None:
        return []
    values = parse_float_list(text, name, unit, positive=False)
    negative = [v for v in values if v < 0.0]
    if negative:
        raise VissimInputError(f"{name} must be frequencies >= 0 {unit}, got {negative[0]:g} {unit}")
    return values


def _light(args: argparse.Namespace):
    """(the report's one wavelength or None, the MTF's `MtfSpectrum` or None) from --wavelength-nm,
    --weights and --spectrum."""
    from vissim.optics.eyes.report import MtfSpectrum

    given = None if args.wavelength_nm is None else parse_float_list(args.wavelength_nm, "--wavelength-nm", "nm")
    several = given is not None and len(given) > 1
    if args.weights is not None and not several:
        raise VissimInputError("--weights needs several --wavelength-nm (one weight each)")
    if args.spectrum is not None:
        if several:
            raise VissimInputError(f"--spectrum {args.spectrum} gives the MTF's wavelengths: give one --wavelength-nm "
                                   "(for the Zernikes and refraction) or none")
        return (given[0] if given else None), MtfSpectrum(*named_spectrum(args.spectrum), args.spectrum)
    if not several:
        return (given[0] if given else None), None
    weights = (parse_float_list(args.weights, "--weights", "relative units", positive=False)
               if args.weights is not None else [1.0] * len(given))
    return None, MtfSpectrum(tuple(given), tuple(weights))


def run(args: argparse.Namespace) -> int:
    from vissim.optics.eyes.eye import build_eye  # the trace's imports are paid when the command runs
    from vissim.optics.eyes.report import eye_report

    powers = trial_lens_powers(args)
    lenses = () if powers is None else (_trial_lens(*powers),)
    wavelength, spectrum = _light(args)
    eye = build_eye(args.eye_model, accommodation_diopters=args.accommodation_diopters, pupil_diameter_mm=args.pupil_mm,
                    iris_mm=args.iris_mm, rx=args.rx,
                    vertex_distance_mm=DEFAULT_SPECTACLE_VERTEX_MM if args.vertex_mm is None else args.vertex_mm)
    report = eye_report(eye, wavelength_nm=wavelength, mtf_spectrum=spectrum,
                        field_deg=field_deg_from_text(args.field_deg), at_spectacle_plane=args.vertex_mm is not None,
                        mtf_cyc_per_mm=_frequencies(args.mtf_cyc_per_mm, "--mtf-cyc-per-mm", "cycles per mm"),
                        mtf_cyc_per_deg=_frequencies(args.mtf_cyc_per_deg, "--mtf-cyc-per-deg", "cycles per degree"),
                        lenses=lenses, lca=args.lca)
    if args.json:
        print_json({**report.as_json(), "vissim_version": __version__})
        return 0
    _print_text(report)
    return 0


def _trial_lens(*powers):
    from vissim.bench.atv.tube import atv_trial_lens  # the tube's image code only when a lens is asked for

    return atv_trial_lens(*powers)


def _rx_line(entry: dict) -> str:
    """The prescription written by `Prescription.format` to 0.001 D (a cylinder that rounds to 0: ``DS``), then M, J0,
    J45 (a component that rounds to 0 is +0.000)."""
    written = Prescription(entry["sphere_diopters"], entry["cylinder_diopters"], entry["axis_deg"]).format(3)
    m, j0, j45 = (round(entry[key], 3) + 0.0 for key in ("M", "J0", "J45"))  # + 0.0: no "-0.000"
    return f"{written:<22} M {m:+.3f}  J0 {j0:+.3f}  J45 {j45:+.3f} D"


def _print_text(report: EyeReport) -> None:
    record = report.as_json()
    pupil, refraction = record["entrance_pupil"], record["refraction"]
    wavelength = "" if report.wavelength_given else " (the model's reference)"
    rx = f", made to need {record['prescription']}" if record["prescription"] else ""
    rows = [
        ("eye", f"{record['model']}{_base(record)} at {record['accommodation_diopters']:g} D accommodation{rx}"),
        ("wavelength", f"{record['wavelength_nm']:g} nm{wavelength}"),
        ("field", f"({record['field_deg'][0]:g}, {record['field_deg'][1]:g}) deg from the {record['field_axis']}"),
        *[("lens", f"{lens['marked_power']} (back vertex power), n_d {lens['refractive_index_d']:g}, "
                   f"{lens['center_thickness_mm']:.3f} mm thick, back vertex {report.lens_setup.vertex_distance_mm:g} mm "
                   "in front of the cornea") for lens in record["lenses"]],
        ("power, f'", f"{record['power_diopters']:.3f} D, {record['image_focal_length_mm']:.4f} mm "
                      "(image space: n'/P)"),
        ("retina", f"{record['retinal_mm_per_deg']:.5f} mm per deg"),
        ("entrance pupil", f"{pupil['diameter_mm']:.4f} mm across (real rays; paraxial "
                           f"{pupil['paraxial_diameter_mm']:.4f}), {pupil['position_mm']:.4f} mm behind the cornea"),
        ("iris", f"{record['iris_mm']:.4f} mm ({pupil['given']} given)"),
        ("RMS (order >= 2)", f"{record['rms_um']:.4f} µm over the {record['zernike_pupil']}"),
        ("refraction at", refraction["refraction_plane"] + " (correcting lens, minus cylinder)"),
        ("refraction over", refraction["pupil_definition"]),
        ("  paraxial", _rx_line(refraction["paraxial"])),
        ("  minimum RMS", _rx_line(refraction["minimum_rms"])),
    ]
    big = {k: v for k, v in record["zernike_um"].items() if abs(v) >= 5e-4 and int(k.split(",")[0]) >= 2}
    rows.append(("Zernikes (µm)", "  ".join(f"{k}: {v:+.4f}" for k, v in big.items()) or "all < 0.0005"))
    if "spectrum" in record["mtf"]:
        light = record["mtf"]["spectrum"]
        span = f"{light['wavelengths_nm'][0]:g}-{light['wavelengths_nm'][-1]:g} nm"
        rows.append(("MTF light", f"{light['name']}, {len(light['wavelengths_nm'])} wavelengths {span} (the eye "
                                  f"traced at each; Zernikes and refraction above at {record['wavelength_nm']:g} nm)"))
    for key, unit in (("cyc_per_deg", "cyc/deg"), ("cyc_per_mm", "cyc/mm")):
        for direction, pairs in record["mtf"].get(key, {}).items():
            rows.append((f"MTF {direction}", ", ".join(f"{f:g} {unit}: {v:.4f}" for f, v in pairs)))
    width = max(len(label) for label, _ in rows)
    for label, text in rows:
        print(f"{label:<{width}}  {text}")
    if "lca" in record:
        _print_lca(record["lca"])


def _print_lca(lca: dict) -> None:
    pupil = lca["pupil"]
    print(f"\nLCA at the corneal vertex, D, re {lca['reference_wavelength_nm']:g} nm; traced over a "
          f"{pupil['entrance_pupil_mm']:.3f} mm entrance pupil (iris {pupil['iris_mm']:.3f} mm) at field "
          f"({lca['field_deg'][0]:g}, {lca['field_deg'][1]:g}) deg")
    print("    nm    traced  min RMS  paraxial  Thibos  Atchison&Smith  traced-Thibos  traced-A&S")
    for r in lca["rows"]:
        traced = r["traced_diopters"]
        print(f"  {r['wavelength_nm']:4.0f}  {traced:+8.3f} {r['traced_minimum_rms_diopters']:+8.3f} "
              f"{r['paraxial_diopters']:+9.3f} {r['thibos_diopters']:+7.3f} {r['atchison_smith_diopters']:+15.3f} "
              f"{traced - r['thibos_diopters']:+14.3f} {traced - r['atchison_smith_diopters']:+11.3f}")


def _base(record: dict) -> str:
    """A measured eye's schematic base, as the text report names it."""
    return f" (measured; on the {record['base_model']} eye)" if "base_model" in record else ""
