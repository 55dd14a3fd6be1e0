"""Tutorial 2: a Mitsuba render of the DSLR bench against vissim's Fourier-optics simulation.

The thesis's bench (an 18 mm f/5 camera focused on a chart 914.4 mm away) looks at a letter "K"
twice: once bare, once through a +2.00 D trial lens held 10 mm in front. Both are path-traced by
Mitsuba through the meshed lens (no PSF anywhere). vissim then simulates the lens from the bare
render alone, as a validation campaign does: the bench's paraxial theory gives the power the
lens adds at the camera and its spectacle magnification; the ray-optics (geometric) PSF of that
defocus blurs the magnified bare render. PSNR and SSIM (`vissim.imaging.metrics`) say
how close the simulation comes to the render -- and, for scale, how far the bare render is.

Run it as ``python docs/tutorials/t2_bench_render_vs_simulation.py OUT_DIR``; the figure goes to
OUT_DIR (default: ``VISSIM_TUTORIAL_OUT``, else ``./tutorial_out``). ``--small`` renders a
smaller tile with fewer samples per pixel (seconds on a CPU); it needs Mitsuba (``vissim[render]``).
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
from vissim.charts import single_letter_spec
from vissim.optics.blur.resample import magnify
from vissim.optics.rx.trial_lens import TrialLens
from vissim.render.run import render_bench
from vissim.imaging.metrics import compare_images

small = "--small" in sys.argv
args = [a for a in sys.argv[1:] if not a.startswith("--")]
out = Path(args[0] if args else os.environ.get("VISSIM_TUTORIAL_OUT", "tutorial_out"))
out.mkdir(parents=True, exist_ok=True)

# 1. The bench (1 arcmin per pixel) and the chart: one letter of LogMAR 1.0 (50 arcmin tall).
size, spp = ((64, 64), 64) if small else ((113, 113), 256)
bare = DslrBench(size_px=size, spp=spp, seed=1)
with_lens = dataclasses.replace(bare, lenses=(TrialLens(2.0, 0.0, 0.0),))
chart = single_letter_spec("K", 1.0)

# 2. The two renders (linear light, float32; the chart's paper and ink reflectances).
sharp = render_bench(bare, chart).pixels.astype(np.float64)
truth = render_bench(with_lens, chart).pixels.astype(np.float64)

# 3. The simulation, from the bare render: what the lens does at the camera (vergence theory
#    through the same thick lens), then magnify and blur with the ray-optics PSF.
setup = with_lens.viewing_setup()
print(f"added defocus {setup.defocus_matrix_diopters[0][0]:+.3f} D, blur disc {setup.blur_diameter_arcmin[0][0]:.1f} arcmin,"
      f" magnification {setup.magnification_principal[0][0]:.4f}")
psf = vissim.compute_psf(setup.wavefront, arcmin_per_px=bare.arcmin_per_px, size_px=64, mode="geometric",
                         wavelength_nm=setup.wavelength_nm, pixel="integrate")
simulated = vissim.blur_image(magnify(sharp, setup.magnification_matrix), psf, arcmin_per_px=bare.arcmin_per_px,
                              padding="edge")

# 4. The numbers: the simulation against the render, and the bare render against it for scale.
model = compare_images(truth, simulated, data_range=1.0)
baseline = compare_images(truth, sharp, data_range=1.0)
print(f"simulation vs render: PSNR {model.psnr_db:.1f} dB, SSIM {model.ssim:.3f}")
print(f"bare render vs render: PSNR {baseline.psnr_db:.1f} dB, SSIM {baseline.ssim:.3f}  (no simulation at all)")
print(f"({size[0]}x{size[1]} px at {spp} spp: part of what is left is the render's Monte Carlo noise)")

# 5. Side by side, and the difference.
fig, axes = plt.subplots(1, 4, figsize=(12, 3.3))
panels = ((sharp, "bare render"), (truth, "render, +2.00 D lens"), (simulated, "vissim simulation"),
          (truth - simulated, f"render − simulation\nPSNR {model.psnr_db:.1f} dB, SSIM {model.ssim:.3f}"))
for ax, (shown, title) in zip(axes, panels):
    kwargs = {"cmap": "RdBu", "vmin": -0.2, "vmax": 0.2} if shown is panels[-1][0] else {"cmap": "gray", "vmin": 0, "vmax": 1}
    ax.imshow(shown, **kwargs)
    ax.set_title(title, fontsize=9)
    ax.axis("off")
fig.savefig(out / "t2_render_vs_simulation.png", dpi=100, bbox_inches="tight")
plt.close(fig)
