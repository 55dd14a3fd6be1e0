"""Paraxial theory of the ATV tube: first-order optics from the phone's screen to the eye's pupil.

Ray transfer matrices (`vissim.optics.rx.trial_lens.transfer_matrix`) of the gaps and lenses
laid out by `vissim.bench.atv.tube.atv_layout` give where a pixel's light lands: the pixel's
visual angle and size, the eye's defocus and blur diameter (from
`vissim.optics.rx.viewing_setup.ViewingSetup.eye`, given the tube's vergence at the pupil), the etendue and the cone of
directions that reach the pupil.  This is the theory both renderers are checked against;
`vissim.atv.predict.predicted_spot` turns it into a retinal image.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vissim.bench.atv.tube import AtvConfig
from vissim.optics.rx.trial_lens import transfer_matrix
from vissim.units import mm_to_m, mrad_to_arcmin

__all__ = ["AtvParaxial", "atv_paraxial"]


@dataclass(frozen=True, eq=False)
class AtvParaxial:
    """First-order optics of the tube from the phone's screen to the eye's pupil (SI: m, rad, D).

    ``system_matrix``: 4x4 ray transfer ``(x, y, u_x, u_y)``, phone plane to pupil plane.  A ray
    from pixel point ``x0`` through pupil point ``xp`` lands at visual angle
    ``pixel_angle_matrix @ x0 + defocus_matrix_diopters @ xp`` (radians, metres).
    """

    system_matrix: np.ndarray
    vergence_matrix_diopters: np.ndarray  # of the pixel's light at the pupil (< 0 diverging)
    defocus_matrix_diopters: np.ndarray  # vergence + eye excess power + accommodation
    pixel_angle_matrix: np.ndarray  # rad per metre of screen offset
    pixel_angle_arcmin: float  # side of the pixel's (square) image, geometric mean of the two axes
    blur_diameter_arcmin: float  # pupil x the largest |principal defocus|
    etendue_m2_sr: float  # pixel area x pupil area x |det B^-1|; flux = radiance x etendue
    cone_center: np.ndarray  # direction (tangents) from the pixel centre to the pupil centre
    cone_radius_rad: float  # directions within this of cone_center reach the pupil (paraxially)
    pixel_direction_arcmin: tuple[float, float]  # (right, up) visual direction of the pixel centre


def _system_matrix(config: AtvConfig) -> np.ndarray:
    tube, layout = config.tube, config.layout()
    system = transfer_matrix(mm_to_m(layout.phone_z_mm - layout.collimator_front_vertex_z_mm))
    system = tube.collimator_lens().ray_transfer_matrix() @ system
    if config.trial_lens is None:
        return transfer_matrix(mm_to_m(layout.collimator_back_vertex_z_mm)) @ system
    system = transfer_matrix(mm_to_m(layout.collimator_back_vertex_z_mm - layout.trial_front_vertex_z_mm)) @ system
    system = config.trial_lens.ray_transfer_matrix() @ system
    return transfer_matrix(mm_to_m(layout.trial_back_vertex_z_mm)) @ system


def atv_paraxial(config: AtvConfig) -> AtvParaxial:
    """The paraxial theory of ``config`` (see `AtvParaxial`)."""
    s = _system_matrix(config)
    a, b, c, d = s[:2, :2], s[:2, 2:], s[2:, :2], s[2:, 2:]
    b_inv = np.linalg.inv(b)
    vergence = -d @ b_inv
    vergence = 0.5 * (vergence + vergence.T)
    setup = config.eye.viewing_setup(vergence)
    pixel_map = -(c - d @ b_inv @ a)  # visual angle = -u at the pupil centre
    pitch_m = mm_to_m(config.tube.pixel_pitch_mm)
    pupil_m = mm_to_m(config.eye.pupil_diameter_mm)
    pixel_angle_rad = pitch_m * math.sqrt(abs(np.linalg.det(pixel_map)))
    offset_m = mm_to_m(np.asarray(config.tube.pixel_offset_mm))
    center = -b_inv @ a @ offset_m
    half_diagonal_m = pitch_m / math.sqrt(2.0)
    radius = np.linalg.norm(b_inv, 2) * (0.5 * pupil_m + np.linalg.norm(a, 2) * half_diagonal_m)
    direction = pixel_map @ offset_m
    return AtvParaxial(
        system_matrix=s,
        vergence_matrix_diopters=vergence,
        defocus_matrix_diopters=np.asarray(setup.defocus_matrix_diopters),
        pixel_angle_matrix=pixel_map,
        pixel_angle_arcmin=float(mrad_to_arcmin(1000.0 * pixel_angle_rad)),
        blur_diameter_arcmin=max(d for d, _ in setup.blur_diameter_arcmin),
        etendue_m2_sr=pitch_m**2 * (math.pi / 4.0) * pupil_m**2 * abs(float(np.linalg.det(b_inv))),
        cone_center=center,
        cone_radius_rad=float(radius),
        pixel_direction_arcmin=(float(mrad_to_arcmin(-1000.0 * direction[0])),
                                float(mrad_to_arcmin(1000.0 * direction[1]))),
    )
