"""gmsh, imported on demand (an optional dependency: INSTALL says how to get it), and a session of it: a model of its
own, silent, its options restored afterwards in a caller's session, and a gmsh exception turned into one
PneumaInputError quoting gmsh's last error lines.
"""

from __future__ import annotations

from contextlib import contextmanager

from ..errors import PneumaInputError

INSTALL = "pip install 'taichi-pneuma[3d]'"
# the global gmsh options meshing sets; a caller's gmsh session gets its values back afterwards
OPTIONS = (
    "General.Terminal",
    "Mesh.Algorithm",
    "Mesh.MeshSizeMax",
    "Mesh.MeshSizeFromPoints",
    "Mesh.MeshSizeFromCurvature",
    "Mesh.MeshSizeExtendFromBoundary",
)


def gmsh_module():
    try:
        import gmsh
    except ImportError:
        raise PneumaInputError(f"3D bodies from shapes are meshed by gmsh, which is not installed: {INSTALL}") from None
    return gmsh


@contextmanager
def session(verbose: bool = False):
    """gmsh with a model of its own, silent unless verbose; initialised and finalised around the block (in a
    caller's gmsh session: its current model and the options set here are restored instead). A gmsh
    exception becomes a PneumaInputError quoting gmsh's last error lines."""
    gmsh = gmsh_module()
    owner = not gmsh.isInitialized()
    if owner:
        gmsh.initialize(readConfigFiles=False, interruptible=False)
    callers = None if owner else (gmsh.model.getCurrent(), {name: gmsh.option.getNumber(name) for name in OPTIONS})
    gmsh.option.setNumber("General.Terminal", 1 if verbose else 0)
    gmsh.logger.start()
    gmsh.model.add("taichi_pneuma_solid")
    try:
        yield gmsh
    except Exception as exc:
        if isinstance(exc, PneumaInputError):
            raise
        log = [line for line in gmsh.logger.get() if "Error" in line or "error" in line]
        raise PneumaInputError(f"gmsh could not mesh the solid: {'; '.join(log[-3:]) or exc}") from None
    finally:
        gmsh.logger.stop()
        if callers is None:  # gmsh initialised here
            gmsh.finalize()
        else:
            gmsh.model.remove()
            gmsh.model.setCurrent(callers[0])
            for name, value in callers[1].items():
                gmsh.option.setNumber(name, value)
