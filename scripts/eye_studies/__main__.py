"""Run the eye studies on renders (this folder) and print their numbers, from the repository's root:

    PYTHONPATH=$PWD python -m scripts.eye_studies [focus] [edge] [wide]

Each study's run time is printed; on 2 cores: taskset -c 0,1 python -m scripts.eye_studies.
"""

from __future__ import annotations

import sys

from vissim.validation.engine.summary import PERFECT_MARGIN_DB
from . import chromatic_focus, slanted_edge, wide_chart


def print_focus() -> None:
    result = chromatic_focus()
    print(f"chromatic focus: {result.model}, {result.pupil_mm:g} mm pupil, Sloan K, trial lens in crown at 12 mm")
    for sweep in result.sweeps:
        print(f"  {sweep.wavelength_nm:.0f} nm: spheres {sweep.spheres_diopters[0]:+.4f}..{sweep.spheres_diopters[-1]:+.4f} D "
              f"({len(sweep.spheres_diopters)}), best {sweep.best_sphere_diopters:+.4f} D, paraxial prediction "
              f"{sweep.predicted_sphere_diopters:+.4f} D, {sweep.seconds:.1f} s")
    for w in (s.wavelength_nm for s in result.sweeps if s.wavelength_nm != 550.0):
        rendered = result.rendered_difference_diopters(w)
        predicted = result.predicted_difference_diopters(w)
        traced = result.traced_difference_diopters(w)
        print(f"  {w:.0f}-550 nm: rendered {rendered:+.4f} D; predicted {predicted:+.4f} D (eye paraxial LCA "
              f"{result.paraxial_lca_diopters[w]:+.4f} + lens and vertex {result.lens_share_diopters(w):+.4f}); "
              f"traced LCA {result.traced_lca_diopters[w]:+.4f} + lens = {traced:+.4f} D; |rendered - predicted| "
              f"{abs(rendered - predicted):.4f} D, |rendered - traced| {abs(rendered - traced):.4f} D")
    print(f"  run time {result.seconds:.1f} s")


def print_edge() -> None:
    result = slanted_edge()
    f = result.frequencies_cyc_per_deg
    print(f"slanted edge: navarro-1985, 4 mm, 550 nm, edge at {result.edge_angle_deg:+.3f} deg, "
          f"{len(result.render_mtfs)} seeds")
    print("  cyc/deg  render  1-seed sigma  traced(pipeline)  geometric(rays x nothing)")
    for i in range(1, len(f)):
        if f[i] <= 40.0:
            print(f"  {f[i]:6.2f}  {result.render_mtf[i]:.4f}  {result.seed_sigma[i]:.4f}  {result.traced_mtf[i]:.4f}  "
                  f"{result.geometric_mtf[i]:.4f}")
    for top in (15.0, 30.0, 60.0):
        print(f"  <= {top:g} cyc/deg: worst |render - traced| {result.worst_deviation(top):.4f}, "
              f"= {result.worst_deviation_in(result.seed_sigma, top):.2f} one-render sigma, "
              f"{result.worst_deviation_in(result.standard_error, top):.2f} standard errors of the mean")
    print(f"  run time {result.seconds:.1f} s")


def print_wide() -> None:
    result = wide_chart()
    print("wide chart 0-20 deg: navarro-1985, 4 mm, reference wavelength, geometric; PSNR dB vs the render")
    for band in result.noise_floor_db:
        print(f"  {band}: field-dependent {result.field_dependent_db[band]:.2f}, single on-axis PSF "
              f"{result.single_psf_db[band]:.2f}, render noise floor {result.noise_floor_db[band]:.2f} "
              f"(a perfect simulation: floor + {PERFECT_MARGIN_DB:.2f})")
    print(f"  run time {result.seconds:.1f} s (renders {result.render_seconds:.1f} s, simulations "
          f"{result.simulation_seconds:.1f} s)")


STUDIES = {"focus": print_focus, "edge": print_edge, "wide": print_wide}

if __name__ == "__main__":
    chosen = sys.argv[1:] or list(STUDIES)
    unknown = [name for name in chosen if name not in STUDIES]
    if unknown:
        sys.exit(f"unknown study {unknown[0]!r}; choose from {', '.join(STUDIES)}")
    for name in chosen:
        STUDIES[name]()
