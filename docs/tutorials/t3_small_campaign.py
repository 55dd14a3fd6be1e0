"""Tutorial 3: a small validation campaign and its report.

A campaign file lists configurations (a letter, its size, the trial lenses) and how to validate
them. For each, Mitsuba renders the DSLR bench with the lenses (the truth; two seeds give its
noise floor) and without them; each simulation is applied to the no-lens render and to the
synthetic chart, and compared with the truth (PSNR, SSIM). ``vissim.run_campaign`` writes every
image and number into a run directory, and the report (tables.md, report.html, figures) is built
from that directory alone. The same file runs with ``vissim validate campaign.toml -o RUN_DIR``.

This one is tiny: one configuration (a +2.00 D lens before a letter "K"), a 65 x 65 px tile and
few samples per pixel. See ``docs/formats.md`` for every field and ``validation/quick.toml`` for
a commented real campaign.

Run it as ``python docs/tutorials/t3_small_campaign.py OUT_DIR``; the campaign file, the run
directory and the report go to OUT_DIR (default: ``VISSIM_TUTORIAL_OUT``, else
``./tutorial_out``). ``--small`` uses fewer samples per pixel; it needs Mitsuba (``vissim[render]``).
"""

import os
import shutil
import sys
from pathlib import Path

import vissim
from vissim.validation.engine.report import write_report

small = "--small" in sys.argv
args = [a for a in sys.argv[1:] if not a.startswith("--")]
out = Path(args[0] if args else os.environ.get("VISSIM_TUTORIAL_OUT", "tutorial_out"))
out.mkdir(parents=True, exist_ok=True)

# 1. The campaign file (TOML). Units: f-number, samples per pixel, arcmin per pixel, pixels
#    [rows, cols], metres, millimetres, nanometres, dioptres.
spp = 16 if small else 132
(out / "t3_campaign.toml").write_text(f"""\
[campaign]
name = "tutorial"
description = "one letter through a +2.00 D trial lens"
f_number = 5.0
spp = {spp}
seeds = [1, 2]
arcmin_per_px = 1.0
tile_px = [65, 65]
chart_distance_m = 0.9144
vertex_distance_mm = 10.0
wavelength_nm = 550.0
simulations = ["wave", "geometric"]
inputs = ["render", "synthetic"]
wave_truth = false
fit_rx = false

[[item]]
name = "myopia +2.00 DS"
letter = "K"
logmar = 1.0
lenses = [2.0]
""")

# 2. Load it (every field is checked here, before anything runs) and run it. A run directory is
#    resumable: what it already holds is reused, so start from an empty one here.
campaign = vissim.load_campaign(out / "t3_campaign.toml")
run_dir = out / "t3_run"
shutil.rmtree(run_dir, ignore_errors=True)
summary = vissim.run_campaign(campaign, run_dir, show_progress=False)
print(f"{summary.items_total} item(s), {summary.renders_made} render(s) made, into {run_dir}")

# 3. The report, from the run directory alone.
for path in write_report(run_dir)[0]:
    print("report:", path)
print((run_dir / "tables.md").read_text()[:2000] if (run_dir / "tables.md").exists() else "")
