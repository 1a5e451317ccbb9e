"""Provenance of a results directory: package versions and the source commit."""

from __future__ import annotations

import platform
from importlib import metadata
from pathlib import Path

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
        import skidnav

        versions["skidnav"] = f"{skidnav.__version__} (source tree)"
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


def git_commit(start: Path | None = None) -> str | None:
    """Commit hash of the source tree holding ``start`` (default: this package), read from the
    ``.git`` directory without running git; None when not in a repository."""
    folder = (start or Path(__file__)).resolve()
    for candidate in [folder, *folder.parents]:
        git_dir = candidate / ".git"
        if (git_dir / "HEAD").is_file():
            try:
                head = (git_dir / "HEAD").read_text().strip()
                if head.startswith("ref:"):
                    return _resolve_ref(git_dir, head.split(None, 1)[1])
                return head or None
            except OSError:
                return None
    return None
