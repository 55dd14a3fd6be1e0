"""Tutorial 10: a measured eye, and a small population of them.

A measured eye is a real person's wavefront: Zernike coefficients measured with a Hartmann-Shack sensor over
a 4 mm pupil. vissim ships two datasets (Jaeken & Artal 2012: 130 subjects, both eyes, the horizontal
meridian -40...40 degrees; Polans et al. 2015: 10 right eyes over a 2-D field), checked by sha256 when
loaded. A measured eye is named ``dataset:subject[:eye]`` anywhere an eye is named, and sits on the relaxed
Navarro schematic eye, which gives it a pupil position, a retinal scale and a dispersion; its aberrations
(orders 2 and up) are the person's. This tutorial:

1. builds subject 17's right eye (Jaeken & Artal) and reads its refraction and wavefront;
2. computes its Strehl ratio and MTF as it is and with its best spectacles (orders 0-2 removed);
3. sets it beside Navarro's schematic eye and Watson's (2013) published mean MTF of corrected human eyes;
4. evaluates a small population (the first right eyes of the dataset) and their quantiles.

Run it as ``python docs/tutorials/t10_measured_eye.py OUT_DIR [--small]``; the figure goes to OUT_DIR
(default: the ``VISSIM_TUTORIAL_OUT`` environment variable, else ``./tutorial_out``). The test suite runs it
with ``--small`` (10 eyes instead of 40) into a temporary directory. From the command line:
``vissim eye --eye-model jaeken-artal-2012:17:right --pupil-mm 4 --wavelength-nm 555`` and
``vissim population jaeken-artal-2012 --pupil-mm 4 -o runs/population`` (all 260 eyes).
"""

import os
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, no window
import matplotlib.pyplot as plt
import numpy as np

import vissim
from vissim.optics.eyes.measured.population import (PopulationCondition, evaluate_population,
                                                     population_quantiles, schematic_mtf, select_eyes)
from vissim.optics.eyes.measured.published import watson_2013_mtf
from vissim.optics.eyes.models import eye_model
from vissim.optics.eyes.report import eye_mtf, eye_report

small = "--small" in sys.argv
args = [a for a in sys.argv[1:] if not a.startswith("--")]
out = Path(args[0] if args else os.environ.get("VISSIM_TUTORIAL_OUT", "tutorial_out"))
out.mkdir(parents=True, exist_ok=True)

# 1. One real eye at the fovea, over the data's 4 mm pupil, in 555 nm light (the photopic peak). The data
#    were measured in the near infrared (780 nm); vissim carries the defocus to 555 nm with the base eye's
#    chromatic difference of focus.
pupil_mm, nm = 4.0, 555.0
name = "jaeken-artal-2012:17:right"
eye = vissim.build_eye(name, pupil_diameter_mm=pupil_mm)
report = eye_report(eye, wavelength_nm=nm)
rx = report.refraction.minimum_rms
m, j0, j45 = rx.power_vector()
# The refraction is the correcting lens at the corneal vertex. M is the spherical equivalent (sphere + half
# the cylinder), J0 and J45 the astigmatism as two crossed Jackson cylinders: -7 D of M is a high myope.
print(f"{name}: refraction {rx} (M {m:+.2f}, J0 {j0:+.2f}, J45 {j45:+.2f} D)")
front = vissim.eye_wavefront(eye, wavelength_nm=nm)
higher = {key: value for key, value in front.coefficients_um.items() if key[0] >= 3}
rms_higher = float(np.sqrt(sum(v * v for v in higher.values())))
print(f"wavefront RMS {report.wavefront.rms_um:.2f} um (orders >= 2), of which orders >= 3: {rms_higher:.3f} um")
print("largest higher-order Zernikes (um):",
      {key: round(value, 3) for key, value in sorted(higher.items(), key=lambda kv: -abs(kv[1]))[:4]})

# 2. Strehl ratio and MTF. As it is, the eye is 7 D out of focus: almost nothing passes. With its best
#    sphero-cylinder (orders 0-2 removed) what is left is the higher-order aberration spectacles cannot
#    correct: this eye's is 0.1 um RMS, mostly vertical coma c(3,-1).
corrected = vissim.Wavefront(higher, pupil_mm, nm)
print(f"Strehl ratio {vissim.strehl_ratio(front, wavelength_nm=nm):.1e} as it is, "
      f"{vissim.strehl_ratio(corrected, wavelength_nm=nm):.3f} with its best sphero-cylinder")
f = np.array([10.0, 20.0, 30.0])
condition = PopulationCondition(pupil_mm, (0.0, 0.0), "sphero-cylinder", nm)  # fovea, best corrected
mtf_subject = eye_mtf(corrected, nm, f)["radial"]
mtf_navarro = schematic_mtf(eye_model("navarro-1985"), condition, f)  # corrected the same way
mtf_watson = watson_2013_mtf(f, pupil_mm)  # the mean of ~200 corrected eyes, 555 nm, from their wavefronts
for k, cpd in enumerate(f):
    print(f"MTF at {cpd:.0f} c/deg: subject 17 {mtf_subject[k]:.3f}, Navarro {mtf_navarro[k]:.3f}, "
          f"Watson 2013 {mtf_watson[k]:.3f}")

# 3. A small population: the first right eyes of the dataset, each with its best sphero-cylinder. One trace
#    of the base eye serves them all; each eye's numbers are its own (MTF, Strehl, M/J0/J45, higher-order
#    RMS). `population_quantiles` gives the 5/25/50/75/95 % quantiles across the eyes.
count = 10 if small else 40
eyes = select_eyes("jaeken-artal-2012", subjects=range(1, count + 1), eyes=["right"])
results = evaluate_population(eyes, [condition], f)
quantiles = population_quantiles(results)[condition.label]
print(f"{quantiles['count']} right eyes, {condition.label}:")
print("  median MTF at 10/20/30 c/deg:", " / ".join(f"{v:.3f}" for v in quantiles["mtf"][2]))
print("  25-75 % at 10 c/deg:", " - ".join(f"{v:.3f}" for v in quantiles["mtf"][[1, 3], 0]))
print("  Strehl median {:.3f}, 5-95 % {:.3f}-{:.3f}".format(*quantiles["strehl"][[2, 0, 4]]))
print("  spherical equivalent M median {:+.2f} D, 5-95 % {:+.2f}...{:+.2f} D".format(*quantiles["m_diopters"][[2, 0, 4]]))
# Navarro's schematic eye sits at or above the population's upper quartile: schematic eyes are built with the
# average eye's spherical aberration and nothing else, while every real eye has some coma, trefoil and
# more. Watson's curve lies far below both, though it too is computed from corrected wavefronts at 555 nm;
# vissim does not yet explain that difference (the Command-line guide, "Populations of measured eyes").

# 4. The figure: MTF curves of subject 17, the population's median and quartiles, Navarro's and Watson's.
frequencies = np.linspace(0.0, 60.0, 31)
curves = evaluate_population(eyes, [condition], frequencies)
stack = np.stack([r.mtf for r in curves])
fig, ax = plt.subplots(figsize=(7, 4.5))
ax.fill_between(frequencies, np.quantile(stack, 0.25, axis=0), np.quantile(stack, 0.75, axis=0), alpha=0.3,
                label=f"{len(curves)} measured eyes, 25-75 %")
ax.plot(frequencies, np.median(stack, axis=0), label="their median")
ax.plot(frequencies, eye_mtf(corrected, nm, frequencies)["radial"], label="subject 17, right eye")
ax.plot(frequencies, schematic_mtf(eye_model("navarro-1985"), condition, frequencies), label="Navarro's eye")
ax.plot(frequencies, watson_2013_mtf(frequencies, pupil_mm), ":", label="Watson 2013 mean")
ax.plot(frequencies, vissim.diffraction_mtf(frequencies, pupil_mm, nm), "k--", label="diffraction limit")
ax.set_xlabel("spatial frequency (cycles/degree)")
ax.set_ylabel("MTF")
ax.set_title(f"fovea, {pupil_mm:g} mm pupil, {nm:g} nm, best sphero-cylinder", fontsize=10)
ax.legend(fontsize=8)
fig.savefig(out / "t10_measured_eye.png", dpi=90, bbox_inches="tight")
plt.close(fig)
print("wrote", out / "t10_measured_eye.png")
