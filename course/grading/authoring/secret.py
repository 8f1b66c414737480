"""The instructor's secret: the key from which a graded class's personal data are drawn.

Without a secret (a self-learner, or the course as published), a student's data set is drawn
from ``sha256(assignment, key, student ID)`` by the public generators in ``data.py``: anyone
with the ID can rebuild it, including the truth behind it (which fault, which blunder).

With a secret, the seed is ``HMAC-SHA256(secret, assignment, key, student ID)``. Only the
instructor can run the generators; students receive the generated data (``course export
--roster``), never the generators, and the grader recomputes the same data from the same
secret. Nothing in the student distribution determines the seed.

The secret lives in a key file OUTSIDE the course folder, made once per class with
``course secret new FILE``, and is named by ``--secret FILE`` or the environment variable
``COURSE_SECRET_FILE``. A key file holds one line ``course-secret-v1:<64 hex digits>``
(lines starting with ``#`` are comments).
"""

from __future__ import annotations

import hashlib
import hmac
import os
import secrets
import stat
from dataclasses import dataclass
from pathlib import Path

__all__ = [
    "KEY_FILE_PREFIX",
    "SECRET_ENV",
    "Secret",
    "SecretError",
    "load_secret",
    "new_secret",
    "public_key_id",
]

#: The environment variable naming the key file (``--secret FILE`` wins over it).
SECRET_ENV = "COURSE_SECRET_FILE"

#: How a key file's key line starts (what a scan for stray key files looks for).
KEY_FILE_PREFIX = "course-secret-v1:"
_PREFIX = KEY_FILE_PREFIX
_KEY_BYTES = 32


class SecretError(ValueError):
    """The secret is missing, unreadable or malformed (the message says which and what to do)."""


@dataclass(frozen=True)
class Secret:
    """An instructor's key (never printed: its repr shows only the public key id)."""

    key: bytes
    source: str = ""

    def __repr__(self) -> str:
        return f"<course secret {self.key_id} from {self.source or 'memory'}>"

    @property
    def key_id(self) -> str:
        """A public fingerprint (12 hex digits) that names the key without revealing it.

        Written into personal-data files and submissions, so the grader can tell when it runs
        with a different key than the one the class's data were issued with.
        """
        return hmac.new(self.key, b"course key id", hashlib.sha256).hexdigest()[:12]

    def seed(self, assignment: str, key: str, student_id: str) -> int:
        """The 256-bit seed of one student's data set ``key`` of ``assignment``."""
        message = f"course-data-v1\0{assignment}\0{key}\0{str(student_id).strip()}".encode()
        return int.from_bytes(hmac.new(self.key, message, hashlib.sha256).digest(), "little")

    def derive(self, label: str) -> bytes:
        """A public value derived from the key for ``label`` (e.g. the salt of a data file)."""
        return hmac.new(self.key, f"course-derive\0{label}".encode(), hashlib.sha256).digest()


#: The key id written where no secret is used (the public generators).
public_key_id = "public"


def new_secret(path: str | Path) -> Secret:
    """Write a new random key to ``path`` (mode 0600); refuse to overwrite an existing file."""
    path = Path(path).expanduser()
    if path.exists():
        raise SecretError(
            f"{path} already exists; a class keeps its key for the whole term "
            "(delete the file yourself if you really want a new one)"
        )
    if not path.parent.is_dir():
        raise SecretError(f"cannot write {path}: the folder {path.parent} does not exist")
    key = secrets.token_bytes(_KEY_BYTES)
    text = (
        "# Instructor secret of a course class: keep it OUT of the course folder and out of\n"
        "# version control. Whoever has it can rebuild every student's personal data.\n"
        f"{_PREFIX}{key.hex()}\n"
    )
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, "w", encoding="ascii") as f:
        f.write(text)
    return Secret(key, str(path))


def load_secret(path: str | Path | None = None, env=None) -> Secret | None:
    """The secret from ``path``, else from ``$COURSE_SECRET_FILE``; None when neither is set.

    Raises :class:`SecretError` with one clear message when the file named is missing,
    unreadable or not a key file (a typo must never silently fall back to public data).
    """
    env = os.environ if env is None else env
    where = "--secret"
    if path is None or str(path) == "":
        path = env.get(SECRET_ENV) or None
        where = f"${SECRET_ENV}"
        if path is None:
            return None
    path = Path(path).expanduser()
    try:
        info = path.stat()
    except FileNotFoundError:
        raise SecretError(
            f"the secret key file {path} (from {where}) does not exist; create one with "
            f"`course secret new {path}`"
        ) from None
    except OSError as exc:
        raise SecretError(f"cannot read the secret key file {path}: {exc.strerror}") from None
    if not stat.S_ISREG(info.st_mode):
        raise SecretError(f"the secret {path} (from {where}) is not a file")
    try:
        text = path.read_text(encoding="ascii")
    except PermissionError:
        raise SecretError(
            f"cannot read the secret key file {path}: permission denied "
            "(run as the user who created it)"
        ) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SecretError(f"cannot read the secret key file {path}: {exc}") from None
    lines = [line.strip() for line in text.splitlines()]
    keys = [line for line in lines if line and not line.startswith("#")]
    if len(keys) != 1 or not keys[0].startswith(_PREFIX):
        raise SecretError(
            f"{path} is not a course key file (expected one line '{_PREFIX}<64 hex digits>'; "
            "make one with `course secret new FILE`)"
        )
    try:
        key = bytes.fromhex(keys[0][len(_PREFIX) :])
    except ValueError:
        raise SecretError(f"{path}: the key is not hexadecimal") from None
    if len(key) < 16:
        raise SecretError(f"{path}: the key is too short ({len(key) * 8} bits; at least 128)")
    return Secret(key, str(path))
