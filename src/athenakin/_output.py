"""Writing an output file: one atomic writer, errors that name the path (private).

Every writer of a user's file goes through :class:`AtomicFile` (a temporary file in
the same folder, flushed to the disk with ``fsync`` and renamed into place, so an
interrupted write or a crash leaves the old file or none, never half of one): the
context managers :func:`atomic_write` (write bytes to a file object),
:func:`atomic_path` (a library writes a path by name: pandas, matplotlib) and
:func:`write_text_atomic` (a whole text). The CLI's output manager
(``cli/_output.py``), the MCAP writer (``ros/_write.py``) and the study's Parquet
parts (``synthesis/_study.py``) use the same class. For a library that writes in
place (numpy's ``savez``), :func:`naming_path` wraps its call. An ``OSError`` always
names the path (``/dev/full``: "No space left on device" alone does not), and a path
that exists but is not a regular file (a FIFO, which would block until a reader
comes; a device; a folder) is refused before anything is written.

Permissions: the temporary file is created with mode ``0o666``, so the kernel applies
the process's umask as for any new file (the umask is never read or changed: changing
it is process-wide and races with threads); a file that replaces one gets that file's
permissions. A symbolic link is followed: its target is replaced, the link stays.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import stat
from collections.abc import Iterator
from pathlib import Path
from types import TracebackType
from typing import IO

from ._validation import check_path
from .errors import InvalidInputError

__all__ = ["AtomicFile", "atomic_write", "atomic_path", "write_text_atomic", "naming_path",
           "check_output_path"]


def check_output_path(path: object, name: str = "path") -> Path:
    """Coerce an output path and refuse one that exists and is not a regular file.

    Raises
    ------
    TypeError
        ``path`` is not a str or os.PathLike.
    InvalidInputError
        ``path`` is empty, or names a FIFO, a device, a socket or a folder.
    """
    p = check_path(path, name)
    try:
        mode = os.stat(p).st_mode
    except OSError:
        return p                      # a new file (or an unreadable folder: open says)
    if not stat.S_ISREG(mode):
        kind = ("a FIFO (named pipe)" if stat.S_ISFIFO(mode) else "a folder"
                if stat.S_ISDIR(mode) else "a device" if stat.S_ISCHR(mode)
                or stat.S_ISBLK(mode) else "not a regular file")
        raise InvalidInputError(f"{name}: {os.fspath(p)} is {kind}; expected the path of a "
                                f"regular file to write")
    return p


@contextlib.contextmanager
def naming_path(path: str | os.PathLike[str]) -> Iterator[None]:
    """Re-raise an ``OSError`` of the block as the same class, naming ``path``."""
    try:
        yield
    except OSError as exc:
        if exc.filename is not None:
            raise
        raise type(exc)(exc.errno, exc.strerror or str(exc), os.fspath(path)) from None


#: Attempts at a free temporary name before giving up (each name has 64 random bits).
_TEMP_TRIES = 100


class AtomicFile:
    """One output file written under a temporary name and moved into place on commit.

    The temporary file lies in the destination's folder (or ``folder``), named
    ``.<name>.<random><suffix>``; :meth:`commit` flushes it to the disk (``fsync``),
    gives it the permissions of the file it replaces (else those of a new file, the
    umask applied by the kernel), renames it over the destination and syncs the
    folder; :meth:`discard` removes it. As a context manager it commits on success and
    discards on an exception (Ctrl-C included).

    Parameters
    ----------
    path : str or Path
        The destination. A symbolic link is followed (its target is replaced).
    suffix : str, keyword-only
        Suffix of the temporary name (``".png"``: libraries that choose the format by
        the name write the right one).
    folder : str or Path, keyword-only, optional
        Where to create the temporary file (default: the destination's folder; the
        CLI stages a file there when the destination's folder does not exist yet).

    Attributes
    ----------
    path : Path
        The destination as given.
    temp : Path
        The temporary file.
    fh : binary file
        The temporary file, open for writing (closed by :meth:`close_handle`, when a
        library writes :attr:`temp` by name, and by :meth:`commit` / :meth:`discard`).

    Raises
    ------
    OSError
        The temporary file cannot be created (the error names the destination).
    """

    def __init__(self, path: str | os.PathLike[str], *, suffix: str = "",
                 folder: str | os.PathLike[str] | None = None) -> None:
        self.path = Path(path)
        self._done = False
        real = Path(os.path.realpath(self.path))
        where = Path(folder) if folder is not None else real.parent
        flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0) \
            | getattr(os, "O_BINARY", 0)
        with naming_path(self.path):
            for _ in range(_TEMP_TRIES):
                temp = where / f".{real.name}.{secrets.token_hex(8)}{suffix}"
                try:
                    fd = os.open(temp, flags, 0o666)
                    break
                except FileExistsError:
                    continue
            else:  # pragma: no cover - 100 collisions of 64 random bits
                raise FileExistsError(f"no free temporary name in {where}")
        self.temp = temp
        self.fh: IO[bytes] = os.fdopen(fd, "wb")

    def close_handle(self) -> None:
        """Close :attr:`fh` (a library then writes :attr:`temp` by its name)."""
        if not self.fh.closed:
            self.fh.close()

    def commit(self) -> Path:
        """Flush the file to the disk and move it into place; returns :attr:`path`.

        Raises
        ------
        OSError
            The file cannot be written, synced or renamed (the error names
            :attr:`path`); the temporary file is then removed.
        """
        if self._done:
            return self.path
        try:
            with naming_path(self.path):
                dest = Path(os.path.realpath(self.path))
                if self.fh.closed:   # written by name: sync what the library wrote
                    fd = os.open(self.temp, os.O_RDONLY | getattr(os, "O_BINARY", 0))
                    try:
                        os.fsync(fd)
                    finally:
                        os.close(fd)
                else:
                    self.fh.flush()
                    os.fsync(self.fh.fileno())
                    self.fh.close()
                with contextlib.suppress(FileNotFoundError):
                    os.chmod(self.temp, stat.S_IMODE(os.stat(dest).st_mode))
                dest.parent.mkdir(parents=True, exist_ok=True)
                os.replace(self.temp, dest)
                self._done = True
                _sync_folder(dest.parent)
        except BaseException:
            self.discard()
            raise
        return self.path

    def discard(self) -> None:
        """Remove the temporary file (nothing is written); a no-op after :meth:`commit`."""
        if not self.fh.closed:
            with contextlib.suppress(OSError):
                self.fh.close()
        if not self._done:
            self._done = True
            with contextlib.suppress(OSError):
                os.unlink(self.temp)

    def __enter__(self) -> AtomicFile:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        if exc_type is None:
            self.commit()
        else:
            self.discard()


def _sync_folder(folder: Path) -> None:
    """``fsync`` a folder so that a rename in it survives a crash (POSIX; else nothing)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:   # some file systems refuse fsync on a folder: the rename stands
        pass
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_write(path: str | os.PathLike[str]) -> Iterator[IO[bytes]]:
    """A binary file object whose content replaces ``path`` when the block succeeds.

    Refuses a path that names something other than a regular file
    (:func:`check_output_path`); see :class:`AtomicFile`.

    Examples
    --------
    ::

        with atomic_write("out.bin") as fh:
            fh.write(data)
    """
    with AtomicFile(check_output_path(path)) as f:
        with naming_path(path):
            yield f.fh


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], *, suffix: str | None = None) -> Iterator[Path]:
    """A temporary path, written by name, that replaces ``path`` when the block succeeds.

    ``suffix``: of the temporary name (default: that of ``path``). See
    :class:`AtomicFile`.

    Examples
    --------
    ::

        with atomic_path(out / "part-000000.parquet") as tmp:
            df.to_parquet(tmp)
    """
    p = check_output_path(path)
    with AtomicFile(p, suffix=p.suffix if suffix is None else suffix) as f:
        f.close_handle()
        with naming_path(p):
            yield f.temp


def write_text_atomic(path: str | Path, text: str | bytes) -> None:
    """Write a file through a temporary file in the same folder and a rename.

    The file gets the permissions a new file would get (``0o666 & ~umask``) or,
    when it replaces a file, that file's permissions; a symbolic link is
    followed (its target is replaced, the link stays a link).

    Raises
    ------
    TypeError, InvalidInputError
        ``path`` is not a path, or names something other than a regular file.
    OSError
        The file cannot be written (the error names ``path``).
    """
    with atomic_write(path) as fh:
        fh.write(text.encode("utf-8") if isinstance(text, str) else text)
