"""What each sweep ``store:`` does with its cases, said once: how a case is simulated and
summarised, whether its part keeps the time series, what the assembled file gets added,
and whether the CUDA backend can run it.

The runner, the workers and the backends ask :data:`STORES` instead of testing the store's
name. The case functions are imported only when a sweep of that store runs.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import xarray as xr

from ..config import Config

#: Config -> the case's dataset; dataset -> its summaries; the assembled file -> (in place)
#: with what the store adds to it. ``None``: the default (simulation.simulate,
#: summary.case_summary, nothing added).
Simulate = Callable[[Config], xr.Dataset]
Summarize = Callable[[xr.Dataset], xr.Dataset]
Finish = Callable[[Path], None]


@dataclass(frozen=True)
class CaseFunctions:
    """How the cases of a store run (``None``: the default of each)."""

    simulate: Simulate | None = None
    summarize: Summarize | None = None
    finish: Finish | None = None


@dataclass(frozen=True)
class Store:
    """One ``store:`` of a sweep file."""

    name: str
    #: A case's part keeps its time series (else its summaries only).
    keeps_series: bool
    #: The cases can run on the CUDA backend (``--backend cuda``: one kernel run each).
    on_cuda: bool
    #: Imports and returns the store's :class:`CaseFunctions`.
    functions: Callable[[], CaseFunctions]


def _defaults() -> CaseFunctions:
    return CaseFunctions()


def _life() -> CaseFunctions:
    from ..service_life import life_case, life_summary

    return CaseFunctions(life_case, life_summary)


def _reliability() -> CaseFunctions:
    from ..reliability import add_reliability_estimate, reliability_case, reliability_summary

    return CaseFunctions(reliability_case, reliability_summary, add_reliability_estimate)


#: Every store, in the order ``store:`` lists them. ``life``: each case is a service-life
#: run (``clearsweep life``), stored as its summary (revolutions to each limit, final wear);
#: ``reliability``: each design is ``reliability.members`` life runs with scatter, stored as
#: their summaries and the reliability estimate (docs/reliability.md).
STORES = {store.name: store for store in (
    Store("full", keeps_series=True, on_cuda=True, functions=_defaults),
    Store("summary", keeps_series=False, on_cuda=True, functions=_defaults),
    Store("life", keeps_series=False, on_cuda=False, functions=_life),
    Store("reliability", keeps_series=False, on_cuda=False, functions=_reliability),
)}
