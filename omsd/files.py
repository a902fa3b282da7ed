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
* anything at the control socket's path that is not a socket (:func:`socket_refusal`);
* a pty link, the control socket and the state file at one path (:func:`shared_path`), or the
  traffic log at one of theirs (:func:`log_shared_path`).

Nor does it start where it cannot work (:meth:`omsd.daemon.Daemon.start`, also exit status 2,
issue 14): a pty link outside the runtime directory whose directory is missing
(:func:`missing_directory`: omsd makes no directory there), a state file that could not be read
or saved (:func:`state_file_problem`; its missing directories are made at the first save).

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


def preflight(
    runtime: Path,
    ptys: Iterable[tuple[str, Path]],
    control: Path | None,
    state: Path | None = None,
) -> None:
    """The checks made before the daemon creates anything (:class:`Refused`): the runtime
    directory, if anything goes in it (then it is created), every pty link's path (``ptys``:
    board name and link), the control socket's, and that no two of them and the state file
    are one path (:func:`shared_path`)."""
    ptys = list(ptys)
    problem = shared_path(ptys, control, state)
    if problem is not None:
        raise Refused(problem)
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


def shared_path(
    ptys: Iterable[tuple[str, Path]], control: Path | None, state: Path | None
) -> str | None:
    """Why two of the pty links, the control socket and the state file cannot be: they are
    one path, and each would be made over the other (the flash saved over the socket, then
    removed with it at the stop), or ``None``. Pty links among themselves are the
    configuration's to refuse (two boards' endpoints)."""
    same = "give each a path of its own"
    where = {_place(link): board for board, link in ptys}
    if control is not None and (board := where.get(_place(control))) is not None:
        return f"{board}: pty link {control} is the control socket's path too: {same}"
    if state is None:
        return None
    if control is not None and _place(state) == _place(control):
        return f"state file {state} is the control socket's path too: {same}"
    if (board := where.get(_place(state))) is not None:
        return f"state file {state} is {board}'s pty link too: {same}"
    return None


def log_shared_path(
    log: Path, ptys: Iterable[tuple[str, Path]], control: Path | None, state: Path | None
) -> str | None:
    """Why the traffic log cannot be at ``log``: it is a pty link's path, the control socket's
    or the state file's (the state file read the log as a corrupt flash and its first save
    renamed the log away; the socket or the link refused the file the log had just made), or
    ``None``. Asked before the log is opened (created)."""
    same = "give each a path of its own"
    place = _place(log)
    if state is not None and _place(state) == place:
        return f"traffic log {log} is the state file's path too: {same}"
    if control is not None and _place(control) == place:
        return f"traffic log {log} is the control socket's path too: {same}"
    for board, link in ptys:
        if _place(link) == place:
            return f"traffic log {log} is {board}'s pty link too: {same}"
    return None


def _place(path: Path) -> str:
    """The directory entry ``path`` names: its directory's real path (symlinks and ``..``
    followed, so ``alias/x`` and ``dir/x`` with ``alias`` a link to ``dir`` are one) and its
    name. The name itself is not followed: a pty link is a symlink, to its device."""
    directory, name = os.path.split(os.fspath(path))
    return os.path.join(os.path.realpath(directory or "."), name)


def missing_directory(directory: Path) -> str | None:
    """Why nothing can be created in ``directory`` (it is missing, or not a directory), or
    ``None``. omsd makes no directory but its runtime directory (and the control socket's):
    a path that names a directory that does not exist is a typing mistake more often than not."""
    try:
        st = os.stat(directory)
    except FileNotFoundError:
        return f"no directory {directory}"
    except OSError as exc:
        return f"cannot use directory {directory}: {exc.strerror or exc}"
    if not stat.S_ISDIR(st.st_mode):
        return f"{directory} is {_what(st.st_mode)}, not a directory"
    return None


def state_file_problem(path: Path) -> str | None:
    """Why the state file at ``path`` could not be read or saved, or ``None``: the path is
    something other than a regular file, or a file that cannot be read; or its directory could
    not be written (a save writes a temporary file there and renames it; directories that do not
    exist yet are made at the first save, so the nearest one that exists must be a writable
    directory). A file that does not exist yet is fine (the first save creates it)."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        pass
    except OSError as exc:  # a regular file where a directory should be (ENOTDIR), ...
        return _blocked(path.parent) or exc.strerror or str(exc)
    else:
        if not stat.S_ISREG(st.st_mode):
            return f"it is {_what(st.st_mode)}, not a file"
        if not os.access(path, os.R_OK):
            return "cannot read it: permission denied"
    return _blocked(path.parent)


def _blocked(directory: Path) -> str | None:
    """Why nothing can be saved in ``directory``, made if need be, or ``None``."""
    existing = directory
    while not os.path.lexists(existing) and existing != existing.parent:
        existing = existing.parent
    try:
        st = os.stat(existing)
    except OSError as exc:
        return f"cannot use directory {existing}: {exc.strerror or exc}"
    if not stat.S_ISDIR(st.st_mode):
        return f"{existing} is {_what(st.st_mode)}, not a directory"
    if not os.access(existing, os.W_OK | os.X_OK):
        return f"directory {existing} is not writable (a save writes a new file there)"
    return None


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
    "log_shared_path",
    "missing_directory",
    "open_log",
    "preflight",
    "pty_link_refusal",
    "shared_path",
    "socket_refusal",
    "state_file_problem",
]
