"""Reading the link secret on CPython, for both ends of the link: the host
(:mod:`skidnav.realtime.link.auth`) and the reference robot's command line
(docs/protocol.md, "Authentication"). CPython only (it reads files through
:mod:`skidnav.files.user`): a board keeps its secret as its port sees fit.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path

from skidnav.errors import UserError
from skidnav.files.user import read_limited
from skidnav.realtime.reference_robot.authentication import MIN_SECRET_BYTES

SECRET_ENV = "SKIDNAV_LINK_SECRET"
"""The environment variable holding the link secret when no secret file is named."""
MAX_SECRET_BYTES = 4096
"""Longest secret file read [bytes]."""


def require_secret(secret: bytes) -> bytes:
    """``secret`` if it is at least :data:`MIN_SECRET_BYTES` long; ValueError otherwise."""
    if len(secret) < MIN_SECRET_BYTES:
        raise ValueError(
            f"expected a link secret of at least {MIN_SECRET_BYTES} bytes, got {len(secret)}"
        )
    return secret


def load_secret(path: Path | str | None, environ: Mapping[str, str] = os.environ) -> bytes | None:
    """The link secret: the contents of the file ``path`` if given, else the value of
    :data:`SECRET_ENV` if it is set, else None (no authentication); trailing whitespace (a
    newline) is not part of it. UserError, in one line that never shows the secret, if the file
    cannot be read or the secret is shorter than :data:`MIN_SECRET_BYTES` — an empty file, or
    the variable set but empty (``SKIDNAV_LINK_SECRET=$(cat missing.key)``), included: a secret
    asked for is never silently none."""
    if path is not None:
        where = str(path)
        raw = read_limited(path, MAX_SECRET_BYTES, "secret file", UserError)
    elif SECRET_ENV in environ:
        where, raw = SECRET_ENV, environ[SECRET_ENV].encode("utf-8", errors="surrogateescape")
    else:
        return None
    try:
        return require_secret(raw.rstrip())
    except ValueError as error:
        raise UserError(f"{where}: {error}") from None
