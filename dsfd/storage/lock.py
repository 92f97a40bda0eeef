"""One controller per state directory: an exclusive POSIX record lock on ``dsfd.lock``.

``dsfd run`` takes the lock before it opens the database or any device, and keeps the file
descriptor open for its whole life; the kernel drops the lock when the process ends, however
it ends (SIGKILL, a crash), so a stale lock file never blocks a restart. The holder writes
its PID into the file for people (``cat dsfd.lock``).

Readers (``dsfd status``, ``dsfd report``) never take the lock: :func:`lock_holder` asks the
kernel who holds it (``F_GETLK`` on a read-only descriptor), so a status query can neither
block a starting daemon nor be mistaken for one.

POSIX (``fcntl``) locks belong to the process and are released when *any* descriptor of the
file is closed by it, so the daemon must never open ``dsfd.lock`` a second time.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import struct
from pathlib import Path

__all__ = ["LOCK_NAME", "StateDirBusyError", "StateLock", "lock_holder"]

LOCK_NAME = "dsfd.lock"
# struct flock on Linux: short l_type, short l_whence, off_t l_start, off_t l_len, pid_t
# l_pid (native alignment; 32 bytes on 64-bit and on 32-bit ARM with a 64-bit off_t).
_FLOCK = "hhqqi4x"


class StateDirBusyError(RuntimeError):
    """Another process holds the state directory's lock."""

    def __init__(self, path: Path, pid: int | None) -> None:
        self.path = path
        self.pid = pid
        who = f"PID {pid}" if pid else "another process"
        super().__init__(f"state directory {path.parent} is in use by {who} (lock "
                         f"{path}): another dsfd run controls this panel")


class StateLock:
    """The held lock of one state directory (release it with :meth:`release`)."""

    def __init__(self, path: Path, fd: int) -> None:
        self.path = path
        self._fd: int | None = fd

    @classmethod
    def acquire(cls, state_dir: Path) -> StateLock:
        """Take the lock without waiting; :class:`StateDirBusyError` names the holder's PID."""
        state_dir.mkdir(parents=True, exist_ok=True)
        path = state_dir / LOCK_NAME
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
        try:
            fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            raise StateDirBusyError(path, lock_holder(state_dir)) from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        return cls(path, fd)

    def release(self) -> None:
        """Drop the lock (the file stays; its PID line is stale from here on)."""
        if self._fd is not None:
            with contextlib.suppress(OSError):
                os.close(self._fd)
            self._fd = None


def lock_holder(state_dir: Path) -> int | None:
    """PID of the process holding ``state_dir``'s lock, None if nobody holds it.

    Raises ``PermissionError`` if the lock file cannot be opened for reading (see
    docs/operating.md on the permissions an operator needs)."""
    path = state_dir / LOCK_NAME
    try:
        fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC)
    except FileNotFoundError:
        return None
    try:
        query = struct.pack(_FLOCK, fcntl.F_WRLCK, os.SEEK_SET, 0, 0, 0)
        answer = fcntl.fcntl(fd, fcntl.F_GETLK, query)
        l_type, *_, pid = struct.unpack(_FLOCK, answer)
        if l_type == fcntl.F_UNLCK:
            return None
        # A holder in another PID namespace is reported as 0: its own line in the file.
        return int(pid) or _pid_in_file(fd) or 0
    finally:
        os.close(fd)


def _pid_in_file(fd: int) -> int | None:
    try:
        text = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
    except OSError:
        return None
    return int(text) if text.isdigit() else None
