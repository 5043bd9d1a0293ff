"""Input files read within a size limit: read_input reads a file only if it is a regular file (a FIFO or a device
such as /dev/zero is refused without blocking), and at most a given number of bytes.
"""

from __future__ import annotations

import os
import stat

from ..errors import PneumaInputError, quoted, require

NOFOLLOW = getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)


def read_input(path: str | os.PathLike, max_bytes: int, what: str, follow_links: bool = True) -> bytes:
    """The bytes of the input file at path (`what` names it in errors: "scene file"), refused unless it is a
    regular file of at most max_bytes bytes: a FIFO, a device or a folder is refused without reading or
    waiting, and no more than max_bytes + 1 bytes are ever read. follow_links False: a link is refused."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | (getattr(os, "O_CLOEXEC", 0) if follow_links else NOFOLLOW))
    except OSError as exc:
        raise PneumaInputError(f"{what} {quoted(path)} cannot be read ({exc.strerror})") from None
    if not stat.S_ISREG(os.fstat(fd).st_mode):  # checked before open(fd), which refuses a folder with its own error
        os.close(fd)
        raise PneumaInputError(
            f"{what} {quoted(path)} is not a regular file (a FIFO, a device or a folder cannot be read as one)"
        )
    with open(fd, "rb") as f:
        try:
            data = f.read(max_bytes + 1)
        except OSError as exc:
            raise PneumaInputError(f"{what} {str(path)!r} cannot be read ({exc.strerror})") from None
    require(len(data) <= max_bytes, f"{path}: larger than {max_bytes} bytes, the most a {what} may be")
    return data
