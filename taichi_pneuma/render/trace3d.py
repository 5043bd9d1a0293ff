"""The trace panel beside a 3D frame: up to two series against the step, the first on the left axis and the
second on the right, drawn once by matplotlib; a cursor marks the current step."""

from __future__ import annotations

import numpy as np

TRACE_COLORS = ("#1f3fe0", "#d62718")


class TracePanel:
    """The series of a track against the step, drawn once by matplotlib onto a (height, width) image;
    frame(i) adds the cursor at step i."""

    def __init__(self, trace, steps: int, width: int, height: int):
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        figure = Figure(figsize=(width / 100, height / 100), dpi=100)
        canvas = FigureCanvasAgg(figure)
        axes = figure.add_axes((0.2, 0.14, 0.6, 0.72))
        step = np.arange(steps)
        for k, ((label, values), color) in enumerate(zip(trace, TRACE_COLORS)):
            ax = axes if k == 0 else axes.twinx()
            ax.plot(step, np.reshape(values, (steps, -1)), color=color, marker="o", markersize=2.5, lw=1.5)
            ax.set_ylabel(label, color=color)
            ax.tick_params(axis="y", colors=color)
        axes.set_xlabel("step")
        axes.set_xlim(0, max(steps - 1, 1))
        canvas.draw()
        self.image = np.asarray(canvas.buffer_rgba())[:, :, :3].copy()
        box = axes.get_window_extent()
        self.columns = [int(round(c)) for c in axes.transData.transform(np.column_stack([step, step * 0]))[:, 0]]
        self.rows = (int(round(height - box.y1)), int(round(height - box.y0)))

    def frame(self, i: int) -> np.ndarray:
        image = self.image.copy()
        image[self.rows[0] : self.rows[1], self.columns[i]] = (60, 60, 60)
        return image
