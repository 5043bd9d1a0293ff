"""Live web views of a deforming, coloured body: viser against trame, with one headless Chromium watching.

    python -m benchmarks.web_viewers [--trame-python /tmp/sz/v_trame/bin/python] [--seconds 8] [--warmup 3]
        [--repeat 2] [--fps 30] [--out benchmarks/results]   (from the repository root, with the project's venv)

Meshes: the 2D reference beam (its triangles, z = 0) and the coarse 3D PneuNet's surface (outer faces and chamber
walls, compacted to the vertices they use), dumped to an .npz that the trame process loads. Each frame moves the
rest vertices by a smooth bend that grows and shrinks (u = a(t) L s^2 across the body, s = (x - x0)/L,
a(t) = 0.3 sin(2 pi t / 4 s)) and colours them by |u| (a 5-stop viridis ramp; trame maps the raw scalar
through VTK's lookup table in the browser instead).
Candidates, each offered --fps frames per second (the publisher sleeps out the rest of each frame period):
  viser-glb: viser 1.1.1, the coloured mesh as a GLB built by trimesh, re-added under one name every frame;
  viser-simple: viser's add_mesh_simple, then handle.vertices = new every frame (one colour: no per-vertex field);
  trame: trame 4 with trame-vtk's VtkLocalView (vtk.js renders in the browser, so rotate/zoom is client-side) of a
      vtkPolyData with point scalars, ctrl.view_update() every frame; run by --trame-python as
      `web_viewers.py --candidate trame` in a subprocess (trame and vtk live in their own venv).
Measured over --seconds after --warmup seconds, --repeat times per candidate and mesh, with one headless Chromium
(Selenium 4, SwiftShader WebGL, 1000 x 700) on the page:
  publish ms/frame: wall time of the publish call (colours, GLB or VTK arrays, the library's send), the mean;
  client frames/s: mesh updates that reached the page, counted by a script injected before the page loads:
      viser decodes its websocket in a Web Worker, so the script wraps window.Worker and counts the worker's
      messages to the page that carry the body's new bytes (GlbMessage or the vertices); trame's wslink websocket
      is in the page, so it wraps window.WebSocket and counts the points arrays vtk.js fetches (messages of the
      points array's size: vtk.js asks for the new arrays of a scene it is about to draw, and skips scenes that a
      newer one overtook);
  client MB/s and KB/frame: bytes of those messages (viser: the body's payload; trame: every websocket message,
      scene descriptions included) per second and per counted frame;
  page rAF/s: requestAnimationFrame callbacks per second (the page's draw loop; viser's three.js canvas draws in it);
  page draws/s: frames the page drew, counted as the tasks in which a WebGL context's clear() was called.
The install sizes are not measured here (a fresh venv each, numpy first, then the candidate: see INSTALL_MB).
Writes web_viewers.md and .json (machine, date). Two shared cores: numbers are noisy, every run is listed.
"""

import argparse
import importlib.metadata
import json
import os
import platform
import subprocess
import tempfile
import threading
import time
from datetime import date
from pathlib import Path

import numpy as np

MESHES = ("beam_2d", "pneunet_3d")
TRAME_PACKAGES = ("trame", "trame-server", "trame-client", "trame-vtk", "trame-vuetify", "vtk")
CHROME_ARGS = ("--headless=new", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader")
# fresh venv, `pip install numpy`, then the candidate: du -sm after minus before (measured by hand, 2026-12-02)
INSTALL_MB = {"anywidget": 79, "viser": 82, "trame + trame-vuetify + trame-vtk + vtk": 715}
JUPYTER = {
    "viser": "an IFrame of its own server, started in the kernel's process",
    "trame": "`await server.ready` then display `server.ui` (trame-jupyter-extension proxies it)",
    "anywidget": "native ipywidgets (the kernel's comm channel), no standalone server",
}
VIRIDIS = np.array([[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]], float)

# Injected before the page's own scripts: counts the body's updates that reach the page (see the module docstring).
COUNTER_JS = """
window.__wb = {frames: 0, bytes: 0, raf: 0, draws: 0};
let drawing = false;
for (const gl of [WebGLRenderingContext, WebGL2RenderingContext]) {
  const clear = gl.prototype.clear;
  gl.prototype.clear = function (mask) {
    if (!drawing) { drawing = true; window.__wb.draws++; setTimeout(() => { drawing = false; }, 0); }
    return clear.call(this, mask);
  };
}
const pointsBytes = %d;
function payload(v) {
  if (v && v.byteLength !== undefined) return v.byteLength;
  if (v && typeof v === 'object') return Object.values(v).reduce((s, x) => s + payload(x), 0);
  return 0;
}
const RealWorker = window.Worker;
window.Worker = function (...a) {
  const w = new RealWorker(...a);
  w.addEventListener('message', (e) => {
    for (const m of (e.data && e.data.messages) || []) {
      const b = m.name === '/body' ? payload(m) : 0;
      if (b > 0) { window.__wb.frames++; window.__wb.bytes += b; }
    }
  });
  return w;
};
window.Worker.prototype = RealWorker.prototype;
const RealSocket = window.WebSocket;
window.WebSocket = function (...a) {
  const s = new RealSocket(...a);
  s.addEventListener('message', (e) => {
    const d = e.data, n = typeof d === 'string' ? d.length : (d.byteLength !== undefined ? d.byteLength : d.size);
    window.__wb.bytes += n;
    if (n >= pointsBytes && n < pointsBytes + 512) window.__wb.frames++;
  });
  return s;
};
window.WebSocket.prototype = RealSocket.prototype;
Object.assign(window.WebSocket, RealSocket);
const realRaf = window.requestAnimationFrame.bind(window);
window.requestAnimationFrame = (cb) => realRaf((t) => { window.__wb.raf++; cb(t); });
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--candidate", choices=("all", "trame"), default="all", help="trame: one run, JSON on stdout")
    parser.add_argument("--trame-python", default="/tmp/sz/v_trame/bin/python", help="a python with trame and vtk")
    parser.add_argument("--seconds", type=float, default=8.0, help="measured wall time of each run")
    parser.add_argument("--warmup", type=float, default=3.0, help="seconds after the page loads before measuring")
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--fps", type=float, default=30.0, help="frames offered per second (0: as fast as it goes)")
    parser.add_argument("--meshes", help="the .npz of the meshes (internal: the trame subprocess)")
    parser.add_argument("--mesh", choices=MESHES, default=MESHES[0], help="internal: the trame subprocess's mesh")
    parser.add_argument("--out", default="benchmarks/results")
    args = parser.parse_args()
    if args.candidate == "trame":
        meshes = np.load(args.meshes)
        print(json.dumps(run_trame(meshes[f"{args.mesh}_v"], meshes[f"{args.mesh}_f"], args)))
        return
    with tempfile.TemporaryDirectory() as tmp:
        npz = Path(tmp) / "meshes.npz"
        np.savez(npz, **dump_meshes())
        meshes = np.load(npz)
        runs = []
        for mesh in MESHES:
            vertices, faces = meshes[f"{mesh}_v"], meshes[f"{mesh}_f"]
            for candidate in ("viser-glb", "viser-simple", "trame"):
                for _ in range(args.repeat):
                    if candidate == "trame":
                        command = [args.trame_python, __file__, "--candidate", "trame", "--meshes", str(npz)]
                        command += ["--mesh", mesh, "--seconds", str(args.seconds), "--warmup", str(args.warmup)]
                        command += ["--fps", str(args.fps)]
                        done = subprocess.run(command, capture_output=True, text=True, timeout=120, check=True)
                        run = json.loads(done.stdout.strip().splitlines()[-1])
                    else:
                        run = run_viser(vertices, faces, candidate == "viser-simple", args)
                    run.update(candidate=candidate, mesh=mesh, triangles=len(faces), vertices=len(vertices))
                    print(json.dumps(run), flush=True)
                    runs.append(run)
        trame_licences = [run.pop("licences") for run in runs if "licences" in run]
        licences = [licence("viser"), licence("trimesh"), *trame_licences[0]]
    machine = f"{platform.node()}, {platform.machine()}, {os.cpu_count()} CPUs"
    record = {"machine": machine, "date": str(date.today()), "seconds": args.seconds, "warmup": args.warmup}
    record.update(fps_offered=args.fps, install_mb=INSTALL_MB, licences=licences, jupyter=JUPYTER, runs=runs)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "web_viewers.json").write_text(json.dumps(record, indent=1) + "\n")
    text = report(record)
    (out / "web_viewers.md").write_text(text)
    print(text)


def dump_meshes() -> dict[str, np.ndarray]:
    """The two meshes as vertices (n, 3) and triangles: the 2D beam at z = 0, the PneuNet's used surface."""
    import taichi_pneuma as tp
    from taichi_pneuma.render.frames3d import surface_triangles

    beam = tp.load_scene("reference_beam").build().mesh
    beam_v = np.c_[beam.vertices, np.zeros(len(beam.vertices))]
    pneunet = tp.load_scene("pneunet_3d").build().mesh
    outer, walls, _ = surface_triangles(pneunet)
    used, faces = np.unique(np.concatenate([outer, *walls]), return_inverse=True)
    return {
        "beam_2d_v": beam_v,
        "beam_2d_f": np.asarray(beam.elements, np.int32),
        "pneunet_3d_v": np.asarray(pneunet.vertices)[used],
        "pneunet_3d_f": faces.reshape(-1, 3).astype(np.int32),
    }


def bend(rest: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
    """Vertices bent by u = a(t) L s^2 along the last axis the body spans, and |u| per vertex."""
    x = rest[:, 0]
    length = x.max() - x.min()
    s = (x - x.min()) / length
    axis = 2 if np.ptp(rest[:, 2]) > 0 else 1
    u = 0.3 * np.sin(2 * np.pi * t / 4.0) * length * s**2
    moved = rest.copy()
    moved[:, axis] += u
    return moved, np.abs(u)


def colours(field: np.ndarray, top: float) -> np.ndarray:
    """RGBA uint8 per vertex: field / top on a 5-stop viridis ramp."""
    f = np.clip(field / top, 0.0, 1.0) * (len(VIRIDIS) - 1)
    rgb = np.stack([np.interp(f, np.arange(len(VIRIDIS)), VIRIDIS[:, k]) for k in range(3)], axis=1)
    return np.c_[rgb, np.full(len(field), 255)].astype(np.uint8)


def counting_chromium(points_bytes: int, *args: str):
    """A headless Chromium (CHROME_ARGS, then args) with COUNTER_JS in place before any page's scripts."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for arg in (*CHROME_ARGS, *args):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
    driver.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument", {"source": COUNTER_JS % points_bytes})
    return driver


def open_page(url: str, points_bytes: int):
    """counting_chromium on url."""
    driver = counting_chromium(points_bytes, "--window-size=1000,700")
    driver.get(url)
    return driver


def watch(driver, published: list[float], args) -> dict:
    """Client and server rates over args.seconds after args.warmup; published holds each publish call's seconds."""
    time.sleep(args.warmup)
    before, sent0, start = driver.execute_script("return {...window.__wb}"), len(published), time.perf_counter()
    time.sleep(args.seconds)
    after, calls, span = (
        driver.execute_script("return {...window.__wb}"),
        published[sent0:],
        time.perf_counter() - start,
    )
    frames, mb = after["frames"] - before["frames"], (after["bytes"] - before["bytes"]) / 1e6
    return {
        "publish_ms": 1e3 * float(np.mean(calls)) if calls else None,
        "published_per_s": len(calls) / span,
        "client_fps": frames / span,
        "client_mb_per_s": mb / span,
        "kb_per_frame": 1e3 * mb / frames if frames else None,
        "page_raf_per_s": (after["raf"] - before["raf"]) / span,
        "page_draws_per_s": (after["draws"] - before["draws"]) / span,
    }


def run_viser(rest: np.ndarray, faces: np.ndarray, simple: bool, args) -> dict:
    """One viser run: the body re-sent every frame (a coloured GLB, or add_mesh_simple's vertices)."""
    import trimesh
    import viser

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    handle = server.scene.add_mesh_simple("/body", rest.astype(np.float32), faces.astype(np.uint32)) if simple else None
    top = bend(rest, 1.0)[1].max()
    published: list[float] = []
    stop = threading.Event()

    def publish() -> None:
        start = time.perf_counter()
        while not stop.is_set():
            t = time.perf_counter() - start
            moved, field = bend(rest, t)
            tick = time.perf_counter()
            if handle is not None:
                handle.vertices = moved.astype(np.float32)
            else:
                glb = trimesh.Trimesh(moved, faces, vertex_colors=colours(field, top), process=False)
                server.scene.add_glb("/body", glb.export(file_type="glb"))
            published.append(time.perf_counter() - tick)
            pace(start, len(published), args.fps)

    publisher = threading.Thread(target=publish)
    publisher.start()
    driver = open_page(f"http://127.0.0.1:{server.get_port()}/", 0)
    try:
        return watch(driver, published, args)
    finally:
        stop.set()
        publisher.join()
        driver.quit()
        server.stop()


def run_trame(rest: np.ndarray, faces: np.ndarray, args) -> dict:
    """One trame run: a VtkLocalView of the body's vtkPolyData, its points and scalars replaced every frame."""
    import asyncio
    import socket

    import vtk  # type: ignore[import-not-found]
    from trame.app import get_server  # type: ignore[import-not-found]
    from trame.ui.vuetify3 import SinglePageLayout  # type: ignore[import-not-found]
    from trame.widgets import vtk as vtk_widgets  # type: ignore[import-not-found]
    from trame.widgets import vuetify3  # type: ignore[import-not-found]
    from vtk.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray  # type: ignore[import-not-found]

    points = vtk.vtkPoints()
    points.SetData(numpy_to_vtk(rest, deep=True))
    cells = vtk.vtkCellArray()
    offsets = np.arange(0, 3 * len(faces) + 1, 3, dtype=np.int64)
    cells.SetData(numpy_to_vtkIdTypeArray(offsets, deep=True), numpy_to_vtkIdTypeArray(faces.ravel().astype(np.int64)))
    body = vtk.vtkPolyData()
    body.SetPoints(points)
    body.SetPolys(cells)
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputData(body)
    mapper.SetScalarRange(0.0, bend(rest, 1.0)[1].max())
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    renderer = vtk.vtkRenderer()
    renderer.AddActor(actor)
    window = vtk.vtkRenderWindow()
    window.AddRenderer(renderer)
    window.SetOffScreenRendering(1)
    renderer.ResetCamera()

    server = get_server("web_viewers", client_type="vue3")
    with (
        SinglePageLayout(server) as layout,
        layout.content,
        vuetify3.VContainer(fluid=True, classes="pa-0 fill-height"),
    ):
        view = vtk_widgets.VtkLocalView(window)
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    published: list[float] = []
    result: dict = {}
    tasks: list = []  # the publisher's task, held while the server runs

    async def publish() -> None:
        start = time.perf_counter()
        while True:
            moved, field = bend(rest, time.perf_counter() - start)
            tick = time.perf_counter()
            points.SetData(numpy_to_vtk(moved, deep=True))
            scalars = numpy_to_vtk(field, deep=True)
            scalars.SetName("u")
            body.GetPointData().SetScalars(scalars)
            body.Modified()
            view.update()
            published.append(time.perf_counter() - tick)
            await asyncio.sleep(max(0.0, start + len(published) / args.fps - time.perf_counter()) if args.fps else 0)

    def client(loop) -> None:
        driver = open_page(f"http://127.0.0.1:{port}/", 8 * rest.size)
        try:
            result.update(watch(driver, published, args))
        finally:
            driver.quit()
            asyncio.run_coroutine_threadsafe(server.stop(), loop)

    @server.controller.add("on_server_ready")
    def ready(**_) -> None:
        loop = asyncio.get_running_loop()
        tasks.append(loop.create_task(publish()))
        threading.Thread(target=client, args=(loop,), daemon=True).start()

    server.start(port=port, open_browser=False, show_connection_info=False, disable_logging=True)
    return result | {"licences": [licence(p) for p in TRAME_PACKAGES]}


def pace(start: float, frames: int, fps: float) -> None:
    """Sleep until frame `frames` is due at fps frames per second (fps 0: only yield the GIL)."""
    time.sleep(max(0.0, start + frames / fps - time.perf_counter()) if fps else 0)


def licence(package: str) -> str:
    """'name version: licence' from the installed package's metadata (its licence expression or classifier)."""
    meta = importlib.metadata.metadata(package)
    classifiers = [c.split(" :: ")[-1] for c in meta.get_all("Classifier") or [] if c.startswith("License ::")]
    text = meta.get("License-Expression") or (classifiers[0] if classifiers else meta.get("License"))
    return f"{package} {importlib.metadata.version(package)}: {text}"


def report(record: dict) -> str:
    """The results page: the runs table, install sizes, licences, Jupyter support, the command."""
    lines = [
        f"Machine: {record['machine']}; {record['date']}. One headless Chromium (SwiftShader WebGL) per run; "
        f"{record['fps_offered']:g} frames/s offered, measured over {record['seconds']:g} s after "
        f"{record['warmup']:g} s. Every run listed (a shared 2-core machine: noisy).",
        "",
        "| candidate | mesh | triangles | publish ms/frame | published/s | client frames/s | client MB/s "
        "| KB/frame | page rAF/s | page draws/s |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in record["runs"]:
        ms = f"{r['publish_ms']:.1f}" if r["publish_ms"] is not None else "-"
        kb = f"{r['kb_per_frame']:.0f}" if r["kb_per_frame"] is not None else "-"
        lines.append(
            f"| {r['candidate']} | {r['mesh']} | {r['triangles']} | {ms} | {r['published_per_s']:.1f} "
            f"| {r['client_fps']:.1f} | {r['client_mb_per_s']:.2f} | {kb} "
            f"| {r['page_raf_per_s']:.1f} | {r['page_draws_per_s']:.1f} |"
        )
    lines += ["", "Install size (MB; fresh venv, `pip install numpy`, then the candidate, `du -sm` difference):", ""]
    lines += [f"- {name}: {mb}" for name, mb in record["install_mb"].items()]
    lines += ["", "Licences (installed packages' metadata):", ""] + [f"- {line}" for line in record["licences"]]
    lines += ["", "Jupyter:", ""] + [f"- {name}: {how}" for name, how in record["jupyter"].items()]
    lines += ["", "Reproduce: `python -m benchmarks.web_viewers --trame-python /tmp/sz/v_trame/bin/python`", ""]
    return "\n".join(lines)


if __name__ == "__main__":
    main()
