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


#: The revision of the results: raised whenever a config gives other results than before
#: (here: the seated balls of A and B balance their friction, and joint P's block meets
#: its walls along its faces' edge lines and wears them over the faces' tracks, issue 41;
#: before it, Hertz's
#: modulus E* in the power law at O, P and under ``contact.elastic: hertz``). It is part
#: of every run's identity (``params.run_identity``): a sweep's parts and a life checkpoint
#: written before are another run's, refused by --resume with the difference named, not
#: mixed into this one's results.
RESULTS_REVISION = 4
#: The version a run's identity records: the package's and the results' revision.
IDENTITY_VERSION = f"{__version__} (results revision {RESULTS_REVISION})"
