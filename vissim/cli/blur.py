"""``vissim blur``: blur an image file through a prescription or wavefront, in linear light."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from vissim.checks import DEFAULT_WAVELENGTH_NM, size_text
from vissim.cli._common import (add_aberration_args, check_outputs_apart, image_sampling, parse_float_list,
                                wavefront_from_args)
from vissim.errors import FieldTooSmallError, VissimInputError
from vissim.imageio import image_files, output_bit_depth, read_image, write_image
from vissim.optics.array_backend import DEVICES, array_backend
from vissim.optics.blur import PADDING_MODES, blur_image
from vissim.optics.blur_device import blur_image_on
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
        "550 nm for all channels with --wavelength-nm 550. An alpha channel is carried through "
        "unchanged (the colour is blurred, the coverage is not); PNG/TIFF outputs keep the input's bit depth.",
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
    colour.add_argument("--wavelength-nm", metavar="NM[,NM...]", help=f"wavelength(s) for every channel (default {DEFAULT_WAVELENGTH_NM:g})")
    colour.add_argument("--channels-nm", metavar="R,G,B", help="one wavelength per RGB channel (default 610,550,465)")
    parser.add_argument(
        "--channel-fwhm-nm",
        type=float,
        metavar="W",
        help="spectral weighting per channel: a Gaussian band of this FWHM around each channel's wavelength",
    )
    parser.add_argument("--lca", action="store_true", help="add the eye's chromatic defocus (Thibos 1992)")
    parser.add_argument("--lca-reference-nm", type=float, default=DEFAULT_WAVELENGTH_NM, metavar="NM",
                        help=f"in-focus wavelength for --lca (default {DEFAULT_WAVELENGTH_NM:g})")
    parser.add_argument("--mode", choices=("wave", "geometric"), default="wave", help="PSF optics (default wave)")
    parser.add_argument("--padding", choices=PADDING_MODES, default="constant", help="outside the image (default constant: border mean)")
    parser.add_argument("--device", choices=DEVICES, default="cpu",
                        help="where to blur: cpu (default), cuda (a GPU through CuPy, the gpu extra), auto (cuda "
                             "when present, else the same code on the CPU); cuda and auto take one full-frame FFT "
                             "per PSF and equal cpu to float32 round-off")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing output")
    parser.set_defaults(func=run)


def image_too_small(path: Path, shape: tuple[int, ...], psf_px: int, step: float) -> VissimInputError:
    """The error for an image smaller than its blur: its size, the PSF field the blur needs, the side that holds it.

    A blur's PSF field is cut to twice the image's longer side plus one (no pixel sees farther);
    an image whose cut field loses more than 1 % of the energy is too small.
    """
    side = math.ceil((psf_px - 1) / 2)
    return VissimInputError(
        f"{path}: the image is {size_text(shape)}, too small for this blur: its PSF needs a "
        f"{psf_px} px field at {step:g} arcmin/px, so the image needs at least {side} px on its longer side "
        "(or a coarser --arcmin-per-px)")


def _channel_psfs(bands, wavefront, step: float, args, lca, shape, progress) -> tuple[list, dict]:
    """One PSF per channel (computed once per distinct band), and the distinct ones by band.

    A PSF's field is cut to twice the image's longer side plus one (no pixel sees farther); an
    image too small for the field its blur needs is refused with `image_too_small`.
    """
    psfs, cache = [], {}
    advance = counter(progress, "PSFs", len(set(bands)))
    for wavelengths, weights in bands:
        key = (wavelengths, weights)
        if key not in cache:
            size = suggested_size_px(wavefront, step, pupil_diameter_mm=args.pupil_mm, wavelength_nm=wavelengths, lca_reference_nm=lca)
            field_px = min(size, 2 * max(shape) + 1)
            label = f"at {', '.join(f'{w:g}' for w in wavelengths)} nm"
            stages = None if progress is None else (lambda stage, done, total, label=label:
                                                    progress(f"{stage} {label}", done, total))
            try:
                cache[key] = compute_psf(
                    wavefront, pupil_diameter_mm=args.pupil_mm, wavelength_nm=wavelengths, weights=weights,
                    lca_reference_nm=lca, arcmin_per_px=step, size_px=field_px, mode=args.mode, progress=stages,
                )
            except FieldTooSmallError:
                if field_px == size:
                    raise
                raise image_too_small(args.input, shape, size, step) from None
            advance()
        psfs.append(cache[key])
    return psfs, cache


def _blur_channels(pixels: np.ndarray, psfs: list, step: float, padding: str, device: str, progress):
    """``pixels`` blurred channel by channel (each with its PSF), reporting each channel done.

    Off the ``"cpu"`` device: all channels at once by `vissim.optics.blur_device.blur_image_on`.
    """
    if device != "cpu":
        return blur_image_on(pixels, psfs if pixels.ndim == 3 else psfs[0], arcmin_per_px=step, padding=padding,
                             device=device)
    if pixels.ndim == 2:
        return blur_image(pixels, psfs[0], arcmin_per_px=step, padding=padding)
    advance = counter(progress, "blurring channels", pixels.shape[2])
    channels = []
    for c, psf in enumerate(psfs):
        channels.append(blur_image(pixels[..., c], psf, arcmin_per_px=step, padding=padding))
        advance()
    return np.stack(channels, axis=-1)


def run(args: argparse.Namespace) -> int:
    check_outputs_apart(image_files(args.input), image_files(args.output))
    if args.device == "cuda":
        array_backend("cuda")  # no GPU: refused before the PSFs are computed
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
        wavelengths = parse_float_list(args.wavelength_nm or f"{DEFAULT_WAVELENGTH_NM:g}", "--wavelength-nm", "nm")
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
        blurred = _blur_channels(image.pixels, psfs, step, args.padding, args.device, progress)
    provenance = make_provenance(command="blur", input=str(args.input), input_provenance=image.provenance,
                                 arcmin_per_px=step, padding=args.padding, device=args.device,
                                 psfs=[p.as_json() for p in cache.values()], rx=args.rx, zernike=args.zernike)
    written = write_image(args.output, blurred, provenance=provenance, overwrite=args.overwrite, arcmin_per_px=step,
                          alpha=image.alpha, bit_depth=output_bit_depth(image, args.output))
    print(f"wrote {written}")
    return 0
