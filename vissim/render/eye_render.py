"""A letter chart at a distance seen by a schematic eye (`vissim_schematic_eye`), optionally through a trial lens.

`EyeRender` is what ``vissim render eye`` asks for, in plain fields (the eye by its model's name, its
accommodation, surfaces, pupil and prescription; the chart; the lens; the image; the sampling);
`eye_bench` builds the eye bench it describes (`vissim.bench.eye.bench.EyeBench`: the chart of
radiance = its reflectance facing the eye at ``chart_distance_m``, the trial lens of crown glass with
its back vertex ``vertex_mm`` in front of the eye, the schematic-eye sensor at the corneal vertex,
turned so that the chart's centre lies at ``field_deg``) and `render_eye_bench` renders a bench at a
sample count and seed (the scene: `vissim.bench.eye.scene.eye_scene`).

Wavelength: ``wavelength_nm`` (monochromatic; default `DEFAULT_EYE_LIGHT_NM`, as in a campaign) on the mono
variant, or ``spectrum="photopic"``: the spectral variant, hero wavelength per path, the film
developing luminance (CIE ȳ = V(λ)).  Determinism: `vissim.render.run.render_scene` (fixed-order
accumulation): the same seed gives the same pixels.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from typing import TYPE_CHECKING

from vissim.errors import VissimInputError
from vissim.optics.eyes.defaults import (DEFAULT_CHART_DISTANCE_M, DEFAULT_EYE_ARCMIN_PER_PX, DEFAULT_EYE_MODEL,
                                         DEFAULT_EYE_PUPIL_MM, DEFAULT_EYE_SIZE_PX, DEFAULT_LETTER,
                                         DEFAULT_LETTER_LOGMAR, DEFAULT_SPECTACLE_VERTEX_MM)

if TYPE_CHECKING:
    from vissim.bench.eye.bench import EyeBench

__all__ = ["EyeRender", "eye_bench", "eye_scene_dict", "render_eye", "render_eye_bench"]


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
    size_px: tuple[int, int] = DEFAULT_EYE_SIZE_PX
    arcmin_per_px: float = DEFAULT_EYE_ARCMIN_PER_PX
    spp: int = 64
    seed: int = 0
    chart_distance_m: float = DEFAULT_CHART_DISTANCE_M
    letter: str = DEFAULT_LETTER
    logmar: float = DEFAULT_LETTER_LOGMAR
    lens: tuple[float, float, float] | None = None  # sphere D, cylinder D, axis deg
    vertex_mm: float = DEFAULT_SPECTACLE_VERTEX_MM
    rx: object = None  # a Prescription (or its text): the eye made to need it at the spectacle plane vertex_mm
    surfaces: tuple = ()  # the model's surfaces altered: sorted (surface name, field, value) triples

    @classmethod
    def for_eye(cls, eye, **view) -> EyeRender:
        """The render of the `Eye` ``eye`` (a named model, its surfaces altered or not), ``view`` the other fields."""
        from vissim.optics.eyes.eye import surface_overrides

        pupil = {"pupil_mm": eye.pupil_diameter_mm, "iris_mm": None} if eye.iris_mm is None else \
            {"pupil_mm": None, "iris_mm": eye.iris_mm}
        if eye.wavelength_nm is not None and eye.wavelength_nm != eye.schematic.reference_wavelength_nm:
            raise VissimInputError("render eye maps its film through the model's reference wavelength; an eye with "
                                   f"another ({eye.wavelength_nm:g} nm) cannot be rendered")
        return cls(model=eye.model, accommodation_diopters=eye.accommodation_diopters, rx=eye.rx,
                   vertex_mm=eye.vertex_distance_mm, surfaces=surface_overrides(eye.schematic), **pupil, **view)

    def as_json(self) -> dict:
        """The settings as plain values, the prescription written in full (to 1e-6 D)."""
        return dict(dataclasses.asdict(self), rx=None if self.rx is None else self.rx.format(6))

    @property
    def eye(self):
        """The `Eye` rendered: the model at its accommodation, its surfaces altered, its pupil and prescription."""
        from vissim.optics.eyes.eye import eye_from_fields

        return eye_from_fields(self.model, self.accommodation_diopters, self.pupil_mm, self.iris_mm, self.rx,
                               self.vertex_mm, self.surfaces)

    def __post_init__(self) -> None:
        from vissim.checks import eye_pupil_diameter_mm, sampler_seed, samples_per_pixel, vertex_distance_mm

        if self.rx is not None:  # a Prescription, or its text once read: held as the number, never as text
            from vissim.optics.rx.prescription import prescription_from

            object.__setattr__(self, "rx", prescription_from(self.rx))
        object.__setattr__(self, "surfaces", tuple(tuple(t) for t in self.surfaces))
        from vissim.bench.eye.bench import EyeBench  # the bench's numerical code when settings are made, not read

        object.__setattr__(self, "wavelength_nm", EyeBench.light_nm(self.wavelength_nm, self.spectrum))
        if (self.pupil_mm is None) == (self.iris_mm is None):
            raise VissimInputError("give the entrance pupil's diameter or the iris's, not both or neither (a scene "
                                   "file's [eye] pupil_diameter_mm or iris_mm; --pupil-mm or --iris-mm)")
        eye_pupil_diameter_mm(self.pupil_mm if self.iris_mm is None else self.iris_mm,
                              "entrance pupil" if self.iris_mm is None else "iris")
        vertex_distance_mm(self.vertex_mm)
        samples_per_pixel(self.spp, "samples per pixel")
        sampler_seed(self.seed)
        self.eye  # the eye's own checks: its model's name and accommodation range, its surfaces, its prescription
        self.bench  # the bench's: the light, the chart and its letter, the lens, the field, the image

    @functools.cached_property
    def bench(self) -> EyeBench:
        """The eye bench these settings describe (`eye_bench`), built once."""
        from vissim.bench.eye.bench import EyeBench
        from vissim.optics.rx.trial_lens import TrialLens

        return EyeBench(eye=self.eye, chart_distance_m=self.chart_distance_m, letter=self.letter, logmar=self.logmar,
                        lenses=() if self.lens is None else (TrialLens(*self.lens),), vertex_mm=self.vertex_mm,
                        field_deg=tuple(self.field_deg), size_px=tuple(self.size_px),
                        arcmin_per_px=self.arcmin_per_px, wavelength_nm=self.wavelength_nm, spectrum=self.spectrum)


def eye_bench(settings: EyeRender) -> EyeBench:
    """The eye bench ``settings`` describe: its eye (`EyeRender.eye`), chart, trial lens and sensor."""
    return settings.bench


def eye_scene_dict(settings: EyeRender) -> dict:
    """The plain scene dict of ``settings``'s bench at its spp and seed (`vissim.bench.eye.scene.eye_scene`)."""
    from vissim.bench.eye.scene import eye_scene

    return eye_scene(eye_bench(settings), settings.spp, settings.seed)


def render_eye_bench(bench: EyeBench, spp: int, seed: int, variant: str | None = None, *, record: dict | None = None):
    """Render the eye bench ``bench`` at ``spp`` samples per pixel from ``seed``; a `vissim.render.run.RenderResult`
    whose provenance holds ``record`` under ``eye`` (default: the bench's `EyeBench.as_json`)."""
    from vissim.bench.eye.scene import eye_scene
    from vissim.provenance import json_safe, make_provenance
    from vissim.render.backend import choose_variant, mitsuba
    from vissim.render.run import mitsuba_versions, render_scene
    from vissim.render.schematic_eye_sensor import register_schematic_eye_sensor

    chosen = choose_variant("spectral" if bench.spectrum == "photopic" else "mono", variant).variant
    register_schematic_eye_sensor(mitsuba("mono", chosen))
    result = render_scene(eye_scene(bench, spp, seed), kind="mono", spp=spp, seed=seed, variant=chosen)
    provenance = make_provenance(command="render eye", eye=bench.as_json() if record is None else record,
                                 variant=result.variant, spp=result.spp, seed=result.seed,
                                 render_seconds=round(result.seconds, 3), mitsuba_render=result.render_record(),
                                 **mitsuba_versions())
    return dataclasses.replace(result, provenance=json_safe(provenance))


def render_eye(settings: EyeRender, variant: str | None = None):
    """Render ``settings`` (module doc); a `vissim.render.run.RenderResult` with provenance."""
    return render_eye_bench(eye_bench(settings), settings.spp, settings.seed, variant, record=settings.as_json())
