"""The package version: one string, ``project.version`` in pyproject.toml.

Read from the installed distribution's metadata; a source checkout that is not
installed (``PYTHONPATH=.``) reads pyproject.toml beside the package instead.
"""

from __future__ import annotations

import re
from importlib import metadata
from pathlib import Path


def _from_pyproject() -> str | None:
    path = Path(__file__).resolve().parent.parent / "pyproject.toml"
    try:
        text = path.read_text(encoding="utf-8")
    except OSError:
        return None
    project = re.search(r"^\[project\]\s*$(.*?)(?=^\[|\Z)", text, re.M | re.S)
    found = project and re.search(r'^version\s*=\s*"([^"]+)"', project.group(1), re.M)
    return found.group(1) if found else None


def _version() -> str:
    try:
        return metadata.version("clearsweep")
    except metadata.PackageNotFoundError:
        return _from_pyproject() or "0+unknown"


__version__ = _version()
