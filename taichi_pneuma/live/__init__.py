"""live: the interactive windows, an equilibrium kept while a slider or the mouse moves a command or a target
(interactive.py: 2D and the shared loop; interactive3d.py: the 3D slider window)."""
