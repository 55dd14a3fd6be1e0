"""``vissim atv``: the absolute threshold for vision (thesis Ch. 5).

* ``vissim atv analyze DIR -o OUT`` -- fit every subject file in DIR; figures, report.md/.html, analysis.json.
* ``vissim atv simulate --rx RX --pupil-mm MM [--accommodation-amplitude-diopters A] [--cycloplegia] -o OUT`` -- a virtual subject.
* ``vissim atv run [--observer simulated|person] -o result.json`` -- one threshold by Listing 5.1.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from vissim.checks import ATV_PARABOLA_WINDOW_DIOPTERS, trial_lens_diopters
from vissim.checks import DEFAULT_WAVELENGTH_NM
from vissim.cli._common import JSON_HELP, add_json_arg, add_rx_arg, check_outputs_apart, print_result, refuse_existing
from vissim.cli._parser import Number
from vissim.errors import VissimInputError
from vissim.optics.rx.conventions import CORNEA_TO_ENTRANCE_PUPIL_MM, EYE_VERTEX_DISTANCE_MM, SPECTACLE_VERTEX_DISTANCE_MM
from vissim.cli import command_help


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "atv",
        help=command_help("atv"),
        description="The thesis's absolute-threshold-for-vision experiment (Ch. 5): analyse participant data, "
        "simulate a virtual subject, or run the threshold procedure with a simulated observer or a person.",
    )
    sub = parser.add_subparsers(dest="atv_command", metavar="ACTION")
    parser.set_defaults(func=lambda args: parser.print_help() or 2)

    analyze = sub.add_parser("analyze", help="fit participant data and write a report",
                             description="Quadratic fits of minimum visible vs trial lens per eye and condition, "
                             "vertex with Fieller and delta-method intervals, compared with the cycloplegic SE.")
    analyze.add_argument("data_dir", type=Path, help="directory of subject_*.json files (e.g. validation/atv)")
    analyze.add_argument("-o", "--output", type=Path, required=True, help="output directory")
    analyze.add_argument("--strict", action="store_true", help="fail if the data disagree with the thesis's own numbers")
    analyze.add_argument("--level", type=float, default=0.95, help="confidence level (default 0.95)")
    analyze.add_argument("--all-sessions", action="store_true", help="fit every session's value instead of the per-lens means")
    analyze.add_argument("--window-diopters", type=float, default=ATV_PARABOLA_WINDOW_DIOPTERS, metavar="W",
                         help="also fit a local parabola over lenses within W D of the least value "
                              f"(default {ATV_PARABOLA_WINDOW_DIOPTERS:g}; 0 to skip)")
    analyze.add_argument("--overwrite", action="store_true", help="replace existing outputs")
    add_json_arg(analyze)
    analyze.set_defaults(func=run_analyze)

    sim = sub.add_parser("simulate", help="simulate the experiment for a virtual subject",
                         description="Fourier retinal image of one phone pixel through the ATV tube and a trial lens, "
                         "threshold by spatial summation, Listing 5.1 with a simulated observer at every lens.")
    add_rx_arg(sim, required=True)
    sim.add_argument("--pupil-mm", type=float, required=True, metavar="MM", help="pupil diameter in mm")
    sim.add_argument("--accommodation-amplitude-diopters", type=float, default=8.0, metavar="A",
                     help="amplitude of accommodation, D: the most the subject can exert (default 8); the "
                          "accommodation exerted at each lens follows from it")
    sim.add_argument("--cycloplegia", action="store_true", help="no accommodation (cycloplegic drops)")
    sim.add_argument("--proximal-diopters", type=float, default=0.0, metavar="P", help="accommodation exerted even when it blurs, D (default 0)")
    sim.add_argument("--lenses", metavar="D[,D...]", help="trial lenses in D (default: the thesis's 17)")
    sim.add_argument("--vertex-mm", type=float, default=None, metavar="MM",
                     help=f"vertex distance: trial lens back vertex to the eye's pupil (default "
                          f"{EYE_VERTEX_DISTANCE_MM:g}: a {SPECTACLE_VERTEX_DISTANCE_MM:g} mm spectacle vertex "
                          f"distance + {CORNEA_TO_ENTRANCE_PUPIL_MM:g} mm cornea to pupil)")
    sim.add_argument("--wavelength-nm", type=float, default=DEFAULT_WAVELENGTH_NM, metavar="NM",
                     help=f"wavelength, nm (default {DEFAULT_WAVELENGTH_NM:g})")
    sim.add_argument("--summation-arcmin", type=float, default=10.0, help="summation (Ricco) diameter, arcmin (default 10)")
    sim.add_argument("--full-capture-code", type=float, default=0.06, help="threshold code value with all flux summed (default 0.06)")
    sim.add_argument("--gamma", type=float, default=2.2, help="display gamma, code value -> luminance (default 2.2)")
    _observer_args(sim, threshold=False)
    sim.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    sim.add_argument("--window-diopters", type=float, default=ATV_PARABOLA_WINDOW_DIOPTERS, metavar="W",
                     help=f"also fit a ±W D local parabola (default {ATV_PARABOLA_WINDOW_DIOPTERS:g}; 0 to skip)")
    sim.add_argument("-o", "--output", type=Path, required=True, help="output directory")
    sim.add_argument("--overwrite", action="store_true", help="replace existing outputs")
    add_json_arg(sim)
    sim.set_defaults(func=run_simulate)

    run = sub.add_parser("run", help="run the threshold procedure once (Listing 5.1)",
                         description="Phase 1: quasi-random narrowing in steps of 0.1; phase 2: bisection down to "
                         "--resolution. A person answers in a one-pixel window (keys y/n/q) or in the terminal.")
    run.add_argument("--observer", choices=("simulated", "person"), default="simulated", action=_ObserverChoice,
                     help="who answers: the simulated observer below, or a person at the display (default simulated)")
    run.add_argument("--display", choices=("auto", "window", "terminal"), default="auto", help="how a person sees the stimulus (default auto)")
    _observer_args(run, threshold=True)
    run.add_argument("--resolution", type=float, default=0.001, help="phase-2 resolution, code value (default 0.001)")
    run.add_argument("--sphere", type=float, metavar="D", help="trial lens sphere in use, dioptres (recorded only)")
    run.add_argument("--eye-side", choices=("R", "L"), help="eye tested (recorded only)")
    run.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    run.add_argument("-o", "--output", type=Path, required=True, help="result JSON file")
    run.add_argument("--overwrite", action="store_true", help="replace an existing result")
    run.add_argument("--json", action="store_true",
                     help=JSON_HELP + " (with --observer simulated only: a person's prompts share that output)")
    run.set_defaults(func=run_procedure_command, prints_live=False)


class _ObserverChoice(argparse.Action):
    """``--observer``: with a person, the command prints live (`vissim.cli`), for the person reads its prompts."""

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, values)
        namespace.prints_live = values == "person"


def _observer_args(parser: argparse.ArgumentParser, *, threshold: bool) -> None:
    group = parser.add_argument_group("simulated observer (Weibull psychometric function)")
    exponent = Number(float, positive=True, allow_inf=True, unit="(Weibull exponent)")
    if threshold:
        group.add_argument("--threshold", type=float, default=0.1, help="50 %% point, code value (default 0.1)")
        group.add_argument("--code-value-slope", type=exponent, default=20.0, metavar="B",
                           help="Weibull exponent of P(seen) as a function of the display code value (default 20; "
                                "inf: a step at --threshold)")
    else:
        group.add_argument("--luminance-slope", type=exponent, default=4.0, metavar="B",
                           help="Weibull exponent of P(seen) as a function of luminance (default 4); as a function "
                                "of the code value it is --gamma times this")
    group.add_argument("--guess", type=float, default=0.0, help="false-alarm rate (default 0)")
    group.add_argument("--lapse", type=float, default=0.0, help="lapse rate (default 0)")


def _window(value: float) -> float | None:
    return value or None  # 0: no window (the parser holds it to ATV_PARABOLA_WINDOW_RANGE_DIOPTERS)


def _vertex(a) -> str:
    if a.vertex_diopters is None:
        return "no minimum"
    return f"{a.vertex_diopters:+.2f} D, CI {a.vertex_interval.describe()}"


def run_analyze(args: argparse.Namespace) -> int:
    from vissim.atv.report import analyse_directory

    check_outputs_apart([args.data_dir], folders=[args.output])
    written, analyses = analyse_directory(
        args.data_dir, args.output, strict=args.strict, level=args.level, average_sessions=not args.all_sessions,
        window_diopters=_window(args.window_diopters), overwrite=args.overwrite,
    )
    lines = []
    for a in analyses:
        se = f"SE {a.measured_se_diopters:+.3f} D" if a.measured_se_diopters is not None else "no SE"
        fit = "all lenses" if a.window_diopters is None else f"±{a.window_diopters:g} D"
        lines.append(f"subject {a.subject_id} {a.eye} {a.condition.replace('_', ' ')} ({fit}): vertex {_vertex(a)}; {se}")
    lines += [f"wrote {path}" for path in written]
    print_result(args, lines, {"analyses": [a.as_json() for a in analyses]}, written)
    return 0


def run_simulate(args: argparse.Namespace) -> int:
    from vissim.atv.report import write_simulation_report
    from vissim.atv.virtual import AtvApparatus, DetectionModel, VirtualSubject, run_virtual_experiment
    from vissim.cli._common import parse_float_list
    from vissim.optics.rx.prescription import Prescription

    subject = VirtualSubject(
        Prescription.parse(args.rx), args.pupil_mm, accommodation_amplitude_diopters=args.accommodation_amplitude_diopters,
        cycloplegia=args.cycloplegia, proximal_accommodation_diopters=args.proximal_diopters,
    )
    vertex = {} if args.vertex_mm is None else {"trial_lens_vertex_mm": args.vertex_mm}
    apparatus = AtvApparatus(**vertex, wavelength_nm=args.wavelength_nm, display_gamma=args.gamma)
    detection = DetectionModel(
        summation_diameter_arcmin=args.summation_arcmin, threshold_code_full_capture=args.full_capture_code,
        psychometric_slope=args.luminance_slope, guess_rate=args.guess, lapse_rate=args.lapse,
    )
    kwargs = {}
    if args.lenses is not None:  # an empty --lenses is an error, not the default lenses
        kwargs["lenses_diopters"] = [trial_lens_diopters(v, "--lenses")
                                     for v in parse_float_list(args.lenses, "--lenses", "D", positive=False)]
    experiment = run_virtual_experiment(subject, apparatus=apparatus, detection=detection, seed=args.seed, **kwargs)
    written, analyses = write_simulation_report(experiment, args.output, window_diopters=_window(args.window_diopters), overwrite=args.overwrite)
    lines = [f"lens {t.trial_lens_diopters:+.2f} D: residual {t.residual_se_diopters:+.2f} D, accommodation "
             f"{t.accommodation_diopters:.2f} D, flux in summation area {t.summation_fraction:.3f}, threshold "
             f"{t.minimum_visible_code:.4f} (model {t.model_threshold_code:.4f})" for t in experiment.trials]
    for a in analyses:
        fit = "all lenses" if a.window_diopters is None else f"±{a.window_diopters:g} D window"
        lines.append(f"fit over {fit}: vertex {_vertex(a)}; SE {a.measured_se_diopters:+.3f} D")
    lines += [f"wrote {path}" for path in written]
    print_result(args, lines, {"experiment": experiment.as_json(), "analyses": [a.as_json() for a in analyses]}, written)
    return 0


def run_procedure_command(args: argparse.Namespace) -> int:
    from vissim.atomic import write_json_atomic
    from vissim.atv.procedure import ProcedureConfig, PsychometricFunction, SimulatedObserver, run_procedure
    from vissim.provenance import make_provenance

    config = ProcedureConfig(resolution_code=args.resolution)
    if args.json and args.observer == "person":
        raise VissimInputError("--json goes with --observer simulated: a person's prompts share the output the JSON "
                               "is printed on")
    refuse_existing(args.output, overwrite=args.overwrite)  # fail before a person spends minutes answering
    observer_record: dict = {"kind": args.observer}
    if args.observer == "simulated":
        psychometric = PsychometricFunction(args.threshold, args.code_value_slope, args.guess, args.lapse)
        observer = SimulatedObserver(psychometric, seed=args.seed)
        observer_record.update(threshold_code=args.threshold, code_value_slope=args.code_value_slope,
                               guess_rate=args.guess, lapse_rate=args.lapse)
    else:
        from vissim.atv.interactive import make_person_observer

        observer = make_person_observer(args.display)
        observer_record["display"] = type(observer).__name__
    try:
        result = run_procedure(observer, config, seed=args.seed)
    finally:
        if hasattr(observer, "close"):
            observer.close()
    record = make_provenance(command="atv run", observer=observer_record, trial_lens_diopters=args.sphere, eye=args.eye_side)
    record["result"] = result.as_json()
    write_json_atomic(args.output, record, overwrite=args.overwrite)
    if result.never_seen:  # no number: the procedure only narrowed down to the display's white
        lines = [f"never seen: none of the {len(result.presentations)} presentations, up to code "
                 f"{result.upper_code:.4f} (the display's white), was seen; the threshold lies above what the "
                 "display shows"]
    else:
        lines = [f"threshold {result.threshold_code:.4f} (code value), interval [{result.lower_code:.4f}, "
                 f"{result.upper_code:.4f}], {len(result.presentations)} presentations"]
    lines.append(f"wrote {args.output}")
    print_result(args, lines, {"observer": observer_record, "result": result.as_json()}, [args.output],
                 {k: v for k, v in record.items() if k != "result"})
    return 0
