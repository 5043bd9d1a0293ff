"""The one place the package gets Taichi from: Taichi itself where its wheel installs, else Quadrants.

Quadrants (the Genesis project's fork of Taichi, `pip install quadrants`) keeps every name the kernels
use (kernel, func, template, types.ndarray, Matrix, linalg.SparseMatrixBuilder / SparseSolver, init's
options) and has wheels where Taichi has none: Python 3.14, Linux aarch64. Every module imports

    from ..backend import ti

and so runs unchanged on either. The choice: PNEUMA_BACKEND=taichi|quadrants forces one (an error
naming the install command when it is not installed); without it, Taichi if it imports, else Quadrants.

What differs is named here once: the environment variables each reads (Taichi's TI_*, Quadrants' QD_*),
and the arches each has (Quadrants dropped OpenGL). Quadrants also dropped Taichi's GUIs (ti.GUI, GGUI);
render/ asks has_gui() / has_ggui() and falls back to its own Pillow canvas.

Taichi 1.7 turns every kernel's Python source into its IR at the first call in a process, even when the compiled
kernel then comes from the offline cache, and for each syntax node it formats the node's source position (the
text of its error messages) with textwrap, again at every call site of an inlined ti.func: half the time of
loading the reference run's kernels. memoize_source_positions() gives the same text from a memo keyed by all it
is made of, as Quadrants does itself (its ASTTransformerContext.memoized_get_pos_info).
"""

from __future__ import annotations

import importlib
import os

from .environment import BACKENDS
from .errors import PneumaInputError

CHOICE_VARIABLE = "PNEUMA_BACKEND"
INSTALL = dict(zip(BACKENDS, ('pip install "taichi>=1.7,<1.8"', 'pip install "quadrants>=1.3.3,<1.5"')))
# the environment variables the package sets, by backend: kernel cache folder, banner printed at import
ENVIRONMENT = {
    "taichi": {"cache": "TI_OFFLINE_CACHE_FILE_PATH", "banner": "ENABLE_TAICHI_HEADER_PRINT"},
    "quadrants": {"cache": "QD_OFFLINE_CACHE_FILE_PATH", "banner": "ENABLE_QUADRANTS_HEADER_PRINT"},
}
ARCH_NAMES = ("cpu", "cuda", "vulkan", "metal", "opengl", "gpu")


class BackendUnavailable(PneumaInputError, ImportError):
    """Neither backend is installed, or PNEUMA_BACKEND names one that is not (or is not a backend): a user's
    mistake (PneumaInputError, as the commands' check_environment says it) and an ImportError."""


def _import(name: str):
    try:
        return importlib.import_module(name)
    except ImportError as exc:
        raise BackendUnavailable(
            f"{CHOICE_VARIABLE}={name}, but {name} does not import ({exc}); install it with: {INSTALL[name]}"
        ) from None


def _choose():
    forced = os.environ.get(CHOICE_VARIABLE, "")
    if forced:
        if forced not in INSTALL:
            raise BackendUnavailable(f"{CHOICE_VARIABLE}={forced!r} is not one of {', '.join(INSTALL)}")
        return forced, _import(forced)
    for name in INSTALL:
        try:
            return name, importlib.import_module(name)
        except ImportError:
            continue
    raise BackendUnavailable(
        "neither taichi nor quadrants is installed; install one with: " + " or ".join(INSTALL.values())
    )


def kernel(function):
    """ti.kernel; under Quadrants with its fastcache (fastcache=True: in a later process the compiled kernel is found
    from a hash of its source, its callees' and its arguments' types, without the AST work). For kernels whose
    arguments are arrays and numbers only: Quadrants 1.3's fastcache cannot hash a class passed as a template (a
    material law), and would warn at every such call."""
    return ti.kernel(fastcache=True)(function) if NAME == "quadrants" else ti.kernel(function)


def memoize_source_positions(context) -> None:
    """Replace Taichi 1.7's ASTTransformerContext.get_pos_info(node) by a memo of it (module docstring), keyed by
    what the text is made of: the function's file, name, first line and source lines, and the node's kind, span
    and, for a block statement, the line of its body."""
    original = context.get_pos_info
    memo: dict[tuple, str] = {}

    def get_pos_info(self, node):
        body = getattr(node, "body", None)
        key = (
            self.file,
            self.func.func.__name__,
            self.lineno_offset,
            tuple(self.src),
            type(node),
            node.lineno,
            node.end_lineno,
            node.col_offset,
            node.end_col_offset,
            body[0].lineno if isinstance(body, list) else None,
        )
        text = memo.get(key)
        if text is None:
            text = memo[key] = original(self, node)
        return text

    get_pos_info.original = original  # type: ignore[attr-defined]  # the method replaced, on the function
    context.get_pos_info = get_pos_info


NAME, ti = _choose()
VERSION = ".".join(str(v) for v in ti.__version__)
if NAME == "taichi" and ti.__version__[:2] == (1, 7):
    from taichi.lang.ast.ast_transformer_utils import ASTTransformerContext

    memoize_source_positions(ASTTransformerContext)
ARCHES = {name: getattr(ti, name) for name in ARCH_NAMES if hasattr(ti, name)}


def environment_name(what: str) -> str:
    """The environment variable this backend reads for `what` ('cache': its kernel cache folder,
    'banner': whether it prints its version line at import)."""
    return ENVIRONMENT[NAME][what]


def has_gui() -> bool:
    """Whether the backend has Taichi's software GUI (ti.GUI)."""
    return hasattr(ti, "GUI")


def has_ggui() -> bool:
    """Whether the backend has Taichi's Vulkan GUI (ti.ui, GGUI)."""
    return hasattr(ti, "ui")
