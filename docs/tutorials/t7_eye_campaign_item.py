"""Tutorial 7: one item of the eye campaign, reproduced with the library.

`validation/eye.toml`'s item "trial lens lens 1" is the Navarro eye (4 mm entrance pupil, relaxed, 550 nm)
looking at a Sloan "K" (LogMAR 0.5) 6 m away through a +1.00 D trial lens 12 mm in front of its cornea.
Mitsuba renders it twice (two seeds: the noise floor) through the eye's traced surfaces; vissim's
schematic-eye simulation (its traced wavefront, the lens and the chart's vergence at its entrance pupil,
the lens's spectacle magnification) blurs the chart as the eye sees it; the render, blurred by the pupil's
in-focus diffraction PSF (the render is ray optics), is the reference. The numbers are the
``schematic_wave`` row of `validation/reports/eye/metrics.csv`.

Run it as ``python docs/tutorials/t7_eye_campaign_item.py OUT_DIR``; the figure goes to OUT_DIR (default
``VISSIM_TUTORIAL_OUT``, else ``./tutorial_out``). At the campaign's 1024 samples per pixel it takes about a
minute and prints the committed row beside its own; ``--small`` renders 64.
"""

import csv
import os
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from scipy import ndimage

import vissim
from vissim.bench.eye.bench import EyeBench
from vissim.imaging.metrics import compare_images, noise_floor
from vissim.optics.eyes.simulations import simulate_view
from vissim.optics.blur.resample import block_mean
from vissim.optics.rx.trial_lens import TrialLens
from vissim.render.eye_render import render_eye_bench
from vissim.validation.eye.item import chart_offset_px, item_ray_psf
from vissim.validation.eye.simulate import EyeScene, margin_px

small = "--small" in sys.argv
args = [a for a in sys.argv[1:] if not a.startswith("--")]
out = Path(args[0] if args else os.environ.get("VISSIM_TUTORIAL_OUT", "tutorial_out"))
out.mkdir(parents=True, exist_ok=True)
spp, oversample = (64 if small else 1024), 2  # the campaign's spp and its simulations' grid (eye.toml)

# 1. The eye and the bench: the chart (K, LogMAR 0.5, 6 m), the image (64 x 64 px of 0.5 arcmin) and the light are
#    the eye's defaults (vissim.optics.eyes.defaults); the lens is meshed thick in crown glass, as rendered.
eye = vissim.build_eye("navarro-1985", pupil_diameter_mm=4.0)
bench = EyeBench(eye, lenses=(TrialLens(1.0),), wavelength_nm=550.0)
view, light = bench.view, bench.light  # the light the bench renders in: 550 nm

# 2. The truth: two renders, and their noise floor.
truth_a, truth_b = (np.asarray(render_eye_bench(bench, spp, seed).pixels, np.float64).squeeze() for seed in (1, 2))
floor = noise_floor(truth_a, truth_b, data_range=1.0)

# 3. The campaign's geometric self-check (`EyeScene`: the bench, its light and the simulations' grid): its ray PSF sets
#    the chart's margin, and its simulation registered onto the render finds where the render put the chart
#    (a few hundredths of a pixel).
scene = EyeScene(bench, oversample)
ray = item_ray_psf(scene)
margin = margin_px(ray, oversample)
(offset_rows, offset_cols), placement, _ = chart_offset_px(truth_a, scene, ray, margin)
print(f"chart placed at ({offset_rows:+.2f}, {offset_cols:+.2f}) px in the render")

# 4. The simulation, by the library: the chart as the eye's pixels see it, on a grid `oversample` times finer and
#    wider by the margin, placed as rendered; magnified and blurred by the schematic eye; cropped, integrated.
step = bench.arcmin_per_px / oversample
rows, cols = bench.size_px
chart = bench.seen_chart(step, (rows * oversample + 2 * margin, cols * oversample + 2 * margin))
chart = ndimage.shift(chart, (offset_rows * oversample, offset_cols * oversample), order=3, mode="nearest")
blurred = simulate_view(view, light, "schematic_wave", chart, step)
simulated = block_mean(blurred[margin:-margin, margin:-margin], oversample)

# 5. The reference: the render blurred by the entrance pupil's in-focus diffraction PSF; the scores.
airy = vissim.compute_psf(vissim.Wavefront({}, view.entrance_pupil_mm), wavelength_nm=550.0,
                          arcmin_per_px=bench.arcmin_per_px, size_px="auto", mode="wave", pixel="integrate")
reference = np.asarray(vissim.blur_image(truth_a, airy, arcmin_per_px=bench.arcmin_per_px, padding="edge"), np.float64)
score = compare_images(reference, simulated, data_range=1.0)
print(f"schematic_wave: PSNR {score.psnr_db:.4f} dB, SSIM {score.ssim:.4f}, "
      f"{score.psnr_db - floor.psnr_db:+.4f} dB over the noise floor ({floor.psnr_db:.4f} dB)")

# 6. The campaign's row, as committed (the same numbers at the campaign's 1024 spp; --small renders fewer).
report = Path(__file__).resolve().parents[2] / "validation" / "reports" / "eye" / "metrics.csv"
if report.exists():
    with report.open(newline="") as rows_file:
        row = next(r for r in csv.DictReader(rows_file)
                   if r["configuration"] == "trial lens +1.00 DS" and r["simulation"] == "schematic_wave")
    print(f"committed row:  PSNR {float(row['psnr_db']):.4f} dB, SSIM {float(row['ssim']):.4f}, "
          f"{float(row['over_floor_db']):+.4f} dB over the noise floor ({float(row['noise_floor_psnr_db']):.4f} dB)")

# 7. Side by side, and the difference.
fig, axes = plt.subplots(1, 3, figsize=(9, 3.3))
panels = ((reference, "render + diffraction"), (simulated, "schematic eye, simulated"),
          (reference - simulated, f"difference\nPSNR {score.psnr_db:.1f} dB"))
for ax, (shown, title) in zip(axes, panels):
    kwargs = {"cmap": "RdBu", "vmin": -0.1, "vmax": 0.1} if shown is panels[-1][0] else {"cmap": "gray", "vmin": 0, "vmax": 1}
    ax.imshow(shown, **kwargs)
    ax.set_title(title, fontsize=9)
    ax.axis("off")
fig.savefig(out / "t7_eye_item.png", dpi=100, bbox_inches="tight")
plt.close(fig)
