"""Regenerate every picture the README and the docs pages show, from the apps' own output, with one command:

    python docs/pictures.py            (about 2 minutes on 2 cores)

Each picture is the file a command writes, run as a user types it into a scratch directory and copied onto
docs/<picture>; nothing is drawn here. PICTURES names every picture, the command that makes it and the file of its
output that it is (tests/test_docs_pictures.py checks that every picture the README and the docs show is one of
them).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

DOCS = Path(__file__).resolve().parent

# picture in docs/ -> (the command, run in a scratch directory, the file it writes there that the picture is)
PICTURES = {
    "inflate.png": ("pneuma-inflate --cy 0.15", "out/inflate_cy+0.15.png"),
    "inflate_plot.png": ("pneuma-inflate --cy 0.15", "out/inflate_cy+0.15_plot.png"),
    "steer.png": ("pneuma-steer", "out/steer.png"),
    "sweep.png": (
        "pneuma-sweep --vary cy=-0.15:0.15:5 --vary E=5e3:2e4:3 --name height_modulus",
        "out/height_modulus.png",
    ),
    "scene_bidirectional.png": ("pneuma-inflate --scene bidirectional", "out/bidirectional.png"),
    "scene_pneunet_finger.png": ("pneuma-inflate --scene pneunet_finger", "out/pneunet_finger.png"),
    "scene_finger_on_ground.png": ("pneuma-inflate --scene finger_on_ground", "out/finger_on_ground.png"),
    "scene_beam_3d.png": ("pneuma-inflate --scene beam_3d", "out/beam_3d.png"),
    "scene_balloon_syringe.png": ("pneuma-inflate --scene balloon_syringe", "out/balloon_syringe.png"),
    "balloon_curves.png": ("python examples/balloon_curves.py out", "out/balloon_curves.png"),
    # the live page in headless Chromium, the browser test's own session (tests/test_web.py, run as a script)
    "live_page.png": ("python tests/test_web.py out", "out/live_page.png"),
}


def command_line(command: str) -> list[str]:
    """The argv of a command as a user types it: pneuma-X runs the app module in this interpreter, python this
    interpreter on the script's path in the repository; the apps run with --quiet (no progress bar)."""
    program, *args = command.split()
    if program == "python":
        return [sys.executable, str(DOCS.parent / args[0]), *args[1:]]
    return [sys.executable, "-m", f"taichi_pneuma.apps.{program.removeprefix('pneuma-')}", *args, "--quiet"]


def main() -> None:
    with tempfile.TemporaryDirectory() as scratch:
        done: set[str] = set()
        for picture, (command, output) in PICTURES.items():
            if command not in done:
                print(f"$ {command}", flush=True)
                subprocess.run(command_line(command), cwd=scratch, check=True, stdout=subprocess.DEVNULL)
                done.add(command)
            shutil.copyfile(Path(scratch) / output, DOCS / picture)
            print(f"  docs/{picture} <- {output}")


if __name__ == "__main__":
    main()
