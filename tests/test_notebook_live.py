"""tp.live in a notebook: a Jupyter kernel (ipykernel, driven by nbclient) runs the cells; the cell that calls
tp.live shows the page's iframe with its token and prints only its URL (no viser banner), and the live frames run
between cells on the kernel's main thread: a chamber commanded from a later cell is settled by the time the next
cell looks, the tip moved."""

import re

import pytest

pytest.importorskip("viser")
nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

CELLS = [
    "import asyncio, taichi_pneuma as tp\nview = tp.live('pneunet_finger', out=OUT)\nview",
    "await asyncio.sleep(2)\nrest = view.session.figures()['tip'][1]\nview.session.command(0, 900.0)",
    "for _ in range(600):\n"
    "    await asyncio.sleep(0.05)\n"
    "    if view.session.equilibrium.converged and view.session.commands[0] == 900.0:\n"
    "        break\n"
    "print('frames', view.frames, 'tip', rest, view.session.figures()['tip'][1], view.session.figures()['state'])",
    "view.stop()",
]


def test_the_notebook_widget_shows_the_page_and_solves_between_cells(tmp_path):
    notebook = nbformat.v4.new_notebook()
    notebook.cells = [nbformat.v4.new_code_cell(f"OUT = {str(tmp_path)!r}")] + [
        nbformat.v4.new_code_cell(source) for source in CELLS
    ]
    nbclient.NotebookClient(notebook, timeout=120, kernel_name="python3").execute()
    *printed, shown = notebook.cells[1].outputs
    html = shown["data"]["text/html"]
    assert "<iframe" in html and "websocket=ws://127.0.0.1:" in html and "token%3D" in html
    # before the iframe, only lines printed to stdout: the backend's start (Taichi or Quadrants) and the page's URL,
    # the one the iframe loads (no viser banner: rich shows it as display data in a kernel, without the token)
    assert all(output["output_type"] == "stream" and output["name"] == "stdout" for output in printed), printed
    lines = "".join(output["text"] for output in printed).splitlines()
    url = re.search(r'src="([^"]+)"', html)[1].replace("&amp;", "&")
    assert [line for line in lines if not line.startswith(("[Taichi]", "[Quadrants]"))] == [
        f"the live page (keep its token private): {url}"
    ]
    words = notebook.cells[3].outputs[-1]["text"].split()
    frames, rest, tip, state = int(words[1]), float(words[3]), float(words[4]), words[5]
    assert frames > 1 and state == "equilibrium"
    # the first chamber of the finger at 900 bends it: its tip moves by more than a hundredth of its length (4)
    assert rest == 0.0 and abs(tip - rest) > 0.04
