"""The live simulator in a browser: a viser page (viser: a web viewer of three.js scenes with GUI controls, served
from Python over a websocket) showing a LiveSession's body as it converges, with its controls.

The page has a slider per chamber command, a "play the schedule" box, a field to colour the body by, a gizmo to
drag a target for the tip (inverse control: the chambers follow), the step's figures (tip, rotation, pressures,
Newton iterations, residual, the frames per second served and those the browser drew), a colour bar and a button
that saves the equilibria kept so far like Result.save; the view turns and zooms with the mouse (2D bodies lie in
the z = 0 plane, seen from +z).

The caller's thread runs the session (run(), or run_async() on a notebook kernel's event loop: Taichi launches
kernels from the main thread only); viser's own threads serve the page and keep its controls' values, in the
order the page's messages came. Each frame (step) reads the controls, hands what changed to the session, takes one
step (LiveSession.advance) and publishes the body as a glTF mesh with a colour per node; only this thread touches
the session, and a control moved during a long step is read, at its latest value, at the next frame.
Publishing only queues a message; viser keeps, per scene node, only the newest message not yet sent to a
client, so a slow client skips frames and never holds the solver back.

Safe by default: the server listens on 127.0.0.1 only; a websocket's HTTP upgrade is refused (403, before any
frame is read) unless its URL carries the page's token (secrets.token_urlsafe, printed in the URL as Jupyter prints
its own), so another user of the machine cannot watch or steer the scene (realtime/gate.py). A message is at most
gate.MAX_MESSAGE bytes, and one is handed on only if it is one this page's client sends with values the page's
controls hold (refusal): a bad one is logged in one line and dropped, the session going on. The page serves the one
scene it was started with and takes no uploads.
"""

from __future__ import annotations

import asyncio
import html
import secrets
import threading
import time
from collections import deque
from typing import cast

import numpy as np

from ..errors import PneumaInputError, quoted, require
from ..io.units import LENGTH, PRESSURE
from ..render.colours import CHAMBER_FILL, FACE, OBSTACLE, OBSTACLE_FILL, colormap
from ..render.view2d import chamber_triangles
from .address import check_host, common_port, page_url
from .gate import guarded_serve
from .pageparts import DrawnRates, colour_bar, finite, iframe_height, quiet_viser
from .session import FIELDS, LiveSession

FPS_WINDOW = 2.0  # seconds of frames the frame rate is measured over
IDLE_SECONDS = 0.02  # the loop's pause when nothing changed (a settled state)
RED = (200, 40, 40)
MIN_RANGE = 1e-3  # the colour scale spans at least this fraction of the field's size
SLIDER_SLACK = 1e-6  # a slider's value is taken this fraction of its range outside it (the client's rounding)
TARGET_ROOM = 10.0  # a target for the tip is taken within this many body extents of the rest body
# the messages viser's client sends for this page's controls (sliders, box, menu, button, the target's gizmo, the
# camera); the others (uploads, share links, forms, clicks, renders, commands) are for controls it does not have
PAGE_MESSAGES = (
    "GuiUpdateMessage",
    "TransformControlsUpdateMessage",
    "TransformControlsDragStartMessage",
    "TransformControlsDragEndMessage",
    "ViewerCameraMessage",
    "LocalStorageGetItemResponseMessage",  # the frames/s the browser drew (pageparts.DrawnRates)
)


class WebView:
    """A LiveSession served as a page (see the module docstring); run() or run_async() runs it, stop() ends it.

    out, stem: where the save button writes (out/<stem>_*); host, port: where the server listens (port 0: a free
    one); field: the FIELDS key the body is first coloured by; token: the URL's token (a fresh random one by
    default)."""

    def __init__(
        self,
        session: LiveSession,
        out="out",
        stem: str | None = None,
        host: str = "127.0.0.1",
        port: int = 8080,
        field: str = "max_stretch",
        token: str | None = None,
    ):
        import viser

        require(field in FIELDS, f"field {field!r} is not one of {', '.join(FIELDS)}")
        require(0 <= port <= 65535, f"port {port} is not one of 0 .. 65535")
        check_host(host)
        self.session, self.out, self.stem = session, out, stem or session.scene.name
        self.field, self.token, self.host = field, token or secrets.token_urlsafe(16), host
        self.stopping, self._asked = threading.Event(), threading.Event()  # stop(); the save button pressed
        self.frames, self.fps, self.published = 0, 0.0, 0
        self._height = 560  # a notebook's iframe height (pixels)
        self.task: asyncio.Task | None = None  # the notebook's frame task (live)
        self._times: deque[float] = deque()
        self._range: tuple[float, float] | None = None  # the colour scale, widened as the field grows
        self._redraw = True  # the body to publish at the next frame whether the state changed or not
        self._driven = 0  # the session's count of commands it set itself, as the sliders show them
        self._inputs: dict = {}  # per control's uuid, the check of a value the page sends for it (_controls)
        mesh = session.mesh  # a 2D body's chambers are holes in its triangles: filled as the videos fill them
        self._chamber_faces = chamber_triangles(mesh) if mesh.dim == 2 and len(mesh.chambers) else None
        self.chambers = None  # their node, once published
        with quiet_viser(), guarded_serve(self.token, self.refusal):  # (viser's banner: its address, no token)
            self.server = viser.ViserServer(host=host, port=common_port(host, port), verbose=False)
        # no share button: viser's relay would put the page on the internet (and its websocket lacks the token)
        self.server.gui.configure_theme(show_share_button=False)
        self.server.scene.set_up_direction("+y")
        self._controls()
        self._place_camera()
        self.drawn = DrawnRates(self.server, FPS_WINDOW, self.stopping)

    @property
    def port(self) -> int:
        return self.server.get_port()

    @property
    def url(self) -> str:
        return page_url(self.host, self.port, self.token)

    @property
    def height(self) -> int:
        """The notebook iframe's height (pixels; iframe_height checks a new one)."""
        return self._height

    @height.setter
    def height(self, value) -> None:
        self._height = iframe_height(value)

    def refusal(self, message) -> str | None:
        """Why a message from the page is refused, None if it is not: it must be msgpack (binary) of a dict whose
        type is one of PAGE_MESSAGES, a control's value one it can hold (a slider's a finite number in its range,
        the box's a bool, the menu's one of its options, the button's True), the target's position finite and
        within TARGET_ROOM body extents, the camera's numbers finite, a drawn frame rate a number (DrawnRates),
        and viser must decode it; none is taken before the controls are made."""
        import msgspec
        from viser import _messages

        if not self._inputs:
            return "the page's controls are not made yet"
        if not isinstance(message, bytes):
            return "a text message (the page sends binary ones)"
        try:
            decoded = msgspec.msgpack.decode(message)
        except (msgspec.DecodeError, RecursionError) as exc:
            return f"not msgpack ({len(message)} bytes: {type(exc).__name__})"
        kind = decoded.get("type") if isinstance(decoded, dict) else None
        if kind not in PAGE_MESSAGES:
            return f"a message of type {quoted(kind)}: this page takes only {', '.join(PAGE_MESSAGES)}"
        reason = self._value_refusal(kind, decoded)
        if reason is not None:
            return f"{kind}: {reason}"
        try:
            _messages.Message.deserialize(message)
        except Exception as exc:  # viser's decoding of a message (any error: the message is malformed)
            return f"{kind}: malformed ({type(exc).__name__}: {quoted(exc)})"
        return None

    def _value_refusal(self, kind: str, message: dict) -> str | None:
        """refusal's check of one of PAGE_MESSAGES' values."""
        if kind == "GuiUpdateMessage":
            uuid = message.get("uuid")
            check = self._inputs.get(uuid) if isinstance(uuid, str) else None
            updates = message.get("updates")
            if check is None:
                return f"uuid {quoted(uuid)} is none of this page's controls"
            if not isinstance(updates, dict) or list(updates) != ["value"]:
                return f"updates {quoted(updates)} must set the control's value only"
            return check(updates["value"])
        if kind == "LocalStorageGetItemResponseMessage":
            return DrawnRates.refusal(message)
        if kind == "ViewerCameraMessage":
            numbers = [x for k, v in message.items() if k != "type" for x in (v if isinstance(v, list) else [v])]
            return None if all(finite(x) for x in numbers) else "its numbers must be finite"
        if message.get("name") != self.target.name:
            return f"name {quoted(message.get('name'))} is not the target's ({self.target.name})"
        if kind == "TransformControlsUpdateMessage":
            position, wxyz = message.get("position"), message.get("wxyz")
            if not (isinstance(wxyz, list) and len(wxyz) == 4 and all(finite(x) for x in wxyz)):
                return f"wxyz {quoted(wxyz)} is not 4 finite numbers"
            if not (isinstance(position, list) and len(position) == 3 and all(finite(x) for x in position)):
                return f"position {quoted(position)} is not 3 finite numbers"
            rest = self._points(self.session.mesh.vertices)
            room = TARGET_ROOM * self._extent()
            if np.any(np.array(position) < rest.min(axis=0) - room) or np.any(
                np.array(position) > rest.max(axis=0) + room
            ):
                return f"position {quoted(position)} is more than {TARGET_ROOM:g} body extents from the body"
        return None

    def _input_checks(self) -> None:
        """Each control's check of a value the page sends for it (by the control's uuid): why it is refused, None
        if it is not. A slider's range is widened by SLIDER_SLACK of it for the client's rounding (the session
        clips)."""

        def slider(low, high):
            slack = SLIDER_SLACK * (high - low)
            return lambda v: (
                None
                if finite(v) and low - slack <= v <= high + slack
                else f"slider value {quoted(v)} is not a finite number in {low:g} .. {high:g}"
            )

        checks = {s._impl.uuid: slider(s.min, s.max) for s in self.sliders}
        checks[self.play._impl.uuid] = lambda v: None if isinstance(v, bool) else f"box value {quoted(v)} is not a bool"
        checks[self.field_menu._impl.uuid] = lambda v: (
            None if isinstance(v, str) and v in FIELDS else f"menu value {quoted(v)} is not one of {', '.join(FIELDS)}"
        )
        checks[self.save._impl.uuid] = lambda v: None if v is True else f"button value {quoted(v)} is not true"
        self._inputs = checks

    def _controls(self) -> None:
        """The page's panel: sliders, play, field, figures, save; the clamp's nodes and the target's gizmo."""
        gui, session, scene = self.server.gui, self.session, self.server.scene
        mesh = session.mesh
        gui.add_markdown(f"**{session.scene.name}**: {mesh.n_vertices} nodes, {mesh.n_elements} elements")
        with gui.add_folder("chambers"):
            self.sliders = [
                gui.add_slider(s.name, min=s.low, max=s.high, step=(s.high - s.low) / 200, initial_value=s.value)
                for s in session.sliders
            ]
        self.play = gui.add_checkbox("play the schedule", initial_value=False)
        self.field_menu = gui.add_dropdown("colour by", tuple(FIELDS), initial_value=self.field)
        self.figures = gui.add_markdown("starting ...")
        self.bar = gui.add_html("")
        self.save = gui.add_button("save state")
        self.save.on_click(lambda _: self._asked.set())
        self.saved = gui.add_markdown("")
        rest = self._points(mesh.vertices)
        scene.add_point_cloud("/clamp", rest[mesh.pinned], colors=RED, point_size=0.004 * self._extent())
        self._surroundings(rest)
        tip = rest[mesh.tip].mean(axis=0)
        self.target = scene.add_transform_controls(
            "/target",
            scale=0.15 * self._extent(),
            disable_rotations=True,
            active_axes=(True, True, mesh.dim == 3),
            position=tip,
        )
        # what the controls showed at the last frame: a control that differs now was moved on the page
        self._shown = self._controls_now()
        self._input_checks()

    def _surroundings(self, rest: np.ndarray) -> None:
        """The ground and the rigid obstacles where they are placed: in 2D their outlines in the z = 0 plane, in 3D
        their surfaces (render/guides3d.py), each a node the frames move by its obstacle's offset."""
        from ..render.guides3d import obstacle_triangles
        from ..terms.obstacle_shapes import Plane

        scene, spec, extent = self.server.scene, self.session.scene, self._extent()
        fill, edge = ((np.array(colour) * 255).round().astype(np.uint8) for colour in (OBSTACLE_FILL, OBSTACLE))
        lo, hi = rest.min(axis=0), rest.max(axis=0)
        ground = next((e.ground_height for e in spec.effects if e.ground_height is not None), None)
        if ground is not None and self.session.mesh.dim == 2:
            ends = np.array([[[lo[0] - extent, ground, 0.0], [hi[0] + extent, ground, 0.0]]])
            scene.add_line_segments("/ground", ends, colors=edge, thickness=3.0)
        elif ground is not None:
            floor = Plane((float(lo[0] + hi[0]) / 2, float(ground), float(lo[2] + hi[2]) / 2), (0.0, 1.0, 0.0))
            triangles, _ = obstacle_triangles(floor, extent)
            self._add_triangles("/ground", triangles, fill)
        self._obstacles = []
        for obstacle in spec.obstacles:
            name = f"/obstacles/{obstacle.name}"
            if self.session.mesh.dim == 2:
                points, closed = obstacle.shape.outline(2 * extent)
                ring = np.column_stack([points, np.zeros(len(points))])
                segments = np.stack([ring, np.roll(ring, -1, axis=0)], axis=1)[: len(ring) if closed else 1]
                self._obstacles.append(scene.add_line_segments(name, segments, colors=edge, thickness=2.5))
            else:
                triangles, edges = obstacle_triangles(obstacle.shape, extent)
                self._obstacles.append(self._add_triangles(name, triangles, fill))
                if len(edges):
                    scene.add_line_segments(f"{name}/edges", edges, colors=edge, thickness=1.5)

    def _add_triangles(self, name: str, triangles: np.ndarray, colour: np.ndarray):
        """Triangles (t, 3, 3) as one flat-shaded mesh node, seen from both sides."""
        faces = np.arange(3 * len(triangles)).reshape(-1, 3)
        return self.server.scene.add_mesh_simple(
            name, triangles.reshape(-1, 3), faces, color=colour, flat_shading=True, side="double"
        )

    def _move_obstacles(self) -> None:
        """Each obstacle's node at its obstacle's offset now (a moving obstacle's, as the schedule plays)."""
        for node, term in zip(self._obstacles, self.session.built.obstacles):
            offset = np.asarray(term.offset, dtype=float)
            if not np.array_equal(node.position, offset):
                node.position = offset

    def _controls_now(self) -> tuple:
        """The values of the page's controls (viser sets them in the order the page's messages came)."""
        sliders = tuple(float(s.value) for s in self.sliders)
        return sliders, bool(self.play.value), str(self.field_menu.value), tuple(self.target.position)

    def _read_page(self) -> None:
        """Hand what the page changed since the last frame to the session: a slider's command, play or pause, the
        field, a dragged target; the save button's press."""
        now, session = self._controls_now(), self.session
        (sliders, playing, field, target), (shown_sliders, shown_playing, shown_field, shown_target) = now, self._shown
        for j, (value, shown) in enumerate(zip(sliders, shown_sliders)):
            if value != shown:
                session.command(j, value)
        if playing != shown_playing:
            session.play(playing)
        if field != shown_field:
            self.field, self._range, self._redraw = field, None, True
        if target != shown_target:
            session.aim(target)
        self._shown = now
        if self._asked.is_set():
            self._asked.clear()
            self._save()

    def _show_session(self) -> None:
        """Set the controls the session moved itself (the sliders while playing or after a reach; play at the
        schedule's end) to its values, and remember them as shown."""
        session, (sliders, playing, field, target) = self.session, self._shown
        if session.driven != self._driven:
            self._driven = session.driven
            for slider, value in zip(self.sliders, session.commands):
                slider.value = float(value)  # type: ignore[misc]  # (viser's setter takes more types than it gives)
            sliders = tuple(float(s.value) for s in self.sliders)  # as the handles hold them (viser may round)
        if playing != session.playing:
            self.play.value = session.playing  # type: ignore[misc]  # (the same setter)
            playing = bool(self.play.value)
        # only what was set here counts as shown: a control the page moved meanwhile still differs, for the next frame
        self._shown = (sliders, playing, field, target)

    def _extent(self) -> float:
        rest = self.session.mesh.vertices
        return float(np.ptp(rest, axis=0).max())

    def _place_camera(self) -> None:
        """Look at the rest body from +z (and, in 3D, from above and the side), far enough to see it whole beside
        the panel."""
        rest = self._points(self.session.mesh.vertices)
        centre, extent = (rest.min(axis=0) + rest.max(axis=0)) / 2, self._extent()
        direction = np.array([0.0, 0.0, 1.0]) if self.session.mesh.dim == 2 else np.array([0.5, 0.6, 1.0])
        aim = centre + np.array([0.2 * extent, 0.0, 0.0])  # the body left of the panel (top right)
        camera = self.server.initial_camera
        camera.look_at = tuple(aim)
        camera.position = tuple(aim + 0.8 * extent * direction / np.linalg.norm(direction))

    def _points(self, positions: np.ndarray) -> np.ndarray:
        """Positions as 3D points (a 2D body in the z = 0 plane)."""
        return positions if positions.shape[1] == 3 else np.column_stack([positions, np.zeros(len(positions))])

    def _save(self) -> None:
        """Write the kept equilibria (Result.save) and say so on the page; bad state is said there, not raised."""
        try:
            paths = self.session.save(self.out, self.stem)
            self.saved.content = f"saved {len(self.session.steps)} states: " + ", ".join(p.name for p in paths)
        except PneumaInputError as exc:
            self.saved.content = f"not saved: {exc}"

    def colours(self) -> np.ndarray:
        """RGBA (n, 4) uint8 per node: the field on the colour map over the range it has spanned, at least
        MIN_RANGE of its size wide (1 where the field is 0: a body at rest is one colour, not its round-off spread
        over the whole map); FACE for none."""
        values = self.session.field(self.field)
        if values is None:
            rgb = np.tile(np.array(FACE), (self.session.mesh.n_vertices, 1))
        else:
            lo, hi = float(values.min()), float(values.max())
            if self._range is not None:
                lo, hi = min(lo, self._range[0]), max(hi, self._range[1])
            size = max(abs(lo), abs(hi))
            widen = max(0.0, (MIN_RANGE * size if size > 0 else 1.0) - (hi - lo)) / 2
            self._range = (lo - widen, hi + widen)
            lo, hi = self._range
            rgb = colormap(values, lo, hi)
        return (np.column_stack([rgb, np.ones(len(rgb))]) * 255).round().astype(np.uint8)

    def _publish(self) -> None:
        """Send the body at the state shown, coloured (a glTF binary with per-node colours; the newest wins)."""
        import trimesh
        from trimesh.visual import TextureVisuals
        from trimesh.visual.material import PBRMaterial

        # a rubber's material: not metallic (glTF's default, dark without an environment), seen from both sides
        visual = TextureVisuals(material=PBRMaterial(metallicFactor=0.0, roughnessFactor=0.8, doubleSided=True))
        visual.vertex_attributes["color"] = self.colours()
        body = trimesh.Trimesh(
            self._points(self.session.positions()), self.session.triangles, visual=visual, process=False
        )
        self.server.scene.add_glb("/body", cast(bytes, body.export(file_type="glb")))
        if self._chamber_faces is not None:  # 2D: each chamber's inside filled, as the videos draw it
            fill = (np.array(CHAMBER_FILL) * 255).round().astype(np.uint8)
            self.chambers = self._add_triangles("/chambers", body.vertices[self._chamber_faces], fill)
        self.published += 1

    def caption(self) -> str:
        """The figures of the state shown, as the page's markdown."""
        figures, units = self.session.figures(), self.session.scene.units
        length, pressure = units.suffix(LENGTH), units.suffix(PRESSURE)
        tip = ", ".join(f"d{axis} {value:+.4g}" for axis, value in zip("xyz", figures["tip"]))
        chambers = ", ".join(
            f"{name} {c:.4g} (p {p:.4g}{pressure})"
            for name, c, p in zip(self.session.names, figures["commands"], figures["pressures"])
        )
        lines = [
            f"tip {tip}{length}, rotation {figures['rotation']:+.2f} deg",
            f"commands: {chambers}",
            f"Newton {figures['iterations']} it, residual {figures['residual']:.1e} ({figures['state']})",
            "; ".join(filter(None, (f"{self.fps:.1f} frames/s served", self.drawn.text()))),
        ]
        if figures["model"] is not None:
            lines.insert(3, figures["model"])
        if figures["playing"] or figures["schedule_step"]:
            lines.append(
                f"schedule step {figures['schedule_step']:g} of {self.session.scene.schedule.increments}"
                + (" (playing)" if figures["playing"] else "")
            )
        if figures["reach_error"] is not None:
            lines.append(f"last reach: {figures['reach_error']:.3g}{length} from its target")
        return "  \n".join(lines)

    def legend(self) -> str:
        """The colour bar of the field the body is coloured by, over its range now (colour_bar); "" for none."""
        if self._range is None:  # (none: the body in one colour, no range)
            return ""
        label, unit = FIELDS[self.field]
        suffix = self.session.scene.units.suffix({"pressure": PRESSURE, "length": LENGTH}[unit]) if unit else ""
        return colour_bar(label, *self._range, suffix)

    def step(self) -> bool:
        """One frame: what the page asked handed to the session, the session's step, then (if the state changed or
        the field did) the body published; the controls the session moved and the figures shown."""
        self._read_page()
        changed = self.session.advance()
        if changed or self._redraw:
            self._redraw = False
            self._publish()
            now = time.perf_counter()
            self._times.append(now)
            while now - self._times[0] > FPS_WINDOW:
                self._times.popleft()
            self.fps = (len(self._times) - 1) / (now - self._times[0]) if len(self._times) > 1 else 0.0
        self._show_session()
        self._move_obstacles()
        caption = self.caption()
        if caption != self.figures.content:
            self.figures.content = caption
        legend = self.legend()
        if legend != self.bar.content:
            self.bar.content = legend
        self.frames += 1
        return changed

    def _repr_html_(self) -> str:
        """The page in an iframe: how a notebook shows the view (tp.live)."""
        return (
            f'<iframe src="{html.escape(self.url)}" width="100%" height="{self.height}" '
            'style="border: 1px solid #ddd"></iframe>'
        )

    def run(self, until=None) -> None:
        """Run frames on this thread (Taichi compiles and launches kernels on the main thread only) until stop()
        is called, or until() returns True; a settled state waits IDLE_SECONDS between frames."""
        while not self.stopping.is_set() and not (until is not None and until()):
            if not self.step():
                self.stopping.wait(IDLE_SECONDS)

    async def run_async(self) -> None:
        """run() as a task of the running event loop (a Jupyter kernel's, on its main thread): a frame, then the
        loop's other work (the notebook's cells) before the next."""
        while not self.stopping.is_set():
            await asyncio.sleep(0 if self.step() else IDLE_SECONDS)

    def stop(self) -> None:
        """End run() (from another thread, a signal handler or a callback) and close the server."""
        self.stopping.set()
        with quiet_viser():  # viser's "Server stopped"
            self.server.stop()


def live(scene, out="out", port: int = 0, field: str = "max_stretch", height: int = 560, reduced=None) -> WebView:
    """The live page of a scene (a Scene, a shipped scene's name or a scene file) in a Jupyter notebook, served
    from this process: shown as the cell's output (an iframe of the page), its frames run as a task of the
    kernel's event loop between cells (the kernel's main thread, where Taichi runs). view.stop() ends it.
    reduced: the file of a reduced model of the scene (pneuma-reduce), solved live inside its training range.
    Outside a running event loop (a script), use pneuma-serve or WebView(...).run()."""
    from ..runtime import ensure_initialised
    from ..scene import scenefile
    from ..scene.shipped import find

    iframe_height(height)
    try:
        loop = asyncio.get_running_loop()
    except RuntimeError:
        require(False, "tp.live needs a running event loop (a Jupyter kernel); in a script run pneuma-serve")
    ensure_initialised()
    scene = scene if not isinstance(scene, str) else scenefile.load_scene(find(scene))
    view = WebView(LiveSession(scene, reduced=reduced), out, port=port, field=field)
    view.height = height
    view.task = loop.create_task(view.run_async())
    print(f"the live page (keep its token private): {view.url}")
    return view
