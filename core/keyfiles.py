"""Key files and the folders that hold them, checked as OpenSSH's ``StrictModes`` checks them.

Whoever can write a key folder can plant a key in it (a car the service admits, a vehicle the car
trusts), and a symbolic link leads keys where its maker chose. So, before a key in it is read or one
is written: a folder that is a link, is not the user's own, or that others may write is refused, and
so is a key file that is a link, is not the user's own, that others may write or (a secret, named
``*secret*`` or ``*signing_key``) read; each in one line naming the fix. Folders are made with mode
0700 whatever the umask, files created exclusively with their final mode (never wider, not for a
moment). The link's CurveZMQ keys (``racf serve keys``) and the fleet's V2V keys use them.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from racf.errors import UserError

__all__ = ["check_folder", "check_file", "make_folder", "write_new", "FOLDER_MODE"]

#: What a key folder's mode is: its owner's alone.
FOLDER_MODE = 0o700


def _owner_fix(path: Path) -> str:
    return f"`chown {os.getuid()} {path}` (or remove it)"


def check_folder(path: Path) -> None:
    """Refuses (one line naming the fix) a key folder that is a symbolic link, is not a folder of this
    user's, or that others may write; a missing one is left to the caller."""
    path = Path(path)
    if path.is_symlink():
        raise UserError(f"key folder {path} is a symbolic link: keys are read and written only in a real folder; "
                        f"replace the link with the folder it points to")
    if not path.exists():
        return
    info = path.stat()
    if not stat.S_ISDIR(info.st_mode):
        raise UserError(f"key folder {path} is not a folder")
    if info.st_uid != os.getuid():
        raise UserError(f"key folder {path} belongs to user {info.st_uid}, not to this one: {_owner_fix(path)}")
    if info.st_mode & 0o022:
        raise UserError(f"key folder {path} may be written by others (mode {stat.S_IMODE(info.st_mode):o}): whoever "
                        f"can write it can plant a key; `chmod 700 {path}`")


def check_file(path: Path) -> None:
    """Refuses a key file that is a symbolic link, not this user's, writable by others, or (a secret)
    readable by them."""
    path = Path(path)
    if path.is_symlink():
        raise UserError(f"key file {path} is a symbolic link: replace it with the file itself")
    info = path.stat()
    if info.st_uid != os.getuid():
        raise UserError(f"key file {path} belongs to user {info.st_uid}, not to this one: {_owner_fix(path)}")
    secret = "secret" in path.name or path.name.endswith(".signing_key")
    if info.st_mode & (0o077 if secret else 0o022):
        raise UserError(f"key file {path} may be {'read or written' if secret else 'written'} by others (mode "
                        f"{stat.S_IMODE(info.st_mode):o}); `chmod {'600' if secret else '644'} {path}`")


def make_folder(path: Path) -> None:
    """``path`` and every missing folder above it, each created with mode 0700 whatever the umask."""
    missing = []
    while not os.path.lexists(path):
        missing.append(path)
        path = path.parent
    for folder in reversed(missing):
        os.mkdir(folder, FOLDER_MODE)
        os.chmod(folder, FOLDER_MODE)  # mkdir's mode is cut by the umask: never wider, here never narrower


def write_new(path: Path, data: bytes, mode: int) -> None:
    """Creates ``path`` with ``mode`` (opened with it, exclusively: the file never exists with another)
    and writes ``data``."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, mode)
    try:
        os.fchmod(fd, mode)  # os.open's mode is cut by the umask: the file may be narrower, never wider
        os.write(fd, data)
    finally:
        os.close(fd)
