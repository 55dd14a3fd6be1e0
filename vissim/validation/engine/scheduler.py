"""Is a Dask scheduler listening at an address? A few seconds' look at its first bytes, before Dask connects.

Dask's client waits long, or asks for absurd memory, when the address belongs to another
service: a web server (the Dask dashboard, port 8787, is an easy mistake) never answers
Dask's handshake, and another service's bytes read as a message length of exabytes. A
scheduler speaks first: on a new connection it sends its handshake, a message whose first
8 bytes are its length (little-endian ``uint64``, a few hundred bytes). `probe_scheduler`
connects, reads those bytes, and names whatever answered instead.
"""

from __future__ import annotations

import socket
import struct

from vissim.errors import VissimInputError

__all__ = ["probe_scheduler", "connect_scheduler", "PROBE_TIMEOUT_S", "SCHEDULER_TIMEOUT_S"]

#: Seconds to wait for the connection, then for the scheduler's first bytes, then for a web server's reply.
PROBE_TIMEOUT_S = 1.5
#: A Dask handshake is a few hundred bytes; anything claiming more than this is not one.
MAX_HANDSHAKE_BYTES = 1 << 20
_HTTP_REQUEST = b"HEAD / HTTP/1.0\r\nHost: vissim-probe\r\n\r\n"
_DASHBOARD_HINT = "a web server, perhaps the Dask dashboard; the scheduler is usually on port 8786"


def _read_some(sock: socket.socket, n_bytes: int) -> bytes:
    """Up to ``n_bytes`` that arrive before the socket's timeout (b'' when none do or it closes)."""
    data = b""
    try:
        while len(data) < n_bytes:
            chunk = sock.recv(n_bytes - len(data))
            if not chunk:
                break
            data += chunk
    except (TimeoutError, OSError):
        pass
    return data


def _shown(data: bytes) -> str:
    """The first bytes of an answer as text a terminal can show."""
    text = data[:24].decode("ascii", "replace")
    return repr("".join(c if c.isprintable() else "." for c in text))


def _is_dask_handshake(data: bytes) -> bool:
    if len(data) < 8:
        return False
    (length,) = struct.unpack("<Q", data[:8])
    return 8 <= length <= MAX_HANDSHAKE_BYTES


def probe_scheduler(address: str, host: str, port: int, timeout_s: float = PROBE_TIMEOUT_S) -> None:
    """Return if what listens at ``host:port`` opens like a Dask scheduler; else one error naming what answered.

    ``address`` is the address as the user wrote it (for the message). Takes at most about
    three times ``timeout_s``.
    """
    where = f"--scheduler {address}"
    try:
        sock = socket.create_connection((host, port), timeout=timeout_s)
    except TimeoutError:
        raise VissimInputError(f"{where}: nothing accepted a connection within {timeout_s:g} s; "
                               "start a scheduler (dask scheduler) or check the address") from None
    except OSError as exc:
        raise VissimInputError(f"{where}: no Dask scheduler answered ({exc.strerror or exc}); "
                               "start one (dask scheduler) or check the address") from None
    with sock:
        first = _read_some(sock, 16)
        if not first:  # silence: a web server waits for a request (a slow scheduler's handshake may still come)
            try:
                sock.sendall(_HTTP_REQUEST)
            except OSError:
                pass
            first = _read_some(sock, 16)
    if _is_dask_handshake(first):
        return
    if first.startswith(b"HTTP/"):
        what = f"answered HTTP ({_DASHBOARD_HINT})"
    elif first:
        what = f"answered {_shown(first)}, which is not the Dask protocol (another service?)"
    else:
        what = f"accepted the connection but sent nothing within {timeout_s:g} s (a Dask scheduler speaks first)"
    raise VissimInputError(f"{where}: not a Dask scheduler: {host}:{port} {what}")


#: How long ``--scheduler`` waits for a Dask scheduler to answer.
SCHEDULER_TIMEOUT_S = 2.0


def connect_scheduler(address: str):
    """A Dask ``Client`` of the scheduler at ``address``, or one clean error within SCHEDULER_TIMEOUT_S."""
    try:
        from distributed import Client
        from distributed.comm import parse_address
    except ImportError:  # pragma: no cover
        raise VissimInputError("--scheduler needs Dask distributed: pip install 'dask[distributed]'") from None
    hint = "expected tcp://HOST:PORT, e.g. tcp://127.0.0.1:8786"
    try:
        scheme, location = parse_address(address)
    except (ValueError, TypeError) as exc:
        raise VissimInputError(f"--scheduler {address!r} is not a Dask scheduler address ({exc}); {hint}") from None
    host, _, port = location.rpartition(":")
    if scheme in ("tcp", "tls", "ws", "wss") and not (host and port.isdigit() and 0 < int(port) < 65536):
        raise VissimInputError(f"--scheduler {address!r} is not a Dask scheduler address; {hint}")
    if scheme == "tcp":  # a web server or another service would keep Dask waiting, or ask for exabytes
        probe_scheduler(address, host.strip("[]"), int(port))
    try:
        return Client(address, timeout=SCHEDULER_TIMEOUT_S)
    except (OSError, TimeoutError):
        raise VissimInputError(f"--scheduler {address}: no Dask scheduler answered within {SCHEDULER_TIMEOUT_S:g} s; "
                               "start one (dask scheduler) or check the address") from None
    except (ValueError, TypeError) as exc:
        raise VissimInputError(f"--scheduler {address!r} is not a Dask scheduler address ({exc}); {hint}") from None
