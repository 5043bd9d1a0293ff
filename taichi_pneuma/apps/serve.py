"""The live simulator in a browser: serve one scene's body, live, to a web page, on this machine only.

    pneuma-serve --scene pneunet_finger          (or python -m taichi_pneuma.apps.serve; needs the [web] extra)

Builds the scene (a shipped scene's name or a scene file; without --scene the reference beam of the flags), then
serves a page (realtime/web.py) with a slider per chamber command, play/pause of the scene's schedule, a gizmo to drag
a target for the tip (inverse control), a field to colour the body by, the step's figures and frame rate, and a
button that writes the equilibria reached so far to --out (<stem>_history.csv, _states.npz, _summary.json, ...,
as pneuma-inflate writes a ramp). It listens on 127.0.0.1 and prints the page's URL with its token: open it in a
browser here, or from another machine through an SSH tunnel (ssh -L PORT:localhost:PORT this-machine, then the
same URL). Ctrl-C stops it; --seconds stops it after that long.
"""

from __future__ import annotations

import argparse
import sys
import time

from .. import runtime
from ..errors import require
from ..io.output import prepare_directory
from .cli import (
    add_ramp_arguments,
    add_scene_arguments,
    app_parser,
    budget,
    exit_code,
    locking_note,
    newton_options,
    scene_of_flags,
)
from .stems import result_stem


def parser() -> argparse.ArgumentParser:
    p = app_parser("pneuma-serve", __doc__)
    add_scene_arguments(p)
    p.add_argument("--port", type=int, default=8080, help="the port to listen on (0: a free one; taken: the next)")
    p.add_argument(
        "--host",
        default="127.0.0.1",
        help="the address to listen on; another than 127.0.0.1 opens the page (with its token) to the network",
    )
    p.add_argument("--field", default="max_stretch", help="the field the body is first coloured by")
    p.add_argument("--seconds", type=float, default=None, help="stop after this many seconds (default: Ctrl-C)")
    p.add_argument(
        "--reduced",
        metavar="MODEL.npz",
        help="solve on this reduced model of the scene (pneuma-reduce) inside its training range (outside: the full)",
    )
    add_ramp_arguments(p)
    return p


def run(args: argparse.Namespace) -> dict:
    try:
        import viser  # noqa: F401
    except ImportError:
        require(False, 'pneuma-serve needs the web extra: pip install "taichi-pneuma[web]"')
    from ..realtime.address import check_host
    from ..realtime.session import FIELDS, LiveSession
    from ..realtime.web import WebView

    require(args.field in FIELDS, f"--field {args.field!r} is not one of {', '.join(FIELDS)}")
    require(0 <= args.port <= 65535, f"--port {args.port} is not one of 0 .. 65535")
    require(args.seconds is None or args.seconds > 0, f"--seconds {args.seconds} must be > 0")
    check_host(args.host)
    scene = scene_of_flags(args)
    stem = result_stem(scene.name if args.scene else f"inflate_cy{args.cy:+.2f}", args, scene) + "_live"
    out = prepare_directory(args.out)
    runtime.init(args.arch)
    session = LiveSession(scene, budget(args), newton_options(args), args.reduced)
    view = WebView(session, out, stem, args.host, args.port, args.field)
    if args.host not in ("127.0.0.1", "localhost", "::1"):
        where = {"": "every address", "0.0.0.0": "every IPv4 address", "::": "every IPv6 address"}.get(args.host)
        print(
            f"warning: listening on {where or args.host}: anyone who can reach it and has the URL can steer this scene"
        )
    note = locking_note(scene, session.mesh)
    if session.reduced is not None:
        model = session.reduced
        elements = f"{len(model.elements)} of {session.mesh.n_elements} elements"
        print(f"reduced model {args.reduced}: {model.n_modes} modes, {elements}, solved live inside its training range")
    print(f"scene {scene.name}: {session.mesh.n_vertices} nodes{note}; the live page (keep its token private):")
    print(f"  {view.url}", flush=True)
    print(f"from another machine: ssh -L {view.port}:localhost:{view.port} <this machine>, then the same URL")
    ends = None if args.seconds is None else time.monotonic() + args.seconds
    try:
        view.run(until=None if ends is None else lambda: time.monotonic() >= ends)
    finally:
        view.stop()
    print(f"served {view.frames} frames; the states kept: {len(session.steps)}")
    return {"all_converged": True}


def main(argv: list[str] | None = None) -> int:
    return exit_code(run, parser().parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
