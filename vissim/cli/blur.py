"""``vissim blur``: blur an image file through a prescription or wavefront, in linear light."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from vissim.cli._common import add_aberration_args, parse_float_list, wavefront_from_args
from vissim.errors import VissimInputError
from vissim.imageio import Image, read_image, write_image
from vissim.optics.blur import PADDING_MODES, blur_image
from vissim.optics.chromatic import gaussian_band
from vissim.optics.psf import compute_psf, suggested_size_px
from vissim.progress import counter, terminal_progress
from vissim.provenance import make_provenance

DEFAULT_CHANNELS_NM = (610.0, 550.0, 465.0)


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "blur",
        help="blur an image through a prescription or Zernike wavefront",
        description="Blur an image (EXR linear; PNG/TIFF decoded from sRGB) with the PSF of an "
        "aberration, in linear light. Mono images use --wavelength-nm; RGB images use one "
        "wavelength per channel (--channels-nm, default 610,550,465), or the thesis's single "
        "550 nm for all channels with --wavelength-nm 550.",
    )
    parser.add_argument("input", type=Path, help="image file (.exr, .png, .tif)")
    parser.add_argument("-o", "--output", required=True, type=Path, help="output image (.exr, .png, .tif)")
    add_aberration_args(parser)
    parser.add_argument(
        "--arcmin-per-px",
        type=float,
        metavar="S",
        help="the image's angular sampling (default: the one its file records, e.g. a vissim chart or render)",
    )
    colour = parser.add_mutually_exclusive_group()
    colour.add_argument("--wavelength-nm", metavar="NM[,NM...]", help="wavelength(s) for every channel (default 550)")
    colour.add_argument("--channels-nm", metavar="R,G,B", help="one wavelength per RGB channel (default 610,550,465)")
    parser.add_argument(
        "--channel-fwhm-nm",
        type=float,
        metavar="W",
        help="spectral weighting per channel: a Gaussian band of this FWHM around each channel's wavelength",
    )
    parser.add_argument("--lca", action="store_true", help="add the eye's chromatic defocus (Thibos 1992)")
    parser.add_argument("--lca-reference-nm", type=float, default=550.0, metavar="NM", help="in-focus wavelength for --lca")
    parser.add_argument("--mode", choices=("wave", "geometric"), default="wave", help="PSF optics (default wave)")
    parser.add_argument("--padding", choices=PADDING_MODES, default="constant", help="outside the image (default constant: border mean)")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing output")
    parser.set_defaults(func=run)


def image_sampling(image: Image, given: float | None, path: Path) -> float:
    """``--arcmin-per-px`` if given, else the sampling the image file records (``Image.arcmin_per_px``)."""
    step = given if given is not None else image.arcmin_per_px
    if step is None:
        raise VissimInputError(f"{path} carries no angular sampling; give --arcmin-per-px (arcmin per pixel)")
    return step


def _channel_psfs(bands, wavefront, step: float, args, lca, shape, progress) -> tuple[list, dict]:
    """One PSF per channel (computed once per distinct band), and the distinct ones by band."""
    psfs, cache = [], {}
    advance = counter(progress, "PSFs", len(set(bands)))
    for wavelengths, weights in bands:
        key = (wavelengths, weights)
        if key not in cache:
            size = suggested_size_px(wavefront, step, pupil_diameter_mm=args.pupil_mm, wavelength_nm=wavelengths, lca_reference_nm=lca)
            size = min(size, 2 * max(shape) + 1)
            label = f"at {', '.join(f'{w:g}' for w in wavelengths)} nm"
            stages = None if progress is None else (lambda stage, done, total, label=label:
                                                    progress(f"{stage} {label}", done, total))
            cache[key] = compute_psf(
                wavefront, pupil_diameter_mm=args.pupil_mm, wavelength_nm=wavelengths, weights=weights,
                lca_reference_nm=lca, arcmin_per_px=step, size_px=size, mode=args.mode, progress=stages,
            )
            advance()
        psfs.append(cache[key])
    return psfs, cache


def _blur_channels(pixels: np.ndarray, psfs: list, step: float, padding: str, progress):
    """``pixels`` blurred channel by channel (each with its PSF), reporting each channel done."""
    if pixels.ndim == 2:
        return blur_image(pixels, psfs[0], arcmin_per_px=step, padding=padding)
    advance = counter(progress, "blurring channels", pixels.shape[2])
    channels = []
    for c, psf in enumerate(psfs):
        channels.append(blur_image(pixels[..., c], psf, arcmin_per_px=step, padding=padding))
        advance()
    return np.stack(channels, axis=-1)


def run(args: argparse.Namespace) -> int:
    image = read_image(args.input)
    step = image_sampling(image, args.arcmin_per_px, args.input)
    wavefront = wavefront_from_args(args)
    n_channels = 1 if image.pixels.ndim == 2 else image.pixels.shape[2]
    if args.channels_nm is not None:
        if n_channels != 3:
            raise VissimInputError(f"--channels-nm needs an RGB image; {args.input} has {n_channels} channel(s)")
        per_channel = [[w] for w in parse_float_list(args.channels_nm, "--channels-nm", "nm")]
        if len(per_channel) != 3:
            raise VissimInputError(f"--channels-nm needs three wavelengths (R,G,B) in nm, got {args.channels_nm!r}")
    elif args.wavelength_nm is not None or n_channels == 1:
        wavelengths = parse_float_list(args.wavelength_nm or "550", "--wavelength-nm", "nm")
        per_channel = [wavelengths] * n_channels
    else:
        per_channel = [[w] for w in DEFAULT_CHANNELS_NM]
    lca = args.lca_reference_nm if args.lca else None
    bands = []
    for wavelengths in per_channel:
        if args.channel_fwhm_nm is not None:
            if len(wavelengths) != 1:
                raise VissimInputError("--channel-fwhm-nm needs one centre wavelength per channel")
            bands.append(gaussian_band(wavelengths[0], args.channel_fwhm_nm))
        else:
            bands.append((tuple(wavelengths), None))
    with terminal_progress() as progress:
        psfs, cache = _channel_psfs(bands, wavefront, step, args, lca, image.pixels.shape[:2], progress)
        blurred = _blur_channels(image.pixels, psfs, step, args.padding, progress)
    provenance = make_provenance(command="blur", input=str(args.input), input_provenance=image.provenance,
                                 arcmin_per_px=step, padding=args.padding,
                                 psfs=[p.as_json() for p in cache.values()], rx=args.rx, zernike=args.zernike)
    written = write_image(args.output, blurred, provenance=provenance, overwrite=args.overwrite, arcmin_per_px=step)
    print(f"wrote {written}")
    return 0
