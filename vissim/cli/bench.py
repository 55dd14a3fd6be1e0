"""``vissim bench wavefront``: the wavefront the bench's trial lenses add, by exact ray trace."""

from __future__ import annotations

import argparse

from vissim import __version__
from vissim.cli._common import add_json_arg, add_trial_lens_args, parse_float_list, print_json, trial_lens_powers
from vissim.errors import VissimInputError
from vissim.cli import command_help

#: Terms below this magnitude (µm) are left out of the text table (the JSON has them all).
_PRINT_FLOOR_UM = 1e-7


def add_parser(subparsers) -> argparse.ArgumentParser:
    parser = subparsers.add_parser("bench", help=command_help("bench"),
                                   description="The virtual DSLR bench's trial lenses, traced exactly.")
    commands = parser.add_subparsers(dest="bench_command", metavar="COMMAND")
    add_wavefront_parser(commands)
    parser.set_defaults(func=lambda args: parser.print_help() or 2)
    return parser


def add_wavefront_parser(subparsers) -> argparse.ArgumentParser:
    from vissim.optics.rx.glass import D_LINE_NM

    parser = subparsers.add_parser(
        "wavefront",
        help="OSA Zernike coefficients the trial lenses add over the camera's entrance pupil",
        description=(
            "Trace rays from a chart point through the bench's trial lenses (their exact surfaces, "
            "dispersive crown glass) onto a grid over the camera's entrance pupil, and print the "
            "optical path difference they add as OSA Zernike coefficients (µm; piston and tilt "
            "removed, tilt reported as the image shift), its RMS and the equivalent added power.  "
            "Options override the --scene file; --sphere/--cylinder replace its lenses with one lens."
        ),
    )
    parser.add_argument("--scene", metavar="TOML", help="bench scene file (see scenes/dslr_bench.toml)")
    add_trial_lens_args(parser.add_argument_group("trial lens (replaces the scene's lenses)"), none_given="the scene's lenses")
    parser.add_argument("--f-number", type=float, metavar="N", help="camera f-number (default 5)")
    parser.add_argument("--wavelength-nm", type=float, default=D_LINE_NM, metavar="NM",
                        help=f"wavelength (default {D_LINE_NM:g}, the d line, where the glass has the "
                             "rendered index 1.523)")
    parser.add_argument("--field-deg", default="0,0", metavar="X,Y",
                        help="chart point as seen from the pupil centre, degrees: X towards the examiner's "
                             "right (the camera's left), Y up (default 0,0)")
    parser.add_argument("--max-order", type=int, default=8, metavar="N", help="Zernike radial order (default 8)")
    add_json_arg(parser)
    parser.set_defaults(func=run_wavefront)
    return parser


def _field_deg(text: str) -> tuple[float, float]:
    values = parse_float_list(text, "--field-deg", "degrees", positive=False)
    if len(values) != 2:
        raise VissimInputError(f"--field-deg must be two angles X,Y in degrees, got {text!r}")
    return values[0], values[1]


def run_wavefront(args: argparse.Namespace) -> int:
    from vissim.bench.dslr.traced_wavefront import trace_bench_wavefront
    from vissim.bench.dslr.scene_files import bench_from_tables
    from vissim.bench.scene_toml import read_scene_toml
    from vissim.optics.rx.trial_lens import TrialLens, trial_lens_effect

    field = _field_deg(args.field_deg)
    powers = trial_lens_powers(args)
    doc, source = ({}, "command line") if args.scene is None else read_scene_toml(args.scene)
    bench = bench_from_tables(doc, source, lenses=None if powers is None else (TrialLens(*powers),),
                              f_number=args.f_number)
    traced = trace_bench_wavefront(bench, field_deg=field, wavelength_nm=args.wavelength_nm,
                                   max_order=args.max_order)
    theory = trial_lens_effect(bench.trial_lens_setup()).added_power.minus_cylinder() if bench.lenses else None
    if args.json:
        result = traced.as_json()
        result.update(
            lenses=[{"marked_power": str(lens.marked_power), "refractive_index": lens.refractive_index,
                     "center_thickness_mm": lens.center_thickness_mm,
                     "back_surface_diopters": lens.back_surface_diopters, "back_vertex_z_mm": z}
                    for lens, z in zip(bench.physical_lenses, bench.lens_back_vertex_z_mm())],
            chart_distance_mm=bench.chart_distance_mm, f_number=bench.f_number,
            vergence_theory_added_power=None if theory is None else theory.format(4),
            vissim_version=__version__,
        )
        print_json(result)
        return 0

    lenses = " + ".join(str(lens.marked_power) for lens in bench.lenses) or "no lens"
    print(f"traced wavefront: {lenses} at {bench.vertex_distance_mm:g} mm, chart at {bench.chart_distance_mm:g} mm, "
          f"field ({field[0]:g}, {field[1]:g}) deg, {traced.wavelength_nm:.7g} nm, "
          f"pupil {traced.pupil_diameter_mm:g} mm (f/{bench.f_number:g})")
    print(f"zernike_um (OSA n,m; piston and tilt removed; |c| >= {_PRINT_FLOOR_UM:g} µm):")
    for (n, m), value in traced.wavefront.coefficients_um.items():
        if abs(value) >= _PRINT_FLOOR_UM:
            print(f"  {f'{n},{m}':>6}  {value:+.7f}")
    print(f"rms:                     {traced.rms_um:.6f} µm (higher orders {traced.higher_order_rms_um:.3g} µm)")
    print(f"equivalent added power:  {traced.added_power.format(4)}"
          + ("" if theory is None else f"   (vergence theory {theory.format(4)})"))
    shift_x, shift_y = (round(v, 9) + 0.0 for v in traced.image_shift_mrad)  # no "-0.00000"
    print(f"image shift (tilt):      x {shift_x:+.5f} mrad, y {shift_y:+.5f} mrad (OSA frame)")
    return 0
