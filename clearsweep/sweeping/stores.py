"""What each sweep ``store:`` does with its cases, said once: how its cases are checked
before anything runs, simulated and summarised, whether a part keeps the time series, the
member dimension its base adds, what the assembled file gets added, and whether the CUDA
batch can run it; and what the ensemble and the CUDA batch do over any store.

The planner, the runner, the workers and the backends ask :data:`STORES`, :data:`ENSEMBLE`
and :data:`CUDA_BATCH` instead of testing the store's name. The case functions are imported
only when a sweep of that store runs.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import xarray as xr

from ..config import Config, ConfigError
from ..outputs import MEMBER_DIM, store_kind
from ..service_life import life_block
from ..simulation import preflight

#: Config -> the case's dataset; dataset -> its summaries; the assembled file -> (in place)
#: with what the store adds to it. ``None``: the default (simulation.simulate,
#: summary.case_summary, nothing added).
Simulate = Callable[[Config], xr.Dataset]
Summarize = Callable[[xr.Dataset], xr.Dataset]
Finish = Callable[[Path], None]
#: The planner's check of one resolved case: ``(config, source, allow_large, label)``,
#: raising ConfigError; ``label``: the case's sweep coordinates.
CheckCase = Callable[[Config, str, bool, Mapping[str, Any]], None]
#: The planner's check of the base config: ``(base, source)``, raising ConfigError.
CheckBase = Callable[[Config, str], None]


@dataclass(frozen=True)
class CaseFunctions:
    """How the cases of a store run (``None``: the default of each)."""

    simulate: Simulate | None = None
    summarize: Summarize | None = None
    finish: Finish | None = None


@dataclass(frozen=True)
class Members:
    """A member dimension (:data:`~clearsweep.outputs.MEMBER_DIM`) that a sweep's base adds
    after the sweep's own dimensions."""

    #: The config key set along it (``"ensemble.member"``).
    key: str
    #: Its size.
    count: int


@dataclass(frozen=True)
class Store:
    """One ``store:`` of a sweep file."""

    name: str
    #: A case's part keeps its time series (else its summaries only).
    keeps_series: bool
    #: The cases can run in the CUDA batch (``--backend cuda``: one kernel run each).
    on_cuda: bool
    #: Each case is a service-life run: a plan counts its blocks, not its duration.
    runs_life: bool
    #: Imports and returns the store's :class:`CaseFunctions`.
    functions: Callable[[], CaseFunctions]
    #: Checks one resolved case before anything runs (nothing compiled or run).
    check_case: CheckCase
    #: Checks the base config of the sweep file.
    check_base: CheckBase
    #: The member dimension the base adds (None: none).
    members: Callable[[Config], Members | None]
    #: A life case runs until every limit it watches is crossed (a reliability member),
    #: not until the first: what a plan's expected blocks count.
    every_limit: bool = False

    @property
    def results_kind(self) -> str:
        """The kind of results file a sweep of this store writes (``outputs.RESULTS_KINDS``,
        as ``outputs.check_output`` compares it)."""
        return store_kind(self.name)

    def finish(self, functions: CaseFunctions, dims: Mapping[str, int]) -> Finish | None:
        """What the assembled file of a sweep over ``dims`` gets added: the store's own
        (``functions.finish``), else the ensemble statistics where the base adds members."""
        return functions.finish or (ENSEMBLE.finish if MEMBER_DIM in dims else None)


@dataclass(frozen=True)
class Ensemble:
    """An ensemble base (``ensemble.members > 1``) over a store that has no members of its
    own: every member an ordinary case, and the file gains the ensemble statistics."""

    #: The config key each member sets.
    key: str
    #: The assembled file -> with the ensemble statistics.
    finish: Finish

    def members(self, base: Config) -> Members | None:
        """The ``member`` dimension of ``base``'s ensemble; None for one member."""
        n = base.ensemble.members
        return Members(self.key, n) if n > 1 else None


@dataclass(frozen=True)
class CudaBatch:
    """How the CUDA batch (``--backend cuda``) stores its cases, whatever the sweep's store:
    a case on the device keeps its summaries only; one named by ``--keep-series`` runs on the
    CPU kernel and keeps its time series."""

    on_device: str
    with_series: str


def add_ensemble_statistics(path: Path) -> None:
    """Append the ensemble statistics (:func:`clearsweep.ensemble.ensemble_statistics`) of
    the summary variables of the sweep file at ``path``; reads the summaries only."""
    import netCDF4

    from ..ensemble import ensemble_statistics, summary_variables

    with xr.open_dataset(path) as ds:
        names = ["status", *summary_variables(ds)]
        stats = ensemble_statistics(ds[names].load())
    stats = stats.drop_vars(list(stats.coords))
    with netCDF4.Dataset(path, "a") as nc:
        nc.setncatts(stats.attrs)
    stats.attrs = {}
    stats.to_netcdf(path, mode="a", engine="netcdf4")


#: The ensemble over the ``full``, ``summary`` and ``life`` stores.
ENSEMBLE = Ensemble("ensemble.member", add_ensemble_statistics)
#: The CUDA batch's stores of :data:`STORES`.
CUDA_BATCH = CudaBatch(on_device="summary", with_series="full")


def _defaults() -> CaseFunctions:
    return CaseFunctions()


def _life() -> CaseFunctions:
    from ..service_life import life_case, life_summary

    return CaseFunctions(life_case, life_summary)


def _reliability() -> CaseFunctions:
    from ..reliability import add_reliability_estimate, reliability_case, reliability_summary

    return CaseFunctions(reliability_case, reliability_summary, add_reliability_estimate)


def _any_base(base: Config, source: str) -> None:
    """Every base that the config admits."""


def _check_run(cfg: Config, source: str, allow_large: bool, label: Mapping[str, Any]) -> None:
    preflight(cfg, allow_large=allow_large, seat=False)     # the run seats it


def _check_life(cfg: Config, source: str, allow_large: bool, label: Mapping[str, Any]) -> None:
    """Each case is a life run: check its blocks, not its duration."""
    life_block(cfg, allow_large=allow_large, source=source)


def _check_reliability_base(base: Config, source: str) -> None:
    if base.ensemble.members > 1:
        raise ConfigError("ensemble.members", base.ensemble.members, "1 with store: reliability "
                          "(its members are reliability.members)", source)


def _check_reliability(cfg: Config, source: str, allow_large: bool,
                       label: Mapping[str, Any]) -> None:
    """A reliability case: limits that can be reached, and a member config (its draws
    applied) that the simulator admits.

    A design whose limits can never be reached (wear-through of an uncoated design) refuses
    the whole sweep before anything runs, its message saying how to run the other designs:
    a ``sweep.skip`` rule for it. A design the sweep file asks for is never dropped unsaid."""
    from ..reliability import check_reliability, member_config

    try:
        check_reliability(cfg, source)
    except ConfigError as exc:
        design = {n: v for n, v in (label or {}).items() if n != MEMBER_DIM}
        if not design:
            raise
        rule = "{" + ", ".join(f"{n}: {v}" for n, v in design.items()) + "}"
        raise ConfigError(exc.key, exc.value, f"{exc.expected}; to run the other designs, "
                          f"skip this one (sweep: skip: [{rule}])", exc.source, exc.suggestion,
                          exc.got) from None
    try:
        life_block(member_config(cfg), allow_large=allow_large, source=source)
    except ConfigError as exc:
        raise ConfigError(exc.key, exc.value, f"{exc.expected} (with the draws of reliability "
                          f"member {cfg.reliability.member})", source, exc.suggestion, exc.got) from None


def _reliability_members(base: Config) -> Members:
    """A reliability sweep's ``member`` dimension: ``reliability.members`` life runs."""
    return Members("reliability.member", base.reliability.members)


#: Every store, in the order ``store:`` lists them. ``life``: each case is a service-life
#: run (``clearsweep life``), stored as its summary (revolutions to each limit, final wear);
#: ``reliability``: each design is ``reliability.members`` life runs with scatter, stored as
#: their summaries and the reliability estimate (docs/reliability.md).
STORES = {store.name: store for store in (
    Store("full", keeps_series=True, on_cuda=True, runs_life=False, functions=_defaults,
          check_case=_check_run, check_base=_any_base, members=ENSEMBLE.members),
    Store("summary", keeps_series=False, on_cuda=True, runs_life=False, functions=_defaults,
          check_case=_check_run, check_base=_any_base, members=ENSEMBLE.members),
    Store("life", keeps_series=False, on_cuda=False, runs_life=True, functions=_life,
          check_case=_check_life, check_base=_any_base, members=ENSEMBLE.members),
    Store("reliability", keeps_series=False, on_cuda=False, runs_life=True,
          functions=_reliability, check_case=_check_reliability,
          check_base=_check_reliability_base, members=_reliability_members, every_limit=True),
)}
