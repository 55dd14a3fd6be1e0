"""A strip of image tiles as one PNG, by plain image operations (no plotting library: milliseconds a strip).

Grey tiles show relative radiance at display gamma (sRGB), as the report's other figures do; a difference tile
shows a signed difference on a fixed scale, mid-grey for none, white for +``difference_range`` and black for
``-difference_range`` (linear).  Each tile carries its label above it.
"""

from __future__ import annotations

import numpy as np

from vissim.imageio import encode_png, srgb_encode

__all__ = ["tile_strip", "TILE_ZOOM", "GAP_PX", "LABEL_PX"]

#: Each image pixel is drawn as this many display pixels (nearest neighbour: the pixels stay visible).
TILE_ZOOM = 2
#: Space between tiles and the label band's height, display pixels.
GAP_PX, LABEL_PX = 6, 30


def _codes(image: np.ndarray, kind: str, difference_range: float) -> np.ndarray:
    image = np.asarray(image, np.float64).squeeze()
    if image.ndim == 3:  # colour: its mean (the renders compared are grey)
        image = image.mean(axis=2)
    if kind == "difference":
        shown = 0.5 + 0.5 * np.clip(image / difference_range, -1.0, 1.0)
    else:
        shown = np.asarray(srgb_encode(np.clip(image, 0.0, 1.0)), np.float64)
    return np.round(255.0 * shown).astype(np.uint8)


def tile_strip(images: list[np.ndarray], kinds: list[str], labels: list[str], difference_range: float = 0.1,
               zoom: int = TILE_ZOOM) -> bytes:
    """PNG bytes: ``images`` side by side (``kinds``: ``"grey"`` or ``"difference"``), each under its label
    (one or two lines)."""
    from PIL import Image, ImageDraw, ImageFont

    tiles = [np.kron(_codes(im, kind, difference_range), np.ones((zoom, zoom), np.uint8))
             for im, kind in zip(images, kinds)]
    height = max(t.shape[0] for t in tiles)
    width = sum(t.shape[1] for t in tiles) + GAP_PX * (len(tiles) - 1)
    canvas = Image.new("L", (width, height + LABEL_PX), 255)
    draw = ImageDraw.Draw(canvas)
    try:
        font = ImageFont.load_default(size=11)
    except TypeError:  # Pillow without FreeType sizes
        font = ImageFont.load_default()
    x = 0
    for tile, label in zip(tiles, labels):
        canvas.paste(Image.fromarray(tile, "L"), (x, LABEL_PX))
        draw.multiline_text((x + 1, 1), label, fill=0, font=font, spacing=1)
        x += tile.shape[1] + GAP_PX
    return encode_png(np.asarray(canvas.convert("RGB")))
