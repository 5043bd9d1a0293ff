"""render: 2D frames (frames.py: FrameRenderer on the canvases of canvases.py and pillow_canvas.py, with
colours.py, text.py, ticks.py, view2d.py, scalebar.py), 3D frames (frames3d.py: camera.py, surface.py, ggui3d.py,
section.py, guides3d.py, trace3d.py), videos (video.py), the history plot (plots.py), ParaView files (paraview.py;
the fibres, sheets and obstacles beside the body: paraview_parts.py), matplotlib pictures of a Result for scripts and
the gallery (drawing.py). The choices the apps offer are plain data here, so --help reads
them without Taichi."""

# auto: the faster one measured, ti.GUI (else Pillow where the backend has no GUI; canvases.open_canvas)
RENDERERS = ("auto", "ggui", "gui", "pillow")
# the fields a body can be coloured by: name -> (label, key of fields.ElementFields.at)
COLOR_FIELDS = {"stretch": ("max stretch", "max_stretch"), "detF": ("det F", "det_F")}
