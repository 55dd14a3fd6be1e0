"""Tutorial 9: a schematic eye, traced surface by surface.

A schematic eye is a published model of the average adult eye: cornea, aqueous, crystalline lens, vitreous,
each surface with its radius, asphericity and distance, each medium with its dispersion. vissim traces real
rays through it, so its refraction, aberrations and image quality come out of the optics, not out of a
formula. This tutorial takes Navarro's eye (1985) and asks it, in order:

1. its power, focal length, retinal scale, entrance pupil and refraction;
2. its wavefront (Zernikes), Strehl ratio and MTF against the diffraction limit;
3. the same 10 and 20 degrees off axis (oblique astigmatism: tangential and sagittal MTFs differ);
4. the eye made to need -3.00 D, bare and through a -3.00 D crown trial lens;
5. a letter chart as the relaxed eye, the myope and the eye 15 degrees off axis see it.

Run it as ``python docs/tutorials/t9_schematic_eye.py OUT_DIR [--small]``; the figure goes to OUT_DIR
(default: the ``VISSIM_TUTORIAL_OUT`` environment variable, else ``./tutorial_out``). The test suite runs it
with ``--small`` (a smaller chart) into a temporary directory. The same numbers come from the command line:
``vissim eye --eye-model navarro-1985 --pupil-mm 4 --wavelength-nm 555 --mtf-cyc-per-deg 10,20,30``.
"""

import os
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, no window
import matplotlib.pyplot as plt
import numpy as np

import vissim
from vissim.bench.atv.tube import atv_trial_lens
from vissim.optics.eyes.report import eye_mtf, eye_report

small = "--small" in sys.argv
args = [a for a in sys.argv[1:] if not a.startswith("--")]
out = Path(args[0] if args else os.environ.get("VISSIM_TUTORIAL_OUT", "tutorial_out"))
out.mkdir(parents=True, exist_ok=True)

# 1. The eye: Navarro's model, relaxed (0 D of accommodation), with a 4 mm entrance pupil (the pupil a
#    clinician measures: the iris's image through the cornea; the iris itself is smaller). All numbers
#    are in 555 nm light, the peak of photopic (daylight) vision. Navarro's eye is focused for 589.3 nm,
#    its reference wavelength; in greener light it is a little myopic (the eye's chromatic aberration).
pupil_mm, nm = 4.0, 555.0
eye = vissim.build_eye("navarro-1985", pupil_diameter_mm=pupil_mm)
report = eye_report(eye, wavelength_nm=nm, mtf_cyc_per_deg=[10, 20, 30])
print(f"power {report.power_diopters:.2f} D, f' {report.image_focal_length_mm:.2f} mm, "
      f"{report.retinal_mm_per_deg * 1000:.1f} um of retina per degree")
print(f"iris {report.wavefront.iris_mm:.2f} mm for a {pupil_mm:g} mm entrance pupil")
# The refraction is the lens that would correct the eye (a myope's is negative), at the corneal vertex.
# Paraxial: from the wavefront's curvature at the pupil's centre. Minimum RMS: the sphero-cylinder that
# flattens the whole wavefront best; with spherical aberration (the pupil's edge focuses more strongly)
# it asks for more minus than the paraxial one.
print(f"refraction: paraxial {report.refraction.paraxial}, minimum RMS {report.refraction.minimum_rms}")

# 2. Its wavefront: OSA Zernike coefficients in micrometres over the entrance pupil. c(2,0) is defocus
#    (positive: myopic), c(4,0) primary spherical aberration; the rest are zero on axis (a centred eye).
front = vissim.eye_wavefront(eye, wavelength_nm=nm)
shown = {key: round(value, 4) for key, value in front.coefficients_um.items() if abs(value) > 5e-4}
print("Zernikes (um):", shown)
# The Strehl ratio is the PSF's peak over a perfect eye's: 1 is diffraction-limited; 0.8 is the usual bar
# for "well corrected". Best-corrected spectacles remove orders 0-2; what is left is spherical aberration.
corrected = vissim.Wavefront({key: value for key, value in front.coefficients_um.items() if key[0] >= 3},
                             pupil_mm, nm)
print(f"Strehl ratio: {vissim.strehl_ratio(front, wavelength_nm=nm):.3f} as it is, "
      f"{vissim.strehl_ratio(corrected, wavelength_nm=nm):.3f} with orders 0-2 corrected")
# The MTF is the contrast the optics pass at each spatial frequency (1: all of it). 30 cycles per degree
# is the finest grating a 20/20 (LogMAR 0) eye resolves; the diffraction limit is the best any 4 mm pupil
# can do.
f = np.array([10.0, 20.0, 30.0])
as_is = report.mtf_cyc_per_deg["radial"]
best = eye_mtf(corrected, nm, f)["radial"]
limit = vissim.diffraction_mtf(f, pupil_mm, nm)
for k, cpd in enumerate(f):
    print(f"MTF at {cpd:.0f} c/deg: {as_is[k][1]:.3f} as it is, {best[k]:.3f} corrected, "
          f"{limit[k]:.3f} diffraction limit")

# 3. Off axis: a chief ray 10 or 20 degrees from the optical axis meets the surfaces obliquely, so the eye
#    has oblique astigmatism. The refraction grows a cylinder; the MTF differs along the field's meridian
#    (tangential) and across it (sagittal).
for field in (10.0, 20.0):
    off = eye_report(eye, wavelength_nm=nm, field_deg=(field, 0.0), mtf_cyc_per_deg=f)
    tangential, sagittal = off.mtf_cyc_per_deg["tangential"], off.mtf_cyc_per_deg["sagittal"]
    print(f"{field:g} deg off axis: refraction {off.refraction.minimum_rms}; MTF at 10 c/deg "
          f"{tangential[0][1]:.3f} tangential, {sagittal[0][1]:.3f} sagittal")

# 4. A myope: the same model made to need -3.00 D at the spectacle plane (12 mm in front of the cornea;
#    its eyeball is longer). Bare, it sees nothing fine; through a -3.00 D crown-glass trial lens at 12 mm
#    the over-refraction (what is left to correct, in front of the lens) is back near the relaxed eye's.
myope = vissim.build_eye("navarro-1985", pupil_diameter_mm=pupil_mm, rx="-3.00")
bare = eye_report(myope, wavelength_nm=nm, mtf_cyc_per_deg=[10])
worn = eye_report(myope, wavelength_nm=nm, mtf_cyc_per_deg=[10], lenses=(atv_trial_lens(-3.0),))
print(f"-3 D myope: refraction {bare.refraction.minimum_rms}, MTF at 10 c/deg {bare.mtf_cyc_per_deg['radial'][0][1]:.3f}; "
      f"through the lens: over-refraction {worn.refraction.minimum_rms}, "
      f"MTF at 10 c/deg {worn.mtf_cyc_per_deg['radial'][0][1]:.3f}")

# 5. What each sees: a letter chart in visual angle (1 arcmin per pixel). At the fovea one PSF serves the
#    whole (small) chart: the traced wavefront's wave PSF, blurred into the chart in linear light. A chart
#    centred 15 degrees off axis needs `blur_eye`, which traces the PSF at field points 2 degrees apart and
#    interpolates between them, so each letter gets the oblique astigmatism of its own place in the field.
#    (In 555 nm light the relaxed eye is slightly myopic on axis, and less so at 10-15 degrees, where the
#    curved retina meets the curved image shell: the off-axis chart can look as sharp as the foveal one at
#    this size. Section 3's numbers say why; at 20 degrees the astigmatism wins.)
step = 1.0
spec = vissim.etdrs_chart_spec((0.7, 0.5) if small else (1.0, 0.4), letters="NCK" if small else "NCKZO")
chart = vissim.render_chart_angular(spec, arcmin_per_px=step)
views = []
for title, who in (("relaxed eye, fovea", eye), ("-3 D myope, fovea", myope)):
    psf = vissim.compute_psf(vissim.eye_wavefront(who, wavelength_nm=nm), wavelength_nm=nm, arcmin_per_px=step,
                             size_px=128)  # 2 degrees: holds the myope's 41 arcmin blur disc (4 mm x 3 D)
    views.append((title, vissim.blur_image(chart.pixels, psf, arcmin_per_px=step)))
views.append(("relaxed eye, 15 deg off axis",
              vissim.blur_eye(chart.pixels, eye, arcmin_per_px=step, wavelength_nm=nm, field_deg=(15.0, 0.0))))

frequencies = np.linspace(0.0, 60.0, 61)
fig = plt.figure(figsize=(11, 7))
ax = fig.add_subplot(2, 1, 1)
ax.plot(frequencies, eye_mtf(front, nm, frequencies)["radial"], label="on axis, as it is")
ax.plot(frequencies, eye_mtf(corrected, nm, frequencies)["radial"], label="on axis, orders 0-2 corrected")
off = vissim.eye_wavefront(eye, wavelength_nm=nm, field_deg=(20.0, 0.0))
for direction, style in (("tangential", ":"), ("sagittal", "-.")):
    ax.plot(frequencies, eye_mtf(off, nm, frequencies, field_deg=(20.0, 0.0))[direction], style,
            label=f"20 deg off axis, {direction}")
ax.plot(frequencies, vissim.diffraction_mtf(frequencies, pupil_mm, nm), "k--", label="diffraction limit")
ax.set_xlabel("spatial frequency (cycles/degree)")
ax.set_ylabel("MTF")
ax.set_title(f"Navarro's eye, {pupil_mm:g} mm pupil, {nm:g} nm")
ax.legend(fontsize=8)
for column, (title, image) in enumerate(views):
    panel = fig.add_subplot(2, 3, 4 + column)
    panel.imshow(image, cmap="gray", vmin=0, vmax=1)
    panel.set_title(title, fontsize=9)
    panel.axis("off")
fig.savefig(out / "t9_schematic_eye.png", dpi=80, bbox_inches="tight")
plt.close(fig)
print("wrote", out / "t9_schematic_eye.png")
