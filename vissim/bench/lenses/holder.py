"""The trial-lens holder's rules, shared by the DSLR and the eye bench: where the lenses sit, how wide
they are, how thick a thin one is made, and their shapes in a Mitsuba scene dict.

Frame: the viewer (the camera's entrance pupil, or the eye's corneal vertex) at z = 0 looking along
+z; the last lens's back vertex at ``vertex_mm``, the others stacked towards the chart with
``lens_gap_mm`` of air (lenses ordered from the chart to the viewer, as in `TrialLensSetup`).

* **Glass**: a thin lens (``refractive_index`` None) becomes a crown-glass lens
  (`CROWN_GLASS_INDEX` unless the bench says otherwise) of realistic centre thickness for the clear
  aperture (`vissim.bench.lenses.mesh.realistic_center_thickness_mm`, edge and centre at least
  `MIN_EDGE_MM` and `MIN_CENTER_MM`).
* **Clear aperture**: `lens_clear_aperture_mm`, the beam at the holder's far side x 1.25 + 2 mm.
* **Shapes**: PLY meshes with exact normals (`cached_lens_ply`) of the refraction-only
  ``vissim_refract`` BSDF; its dispersion is spectacle crown's in a spectral render and when a
  one-wavelength render names its wavelength (`lens_shapes`).

Nothing here imports Mitsuba.
"""

from __future__ import annotations

import math
from typing import Any

from vissim.bench.lenses.mesh import cached_lens_ply, realistic_center_thickness_mm
from vissim.optics.rx.trial_lens import MAX_LENSES_IN_HOLDER, TrialLens

__all__ = ["LENS_GAP_MM", "MIN_EDGE_MM", "MIN_CENTER_MM", "MESH_RINGS", "MESH_SEGMENTS", "lens_clear_aperture_mm",
           "physical_lens", "lens_back_vertex_z_mm", "lens_shapes"]

#: Air between lenses in the holder, mm.
LENS_GAP_MM = 2.0
#: Minimum edge and centre thickness of a trial lens made from a thin one, mm.
MIN_EDGE_MM = 1.0
MIN_CENTER_MM = 1.0
#: Tessellation of each lens surface: rings, and segments per ring.
MESH_RINGS = 16
MESH_SEGMENTS = 64


def lens_clear_aperture_mm(beam_diameter_mm: float, half_angle_rad: float, vertex_distance_mm: float,
                           lens_gap_mm: float) -> float:
    """The trial lenses' clear aperture, mm: the beam at the holder's far side (a ``beam_diameter_mm`` pupil's
    beam widened to ``half_angle_rad`` over the vertex distance + 3 lenses of <= 4 mm and their gaps) x 1.25
    + 2 mm, rounded up to 0.5 mm. The one rule, for the DSLR and the eye alike."""
    depth = vertex_distance_mm + MAX_LENSES_IN_HOLDER * (4.0 + lens_gap_mm)
    beam = beam_diameter_mm + 2.0 * depth * math.tan(half_angle_rad)
    return math.ceil(2.0 * (1.25 * beam + 2.0)) / 2.0


def physical_lens(lens: TrialLens, clear_aperture_mm: float, refractive_index: float) -> TrialLens:
    """``lens`` as rendered: a thick lens as it is; a thin one made of ``refractive_index`` (unless it names its
    own) with the realistic centre thickness for ``clear_aperture_mm``."""
    if not lens.is_thin:
        return lens
    index = lens.refractive_index or refractive_index
    thickness = realistic_center_thickness_mm(lens.marked_power, clear_aperture_mm, index, MIN_EDGE_MM,
                                              MIN_CENTER_MM, back_surface_diopters=lens.back_surface_diopters)
    return TrialLens(lens.sphere_diopters, lens.cylinder_diopters, lens.axis_deg, refractive_index=index,
                     center_thickness_mm=thickness, back_surface_diopters=lens.back_surface_diopters)


def lens_back_vertex_z_mm(lenses: tuple[TrialLens, ...], vertex_mm: float, lens_gap_mm: float) -> tuple[float, ...]:
    """World z of each physical lens's back vertex, in the order of ``lenses`` (chart to viewer)."""
    z, positions = vertex_mm, []
    for lens in reversed(lenses):
        positions.append(z)
        z += lens.center_thickness_mm + lens_gap_mm
    return tuple(reversed(positions))


def _translate(x: float, y: float, z: float) -> list[list[float]]:
    return [[1.0, 0.0, 0.0, x], [0.0, 1.0, 0.0, y], [0.0, 0.0, 1.0, z], [0.0, 0.0, 0.0, 1.0]]


def lens_shapes(lenses: tuple[TrialLens, ...], back_vertex_z_mm: tuple[float, ...], clear_aperture_mm: float, *,
                kind: str = "mono", lens_wavelength_nm: float | None = None,
                sensor_terminates_secondary: bool = False, fresnel_loss: bool = False,
                rings: int = MESH_RINGS, segments: int = MESH_SEGMENTS, mesh_cache_dir=None) -> dict[str, Any]:
    """``{"lens_i": shape}`` of the physical ``lenses`` at ``back_vertex_z_mm`` (module doc).

    The glass: spectacle crown, dispersive, in a ``"spectral"`` render (each path's hero wavelength;
    ``sensor_terminates_secondary`` when the sensor ends the other wavelengths itself) and when
    ``lens_wavelength_nm`` is given (a one-wavelength render: crown's index there); otherwise each lens's
    index at every wavelength."""
    shapes: dict[str, Any] = {}
    for i, (lens, z) in enumerate(zip(lenses, back_vertex_z_mm)):
        path = cached_lens_ply(lens, clear_aperture_mm, rings=rings, segments=segments, cache_dir=mesh_cache_dir)
        bsdf: dict[str, Any] = {"type": "vissim_refract", "int_ior": float(lens.refractive_index),
                                "fresnel_loss": bool(fresnel_loss)}
        if kind == "spectral":
            bsdf["dispersion"] = "crown"
            if sensor_terminates_secondary:
                bsdf["sensor_terminates_secondary"] = True
        elif lens_wavelength_nm is not None:
            bsdf.update(dispersion="crown", wavelength_nm=float(lens_wavelength_nm))
        shapes[f"lens_{i}"] = {"type": "ply", "filename": str(path), "face_normals": False,
                               "to_world": _translate(0.0, 0.0, z), "bsdf": bsdf}
    return shapes
