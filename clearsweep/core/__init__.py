"""Numba kernel of clearsweep: pure functions over float64 arrays and scalars, SI units.

Compiled functions are cached on disk (``cache=True``). Numba keys a cached function on
its own source file only, so a change in a helper it calls from another file would
leave a stale binary. The cache therefore lives in a folder named by a hash of every
source file of this package: any change to the kernel gets a fresh cache.
"""

import hashlib
import os
from pathlib import Path

import numba


def _cache_dir() -> str:
    here = Path(__file__).resolve().parent
    digest = hashlib.sha256()
    for path in sorted(here.glob("*.py")):
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    digest.update(numba.__version__.encode())
    root = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(Path.home(), ".cache"), "clearsweep", "numba")
    return os.path.join(root, digest.hexdigest()[:16])


numba.config.CACHE_DIR = _cache_dir()
