"""Images resampled by a lens's magnification, and integrated onto coarser pixels."""

from __future__ import annotations

import numpy as np

from vissim.lazy_import import lazy_module
from vissim.units import xy_matrix_to_image_rowcol

ndimage = lazy_module("scipy.ndimage")

__all__ = ["magnify", "block_mean", "SUBPIXELS_PER_PX"]

#: Sub-pixels per output pixel (per axis) where vissim works on a finer grid and then integrates
#: onto the output pixels: a geometric PSF's ``pixel="sample"`` histogram, a campaign's synthetic
#: chart and the bench's wave truth (which images that chart, so the two must agree).
SUBPIXELS_PER_PX = 5


def magnify(image: np.ndarray, matrix_xy, *, background: float | None = None) -> np.ndarray:
    """Resample ``image`` magnified by a 2 x 2 matrix (TABO x/y frame) about its centre.

    In image axes the matrix is `vissim.units.xy_matrix_to_image_rowcol` of it; the
    optical axis is the tile's centre.  Radiance is conserved: values are resampled, not scaled.
    """
    m = np.asarray(matrix_xy, dtype=float)
    if np.allclose(m, np.eye(2), atol=1e-12):
        return np.asarray(image, dtype=np.float32)
    inverse = np.linalg.inv(xy_matrix_to_image_rowcol(m))
    centre = (np.array(image.shape[:2], dtype=float) - 1.0) / 2.0
    fill = float(np.median(np.concatenate([image[0], image[-1]]))) if background is None else background
    offset = centre - inverse @ centre
    if inverse[0, 1] == 0.0 and inverse[1, 0] == 0.0:  # a scaling along the image's axes: SciPy's separable zoom
        inverse = np.diag(inverse)
    out = ndimage.affine_transform(np.asarray(image, dtype=np.float64), inverse, offset=offset, order=3,
                                   mode="constant", cval=fill)
    return out.astype(np.float32)


def block_mean(image: np.ndarray, factor: int) -> np.ndarray:
    """Integrate onto pixels ``factor`` times larger (exact for pixel-integrated images)."""
    if factor == 1:
        return image
    rows, cols = image.shape[0] // factor, image.shape[1] // factor
    return image[: rows * factor, : cols * factor].reshape(rows, factor, cols, factor).mean(axis=(1, 3)).astype(np.float32)
