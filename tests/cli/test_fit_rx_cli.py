"""``vissim fit-rx``: sampling and pupil from the files, the bench tie from flags, one-line refusals."""

import json

import numpy as np
import pytest

from vissim.cli import main
from vissim.imageio import write_image
from vissim.optics.rx.trial_lens import TrialLens
from vissim.provenance import make_provenance

from tests.fit.synthetic import capture


@pytest.fixture(scope="module")
def plus_two():
    return capture(TrialLens(2.0))


def _write(path, pixels, step=1.0):
    write_image(path, np.asarray(pixels, np.float32), provenance=make_provenance(command="test"), arcmin_per_px=step,
                overwrite=True)
    return str(path)


def test_the_bench_tie_from_flags_gives_a_signed_fit_as_json(tmp_path, plus_two, capsys):
    image, reference, truth = plus_two
    out = tmp_path / "fit.json"
    code = main(["fit-rx", _write(tmp_path / "i.exr", image), "--reference", _write(tmp_path / "r.exr", reference),
                 "--pupil-mm", "3.6", "--mode", "geometric", "--vertex-mm", "10", "--object-distance-m", "0.9144",
                 "--json", "-o", str(out)])
    record = json.loads(capsys.readouterr().out)
    assert code == 0 and record["status"] == "ok"
    assert record["sphere_diopters"] == pytest.approx(truth[0], abs=0.03)
    assert record["settings"]["arcmin_per_px"] == 1.0  # read from the files
    written = json.loads(out.read_text())
    assert written["fit"]["status"] == "ok" and written["provenance"]["inputs"]["command"] == "fit-rx"
    assert record["written"] == [str(out)] and record["provenance"] == written["provenance"]


def test_without_a_bench_the_text_output_says_the_sign_is_undetermined(tmp_path, plus_two, capsys):
    image, reference, _ = plus_two
    code = main(["fit-rx", _write(tmp_path / "i.exr", image), "--reference", _write(tmp_path / "r.exr", reference),
                 "--pupil-mm", "3.6", "--mode", "geometric"])
    out = capsys.readouterr().out
    assert code == 0 and "SIGN UNDETERMINED" in out and "either +1.9" in out and "either -1.9" in out


@pytest.mark.parametrize("case, message", [
    ("size", "they must match, pixel for pixel"),
    ("sampling", "IMAGE is sampled at 1.0 arcmin/px but REF at 0.5 arcmin/px"),
    ("no sampling", "give --arcmin-per-px"),
    ("no pupil", "give --pupil-mm"),
    ("half a bench", "--vertex-mm and --object-distance-m go together"),
    ("blurred reference", "reference is itself blurred"),
    ("flat image", "image has no structure"),
])
def test_bad_input_gets_one_error_line_and_exit_2(tmp_path, plus_two, capsys, case, message):
    image, reference, _ = plus_two
    img, ref = tmp_path / "i.exr", tmp_path / "r.exr"
    argv = ["fit-rx", str(img), "--reference", str(ref), "--pupil-mm", "3.6"]
    _write(img, image)
    _write(ref, reference)
    if case == "size":
        _write(ref, reference[:, :90])
    elif case == "sampling":
        _write(ref, reference, step=0.5)
    elif case == "no sampling":
        write_image(img, image.astype(np.float32), overwrite=True)
        write_image(ref, reference.astype(np.float32), overwrite=True)
    elif case == "no pupil":
        argv = argv[:4]
    elif case == "half a bench":
        argv += ["--vertex-mm", "10"]
    elif case == "blurred reference":
        _write(ref, capture(TrialLens(1.0), noise=0.0)[0])
    elif case == "flat image":
        _write(img, np.full_like(image, 0.5))
    code = main(argv + ["-o", str(tmp_path / "fit.json")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and err[0].startswith("vissim: error: ") and message in err[0], err
    assert not (tmp_path / "fit.json").exists()


def test_a_render_whose_lenses_theory_contradicts_is_reported_as_a_disagreement(tmp_path, plus_two, capsys):
    """The image records a bench with a +2.25 D lens (as ``vissim render bench`` does) but shows +2 D:
    the fit (about +1.99 D, interval +-0.01 D) is printed beside theory (+2.24 D) and flagged."""
    from vissim.bench.dslr.bench import DslrBench

    image, reference, _ = plus_two
    said = make_provenance(command="test", bench=DslrBench(lenses=(TrialLens(2.25),), size_px=(96, 96)))
    path = tmp_path / "i.exr"
    write_image(path, np.asarray(image, np.float32), provenance=said, arcmin_per_px=1.0)
    code = main(["fit-rx", str(path), "--reference", _write(tmp_path / "r.exr", reference), "--mode", "geometric",
                 "-o", str(tmp_path / "fit.json")])
    out = capsys.readouterr().out
    assert code == 0 and "vergence theory for the rendered lenses (+2.00 DS" not in out
    assert "DISAGREES: vergence theory lies outside the fit's 95 % interval in M" in out
    theory = json.loads((tmp_path / "fit.json").read_text())["fit"]["vergence_theory"]
    assert theory["agrees"] is False and theory["errors_diopters"]["M_diopters"] < -0.2
