"""Tutorial 8: one letter through twenty real eyes.

Twenty right eyes of Jaeken & Artal's 130 subjects (2012: wavefronts measured over a 4 mm pupil, shipped with
vissim), each seeing the same letter at the fovea through a 4 mm pupil (the data's) in 555 nm light, wearing
its best sphero-cylindrical spectacles: what is left is each eye's own higher-order aberration, which
spectacles cannot correct and which differs from eye to eye. The Navarro schematic eye is shown beside them.

Run it as ``python docs/tutorials/t8_twenty_real_eyes.py OUT_DIR [--small]``; the figure goes to OUT_DIR
(default: the ``VISSIM_TUTORIAL_OUT`` environment variable, else ``./tutorial_out``). The test suite runs it
with ``--small`` (a smaller letter grid) into a temporary directory.
"""

import os
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, no window
import matplotlib.pyplot as plt
import numpy as np

import vissim
from vissim.charts import optotype_tile

small = "--small" in sys.argv
args = [a for a in sys.argv[1:] if not a.startswith("--")]
out = Path(args[0] if args else os.environ.get("VISSIM_TUTORIAL_OUT", "tutorial_out"))
out.mkdir(parents=True, exist_ok=True)

# 1. The letter: a Sloan K at LogMAR 0.1 (6/7.5), in visual angle at 0.25 arcmin per pixel.
step = 0.25  # arcmin per pixel
size = 96 if small else 160
letter = optotype_tile("K", 0.1, arcmin_per_px=step, size_px=(size, size), viewing_distance_m=6.0,
                       snap_to_pixels=False).pixels.astype(np.float64)

# 2. Twenty measured eyes: a measured eye is named by its dataset, subject and eye. It sits on the
#    Navarro eye (its pupil, retinal scale and dispersion); its wavefront is the subject's own.
pupil_mm, nm = 4.0, 555.0
names = [f"jaeken-artal-2012:{subject}:right" for subject in range(1, 21)] + ["navarro-1985"]
panels = []
for name in names:
    eye = vissim.build_eye(name, pupil_diameter_mm=pupil_mm)
    front = vissim.eye_wavefront(eye, wavelength_nm=nm)  # at the fovea
    # 3. Best spectacles: a sphero-cylinder removes orders 0-2 (piston, tilt, defocus, astigmatism) and
    #    leaves the higher orders, which spectacles cannot correct.
    higher = vissim.Wavefront({key: value for key, value in front.coefficients_um.items() if key[0] >= 3},
                              pupil_mm, nm)
    psf = vissim.compute_psf(higher, wavelength_nm=nm, arcmin_per_px=step, size_px=size)
    seen = vissim.blur_image(letter, psf, arcmin_per_px=step, padding="edge")
    strehl = vissim.strehl_ratio(higher, wavelength_nm=nm)
    rms = np.sqrt(sum(v * v for v in higher.coefficients_um.values()))
    panels.append((name, seen, strehl, rms))
    print(f"{name:28s} higher-order RMS {rms:.3f} um, Strehl {strehl:.3f}")

# 4. The mosaic, the schematic eye last, with each eye's Strehl ratio and higher-order RMS.
measured = [p for p in panels if p[0] != "navarro-1985"]
strehls = np.array([p[2] for p in measured])
print(f"20 measured eyes: Strehl median {np.median(strehls):.3f}, range {strehls.min():.3f}-{strehls.max():.3f}; "
      f"Navarro {panels[-1][2]:.3f}")
fig, axes = plt.subplots(3, 7, figsize=(14, 6.6))
for ax, (name, seen, strehl, rms) in zip(axes.flat, panels):
    middle, half = size // 2, 36  # the letter and its blur, 18 arcmin across
    ax.imshow(seen[middle - half:middle + half, middle - half:middle + half], cmap="gray", vmin=0, vmax=1,
              interpolation="nearest")
    label = name.split(":")[1] if ":" in name else "Navarro"
    ax.set_title(f"{label}: S {strehl:.2f}, {rms:.2f} µm", fontsize=8)
    ax.set_axis_off()
fig.suptitle(f"K at LogMAR 0.1 through 20 real eyes (Jaeken & Artal 2012, right eyes 1-20) and Navarro's: "
             f"fovea, {pupil_mm:g} mm pupil, {nm:g} nm, best sphero-cylinder; S = Strehl, RMS of orders >= 3",
             fontsize=9)
fig.savefig(out / "t8_twenty_eyes.png", dpi=90, bbox_inches="tight")
plt.close(fig)
print("wrote", out / "t8_twenty_eyes.png")
