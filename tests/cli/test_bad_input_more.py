"""More bad or surprising input on the command line: one ``vissim: error:`` line and exit 2, or one warning.

Each case was once a traceback, a hang, or silently accepted: a truncated EXR, a ``--scheduler``
that is no Dask scheduler (a web server, another service, empty), and the rest below.
"""

import http.server
import socket
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from test_bad_input import assert_one_error_line, run  # run(capfd, ...) captures native output too

from vissim.errors import VissimInputError
from vissim.imageio import write_image
from vissim.validation.engine import runner
from vissim.validation.engine.scheduler import PROBE_TIMEOUT_S

TINY_CAMPAIGN = ('[campaign]\nname = "tiny"\nspp = 4\ntile_px = [48, 48]\nsimulations = ["geometric"]\n'
                 '[[item]]\nletter = "K"\nlogmar = 0.5\nlenses = [2.0]\n')


# -- a truncated EXR ---------------------------------------------------------------------------
@pytest.fixture
def valid_exr(tmp_path):
    path = tmp_path / "chart.exr"
    pixels = np.random.default_rng(0).uniform(0.05, 0.9, (64, 48)).astype(np.float32)  # noise: several chunks
    write_image(path, pixels, arcmin_per_px=1.0)
    return path


@pytest.mark.parametrize("fraction", [0.05, 0.5, 0.9])
def test_a_truncated_exr_is_one_line_naming_the_file_and_openexr_prints_nothing(capfd, tmp_path, valid_exr, fraction):
    data = valid_exr.read_bytes()
    cut = tmp_path / "cut.exr"
    cut.write_bytes(data[: int(len(data) * fraction)])
    out = tmp_path / "out.exr"
    code, stdout, err = run(capfd, "blur", cut, "-o", out, "--rx", "-1 DS", "--pupil-mm", "3")
    assert_one_error_line(code, err, str(cut), "cannot read as OpenEXR", "truncated")
    assert "IndexError" not in err and "list index" not in err
    assert stdout == "" and not out.exists()


# -- --scheduler at something that is no Dask scheduler ----------------------------------------
def validate_with_scheduler(capfd, tmp_path, address):
    (tmp_path / "tiny.toml").write_text(TINY_CAMPAIGN)
    started = time.perf_counter()
    code, _, err = run(capfd, "validate", tmp_path / "tiny.toml", "-o", tmp_path / "out", "--scheduler", address)
    return code, err, time.perf_counter() - started


@pytest.fixture(autouse=True)
def _no_rendering(monkeypatch):
    def refuse(spec):
        raise AssertionError(f"rendered {spec}")

    monkeypatch.setattr(runner, "render_any", refuse)


@pytest.fixture
def web_server():
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), http.server.SimpleHTTPRequestHandler)
    server.RequestHandlerClass.log_message = lambda *a: None
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{server.server_address[1]}"
    server.shutdown()
    server.server_close()


@pytest.fixture
def garbage_server():
    """A loopback service that greets every connection with bytes that are not Dask's."""
    listener = socket.create_server(("127.0.0.1", 0))
    stop = threading.Event()

    def serve():
        listener.settimeout(0.2)
        while not stop.is_set():
            try:
                conn, _ = listener.accept()
            except OSError:
                continue
            with conn:
                conn.sendall(b"SSH-2.0-OpenSSH_9.6\r\n" + b"\xff" * 64)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{listener.getsockname()[1]}"
    stop.set()
    thread.join()
    listener.close()


# The probe's three waits (connect, first bytes, a web reply), plus 3 s for Dask's set-up (warm interpreter).
WITHIN_S = 3 * PROBE_TIMEOUT_S + 3.0


def test_a_web_server_as_scheduler_fails_within_seconds_saying_it_answered_http(capfd, tmp_path, web_server):
    code, err, seconds = validate_with_scheduler(capfd, tmp_path, web_server)
    assert_one_error_line(code, err, web_server, "answered HTTP", "dashboard", "8786")
    assert seconds < WITHIN_S and not (tmp_path / "out").exists()


def test_another_service_as_scheduler_fails_within_seconds_naming_what_it_said(capfd, tmp_path, garbage_server):
    code, err, seconds = validate_with_scheduler(capfd, tmp_path, garbage_server)
    assert_one_error_line(code, err, garbage_server, "not the Dask protocol", "SSH-2.0")
    assert "EiB" not in err and seconds < WITHIN_S and not (tmp_path / "out").exists()


def test_a_silent_service_as_scheduler_fails_within_seconds(capfd, tmp_path):
    """A listener that accepts and never speaks (nor answers a web request): Dask would wait for minutes."""
    with socket.create_server(("127.0.0.1", 0)) as listener:  # the kernel accepts; nothing reads or writes
        address = f"tcp://127.0.0.1:{listener.getsockname()[1]}"
        code, err, seconds = validate_with_scheduler(capfd, tmp_path, address)
    assert_one_error_line(code, err, address, "accepted the connection but sent nothing")
    assert seconds < WITHIN_S and not (tmp_path / "out").exists()


@pytest.mark.parametrize("address", ["", "  "])
def test_an_empty_scheduler_is_an_error_not_a_local_run(capfd, tmp_path, address):
    code, err, _ = validate_with_scheduler(capfd, tmp_path, address)
    assert_one_error_line(code, err, "--scheduler is empty", "tcp://HOST:PORT")
    assert not (tmp_path / "out").exists()


def test_a_real_scheduler_passes_the_probe():
    """Oracle: a Dask scheduler on loopback; the probe must let it through (else no cluster could be used)."""
    distributed = pytest.importorskip("distributed")
    from vissim.validation.engine.scheduler import probe_scheduler

    with distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=None, host="127.0.0.1",
                                  scheduler_kwargs={"protocol": "tcp"}) as cluster:
        address = cluster.scheduler_address
        host, port = address.removeprefix("tcp://").rsplit(":", 1)
        probe_scheduler(address, host, int(port))  # returns: no error


# -- alpha and bit depth survive a blur --------------------------------------------------------
def _edge_rgba(tmp_path):
    """A sharp vertical edge in RGB with a patterned alpha (the oracle for 'carried unchanged')."""
    from PIL import Image as PILImage

    rgba = np.zeros((40, 40, 4), np.uint8)
    rgba[:, 20:, :3] = 230
    rgba[:, :, 3] = (np.arange(40)[:, None] * 6 + np.arange(40)[None, :]) % 256
    path = tmp_path / "edge.png"
    PILImage.fromarray(rgba, mode="RGBA").save(path)
    return path, rgba


BLUR = ["--rx", "-2 DS", "--pupil-mm", "3", "--arcmin-per-px", "1"]


@pytest.mark.parametrize("suffix", [".png", ".tif", ".exr"])
def test_blur_keeps_the_alpha_channel_unchanged_and_blurs_the_colour(capfd, tmp_path, suffix):
    from vissim.imageio import read_image

    path, rgba = _edge_rgba(tmp_path)
    out = tmp_path / f"out{suffix}"
    code, _, err = run(capfd, "blur", path, "-o", out, *BLUR)
    assert code == 0, err
    result = read_image(out)
    assert result.alpha is not None
    np.testing.assert_allclose(result.alpha * 255.0, rgba[..., 3], atol=1e-3)  # code for code
    sharp = read_image(path).pixels
    assert np.abs(result.pixels[:, 18:22] - sharp[:, 18:22]).max() > 0.05  # the edge was blurred


def test_blur_depth_keeps_the_alpha_channel_cropped_like_the_image(capfd, tmp_path):
    from vissim.imageio import read_image

    path, rgba = _edge_rgba(tmp_path)
    depth = tmp_path / "depth.npy"
    np.save(depth, np.full((40, 40), 2.0))
    out = tmp_path / "out.png"
    code, _, err = run(capfd, "blur-depth", path, depth, "-o", out, "--rx", "-2 DS", "--pupil-mm", "3",
                       "--arcmin-per-px", "1", "--crop-px", "4")
    assert code == 0, err
    result = read_image(out)
    np.testing.assert_allclose(result.alpha * 255.0, rgba[4:-4, 4:-4, 3], atol=1e-3)


def test_a_16_bit_png_is_written_back_at_16_bits(capfd, tmp_path):
    """Oracle: blur preserves a uniform image (the PSF sums to 1, the padding is the border mean), so each
    16-bit code comes back within one code; at 8 bits the level 12345/65535 would be off by ~50 codes."""
    from PIL import Image as PILImage

    path, out = tmp_path / "flat16.png", tmp_path / "out.png"
    PILImage.fromarray(np.full((40, 40), 12345, np.uint16)).save(path)
    code, _, err = run(capfd, "blur", path, "-o", out, *BLUR)
    assert code == 0, err
    with PILImage.open(out) as written:
        assert written.mode.startswith("I;16")
        assert np.abs(np.asarray(written).astype(int) - 12345).max() <= 1


def test_a_16_bit_colour_tiff_stays_16_bit_as_tiff_and_warns_once_as_png(capfd, tmp_path, caplog):
    import tifffile

    path = tmp_path / "flat16.tif"
    tifffile.imwrite(path, np.full((40, 40, 3), 40000, np.uint16), photometric="rgb")
    code, _, err = run(capfd, "blur", path, "-o", tmp_path / "out.tif", *BLUR)
    assert code == 0, err
    assert tifffile.imread(tmp_path / "out.tif").dtype == np.uint16
    code, _, err = run(capfd, "blur", path, "-o", tmp_path / "out.png", *BLUR)
    assert code == 0, err
    assert [r.getMessage() for r in caplog.records if r.levelname == "WARNING"] == [
        f"{tmp_path / 'out.png'}: 16-bit colour PNG cannot be written; writing 8 bits (use .tif or .exr to keep 16)"]


# -- --arcmin-per-px against the file's own sampling -------------------------------------------
def test_an_overriding_sampling_is_one_warning_line_naming_both(tmp_path, valid_exr):
    import subprocess
    import sys

    def blur(step):
        out = tmp_path / f"out{step}.exr"
        argv = [sys.executable, "-m", "vissim", "blur", str(valid_exr), "-o", str(out), "--rx", "-1 DS",
                "--pupil-mm", "3", "--arcmin-per-px", step]
        done = subprocess.run(argv, capture_output=True, text=True, check=False)
        assert done.returncode == 0, done.stderr
        return done.stderr.splitlines()

    assert blur("0.5") == [f"vissim: warning: --arcmin-per-px 0.5 overrides the 1 arcmin/px that {valid_exr} records"]
    assert blur("1") == []  # the same sampling: nothing to say


def test_fit_rx_warns_when_its_sampling_overrides_what_the_files_record(capfd, caplog, tmp_path, valid_exr,
                                                                        monkeypatch):
    import vissim.fit.rx_fit

    def stop(*args, **kwargs):
        raise VissimInputError("stopped before fitting")

    monkeypatch.setattr(vissim.fit.rx_fit, "fit_rx", stop)
    reference = tmp_path / "ref.exr"
    reference.write_bytes(valid_exr.read_bytes())
    code, _, err = run(capfd, "fit-rx", valid_exr, "--reference", reference, "--arcmin-per-px", "2",
                       "--pupil-mm", "3", "--magnification", "none")
    assert code == 2 and "stopped before fitting" in err
    assert [r.getMessage() for r in caplog.records if r.levelname == "WARNING"] == [
        f"--arcmin-per-px 2 overrides the 1 arcmin/px that {path} records" for path in (valid_exr, reference)]


# -- an image smaller than its blur ------------------------------------------------------------
@pytest.mark.parametrize("rows, cols", [(1, 1), (3, 5)])
def test_a_tiny_image_is_refused_naming_its_size_width_by_height(capfd, tmp_path, rows, cols):
    path, out = tmp_path / "tiny.exr", tmp_path / "out.exr"
    write_image(path, np.ones((rows, cols), np.float32), arcmin_per_px=1.0)
    code, _, err = run(capfd, "blur", path, "-o", out, "--rx", "-1 DS", "--pupil-mm", "3")
    assert_one_error_line(code, err, str(path), f"the image is {cols} × {rows} px" + ("" if rows == cols else " (width × height)"), "at least")
    assert not out.exists()


# -- samples per pixel out of range ------------------------------------------------------------
def spp_campaign(tmp_path, spp: str):
    path = tmp_path / "spp.toml"
    path.write_text(TINY_CAMPAIGN.replace("spp = 4", f"spp = {spp}"))
    return path


@pytest.mark.parametrize("spp", ["1e9", "1e400", "0", "-3"])
def test_spp_out_of_range_says_the_range_not_whole_number(capfd, tmp_path, spp):
    code, _, err = run(capfd, "validate", spp_campaign(tmp_path, spp), "-o", tmp_path / "out")
    assert_one_error_line(code, err, "campaign.spp", "must be 1 to 65536 samples per pixel")
    assert "whole number" not in err and not (tmp_path / "out").exists()


def test_spp_in_range_but_fractional_says_whole_number(capfd, tmp_path):
    code, _, err = run(capfd, "validate", spp_campaign(tmp_path, "2.5"), "-o", tmp_path / "out")
    assert_one_error_line(code, err, "campaign.spp", "whole number", "1 to 65536")


def test_the_spp_check_of_the_library_names_the_range_first():
    from vissim.checks import MAX_SPP, samples_per_pixel
    from vissim.errors import VissimInputError

    with pytest.raises(VissimInputError, match=f"must be 1-{MAX_SPP} samples per pixel, got 1000000000.0"):
        samples_per_pixel(1e9)
    assert samples_per_pixel(4.0) == 4


# -- configuration names -----------------------------------------------------------------------
def named_campaign(tmp_path, name: str, where: str = "item"):
    path = tmp_path / "named.toml"
    entry = 'letter = "K"\nlogmar = 0.5\n' if where == "item" else 'letter = ["K"]\nlogmar = [0.5]\n'
    path.write_text(TINY_CAMPAIGN.split("[[item]]")[0] + f"[[{where}]]\nname = {name}\n{entry}")
    return path


def test_a_10_mb_configuration_name_is_refused_stating_the_limit(capfd, tmp_path):
    from vissim.checks import MAX_NAME_CHARS

    code, _, err = run(capfd, "validate", named_campaign(tmp_path, '"' + "x" * 10**7 + '"'), "-o", tmp_path / "out")
    assert_one_error_line(code, err, "item[0].name", f"at most {MAX_NAME_CHARS} characters", "got 10000000")
    assert len(err) < 300 and not (tmp_path / "out").exists()


@pytest.mark.parametrize("name, where", [('"a\\nb"', "sweep"), ('"tab\\there"', "item")])
def test_a_configuration_name_with_a_control_character_is_refused(capfd, tmp_path, name, where):
    code, _, err = run(capfd, "validate", named_campaign(tmp_path, name, where), "-o", tmp_path / "out")
    assert_one_error_line(code, err, f"{where}[0].name", "one line of printable text")


def test_a_name_at_the_limit_loads():
    from vissim.checks import MAX_NAME_CHARS, name_problem

    assert name_problem("K +0.5 black: +2.00 D, f/5 ±0.25 D") is None
    assert name_problem("n" * MAX_NAME_CHARS) is None and name_problem("n" * (MAX_NAME_CHARS + 1))
    docs = Path(__file__).parents[2] / "docs"
    assert f"at most {MAX_NAME_CHARS} printable characters" in (docs / "formats.md").read_text(encoding="utf-8")


# -- --lenses '' -------------------------------------------------------------------------------
@pytest.mark.parametrize("lenses", ["", " , "])
def test_empty_lenses_are_an_error_not_the_default_lenses(capfd, tmp_path, lenses):
    out = tmp_path / "atv"
    code, _, err = run(capfd, "atv", "simulate", "--rx", "-1 DS", "--pupil-mm", "3", "--lenses", lenses, "-o", out)
    assert_one_error_line(code, err, "--lenses is empty")
    assert not out.exists()


def test_a_10_mb_campaign_description_is_refused_stating_the_limit(capfd, tmp_path):
    from vissim.checks import MAX_DESCRIPTION_CHARS

    path = tmp_path / "described.toml"
    head, items = TINY_CAMPAIGN.split("[[item]]")
    path.write_text(head.replace("[campaign]\n", '[campaign]\ndescription = "' + "d" * 10**7 + '"\n')
                    + "[[item]]" + items)
    code, _, err = run(capfd, "validate", path, "-o", tmp_path / "out")
    assert_one_error_line(code, err, "description", f"at most {MAX_DESCRIPTION_CHARS} characters", "got 10000000")
    assert not (tmp_path / "out").exists()
    docs = Path(__file__).parents[2] / "docs"
    assert f"at most {MAX_DESCRIPTION_CHARS} characters" in (docs / "formats.md").read_text(encoding="utf-8")


def test_an_unknown_option_points_to_its_own_command_s_help(capfd):
    code, _, err = run(capfd, "atv", "simulate", "--rx", "+1.00 DS", "--pupil-mm", "4", "--slope", "3", "-o", "x")
    assert_one_error_line(code, err, "unrecognized arguments: --slope 3", "(see 'vissim atv simulate --help')")


@pytest.mark.parametrize("argv", [("fit-rx", ".", "--reference", "."), ("blur", ".", "-o", "x.png", "--rx", "plano",
                                                                         "--pupil-mm", "3")])
def test_a_folder_spelled_dot_as_an_image_is_one_error_line(capfd, argv):
    code, _, err = run(capfd, *argv)
    assert_one_error_line(code, err, ". is a folder, not an image file")


@pytest.mark.parametrize("name", ["jaeken-artal-2012:17:right", "le-grand"])
def test_an_eye_named_without_its_option_is_pointed_to_eye_model(capfd, name):
    code, _, err = run(capfd, "eye", name, "--pupil-mm", "4")
    assert_one_error_line(code, err, f"unrecognized arguments: {name}", f"an eye is chosen with --eye-model {name}")
