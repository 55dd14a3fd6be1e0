"""`vissim validate` on bad input: one `vissim: error:` line naming the culprit, exit 2, nothing written."""

import time

import pytest

from vissim.cli import main
from vissim.validation.engine import runner, scheduler

TINY = '[campaign]\nname = "tiny"\nspp = 4\ntile_px = [48, 48]\nsimulations = ["geometric"]\n' \
       '[[item]]\nletter = "K"\nlogmar = 0.5\nlenses = [2.0]\n'


def refuse(spec):  # a renderer that must not be called
    raise AssertionError(f"rendered {spec}")


@pytest.fixture(autouse=True)
def _no_rendering(monkeypatch):
    monkeypatch.setattr(runner, "render_any", refuse)


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("vissim: error: "), err
    return err[0]


def validate(campaign, out, *options) -> int:
    return main(["validate", str(campaign), "-o", str(out), *options])


@pytest.mark.parametrize("name, content, fragment", [
    ("absent.toml", None, "does not exist"),
    (".", None, "is a folder, not a campaign file"),
    ("binary.toml", b"\x89PNG\r\n\x1a\n\xff\xfe\x00", "not UTF-8"),
    ("notes.md", b"# Notes\n\nSome *text*.\n", "not valid TOML"),
    ("empty.toml", b"", "it is empty"),
    ("pyproject.toml", b'[project]\nname = "x"\n[tool.x]\ny = 1\n', "its tables: project, tool"),
    ("scene.toml", b"[image]\nsize_px = [8, 8]\n[[panel]]\ndistance_m = 1.0\n", "not a campaign file"),
])
def test_paths_that_are_not_campaign_files(tmp_path, capsys, name, content, fragment):
    path = tmp_path / "in" / name
    (tmp_path / "in").mkdir()
    if content is not None:
        path.write_bytes(content)
    out = tmp_path / "out"
    assert validate(path, out) == 2
    line = one_error_line(capsys)
    assert str(path) in line and fragment in line, line
    assert not out.exists()


def test_an_output_path_that_is_a_file(tmp_path, capsys):
    (tmp_path / "tiny.toml").write_text(TINY)
    (tmp_path / "taken").write_text("a file")
    assert validate(tmp_path / "tiny.toml", tmp_path / "taken") == 2
    assert "is a file, not a run folder" in one_error_line(capsys)


def test_an_unreachable_scheduler_fails_within_seconds(tmp_path, capsys):
    (tmp_path / "tiny.toml").write_text(TINY)
    started = time.perf_counter()
    assert validate(tmp_path / "tiny.toml", tmp_path / "out", "--scheduler", "tcp://127.0.0.1:1") == 2
    # the connect timeout, plus 3 s for Dask's client set-up and teardown (the interpreter is warm)
    assert time.perf_counter() - started < scheduler.SCHEDULER_TIMEOUT_S + 3.0
    line = one_error_line(capsys)
    assert "tcp://127.0.0.1:1" in line and "no Dask scheduler answered" in line
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("address", ["tcp://host:port", "foo://x:1", "tcp://:8786", "tcp://127.0.0.1:99999", "tcp://"])
def test_a_malformed_scheduler_address(tmp_path, capsys, address):
    (tmp_path / "tiny.toml").write_text(TINY)
    assert validate(tmp_path / "tiny.toml", tmp_path / "out", "--scheduler", address) == 2
    line = one_error_line(capsys)
    assert address in line and "not a Dask scheduler address" in line
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("options, fragment", [
    (["--workers", "0"], "--workers"), (["--spp", "0"], "--spp"), (["--spp", str(10**12)], "--spp"),
])
def test_bad_run_options(tmp_path, capsys, options, fragment):
    (tmp_path / "tiny.toml").write_text(TINY)
    assert validate(tmp_path / "tiny.toml", tmp_path / "out", *options) == 2
    assert fragment in one_error_line(capsys)
    assert not (tmp_path / "out").exists()


def capture_campaign(tmp_path, capture_entry: str):
    (tmp_path / "raw.dng").write_bytes(b"not the photograph the manifest describes")
    (tmp_path / "manifest.toml").write_text(capture_entry)
    (tmp_path / "captures.toml").write_text(
        '[campaign]\nname = "captures"\ntile_px = [48, 48]\nmanifest = "manifest.toml"\n'
        '[[item]]\nname = "from a photo"\nletter = "K"\nlogmar = 0.5\nlenses = [2.0]\ncapture = "k-plus2"\n'
        '[[item]]\nname = "not in the manifest"\nletter = "N"\nlogmar = 0.5\ncapture = "nowhere"\n')
    return tmp_path / "captures.toml"


def test_a_campaign_that_compares_nothing_exits_2_and_writes_no_report(tmp_path, capsys):
    path = capture_campaign(tmp_path, '[[capture]]\nid = "k-plus2"\nfile = "absent.dng"\nletter = "K"\n'
                                      'letter_center_px = [64.0, 64.0]\nno_lens_capture = "k-plain"\n')
    assert validate(path, tmp_path / "out") == 2
    line = one_error_line(capsys)
    assert "all 2 items were skipped" in line and "absent.dng is absent" in line and "'nowhere'" in line
    assert not (tmp_path / "out").exists()


def test_a_wrong_checksum_is_reported_before_a_missing_no_lens_capture(tmp_path, capsys):
    """Integrity first: the capture's own file is checked before the captures it refers to."""
    path = capture_campaign(tmp_path, '[[capture]]\nid = "k-plus2"\nfile = "raw.dng"\nsha256 = "' + "0" * 64 + '"\n'
                                      'letter = "K"\nletter_center_px = [64.0, 64.0]\n')
    assert validate(path, tmp_path / "out") == 2
    line = one_error_line(capsys)
    assert "does not match its sha256" in line and "no_lens_capture" not in line, line
