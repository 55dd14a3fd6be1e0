"""``vissim blur``: blur an image file through a prescription or wavefront, in linear light."""

from __future__ import annotations

import argparse
from pathlib import Path

from vissim.checks import DEFAULT_WAVELENGTH_NM, counted
from vissim.cli._common import (EYE_ACCOMMODATION_HELP, EYE_RX_HELP, FIELD_DEG_HELP, add_aberration_args,
                                add_json_arg, print_result,
                                check_zernike_pupil,
                                add_eye_model_arg, check_outputs_apart, eye_from_args, field_deg_from_text,
                                image_sampling, parse_float_list, wavefront_from_args)
from vissim.errors import FieldTooSmallError, VissimInputError
from vissim.optics.blur.padding import PADDING_MODES
from vissim.optics.runtime.devices import DEVICES
from vissim.progress import counter, terminal_progress
from vissim.provenance import make_provenance
from vissim.cli import command_help

DEFAULT_CHANNELS_NM = (610.0, 550.0, 465.0)


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "blur",
        help=command_help("blur"),
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
        help="spectral weighting per channel: a Gaussian band of this FWHM around each channel's wavelength "
             "(default none: each channel at its one wavelength)",
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
    add_eye_model_args(parser)
    parser.add_argument("--overwrite", action="store_true", help="replace an existing output")
    add_json_arg(parser)
    parser.set_defaults(func=run)


def add_eye_model_args(parser) -> None:
    """``--eye-model`` and the options that go with it (``vissim blur``)."""
    eye = parser.add_argument_group(
        "schematic eye (in place of the reduced eye)",
        "With --eye-model the image is seen by a traced schematic eye: each channel's wavelength is traced "
        "(the eye's own spherical aberration, dispersion and off-axis aberrations, no --lca; a --channel-fwhm-nm band "
        "at each of its wavelengths) over the --pupil-mm entrance pupil; " + EYE_RX_HELP + ". The PSF varies "
        "over the image: it is traced at a grid of field points --field-step-deg apart and interpolated between "
        "them; an image within one step is blurred by the one PSF at its centre. The image stays in visual angle "
        "(the eye's distortion is not applied).")
    add_eye_model_arg(eye, "a schematic eye (default none: the reduced eye)")
    eye.add_argument("--field-deg", metavar="X,Y",
                     help=f"with --eye-model: the image centre's {FIELD_DEG_HELP} (default 0,0: the eye looks at "
                     "the image centre)")
    eye.add_argument("--accommodation-diopters", type=float, metavar="A",
                     help=f"with --eye-model: accommodation exerted, {EYE_ACCOMMODATION_HELP} (default 0)")
    eye.add_argument("--field-step-deg", type=float, metavar="S",
                     help="with --eye-model: spacing of the traced PSFs over the image, degrees of visual angle "
                     "(default 2)")


def _channel_psfs(bands, wavefront, step: float, args, lca, shape, progress) -> tuple[list, dict]:
    """One PSF per channel (computed once per distinct band, `image_kernel_psf`), and the distinct ones by band;
    an image too small for its blur is refused naming the file."""
    from vissim.optics.blur.convolve import image_kernel_psf  # the numerical code, when the command runs

    psfs, cache = [], {}
    advance = counter(progress, "PSFs", len(set(bands)))
    for wavelengths, weights in bands:
        key = (wavelengths, weights)
        if key not in cache:
            label = f"at {', '.join(f'{w:g}' for w in wavelengths)} nm"
            stages = None if progress is None else (lambda stage, done, total, label=label:
                                                    progress(f"{stage} {label}", done, total))
            try:
                cache[key] = image_kernel_psf(wavefront, shape, arcmin_per_px=step, wavelength_nm=wavelengths,
                                              weights=weights, lca_reference_nm=lca, mode=args.mode, progress=stages)
            except FieldTooSmallError as error:
                raise FieldTooSmallError(f"{args.input}: {error}") from None
            advance()
        psfs.append(cache[key])
    return psfs, cache


def _blur_channels(pixels, psfs: list, step: float, padding: str, device: str, progress):
    """``pixels`` blurred channel by channel (each with its PSF), reporting each channel done.

    Off the ``"cpu"`` device: all channels at once by `vissim.optics.blur.device.blur_image_on`.
    """
    import numpy as np

    from vissim.optics.blur.convolve import blur_image
    from vissim.optics.blur.device import blur_image_on

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
    from vissim.imageio import image_files, output_bit_depth, read_image, write_image
    from vissim.optics.runtime.array_backend import array_backend
    from vissim.optics.rx.chromatic import gaussian_band

    check_zernike_pupil(args)
    check_outputs_apart(image_files(args.input), image_files(args.output))
    _check_eye_options(args)
    if args.device == "cuda":
        array_backend("cuda")  # no GPU: refused before the PSFs are computed
    image = read_image(args.input)
    step = image_sampling(image, args.arcmin_per_px, args.input)
    wavefront = wavefront_from_args(args) if args.eye_model is None else None
    n_channels = 1 if image.pixels.ndim == 2 else image.pixels.shape[2]
    if args.channels_nm is not None:
        if n_channels != 3:
            raise VissimInputError(f"--channels-nm needs an RGB image; {args.input} has {counted(n_channels, 'channel')}")
        per_channel = [[w] for w in parse_float_list(args.channels_nm, "--channels-nm", "nm")]
        if len(per_channel) != 3:
            raise VissimInputError(f"--channels-nm needs three wavelengths (R,G,B) in nm, got {args.channels_nm!r}")
    elif args.wavelength_nm is not None or n_channels == 1:
        wavelengths = ([DEFAULT_WAVELENGTH_NM] if args.wavelength_nm is None
                       else parse_float_list(args.wavelength_nm, "--wavelength-nm", "nm"))
        per_channel = [wavelengths] * n_channels
    else:
        per_channel = [[w] for w in DEFAULT_CHANNELS_NM]
    bands = []
    for wavelengths in per_channel:
        if args.channel_fwhm_nm is not None:
            if len(wavelengths) != 1:
                raise VissimInputError("--channel-fwhm-nm needs one centre wavelength per channel")
            bands.append(gaussian_band(wavelengths[0], args.channel_fwhm_nm))
        else:
            bands.append((tuple(wavelengths), None))
    if args.eye_model is not None:
        return _run_eye(args, image, step, bands)
    lca = args.lca_reference_nm if args.lca else None
    with terminal_progress() as progress:
        psfs, cache = _channel_psfs(bands, wavefront, step, args, lca, image.pixels.shape[:2], progress)
        blurred = _blur_channels(image.pixels, psfs, step, args.padding, args.device, progress)
    provenance = make_provenance(command="blur", input=str(args.input), input_provenance=image.provenance,
                                 arcmin_per_px=step, padding=args.padding, device=args.device,
                                 psfs=[p.as_json() for p in cache.values()], rx=args.rx, zernike=args.zernike)
    written = write_image(args.output, blurred, provenance=provenance, overwrite=args.overwrite, arcmin_per_px=step,
                          alpha=image.alpha, bit_depth=output_bit_depth(image, args.output))
    print_result(args, [f"wrote {written}"], {"arcmin_per_px": step, "size_px": list(blurred.shape[:2]),
                                              "psfs": len(cache)}, [written], provenance)
    return 0


def _check_eye_options(args: argparse.Namespace) -> None:
    """The refusals of --eye-model's combinations, before any image is read."""
    eye_only = {"--field-deg": args.field_deg, "--accommodation-diopters": args.accommodation_diopters,
                "--field-step-deg": args.field_step_deg}
    if args.eye_model is None:
        given = [name for name, value in eye_only.items() if value is not None]
        if given:
            raise VissimInputError(f"{' and '.join(given)} {'needs' if len(given) == 1 else 'need'} --eye-model (the "
                                   "reduced eye has one PSF over the field and no accommodation)")
        return
    if args.lca:
        raise VissimInputError("--lca does not go with --eye-model: the traced eye has its own dispersion")
    if args.zernike is not None:
        raise VissimInputError("--zernike with --eye-model is not supported by blur; give the eye's --rx")
    if args.device != "cpu":
        raise VissimInputError(f"--device {args.device} with --eye-model: the field-dependent blur runs on the cpu")


def _run_eye(args: argparse.Namespace, image, step: float, bands: list) -> int:
    """``blur --eye-model``: one PSF grid per distinct channel band ((wavelengths, weights)), the image
    blurred field-dependently."""
    from vissim.imageio import output_bit_depth, write_image
    from vissim.optics.eyes.field_blur import DEFAULT_FIELD_STEP_DEG, eye_psf_grids  # the trace's imports, when used
    from vissim.optics.blur.field_dependent import blur_field_dependent

    field = field_deg_from_text(args.field_deg) if args.field_deg is not None else (0.0, 0.0)
    field_step = DEFAULT_FIELD_STEP_DEG if args.field_step_deg is None else args.field_step_deg
    the_eye = eye_from_args(args, args.rx)
    with terminal_progress() as progress:
        channel_grids = eye_psf_grids(image.pixels.shape[:2], the_eye, [b[0] for b in bands], [b[1] for b in bands],
                                      arcmin_per_px=step, field_deg=field, field_step_deg=field_step, mode=args.mode,
                                      progress=progress)
    blurred = blur_field_dependent(image.pixels, channel_grids if image.pixels.ndim == 3 else channel_grids[0],
                                   arcmin_per_px=step, padding=args.padding)
    any_grid = channel_grids[0]
    eye = {**the_eye.as_json(), "field_deg": list(field), "field_step_deg": field_step, "nodes": list(any_grid.shape),
           "node_count": any_grid.node_count, "channel_wavelengths_nm": [list(b[0]) for b in bands],
           "channel_weights": [None if b[1] is None else list(b[1]) for b in bands],
           "distortion": "not applied (visual-angle coordinates)"}
    provenance = make_provenance(command="blur", input=str(args.input), input_provenance=image.provenance,
                                 arcmin_per_px=step, padding=args.padding, device=args.device, rx=args.rx,
                                 eye_model=eye)
    written = write_image(args.output, blurred, provenance=provenance, overwrite=args.overwrite, arcmin_per_px=step,
                          alpha=image.alpha, bit_depth=output_bit_depth(image, args.output))
    print_result(args, [f"wrote {written} ({args.eye_model}, {any_grid.shape[0]} x {any_grid.shape[1]} PSF nodes "
                        f"{field_step:g} deg apart)"],
                 {"arcmin_per_px": step, "size_px": list(blurred.shape[:2]), "psf_nodes": list(any_grid.shape),
                  "field_step_deg": field_step}, [written], provenance)
    return 0
