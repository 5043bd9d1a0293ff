"""Parts of the live page (realtime/web.py) beside its WebView: the colour bar's HTML, viser's console silenced,
the notebook iframe's height checked, a number from the page checked finite, and the frames per second each open
page's browser draws (DrawnRates: a script in the page counts them, the server reads them back)."""

from __future__ import annotations

import contextlib
import html
import math
import string
import threading

import numpy as np

from ..errors import quoted, require
from ..render.colours import COLORMAP, colormap

HEIGHTS = (100, 4000)  # the notebook iframe's heights allowed (pixels)
BAR_STOPS = 16  # the colour bar's gradient: this many colours of the map, evenly spaced
DRAWS_KEY = "pneuma_draws_"  # + the client's id: the browser's localStorage key of its drawn frames per second
DRAW_GAP_MS = 500  # a longer pause between drawn frames ends a run of them (viser draws on demand: idle, it rests)
RATE_CHARS = 32  # the longest rate a page may report (characters)
POLL_SECONDS = 1.0  # how often the server reads the browsers' rates (and waits at most for one's answer)


def iframe_height(height) -> int:
    """A notebook iframe's height: an integer number of pixels in HEIGHTS."""
    require(
        isinstance(height, int) and not isinstance(height, bool) and HEIGHTS[0] <= height <= HEIGHTS[1],
        f"height {quoted(height)} is not an integer number of pixels in {HEIGHTS[0]} .. {HEIGHTS[1]}",
    )
    return height


def finite(value) -> bool:
    """Whether value is a finite number (an int or a float, not a bool)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


@contextlib.contextmanager
def quiet_viser():
    """viser's own lines (its banner, "Server stopped") silenced while in the block: viser prints them with rich's
    console, which in a notebook kernel shows them in the cell's output through IPython's display, past sys.stdout;
    verbose=False only silences its connection lines. rich's console drops all it is given while quiet (any
    thread's, for the moment the block lasts: the server's start or stop)."""
    import rich

    console = rich.get_console()
    quiet, console.quiet = console.quiet, True
    try:
        yield
    finally:
        console.quiet = quiet


def colour_bar(label: str, lo: float, hi: float, suffix: str) -> str:
    """The colour bar under the figures, as HTML: the field's label over a strip of the colour map (BAR_STOPS of its
    colours, lo at the left end, hi at the right, colormap's own mapping of lo + t (hi - lo) for t = 0 .. 1), the
    range's ends under its ends, in the field's unit."""
    colours = colormap(np.linspace(lo, hi, BAR_STOPS), lo, hi)
    stops = ", ".join(
        f"#{r:02x}{g:02x}{b:02x} {100 * k / (BAR_STOPS - 1):.4g}%"
        for k, (r, g, b) in enumerate((colours * 255).round().astype(int))
    )
    end = "<span>{:.4g}{}</span>"
    return (
        f'<div style="font-size: 0.85em; padding: 0 0.75em">{html.escape(label)} ({COLORMAP})'
        f'<div style="height: 0.9em; border: 1px solid #888; background: linear-gradient(to right, {stops})"></div>'
        f'<div style="display: flex; justify-content: space-between">{end.format(lo, suffix)}{end.format(hi, suffix)}'
        "</div></div>"
    )


DRAW_COUNTER = string.Template("""(() => {
  const key = "viser-user:$key";  // viser's client prefixes the keys it reads for the server (LocalStorageHandle)
  if (window.__pneumaDraws) { window.__pneumaDraws.key = key; return; }  // (a reconnect: the counter runs already)
  const state = (window.__pneumaDraws = { key, drew: false, times: [], written: 0 });
  for (const name of Object.keys(localStorage))  // the keys of this origin's earlier pages
    if (name.startsWith("viser-user:$prefix") && name !== key) localStorage.removeItem(name);
  for (const kind of [window.WebGLRenderingContext, window.WebGL2RenderingContext]) {
    if (!kind) continue;
    const clear = kind.prototype.clear;  // three.js clears the canvas at the start of each frame it draws
    kind.prototype.clear = function (...args) { state.drew = true; return clear.apply(this, args); };
  }
  const tick = (now) => {
    if (state.drew) {
      state.drew = false;
      const times = state.times;
      if (times.length && now - times[times.length - 1] > $gap) times.length = 0;
      times.push(now);
      while (now - times[0] > $window) times.shift();
      if (times.length > 1 && now - state.written > 250) {
        localStorage.setItem(state.key, String(((times.length - 1) * 1000) / (now - times[0])));
        state.written = now;
      }
    }
    requestAnimationFrame(tick);
  };
  requestAnimationFrame(tick);
})();""")


def draw_counter(client_id: int, window: float) -> str:
    """The script (run in the page by viser's client) that counts the frames the browser draws: the animation
    frames in which a WebGL canvas was cleared (three.js clears it as it starts to draw), over the last `window`
    seconds of a run of them (a pause over DRAW_GAP_MS starts a new run: viser draws on demand, so an idle page
    keeps the rate of its last busy run, as the server's rate does), written to the browser's localStorage under
    DRAWS_KEY + client_id for the server to read (draw_rate)."""
    return DRAW_COUNTER.substitute(
        key=f"{DRAWS_KEY}{client_id}", prefix=DRAWS_KEY, gap=DRAW_GAP_MS, window=f"{1000 * window:g}"
    )


def draw_rate(value) -> float | None:
    """The frames per second a page reports it draws (draw_counter's localStorage value): a string of at most
    RATE_CHARS characters holding a finite number >= 0; None for none yet or anything else."""
    if not isinstance(value, str) or len(value) > RATE_CHARS:
        return None
    try:
        rate = float(value)
    except ValueError:
        return None
    return rate if math.isfinite(rate) and rate >= 0 else None


class DrawnRates:
    """The frames per second each open page's browser draws, by viser client id: draw_counter runs in each page
    as it connects (viser's RunJavascriptMessage), and a thread of its own reads each page's rate back every
    POLL_SECONDS (viser's localStorage request; a page's answer is checked by refusal before viser takes it)."""

    def __init__(self, server, window: float, stopping: threading.Event):
        self.rates: dict[int, float] = {}
        self.window = window
        server.on_client_connect(self._install)
        server.on_client_disconnect(lambda client: self.rates.pop(client.client_id, None))
        threading.Thread(target=self._read, args=(server, stopping), daemon=True, name="live page draws").start()

    def _install(self, client) -> None:
        from viser import _messages

        script = draw_counter(client.client_id, self.window)
        client._websock_connection.queue_message(_messages.RunJavascriptMessage(source=script))

    def _read(self, server, stopping: threading.Event) -> None:
        while not stopping.wait(POLL_SECONDS):
            for client_id, client in server.get_clients().items():
                try:
                    value = client.local_storage.get_item(f"{DRAWS_KEY}{client_id}", timeout=POLL_SECONDS)
                except (RuntimeError, TimeoutError):  # gone, or its browser refuses localStorage, or slow: none
                    continue
                rate = draw_rate(value)
                if rate is not None:
                    self.rates[client_id] = rate

    def text(self) -> str:
        """The rates as the page's figures say them ("" before a page has drawn)."""
        rates = [f"{rate:.1f}" for _, rate in sorted(self.rates.items())]
        if not rates:
            return ""
        return f"the browser{'s' if len(rates) > 1 else ''} drew {', '.join(rates)} frames/s"

    @staticmethod
    def refusal(message: dict) -> str | None:
        """Why a page's localStorage answer is refused (None if it is not): its value must be a rate (draw_rate)
        or none, its error none or a string, its request's id a string, each of at most 200 characters."""
        value, error, request = message.get("value"), message.get("error"), message.get("request_uuid")
        if not (isinstance(request, str) and len(request) <= 200):
            return f"request_uuid {quoted(request)} is not a string of at most 200 characters"
        if not (error is None or (isinstance(error, str) and len(error) <= 200)):
            return f"error {quoted(error)} is not none or a string of at most 200 characters"
        if value is not None and draw_rate(value) is None:
            return f"value {quoted(value)} is not a frame rate (a number >= 0 in at most {RATE_CHARS} characters)"
        return None
