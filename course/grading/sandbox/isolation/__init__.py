"""The isolation layers of a grading child, one per module, and which ones this machine offers.

namespaces
    bubblewrap: mount, network, PID, IPC and UTS namespaces around the fork server.
landlock
    The kernel's allow-list of what each child may read and write; no TCP, no signals out.
seccomp
    The kernel refuses processes, exec, ptrace, sockets, raising limits, new namespaces,
    changes of file metadata.
privileges
    Children started by root switch to ``nobody``.
limits
    Resource limits: address space, CPU time, file size, no core files.
paths
    What a child may read (the Python installation, system libraries, the course's data).
audit
    A Python audit hook for clear error messages (not a security boundary).

:func:`detect` decides, in this order: the file-system layers are bubblewrap's namespaces and
Landlock, both when the machine offers both, otherwise the one it offers; seccomp and the
unprivileged user come on top whenever available. A machine with neither file-system layer
makes ``course grade`` refuse to run unless the instructor passes ``--unsafe-no-isolation``.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass, replace

__all__ = ["Isolation", "IsolationError", "detect"]


class IsolationError(RuntimeError):
    """The machine offers no kernel-enforced file-system isolation (and it was required)."""


@dataclass(frozen=True)
class Isolation:
    """The layers a sandbox uses (decided once per grading run)."""

    landlock: int = 0  # Landlock ABI used in each child (0: none)
    bwrap: str | None = None  # bubblewrap binary (namespaces), or None
    seccomp: bool = False
    drop_to: tuple[int, int] | None = None  # (uid, gid) of nobody when grading as root
    unprivileged: bool | None = None  # known once the fork server has checked
    unsafe: bool = False

    @property
    def filesystem(self) -> bool:
        """Whether the kernel walls off the file system (Landlock or a mount namespace)."""
        return bool(self.landlock or self.bwrap)

    def with_(self, **changes) -> Isolation:
        return replace(self, **changes)

    def layers(self) -> list[str]:
        out = []
        if self.bwrap:
            out.append("namespaces via bubblewrap (mount, network, pid, ipc)")
        if self.landlock:
            what = "files" + (", TCP" if self.landlock >= 4 else "")
            what += ", signals and abstract sockets" if self.landlock >= 6 else ""
            out.append(f"Landlock ABI {self.landlock} ({what})")
        if self.seccomp:
            out.append("seccomp (processes, exec, ptrace, sockets, namespaces, file metadata)")
        if self.drop_to is not None and self.unprivileged:
            out.append(f"unprivileged user (uid {self.drop_to[0]})")
        elif self.drop_to is None and os.geteuid() != 0:
            out.append(f"unprivileged user (uid {os.geteuid()}, the grader's)")
        out.append("resource limits")
        return out

    def describe(self) -> str:
        """One line for the instructor: the active layers, and what is missing."""
        text = "Sandbox: " + "; ".join(self.layers())
        missing = []
        if not self.bwrap:
            missing.append("namespaces (install bubblewrap)")
        if not self.landlock:
            missing.append("Landlock (kernel >= 5.13)")
        if not self.seccomp:
            missing.append("seccomp (install libseccomp2, release 2.5.4 or later)")
        if self.drop_to is not None and self.unprivileged is False:
            missing.append("unprivileged user (the Python installation is not readable by nobody)")
        if missing:
            text += ". Not available: " + ", ".join(missing)
        if not self.filesystem:
            text += ". UNSAFE: student code can read and write the grader's files"
        return text + "."


@functools.lru_cache(maxsize=8)
def detect(*, namespaces: bool = True, landlock: bool = True, unsafe: bool = False) -> Isolation:
    """What this machine offers (``namespaces``/``landlock`` False: do not use that layer).

    Raises :class:`IsolationError` when neither file-system layer is available, unless
    ``unsafe``.
    """
    from course.grading.sandbox.isolation import landlock as _landlock
    from course.grading.sandbox.isolation import namespaces as _namespaces
    from course.grading.sandbox.isolation import privileges, seccomp

    iso = Isolation(
        landlock=_landlock.abi_version() if landlock else 0,
        bwrap=_namespaces.find_bwrap() if namespaces else None,
        seccomp=seccomp.available(),
        drop_to=privileges.target(),
        unsafe=unsafe,
    )
    if not iso.filesystem and not unsafe:
        raise IsolationError(
            "this machine offers no kernel-enforced file-system isolation for student code "
            "(neither Landlock, Linux >= 5.13, nor user namespaces through bubblewrap: "
            "`apt-get install bubblewrap`). Grade elsewhere, or pass --unsafe-no-isolation "
            "if you trust every submission."
        )
    return iso
