"""xarray's tests for dask arrays, without importing dask before a dask object exists.

Where dask is installed, xarray imports ``dask.array`` (and with it scipy's fft, sparse and
special modules) the first time it builds a ``Variable`` from a numpy array, only to ask
whether the data is a dask array (``xarray.namedarray.pycompat.array_type("dask")``), and
``dask`` itself (its scheduler, delayed and config modules) the first time it asks whether
an array is a dask collection (``xarray.namedarray.utils.is_dask_collection``). Those
imports were most of a short run's start beyond the imports every run needs (issue 32,
benchmarks/README.md). :func:`defer_dask_array` answers both without importing dask where
the answer cannot be "yes":

- no object can be a dask array while ``dask.array`` is not imported: xarray's cache of
  array modules gets an entry that says so, which becomes xarray's own entry (the same
  import, the same types) as soon as ``dask.array`` is imported, by the user, by
  ``open_dataset(..., chunks=...)`` or by a Dask cluster;
- an object without a ``__dask_graph__`` attribute is no dask collection (the first test of
  ``dask.base.is_dask_collection``); any other is asked of dask as before.

Nothing else about xarray's use of dask changes. Where xarray lacks what this relies on (a
version that does it differently), :func:`defer_dask_array` leaves that part as it is.
"""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable
from typing import Any


class _DeferredDask:
    """xarray's ``DuckArrayModule("dask")``, made when ``dask.array`` is imported."""

    def __init__(self, module_class: type) -> None:
        self._module_class = module_class
        self._made: Any = None

    def _module(self) -> Any:
        if self._made is None:
            self._made = self._module_class("dask")
        return self._made

    @property
    def type(self) -> tuple[type, ...]:
        if self._made is None and getattr(sys.modules.get("dask.array"), "Array", None) is None:
            return ()       # no dask array can exist yet
        return self._module().type

    @property
    def module(self) -> Any:
        return self._module().module

    @property
    def version(self) -> Any:
        return self._module().version

    @property
    def available(self) -> bool:
        return self._module().available


def _without_dask_graph(is_dask_collection: Callable[[object], bool]) -> Callable[[object], bool]:
    """``is_dask_collection`` that answers False, importing nothing, for an object without
    ``__dask_graph__``."""
    if getattr(is_dask_collection, "_clearsweep_deferred", False):
        return is_dask_collection

    @functools.wraps(is_dask_collection)
    def deferred(x: object) -> bool:
        return hasattr(x, "__dask_graph__") and is_dask_collection(x)

    deferred._clearsweep_deferred = True        # type: ignore[attr-defined]
    return deferred


def defer_dask_array() -> bool:
    """Let xarray import dask only once a dask object can exist (module docstring); True
    where both deferrals are in place."""
    try:
        from xarray.namedarray import pycompat
        from xarray.namedarray import utils as namedarray_utils
    except ImportError:
        return False
    cache = getattr(pycompat, "_cached_duck_array_modules", None)
    module_class = getattr(pycompat, "DuckArrayModule", None)
    test = getattr(namedarray_utils, "is_dask_collection", None)
    placed = 0
    if isinstance(cache, dict) and isinstance(module_class, type):
        cache.setdefault("dask", _DeferredDask(module_class))
        placed += isinstance(cache["dask"], _DeferredDask)
    if callable(test):
        namedarray_utils.is_dask_collection = _without_dask_graph(test)  # type: ignore[assignment]
        placed += 1
    return placed == 2
