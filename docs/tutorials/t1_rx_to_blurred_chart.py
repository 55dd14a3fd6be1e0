"""Tutorial 1: a prescription -> its wavefront -> the PSF -> a blurred letter chart, the MTF, and
through focus.

Run it as ``python docs/tutorials/t1_rx_to_blurred_chart.py OUT_DIR [--small]``; figures go to
OUT_DIR (default: the ``VISSIM_TUTORIAL_OUT`` environment variable, else ``./tutorial_out``).
The test suite runs it with ``--small`` into a temporary directory.
"""

import os
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, no window
import matplotlib.pyplot as plt
import numpy as np

import vissim

small = "--small" in sys.argv
args = [a for a in sys.argv[1:] if not a.startswith("--")]
out = Path(args[0] if args else os.environ.get("VISSIM_TUTORIAL_OUT", "tutorial_out"))
out.mkdir(parents=True, exist_ok=True)

# 1. A prescription: the lens that corrects this eye (TABO axis, minus cylinder). The eye
#    itself is myopic by 1 D with 0.75 D of astigmatism.
rx = vissim.Prescription(-1.0, -0.75, 180)
print("prescription:", rx)

# 2. Its wavefront over a 3 mm pupil: OSA Zernike coefficients in micrometres, keyed (n, m).
pupil_mm = 3.0
front = vissim.Wavefront.from_prescription(rx, pupil_diameter_mm=pupil_mm)
print("Zernike coefficients (um):", dict(front.coefficients_um))

# 3. The PSF at 550 nm. It carries its sampling (arcmin per pixel); row 0 is the top of the
#    visual field, the chief ray is at [N//2, N//2] (docs/conventions.md).
step = 0.5  # arcmin per pixel
size = 96 if small else 192
psf = vissim.compute_psf(front, wavelength_nm=550.0, arcmin_per_px=step, size_px=size)
print(f"PSF {psf.data.shape} at {psf.arcmin_per_px} arcmin/px, {100 * psf.energy_in_field:.2f} % in the field")

half = size * step / 2
fig, ax = plt.subplots(figsize=(4.5, 4))
shown = ax.imshow(np.log10(np.maximum(psf.data, 1e-8)), extent=(-half, half, -half, half),
                  origin="upper", vmin=-6, cmap="magma")
ax.set_xlabel("x, observer's right (arcmin)")
ax.set_ylabel("y, up (arcmin)")
ax.set_title(f"log10 PSF, {step} arcmin/px, {size} px, 550 nm")
fig.colorbar(shown, ax=ax)
fig.savefig(out / "t1_psf_log.png", dpi=100, bbox_inches="tight")
plt.close(fig)

# 4. The MTF along the horizontal axis, against the diffraction limit of the same pupil.
freqs = vissim.frequencies_cyc_per_deg(psf)
mtf_row = vissim.mtf(psf, remove_pixel=True)[size // 2]
keep = (freqs >= 0) & (freqs <= 0.5 * 60 / step)  # up to the sampling's Nyquist
fig, ax = plt.subplots(figsize=(5, 3.5))
ax.plot(freqs[keep], mtf_row[keep], label=f"{rx} over {pupil_mm:g} mm")
ax.plot(freqs[keep], vissim.diffraction_mtf(freqs[keep], pupil_mm, 550.0), "--", label="diffraction limit")
ax.set_xlabel("spatial frequency (cycles/degree)")
ax.set_ylabel("MTF (horizontal)")
ax.legend()
fig.savefig(out / "t1_mtf.png", dpi=100, bbox_inches="tight")
plt.close(fig)

# 5. A letter chart at the PSF's sampling, blurred in linear light.
spec = vissim.etdrs_chart_spec((1.0, 0.6) if small else (1.0, 0.3))
chart = vissim.render_chart_angular(spec, arcmin_per_px=step)
blurred = vissim.blur_image(chart.pixels, psf, arcmin_per_px=chart.arcmin_per_px)
print(f"chart {chart.pixels.shape} px; mean {chart.pixels.mean():.4f} -> {blurred.mean():.4f} after blur")

fig, axes = plt.subplots(1, 2, figsize=(8, 8 * chart.pixels.shape[0] / (2 * chart.pixels.shape[1]) + 0.5))
for ax, image, title in zip(axes, (chart.pixels, blurred), ("sharp", f"seen without {rx}")):
    ax.imshow(image, cmap="gray", vmin=0, vmax=1)  # linear reflectance, shown as is
    ax.set_title(title)
    ax.axis("off")
fig.savefig(out / "t1_chart.png", dpi=100, bbox_inches="tight")
plt.close(fig)

# 6. Through focus: the eye now wears a lens whose sphere is off its prescription by -0.5 ...
#    +0.5 D (cylinder and axis right), so pure defocus is left over: a lens 0.25 D too strong
#    (more minus) leaves the residual of Prescription(+0.25).  Sharpest at 0; the PSF at the
#    top, a 20/63 letter (logMAR 0.5) seen through it below.
offsets = (-0.5, -0.25, 0.0, 0.25, 0.5)
letter = vissim.render_chart_angular(vissim.single_letter_spec("K", 0.5), arcmin_per_px=step)
crop = 12  # PSF pixels shown each side of the chief ray (6 arcmin)
fig, axes = plt.subplots(2, len(offsets), figsize=(2.2 * len(offsets), 4.6))
for column, offset in enumerate(offsets):
    residual = vissim.Prescription(-offset)  # what the worn lens (rx + offset sphere) leaves uncorrected
    focus_psf = vissim.compute_psf(vissim.Wavefront.from_prescription(residual, pupil_diameter_mm=pupil_mm),
                                   wavelength_nm=550.0, arcmin_per_px=step, size_px=size)
    c = size // 2
    extent = (-crop * step, crop * step, -crop * step, crop * step)
    axes[0, column].imshow(focus_psf.data[c - crop:c + crop, c - crop:c + crop], extent=extent,
                           origin="upper", cmap="magma")
    axes[0, column].set_title(f"{offset:+.2f} D", fontsize=9)
    axes[0, column].set_xlabel("arcmin", fontsize=8)
    seen = vissim.blur_image(letter.pixels, focus_psf, arcmin_per_px=step)
    axes[1, column].imshow(seen, cmap="gray", vmin=0, vmax=1)
    axes[1, column].axis("off")
axes[0, 0].set_ylabel("PSF (linear)")
fig.suptitle(f"through focus: worn sphere minus prescribed ({rx} prescribed), {pupil_mm:g} mm pupil, 550 nm",
             fontsize=10)
fig.savefig(out / "t1_through_focus.png", dpi=100, bbox_inches="tight")
plt.close(fig)
print("figures in", out)
