"""Files and permissions: what the daemon creates, and what it refuses to touch (issue 13).

Everything the daemon creates is private to the user it runs as, unless the configuration
names a group:

* the runtime directory (:func:`omsd.config.runtime_directory`: ``$RUNTIME_DIRECTORY``,
  ``$XDG_RUNTIME_DIR/omsd`` or ``/tmp/omsd-<uid>``), where the default pty links and the
  control socket go, is created mode 0700;
* the traffic log and the state file are created 0600, or 0640 in the group of ``[log] group``
  / ``[state] group`` (:func:`file_mode`, :func:`open_log`);
* the control socket is 0600 (:mod:`omsd.control.server`).

And it leaves alone what is not its own. Before anything is served (:func:`preflight`, called
by :meth:`omsd.daemon.Daemon.start`), it refuses, with one line and exit status 2:

* a runtime directory that is a symlink, is not a directory, is owned by another user, or that
  its group or anyone can write, as OpenSSH, tmux and systemd refuse theirs: whoever could
  change it could replace a pty link or the control socket (:func:`check_runtime_directory`);
* anything at a pty link's path that is not omsd's own kind of link, a symlink to a pty device
  (``/dev/pts/N``; ``/dev/ttysNNN`` on macOS and the BSDs) left by a daemon that died: a
  regular file, a directory, a socket, a symlink anywhere else (:func:`pty_link_refusal`);
* anything at the control socket's path that is not a socket (:func:`socket_refusal`).

Apart from those checks nothing here changes a file that omsd did not create: an existing log
file keeps its owner, group and mode.
"""

from __future__ import annotations

import contextlib
import grp
import os
import re
import stat
from collections.abc import Iterable
from pathlib import Path

DIRECTORY_MODE = 0o700
FILE_MODE = 0o600
GROUP_FILE_MODE = 0o640

_PTY_DEVICE = re.compile(r"/dev/pts/[0-9]+|/dev/ttys[0-9]+")
"""What :func:`os.ttyname` gives for a pty's slave: what omsd's own pty links point at."""


class Refused(Exception):
    """A path omsd will not use or replace. ``str()`` is one line: the path, what is there and
    what to do."""


def file_mode(group: str | None) -> int:
    """The mode of a file the daemon creates: 0600, or 0640 with a group."""
    return FILE_MODE if group is None else GROUP_FILE_MODE


def group_id(group: str | None) -> int:
    """The gid of ``group`` (``-1``, "leave it", for none); ``OSError`` for an unknown name."""
    if group is None:
        return -1
    try:
        return grp.getgrnam(group).gr_gid
    except KeyError:
        raise OSError(f"no group {group!r}") from None


def is_pty_device(target: str) -> bool:
    """Whether a symlink's target is a pty's slave device: the kind of link omsd makes."""
    return _PTY_DEVICE.fullmatch(target) is not None


def _what(mode: int) -> str:
    if stat.S_ISREG(mode):
        return "a regular file"
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISSOCK(mode):
        return "a socket"
    if stat.S_ISFIFO(mode):
        return "a named pipe"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    return "something else"


# -- the runtime directory ----------------------------------------------------------------------


def check_runtime_directory(path: Path) -> None:
    """Create ``path`` mode 0700 if it is missing (its parents as usual), then make sure that
    nobody but this user can change it; :class:`Refused` otherwise."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        path.parent.mkdir(parents=True, exist_ok=True)
        try:
            os.mkdir(path, DIRECTORY_MODE)
        except FileExistsError:
            pass  # made meanwhile: checked below like any other
        else:
            os.chmod(path, DIRECTORY_MODE)  # exactly 0700, whatever the umask
        st = os.lstat(path)
    problem = None
    if stat.S_ISLNK(st.st_mode):
        problem = f"is a symlink (to {os.readlink(path)})"
    elif not stat.S_ISDIR(st.st_mode):
        problem = f"is {_what(st.st_mode)}, not a directory"
    elif st.st_uid != os.geteuid():
        problem = f"is owned by uid {st.st_uid}, not by this user (uid {os.geteuid()})"
    elif st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        problem = f"is writable by its group or by anyone (mode {stat.S_IMODE(st.st_mode):04o})"
    if problem is not None:
        raise Refused(
            f"runtime directory {path} {problem}: another user could replace the pty links and"
            " the control socket in it; refusing to use it (remove it, or give --pty and"
            " --control paths elsewhere)"
        )


# -- what is at a path omsd is to create --------------------------------------------------------


def pty_link_refusal(link: Path) -> str | None:
    """Why the pty link ``link`` must not be created (one line), or ``None``: nothing there,
    or a symlink to a pty device (a link omsd left, replaced)."""
    try:
        st = os.lstat(link)
    except FileNotFoundError:
        return None
    if stat.S_ISLNK(st.st_mode):
        target = os.readlink(link)
        if is_pty_device(target):
            return None
        return (
            f"{link} is a symlink to {target}, not to a pty; refusing to replace it"
            " (remove it, or choose another path)"
        )
    return (
        f"{link} is {_what(st.st_mode)}, not a pty link; refusing to replace it"
        " (remove it, or choose another path)"
    )


def socket_refusal(path: Path) -> str | None:
    """Why the control socket ``path`` must not be created (one line), or ``None``: nothing
    there, or a socket (a live one is found and reported by the control server; a stale one
    is replaced)."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return None
    if stat.S_ISSOCK(st.st_mode):
        return None
    what = f"a symlink to {os.readlink(path)}" if stat.S_ISLNK(st.st_mode) else _what(st.st_mode)
    return (
        f"control socket {path} is {what}, not a socket; refusing to replace it"
        " (remove it, or give another --control path)"
    )


def preflight(runtime: Path, ptys: Iterable[tuple[str, Path]], control: Path | None) -> None:
    """The checks made before the daemon creates anything (:class:`Refused`): the runtime
    directory, if anything goes in it (then it is created), every pty link's path (``ptys``:
    board name and link) and the control socket's."""
    places = [link for _, link in ptys] + ([] if control is None else [control])
    if any(p.is_relative_to(runtime) for p in places):
        check_runtime_directory(runtime)
    for board, link in ptys:
        problem = pty_link_refusal(link)
        if problem is not None:
            raise Refused(f"{board}: {problem}")
    if control is not None:
        problem = socket_refusal(control)
        if problem is not None:
            raise Refused(problem)


# -- files the daemon creates -------------------------------------------------------------------


def open_log(path: Path, group: str | None = None) -> int:
    """Open ``path`` for appending (``O_APPEND``); a file created here is 0600, or 0640 and in
    ``group``. An existing file is used as it is. ``OSError`` if it cannot be opened (a file
    created here and then not given to its group is removed again)."""
    flags = os.O_WRONLY | os.O_APPEND | os.O_CLOEXEC
    for _ in range(8):  # a file that comes and goes between the two opens
        try:
            fd = os.open(path, flags | os.O_CREAT | os.O_EXCL, FILE_MODE)
        except FileExistsError:
            try:
                return os.open(path, flags)
            except FileNotFoundError:
                continue
        try:
            if group is not None:
                os.fchown(fd, -1, group_id(group))
            os.fchmod(fd, file_mode(group))
        except BaseException:
            os.close(fd)
            with contextlib.suppress(OSError):
                os.unlink(path)
            raise
        return fd
    return os.open(path, flags | os.O_CREAT, FILE_MODE)


__all__ = [
    "DIRECTORY_MODE",
    "FILE_MODE",
    "GROUP_FILE_MODE",
    "Refused",
    "check_runtime_directory",
    "file_mode",
    "group_id",
    "is_pty_device",
    "open_log",
    "preflight",
    "pty_link_refusal",
    "socket_refusal",
]
