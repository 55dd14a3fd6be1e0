"""``vissim render depth``: a depth scene (charts at several distances, a tilted chart) through an eye or the DSLR.

Registered by `vissim.cli.render` through `add_depth_parser`.  Thin: load the
scene file (`vissim.bench.depth.scene_files`), apply the options, call
`vissim.render.depth_render.render_depth`, write the blurred image (and on request the
all-in-focus image and the axial depth map) with provenance, print a summary with the
predicted blur of every panel.

The depth map is metres along the view axis from the pupil to each pixel's nearest surface
(docs/conventions.md), ``inf`` for sky: an EXR with one
channel ``Z`` (or ``.npy``), which ``vissim blur-depth AIF.exr DEPTH.exr`` reads as is.

The all-in-focus image and the depth map cover a margin beyond the blurred image's frame on
every side (``--margin-px``; default the scene's largest blur radius,
`vissim.bench.depth.viewers.frame_margin_px`), recorded as ``margin_px`` in their
provenance: ``blur-depth`` simulates on the larger grid, so it sees what the observer sees
beyond the frame, and crops its output to the blurred image's frame.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from vissim.checks import EYE_PUPIL_RANGE_MM, eye_pupil_diameter_mm, size_text
from vissim.cli._common import (add_json_arg, add_rx_arg, print_result, add_trial_lens_args, check_outputs_apart, refuse_existing,
                                trial_lens_powers)
from vissim.errors import VissimInputError

__all__ = ["add_depth_parser", "run_depth", "write_depth"]


def add_depth_parser(subparsers) -> argparse.ArgumentParser:
    """Add the ``depth`` sub-command to ``subparsers`` (those of ``vissim render``) and return it."""
    parser = subparsers.add_parser(
        "depth",
        help="charts at several distances (or a tilted chart) seen by an eye or the DSLR",
        description=(
            "Render a depth scene file (scenes/depth_panels.toml, scenes/depth_tilted.toml) by path tracing: "
            "the blurred image of the scene's observer, and on request the all-in-focus image (a pinhole at "
            "the pupil) and the depth map (axial metres, inf = sky) on the same pixel grid.  Eye options "
            "replace the file's observer with an eye, camera options with the DSLR bench camera."
        ),
    )
    parser.add_argument("scene", type=Path, help="depth scene TOML, e.g. scenes/depth_panels.toml")
    eye = parser.add_argument_group("eye (an eye focused at 1 / (A - Rx) metres; Rx not worn)")
    add_rx_arg(eye, default_text=" (default: the file's observer; plano when another eye option is given)")
    eye.add_argument("--pupil-mm", type=float, metavar="MM",
                     help=f"the eye's pupil diameter, {EYE_PUPIL_RANGE_MM[0]:g}-{EYE_PUPIL_RANGE_MM[1]:g} mm (default: the file's "
                          "observer; 4 when another eye option is given)")
    eye.add_argument("--accommodation-diopters", type=float, metavar="A", help="accommodation exerted, dioptres >= 0 (default: the file's observer; 0 "
                     "when another eye option is given)")
    camera = parser.add_argument_group("DSLR bench camera (thin lens, entrance pupil focal length / f-number)")
    camera.add_argument("--f-number", type=float, metavar="N", help="f-number (default 5)")
    camera.add_argument("--focus-distance-m", type=float, metavar="F", help="focus distance in metres (default 0.9144)")
    camera.add_argument("--focal-length-mm", type=float, metavar="MM", help="focal length (default 18)")
    add_trial_lens_args(parser.add_argument_group("trial lens on the DSLR bench camera (replaces the file's lenses)"),
                        none_given="the file's lenses")
    out = parser.add_argument_group("outputs")
    out.add_argument("-o", "--output", required=True, type=Path, metavar="PATH", help="blurred image, .exr (linear)")
    out.add_argument("--all-in-focus", type=Path, metavar="PATH", help="also the all-in-focus image, .exr")
    out.add_argument("--depth", type=Path, metavar="PATH", help="also the axial depth map in metres, .exr (Z) or .npy")
    out.add_argument("--overwrite", action="store_true", help="replace existing outputs")
    sampling = parser.add_argument_group("sampling (defaults: the scene file's)")
    sampling.add_argument("--spp", type=int, metavar="N", help="samples per pixel of the blurred render (default: the file's, else 64)")
    sampling.add_argument("--aux-spp", type=int, metavar="N",
                          help="samples per pixel of the all-in-focus and depth renders (default: the file's, else 64)")
    sampling.add_argument("--seed", type=int, metavar="S", help="seed (all-in-focus: S + 1, depth: S + 2; default: the file's, else 0)")
    sampling.add_argument("--margin-px", type=int, metavar="M",
                          help="render the all-in-focus image and the depth M px beyond every side of the frame "
                               "(default: the scene's largest blur radius + 2 px; 0: none)")
    sampling.add_argument("--rgb", action="store_true", help="render RGB (default: monochrome)")
    sampling.add_argument("--variant", metavar="V", help="Mitsuba variant (default: chosen by vissim)")
    add_json_arg(parser)
    parser.set_defaults(func=run_depth)
    return parser


def _viewer(args: argparse.Namespace, loaded):
    from vissim.bench.depth.viewers import CameraViewer, EyeViewer
    from vissim.optics.rx.prescription import Prescription
    from vissim.optics.rx.trial_lens import TrialLens

    eye_given = any(v is not None for v in (args.rx, args.pupil_mm, args.accommodation_diopters))
    camera_given = any(v is not None for v in (args.f_number, args.focus_distance_m, args.focal_length_mm,
                                               args.sphere, args.cylinder, args.axis))
    if eye_given and camera_given:
        raise VissimInputError("give eye options (--rx/--pupil-mm/--accommodation-diopters) or camera options, not both")
    if eye_given:
        if args.pupil_mm is not None:
            eye_pupil_diameter_mm(args.pupil_mm, "--pupil-mm")
        base = loaded.viewer if isinstance(loaded.viewer, EyeViewer) else EyeViewer()
        changes = {"prescription": None if args.rx is None else Prescription.parse(args.rx),
                   "pupil_diameter_mm": args.pupil_mm, "accommodation_diopters": args.accommodation_diopters}
        return dataclasses.replace(base, **{k: v for k, v in changes.items() if v is not None})
    if camera_given:
        base = loaded.viewer if isinstance(loaded.viewer, CameraViewer) else CameraViewer()
        changes = {"f_number": args.f_number, "focus_distance_m": args.focus_distance_m,
                   "focal_length_mm": args.focal_length_mm}
        powers = trial_lens_powers(args)
        if powers is not None:
            changes["lenses"] = (TrialLens(*powers),)
        return dataclasses.replace(base, **{k: v for k, v in changes.items() if v is not None})
    return loaded.viewer


def _check_outputs(args: argparse.Namespace) -> None:
    paths = [p for p in (args.output, args.all_in_focus, args.depth) if p is not None]
    check_outputs_apart([args.scene], paths)  # the three outputs apart from the scene and from each other
    for path, allowed in ((args.output, (".exr",)), (args.all_in_focus, (".exr",)), (args.depth, (".exr", ".npy"))):
        if path is None:
            continue
        if path.suffix.lower() not in allowed:
            raise VissimInputError(f"{path}: expected a file ending in {' or '.join(allowed)} (linear float)")
    refuse_existing(*paths, overwrite=args.overwrite)


def write_depth(path: Path, depth_m, *, provenance: dict | None = None, overwrite: bool = False,
                arcmin_per_px: float | None = None) -> Path:
    """Write an axial depth map (metres, inf = sky) as a one-channel ``Z`` EXR or a ``.npy``, atomically.

    ``arcmin_per_px`` is recorded in the EXR's provenance (a ``.npy`` holds none).
    """
    import numpy as np  # paid when it runs

    from vissim.atomic import atomic_output
    from vissim.imageio import write_data_map

    depth = np.ascontiguousarray(depth_m, dtype=np.float32)
    if depth.ndim != 2 or np.isnan(depth).any() or (depth <= 0).any():
        raise VissimInputError(f"{path}: a depth map must be (H, W) positive metres or inf")
    if path.suffix.lower() != ".npy":
        return write_data_map(path, depth, channel="Z", provenance=provenance, overwrite=overwrite,
                              arcmin_per_px=arcmin_per_px)
    with atomic_output(path, overwrite=overwrite) as tmp:
        with open(tmp, "wb") as handle:
            np.save(handle, depth, allow_pickle=False)
    return path


def run_depth(args: argparse.Namespace) -> int:
    from vissim.bench.depth.scene import panel_geometries
    from vissim.bench.depth.scene_files import load_depth_scene_toml
    from vissim.bench.depth.viewers import frame_margin_px, viewing_setup
    from vissim.imageio import write_image
    from vissim.render.depth_render import render_depth

    _check_outputs(args)
    for name in ("spp", "aux_spp"):
        value = getattr(args, name)
        if value is not None and value < 1:
            option = "--" + name.replace("_", "-")
            raise VissimInputError(f"{option} must be a positive number of samples per pixel, got {value}")
    if args.margin_px is not None and args.margin_px < 0:
        raise VissimInputError(f"--margin-px must be a whole number of pixels >= 0, got {args.margin_px}")
    loaded = load_depth_scene_toml(args.scene, spp=args.spp, seed=args.seed, aux_spp=args.aux_spp)
    viewer = _viewer(args, loaded)
    margin = frame_margin_px(viewer, loaded.scene) if args.margin_px is None else args.margin_px
    auxiliary = args.all_in_focus is not None or args.depth is not None
    result = render_depth(
        loaded.scene, viewer, spp=loaded.spp, seed=loaded.seed, all_in_focus=args.all_in_focus is not None,
        depth=args.depth is not None, aux_spp=loaded.aux_spp, kind="rgb" if args.rgb else "mono", variant=args.variant,
        margin_px=margin if auxiliary else 0,
    )
    provenance = dict(result.provenance)
    provenance["inputs"] = dict(provenance["inputs"], scene_file=str(args.scene), command="render depth")
    step = loaded.scene.arcmin_per_px
    write_image(args.output, result.blurred, provenance=provenance, overwrite=args.overwrite, arcmin_per_px=step)
    written = [str(args.output)]
    if args.all_in_focus is not None:
        aif = dict(provenance, inputs=dict(provenance["inputs"], image="all_in_focus (pinhole at the pupil centre)"))
        write_image(args.all_in_focus, result.all_in_focus, provenance=aif, overwrite=args.overwrite, arcmin_per_px=step)
        written.append(str(args.all_in_focus))
    if args.depth is not None:
        depth = dict(provenance, inputs=dict(provenance["inputs"], image="axial depth, metres, inf = sky"))
        write_depth(args.depth, result.depth_m, provenance=depth, overwrite=args.overwrite, arcmin_per_px=step)
        written.append(str(args.depth))
    rows, cols = loaded.scene.size_px
    lines = [f"wrote {', '.join(written)}: {size_text((rows, cols))}, {result.spp} spp, {result.variant}, "
             f"{result.seconds:.1f} s; {viewer.label()}"]
    if result.margin_px:
        lines.append(f"  all-in-focus and depth: {size_text((rows + 2 * result.margin_px, cols + 2 * result.margin_px))} "
                     f"(a {result.margin_px} px margin beyond the frame; blur-depth crops it)")
    setup = viewing_setup(viewer, loaded.scene)
    panels = []
    for g in panel_geometries(loaded.scene):
        blur = [float(setup.blur_diameter_at_arcmin(d)) for d in (g.distance_left_m, g.distance_right_m)]
        where = f"{blur[0]:.1f}'" if g.kind == "panel" else f"{blur[0]:.1f}' (left) to {blur[1]:.1f}' (right)"
        lines.append(f"  {g.name}: predicted blur diameter {where}")
        panels.append({"name": g.name, "kind": g.kind, "blur_diameter_arcmin": blur if g.kind != "panel" else blur[0]})
    print_result(args, lines, {"size_px": [rows, cols], "spp": result.spp, "variant": result.variant,
                               "seconds": result.seconds, "viewer": viewer.label(), "margin_px": result.margin_px,
                               "panels": panels}, written, provenance)
    return 0
