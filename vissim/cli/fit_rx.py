"""``vissim fit-rx``: the sphero-cylinder a capture shows, fitted against its sharp reference."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from vissim.checks import (DEFAULT_WAVELENGTH_NM, FIT_POWER_RANGE_DIOPTERS, MODEL_ERROR_RANGE_DIOPTERS, number_within,
                           VERTEX_DISTANCE_RANGE_MM)
from vissim.cli._common import add_json_arg, check_outputs_apart, image_sampling, print_json, refuse_existing
from vissim.cli._parser import Number
from vissim.errors import VissimInputError
from vissim.progress import terminal_progress
from vissim.cli import command_help


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "fit-rx",
        help=command_help("fit-rx"),
        description=(
            "Fit the sphero-cylinder added at the camera (what 'vissim trial-lens' prints as effective_*) that "
            "turns REFERENCE (the sharp no-lens capture, render or chart) into IMAGE, with the Fourier model, in "
            "power vectors, multi-started, shift re-solved in the loop.  Sampling and pupil come from the images' "
            "provenance when present.  Blur alone is even in the power: the sign comes from the trial lens's "
            "magnification, tied to the bench (from a bench render's provenance, or --vertex-mm and "
            "--object-distance-m); without it the sign is reported undetermined."),
    )
    parser.add_argument("image", type=Path, metavar="IMAGE", help="the blurred capture (EXR, PNG, TIFF)")
    parser.add_argument("--reference", type=Path, required=True, metavar="REF", help="the sharp reference, same size")
    parser.add_argument("--pupil-mm", type=float, metavar="MM", help="entrance pupil diameter (default: from the bench in IMAGE's provenance)")
    parser.add_argument("--arcmin-per-px", type=float, metavar="S", help="angular sampling (default: from the files)")
    parser.add_argument("--mode", choices=("wave", "geometric"),
                        help="optics of the model: geometric (default for Mitsuba renders, which have no diffraction) or wave (default otherwise)")
    parser.add_argument("--magnification", choices=("bench", "free", "none"),
                        help="how magnification follows power: bench (default when a bench is known), free (a fitted "
                             "isotropic scale) or none; only bench determines the sign")
    parser.add_argument("--vertex-mm", type=Number(float, nonnegative=True, maximum=VERTEX_DISTANCE_RANGE_MM[1]), metavar="MM", help="trial lens back vertex to the camera (with --object-distance-m: a bench tie for a capture from elsewhere)")
    parser.add_argument("--object-distance-m", type=Number(float, positive=True), metavar="M", help="camera to the chart, metres (with --vertex-mm)")
    parser.add_argument("--wavelength-nm", type=float, default=DEFAULT_WAVELENGTH_NM, metavar="NM",
                        help=f"wave mode: wavelength (default {DEFAULT_WAVELENGTH_NM:g})")
    parser.add_argument("--fit-focus-offset", action="store_true", help="also fit a focus offset (dioptres)")
    parser.add_argument("--fit-pupil", action="store_true", help="also fit the pupil diameter (trades against power)")
    parser.add_argument("--max-power-diopters", type=Number(float, positive=True, maximum=FIT_POWER_RANGE_DIOPTERS[1]),
                        default=6.0, metavar="D",
                        help="search range of the sphere (cylinder: half of it); default 6")
    parser.add_argument("--model-error-diopters", metavar="D",
                        type=Number(float, nonnegative=True, maximum=MODEL_ERROR_RANGE_DIOPTERS[1]),
                        help="the model's own error per power-vector component, added to the noise in the intervals "
                             "(default 0.0045: measured on Mitsuba bench renders; 0 gives noise-only intervals)")
    add_json_arg(parser)
    parser.add_argument("-o", "--output", type=Path, metavar="FIT.json", help="also write the JSON record with provenance")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing output")
    parser.set_defaults(func=run)


def _channel(image):
    """Luminance (ITU-R BT.709) of an RGB image, or the image itself if grey."""
    import numpy as np

    from vissim.units import REC709_LUMINANCE

    pixels = image.pixels
    if pixels.ndim == 3:
        return np.tensordot(pixels, np.asarray(REC709_LUMINANCE, dtype=np.float32), axes=([2], [0]))
    return pixels


def _sampling(args, image, reference) -> float:
    from vissim.checks import arcmin_per_px as check

    if args.arcmin_per_px is not None:
        for im, path in ((image, args.image), (reference, args.reference)):
            image_sampling(im, args.arcmin_per_px, path)  # warns when the option overrides what a file records
        return check(args.arcmin_per_px)
    steps = {name: im.arcmin_per_px for name, im in (("IMAGE", image), ("REF", reference)) if im.arcmin_per_px}
    if not steps:
        raise VissimInputError("neither IMAGE nor REF records its angular sampling; give --arcmin-per-px (arcmin per pixel)")
    values = sorted(set(steps.values()))
    if len(values) > 1 and not math.isclose(values[0], values[-1], rel_tol=1e-6):
        raise VissimInputError(f"IMAGE is sampled at {steps.get('IMAGE')} arcmin/px but REF at {steps.get('REF')} "
                               "arcmin/px; resample one of them first")
    return values[0]


def _bench(args, image):
    from vissim.bench.dslr.bench import DslrBench
    from vissim.fit.capture import bench_from_provenance

    if (args.vertex_mm is None) != (args.object_distance_m is None):
        raise VissimInputError("--vertex-mm and --object-distance-m go together (the bench tie needs both)")
    if args.vertex_mm is not None:
        distance_mm = 1000.0 * args.object_distance_m
        return DslrBench(focus_distance_mm=distance_mm, chart_distance_mm=distance_mm, vertex_distance_mm=args.vertex_mm)
    return bench_from_provenance(image.provenance)


def run(args: argparse.Namespace) -> int:
    from vissim.checks import pupil_diameter_mm as check_pupil
    from vissim.fit.capture import compare_with_theory, rendered_bench
    from vissim.fit.rx_fit import fit_rx
    from vissim.imageio import image_files, read_image
    from vissim.provenance import make_provenance, to_json

    check_outputs_apart((*image_files(args.image), *image_files(args.reference)), [args.output])
    refuse_existing(args.output, overwrite=args.overwrite)
    number_within(args.max_power_diopters, "--max-power-diopters", "dioptres", FIT_POWER_RANGE_DIOPTERS)
    image = read_image(args.image)
    reference = read_image(args.reference)
    step = _sampling(args, image, reference)
    bench = _bench(args, image)
    if args.pupil_mm is not None:
        pupil = check_pupil(args.pupil_mm)
    elif bench is not None and args.vertex_mm is None:
        pupil = bench.entrance_pupil_diameter_mm
    else:
        raise VissimInputError(f"{args.image} records no bench to take the pupil from; give --pupil-mm (mm)")
    magnification = args.magnification or ("bench" if bench is not None else "none")
    if magnification == "bench" and bench is None:
        raise VissimInputError("--magnification bench needs a bench: a bench render's provenance, or --vertex-mm "
                               "and --object-distance-m")
    rendered = isinstance(image.provenance.get("inputs"), dict) and "mitsuba_render" in image.provenance["inputs"]
    mode = args.mode or ("geometric" if rendered else "wave")
    with terminal_progress() as progress:
        fit = fit_rx(_channel(image), _channel(reference), arcmin_per_px=step,
                     pupil_diameter_mm=pupil, mode=mode, magnification=magnification, bench=bench,
                     wavelength_nm=args.wavelength_nm, fit_focus_offset=args.fit_focus_offset, fit_pupil=args.fit_pupil,
                     max_power_diopters=args.max_power_diopters, progress=progress,
                     **({} if args.model_error_diopters is None else {"model_error_diopters": args.model_error_diopters}))
    record = fit.as_json()
    rendered_with = rendered_bench(image.provenance)
    if rendered_with is not None:  # a bench render: the fit beside vergence theory for its lenses
        record["vergence_theory"] = compare_with_theory(fit, rendered_with)
    record["mode_chosen"] = "given" if args.mode else ("geometric: IMAGE is a Mitsuba render" if rendered else "wave")
    provenance = None
    if args.output is not None:
        from vissim.atomic import write_text_atomic

        provenance = make_provenance(command="fit-rx", image=str(args.image), reference=str(args.reference),
                                     image_provenance=image.provenance, reference_provenance=reference.provenance)
        write_text_atomic(args.output, to_json({"fit": record, "provenance": provenance}) + "\n",
                          overwrite=args.overwrite)
    if args.json:
        print_json(record, [] if args.output is None else [args.output], provenance)
    else:
        _print_text(record, args)
    return 0 if fit.status != "failed" else 1


def _print_text(record: dict, args) -> None:
    settings = record["settings"]
    print(f"fit of {args.image} against {args.reference}: {settings['mode']} optics, pupil "
          f"{settings['pupil_diameter_mm']:g} mm, {settings['arcmin_per_px']:g} arcmin/px, magnification "
          f"{settings['magnification_model']['name']}")
    if record["status"] == "failed":
        print(f"FAILED: {record['reason']}")
    elif record["status"] == "ok":
        axis = f"x {record['axis_deg']:.1f}" if record["axis_determined"] else "(axis undetermined: cylinder ~ 0)"
        print(f"added at the camera: {record['sphere_diopters']:+.3f} {record['cylinder_diopters']:+.3f} {axis}")
        iv = record["interval_95"]
        pv = record["power_vector"]
        for key in ("M_diopters", "J0_diopters", "J45_diopters"):
            print(f"  {key.split('_')[0]:>3} = {pv[key]:+.4f} D   95 % [{iv[key][0]:+.4f}, {iv[key][1]:+.4f}]")
        if iv["axis_deg"] is not None:
            print(f"  axis 95 % [{iv['axis_deg'][0]:.1f}, {iv['axis_deg'][1]:.1f}] deg")
    else:
        print(f"SIGN UNDETERMINED: {record['reason']}")
        for solution in record["solutions"]:
            print(f"  either {solution['sphere_diopters']:+.3f} {solution['cylinder_diopters']:+.3f} x "
                  f"{solution['axis_deg'] if solution['axis_deg'] is not None else '?'}")
    theory = record.get("vergence_theory")
    if theory is not None:
        print(f"vergence theory for the rendered lenses ({', '.join(theory['trial_lenses'])}): "
              f"{theory['vergence_theory']}; Table 4.2: {theory['table_4_2']}")
        if theory["agrees"] is False:
            print(f"DISAGREES: {theory['disagreement']}")
        elif theory["agrees"]:
            print("agrees: theory lies inside the 95 % interval in M, J0 and J45")
    print(f"residual PSNR {record['residual_psnr_db']:.1f} dB; shift ({record['nuisances']['shift_rows_px']:+.2f}, "
          f"{record['nuisances']['shift_cols_px']:+.2f}) px; {record['evaluations']} model evaluations, "
          f"{record['seconds']:.1f} s")
    if args.output is not None:
        print(f"wrote {args.output}")
