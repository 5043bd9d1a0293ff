"""The live page in a real browser (realtime/web.py, pneuma-serve): headless Chromium (the distribution's chromium
and chromedriver, driven by Selenium) loads the page of the 2D reference beam, moves the chamber's slider, and the
tip figure and the drawn frame change and the page reports the frames per second served and those the browser
drew; the colour bar follows the field and its range; a websocket without the page's token is refused in its HTTP
upgrade, a client that never reads does not stall the solver, and the server is not reachable from the network.

    python tests/test_web.py DIR      the same browser session, its screenshot written to DIR/live_page.png (docs)
"""

from __future__ import annotations

import io
import logging
import os
import re
import shutil
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

viser = pytest.importorskip("viser")

CHROMIUM, CHROMEDRIVER = "/usr/bin/chromium", "/usr/bin/chromedriver"  # Debian's chromium, chromium-driver
if not (Path(CHROMIUM).exists() and Path(CHROMEDRIVER).exists()):
    if os.environ.get("CI"):  # .ci/run installs them: their absence there is a failure, not a skip
        raise RuntimeError(f"{CHROMIUM} and {CHROMEDRIVER} are missing (apt-get install chromium chromium-driver)")
    pytest.skip("no chromium and chromedriver here", allow_module_level=True)


def chromium(width=1200, height=720):
    """A headless Chromium with WebGL in software (SwiftShader), as a machine without a GPU has it."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for flag in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--use-angle=swiftshader",
                 "--enable-unsafe-swiftshader", f"--window-size={width},{height}"):  # fmt: skip
        options.add_argument(flag)
    return webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)


def view_of(scene_name="reference_beam", out="out"):
    import taichi_pneuma as tp
    from taichi_pneuma.realtime.session import LiveSession
    from taichi_pneuma.realtime.web import WebView

    tp.init("cpu")
    return WebView(LiveSession(tp.load_scene(scene_name)), out, port=0)


def browse(view, screenshot: Path | None = None, timeout=90.0) -> dict:
    """Load the page, wait for the figures, move the first slider 30 steps right, wait for the new equilibrium;
    the solver runs on this (the main) thread meanwhile. Returns the captions and canvas images before and after."""
    from PIL import Image
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    seen: dict = {}

    def caption(driver) -> str:
        found = driver.find_elements(By.XPATH, "//p[contains(., 'frames/s')]")
        return found[0].text if found else ""

    def wait(driver, done) -> str:
        ends = time.monotonic() + timeout
        while time.monotonic() < ends:
            text = caption(driver)
            if done(text):
                return text
            time.sleep(0.2)
        raise AssertionError(f"the page's figures never showed it: {caption(driver)!r}")

    def canvas(driver):
        largest = max(driver.find_elements(By.TAG_NAME, "canvas"), key=lambda c: c.size["width"] * c.size["height"])
        return np.asarray(Image.open(io.BytesIO(largest.screenshot_as_png)).convert("RGB"), dtype=float)

    def session():
        driver = chromium()
        try:
            driver.get(view.url)
            seen["before"] = wait(driver, lambda text: "equilibrium" in text)
            # the first frame drawn, and viser's client settled: a slider moved in its first second or two can be
            # reset to its initial value by the client itself (seen with viser 1.1.1; docs/live.md)
            time.sleep(4.0)
            seen["canvas_before"] = canvas(driver)
            slider = driver.find_elements(By.CSS_SELECTOR, "[role=slider]")[0]
            slider.click()
            for _ in range(30):
                slider.send_keys(Keys.ARROW_RIGHT)
            moved = lambda text: "(equilibrium)" in text and "main 1 " not in text  # noqa: E731
            seen["after"] = wait(driver, moved)
            time.sleep(2.0)  # the last keys' equilibrium
            seen["after"] = wait(driver, moved)
            seen["canvas_after"] = canvas(driver)
            if screenshot is not None:
                driver.save_screenshot(str(screenshot))
        except BaseException as exc:
            seen["error"] = exc
        finally:
            driver.quit()

    thread = threading.Thread(target=session)
    thread.start()
    view.run(until=lambda: not thread.is_alive())
    if "error" in seen:
        raise seen["error"]
    return seen


@pytest.fixture(scope="module")
def view(tmp_path_factory):
    view = view_of(out=tmp_path_factory.mktemp("out"))
    yield view
    view.stop()


def test_moving_a_slider_in_the_browser_changes_the_tip_the_drawn_frame_and_reports_both_frame_rates(view, caplog):
    caplog.set_level(logging.WARNING, logger="taichi_pneuma.live")
    seen = browse(view)
    # every message the browser sent (slider, camera, ...) passed the page's checks (realtime/web.py refusal)
    assert not [r.getMessage() for r in caplog.records if "refused" in r.getMessage()]
    tip = lambda text: float(re.search(r"dy ([-+][0-9.e-]+)", text).group(1))  # noqa: E731
    assert tip(seen["before"]) == 0.0
    # the slider's steps of 1/200 of its range (1 .. 3.5) command a larger area ratio: the chamber above the neutral
    # axis lifts the tip first (the reference beam's tip rises before it curls down)
    ratio = float(re.search(r"main ([0-9.]+)", seen["after"]).group(1))
    assert ratio > 1.05 and tip(seen["after"]) > 0.01
    # the server's rate and the browser's own (the frames it drew, counted in the page and read back), both > 0
    served = float(re.search(r"([0-9.]+) frames/s served", seen["after"]).group(1))
    drawn = float(re.search(r"the browser drew ([0-9.]+) frames/s", seen["after"]).group(1))
    assert served > 0 and drawn > 0, seen["after"]
    changed = np.abs(seen["canvas_after"] - seen["canvas_before"]).max(axis=2) > 30
    assert changed.mean() > 0.005, f"{changed.mean():.4f} of the canvas changed"
    # the state the page shows is the session's: the browser drove the same solver
    assert view.session.commands[0] == pytest.approx(ratio, abs=1e-3)


def test_the_pages_controls_reach_the_session_and_the_session_moves_the_sliders_back(tmp_path):
    """The controls as viser holds them after a page's messages (set here on the handles): a slider commands the
    chamber; play runs the schedule, the sliders following it without stopping it; a dragged target is reached;
    the save button writes the kept equilibria under out (its stem: the scene's name)."""
    view = view_of("pneunet_finger", out=tmp_path)
    try:
        view.step()
        view.sliders[1].value = 450.0
        for _ in range(40):
            view.step()
        assert view.session.commands[1] == 450.0 and view.session.equilibrium.converged
        mesh = view.session.mesh
        known = mesh.vertices[mesh.tip].mean(axis=0) + view.session.figures()["tip"]  # where 450 in c2 puts the tip
        view.play.value = True
        for _ in range(40):
            view.step()
        session = view.session
        assert session.playing and session.schedule_step > 1
        assert [s.value for s in view.sliders] == pytest.approx(session.commands[:6])  # the sliders follow
        view.play.value = False
        view.step()
        assert not session.playing
        view.target.position = (known[0], known[1], 0.0)  # the target dragged there
        view.step()
        assert session.reached is not None and session.reached < 2e-3 * np.ptp(mesh.vertices[:, 0])
        view._asked.set()  # the save button's press
        view.step()
        assert (tmp_path / "pneunet_finger_states.npz").is_file()
        assert "saved" in view.saved.content and "pneunet_finger_history.csv" in view.saved.content
    finally:
        view.stop()


def test_a_body_at_rest_is_one_colour_and_the_scale_keeps_a_minimum_width(tmp_path):
    """At rest the stretch is 1 to round-off: the body is drawn in one colour (the scale at least 1e-3 of the field
    wide, not its round-off spread over the whole map)."""
    view = view_of("pneunet_finger", out=tmp_path)
    try:
        colours = view.colours()
        lo, hi = view._range
        assert np.ptp(colours[:, :3].astype(int), axis=0).max() <= 2  # of 255: one colour, to the map's rounding
        assert hi - lo >= 0.99e-3 * max(abs(lo), abs(hi))
    finally:
        view.stop()


def test_the_colour_bar_spans_the_colour_map_from_the_ranges_low_end_to_its_high_end():
    """The bar's gradient runs from viridis's first colour (#440154, matplotlib's published table) at 0% to its last
    (#fde725) at 100%, the range's ends printed under it in the field's unit."""
    from taichi_pneuma.realtime.pageparts import colour_bar

    bar = colour_bar("von Mises stress", 0.25, 37.5, " kPa")
    stops = re.findall(r"(#[0-9a-f]{6}) ([0-9.]+)%", bar)
    assert stops[0] == ("#440154", "0") and stops[-1] == ("#fde725", "100")
    assert [float(p) for _, p in stops] == sorted(float(p) for _, p in stops)
    assert re.findall(r"<span>([^<]*)</span>", bar) == ["0.25 kPa", "37.5 kPa"]
    assert bar.startswith('<div style="font-size: 0.85em; padding: 0 0.75em">von Mises stress (viridis)')


def bar_range(view) -> tuple[float, float, str]:
    """The range the page's colour bar shows, and its unit."""
    (lo, unit), (hi, _) = re.findall(r"<span>([-+0-9.e]+)(.*?)</span>", view.bar.content)
    return float(lo), float(hi), unit


def test_the_colour_bar_follows_the_field_and_its_range(tmp_path):
    """Inflated, the bar's range covers the max stretch the body has (over 1: the chamber stretches its walls);
    coloured by the von Mises stress of a settled state, the bar is relabelled and spans that field's values now, in
    the scene's pressure unit (kPa); by the displacement, in mm; by none, it is gone."""
    view = view_of("pneunet_mm_kpa", out=tmp_path)
    try:
        assert view.bar.content == ""  # (before the first frame: no range yet)
        view.sliders[0].value = view.sliders[0].max / 2
        for _ in range(100):
            view.step()
            if view.session.equilibrium.converged and view.session.commands[0] > 0:
                break
        lo, hi, unit = bar_range(view)
        stretch = view.session.field("max_stretch")
        assert "max stretch" in view.bar.content and unit == ""
        assert lo <= stretch.min() * (1 + 1e-3) and hi >= stretch.max() * (1 - 1e-3) and hi > 1.01  # (4 digits)
        assert view.session.equilibrium.converged
        view.field_menu.value = "von_mises"
        view.step()
        lo, hi, unit = bar_range(view)
        stress = view.session.field("von_mises")
        assert "von Mises stress" in view.bar.content and unit == " kPa"
        assert hi == pytest.approx(stress.max(), rel=1e-3) and lo == pytest.approx(stress.min(), rel=1e-3)
        view.field_menu.value = "displacement"
        view.step()
        lo, hi, unit = bar_range(view)
        tip = np.linalg.norm(view.session.figures()["tip"])  # the tip's mean displacement: within the range
        assert "displacement" in view.bar.content and unit == " mm" and lo < tip < hi
        view.field_menu.value = "none"
        view.step()
        assert view.bar.content == ""
    finally:
        view.stop()


def test_starting_and_stopping_the_page_shows_nothing_of_visers(capfd, monkeypatch):
    """viser prints its banner (and "Server stopped") with rich's console, which in a notebook kernel displays it as
    the cell's output: with the console made a Jupyter one here, nothing is displayed, nor printed."""
    import rich
    import rich.jupyter

    shown = []
    monkeypatch.setattr(rich.get_console(), "is_jupyter", True)
    monkeypatch.setattr(rich.jupyter, "display", lambda segments, text: shown.append(text))
    view_of("pneunet_finger").stop()
    out, err = capfd.readouterr()
    assert shown == [] and [line for line in out.splitlines() if not line.startswith("[Taichi]")] == []
    assert "viser" not in err


def test_a_2d_bodys_chambers_are_filled_on_the_page_at_their_walls_positions(tmp_path):
    """The chambers are holes in a 2D body's triangles: the page fills them (as the videos do), a mesh whose
    corners are the chamber walls' nodes where the session has them, moved as they inflate."""
    view = view_of("pneunet_finger", out=tmp_path)
    try:
        view.sliders[0].value = 600.0
        for _ in range(10):
            view.step()
        mesh, positions = view.session.mesh, view.session.positions()
        corners = np.asarray(view.chambers.vertices).reshape(-1, 3)
        walls = positions[np.concatenate(mesh.chambers)]
        assert np.allclose(corners[:, 2], 0.0) and len(corners) == 3 * len(view._chamber_faces)
        assert np.abs(corners[:, None, :2] - walls[None]).sum(axis=2).min(axis=1).max() < 1e-6  # on the walls (float32)
        assert not np.allclose(walls, mesh.vertices[np.concatenate(mesh.chambers)])  # moved: the chamber inflated
    finally:
        view.stop()


def test_the_page_draws_the_obstacles_and_moves_them_with_their_offset(tmp_path):
    """gripper_2d's cylinder is an outline in the z = 0 plane, its radius's circle about its centre; a node that
    follows its obstacle's offset (a moving obstacle's, as a schedule plays)."""
    view = view_of("gripper_2d", out=tmp_path)
    try:
        (node,) = view._obstacles
        cylinder = view.session.scene.obstacles[0].shape
        ends = np.asarray(node.points).reshape(-1, 3)
        assert np.allclose(ends[:, 2], 0.0)
        assert np.allclose(np.linalg.norm(ends[:, :2] - np.asarray(cylinder.center[:2]), axis=1), cylinder.radius)
        view.session.built.obstacles[0].set_offset([1.5, -0.5])
        view.step()
        assert np.allclose(node.position, [1.5, -0.5, 0.0])
    finally:
        view.stop()


def test_a_websocket_without_the_pages_token_is_refused_and_one_with_it_is_served(view):
    from websockets.exceptions import InvalidStatus
    from websockets.sync.client import connect

    protocol = [f"viser-v{viser.__version__}"]
    with pytest.raises(InvalidStatus) as refused:  # in the HTTP upgrade: no websocket, no frame read
        connect(f"ws://127.0.0.1:{view.port}/", subprotocols=protocol)
    assert refused.value.response.status_code == 403
    with connect(f"ws://127.0.0.1:{view.port}/?token={view.token}", subprotocols=protocol) as ws:
        assert len(ws.recv(timeout=30)) > 0


def test_a_client_that_never_reads_does_not_stall_the_solver(view):
    from websockets.sync.client import connect

    stalled = connect(  # (its close would wait 10 s for a closing handshake it never reads)
        f"ws://127.0.0.1:{view.port}/?token={view.token}",
        subprotocols=[f"viser-v{viser.__version__}"],
        close_timeout=0.1,
    )
    with stalled:
        published = view.published
        for k in range(80):  # a slider dragged back and forth: each frame publishes the body (~200 KB)
            view.session.command(0, 1.0 + 0.5 * (k % 2))
            view.step()
        assert view.published - published == 80


def test_the_server_listens_on_the_loopback_address_only(view):
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.connect(("10.255.255.255", 1))  # no packet sent: it picks the interface a route would use
        address = probe.getsockname()[0]
    if address.startswith("127."):
        pytest.skip("no address but the loopback here")
    with pytest.raises(OSError):
        socket.create_connection((address, view.port), timeout=5).close()


def test_pneuma_serve_prints_the_url_with_its_token_and_refuses_a_bad_field(tmp_path):
    run = lambda *flags: subprocess.run(  # noqa: E731
        [sys.executable, "-m", "taichi_pneuma.apps.serve", "--scene", "pneunet_finger", "--port", "0", *flags],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=120,
    )
    served = run("--seconds", "3", "--out", "out")
    assert served.returncode == 0, served.stderr
    assert re.search(r"http://127\.0\.0\.1:\d+/\?websocket=ws://127\.0\.0\.1:\d+/%3Ftoken%3D[\w-]{20,}", served.stdout)
    bad = run("--field", "strain")
    assert bad.returncode == 2 and bad.stderr.strip().count("\n") == 0
    assert "--field 'strain' is not one of none, max_stretch" in bad.stderr


if __name__ == "__main__":
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    live = view_of(out=out)
    try:
        browse(live, screenshot=out / "live_page.png")
    finally:
        live.stop()
    shutil.rmtree(out / "__pycache__", ignore_errors=True)
