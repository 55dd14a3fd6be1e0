"""``vissim population``: many measured eyes under the same conditions, and their spread."""

from __future__ import annotations

import argparse
from pathlib import Path

from vissim.checks import MAX_POWER_DIOPTERS, mtf_cyc_per_deg, number_within, vertex_distance_mm
from vissim.cli._common import add_json_arg, field_deg_from_text, parse_float_list, print_result
from vissim.errors import VissimInputError
from vissim.optics.eyes.defaults import MEASURED_DATASET_NAMES as DATASET_NAMES
from vissim.optics.eyes.defaults import (DEFAULT_SPECTACLE_VERTEX_MM, PHOTOPIC_FOCUS_NM, POPULATION_CORRECTION,
                                         POPULATION_CORRECTIONS, POPULATION_FIELD_DEG, POPULATION_MTF_CYC_PER_DEG,
                                         POPULATION_PUPILS_MM)
from vissim.cli import command_help

CORRECTIONS = POPULATION_CORRECTIONS


def _listed(values) -> str:
    return ",".join(f"{v:g}" for v in values)


def add_parser(subparsers) -> argparse.ArgumentParser:
    parser = subparsers.add_parser(
        "population",
        help=command_help("population"),
        description=(
            "Evaluate a population of measured eyes (a dataset's eyes, a list, or those whose foveal spherical "
            "equivalent lies in a range) under every combination of the pupils, fields and corrections given: per eye "
            "the MTF, the Strehl ratio, the refraction (M, J0, J45 over the pupil) and the higher-order RMS. Writes "
            "eyes.csv, quantiles.json, gap.md (the population beside the Navarro schematic eye and the published "
            "human MTFs that share its conditions), figure_mtf.png (the population's MTFs as a fan chart), "
            "figure_letters.png (a letter through 16 of the eyes) and, with three or more fields on the horizontal "
            "meridian, figure_astigmatism.png (cylinder against field beside every schematic eye) into the "
            "output folder."),
    )
    parser.add_argument("dataset", choices=DATASET_NAMES, help="the measured eyes")
    parser.add_argument("-o", "--output", type=Path, required=True, help="output folder")
    parser.add_argument("--subjects", metavar="N[,N...]", help="subjects, as numbered in the data (default all)")
    parser.add_argument("--eyes", metavar="SIDE[,SIDE]", help="right, left or both (default: the dataset's eyes)")
    parser.add_argument("--foveal-se-diopters", metavar="LOW,HIGH",
                        help="keep the eyes whose foveal spherical equivalent (over the data's pupil, in "
                             f"{PHOTOPIC_FOCUS_NM:g} nm light) is within LOW..HIGH D (default: every eye)")
    parser.add_argument("--pupil-mm", metavar="MM[,MM...]",
                        help=f"entrance pupil diameters, mm, at most the data's (default {_listed(POPULATION_PUPILS_MM)})")
    parser.add_argument("--field-deg", metavar="X,Y[;X,Y...]",
                        help="field angles, degrees, x (examiner's right: the observer's left) and y (up), from the "
                             "line of sight, as the data were measured; several with ; "
                             f"(default {_listed(POPULATION_FIELD_DEG)}: the fovea)")
    parser.add_argument("--correction", default=POPULATION_CORRECTION, metavar="STATE[,STATE]",
                        help=f"{' or '.join(CORRECTIONS)} (default {POPULATION_CORRECTION}: orders 0-2 removed; "
                             "accommodating: uncorrected, hyperopia cancelled up to --accommodation-amplitude-diopters), "
                             "or the spectacles worn as a prescription, e.g. '-1.00 -0.50 x 90'")
    parser.add_argument("--accommodation-amplitude-diopters", type=float, metavar="A",
                        help="with --correction accommodating: how far the eyes can accommodate to cancel their "
                             "hyperopia, D (required there)")
    parser.add_argument("--vertex-mm", type=float, default=DEFAULT_SPECTACLE_VERTEX_MM, metavar="MM",
                        help=f"spectacles' distance in front of the cornea (default {DEFAULT_SPECTACLE_VERTEX_MM:g})")
    parser.add_argument("--wavelength-nm", type=float, metavar="NM",
                        help=f"light (default {PHOTOPIC_FOCUS_NM:g}: V(λ)'s peak, the published fits' light)")
    parser.add_argument("--mtf-cyc-per-deg", default=_listed(POPULATION_MTF_CYC_PER_DEG), metavar="F[,F...]",
                        help=f"MTF frequencies, cycles/deg (default {_listed(POPULATION_MTF_CYC_PER_DEG)})")
    parser.add_argument("--workers", type=int, default=1, metavar="N", help="spread the eyes over N processes (default 1)")
    parser.add_argument("--scheduler", metavar="ADDRESS", help="spread the eyes over a Dask distributed scheduler")
    parser.add_argument("--overwrite", action="store_true", help="replace files from an earlier run")
    add_json_arg(parser)
    parser.set_defaults(func=run)
    return parser


def _conditions(args):
    from vissim.optics.eyes.measured.population import parse_correction, population_conditions

    pupils = (list(POPULATION_PUPILS_MM) if args.pupil_mm is None  # the defaults as numbers, not read back from text
              else parse_float_list(args.pupil_mm, "--pupil-mm", "mm"))
    fields = ([POPULATION_FIELD_DEG] if args.field_deg is None
              else [field_deg_from_text(text) for text in args.field_deg.split(";") if text.strip()])
    corrections = [c.strip() for c in args.correction.split(",") if c.strip()]
    if not fields:
        raise VissimInputError(f"--field-deg is empty; expected X,Y[;X,Y...] in degrees, got {args.field_deg!r}")
    if not corrections:
        raise VissimInputError(f"--correction is empty; expected {' or '.join(CORRECTIONS)}")
    try:
        corrections = [parse_correction(c) for c in corrections]
    except VissimInputError as error:
        raise VissimInputError(f"--correction: {error}") from None
    nm = PHOTOPIC_FOCUS_NM if args.wavelength_nm is None else args.wavelength_nm
    amplitude = {} if args.accommodation_amplitude_diopters is None else {
        "accommodation_amplitude_diopters": args.accommodation_amplitude_diopters}
    return population_conditions(pupils, fields, corrections, wavelength_nm=nm,
                                 vertex_mm=vertex_distance_mm(args.vertex_mm, "--vertex-mm"), **amplitude)


def _eyes(args):
    from vissim.optics.eyes.measured.population import select_eyes

    for option, text in (("--subjects", args.subjects), ("--eyes", args.eyes), ("--foveal-se-diopters",
                                                                              args.foveal_se_diopters)):
        if text is not None and not text.replace(",", "").strip():
            raise VissimInputError(f"{option} is empty ({text!r}); leave it out to take every eye")
    subjects = None
    if args.subjects:
        try:
            subjects = [int(s) for s in args.subjects.split(",") if s.strip()]
        except ValueError:
            raise VissimInputError(f"--subjects takes whole numbers, got {args.subjects!r}") from None
    sides = None if not args.eyes else [s.strip() for s in args.eyes.split(",") if s.strip()]
    se = None
    if args.foveal_se_diopters:
        se = parse_float_list(args.foveal_se_diopters, "--foveal-se-diopters", "D", positive=False)
        if len(se) != 2:
            raise VissimInputError(f"--foveal-se-diopters takes LOW,HIGH, got {args.foveal_se_diopters!r}")
        se = [number_within(v, "--foveal-se-diopters", "dioptres", (-MAX_POWER_DIOPTERS, MAX_POWER_DIOPTERS))
              for v in se]
    return select_eyes(args.dataset, subjects=subjects, eyes=sides, foveal_se_within_diopters=se)


def run(args: argparse.Namespace) -> int:
    from vissim.optics.eyes.measured.population import evaluate_population
    from vissim.provenance import make_provenance
    from vissim.validation.population.report import write_population_run

    if args.output.exists() and not args.output.is_dir():
        raise VissimInputError(f"-o {args.output} is a file; a population run writes into a folder")
    frequencies = mtf_cyc_per_deg(parse_float_list(args.mtf_cyc_per_deg, "--mtf-cyc-per-deg", "cycles/deg"),
                                  "--mtf-cyc-per-deg")
    conditions = _conditions(args)
    eyes = _eyes(args)
    if not eyes:
        raise VissimInputError(f"no eye of {args.dataset} matches the selection given")
    from vissim.atomic import refuse_existing
    from vissim.validation.population.report import population_run_files

    refuse_existing(*(args.output / name for name in population_run_files(conditions, frequencies)),
                    overwrite=args.overwrite)  # before the eyes are evaluated
    client = None
    if args.scheduler is not None:
        from vissim.validation.engine.scheduler import connect_scheduler

        client = connect_scheduler(args.scheduler)
    try:
        results = evaluate_population(eyes, conditions, frequencies, workers=args.workers, client=client)
    finally:
        if client is not None:
            client.close()
    provenance = make_provenance(command="population", dataset=args.dataset, eyes=[e.name for e in eyes],
                                 conditions=[c.label for c in conditions], mtf_cyc_per_deg=frequencies)
    written = write_population_run(args.output, results, conditions, frequencies, provenance, overwrite=args.overwrite)
    counts = {c.label: sum(r.condition == c for r in results) for c in conditions}
    lines = [f"{label}: {count} of {len(eyes)} eyes" for label, count in counts.items()]
    lines += [f"wrote {path}" for path in written]
    record = {"dataset": args.dataset, "eyes": [e.name for e in eyes], "mtf_cyc_per_deg": frequencies,
              "conditions": [{"condition": label, "eyes_evaluated": count} for label, count in counts.items()]}
    print_result(args, lines, record, written, provenance)
    return 0
