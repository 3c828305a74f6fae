"""The study kinds, said once: what ``report`` prints and which figures ``plot`` refuses for
each kind of results file (a run, a life run, a grid, sampling, ensemble, life or reliability
sweep).

:func:`clearsweep.outputs.kind_of` tells a file's kind (``analysis.results_kind`` for an open
dataset); the CLI asks :data:`STUDIES` what to do with it instead of testing the kind's name.
How a sweep's cases are checked, run, stored and assembled is the sweep's store's
(:data:`clearsweep.sweeping.stores.STORES`). The report functions are imported only when a
file of their kind is reported.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from .choices import DEFAULT_SWEEP_METRIC
from .outputs import RESULTS_KINDS

#: The figure kinds that draw one run's time series and wear maps.
RUN_FIGURES = "slider, forces, spectrum, wear-map, wear-polar or orbit"

if TYPE_CHECKING:
    import xarray as xr

#: Imports and returns a text report: the dataset -> its text.
TextReport = Callable[[], Callable[["xr.Dataset"], str]]
#: Imports and returns a table report: ``(dataset, format, reference)`` -> its text.
TableReport = Callable[[], Callable[..., str]]


@dataclass(frozen=True)
class Refusal:
    """A figure kind that does not draw a study kind: why (``{path}``: the file), and whether
    ``--metric`` lifts it."""

    message: str
    unless_metric: bool = False

    def applies(self, metric: str | None) -> bool:
        return not (self.unless_metric and metric is not None)


@dataclass(frozen=True)
class StudyKind:
    """One kind of results file (a key of :data:`clearsweep.outputs.RESULTS_KINDS`)."""

    name: str
    #: ``report`` prints it as text only (None: as tables); imported on use.
    text_report: TextReport | None = None
    #: A variable the text report reads (a file without it is refused, naming it).
    report_reads: str | None = None
    #: ``report --metric`` prints the metric's table instead of the text report.
    metric_table: bool = False
    #: The table report (None: the statistics and wear tables, or ``--reference``'s).
    table_report: TableReport | None = None
    #: ``plot --kind K`` of such a file is refused: figure kind -> :class:`Refusal`.
    refusals: Mapping[str, Refusal] = field(default_factory=dict)

    @property
    def described(self) -> str:
        """How a message names such a file (``"a life run"``)."""
        return RESULTS_KINDS[self.name]

    def text_only(self, metric: str | None) -> Callable[[xr.Dataset], str] | None:
        """The text report ``report`` prints (None: tables), given ``--metric``."""
        if self.text_report is None or (metric and self.metric_table):
            return None
        return self.text_report()

    def refusal(self, figure: str, path: str, metric: str | None) -> str | None:
        """Why ``plot --kind figure`` does not draw the file ``path`` of this kind (None: it may)."""
        refusal = self.refusals.get(figure)
        if refusal is None or not refusal.applies(metric):
            return None
        return refusal.message.format(path=path, described=self.described)


def _life_text() -> Callable[[xr.Dataset], str]:
    from .service_life import life_summary_text

    return life_summary_text


def _life_sweep_text() -> Callable[[xr.Dataset], str]:
    from .service_life import life_sweep_text

    return life_sweep_text


def _reliability_text() -> Callable[[xr.Dataset], str]:
    from .reliability import reliability_text

    return reliability_text


def _ensemble_report() -> Callable[..., str]:
    from .analysis import format_ensemble_report

    return format_ensemble_report


#: ``--kind life`` of a file that is not a life run.
_NOT_LIFE = Refusal("--kind life draws a life run (`clearsweep life CONFIG` writes one); {path} "
                    "is {described}")

#: Every study kind, in the order of :data:`clearsweep.outputs.RESULTS_KINDS`.
STUDIES = {study.name: study for study in (
    StudyKind("run", refusals={
        "sweep": Refusal("--kind sweep draws a metric across a sweep's designs; {path} is a "
                         f"single run: draw it with --kind {RUN_FIGURES}"),
        "life": Refusal(_NOT_LIFE.message + f": draw it with --kind {RUN_FIGURES}")}),
    StudyKind("life", _life_text, "stop_reason", refusals={
        "sweep": Refusal("--kind sweep draws a sweep; {path} is a life run: --kind life draws it")}),
    StudyKind("reliability", _reliability_text, "b10", metric_table=True,
              refusals={"life": _NOT_LIFE}),
    StudyKind("life-sweep", _life_sweep_text, metric_table=True, refusals={
        "sweep": Refusal("--kind sweep of {path}, a life sweep, needs --metric: its default, "
                         f"{DEFAULT_SWEEP_METRIC}, is a dynamics metric a life sweep does not "
                         "keep (e.g. --metric cycles_reached)", unless_metric=True)}),
    StudyKind("ensemble", table_report=_ensemble_report, refusals={"life": _NOT_LIFE}),
    StudyKind("sample", refusals={"life": _NOT_LIFE}),
    StudyKind("sweep", refusals={"life": _NOT_LIFE}),
)}
