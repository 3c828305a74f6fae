"""Numba kernel of clearsweep: pure functions over float64 arrays and scalars, SI units.

Compiled functions are cached on disk (``cache=True``), in a folder named by a hash of
every source file of this package (``numba_compat.cache_dir``): Numba keys a cached
function on its own source file only, so a change in a helper it calls from another file
would otherwise leave a stale binary. Numba's cache locator reads the folder when a
function is decorated, so it is set here, before any kernel module is imported.
"""

from .numba_compat import use_cache_dir

use_cache_dir()
