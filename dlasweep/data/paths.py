"""Where outputs go: a target checked before any work, one message for each way it cannot be written."""

from __future__ import annotations

import tempfile
from pathlib import Path


def writable(path, folder: bool = False) -> Path:
    """``path`` as a Path when a file can be written there (``folder``: a folder filled or created there).

    Raises
    ------
    OSError
        Naming the path, nothing written: ``IsADirectoryError`` (a folder where a file goes),
        ``NotADirectoryError`` (a file where a folder goes), ``FileNotFoundError`` (its folder is
        missing), ``PermissionError`` (its folder cannot be written).
    """
    path = Path(path)
    if path.exists() and path.is_dir() != folder:
        raise (NotADirectoryError(f"{path}: exists and is not a folder") if folder else
               IsADirectoryError(f"{path}: is a folder"))
    parent = path if folder and path.is_dir() else path.parent
    if not parent.is_dir():
        raise FileNotFoundError(f"{path}: folder {parent} does not exist")
    try:
        # A real attempt: permission bits say nothing for root or a read-only mount.
        with tempfile.TemporaryFile(dir=parent):
            pass
    except OSError:
        raise PermissionError(f"{path}: folder {parent} is not writable") from None
    return path
