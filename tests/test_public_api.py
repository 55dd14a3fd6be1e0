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

    import vissim.optics.psf.compute as module

    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted >= 3 and result.failed == 0


def test_the_cheap_docstring_examples_run():
    """The Examples of the public names that need neither Mitsuba nor files (those are +SKIP)."""
    import doctest
    import importlib

    modules = ("vissim.optics.rx.prescription", "vissim.optics.pupil.wavefront", "vissim.optics.blur.convolve", "vissim.charts",
               "vissim.fit.rx_fit", "vissim.validation.engine.loader", "vissim.validation.engine.runner", "vissim.atv.analysis",
               "vissim.render.run", "vissim.optics.psf.metrics", "vissim.optics.depth.depth_map", "vissim.atv.data",
               "vissim.bench.dslr.bench", "vissim.spectra", "vissim.optics.pupil.spectral_wavefront")
    attempted = 0
    for name in modules:
        result = doctest.testmod(importlib.import_module(name), optionflags=doctest.NORMALIZE_WHITESPACE)
        assert result.failed == 0, name
        attempted += result.attempted
    assert attempted >= 20


# -- wrong argument types: one error at once, saying what is accepted ------------------------
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from vissim.errors import VissimInputError, VissimTypeError  # noqa: E402


def _front():
    return vissim.Wavefront.from_prescription(vissim.Prescription(-1.0), 3.0)


def _psf():
    return vissim.compute_psf(_front(), arcmin_per_px=1.0, size_px=64)


IMAGE = np.ones((32, 32), np.float32)

# (call, a fragment of what the error says is accepted); each used to fail deep inside (or not at all)
WRONG_TYPES = [
    (lambda: vissim.compute_psf("-2.00 DS", pupil_diameter_mm=3.0), "must be a Wavefront or an OpdMap"),
    (lambda: vissim.compute_psf(vissim.Prescription(-2.0)), "must be a Wavefront or an OpdMap"),
    (lambda: vissim.strehl_ratio(_psf()), "must be a Wavefront or an OpdMap"),
    (lambda: vissim.blur_image(IMAGE, _front(), arcmin_per_px=1.0), "psf must be a PSF"),
    (lambda: vissim.blur_image(IMAGE, "psf", arcmin_per_px=1.0), "psf must be a PSF"),
    (lambda: vissim.blur_image("chart.png", _psf(), arcmin_per_px=1.0), "image must be an ndarray"),
    (lambda: vissim.Prescription("-2.00 DS"), "Prescription.parse"),
    (lambda: vissim.Wavefront("2,0=0.5", 3.0), "must be a mapping {(n, m): µm}"),
    (lambda: vissim.Wavefront(vissim.Prescription(-1.0), 3.0), "Wavefront.from_prescription"),
    (lambda: vissim.Wavefront({"defocus": 0.5}, 3.0), "tuple (n, m) of integers"),
    (lambda: vissim.Wavefront.from_prescription("-2 DS", 3.0), "vissim.Prescription.parse"),
    (lambda: vissim.mtf(_front()), "must be a PSF"),
    (lambda: vissim.otf(IMAGE), "must be a PSF"),  # an ndarray has a .data buffer: it used to pass
    (lambda: vissim.frequencies_cyc_per_deg(_front()), "must be a PSF"),
    (lambda: vissim.fit_rx("a.png", "b.png", arcmin_per_px=1.0, pupil_diameter_mm=3.0), "must be an ndarray"),
    (lambda: vissim.blur_depth(IMAGE, "depth.exr", rx=vissim.Prescription(-1.0),
                               pupil_diameter_mm=3.0, arcmin_per_px=1.0), "depth_m must be an ndarray"),
    (lambda: vissim.etdrs_chart_spec(letters=5), "letters must be a str"),
    (lambda: vissim.render_chart_angular("K"), "must be a ChartSpec"),
    (lambda: vissim.etdrs_chart_spec("1,0"), "logmar_range must be (first, last) LogMAR"),
    (lambda: vissim.parse_spherocylinder(-2.0), "must be text such as '-2.00 -1.25 x 180'"),
    (lambda: vissim.PSF.from_array("kernel", 1.0), "a PSF's data must be a number or a sequence of numbers"),
    (lambda: vissim.render_bench("bench", vissim.single_letter_spec("K", 1.0)), "must be a DslrBench"),
    (lambda: vissim.render_bench(vissim.DslrBench(), IMAGE), "must be a ChartSpec"),
    (lambda: vissim.load_campaign(5), "must be a path (str or pathlib.Path)"),
    (lambda: vissim.run_campaign("validation/quick.toml", "runs/x"), "must be a Campaign (from vissim.load_campaign"),
    (lambda: vissim.load_subject(None), "must be a path (str or pathlib.Path)"),
    (lambda: vissim.load_directory(5), "must be a path (str or pathlib.Path)"),
    (lambda: vissim.analyse_subject("subject_001.json"), "must be a SubjectData (from vissim.load_subject"),
    (lambda: vissim.fit_quadratic("a", "b"), "must be a number or a sequence of numbers in D"),
    (lambda: vissim.render_chart_print("K"), "must be a ChartSpec"),
    (lambda: vissim.build_eye("navarro-1985", pupil_diameter_mm=3.0, rx=-1.0), "expected a Prescription (the correcting lens)"),
    (lambda: vissim.Eye("navarro-1985"), "must be a SchematicEye"),
    (lambda: vissim.eye_wavefront(5, wavelength_nm=555.0), "must be an Eye (vissim.build_eye)"),
    (lambda: vissim.eye_spectral_wavefront(None, wavelengths_nm=[500.0, 600.0]), "must be an Eye (vissim.build_eye)"),
    (lambda: vissim.SpectralWavefront((500.0,), ("2,0=0.1",)), "must be a Wavefront"),
    (lambda: vissim.named_spectrum(5), "must be text, one of photopic"),
    (lambda: vissim.blur_eye("chart.png", vissim.build_eye("navarro-1985"), arcmin_per_px=1.0, wavelength_nm=555.0),
     "image must be an ndarray"),
]


@pytest.mark.parametrize("call, accepted", WRONG_TYPES)
def test_a_wrong_argument_type_is_one_type_error_saying_what_is_accepted(call, accepted):
    with pytest.raises(VissimTypeError) as caught:
        call()
    assert isinstance(caught.value, TypeError) and isinstance(caught.value, VissimInputError)
    message = str(caught.value)
    assert accepted in message and "\n" not in message and len(message) < 300, message


@pytest.mark.parametrize("call, fragment", [
    (lambda: vissim.strehl_ratio(_front(), wavelength_nm="green"), "wavelength must be a number in nm"),
    (lambda: vissim.strehl_ratio(_front(), pupil_diameter_mm=-1.0), "pupil diameter must be a positive"),
    (lambda: vissim.strehl_ratio(_front(), pupil_diameter_mm=9.0), "larger than the 3 mm pupil"),
    (lambda: vissim.compute_psf(_front(), size_px=None), "PSF size must be an integer"),
    (lambda: vissim.compute_psf(_front(), weights="heavy"), "one non-negative weight per wavelength"),
    (lambda: vissim.compute_psf(_front(), lca_reference_nm=-5.0), "LCA reference wavelength"),
    (lambda: vissim.diffraction_mtf("high", 3.0, 550.0), "cycles/degree"),
    (lambda: vissim.blur_image(IMAGE, _psf(), arcmin_per_px=float("nan")), "arcmin per pixel"),
    (lambda: vissim.DslrBench(focal_length_mm="long"), "focal length mm must be a number in mm"),
    (lambda: vissim.single_letter_spec(5, 1.0), "unknown Sloan letter '5'"),
    (lambda: vissim.build_eye("navaro", pupil_diameter_mm=3.0), "unknown eye model 'navaro'"),
    (lambda: vissim.eye_wavefront("navarro-1985"), "takes an Eye, not the name 'navarro-1985'"),
    (lambda: vissim.build_eye("navarro-1985", pupil_diameter_mm=3.0, iris_mm=3.0), "not both"),
    (lambda: vissim.build_eye("navarro-1985", surfaces={"cornea": {"conic": 0.0}}), "has no surface 'cornea'"),
    (lambda: vissim.build_eye("navarro-1985", surfaces={"cornea front": {"conic": "flat"}}), "must be a finite number"),
])
def test_a_bad_value_is_one_input_error_naming_it_and_its_unit(call, fragment):
    with pytest.raises(VissimInputError, match=fragment.replace("(", r"\(")):
        call()


def test_every_public_entry_point_is_called_with_a_wrong_argument_above():
    """The two lists above reach every public function and class: a new one must join them."""
    import inspect

    source = inspect.getsource(inspect.getmodule(test_every_public_entry_point_is_called_with_a_wrong_argument_above))
    listed = source[source.index("WRONG_TYPES = ["):source.index("def test_right_types_still_give_the_physics")]
    made_by_vissim = {"__version__", "RxFit"}  # RxFit is fit_rx's result, not built by users
    missing = [n for n in vissim.__all__ if n not in made_by_vissim and f"vissim.{n}(" not in listed
               and f"vissim.{n}." not in listed]
    assert not missing, missing


def test_right_types_still_give_the_physics():
    """Oracle: a zero wavefront's Strehl ratio is 1 by definition, and a PSF's MTF is 1 at zero frequency."""
    assert vissim.strehl_ratio(vissim.Wavefront.zero(3.0)) == pytest.approx(1.0, abs=1e-9)
    psf = _psf()
    assert vissim.mtf(psf)[32, 32] == pytest.approx(1.0, abs=1e-6)


def test_dir_lists_only_the_public_names():
    assert dir(vissim) == sorted(vissim.__all__)
    assert not {"annotations", "importlib", "logging"} & set(dir(vissim))
    assert not [name for name in vars(vissim) if not name.startswith("_") and name not in vissim.__all__
                and not isinstance(getattr(vissim, name), type(vissim))]  # submodules aside


def test_the_rx_fit_repr_is_one_short_line_with_the_fitted_power_and_residual():
    """A fit's record (as_json) runs to kilobytes; its repr is one line with the power and the residual."""
    from vissim.fit.result import RxFit, Solution

    best = Solution(power_vector=(-2.25, 0.5, 0.0), covariance=np.eye(3) * 1e-4, ssr=1.5, parameters=np.zeros(5))
    fit = RxFit(status="ok", reason=None, best=best, alternatives=((best, 120.0),) * 3, sign_delta_chi2=120.0,
                axis_determined=True, residual_psnr_db=42.5, residual_sigma=0.003, unexplained_fraction=0.0012,
                nuisances={"shift_px": [0.1, -0.2], "gain": 1.01}, settings={"mode": "geometric"}, evaluations=694,
                seconds=1.6, model=np.zeros((64, 64)))
    text = repr(fit)
    assert len(text) < 250 and "\n" not in text, text
    assert str(fit.effective_power) in text and "M -2.250 D" in text and "residual PSNR 42.5 dB" in text
    failed = RxFit(status="failed", reason="no letter found", best=best, alternatives=(), sign_delta_chi2=None,
                   axis_determined=False, residual_psnr_db=3.0, residual_sigma=0.3, unexplained_fraction=0.9,
                   nuisances={}, settings={}, evaluations=10, seconds=0.1, model=np.zeros((4, 4)))
    assert "status='failed'" in repr(failed) and "no letter found" in repr(failed)
