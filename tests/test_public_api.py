"""The top-level ``vissim`` namespace: the names a user needs, loaded lazily, without Mitsuba."""

import subprocess
import sys

import vissim

# The user's path through the library (issue 16): Rx -> wavefront -> PSF -> image, charts,
# depth scenes, the bench render, fitting, campaigns, ATV data.
EXPECTED = {
    "Prescription", "parse_spherocylinder", "Wavefront", "PSF", "compute_psf", "strehl_ratio", "mtf",
    "otf", "diffraction_mtf", "frequencies_cyc_per_deg", "blur_image", "etdrs_chart_spec",
    "single_letter_spec", "render_chart_angular", "render_chart_print", "blur_depth", "DslrBench",
    "render_bench", "fit_rx", "RxFit",
    "load_campaign", "run_campaign", "load_subject", "load_directory", "analyse_subject", "fit_quadratic",
}


def test_public_names_are_listed_and_resolve_to_their_defining_objects():
    assert EXPECTED <= set(vissim.__all__)
    for name in EXPECTED:
        obj = getattr(vissim, name)
        assert obj.__module__.startswith("vissim."), name
        assert obj.__doc__, f"vissim.{name} has no docstring"


def test_an_unknown_name_raises_attribute_error():
    try:
        vissim.no_such_function  # noqa: B018
    except AttributeError as exc:
        assert "no_such_function" in str(exc)
    else:
        raise AssertionError("expected AttributeError")


def test_importing_every_public_name_does_not_import_mitsuba():
    code = ("import sys, vissim\n"
            "[getattr(vissim, n) for n in vissim.__all__]\n"
            "print(sorted(m for m in ('mitsuba', 'drjit') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_the_psf_docstring_example_runs():
    import doctest

    import vissim.optics.psf as module

    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted >= 3 and result.failed == 0


def test_the_cheap_docstring_examples_run():
    """The Examples of the public names that need neither Mitsuba nor files (those are +SKIP)."""
    import doctest
    import importlib

    modules = ("vissim.optics.prescription", "vissim.optics.wavefront", "vissim.optics.blur", "vissim.charts",
               "vissim.fit.rx_fit", "vissim.validation.campaign", "vissim.validation.runner", "vissim.atv.analysis",
               "vissim.render.run", "vissim.optics.psf_metrics", "vissim.optics.depth", "vissim.atv.data",
               "vissim.bench.dslr")
    attempted = 0
    for name in modules:
        result = doctest.testmod(importlib.import_module(name), optionflags=doctest.NORMALIZE_WHITESPACE)
        assert result.failed == 0, name
        attempted += result.attempted
    assert attempted >= 20
