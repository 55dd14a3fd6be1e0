"""The built-in demonstration: a LogMAR chart seen through two prescriptions.

Writes, under one output folder, the chart (linear EXR + sRGB PNG), the PSFs of an eye
corrected by ``-2.00 DS`` and by ``-2.00 DC x 90`` (3 mm pupil, 550 nm, wave optics) and the
chart blurred by each, every file with its provenance, plus ``summary.json``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vissim.chart_defaults import DEMO_PRESCRIPTIONS
from vissim.checks import DEFAULT_WAVELENGTH_NM
from vissim.atomic import write_json_atomic
from vissim.charts import etdrs_chart_spec, render_chart_angular
from vissim.imageio import to_preview_png, write_image
from vissim.optics.blur.convolve import blur_image
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import compute_psf, suggested_size_px
from vissim.optics.pupil.wavefront import Wavefront
from vissim.provenance import make_provenance

log = logging.getLogger(__name__)

@dataclass(frozen=True)
class DemoSettings:
    pupil_diameter_mm: float = 3.0
    wavelength_nm: float = DEFAULT_WAVELENGTH_NM
    arcmin_per_px: float = 1.0
    logmar_top: float = 1.0
    logmar_bottom: float = 0.3
    viewing_distance_m: float = 6.0


def run_demo(output_dir: str | Path, *, settings: DemoSettings = DemoSettings(), overwrite: bool = False) -> list[Path]:
    """Write the demonstration files; returns the paths written."""
    out = Path(output_dir)
    spec = etdrs_chart_spec((settings.logmar_top, settings.logmar_bottom), viewing_distance_m=settings.viewing_distance_m)
    chart = render_chart_angular(spec, settings.arcmin_per_px)
    chart_prov = make_provenance(command="demo", chart=chart.sidecar(), arcmin_per_px=settings.arcmin_per_px)
    written = [
        write_image(out / "chart.exr", chart.pixels, provenance=chart_prov, overwrite=overwrite),
        write_image(out / "chart.png", chart.pixels, provenance=chart_prov, overwrite=overwrite),
    ]
    summary = {"settings": settings.__dict__, "chart_shape_px": list(chart.pixels.shape), "cases": {}}
    for name, text in DEMO_PRESCRIPTIONS.items():
        rx = Prescription.parse(text)
        front = Wavefront.from_prescription(rx, settings.pupil_diameter_mm)
        size = suggested_size_px(front, settings.arcmin_per_px, wavelength_nm=settings.wavelength_nm)
        psf = compute_psf(front, wavelength_nm=settings.wavelength_nm, arcmin_per_px=settings.arcmin_per_px, size_px=size)
        fine = compute_psf(front, wavelength_nm=settings.wavelength_nm, arcmin_per_px=0.25, size_px=4 * size)
        blurred = blur_image(chart.pixels, psf, arcmin_per_px=settings.arcmin_per_px)
        prov = make_provenance(command="demo", prescription=str(rx), psf=psf.as_json(), chart=chart_prov["inputs"])
        written += [
            write_image(out / f"psf_{name}.exr", psf.data.astype(np.float32), provenance=prov, overwrite=overwrite),
            to_preview_png(out / f"psf_{name}.png", fine.data.astype(np.float32), provenance=prov, overwrite=overwrite),
            write_image(out / f"chart_{name}.exr", blurred, provenance=prov, overwrite=overwrite),
            write_image(out / f"chart_{name}.png", blurred, provenance=prov, overwrite=overwrite),
        ]
        summary["cases"][name] = {
            "prescription": str(rx),
            "psf_size_px": size,
            "energy_in_field": psf.energy_in_field,
            "mean_before": float(chart.pixels.mean(dtype=np.float64)),
            "mean_after": float(blurred.mean(dtype=np.float64)),
        }
        log.info("demo %s: %s", name, summary["cases"][name])
    written.append(write_json_atomic(out / "summary.json", summary, overwrite=overwrite))
    return written
