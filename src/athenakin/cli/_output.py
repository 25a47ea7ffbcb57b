"""The files one CLI command writes: checked up front, written together at the end (private).

Every command that writes files declares them to an :class:`Outputs` before it
computes anything, renders each one into a temporary file in its destination
folder, and only when everything has succeeded moves them all into place (each
one an :class:`athenakin._output.AtomicFile`, the package's one atomic writer:
``fsync``, then a rename). A failure anywhere leaves no output and no temporary
file behind. The rules:

* an output never replaces one of the command's inputs (``plan wp.csv -o wp.csv``);
* an output never replaces an existing file unless ``--force`` is given;
* a written file gets the permissions a new file would get (``0o666 & ~umask``),
  or, when it replaces a file, that file's permissions;
* replacing a symbolic link writes the file it points to; the link stays a link;
* an output is never a device, FIFO or socket (``-o /dev/null --force`` would replace
  ``/dev/null`` itself).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path
from types import TracebackType

from .._output import AtomicFile

__all__ = ["Outputs", "outputs", "add_force_option", "input_paths", "INPUT_ATTRIBUTES"]

#: Attributes of the parsed arguments that name input files.
INPUT_ATTRIBUTES = ("path", "design", "rcm_file", "q_file", "measurements")


def add_force_option(p: argparse.ArgumentParser) -> None:
    """``--force``: allow replacing existing files (never the command's own inputs)."""
    p.add_argument("--force", action="store_true",
                   help="replace existing output files (never one of the inputs)")


def input_paths(args: argparse.Namespace) -> list[Path]:
    """The input files named by the parsed arguments (see :data:`INPUT_ATTRIBUTES`)."""
    return [Path(v) for a in INPUT_ATTRIBUTES if isinstance(v := getattr(args, a, None),
                                                             (str, Path))]


def _same_file(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.realpath(a) == os.path.realpath(b)


class Outputs:
    """The output files of one command run (module docstring).

    Parameters
    ----------
    option : str
        How the command names its outputs in messages (``"-o"``).
    force : bool
        Allow replacing existing files.
    inputs : list of Path
        Files the command reads; no output may replace one of them.

    Examples
    --------
    ::

        with Outputs(force=args.force, inputs=input_paths(args)) as outs:
            out = outs.add(args.output)          # checks now, before any work
            outs.write(out, text)                # or: save(outs.temp(out))
            written = outs.commit()              # all files move into place
    """

    def __init__(self, *, force: bool = False, inputs: list[Path] | None = None,
                 option: str = "-o") -> None:
        self.force = bool(force)
        self.option = option
        self.inputs = [Path(p) for p in inputs or []]
        self._targets: list[Path] = []
        self._temps: dict[Path, AtomicFile] = {}
        self._staging: Path | None = None
        self._committed = False

    # ---------------------------------------------------------------------- declare
    def add(self, path: str | Path, *, option: str | None = None,
            create_folder: bool = False) -> Path:
        """Declare an output file; raise now if it may not be written.

        Raises ``ValueError`` (an input, a folder, a missing folder),
        ``FileExistsError`` (exists, no ``--force``) or ``PermissionError``.

        Parameters
        ----------
        path : str or Path
            The file to write.
        option : str, optional
            The option that named it, for messages (default: the ``option`` of the
            constructor).
        create_folder : bool
            Create the file's folder at commit if it does not exist (else that is
            an error now).

        Returns
        -------
        Path
        """
        path = Path(path)
        opt = option or self.option
        for src in self.inputs:
            if _same_file(path, src):
                raise ValueError(f"{opt}: {str(path)!r} is an input of this command; "
                                 f"writing it would destroy the input (choose another name)")
        if any(_same_file(path, t) for t in self._targets):
            raise ValueError(f"{opt}: {str(path)!r} is written twice by this command")
        if path.is_dir():
            raise ValueError(f"{opt}: {str(path)!r} is a folder, expected a file name")
        if os.path.exists(path) and not stat.S_ISREG(os.stat(path).st_mode):
            # /dev/null, a FIFO, a socket: os.replace would put a file in its place (as root,
            # /dev/null itself)
            raise ValueError(f"{opt}: {str(path)!r} is not a regular file (a device, FIFO or "
                             f"socket); expected a file name")
        if os.path.lexists(path) and not self.force:
            raise FileExistsError(f"{opt}: {str(path)!r} exists; use --force to replace it")
        parent = _existing_ancestor(path.parent) if create_folder else path.parent
        if parent is None or not parent.is_dir():
            raise ValueError(f"{opt}: folder {str(path.parent)!r} does not exist")
        if not os.access(parent, os.W_OK | os.X_OK):
            raise PermissionError(f"{opt}: folder {str(parent)!r} is not writable")
        self._targets.append(path)
        return path

    def add_in_folder(self, folder: str | Path, name: str, *, option: str) -> Path:
        """Declare ``folder / name``; the folder may not exist yet (it is created at commit)."""
        folder = Path(folder)
        if folder.exists() and not folder.is_dir():
            raise ValueError(f"{option}: {str(folder)!r} exists and is not a folder")
        return self.add(folder / name, option=option, create_folder=True)

    def drop(self, path: Path) -> None:
        """Undeclare an output that the command turned out not to write (nothing to check)."""
        path = Path(path)
        if path in self._targets:
            self._targets.remove(path)
        tmp = self._temps.pop(path, None)
        if tmp is not None:
            tmp.discard()

    # ---------------------------------------------------------------------- render
    def temp(self, path: Path) -> Path:
        """A fresh temporary file for ``path`` (same folder and suffix) to render into.

        The suffix is kept so that writers that choose the format by the file name
        (matplotlib, imageio) write the right one.
        """
        path = Path(path)
        if path not in self._targets:
            raise ValueError(f"{str(path)!r} was not declared with Outputs.add")
        old = self._temps.pop(path, None)
        if old is not None:
            old.discard()
        folder = None if path.parent.is_dir() else self._staging_dir(path)
        f = AtomicFile(path, suffix=path.suffix, folder=folder)
        f.close_handle()
        self._temps[path] = f
        return f.temp

    def write(self, path: Path, data: str | bytes) -> None:
        """Render ``data`` (text is UTF-8 encoded) as the future content of ``path``."""
        tmp = self.temp(path)
        tmp.write_bytes(data.encode("utf-8") if isinstance(data, str) else data)

    def _staging_dir(self, path: Path) -> Path:
        if self._staging is None:
            base = _existing_ancestor(path.parent)
            assert base is not None
            self._staging = Path(tempfile.mkdtemp(prefix=".athenakin-", dir=base))
        return self._staging

    # ---------------------------------------------------------------------- finish
    def commit(self) -> list[Path]:
        """Move every rendered file into place; returns the paths, in declaration order.

        Raises
        ------
        ValueError
            A declared output was never rendered (a bug of the command).
        """
        missing = [str(p) for p in self._targets if p not in self._temps]
        if missing:
            raise ValueError(f"outputs not rendered: {missing}")
        for path in self._targets:
            dest = Path(os.path.realpath(path))  # through a symlink: write its target
            if os.path.lexists(dest) and not self.force:
                raise FileExistsError(f"{self.option}: {str(path)!r} appeared while the "
                                      f"command ran; use --force to replace it")
            self._temps[path].commit()           # fsync, the old file's mode, rename
            del self._temps[path]
        self._committed = True
        self.discard()
        return list(self._targets)

    def discard(self) -> None:
        """Remove every temporary file (nothing is written)."""
        for tmp in self._temps.values():
            tmp.discard()
        self._temps.clear()
        if self._staging is not None:
            shutil.rmtree(self._staging, ignore_errors=True)
            self._staging = None

    def __enter__(self) -> Outputs:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.discard()


def _existing_ancestor(folder: Path) -> Path | None:
    """``folder`` if it exists, else its nearest existing ancestor (None if none)."""
    f = Path(folder) if str(folder) else Path(".")
    for cand in (f, *f.parents):
        if cand.exists():
            return cand
    return None


@contextlib.contextmanager
def outputs(args: argparse.Namespace, *, option: str = "-o") -> Iterator[Outputs]:
    """:class:`Outputs` for the parsed arguments (``--force`` and the input files)."""
    with Outputs(force=bool(getattr(args, "force", False)), inputs=input_paths(args),
                 option=option) as outs:
        yield outs
