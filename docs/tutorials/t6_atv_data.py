"""Tutorial 6: the ATV participant data -- load it, analyse it, plot the fits.

The committed data (``validation/atv/subject_*.json``, transcribed from the thesis's appendix)
give, per eye, trial lens and session, the least display code value the participant could see.
`vissim.analyse_subject` fits ``y = a x^2 + b x + c`` per eye and condition (with and
without cycloplegic drops) and compares the vertex, with its Fieller interval, with the
measured spherical equivalent.

Run it as ``python docs/tutorials/t6_atv_data.py OUT_DIR``; the figure goes to OUT_DIR
(default: ``VISSIM_TUTORIAL_OUT``, else ``./tutorial_out``). ``--small`` changes nothing here
(the analysis takes well under a second).
"""

import os
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import vissim
from vissim.atv.report import plot_fits

args = [a for a in sys.argv[1:] if not a.startswith("--")]
out = Path(args[0] if args else os.environ.get("VISSIM_TUTORIAL_OUT", "tutorial_out"))
out.mkdir(parents=True, exist_ok=True)
data = Path(__file__).resolve().parents[2] / "validation" / "atv"

# 1. Load every participant (each file is checked against the thesis's own summary tables;
#    strict=True would turn a discrepancy into an error instead of a logged warning).
subjects = vissim.load_directory(data)
print(f"{len(subjects)} participant(s) in {data.name}/")

# 2. The quadratic analysis: one CurveAnalysis per eye and condition.
for subject in subjects:
    analyses = vissim.analyse_subject(subject)
    for a in analyses:
        interval = a.vertex_interval
        vertex = "no minimum" if a.vertex_diopters is None else f"{a.vertex_diopters:+.2f} D"
        se = "–" if a.measured_se_diopters is None else f"{a.measured_se_diopters:+.2f} D"
        print(f"{a.label}:\n  {len(a.lens_diopters)} lenses, vertex {vertex}, "
              f"{interval.method} {interval.level:.0%} interval {interval.describe()}, measured SE {se}")
        for note in a.notes:
            print("  note:", note)

    # 3. One figure per participant: rows = conditions, columns = eyes.
    plot_fits(analyses, out / f"t6_subject_{subject.subject_id}_fits.png",
              title=f"subject {subject.subject_id}", overwrite=True)
