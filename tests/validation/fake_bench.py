"""A stand-in for the Mitsuba bench in harness tests: magnification, geometric blur, seeded noise.

Picklable (module level) so process pools and Dask workers can run it.  Its optics come from the
ray-transfer matrices (``trial_lens_effect``) directly, not from the ``ViewingSetup`` the
simulations use, so harness tests would see a setup error.
"""

import numpy as np

from vissim.charts import optotype_tile
from vissim.optics.blur import blur_image
from vissim.optics.psf import compute_psf, suggested_size_px
from vissim.optics.trial_lens import entrance_pupil_diameter_mm, trial_lens_effect
from vissim.optics.wavefront import Wavefront
from vissim.validation.campaign import load_campaign
from vissim.validation.renders import bench_for
from vissim.optics.resample import magnify


def fake_render(spec):
    tile = optotype_tile(spec.letter, spec.logmar, arcmin_per_px=spec.arcmin_per_px, shape_px=spec.tile_px,
                         polarity=spec.polarity, viewing_distance_m=spec.chart_distance_m,
                         snap_to_pixels=False).pixels
    if spec.lenses:
        effect = trial_lens_effect(bench_for(spec).trial_lens_setup())
        front = Wavefront.from_prescription(effect.camera_prescription,
                                            entrance_pupil_diameter_mm(spec.focal_length_mm, spec.f_number))
        psf = compute_psf(front, arcmin_per_px=spec.arcmin_per_px, size_px=suggested_size_px(front, spec.arcmin_per_px),
                          mode="geometric")
        tile = blur_image(magnify(tile, effect.magnification_matrix), psf, arcmin_per_px=spec.arcmin_per_px, padding="edge")
    rng = np.random.default_rng(spec.seed)
    return (tile + rng.normal(0, 0.005, tile.shape)).astype(np.float32)


def refuse(spec):  # a renderer that must not be called
    raise AssertionError(f"re-rendered {spec}")


def write_campaign(directory, text: str, name: str = "tiny.toml"):
    """The campaign ``text`` written as ``directory / name`` and loaded."""
    path = directory / name
    path.write_text(text)
    return load_campaign(path)
