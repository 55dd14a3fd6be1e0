"""A stand-in for the Mitsuba bench in harness tests: magnification, geometric blur, seeded noise.

Picklable (module level) so process pools and Dask workers can run it.  Its optics come from the
ray-transfer matrices (``trial_lens_effect``) directly, not from the ``ViewingSetup`` the
simulations use, so harness tests would see a setup error.
"""

import numpy as np

from vissim.charts import optotype_tile
from vissim.optics.blur.convolve import blur_image
from vissim.optics.psf.compute import compute_psf, suggested_size_px
from vissim.optics.rx.trial_lens import entrance_pupil_diameter_mm, trial_lens_effect
from vissim.optics.pupil.wavefront import Wavefront
from vissim.validation.engine.loader import load_campaign

from vissim.optics.blur.resample import magnify


def fake_render(spec):
    bench = spec.bench
    step = bench.arcmin_per_px
    tile = optotype_tile(spec.letter, spec.logmar, arcmin_per_px=step, size_px=bench.size_px,
                         polarity=spec.polarity, viewing_distance_m=bench.chart_distance_mm / 1000.0,
                         snap_to_pixels=False).pixels
    if bench.lenses:
        effect = trial_lens_effect(bench.trial_lens_setup())
        front = Wavefront.from_prescription(effect.camera_prescription,
                                            entrance_pupil_diameter_mm(bench.focal_length_mm, bench.f_number))
        psf = compute_psf(front, arcmin_per_px=step, size_px=suggested_size_px(front, step), mode="geometric")
        tile = blur_image(magnify(tile, effect.magnification_matrix), psf, arcmin_per_px=step, padding="edge")
    rng = np.random.default_rng(bench.seed)
    return (tile + rng.normal(0, 0.005, tile.shape)).astype(np.float32)


def refuse(spec):  # a renderer that must not be called
    raise AssertionError(f"re-rendered {spec}")


def write_campaign(directory, text: str, name: str = "tiny.toml"):
    """The campaign ``text`` written as ``directory / name`` and loaded."""
    path = directory / name
    path.write_text(text)
    return load_campaign(path)
