"""Who looks at a depth scene: an eye (a thin lens at its pupil) or the DSLR bench camera.

Both are ideal thin lenses at the pupil plane with flat focal surfaces, described by the 2 x 2
vergence matrix ``K`` (dioptres, TABO x/y frame) they focus: an object point at axial
distance ``z`` is sharp in the meridians where ``1/z = K``, and blurred elsewhere by a
geometric spot of ``pupil x (K - I/z)`` milliradians (pupil in mm; conventions: D x mm = mrad).

* `EyeViewer` -- ``K = A I - Rx``: the eye's correcting lens ``Rx`` (a
  `Prescription`, myope negative, *not* worn) and accommodation
  ``A >= 0``.  So defocus at distance d is ``Rx + 1/d - A``, exactly
  `vissim.optics.rx.viewing_setup.ViewingSetup.eye`: a -2 D myope focuses 0.5 m (K = +2 D), an
  emmetrope accommodating 3 D focuses 1/3 m, a relaxed +1 D hyperope has K = -1 D (focus
  "beyond infinity": blur at 6 m is pupil x (1 + 1/6) D), and ``plano -2.00 x 90`` has
  K = diag(2, 0) D (excess power in the horizontal meridian: horizontal blur).  Both come from
  `vissim.optics.rx.viewing_setup.ViewingSetup` (`viewing_setup`), which decides them.  Rendered by
  the Mitsuba sensor ``vissim_eye`` (`vissim.render.eye_sensor`), which takes any such K.
* `CameraViewer` -- the DSLR of `vissim.bench.dslr.bench` (Mitsuba ``thinlens``,
  entrance pupil = focal length / f-number): ``K = I / focus distance`` plus the power its
  trial lenses add (`vissim.optics.rx.trial_lens.trial_lens_effect`, for an object at the focus
  distance; the lenses' vergence effect changes it by < 1 % between 0.4 m and infinity).

`equivalent_eye` is the eye that blurs like a viewer (``Rx = -K``, same pupil, A = 0):
what `vissim.optics.depth.depth_map.blur_depth` is given to simulate a render of that viewer.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from typing import Union

import numpy as np

from vissim.bench.dslr.bench import DslrBench
from vissim.checks import accommodation_diopters, eye_prescription_meridians, eye_pupil_diameter_mm, positive_number
from vissim.errors import VissimInputError
from vissim.optics.rx.prescription import Prescription
from vissim.optics.rx.trial_lens import CROWN_GLASS_INDEX, TrialLens, entrance_pupil_diameter_mm
from vissim.optics.rx.viewing_setup import ViewingSetup
from vissim.thesis import THESIS_CHART_DISTANCE_MM, THESIS_F_NUMBER, THESIS_FOCAL_LENGTH_MM, THESIS_VERTEX_DISTANCE_MM
from vissim.units import m_to_mm, mm_to_m

__all__ = ["EyeViewer", "CameraViewer", "Viewer", "viewing_setup", "equivalent_eye", "frame_margin_px",
           "FRAME_MARGIN_EXTRA_PX"]


@dataclass(frozen=True)
class EyeViewer:
    """An eye of correcting lens ``prescription`` (myope < 0, not worn), pupil, accommodation (checks' range)."""

    prescription: Prescription = field(default_factory=lambda: Prescription(0.0))
    pupil_diameter_mm: float = 4.0
    accommodation_diopters: float = 0.0

    def __post_init__(self) -> None:
        eye_prescription_meridians(self.prescription.sphere_diopters, self.prescription.cylinder_diopters,
                                   f"the eye's prescription {self.prescription}")
        pupil = eye_pupil_diameter_mm(self.pupil_diameter_mm, "the eye's pupil diameter")  # a human eye's
        setup = ViewingSetup.eye(self.prescription, pupil, self.accommodation_diopters)  # validates
        object.__setattr__(self, "pupil_diameter_mm", setup.pupil_diameter_mm)
        object.__setattr__(self, "accommodation_diopters", accommodation_diopters(self.accommodation_diopters))

    def label(self) -> str:
        return f"eye {self.prescription.format()}, {self.pupil_diameter_mm:g} mm pupil, A {self.accommodation_diopters:g} D"


@dataclass(frozen=True)
class CameraViewer:
    """The DSLR bench camera (thin lens, f/N) focused at ``focus_distance_m``, optional trial lenses."""

    focal_length_mm: float = THESIS_FOCAL_LENGTH_MM
    f_number: float = THESIS_F_NUMBER
    focus_distance_m: float = mm_to_m(THESIS_CHART_DISTANCE_MM)
    lenses: tuple[TrialLens, ...] = ()
    vertex_distance_mm: float = THESIS_VERTEX_DISTANCE_MM
    lens_gap_mm: float = 2.0
    refractive_index: float = CROWN_GLASS_INDEX
    clear_aperture_mm: float | None = None
    fresnel_loss: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "focus_distance_m", positive_number(self.focus_distance_m, "focus distance", "m"))
        lenses = (self.lenses,) if isinstance(self.lenses, TrialLens) else tuple(self.lenses)
        object.__setattr__(self, "lenses", lenses)
        self.bench()  # validates through DslrBench

    def bench(self, scene=None) -> DslrBench:
        """The `DslrBench` of this camera on ``scene``'s pixel grid (object distance = focus).

        ``scene`` (a `DepthScene`) sets the grid, sampler and
        texel density, hence the lenses' clear aperture; None: an 8 x 8 grid at 1 arcmin/px.
        """
        grid = {"size_px": (8, 8)} if scene is None else {
            key: getattr(scene, key) for key in ("arcmin_per_px", "size_px", "sampler", "texels_per_px")}
        # every field but the focus distance is a DslrBench field of the same name
        camera = {f.name: getattr(self, f.name) for f in fields(self) if f.name != "focus_distance_m"}
        distance_mm = m_to_mm(self.focus_distance_m)
        return DslrBench(focus_distance_mm=distance_mm, chart_distance_mm=distance_mm, **camera, **grid)

    @property
    def pupil_diameter_mm(self) -> float:
        return entrance_pupil_diameter_mm(self.focal_length_mm, self.f_number)

    def label(self) -> str:
        lenses = " + ".join(str(lens.marked_power) for lens in self.lenses) or "no lens"
        return (f"camera {self.focal_length_mm:g} mm f/{self.f_number:g} focused at {self.focus_distance_m:g} m, "
                f"{lenses}")


Viewer = Union[EyeViewer, CameraViewer]


def viewing_setup(viewer: Viewer, scene=None) -> ViewingSetup:
    """The viewer's `ViewingSetup`: its focus matrix, blur and pupil.

    An eye looks at infinity; the camera is its bench on ``scene``'s grid (`CameraViewer.bench`,
    which sizes the trial lenses), looking at its focus distance (the lenses' vergence effect is
    taken there, module doc).
    """
    if isinstance(viewer, EyeViewer):
        return ViewingSetup.eye(viewer.prescription, viewer.pupil_diameter_mm, viewer.accommodation_diopters)
    if not isinstance(viewer, CameraViewer):
        raise VissimInputError(f"viewer must be an EyeViewer or a CameraViewer, got {type(viewer).__name__}")
    return viewer.bench(scene).viewing_setup()


def equivalent_eye(viewer: Viewer, scene=None) -> EyeViewer:
    """The `EyeViewer` that blurs like ``viewer``: Rx = -K, same pupil, no accommodation."""
    if isinstance(viewer, EyeViewer):
        return viewer
    setup = viewing_setup(viewer, scene)
    return EyeViewer(Prescription.from_power_matrix(-setup.focus_matrix_diopters), setup.pupil_diameter_mm, 0.0)


#: Pixels added to the largest blur radius in `frame_margin_px`: the pixel's own width and
#: the diffraction PSF's core (the Airy radius of a 3 mm pupil at 550 nm is 0.77 arcmin).
FRAME_MARGIN_EXTRA_PX = 2


def frame_margin_px(viewer: Viewer, scene) -> int:
    """Pixels to render and simulate beyond each side of ``scene``'s frame, then crop.

    The largest geometric blur radius of any panel depth (a tilted chart's blur is largest at an
    end: ``|K - 1/z|`` is convex in ``1/z``) rounded up, plus `FRAME_MARGIN_EXTRA_PX`.  A pixel
    of the frame then receives light only from inside the margin, so a simulation on the
    enlarged grid sees what the observer sees beyond the frame.
    """
    setup = viewing_setup(viewer, scene)
    diameters = setup.blur_diameter_at_arcmin(np.asarray(scene.distances_m()))
    return int(math.ceil(0.5 * float(np.max(diameters)) / scene.arcmin_per_px - 1e-9)) + FRAME_MARGIN_EXTRA_PX
