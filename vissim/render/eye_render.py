"""A letter chart at a distance seen by a schematic eye (`vissim_schematic_eye`), optionally through a trial lens.

The scene is the DSLR bench's (`vissim.bench.dslr.bench.dslr_scene`: a self-emitting chart of
radiance = its reflectance facing the observer at ``chart_distance_m``, a trial lens mesh of
``vissim_refract`` crown glass, dispersive as the exact trace's, with its back vertex ``vertex_mm`` in
front of the eye; the letter sized for the chart's distance: `eye_chart`), with its
``thinlens`` camera replaced by the schematic-eye sensor at the corneal vertex.  The bench's
camera pupil is set to the eye's entrance pupil so the lens mesh is sized for the eye's beam.
``field_deg`` turns the eye about its corneal vertex so that the chart's centre lies at that field
angle from the eye's optical axis (OSA's frame: x the examiner's right, the observer's left; y up); the image stays centred on the chart
(`eye_to_world`), seen through the trial lens's centre.

Wavelength: ``wavelength_nm`` (monochromatic; default the model's reference) on the mono
variant, or ``spectrum="photopic"``: the spectral variant, hero wavelength per path, the film
developing luminance (CIE ȳ = V(λ)).  Determinism: `vissim.render.run.render_scene` (fixed-order
accumulation): the same seed gives the same pixels.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from vissim.errors import VissimInputError
from vissim.optics.eyes.defaults import DEFAULT_EYE_MODEL, DEFAULT_EYE_PUPIL_MM, DEFAULT_SPECTACLE_VERTEX_MM

__all__ = ["EyeRender", "eye_bench", "eye_chart", "eye_scene_dict", "eye_to_world", "render_eye", "SPECTRA"]

SPECTRA = ("mono", "photopic")


@dataclass(frozen=True)
class EyeRender:
    """What to render (module doc); pupil: exactly one of ``pupil_mm`` (entrance pupil) and ``iris_mm``."""

    model: str = DEFAULT_EYE_MODEL
    accommodation_diopters: float = 0.0
    pupil_mm: float | None = DEFAULT_EYE_PUPIL_MM
    iris_mm: float | None = None
    field_deg: tuple[float, float] = (0.0, 0.0)
    wavelength_nm: float | None = None
    spectrum: str = "mono"
    size_px: tuple[int, int] = (64, 64)
    arcmin_per_px: float = 1.0
    spp: int = 64
    seed: int = 0
    chart_distance_m: float = 6.0
    letter: str = "K"
    logmar: float = 1.0
    lens: tuple[float, float, float] | None = None  # sphere D, cylinder D, axis deg
    vertex_mm: float = DEFAULT_SPECTACLE_VERTEX_MM
    rx: str | None = None  # the eye made to need this prescription at the spectacle plane vertex_mm
    surfaces: tuple = ()  # the model's surfaces altered: sorted (surface name, field, value) triples

    @classmethod
    def for_eye(cls, eye, **view) -> EyeRender:
        """The render of the `Eye` ``eye`` (a named model, its surfaces altered or not), ``view`` the other fields."""
        from vissim.optics.eyes.eye import surface_overrides
        from vissim.optics.prescription import Prescription

        pupil = {"pupil_mm": eye.pupil_mm, "iris_mm": None} if eye.iris_mm is None else \
            {"pupil_mm": None, "iris_mm": eye.iris_mm}
        if eye.wavelength_nm is not None and eye.wavelength_nm != eye.schematic.reference_wavelength_nm:
            raise VissimInputError("render eye maps its film through the model's reference wavelength; an eye with "
                                   f"another ({eye.wavelength_nm:g} nm) cannot be rendered")
        if eye.rx is not None and not eye.rx.is_close(Prescription.parse(str(eye.rx))):
            raise VissimInputError(f"render eye holds a prescription in 0.01 D steps and whole degrees; "
                                   f"{eye.rx.format(4)} is not one")
        return cls(model=eye.model, accommodation_diopters=eye.accommodation_diopters, rx=eye.rx and str(eye.rx),
                   vertex_mm=eye.vertex_mm, surfaces=surface_overrides(eye.schematic), **pupil, **view)

    @property
    def eye(self):
        """The `Eye` rendered: the model at its accommodation, its surfaces altered, its pupil and prescription."""
        from vissim.optics.eyes.eye import eye_from_fields

        return eye_from_fields(self.model, self.accommodation_diopters, self.pupil_mm, self.iris_mm, self.rx,
                               self.vertex_mm, self.surfaces)

    def __post_init__(self) -> None:
        if self.spectrum not in SPECTRA:
            raise VissimInputError(f"spectrum must be one of {', '.join(SPECTRA)}, got {self.spectrum!r}")
        if self.spectrum == "photopic" and self.wavelength_nm is not None:
            raise VissimInputError("give a wavelength (monochromatic) or the photopic spectrum, not both")
        from vissim.checks import arcmin_per_px, eye_pupil_diameter_mm, finite_number, number_within, positive_number
        from vissim.charts import single_letter_spec
        from vissim.checks import EYE_RENDER_MAX_FIELD_DEG, EYE_RENDER_WAVELENGTH_RANGE_NM, LOGMAR_RANGE
        if self.rx is not None:
            from vissim.optics.prescription import Prescription

            object.__setattr__(self, "rx", str(Prescription.parse(self.rx)))
        object.__setattr__(self, "surfaces", tuple(tuple(t) for t in self.surfaces))
        if (self.pupil_mm is None) == (self.iris_mm is None):
            raise VissimInputError("give the entrance pupil (pupil_mm) or the iris (iris_mm), not both or neither")
        eye_pupil_diameter_mm(self.pupil_mm if self.iris_mm is None else self.iris_mm,
                              "entrance pupil" if self.iris_mm is None else "iris")
        for value in self.field_deg:
            if abs(finite_number(value, "field angle", "deg")) > EYE_RENDER_MAX_FIELD_DEG:
                raise VissimInputError(f"field angle {value:g} deg: the eye sensor renders within "
                                       f"{EYE_RENDER_MAX_FIELD_DEG:g} deg of the axis")
        if self.wavelength_nm is not None:
            number_within(self.wavelength_nm, "wavelength", "nm", EYE_RENDER_WAVELENGTH_RANGE_NM)
        arcmin_per_px(self.arcmin_per_px)
        positive_number(self.chart_distance_m, "chart distance", "m")
        number_within(self.logmar, "letter size", "logMAR", LOGMAR_RANGE)
        single_letter_spec(self.letter, self.logmar, viewing_distance_m=self.chart_distance_m)  # a Sloan letter
        positive_number(self.vertex_mm, "vertex distance", "mm")
        if int(self.spp) < 1:
            raise VissimInputError(f"samples per pixel must be >= 1, got {self.spp}")
        self.eye  # the eye's own checks: its model's name and accommodation range, its surfaces, its prescription


def _clear_aperture_mm(settings: EyeRender, pupil_mm: float) -> float:
    """The lens mesh's diameter: the bench's rule (`lens_clear_aperture_mm`) for the widest direction the image
    looks along, field offset included, and a beam 1.2 x ``pupil_mm`` (an iris's entrance pupil is <= ~1.13 x it)."""
    from vissim.bench.dslr.bench import DslrBench, lens_clear_aperture_mm

    rows, cols = settings.size_px
    half_deg = [abs(f) + 0.5 * n * settings.arcmin_per_px / 60.0 for f, n in zip(settings.field_deg, (cols, rows))]
    return lens_clear_aperture_mm(1.2 * pupil_mm, math.radians(math.hypot(*half_deg)), settings.vertex_mm,
                                  DslrBench.lens_gap_mm)


def eye_to_world(eye, field_deg) -> list[list[float]]:
    """The sensor's to_world (4 x 4, corneal vertex at the origin) that turns the `SchematicEye` ``eye`` so
    that the world's +z (the chart's centre) lies at the field angle ``field_deg`` = (x, y) degrees, OSA's
    frame: `vissim.optics.eyes.sight.eye_to_world_rotation`, the one rule the simulations share."""
    from vissim.optics.eyes.sight import eye_to_world_rotation

    out = np.eye(4)
    out[:3, :3] = eye_to_world_rotation(eye, field_deg)
    return out.tolist()


def eye_bench(settings: EyeRender):
    """The DSLR bench the scene is built from: its camera pupil the eye's (``pupil_mm`` or ``iris_mm``), the
    trial lens's clear aperture by the bench's rule for the widest direction the image looks along."""
    from vissim.bench.dslr.bench import DslrBench
    from vissim.optics.trial_lens import TrialLens

    pupil_mm = settings.pupil_mm or settings.iris_mm
    distance_mm = 1000.0 * settings.chart_distance_m
    focal_mm = 18.0
    return DslrBench(focal_length_mm=focal_mm, f_number=focal_mm / pupil_mm, focus_distance_mm=distance_mm,
                     chart_distance_mm=distance_mm, vertex_distance_mm=settings.vertex_mm,
                     clear_aperture_mm=_clear_aperture_mm(settings, pupil_mm),
                     lenses=() if settings.lens is None else (TrialLens(*settings.lens),),
                     arcmin_per_px=settings.arcmin_per_px, size_px=tuple(settings.size_px), spp=settings.spp,
                     seed=settings.seed, sampler="independent")


def eye_chart(settings: EyeRender, bench):
    """The printed chart (`vissim.charts.render_chart_print`): the letter sized for ``chart_distance_m``, so it
    subtends ``logmar`` there, at the texel pitch the bench's texture needs."""
    from vissim.bench.dslr.bench import chart_mm_per_texel
    from vissim.charts import MM_PER_INCH, render_chart_print, single_letter_spec

    spec = single_letter_spec(settings.letter, settings.logmar, viewing_distance_m=settings.chart_distance_m)
    return render_chart_print(spec, MM_PER_INCH / chart_mm_per_texel(bench))


def eye_scene_dict(settings: EyeRender) -> dict:
    """The plain scene dict (module doc); its camera is the schematic-eye sensor, handed the eye itself."""
    from vissim.bench.dslr.bench import dslr_scene

    from vissim.render.schematic_eye_sensor import register_sensor_eye

    sensor = {"type": "vissim_schematic_eye", "eye_key": register_sensor_eye(settings.eye),
              "arcmin_per_px": float(settings.arcmin_per_px), "field_x_deg": float(settings.field_deg[0]),
              "field_y_deg": float(settings.field_deg[1])}
    if settings.wavelength_nm is not None:
        sensor["wavelength_nm"] = float(settings.wavelength_nm)
    bench = eye_bench(settings)
    chart = eye_chart(settings, bench)
    eye = settings.eye.optics
    if settings.spectrum == "photopic":  # crown at each path's hero wavelength; the sensor ends the others
        scene = dslr_scene(bench, chart.pixels, chart.mm_per_px, kind="spectral", sensor_terminates_secondary=True)
    else:
        scene = dslr_scene(bench, chart.pixels, chart.mm_per_px, kind="mono",
                           lens_wavelength_nm=settings.wavelength_nm or eye.reference_wavelength_nm)
    camera = scene["camera"]
    # the bench's camera sits at the origin looking along +z (identity): the eye takes its place, turned
    turn = eye_to_world(eye, settings.field_deg)
    sensor.update({"to_world": turn, "film": camera["film"], "sampler": camera["sampler"],
                   "far_clip": 10.0 * bench.chart_distance_mm})
    scene["camera"] = sensor
    return scene


def render_eye(settings: EyeRender, variant: str | None = None):
    """Render ``settings`` (module doc); a `vissim.render.run.RenderResult` with provenance."""
    from vissim.provenance import json_safe, make_provenance
    from vissim.render.backend import choose_variant, mitsuba
    from vissim.render.run import mitsuba_versions, render_scene
    from vissim.render.schematic_eye_sensor import register_schematic_eye_sensor

    chosen = choose_variant("spectral" if settings.spectrum == "photopic" else "mono", variant).variant
    register_schematic_eye_sensor(mitsuba("mono", chosen))
    result = render_scene(eye_scene_dict(settings), kind="mono", spp=settings.spp, seed=settings.seed,
                          variant=chosen)
    provenance = make_provenance(command="render eye", eye=dataclasses.asdict(settings), variant=result.variant,
                                 spp=result.spp, seed=result.seed, render_seconds=round(result.seconds, 3),
                                 mitsuba_render=result.render_record(), **mitsuba_versions())
    return dataclasses.replace(result, provenance=json_safe(provenance))
