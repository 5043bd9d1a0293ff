"""Frames per second of the live page (realtime/web.py) against the native windows, while a slider is dragged.

    xvfb-run -a python benchmarks/live_page.py [--frames 120] [--warmup 10] [--frames-3d 30] [--warmup-3d 3]
        [--views page,reader,browser,native] [--out benchmarks/results]   (repository root on PYTHONPATH, project venv)

Scenes: the 2D reference beam (tp.load_scene("reference_beam"), one area-controlled chamber), the coarse 3D PneuNet
(render3d.live_scene: 840 nodes, linear tetrahedra, the scene the native window's 22 frames/s were measured on) and
the shipped 3D PneuNet (tp.load_scene("pneunet_3d"), P2 tetrahedra); the PneuNets' six chambers driven together.
The drag is scripted: every chamber's command moves by one step per frame from its slider's low end to its high end
and back (a triangle wave over warm-up + measured frames); the warm-up frames are its first ones and are not timed.
Views:
  page: WebView(LiveSession(scene), out=tmpdir, port=0) with no browser; per frame session.command(j, value) for
      each chamber, then view.step() (one Newton step, LiveSession.advance, then the body published as a coloured
      GLB and the figures updated); frames/s = frames / wall time; the share in advance is timed around it;
  reader: the same with one websocket client (the page's token) that reads every message and draws nothing, on a
      thread: the server's load when the browser is on another machine;
  browser: the same with one headless Chromium (Selenium 4, SwiftShader WebGL, 1200 x 720) on view.url, opened
      in a thread and given BROWSER_WAIT seconds to connect before the frames; the page's received body updates
      are counted by web_viewers.COUNTER_JS (messages from viser's decoding worker carrying a GLB);
  native: 3D: interactive.explore_solid (GGUI, 960 x 640, one LiveEquilibrium step per frame, the same step as
      the page's) with interactive3d.commands_from replaced to return the path's next commands, its own 'fps'
      (frames after the first); 2D: interactive.explore (the 'auto' canvas, ti.GUI, 960 x 384; a full Newton solve
      per slider move) with the canvas's slider query replaced, frames/s = frames / wall time of the call.
Run under xvfb-run -a (the native windows draw offscreen; GGUI on Mesa's lavapipe Vulkan).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import tempfile
import threading
import time
from datetime import date
from pathlib import Path

import numpy as np

BROWSER_WAIT = 8.0  # seconds the browser is given to load the page and connect before the frames
# the scenes: the 2D reference beam; the coarse PneuNet of the native window's measurement (render3d.live_scene:
# gmsh at edge 0.3, linear tetrahedra, 840 nodes, one material, six chambers to 900 Pa); the shipped pneunet_3d
# (quadratic tetrahedra, 13,573 nodes)
SCENES = {"reference_beam": "2D reference beam", "coarse_pneunet": "coarse 3D PneuNet", "pneunet_3d": "3D PneuNet"}


def scene_named(name: str):
    """A scene of SCENES by name."""
    if name == "coarse_pneunet":
        from render3d import live_scene  # benchmarks/ (this script's directory) is on sys.path

        return live_scene()[0].scene
    import taichi_pneuma as tp

    return tp.load_scene(name)


def drag(low: np.ndarray, high: np.ndarray, warmup: int, frames: int) -> np.ndarray:
    """(warmup + frames, chambers) commands: low -> high -> low in equal steps, one per frame (a triangle wave
    over all the frames; the warm-up frames are its first ones)."""
    total = warmup + frames
    t = np.arange(total) / (total - 1)
    share = 1.0 - np.abs(2.0 * t - 1.0)
    return low + np.outer(share, high - low)


def reading_client(view) -> tuple:
    """A websocket client of the page (with its token) that reads every message and draws nothing, on a thread: the
    load a browser on another machine puts on the server. Returns (connection, [messages read])."""
    import viser
    from websockets.sync.client import connect

    socket = connect(
        f"ws://127.0.0.1:{view.port}/?token={view.token}", subprotocols=[f"viser-v{viser.__version__}"], max_size=None
    )
    read = [0]

    def loop() -> None:
        try:
            while True:
                socket.recv()
                read[0] += 1
        except Exception:  # the connection closed at the end
            pass

    threading.Thread(target=loop, daemon=True).start()
    return socket, read


def page_run(scene, path: np.ndarray, warmup: int, client: str = "", reduced=None) -> dict:
    """The live page's loop with no client, a reading one ('reader') or one headless Chromium ('browser'):
    frames/s over the path after the warm-up. reduced: a reduced model's file (LiveSession's)."""
    from taichi_pneuma.realtime.session import LiveSession
    from taichi_pneuma.realtime.web import WebView

    session = LiveSession(scene, reduced=reduced)
    advance, in_advance = session.advance, []

    def timed() -> bool:
        start = time.perf_counter()
        changed = advance()
        in_advance.append(time.perf_counter() - start)
        return changed

    session.advance = timed  # type: ignore[method-assign]
    with tempfile.TemporaryDirectory() as out:
        view = WebView(session, out=out, port=0)
        driver, counts, reader = None, {}, None
        try:
            if client == "browser":
                driver = open_browser(view.url)
            if client == "reader":
                reader = reading_client(view)
                time.sleep(1.0)  # the scene's first messages read
            for k, commands in enumerate(path):
                if k == warmup:
                    in_advance.clear()
                    published, start = view.published, time.perf_counter()
                    received = page_counter(driver) if reader is None else reader[1][0]
                for j, value in enumerate(commands):
                    session.command(j, float(value))
                view.step()
            seconds = time.perf_counter() - start
            if driver is not None:
                time.sleep(0.5)  # the last queued messages reach the page
                counts = {"clients": len(view.server.get_clients()), "received": page_counter(driver) - received}
            if reader is not None:
                time.sleep(0.5)
                counts = {"clients": len(view.server.get_clients()), "received": reader[1][0] - received}
        finally:
            if reader is not None:
                reader[0].close()
            if driver is not None:
                driver.quit()
            view.stop()
    frames = len(path) - warmup
    result = {
        "frames": frames,
        "seconds": seconds,
        "fps": frames / seconds,
        "advance_share": float(np.sum(in_advance)) / seconds,
        "ms_per_advance": 1e3 * float(np.mean(in_advance)),
        "published": view.published - published,
    }
    if counts:
        result |= {"browser_clients": counts["clients"], "browser_received_fps": counts["received"] / seconds}
    return result


def open_browser(url: str):
    """A headless Chromium with the frame counter, opening url in a thread; BROWSER_WAIT seconds to connect."""
    from benchmarks.web_viewers import counting_chromium

    driver = counting_chromium(0, "--disable-dev-shm-usage", "--window-size=1200,720")
    opener = threading.Thread(target=driver.get, args=(url,), daemon=True)
    opener.start()
    time.sleep(BROWSER_WAIT)
    opener.join(timeout=10)
    return driver


def page_counter(driver) -> int:
    """The body updates the page has received so far (0 without a browser)."""
    return int(driver.execute_script("return window.__wb.frames")) if driver is not None else 0


def native_3d(scene, path: np.ndarray, warmup: int, reduced=None) -> dict:
    """explore_solid with the sliders' values scripted; its own fps over the frames after the first (the
    warm-up frames included: explore_3d times every frame but the first). reduced: a reduced model's file."""
    from taichi_pneuma.realtime import interactive3d
    from taichi_pneuma.realtime.interactive import explore_solid

    rows = iter(path[1:])
    real = interactive3d.commands_from
    interactive3d.commands_from = lambda sliders, shown, values: next(rows, None)  # type: ignore[assignment]
    try:
        start = time.perf_counter()
        summary = explore_solid(scene, (960, 640), max_frames=len(path), reduced=reduced)
        seconds = time.perf_counter() - start
    finally:
        interactive3d.commands_from = real
    return {"frames": summary["frames"], "fps": summary["fps"], "solves": summary["solves"], "call_seconds": seconds}


def native_2d(scene, path: np.ndarray, warmup: int, growth: float) -> dict:
    """explore with the canvas slider scripted; frames/s = frames / the call's wall time (warm-up included:
    the window opens inside the call, so the whole call is timed)."""
    from taichi_pneuma.realtime.interactive import explore
    from taichi_pneuma.render import canvases

    rows = iter(path[:, 0])
    saved = {c: c.slider for c in (canvases.GUICanvas, canvases.GGUICanvas)}
    for c in saved:
        c.slider = lambda self, label, value, low, high, row=0: float(next(rows, value))  # type: ignore[method-assign]
    try:
        start = time.perf_counter()
        summary = explore(scene, growth=growth, size=(960, 384), max_frames=len(path))
        seconds = time.perf_counter() - start
    finally:
        for c, f in saved.items():
            c.slider = f  # type: ignore[method-assign]
    return {"frames": len(path), "fps": len(path) / seconds, "solves": summary["solves"], "call_seconds": seconds}


def report(record: dict) -> str:
    """The Markdown table of a record."""
    lines = [
        f"Machine: {record['machine']}; {record['date']}; load average (1 min) {record['load'][0]:.1f} before,"
        f" {record['load'][1]:.1f} after. Command (repository root):",
        "",
        f"    {record['command']}",
        "",
        "Each row: the mean of the runs (runs: each run's value). See benchmarks/live_page.py's docstring for",
        "what each view times. Page received/s: with Chromium, the body updates that reached the page; with the",
        "reading client, the websocket messages it read (viser sends a frame's messages together, or several frames'",
        "when the client lags).",
        "",
        "| scene | nodes | view | frames/s | runs | share in advance | ms per advance | page received/s |",
        "|---|---:|---|---:|---|---:|---:|---:|",
    ]
    for row in record["rows"]:
        runs = row["runs"]
        fps = [r["fps"] for r in runs if r.get("fps")]
        share = [r["advance_share"] for r in runs if "advance_share" in r]
        ms = [r["ms_per_advance"] for r in runs if "ms_per_advance" in r]
        got = [r["browser_received_fps"] for r in runs if "browser_received_fps" in r]
        lines.append(
            f"| {row['scene']} | {row['nodes']} | {row['view']} | {np.mean(fps):.2f} | "
            + ", ".join(f"{v:.2f}" for v in fps)
            + f" | {f'{np.mean(share):.0%}' if share else '-'} | {f'{np.mean(ms):.0f}' if ms else '-'}"
            + f" | {f'{np.mean(got):.2f}' if got else '-'} |"
        )
    return "\n".join(lines) + "\n"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--frames", type=int, default=120)
    p.add_argument("--warmup", type=int, default=10)
    p.add_argument("--frames-3d", type=int, default=30)
    p.add_argument("--warmup-3d", type=int, default=3)
    p.add_argument("--views", default="page,reader,browser,native")
    p.add_argument("--scenes", default=",".join(SCENES))
    p.add_argument("--repeat", type=int, default=1)
    p.add_argument("--out", default=None, help="write live_page.md and .json here")
    args = p.parse_args()

    from taichi_pneuma import runtime
    from taichi_pneuma.realtime.interactive import chamber_sliders

    runtime.init("cpu")
    rows, load = [], os.getloadavg()[0]
    for name in args.scenes.split(","):
        scene = scene_named(name)
        sliders = chamber_sliders(scene)
        low, high = np.array([s.low for s in sliders]), np.array([s.high for s in sliders])
        mesh = scene.build().mesh
        three_d = mesh.dim == 3
        warmup, frames = (args.warmup_3d, args.frames_3d) if three_d else (args.warmup, args.frames)
        path = drag(low, high, warmup, frames)
        nodes = mesh.n_vertices
        for view in args.views.split(","):
            runs = []
            for _ in range(args.repeat):
                if view == "native":
                    run = native_3d(scene, path, warmup) if three_d else native_2d(scene, path, warmup, float(high[0]))
                else:
                    run = page_run(scene, path, warmup, client="" if view == "page" else view)
                print(name, view, json.dumps(run), flush=True)
                runs.append(run)
            label = {
                "page": "live page, no client",
                "reader": "live page + a client reading every frame",
                "browser": "live page + headless Chromium on the same cores",
            }.get(view, "")
            label = label or ("native GGUI window (explore_solid)" if three_d else "native ti.GUI window (explore)")
            rows.append({"scene": name, "nodes": nodes, "view": label, "key": view, "runs": runs})
    record = {
        "machine": f"{platform.machine()}, {os.cpu_count()} CPUs (shared), {platform.python_version()}",
        "date": date.today().isoformat(),
        "command": "xvfb-run -a python benchmarks/live_page.py " + " ".join(os.sys.argv[1:]),
        "load": [load, os.getloadavg()[0]],
        "rows": rows,
    }
    text = report(record)
    print(text)
    if args.out:
        out = Path(args.out)
        (out / "live_page.json").write_text(json.dumps(record, indent=1))
        (out / "live_page.md").write_text(text)


if __name__ == "__main__":
    main()
