"""The eye bench: a letter chart at a distance, trial lenses in front of the eye, the eye's sensor.

World frame (millimetres): the eye's corneal vertex at z = 0, the chart's centre on +z at
``chart_distance_m``; world x the examiner's right, y up (`vissim.bench.scene_parts`).  Light
travels towards -z: chart, trial lenses (the last one's back vertex ``vertex_mm`` in front of the
cornea, the others stacked towards the chart with ``lens_gap_mm`` of air), eye.

* **Chart**: one Sloan letter sized for ``chart_distance_m`` so that it subtends ``logmar`` there
  (`chart`), printed at ``texels_per_px`` texels per image pixel on the chart, self-emitting
  (radiance = its reflectance); the texture covers the field, magnified by the lenses, plus the
  blur the lenses add for an eye focused on the chart over the eye's pupil, plus a margin
  (`texture_shape`): beyond it the scene is black (`chart_half_arcmin`).
* **Lenses**: the holder's rules shared with the DSLR bench (`vissim.bench.lenses.holder`): thin
  lenses made crown glass of realistic thickness, meshed with a clear aperture wide enough for a
  beam 1.2 x the eye's pupil (an iris's entrance pupil is <= ~1.13 x it) along the widest
  direction the image looks (`clear_aperture_mm`).
* **A measured eye** is its base eye with a phase plane at its entrance pupil that gives it the measured
  wavefront at the chart's field (`measured_phase`); no lenses are put before it (its simulations do not trace
  them).
* **Sensor**: the schematic-eye sensor (`vissim.render.schematic_eye_sensor`) of the `Eye` ``eye``,
  turned so that the chart's centre lies at the field angle ``field_deg`` (OSA's frame: x the
  examiner's right, the observer's left; y up), ``size_px`` pixels of ``arcmin_per_px``; light of
  ``wavelength_nm`` (None: `DEFAULT_EYE_LIGHT_NM`) or the ``photopic`` spectrum.

`vissim.bench.eye.scene.eye_scene` builds its Mitsuba scene dict.  Nothing here imports Mitsuba.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass

import numpy as np

from vissim.bench.lenses.holder import LENS_GAP_MM, lens_back_vertex_z_mm, lens_clear_aperture_mm, physical_lens
from vissim.bench.scene_parts import chart_texture_shape
from vissim.checks import EYE_LIGHT_RANGE_NM, LOGMAR_RANGE, eye_field_deg
from vissim.checks import arcmin_per_px as check_arcmin_per_px
from vissim.checks import finite_number, instance_of, number_within, positive_number
from vissim.checks import size_px as check_size_px
from vissim.checks import vertex_distance_mm as check_vertex_mm
from vissim.errors import VissimInputError
from vissim.optics.eyes.defaults import (DEFAULT_CHART_DISTANCE_M, DEFAULT_EYE_ARCMIN_PER_PX, DEFAULT_EYE_LIGHT_NM,
                                         DEFAULT_EYE_SIZE_PX, DEFAULT_LETTER, DEFAULT_LETTER_LOGMAR,
                                         DEFAULT_SPECTACLE_VERTEX_MM)
from vissim.optics.eyes.eye import Eye, surface_overrides
from vissim.optics.eyes.viewing import EyeView
from vissim.optics.rx.viewing_setup import ViewingSetup
from vissim.optics.rx.trial_lens import CROWN_GLASS_INDEX, MAX_LENSES_IN_HOLDER, TrialLens, TrialLensSetup
from vissim.units import arcmin_to_rad

__all__ = ["EyeBench", "SPECTRA", "TEXELS_PER_PX", "BEAM_MARGIN", "letter_in_visual_angle"]

#: The light: one wavelength, or white light developed as luminance (CIE ȳ = V(λ)).
SPECTRA = ("mono", "photopic")
#: Chart texels per image pixel on the chart.
TEXELS_PER_PX = 4.0
#: The lenses' clear aperture is sized for a beam this many times the eye's pupil.
BEAM_MARGIN = 1.2


@dataclass(frozen=True)
class EyeBench:
    """Chart, lens stack and eye sensor of the eye bench (module doc); sampling (spp, seed) is the render's."""

    eye: Eye
    chart_distance_m: float = DEFAULT_CHART_DISTANCE_M
    letter: str = DEFAULT_LETTER
    logmar: float = DEFAULT_LETTER_LOGMAR
    lenses: tuple[TrialLens, ...] = ()
    vertex_mm: float = DEFAULT_SPECTACLE_VERTEX_MM
    lens_gap_mm: float = LENS_GAP_MM
    refractive_index: float = CROWN_GLASS_INDEX
    field_deg: tuple[float, float] = (0.0, 0.0)
    size_px: tuple[int, int] = DEFAULT_EYE_SIZE_PX
    arcmin_per_px: float = DEFAULT_EYE_ARCMIN_PER_PX
    wavelength_nm: float | None = None
    spectrum: str = "mono"
    texels_per_px: float = TEXELS_PER_PX

    def __post_init__(self) -> None:
        instance_of(self.eye, Eye, "the eye bench's eye", "an Eye (vissim.optics.eyes.eye.build_eye)")
        self._check_light()
        self._check_chart()
        self._check_lenses()
        object.__setattr__(self, "field_deg", eye_field_deg(self.field_deg))
        object.__setattr__(self, "size_px", check_size_px(self.size_px))
        check_arcmin_per_px(self.arcmin_per_px)
        self.trial_lens_setup()  # validates the stack against the chart distance

    @staticmethod
    def light_nm(wavelength_nm: float | None, spectrum: str) -> float | None:
        """The one wavelength of a ``spectrum`` light (`DEFAULT_EYE_LIGHT_NM` when none is given); None: photopic."""
        if spectrum not in SPECTRA:
            raise VissimInputError(f"spectrum must be one of {', '.join(SPECTRA)}, got {spectrum!r}")
        if spectrum == "photopic":
            if wavelength_nm is not None:
                raise VissimInputError("give a wavelength (monochromatic) or the photopic spectrum, not both")
            return None
        if wavelength_nm is None:
            return DEFAULT_EYE_LIGHT_NM
        return number_within(wavelength_nm, "wavelength", "nm", EYE_LIGHT_RANGE_NM)

    def _check_light(self) -> None:
        object.__setattr__(self, "wavelength_nm", self.light_nm(self.wavelength_nm, self.spectrum))

    def _check_chart(self) -> None:
        from vissim.charts import single_letter_spec

        positive_number(self.chart_distance_m, "chart distance", "m")
        number_within(self.logmar, "letter size", "logMAR", LOGMAR_RANGE)
        single_letter_spec(self.letter, self.logmar, viewing_distance_m=self.chart_distance_m)  # a Sloan letter
        positive_number(self.texels_per_px, "chart texels per pixel", "texels")

    def _check_lenses(self) -> None:
        lenses = (self.lenses,) if isinstance(self.lenses, TrialLens) else tuple(self.lenses)
        if len(lenses) > MAX_LENSES_IN_HOLDER or not all(isinstance(lens, TrialLens) for lens in lenses):
            raise VissimInputError(
                f"the holder takes up to {MAX_LENSES_IN_HOLDER} TrialLens objects, got {self.lenses!r}")
        object.__setattr__(self, "lenses", lenses)
        if lenses and self.eye.measured is not None:
            raise VissimInputError(f"{self.eye.model} is a measured eye: lenses in front of it are not rendered (its "
                                   "simulations do not trace them); give the chart's distance instead")
        object.__setattr__(self, "vertex_mm", check_vertex_mm(self.vertex_mm))
        if not finite_number(self.lens_gap_mm, "lens gap", "mm") >= 0.0:
            raise VissimInputError(f"lens gap must be >= 0 mm, got {self.lens_gap_mm!r}")
        if positive_number(self.refractive_index, "refractive index", "(dimensionless)") <= 1.0:
            raise VissimInputError(f"refractive index must exceed 1, got {self.refractive_index:g}")

    # -- the eye and its light ------------------------------------------------------------
    @property
    def pupil_mm(self) -> float:
        """The eye's pupil as given (entrance pupil, or iris), mm: the beam the lenses and the texture are sized for."""
        return self.eye.pupil_diameter_mm or self.eye.iris_mm

    @property
    def light(self):
        """The light the bench renders in, as the simulations take it (`vissim.optics.eyes.simulations.Light`):
        photopic or its one wavelength."""
        from vissim.optics.eyes.simulations import Light

        return Light.photopic() if self.spectrum == "photopic" else Light.monochromatic(self.wavelength_nm)

    @property
    def lens_wavelength_nm(self) -> float:
        """The wavelength of a one-wavelength render's glass: ``wavelength_nm``, else (photopic) the eye's reference."""
        return self.wavelength_nm or self.eye.optics.reference_wavelength_nm

    @functools.cached_property
    def measured_phase(self):
        """A measured eye's phase plane (`vissim.optics.eyes.measured.phase_plane`) at the chart's field, fitted in the
        render's light (photopic: at its focus, `Light.focus_nm`, and used at every wavelength: the measured eye's
        chromatic difference is its base eye's); None for a schematic eye."""
        if self.eye.measured is None:
            return None
        from vissim.optics.eyes.measured.phase_plane import measured_phase_plane

        return measured_phase_plane(self.eye, self.field_deg, self.light.focus_nm)

    @property
    def phase_plane(self):
        """The `PhasePlane` the sensor's rays cross (`measured_phase`); None for a schematic eye."""
        return None if self.measured_phase is None else self.measured_phase.plane

    # -- the lenses -----------------------------------------------------------------------
    @functools.cached_property
    def clear_aperture_mm(self) -> float:
        """The lens meshes' diameter (`lens_clear_aperture_mm`) for the widest direction the image looks along,
        field offset included, and a beam `BEAM_MARGIN` x the eye's pupil."""
        rows, cols = self.size_px
        half_deg = [abs(f) + 0.5 * n * self.arcmin_per_px / 60.0 for f, n in zip(self.field_deg, (cols, rows))]
        return lens_clear_aperture_mm(BEAM_MARGIN * self.pupil_mm, math.radians(math.hypot(*half_deg)),
                                      self.vertex_mm, self.lens_gap_mm)

    @functools.cached_property
    def physical_lenses(self) -> tuple[TrialLens, ...]:
        """The lenses as rendered: thick, with an index (thin ones made realistic in crown glass)."""
        return tuple(physical_lens(lens, self.clear_aperture_mm, self.refractive_index) for lens in self.lenses)

    def lens_back_vertex_z_mm(self) -> tuple[float, ...]:
        """World z of each lens's back vertex, in the order of ``lenses`` (chart to eye)."""
        return lens_back_vertex_z_mm(self.physical_lenses, self.vertex_mm, self.lens_gap_mm)

    def trial_lens_setup(self) -> TrialLensSetup:
        """The rendered lenses as a `TrialLensSetup` (object distance = chart distance)."""
        return TrialLensSetup(self.physical_lenses, self.vertex_mm, self.chart_distance_m, self.lens_gap_mm)

    # -- the chart ------------------------------------------------------------------------
    @property
    def chart_distance_mm(self) -> float:
        return 1000.0 * self.chart_distance_m

    @property
    def pitch_mm(self) -> float:
        """Size on the chart of the central image pixel, mm."""
        return self.chart_distance_mm * math.tan(arcmin_to_rad(self.arcmin_per_px))

    @functools.cached_property
    def chart(self):
        """The printed chart (`vissim.charts.render_chart_print`): the letter sized for ``chart_distance_m``, at
        ``texels_per_px`` texels per image pixel on the chart."""
        from vissim.charts import MM_PER_INCH, render_chart_print, single_letter_spec

        spec = single_letter_spec(self.letter, self.logmar, viewing_distance_m=self.chart_distance_m)
        return render_chart_print(spec, MM_PER_INCH / (self.pitch_mm / self.texels_per_px))

    @functools.cached_property
    def texture_shape(self) -> tuple[int, int]:
        """(rows, cols) texels of the chart texture (module doc: field, lens blur and magnification, margin)."""
        setup = ViewingSetup.through_lenses(self.pupil_mm, self.trial_lens_setup())
        blur_px = max(d for d, _ in setup.blur_diameter_arcmin) / self.arcmin_per_px
        magnification = max(abs(m) for m, _ in setup.magnification_principal)
        return chart_texture_shape(self.size_px, self.pitch_mm, blur_px, magnification, self.chart.mm_per_px)

    @functools.cached_property
    def chart_half_arcmin(self) -> tuple[float, float]:
        """The chart texture's half size seen from the corneal vertex, arcmin (rows, columns): beyond it, black."""
        mm_per_px, distance_mm = self.chart.mm_per_px, self.chart_distance_mm
        return tuple(60.0 * math.degrees(math.atan(0.5 * n * mm_per_px / distance_mm)) for n in self.texture_shape)

    # -- what the eye sees -----------------------------------------------------------------
    @functools.cached_property
    def view(self) -> EyeView:
        """The rendered eye looking at the chart through the rendered (thick) lens: the viewing physics
        (`vissim.optics.eyes.viewing.EyeView`) the simulations of this bench use."""
        if len(self.lenses) > 1:
            raise VissimInputError(f"the eye's viewing physics takes one trial lens, the bench holds {len(self.lenses)}")
        lens = self.physical_lenses[0] if self.lenses else None
        return EyeView(self.eye, self.chart_distance_m, self.field_deg, lens, self.vertex_mm)

    def seen_chart(self, step_arcmin: float, shape: tuple[int, int]) -> np.ndarray:
        """The chart as the eye's pixels see it (`EyeView.chart_points_arcmin`: each pixel's line of sight from
        the entrance pupil to the flat chart), ``shape`` pixels of ``step_arcmin`` centred on the chart; read-only."""
        key = (float(step_arcmin), tuple(int(n) for n in shape))
        if key not in self._seen_charts:
            self._seen_charts[key] = _seen_chart(self, *key)
        return self._seen_charts[key]

    @functools.cached_property
    def _seen_charts(self) -> dict:
        return {}  # (step, shape) -> `seen_chart`: every simulation of an item draws it

    # -- records --------------------------------------------------------------------------
    def as_json(self) -> dict:
        """Everything the bench's render depends on but its sampling, as plain values."""
        lenses = [dataclasses.asdict(lens) for lens in self.lenses]
        eye = dict(self.eye.as_json(), surfaces=surface_overrides(self.eye.schematic))
        return {"eye": eye, "chart_distance_m": self.chart_distance_m, "letter": self.letter, "logmar": self.logmar,
                "lenses": lenses, "vertex_mm": self.vertex_mm, "lens_gap_mm": self.lens_gap_mm,
                "refractive_index": self.refractive_index, "field_deg": self.field_deg, "size_px": self.size_px,
                "arcmin_per_px": self.arcmin_per_px, "wavelength_nm": self.wavelength_nm, "spectrum": self.spectrum,
                "texels_per_px": self.texels_per_px,
                **({} if self.measured_phase is None else {"phase_plane": self.measured_phase.as_json()})}


@functools.lru_cache(maxsize=32)
def letter_in_visual_angle(letter: str, logmar: float, distance_m: float, step_arcmin: float, shape: tuple[int, int],
                           half_size_arcmin: tuple[float, float]) -> np.ndarray:
    """The bench's letter (printed for ``distance_m``, `EyeBench.chart`) drawn in visual angle, centred, ``shape``
    pixels of ``step_arcmin``; black beyond the chart's half size (rows, columns; arcmin)."""
    from vissim.charts import optotype_tile

    pixels = optotype_tile(letter, logmar, arcmin_per_px=step_arcmin, size_px=shape,
                           viewing_distance_m=distance_m, snap_to_pixels=False).pixels.astype(np.float64)
    for axis, half in enumerate(half_size_arcmin):
        offset = step_arcmin * np.abs(np.arange(shape[axis]) - (shape[axis] - 1) / 2.0)
        outside = offset > half
        if axis == 0:
            pixels[outside, :] = 0.0
        else:
            pixels[:, outside] = 0.0
    return pixels


def _seen_chart(bench: EyeBench, step: float, shape: tuple[int, int]) -> np.ndarray:
    from scipy import ndimage

    draw = functools.partial(letter_in_visual_angle, bench.letter, bench.logmar, bench.chart_distance_m, step)
    points = bench.view.chart_points_arcmin(shape, step)
    if points is None:
        seen = np.array(draw(shape, bench.chart_half_arcmin))
    else:
        base_shape = tuple(int(math.ceil(1.15 * n)) + 8 for n in shape)
        base = draw(base_shape, bench.chart_half_arcmin)
        row_arcmin, col_arcmin = points
        coords = [row_arcmin / step + (base_shape[0] - 1) / 2.0, col_arcmin / step + (base_shape[1] - 1) / 2.0]
        seen = ndimage.map_coordinates(base, coords, order=1, mode="nearest")
    seen.setflags(write=False)
    return seen
