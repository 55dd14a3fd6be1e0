"""A failed write never leaves a trace: one error line, exit 2, old files intact, no temporary file.

Oracle: the files on disk before and after.  A full disk is simulated by making the writer
that vissim calls (OpenEXR, Pillow, matplotlib, a text write) write part of its file and then
fail as it does on a full disk: OpenEXR raises ``RuntimeError('... No space left on device.')``,
the others ``OSError(ENOSPC)``.
"""

import errno
import os
from pathlib import Path

import matplotlib.figure
import numpy as np
import OpenEXR
import PIL.Image
import pytest

import vissim.imageio
from vissim.atomic import atomic_output, existing_output_error, output_transaction, refuse_existing
from vissim.cli import main
from vissim.errors import VissimInputError
from vissim.imageio import write_image

FULL = os.strerror(errno.ENOSPC)  # "No space left on device"


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("vissim: error: "), err
    return err[0]


def snapshot(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


def full_disk_oserror(path):
    Path(path).write_bytes(b"half a file")
    raise OSError(errno.ENOSPC, FULL)


class FullDiskExr:
    """OpenEXR.File whose write fails as OpenEXR's does on a full disk (reading is untouched)."""

    real = OpenEXR.File

    def __init__(self, *args, **kwargs):
        self._file = self.real(*args, **kwargs)

    def __getattr__(self, name):
        return getattr(self._file, name)

    def write(self, name):
        Path(name).write_bytes(b"half a file")
        raise RuntimeError(f'Failed to write pixel data to image file "{name}". {FULL}.')


@pytest.fixture
def chart_png(tmp_path):
    """A small chart with its sampling: the input of blur."""
    path = tmp_path / "in" / "chart.png"
    assert main(["chart", "--tile", "--letter", "N", "--logmar", "0.5", "-o", str(path)]) == 0
    return path


@pytest.mark.parametrize("suffix", [".exr", ".png"])
def test_blur_on_a_full_disk(tmp_path, capsys, monkeypatch, chart_png, suffix):
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    (out_dir / f"blurred{suffix}").write_bytes(b"an earlier result")
    before = snapshot(out_dir)
    monkeypatch.setattr(vissim.imageio.OpenEXR, "File", FullDiskExr)
    monkeypatch.setattr(PIL.Image.Image, "save", lambda self, fp, *a, **k: full_disk_oserror(fp))
    capsys.readouterr()
    code = main(["blur", str(chart_png), "-o", str(out_dir / f"blurred{suffix}"), "--rx", "-1.00 DS",
                 "--pupil-mm", "3", "--overwrite"])
    line = one_error_line(capsys)
    assert code == 2 and f"cannot write {out_dir / f'blurred{suffix}'}: {FULL}" in line, line
    assert snapshot(out_dir) == before  # the old file intact, no temporary file, no sidecar


def test_psf_png_on_a_full_disk_leaves_not_even_its_exr(tmp_path, capsys, monkeypatch):
    """psf -o out.png writes out.exr, then the preview: when the preview fails, neither appears."""
    monkeypatch.setattr(PIL.Image.Image, "save", lambda self, fp, *a, **k: full_disk_oserror(fp))
    code = main(["psf", "--rx", "-1.00 DS", "--pupil-mm", "3", "--size", "64", "--arcmin-per-px", "0.5",
                 "-o", str(tmp_path / "psf.png")])
    assert code == 2 and f"cannot write {tmp_path / 'psf.png'}: {FULL}" in one_error_line(capsys)
    assert snapshot(tmp_path) == {}


def test_psf_exr_on_a_full_disk(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(vissim.imageio.OpenEXR, "File", FullDiskExr)
    code = main(["psf", "--rx", "-1.00 DS", "--pupil-mm", "3", "--size", "64", "--arcmin-per-px", "0.5",
                 "-o", str(tmp_path / "psf.exr")])
    line = one_error_line(capsys)
    assert code == 2 and line.endswith(f"cannot write {tmp_path / 'psf.exr'}: {FULL}; nothing there was changed")
    assert snapshot(tmp_path) == {}


def test_chart_print_pdf_on_a_full_disk(tmp_path, capsys, monkeypatch):
    pdf = tmp_path / "chart.pdf"
    pdf.write_bytes(b"%PDF an earlier chart")
    before = snapshot(tmp_path)
    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", lambda self, fname, *a, **k: full_disk_oserror(fname))
    code = main(["chart", "--print", "--logmar-range", "1.0,0.8", "-o", str(pdf), "--overwrite"])
    assert code == 2 and f"cannot write {pdf}: {FULL}" in one_error_line(capsys)
    assert snapshot(tmp_path) == before


def test_chart_whose_letter_boxes_cannot_be_written_leaves_no_chart(tmp_path, capsys, monkeypatch):
    """The last file of three fails: the image and its provenance sidecar do not appear either."""
    real = Path.write_text

    def write_text(self, data, *args, **kwargs):
        if ".letters.json" in self.name:
            full_disk_oserror(self)
        return real(self, data, *args, **kwargs)

    monkeypatch.setattr(Path, "write_text", write_text)
    code = main(["chart", "--tile", "--letter", "N", "--logmar", "0.5", "-o", str(tmp_path / "tile.png")])
    said = capsys.readouterr()
    assert code == 2 and said.out == "", "a 'wrote' line for a file that was then taken back"
    assert len(said.err.splitlines()) == 1 and "tile.png.letters.json" in said.err
    assert snapshot(tmp_path) == {}


def test_a_command_says_what_it_wrote_once_it_is_written(tmp_path, capsys):
    code = main(["chart", "--tile", "--letter", "N", "--logmar", "0.5", "-o", str(tmp_path / "tile.png")])
    assert code == 0
    wrote = [line.split()[1] for line in capsys.readouterr().out.splitlines() if line.startswith("wrote ")]
    assert wrote and all(Path(path).exists() for path in wrote)


def test_a_transaction_renames_nothing_when_a_later_write_fails(tmp_path):
    (tmp_path / "a.txt").write_text("old a")
    with pytest.raises(VissimInputError, match="b.txt"):
        with output_transaction():
            with atomic_output(tmp_path / "a.txt", overwrite=True) as tmp:
                tmp.write_text("new a")
            with atomic_output(tmp_path / "b.txt") as tmp:
                full_disk_oserror(tmp)
    assert snapshot(tmp_path) == {"a.txt": b"old a"}


def test_one_output_written_twice_in_one_command_is_refused(tmp_path):
    with pytest.raises(VissimInputError, match="written twice"):
        with output_transaction():
            for _ in range(2):
                with atomic_output(tmp_path / "x" / ".." / "a.txt") as tmp:
                    tmp.write_text("a")
    assert snapshot(tmp_path) == {}


@pytest.mark.parametrize("spelling", ["same", "dotdot", "hardlink"])
def test_two_outputs_of_one_command_that_are_one_file_are_refused_before_any_work(tmp_path, capsys, spelling):
    # vissim.atomic.check_outputs_apart decides it for every command; render depth has three outputs
    scene = Path(__file__).resolve().parents[2] / "scenes" / "depth_panels.toml"
    blurred = tmp_path / "blurred.exr"
    if spelling == "hardlink":
        blurred.write_bytes(b"mine")
        os.link(blurred, tmp_path / "linked.exr")
    other = {"same": blurred, "dotdot": tmp_path / "x" / ".." / "blurred.exr", "hardlink": tmp_path / "linked.exr"}
    before = snapshot(tmp_path)
    code = main(["render", "depth", str(scene), "-o", str(blurred), "--depth", str(other[spelling]), "--overwrite"])
    assert code == 2 and "are the same file" in one_error_line(capsys)
    assert snapshot(tmp_path) == before


def test_the_refusal_to_overwrite_has_one_wording(tmp_path, capsys):
    """The library, the image writer and every command say the same words (vissim.atomic.existing_output_error)."""
    taken = tmp_path / "taken.png"
    taken.write_bytes(b"mine")
    expected = str(existing_output_error(taken))
    with pytest.raises(VissimInputError) as library:
        refuse_existing(taken, overwrite=False)
    with pytest.raises(VissimInputError) as writer:
        write_image(taken, [[0.5]])
    code = main(["chart", "--tile", "--letter", "N", "--logmar", "0.5", "-o", str(taken)])
    assert code == 2 and one_error_line(capsys) == f"vissim: error: {expected}"
    assert str(library.value) == str(writer.value) == expected
    assert "--overwrite" in expected and "overwrite=True" in expected


def test_a_failed_command_leaves_no_folder_it_made(tmp_path, capsys, monkeypatch):
    """demo -o new/demo on a full disk: no file, and not the folders made to hold them."""
    monkeypatch.setattr(vissim.imageio.OpenEXR, "File", FullDiskExr)
    assert main(["demo", "-o", str(tmp_path / "new" / "demo")]) == 2
    assert "cannot write" in one_error_line(capsys)
    assert list(tmp_path.iterdir()) == []


def test_a_stale_sidecar_is_removed_only_when_the_command_succeeds(tmp_path):
    """An image rewritten without provenance drops its old sidecar, but not if the command then fails."""
    path = tmp_path / "a.png"
    write_image(path, np.full((4, 4), 0.5), provenance={"command": "first"})
    with pytest.raises(RuntimeError, match="later failure"):
        with output_transaction():
            write_image(path, np.full((4, 4), 0.25), overwrite=True)
            raise RuntimeError("later failure")
    assert (tmp_path / "a.png.json").exists()
    with output_transaction():
        write_image(path, np.full((4, 4), 0.25), overwrite=True)
    assert not (tmp_path / "a.png.json").exists()
