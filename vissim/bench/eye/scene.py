"""The eye bench's Mitsuba scene dict: the chart emitter, the lens meshes and the schematic-eye sensor.

The chart, its texture, the film and the integrator are `vissim.bench.scene_parts`'s, the lenses
the holder's (`vissim.bench.lenses.holder.lens_shapes`), as the DSLR bench's are; the sensor is
``vissim_schematic_eye`` (`vissim.render.schematic_eye_sensor`) at the corneal vertex, handed the
bench's `Eye` itself (`vissim.bench.eye.sensor_eyes.register_sensor_eye`) and turned by
`eye_to_world`.  The lenses' glass: spectacle crown, dispersive, at each path's hero wavelength in
photopic light (the sensor ends the others), else at the render's one wavelength.

Plain values only, as every bench's dict (`vissim.render.run.to_mitsuba_dict` converts them);
nothing here imports Mitsuba.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from vissim.bench.eye.bench import EyeBench
from vissim.bench.eye.sensor_eyes import register_sensor_eye
from vissim.bench.lenses.holder import lens_shapes
from vissim.bench.scene_parts import chart_emitter, chart_texture, hdr_film, path_integrator
from vissim.checks import samples_per_pixel, size_text
from vissim.optics.eyes.sight import eye_to_world_rotation

__all__ = ["eye_scene", "eye_sensor", "eye_to_world", "SENSOR_TYPE", "SAMPLER"]

#: The sensor's Mitsuba plugin (registered by `vissim.render.schematic_eye_sensor`).
SENSOR_TYPE = "vissim_schematic_eye"
#: The sensor's Mitsuba sampler.
SAMPLER = "independent"


def eye_to_world(eye, field_deg) -> list[list[float]]:
    """The sensor's to_world (4 x 4, corneal vertex at the origin) that turns the `SchematicEye` ``eye`` so
    that the world's +z (the chart's centre) lies at the field angle ``field_deg`` = (x, y) degrees, OSA's
    frame: `vissim.optics.eyes.sight.eye_to_world_rotation`, the one rule the simulations share."""
    out = np.eye(4)
    out[:3, :3] = eye_to_world_rotation(eye, field_deg)
    return out.tolist()


def _film_kind(bench: EyeBench) -> str:
    return "spectral" if bench.spectrum == "photopic" else "mono"


def eye_sensor(bench: EyeBench, spp: int, seed: int) -> dict[str, Any]:
    """The ``vissim_schematic_eye`` sensor of ``bench``: its eye handed over, turned to the field, ``spp``
    samples per pixel from ``seed``."""
    sensor: dict[str, Any] = {"type": SENSOR_TYPE, "eye_key": register_sensor_eye(bench.eye, bench.phase_plane),
                              "arcmin_per_px": float(bench.arcmin_per_px), "field_x_deg": float(bench.field_deg[0]),
                              "field_y_deg": float(bench.field_deg[1])}
    if bench.wavelength_nm is not None:
        sensor["wavelength_nm"] = float(bench.wavelength_nm)
    sensor.update({"to_world": eye_to_world(bench.eye.optics, bench.field_deg),
                   "film": hdr_film(bench.size_px, _film_kind(bench)),
                   "sampler": {"type": SAMPLER, "sample_count": samples_per_pixel(spp), "seed": int(seed)},
                   "far_clip": 10.0 * bench.chart_distance_mm})
    return sensor


def _chart(bench: EyeBench) -> dict[str, Any]:
    """The chart emitter: the printed letter cropped or padded to the bench's texture."""
    chart = bench.chart
    what = f"{size_text(bench.size_px)} eye image"
    texture, height_mm, width_mm = chart_texture(chart.pixels, bench.texture_shape, chart.mm_per_px, what)
    return chart_emitter(texture, height_mm, width_mm, bench.chart_distance_mm, kind=_film_kind(bench))


def eye_scene(bench: EyeBench, spp: int, seed: int, *, mesh_cache_dir=None) -> dict[str, Any]:
    """The Mitsuba scene dict of ``bench`` rendered at ``spp`` samples per pixel from ``seed`` (module doc)."""
    photopic = bench.spectrum == "photopic"
    scene: dict[str, Any] = {"type": "scene", "integrator": path_integrator(), "camera": eye_sensor(bench, spp, seed),
                             "chart": _chart(bench)}
    scene.update(lens_shapes(bench.physical_lenses, bench.lens_back_vertex_z_mm(), bench.clear_aperture_mm,
                             kind=_film_kind(bench), lens_wavelength_nm=None if photopic else bench.lens_wavelength_nm,
                             sensor_terminates_secondary=photopic, mesh_cache_dir=mesh_cache_dir))
    return scene
