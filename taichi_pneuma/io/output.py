"""Result files: written whole or not at all, inside the output directory only, by one run per name at a time
(input files are read by inputs.py).

- A result file is written into a private folder made for it beside its target (mkdtemp: mode 0700, a
  random name `.<file>.<pid>.<random>.partial`, made by mkdir, so never a planted link or another's
  folder), then renamed onto the target: the rename replaces a link found there instead of following it,
  and a folder there is one error naming the file.
- A folder a run writes into inside the output directory (<stem>_vtk) is a Subfolder: made, then opened
  without following a link, and its files renamed into it through that descriptor, so a link planted
  at its name, or swapped in during the run, is never followed.
- A run holds a lock per result stem (lock_stems): `.<stem>.lock` in the output directory, flock'ed; a
  second run of the same stem is one error naming it (another run holds it), never an interleaving.
- The private folders that runs killed outright (SIGKILL) left behind are removed by the next run that
  prepares the directory (those of processes no longer alive).

Result files are named after the scene, so a scene name must be a plain file name (STEM): no
separator, no leading dot, nothing that could lead outside the output directory. Chamber names head CSV
columns, so they must not start like a spreadsheet formula (check_heading).
"""

from __future__ import annotations

import fcntl
import json
import os
import re
import shutil
import tempfile
import weakref
from contextlib import ExitStack, contextmanager, nullcontext
from pathlib import Path

import numpy as np

from ..errors import PneumaInputError, require
from .inputs import NOFOLLOW

MAX_NAME = 100
STEM = re.compile(r"[A-Za-z0-9_+-][A-Za-z0-9_.+-]*")
PARTIAL = re.compile(r"\..+\.(\d{1,9})\.[a-z0-9_]{8}\.partial")  # .<file>.<pid>.<random>.partial
FORMULA = ("=", "+", "-", "@", "\t", "\r")  # a spreadsheet reads a CSV cell starting so as a formula


def check_stem(name) -> str:
    """Return name if it can name result files inside the output directory, else raise naming it and what is allowed."""
    require(
        isinstance(name, str) and len(name) <= MAX_NAME and STEM.fullmatch(name) is not None,
        f"name = {name!r} cannot name the result files: use 1 to {MAX_NAME} letters, digits and _ + - . "
        f"(not starting with '.')",
    )
    return name


def check_heading(what: str, name) -> None:
    """Refuse a name that heads CSV columns (a chamber's: <name>.pressure) if it starts with one of FORMULA,
    which would make a spreadsheet read the heading as a formula."""
    require(
        not (isinstance(name, str) and name.startswith(FORMULA)),
        f"{what} {name!r} cannot start with = + - @, a tab or a carriage return: it heads CSV columns, which a "
        f"spreadsheet would read as a formula",
    )


def reduce_to_stem(text: str) -> str:
    """text made a valid stem: every other character replaced by '_', leading dots dropped, cut to MAX_NAME."""
    return re.sub(r"[^A-Za-z0-9_.+-]", "_", text).lstrip(".")[:MAX_NAME] or "scene"


def prepare_directory(path: str | os.PathLike) -> Path:
    """Create the output directory if needed, check it is writable (raise naming it otherwise) and remove
    the private folders of dead runs from it."""
    directory = Path(path)
    try:
        directory.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=directory):
            pass
    except OSError as exc:
        raise PneumaInputError(f"output directory {str(directory)!r} is not writable ({exc.strerror})") from None
    remove_stale(directory)
    return directory


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


def remove_stale(directory: Path) -> None:
    """Remove the private folders (PARTIAL) in directory whose process is no longer alive."""
    for entry in os.scandir(directory):
        match = PARTIAL.fullmatch(entry.name)
        if match and entry.is_dir(follow_symlinks=False) and not alive(int(match.group(1))):
            shutil.rmtree(entry.path, ignore_errors=True)


@contextmanager
def private_folder(directory: Path, name: str):
    """A new folder in directory only this user can enter (named after the file `name` and this process), removed
    with its contents afterwards."""
    folder = Path(tempfile.mkdtemp(prefix=f".{name}.{os.getpid()}.", suffix=".partial", dir=directory))
    try:
        yield folder
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def held_private_folder(owner, directory: Path, name: str) -> Path:
    """A private folder in directory, as private_folder's, kept until owner is collected or the process ends: the
    scratch of a writer of many files (write_atomic's scratch), one folder made and removed instead of one per
    file (removing a folder takes as long as writing a step's VTU here). A killed run's is removed by the next
    run's prepare_directory."""
    folder = Path(tempfile.mkdtemp(prefix=f".{name}.{os.getpid()}.", suffix=".partial", dir=directory))
    weakref.finalize(owner, shutil.rmtree, folder, True)
    return folder


class Subfolder:
    """A folder `name` inside an output directory, made if missing and opened without following a link (a
    link or a file at its name is refused, naming it); files are renamed into it through that descriptor."""

    def __init__(self, directory: str | os.PathLike, name: str):
        self.directory, self.path = Path(directory), Path(directory) / name
        try:
            self.path.mkdir(exist_ok=True)
        except FileExistsError:
            pass  # a link or a file: refused below
        except OSError as exc:
            raise PneumaInputError(f"cannot make the folder {str(self.path)!r} ({exc.strerror})") from None
        try:
            self.fd = os.open(self.path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_DIRECTORY", 0) | NOFOLLOW)
        except OSError:
            kind = "a link" if self.path.is_symlink() else "a file"
            raise PneumaInputError(
                f"{str(self.path)!r} is {kind}, not a folder: the results cannot go in it "
                f"(a link inside the output directory is never followed); remove it"
            ) from None
        weakref.finalize(self, os.close, self.fd)

    def names(self) -> list[str]:
        return os.listdir(self.fd)

    def remove(self, name: str) -> None:
        """Remove the file `name` from the folder (a folder of that name is left alone)."""
        try:
            os.unlink(name, dir_fd=self.fd)
        except IsADirectoryError:
            pass


def write_atomic(path: str | os.PathLike, write, folder: Subfolder | None = None, scratch: Path | None = None) -> Path:
    """Call write(tmp_path) on a path in a private folder beside path, and rename it to path only if it
    returns without error. folder: the Subfolder path lies in (its
    private folder is then made in the output directory, and the rename goes through the folder's
    descriptor). scratch: a held_private_folder of that directory to use instead of a new private folder.

    An OSError (disk full, permission, a folder at path) becomes a PneumaInputError naming the file."""
    path = Path(path)
    try:
        with (
            nullcontext(scratch)
            if scratch is not None
            else private_folder(path.parent if folder is None else folder.directory, path.name)
        ) as private:
            tmp = private / path.name
            write(tmp)
            if folder is None:
                os.replace(tmp, path)
            else:
                os.replace(tmp, path.name, dst_dir_fd=folder.fd)
    except OSError as exc:
        raise PneumaInputError(f"cannot write {str(path)!r} ({exc.strerror or exc})") from None
    return path


def save_text(path: Path, text: str, scratch: Path | None = None) -> Path:
    return write_atomic(path, lambda tmp: tmp.write_text(text, encoding="utf-8"), scratch=scratch)


def save_json(path: Path, data: dict) -> Path:
    return save_text(path, json.dumps(data, indent=2) + "\n")


def save_npz(path: Path, **arrays) -> Path:
    """The arrays as an .npz file, uncompressed: float states compress by ~10 % at ~20x the time (0.16
    against 0.007 s for the reference ramp's states)."""

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as f:
            np.savez(f, **arrays)

    return write_atomic(path, write)


def open_appending(path: Path):
    """A text file of the output directory opened to append to, not through a link (refused as an error naming it)."""
    try:
        return os.fdopen(os.open(path, os.O_WRONLY | os.O_APPEND | NOFOLLOW), "a", newline="", encoding="utf-8")
    except OSError as exc:
        raise PneumaInputError(f"cannot append to {str(path)!r} ({exc.strerror})") from None


# --- one run per stem ------------------------------------------------------------------------------

_locks: dict[tuple, list] = {}  # (device, inode of the directory, stem) -> [descriptor, depth]: held by this process


def same_file(fd: int, path: Path) -> bool:
    try:
        a, b = os.fstat(fd), os.stat(path, follow_symlinks=False)
    except FileNotFoundError:
        return False
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


def acquire(directory: Path, stem: str) -> int:
    """The descriptor of directory/.<stem>.lock, flock'ed by this process (PneumaInputError if another holds it)."""
    path = directory / f".{stem}.lock"
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | NOFOLLOW, 0o600)
        except OSError as exc:
            raise PneumaInputError(f"cannot lock the results named {stem!r}: {str(path)!r} ({exc.strerror})") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            raise PneumaInputError(
                f"another run is writing the results named {stem!r} in {str(directory)!r} (it "
                f"holds {path.name}); wait for it to end, or give another --out or name"
            ) from None
        if same_file(fd, path):  # else the last holder removed the file between our open and flock: again
            return fd
        os.close(fd)


@contextmanager
def lock_stem(directory: str | os.PathLike, stem: str):
    """Hold the lock of the result files named `stem` in directory for the block (re-entrant in a process);
    the lock file is removed afterwards."""
    directory, stem = Path(directory), check_stem(stem)
    info = os.stat(directory)
    key = (info.st_dev, info.st_ino, stem)
    if key not in _locks:
        _locks[key] = [acquire(directory, stem), 0]
    held = _locks[key]
    held[1] += 1
    try:
        yield
    finally:
        held[1] -= 1
        if held[1] == 0:
            del _locks[key]
            path = directory / f".{stem}.lock"
            if same_file(held[0], path):
                os.unlink(path)
            os.close(held[0])


@contextmanager
def lock_stems(directory: str | os.PathLike, *stems: str):
    """lock_stem for each of stems."""
    with ExitStack() as stack:
        for stem in stems:
            stack.enter_context(lock_stem(directory, stem))
        yield


# --- input files -----------------------------------------------------------------------------------
