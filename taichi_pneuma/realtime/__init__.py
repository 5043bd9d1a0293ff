"""realtime: the live views, an equilibrium kept while a slider, the schedule or the mouse moves a command or a
target: the native windows (interactive.py: 2D and the shared loop; interactive3d.py: the 3D slider window) and the
browser page (session.py: the live state apart from any view; web.py: the page, pneuma-serve and tp.live)."""
