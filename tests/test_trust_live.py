"""The live server against hostile clients (realtime/gate.py, realtime/web.py, realtime/session.py, pneuma-serve):
a websocket without the page's token, however its frames are packed, is refused in its HTTP upgrade and changes
nothing; a message past gate.MAX_MESSAGE closes its connection without growing the server; every bad message from
a client with the token (values outside a control's, NaN, uploads, other types, malformed bytes) is refused with
one log line and no traceback, the session going on; a command with no equilibrium says so and comes back to
the last one; --host and the notebook's height are checked. One server (pneunet_finger) serves the module; no
browser is needed (raw sockets and the websockets client)."""

from __future__ import annotations

import asyncio
import logging
import math
import os
import socket
import subprocess
import sys
import time
import urllib.request

import numpy as np
import pytest

viser = pytest.importorskip("viser")
msgspec = pytest.importorskip("msgspec")

import taichi_pneuma as tp  # noqa: E402
from taichi_pneuma.errors import PneumaInputError  # noqa: E402
from taichi_pneuma.realtime.address import page_url  # noqa: E402
from taichi_pneuma.realtime.gate import MAX_CONNECTIONS, MAX_MESSAGE, MAX_REFUSED  # noqa: E402
from taichi_pneuma.realtime.session import NO_EQUILIBRIUM, LiveSession  # noqa: E402
from taichi_pneuma.realtime.web import WebView, live  # noqa: E402
from taichi_pneuma.solve.newton import NewtonOptions  # noqa: E402

PROTOCOL = f"viser-v{viser.__version__}"
GROWTH_BOUND = 40e6  # bytes the server may grow by while a client sends a 10 MB message


@pytest.fixture(scope="module")
def view(tmp_path_factory):
    tp.init("cpu")
    view = WebView(LiveSession(tp.load_scene("pneunet_finger")), tmp_path_factory.mktemp("out"), port=0)
    for _ in range(5):
        view.step()
    yield view
    view.stop()


def pack(message: dict) -> bytes:
    return msgspec.msgpack.encode(message)


def frame(payload: bytes, opcode: int = 2) -> bytes:
    """One masked websocket frame (a client's) holding payload."""
    n = len(payload)
    head = bytes([0x80 | opcode]) + (bytes([0x80 | n]) if n < 126 else bytes([0x80 | 126]) + n.to_bytes(2, "big"))
    mask = os.urandom(4)
    return head + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(payload))


def state(view) -> tuple:
    """What a session holds that a client could change: commands, playing, a pending target, the last reach, the
    field, the target's position."""
    s = view.session
    return (tuple(s.commands), s.playing, s._target is None, s.reached, view.field, tuple(view.target.position))


def settle_frames(view, seconds=1.0) -> None:
    """Frames for `seconds`: viser's thread handles what came meanwhile, the frame loop reads it."""
    ends = time.monotonic() + seconds
    while time.monotonic() < ends:
        view.step()
        time.sleep(0.02)


def drawn_message(value) -> dict:
    """The page's answer to the server's request for the frames/s its browser drew (pageparts.DrawnRates)."""
    return {"type": "LocalStorageGetItemResponseMessage", "value": value, "error": None, "request_uuid": "r"}


def slider_message(view, index, value) -> dict:
    return {"type": "GuiUpdateMessage", "uuid": view.sliders[index]._impl.uuid, "updates": {"value": value}}


def target_message(position) -> dict:
    return {
        "type": "TransformControlsUpdateMessage",
        "name": "/target",
        "wxyz": [1.0, 0.0, 0.0, 0.0],
        "position": position,
    }


@pytest.mark.parametrize("token", ["", "wrong", "TOKEN+x"], ids=["none", "wrong", "longer"])
def test_a_websocket_without_the_token_is_refused_in_its_upgrade_though_its_frames_come_in_the_same_write(view, token):
    """The upgrade request and, in the same TCP write, frames that would move a slider, start play, aim at the tip
    target (NaN, then a point) and change the field: answered 403, and the session holds what it held."""
    token = token.replace("TOKEN", view.token)
    before = state(view)
    payloads = [
        slider_message(view, 0, 450.0),
        {"type": "GuiUpdateMessage", "uuid": view.play._impl.uuid, "updates": {"value": True}},
        target_message([math.nan, 0.0, 0.0]),
        target_message([1.0, 0.5, 0.0]),
        {"type": "GuiUpdateMessage", "uuid": view.field_menu._impl.uuid, "updates": {"value": "det_F"}},
    ]
    request = (
        f"GET /?token={token} HTTP/1.1\r\nHost: 127.0.0.1:{view.port}\r\nUpgrade: websocket\r\n"
        "Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n"
        f"Sec-WebSocket-Protocol: {PROTOCOL}\r\n\r\n"
    ).encode()
    with socket.create_connection(("127.0.0.1", view.port), timeout=10) as client:
        client.sendall(request + b"".join(frame(pack(p)) for p in payloads))
        answer = client.recv(4096)
    assert answer.startswith(b"HTTP/1.1 403"), answer[:80]
    settle_frames(view)
    assert state(view) == before


def test_a_request_that_is_not_http_is_logged_in_one_line_without_a_traceback(view, caplog, capfd):
    caplog.set_level(logging.INFO)
    with socket.create_connection(("127.0.0.1", view.port), timeout=10) as client:
        client.sendall(b"GARBAGE\r\n\r\n")
        assert client.recv(4096) == b""  # closed, unanswered
    ends = time.monotonic() + 10
    while not any("handshake" in r.getMessage() for r in caplog.records) and time.monotonic() < ends:
        time.sleep(0.05)
    logged = [r for r in caplog.records if "handshake" in r.getMessage()]
    assert len(logged) == 1 and "\n" not in logged[0].getMessage() and logged[0].exc_info is None
    assert "did not receive a valid HTTP request" in logged[0].getMessage()
    assert "Traceback" not in capfd.readouterr().err


def test_a_message_larger_than_the_bound_closes_its_connection_and_the_server_grows_less_than_40_mb(view):
    from websockets.exceptions import ConnectionClosed
    from websockets.sync.client import connect

    def rss() -> int:
        with open("/proc/self/status") as status:
            return next(int(line.split()[1]) * 1024 for line in status if line.startswith("VmRSS"))

    before = rss()
    array = b"\xdd" + (10**7).to_bytes(4, "big") + b"\xc0" * 10**7  # msgpack: 10 MB, ten million nils
    url = f"ws://127.0.0.1:{view.port}/?token={view.token}"
    with connect(url, subprotocols=[PROTOCOL], close_timeout=1) as ws, pytest.raises(ConnectionClosed) as closed:
        ws.send(array)
        while True:
            ws.recv(timeout=30)
    assert closed.value.rcvd is not None and closed.value.rcvd.code == 1009  # message too big
    settle_frames(view, 0.5)
    assert rss() - before < GROWTH_BOUND
    assert MAX_MESSAGE < len(array)


BAD = {
    "menu value outside its options": lambda v: {
        "type": "GuiUpdateMessage",
        "uuid": v.field_menu._impl.uuid,
        "updates": {"value": "garbage"},
    },
    "menu value unhashable": lambda v: {
        "type": "GuiUpdateMessage",
        "uuid": v.field_menu._impl.uuid,
        "updates": {"value": ["det_F"]},
    },
    "slider NaN": lambda v: slider_message(v, 0, math.nan),
    "slider infinite": lambda v: slider_message(v, 1, math.inf),
    "slider past its range": lambda v: slider_message(v, 2, 1e9),
    "slider a string": lambda v: slider_message(v, 3, "450"),
    "box not a bool": lambda v: {"type": "GuiUpdateMessage", "uuid": v.play._impl.uuid, "updates": {"value": 1}},
    "slider's range changed": lambda v: {
        "type": "GuiUpdateMessage",
        "uuid": v.sliders[0]._impl.uuid,
        "updates": {"max": 1e9},
    },
    "control named by a list": lambda v: {"type": "GuiUpdateMessage", "uuid": [1], "updates": {"value": 1.0}},
    "unknown control": lambda v: {"type": "GuiUpdateMessage", "uuid": "nope", "updates": {"value": 1.0}},
    "target NaN": lambda v: target_message([math.nan, 1.0, 0.0]),
    "target infinite": lambda v: target_message([0.0, -math.inf, 0.0]),
    "target far away": lambda v: target_message([1e30, 0.0, 0.0]),
    "target of two numbers": lambda v: target_message([1.0, 0.0]),
    "another node moved": lambda v: {**target_message([1.0, 0.0, 0.0]), "name": "/clamp"},
    "camera NaN": lambda v: {
        "type": "ViewerCameraMessage",
        "wxyz": [1, 0, 0, 0],
        "position": [0, 0, math.nan],
        "fov": 1.0,
        "near": 0.1,
        "far": 10.0,
        "image_height": 10,
        "image_width": 10,
        "look_at": [0, 0, 0],
        "up_direction": [0, 1, 0],
    },
    "camera missing fields": lambda v: {"type": "ViewerCameraMessage", "wxyz": [1, 0, 0, 0]},
    "an upload": lambda v: {
        "type": "FileTransferStartUpload",
        "source_component_uuid": v.sliders[0]._impl.uuid,
        "transfer_uuid": "t",
        "filename": "x.bin",
        "mime_type": "application/octet-stream",
        "part_count": 10**6,
        "size_bytes": 10**9,
    },
    "an upload's part": lambda v: {
        "type": "FileTransferPart",
        "source_component_uuid": v.sliders[0]._impl.uuid,
        "transfer_uuid": "t",
        "part_index": 0,
        "content": b"\0" * 60000,
    },
    "a drawn rate not a number": lambda v: drawn_message("fast"),
    "a drawn rate NaN": lambda v: drawn_message("nan"),
    "a drawn rate below 0": lambda v: drawn_message("-1"),
    "a drawn rate too long": lambda v: drawn_message("1" * 33),
    "a drawn rate's error too long": lambda v: {**drawn_message(None), "error": "x" * 201},
    "a share link": lambda v: {"type": "ShareUrlRequest"},
    "an unknown type": lambda v: {"type": "NoSuchMessage"},
    "no type": lambda v: {"uuid": "x"},
    "a list": lambda v: [1, 2, 3],
}


@pytest.mark.parametrize("attack", list(BAD) + ["not msgpack", "nested too deep", "a text frame"])
def test_a_bad_message_with_the_token_is_refused_in_one_log_line_and_the_session_goes_on(view, caplog, capfd, attack):
    """Each bad message is logged once, in one line without a traceback, changes nothing the session holds, and
    the same connection's next message (a slider moved) is still taken."""
    from websockets.sync.client import connect

    caplog.set_level(logging.WARNING, logger="taichi_pneuma.live")
    settle_frames(view, 0.2)
    before = state(view)
    moved = round(float(view.session.commands[4]) + 10.0, 6)
    with connect(f"ws://127.0.0.1:{view.port}/?token={view.token}", subprotocols=[PROTOCOL], close_timeout=0.1) as ws:
        if attack == "a text frame":
            ws.send("{}")
        else:
            raw = {"not msgpack": b"\xc1\xff\x00", "nested too deep": b"\x91" * 60000 + b"\xc0"}
            ws.send(raw[attack] if attack in raw else pack(BAD[attack](view)))
        ws.send(pack(slider_message(view, 4, moved)))
        ends = time.monotonic() + 20
        while view.sliders[4].value != moved and time.monotonic() < ends:
            time.sleep(0.02)
        settle_frames(view, 0.3)
    refusals = [r for r in caplog.records if "refused a message" in r.getMessage()]
    assert len(refusals) == 1, [r.getMessage() for r in caplog.records]
    assert "\n" not in refusals[0].getMessage() and refusals[0].exc_info is None
    # the server's records (this test's own client may log its closing handshake cut short on a loaded machine)
    assert all(r.exc_info is None for r in caplog.records if r.name != "websockets.client")
    assert "Traceback" not in capfd.readouterr().err
    commands = list(before[0])
    commands[4] = moved
    assert state(view) == (tuple(commands), *before[1:])


def test_a_client_that_keeps_sending_refused_messages_is_closed_and_logs_a_bounded_number_of_lines(view, caplog):
    """MAX_REFUSED bad messages in a row (a menu value off its list), then more: the connection is closed (1008)
    after the MAX_REFUSED-th, so the log holds MAX_REFUSED refusals and one closing line, however many were sent."""
    from websockets.exceptions import ConnectionClosed
    from websockets.sync.client import connect

    caplog.set_level(logging.WARNING, logger="taichi_pneuma.live")
    bad = pack({"type": "GuiUpdateMessage", "uuid": view.field_menu._impl.uuid, "updates": {"value": "garbage"}})
    url = f"ws://127.0.0.1:{view.port}/?token={view.token}"
    with connect(url, subprotocols=[PROTOCOL], close_timeout=0.1) as ws, pytest.raises(ConnectionClosed) as closed:
        for _ in range(10 * MAX_REFUSED):
            ws.send(bad)
            time.sleep(0.005)
        while True:  # viser's own messages come first; the close ends the loop
            ws.recv(timeout=10)
    assert closed.value.rcvd is not None and closed.value.rcvd.code == 1008
    lines = [r.getMessage() for r in caplog.records]
    assert sum("refused a message" in line for line in lines) == MAX_REFUSED
    assert sum("closed the connection" in line for line in lines) == 1


def test_past_the_open_pages_bound_an_upgrade_is_answered_503_and_a_closed_page_makes_room(view):
    """MAX_CONNECTIONS websockets with the token open at once: one more is refused in its upgrade (503); once one
    closes, a new one is taken."""
    from websockets.exceptions import InvalidStatus
    from websockets.sync.client import connect

    url = f"ws://127.0.0.1:{view.port}/?token={view.token}"
    pages = [connect(url, subprotocols=[PROTOCOL], close_timeout=0.1) for _ in range(MAX_CONNECTIONS)]
    try:
        with pytest.raises(InvalidStatus) as refused:
            connect(url, subprotocols=[PROTOCOL], close_timeout=0.1)
        assert refused.value.response.status_code == 503
        pages.pop().close()
        ends = time.monotonic() + 10
        while True:
            try:
                pages.append(connect(url, subprotocols=[PROTOCOL], close_timeout=0.1))
                break
            except InvalidStatus:
                assert time.monotonic() < ends, "a closed page made no room"
                time.sleep(0.05)
    finally:
        for page in pages:
            page.close()


def test_session_commands_and_targets_must_be_finite(view):
    session = view.session
    with pytest.raises(PneumaInputError, match="chamber c1's command = nan must be a finite number"):
        session.command(0, math.nan)
    with pytest.raises(PneumaInputError, match="target coordinate y = inf must be a finite number"):
        session.aim((0.0, math.inf, 0.0))
    assert np.all(np.isfinite(session.commands)) and session._target is None


def test_past_a_pressure_limit_point_the_session_says_no_equilibrium_and_comes_back_to_the_last_one():
    """balloon_pressure's wall, settled just below its peak pressure (0.0283164 kPa, docs/chambers.md), commanded
    past it with 10 Newton steps a try: after its cut-backs, within (2 MAX_CUTS + 1) 10 frames, the state is the
    last equilibrium found (between the two commands, below the peak), said to be none at the command, and the
    frames stop; back at 0.0283 the state is that equilibrium's again, and at 0 (a jump that takes cut-backs) rest."""
    tp.init("cpu")
    session = LiveSession(tp.load_scene("balloon_pressure"), newton=NewtonOptions(tol=1e-5, max_iterations=10))

    def settle(frames):
        for frame in range(frames):
            if not session.advance() and session.equilibrium.converged:
                return frame
        return frames

    for pressure in (0.01, 0.02, 0.025, 0.028, 0.0283):
        session.command(0, pressure)
        settle(200)
        assert session.figures()["state"] == "equilibrium", (pressure, session.figures())
    below = session.figures()["tip"][1]  # the dent's apex at 0.0283, about 0.95 mm up (popped out: 5.4)
    session.command(0, 0.0285)
    frames = 0
    while session.figures()["state"] != NO_EQUILIBRIUM and frames < 170:
        session.advance()
        frames += 1
    shown = session.positions().copy()
    assert abs(session.figures()["tip"][1] - below) < 0.05  # not popped out
    pressure = session.figures()["pressures"][0]
    assert session.figures()["state"] == NO_EQUILIBRIUM, session.figures()
    assert session.equilibrium.converged and 0.0283 <= pressure < 0.0283164, pressure
    assert not session.advance() and np.array_equal(session.positions(), shown)  # it waits for the command to move
    session.command(0, 0.0283)
    settle(20)
    assert session.figures()["state"] == "equilibrium"
    assert abs(session.figures()["tip"][1] - below) < 0.05  # the dented branch's equilibrium again
    session.command(0, 0.0)
    settle(400)
    assert session.figures()["state"] == "equilibrium"
    assert np.abs(session.figures()["tip"]).max() < 1e-6


def serve(*flags, timeout=60):
    return subprocess.run(
        [sys.executable, "-m", "taichi_pneuma.apps.serve", "--scene", "pneunet_finger", "--port", "0", *flags],
        capture_output=True,
        text=True,
        timeout=timeout,
    )


@pytest.mark.parametrize(
    "host, said",
    [
        ("no-such-host.invalid", "host 'no-such-host.invalid' does not resolve"),
        ("192.0.2.1", "host '192.0.2.1' (192.0.2.1) is not an address this machine can listen on"),
    ],
)
def test_pneuma_serve_refuses_a_host_it_cannot_listen_on_in_one_line(host, said):
    done = serve("--host", host)
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert done.stderr.startswith(f"error: {said}")


@pytest.mark.parametrize("host", ["", "::"], ids=["empty", "ipv6-any"])
def test_the_url_of_a_wildcard_host_is_one_a_browser_here_opens(view, host):
    """The page and its websocket (with the token) answer at the URL printed for '' and '::'."""
    from urllib.parse import parse_qs, urlsplit

    from websockets.sync.client import connect

    other = WebView(view.session, view.out, host=host, port=0)
    try:
        with urllib.request.urlopen(other.url, timeout=10) as page:
            assert page.status == 200
        websocket = parse_qs(urlsplit(other.url).query)["websocket"][0]
        with connect(websocket, subprotocols=[PROTOCOL]) as ws:
            assert len(ws.recv(timeout=30)) > 0
    finally:
        other.stop()
    assert page_url("::1", 80, "t").startswith("http://[::1]:80/?websocket=ws://[::1]:80/")


def test_the_notebook_iframes_height_is_an_integer_in_range(view):
    async def show():
        return live("pneunet_finger", height='560" onload="alert(1)')  # type: ignore[arg-type]

    with pytest.raises(PneumaInputError, match="height .* is not an integer number of pixels in 100 .. 4000"):
        asyncio.run(show())
    with pytest.raises(PneumaInputError, match="height"):
        view.height = 10**6
    view.height = 700
    assert 'height="700"' in view._repr_html_()
