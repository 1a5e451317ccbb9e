"""Provenance of a results directory: package versions, and the code that produced each run."""

from __future__ import annotations

import hashlib
import platform
import subprocess
from importlib import metadata
from pathlib import Path
from typing import Any

from skidnav.version import __version__

PACKAGE_DIR = Path(__file__).resolve().parents[1]
"""The installed (or source-tree) ``skidnav`` package folder."""
CODE_KEYS = ("version", "commit", "dirty", "source_sha256")
"""The fields of :func:`code_version`; runs whose fields differ came from different code."""

PACKAGES = (
    "skidnav",
    "numpy",
    "numba",
    "gymnasium",
    "scikit-learn",
    "scipy",
    "pandas",
    "pyarrow",
    "matplotlib",
    "dask",
    "distributed",
    "tqdm",
)


def package_versions() -> dict[str, str]:
    """Installed versions of skidnav's main dependencies (and Python); "absent" when missing."""
    versions = {"python": platform.python_version()}
    for name in PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = "absent"
    if versions["skidnav"] == "absent":
        versions["skidnav"] = f"{__version__} (source tree)"
    return versions


def _resolve_ref(git_dir: Path, ref: str) -> str | None:
    loose = git_dir / ref
    if loose.is_file():
        return loose.read_text().strip()
    packed = git_dir / "packed-refs"
    if packed.is_file():
        for line in packed.read_text().splitlines():
            parts = line.split()
            if len(parts) == 2 and parts[1] == ref:
                return parts[0]
    return None


def _repository(start: Path | None) -> Path | None:
    """The folder holding the ``.git`` directory above ``start`` (default: this package)."""
    folder = (start or Path(__file__)).resolve()
    for candidate in [folder, *folder.parents]:
        if (candidate / ".git" / "HEAD").is_file():
            return candidate
    return None


def git_commit(start: Path | None = None) -> str | None:
    """Commit hash of the source tree holding ``start`` (default: this package), read from the
    ``.git`` directory without running git; None when not in a repository."""
    root = _repository(start)
    if root is None:
        return None
    git_dir = root / ".git"
    try:
        head = (git_dir / "HEAD").read_text().strip()
        if head.startswith("ref:"):
            return _resolve_ref(git_dir, head.split(None, 1)[1])
        return head or None
    except OSError:
        return None


def git_dirty(start: Path | None = None) -> bool | None:
    """True when tracked files of the source tree differ from its commit (as ``git describe
    --dirty``: untracked files do not count); None without a repository or without git."""
    root = _repository(start)
    if root is None:
        return None
    try:
        status = subprocess.run(
            ["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
            timeout=30,
            check=False,
        )
    except (OSError, subprocess.TimeoutExpired):
        return None
    return bool(status.stdout.strip()) if status.returncode == 0 else None


def source_digest(package: Path = PACKAGE_DIR) -> str:
    """SHA-256 over the relative paths and bytes of every ``.py`` file of the package: it tells
    two code versions apart even when both are uncommitted edits of the same commit."""
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        digest.update(path.relative_to(package).as_posix().encode())
        digest.update(b"\0")
        digest.update(path.read_bytes())
    return digest.hexdigest()


def skidnav_version() -> str:
    """The installed skidnav version (the package's ``__version__`` when run from a source tree)."""
    try:
        return metadata.version("skidnav")
    except metadata.PackageNotFoundError:
        return __version__


def code_version() -> dict[str, Any]:
    """The code running now, keys :data:`CODE_KEYS`: skidnav version, git commit (None outside a
    repository), dirty flag (None when unknown) and :func:`source_digest`."""
    return {
        "version": skidnav_version(),
        "commit": git_commit(),
        "dirty": git_dirty(),
        "source_sha256": source_digest(),
    }


def describe_code(code: dict[str, Any]) -> str:
    """One line naming a :func:`code_version`, e.g. ``skidnav 0.1.0, commit 0f79e4a (dirty)``."""
    if not code:
        return "code not recorded"
    commit = code.get("commit")
    text = f"skidnav {code.get('version')}, " + (f"commit {commit[:10]}" if commit else "no commit")
    if code.get("dirty"):
        text += " (dirty)"
    source = code.get("source_sha256")
    return text + (f", source {source[:10]}" if source else "")
