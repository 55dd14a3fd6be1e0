"""Tutorial 5: fitting a prescription to a capture with `vissim.fit_rx`.

The capture here is synthetic, so the answer is known: the thesis's DSLR bench looks at a
letter "K" through a trial lens of +0.50 -1.50 x 30 held 10 mm in front of the camera. The
capture is made as the campaign's simulations make it (a 4x finer chart, the bench's spectacle
magnification, the ray-optics PSF, pixel means, noise); the fit's own model shares none of it.

Run it as ``python docs/tutorials/t5_fit_prescription.py OUT_DIR``; the figure goes to OUT_DIR
(default: ``VISSIM_TUTORIAL_OUT``, else ``./tutorial_out``).
"""

import dataclasses
import os
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import vissim
from vissim.bench.dslr.bench import DslrBench
from vissim.charts import optotype_tile
from vissim.optics.blur.resample import block_mean, magnify
from vissim.optics.rx.trial_lens import TrialLens

args = [a for a in sys.argv[1:] if not a.startswith("--")]
out = Path(args[0] if args else os.environ.get("VISSIM_TUTORIAL_OUT", "tutorial_out"))
out.mkdir(parents=True, exist_ok=True)

# 1. The bench and the lens; the setup says what the lens does at the camera (vergence theory).
shape = (96, 96)  # capture pixels, 1 arcmin each
bench = DslrBench(size_px=shape)
lens = TrialLens(0.5, -1.5, 30.0)
setup = dataclasses.replace(bench, lenses=(lens,)).viewing_setup()

# 2. A synthetic capture and its sharp reference (the same chart without the lens).
q = 4  # render 4x finer, blur there, then average onto the capture's pixels
fine = optotype_tile("K", 1.0, arcmin_per_px=1.0 / q, size_px=(shape[0] * q, shape[1] * q)).pixels
psf = vissim.compute_psf(setup.wavefront, arcmin_per_px=1.0 / q, size_px=256, mode="geometric",
                         wavelength_nm=setup.wavelength_nm)
seen = vissim.blur_image(magnify(fine, setup.magnification_matrix), psf, arcmin_per_px=1.0 / q, padding="edge")
rng = np.random.default_rng(0)
image = block_mean(seen, q).astype(np.float64) + 0.002 * rng.standard_normal(shape)
reference = block_mean(fine, q).astype(np.float64)

# 3. The fit: ray optics (a render has no diffraction), magnification tied to the bench's
#    geometry, which is what tells a plus lens from a minus one.
fit = vissim.fit_rx(image, reference, arcmin_per_px=1.0, pupil_diameter_mm=3.6, bench=bench)
record = fit.as_json()
print("status:", fit.status)
print(f"fitted: {record['sphere_diopters']:+.2f} {record['cylinder_diopters']:+.2f} x {record['axis_deg']:.0f}"
      f"  (95 % interval of the axis: {record['interval_95']['axis_deg']})")
print(f"lens as held: {lens.sphere_diopters:+.2f} {lens.cylinder_diopters:+.2f} x {lens.axis_deg:.0f};"
      " the fit reports the power it adds at the camera, which the 10 mm vertex distance changes slightly")

# 4. Capture, the fit's model of it, and what is left.
fig, axes = plt.subplots(1, 3, figsize=(9, 3.2))
for ax, shown, title in zip(axes, (image, fit.model, image - fit.model), ("capture", "model", "residual")):
    ax.imshow(shown, cmap="gray")
    ax.set_title(title)
    ax.axis("off")
fig.savefig(out / "t5_fit.png", dpi=100, bbox_inches="tight")
plt.close(fig)
