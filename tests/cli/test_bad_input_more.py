"""More bad or surprising input on the command line: one ``vissim: error:`` line and exit 2, or one warning.

Each case was once a traceback, a hang, or silently accepted: a truncated EXR, a ``--scheduler``
that is no Dask scheduler (a web server, another service, empty), and the rest below.
"""

import http.server
import socket
import threading
import time

import numpy as np
import pytest

from vissim.cli import main
from vissim.imageio import write_image
from vissim.validation import runner
from vissim.validation.scheduler_probe import PROBE_TIMEOUT_S

TINY_CAMPAIGN = ('[campaign]\nname = "tiny"\nspp = 4\ntile_px = [48, 48]\nsimulations = ["geometric"]\n'
                 '[[item]]\nletter = "K"\nlogmar = 0.5\nlenses = [2.0]\n')


def run(capfd, *argv):
    """Exit code, stdout and stderr of one command, captured at the file descriptors (native output too)."""
    code = main([str(a) for a in argv])
    out, err = capfd.readouterr()
    return code, out, err


def assert_one_error_line(code, err, *fragments):
    assert code == 2, err
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("vissim: error: "), err
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


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

    monkeypatch.setattr(runner, "render_spec", refuse)


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


@pytest.mark.parametrize("address", ["", "  "])
def test_an_empty_scheduler_is_an_error_not_a_local_run(capfd, tmp_path, address):
    code, err, _ = validate_with_scheduler(capfd, tmp_path, address)
    assert_one_error_line(code, err, "--scheduler is empty", "tcp://HOST:PORT")
    assert not (tmp_path / "out").exists()


def test_a_real_scheduler_passes_the_probe():
    """Oracle: a Dask scheduler on loopback; the probe must let it through (else no cluster could be used)."""
    distributed = pytest.importorskip("distributed")
    from vissim.validation.scheduler_probe import probe_scheduler

    with distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=None, host="127.0.0.1",
                                  scheduler_kwargs={"protocol": "tcp"}) as cluster:
        address = cluster.scheduler_address
        host, port = address.removeprefix("tcp://").rsplit(":", 1)
        probe_scheduler(address, host, int(port))  # returns: no error
