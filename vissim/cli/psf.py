"""``vissim psf``: compute a PSF and write it as a float32 ``Y`` EXR (and a PNG preview)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from vissim.checks import DEFAULT_WAVELENGTH_NM
from vissim.checks import size_text
from vissim.cli._common import (EYE_ACCOMMODATION_HELP, EYE_RX_HELP, FIELD_DEG_HELP, add_aberration_args,
                                add_json_arg, print_result,
                                check_zernike_pupil,
                                add_eye_model_arg, eye_from_args, field_deg_from_text, parse_float_list,
                                wavefront_from_args)
from vissim.errors import VissimInputError
from vissim.provenance import make_provenance
from vissim.spectra import SPECTRA, SPECTRUM_START_NM, SPECTRUM_STEP_NM, SPECTRUM_STOP_NM, named_spectrum
from vissim.cli import command_help

if TYPE_CHECKING:
    from vissim.optics.pupil.spectral_wavefront import SpectralWavefront
    from vissim.optics.pupil.wavefront import Wavefront


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "psf",
        help=command_help("psf"),
        description="Compute the PSF of a prescription or Zernike wavefront at a stated angular "
        "sampling, over any field. Writes a float32 single-channel (Y) EXR normalised to the PSF's total "
        "energy, so it sums to the fraction the field holds (recorded as energy_in_field in the file's "
        "provenance; a warning when more than 1 % falls outside), origin at [N//2, N//2], row 0 at the "
        "top of the visual field; when -o ends in .png, also a peak-normalised PNG preview (the EXR goes "
        "beside it).",
    )
    add_aberration_args(parser)
    parser.add_argument("--wavelength-nm", default=None, metavar="NM[,NM...]",
                        help=f"wavelength(s) in nm (default {DEFAULT_WAVELENGTH_NM:g})")
    parser.add_argument("--weights", metavar="W[,W...]", help="relative weight per wavelength (default equal)")
    parser.add_argument("--spectrum", metavar="NAME",
                        help="a named light in place of --wavelength-nm and --weights: " + ", ".join(SPECTRA) +
                        f" ({SPECTRUM_START_NM:g}-{SPECTRUM_STOP_NM:g} nm every {SPECTRUM_STEP_NM:g} nm; photopic: "
                        "an equal-energy light weighted by the CIE 1924 photopic luminous efficiency V(λ))")
    parser.add_argument("--lca", action="store_true", help="add the eye's chromatic defocus (Thibos 1992)")
    parser.add_argument("--lca-reference-nm", type=float, default=DEFAULT_WAVELENGTH_NM, metavar="NM",
                        help=f"in-focus wavelength for --lca (default {DEFAULT_WAVELENGTH_NM:g})")
    add_eye_model_arg(parser, "a schematic eye in place of the reduced eye: its traced "
                        "wavefront over the --pupil-mm entrance pupil, at --field-deg and --accommodation-diopters, "
                        "traced at each wavelength (its spherical aberration and its own dispersion: defocus, and off "
                        "axis each wavelength's image point seen from the model's reference wavelength's; no --lca), "
                        "--zernike added over the same pupil; " + EYE_RX_HELP + " (vissim.optics.eyes.psf_wavefront)")
    parser.add_argument("--field-deg", metavar="X,Y",
                        help=f"with --eye-model: the {FIELD_DEG_HELP}; the PSF is centred on the chief ray's image "
                        "point at the model's reference wavelength (default 0,0)")
    parser.add_argument("--accommodation-diopters", type=float, metavar="A",
                        help=f"with --eye-model: accommodation exerted, {EYE_ACCOMMODATION_HELP} "
                        "(default 0, relaxed)")
    parser.add_argument("--arcmin-per-px", type=float, default=0.25, metavar="S", help="output sampling (default 0.25)")
    parser.add_argument("--size", type=int, default=256, metavar="N", help="output field, N x N pixels (default 256)")
    parser.add_argument("--mode", choices=("wave", "geometric"), default="wave", help="wave (default) or geometric optics")
    parser.add_argument("--float64", action="store_true", help="compute in float64 (default float32; files are float32)")
    parser.add_argument("-o", "--output", required=True, type=Path, help="out.exr or out.png")
    parser.add_argument("--overwrite", action="store_true", help="replace existing outputs")
    add_json_arg(parser)
    parser.set_defaults(func=run)


def _light(args: argparse.Namespace) -> tuple[list[float], list[float] | None]:
    """(wavelengths nm, weights or None): --spectrum's, or --wavelength-nm's and --weights'."""
    if args.spectrum is not None:
        if args.wavelength_nm is not None or args.weights is not None:
            raise VissimInputError(f"--spectrum {args.spectrum} gives the wavelengths and weights: drop "
                                   "--wavelength-nm and --weights, or --spectrum")
        wavelengths, weights = named_spectrum(args.spectrum)
        return list(wavelengths), list(weights)
    text = args.wavelength_nm if args.wavelength_nm is not None else f"{DEFAULT_WAVELENGTH_NM:g}"
    wavelengths = parse_float_list(text, "--wavelength-nm", "nm")
    weights = parse_float_list(args.weights, "--weights", "relative units", positive=False) if args.weights else None
    return wavelengths, weights


def run(args: argparse.Namespace) -> int:
    import numpy as np  # the numerical code is paid when the command runs

    from vissim.imageio import to_preview_png, write_image
    from vissim.optics.psf.compute import compute_psf

    check_zernike_pupil(args)
    wavelengths, weights = _light(args)
    if args.eye_model is None and (args.field_deg is not None or args.accommodation_diopters is not None):
        raise VissimInputError("--field-deg and --accommodation-diopters need --eye-model (the reduced eye has one "
                               "PSF over the field and no accommodation)")
    wavefront = _eye_front(args, wavelengths) if args.eye_model is not None else wavefront_from_args(args)
    psf = compute_psf(wavefront, pupil_diameter_mm=args.pupil_mm, wavelength_nm=wavelengths, weights=weights,
                      lca_reference_nm=args.lca_reference_nm if args.lca else None,
                      arcmin_per_px=args.arcmin_per_px, size_px=args.size, mode=args.mode,
                      dtype=np.float64 if args.float64 else np.float32, normalise="total")
    provenance = make_provenance(command="psf", psf=psf.as_json(), rx=args.rx, zernike=args.zernike,
                                 eye_model=args.eye_model or "reduced", field_deg=args.field_deg,
                                 accommodation_diopters=args.accommodation_diopters,
                                 spectrum=args.spectrum, eye_wavefront_um=_eye_record(wavefront) if args.eye_model else None)
    output = args.output
    exr_path = output.with_suffix(".exr") if output.suffix.lower() == ".png" else output
    data = psf.data.astype(np.float32)
    step = psf.arcmin_per_px
    written = [write_image(exr_path, data, provenance=provenance, overwrite=args.overwrite, arcmin_per_px=step)]
    if output.suffix.lower() == ".png":
        written.append(to_preview_png(output, data, provenance=provenance, overwrite=args.overwrite, arcmin_per_px=step))
    lines = [f"wrote {path}" for path in written]
    lines.append(
        f"PSF {size_text(psf.size_px)} at {psf.arcmin_per_px:g} arcmin/px, pupil "
        f"{psf.pupil_diameter_mm:g} mm, {psf.mode} optics, {100 * psf.energy_in_field:.2f} % of the energy in the field"
    )
    record = {"size_px": list(psf.size_px), "arcmin_per_px": psf.arcmin_per_px,
              "pupil_diameter_mm": psf.pupil_diameter_mm, "mode": psf.mode, "energy_in_field": psf.energy_in_field,
              "wavelength_nm": list(psf.wavelengths_nm)}
    print_result(args, lines, record, written, provenance)
    return 0


def _eye_front(args: argparse.Namespace, wavelengths: list[float]) -> Wavefront | SpectralWavefront:
    """The schematic eye's traced wavefront at each wavelength, the eye having --rx, with --zernike added
    (`eye_spectral_wavefront`: one wavelength's front is `eye_wavefront`'s, with its map to visual angle)."""
    from vissim.optics.eyes.psf_wavefront import eye_spectral_wavefront  # paid when it runs
    from vissim.optics.pupil.spectral_wavefront import SpectralWavefront
    from vissim.optics.pupil.wavefront import Wavefront, parse_zernike_terms

    if args.lca:
        raise VissimInputError("--eye-model takes no --lca: the traced eye has its own dispersion")
    if len(set(wavelengths)) != len(wavelengths):
        raise VissimInputError(f"--wavelength-nm lists a wavelength twice: {', '.join(f'{w:g}' for w in wavelengths)} nm")
    field = field_deg_from_text(args.field_deg) if args.field_deg is not None else (0.0, 0.0)
    front = eye_spectral_wavefront(eye_from_args(args, args.rx), wavelengths_nm=wavelengths, field_deg=field)
    if args.zernike is not None:
        measured = args.zernike_pupil_mm if args.zernike_pupil_mm is not None else args.pupil_mm
        extra = Wavefront(parse_zernike_terms(args.zernike), measured)
        front = front.map(lambda f: f + extra) if isinstance(front, SpectralWavefront) else front + extra
    return front


def _eye_record(front: Wavefront | SpectralWavefront) -> dict:
    """The eye's Zernikes for the provenance: ``"n,m"`` -> µm, or per wavelength (nm) for several."""
    from vissim.optics.pupil.spectral_wavefront import SpectralWavefront

    if isinstance(front, SpectralWavefront) and len(front.fronts) == 1:
        return _eye_record(front.fronts[0])
    if isinstance(front, SpectralWavefront):
        return {f"{w:g}": _eye_record(f) for w, f in zip(front.wavelengths_nm, front.fronts)}
    return {f"{n},{m}": c for (n, m), c in front.coefficients_um.items()}
