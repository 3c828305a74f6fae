"""The study kinds said once: ``analysis.results_kind`` tells what a results file holds (a
run, a life run, a grid, sampling, ensemble, life or reliability sweep; report and plot ask
it), and ``sweeping.stores.STORES`` what each sweep ``store:`` does with its cases."""

import pytest
import xarray as xr

from clearsweep.analysis import RESULTS_KINDS, results_kind

CASE = {"slider_position": ("time", [0.3, 0.31]), "status": ((), "ok")}
ENSEMBLE = {"x": (("B_coating", "member"), [[1.0, 2.0]]), "members_ok": ("B_coating", [2]),
            "x_mean": ("B_coating", [1.5])}

FILES = [
    ("run", xr.Dataset(CASE, coords={"time": [0.0, 0.1]})),
    ("life", xr.Dataset({"stop_reason": ((), "cycles"), "wear_depth_max": ("cycle", [1.0])})),
    # a life file written before stop_reason: its blocks' status says what it is
    ("life", xr.Dataset({"block_status": ("cycle", ["ok"]), "wear_depth_max": ("cycle", [1.0])})),
    ("reliability", xr.Dataset({"b10": ("B_coating", [1.0])}, attrs={"sweep_store": "reliability"})),
    ("life-sweep", xr.Dataset({"cycles_reached": ("B_coating", [1.0])}, attrs={"sweep_store": "life"})),
    ("ensemble", xr.Dataset(ENSEMBLE, attrs={"sweep_store": "summary"})),
    # members without their statistics are a grid over member, not an ensemble report
    ("sweep", xr.Dataset({"x": (("B_coating", "member"), [[1.0, 2.0]])})),
    ("sample", xr.Dataset({"x": ("sample", [1.0, 2.0])}, attrs={"sweep_store": "summary"})),
    # a sampling sweep with members is reported as an ensemble
    ("ensemble", xr.Dataset({"x": (("sample", "member"), [[1.0, 2.0]]), "members_ok": ("sample", [2])})),
    ("sweep", xr.Dataset({"x": ("B_clearance", [1.0, 2.0])}, attrs={"sweep_store": "full"})),
    # a one-case sweep keeps its store attribute: a sweep, not a run
    ("sweep", xr.Dataset(CASE, coords={"time": [0.0, 0.1]}, attrs={"sweep_store": "summary"})),
]


@pytest.mark.parametrize("kind, ds", FILES, ids=[f"{k}-{i}" for i, (k, _) in enumerate(FILES)])
def test_results_kind_names_each_kind_of_file(kind, ds):
    assert kind in RESULTS_KINDS
    assert results_kind(ds) == kind


def test_every_kind_is_named_by_some_file():
    assert {k for k, _ in FILES} == set(RESULTS_KINDS)


def test_the_store_registry_lists_the_stores_a_sweep_file_takes():
    from clearsweep.sweeping import STORE_MODES
    from clearsweep.sweeping.stores import STORES

    assert tuple(STORES) == STORE_MODES
    # only the time-series store keeps series; the life-run stores cannot run on the device
    assert [s.name for s in STORES.values() if s.keeps_series] == ["full"]
    assert [s.name for s in STORES.values() if not s.on_cuda] == ["life", "reliability"]


def test_every_figure_kind_the_cli_offers_is_drawn_by_the_figure_table():
    from clearsweep.choices import KINDS
    from clearsweep.plotting import FIGURES

    assert tuple(FIGURES) == KINDS


@pytest.mark.parametrize("kind, ds", FILES, ids=[f"{k}-{i}" for i, (k, _) in enumerate(FILES)])
def test_a_file_on_disk_is_told_by_the_same_rule_as_an_open_dataset(tmp_path, kind, ds):
    """``outputs.file_kind`` (the overwrite check, which reads the header alone) and
    ``results_kind`` (report, plot) name every kind of file alike."""
    from clearsweep.outputs import RESULTS_SOURCE, file_kind

    path = tmp_path / "f.nc"
    ds.assign_attrs(source=RESULTS_SOURCE).to_netcdf(path)
    assert file_kind(path) == kind
    ds.to_netcdf(tmp_path / "foreign.nc")
    assert file_kind(tmp_path / "foreign.nc") is None       # not clearsweep's: no kind


def test_every_study_kind_is_in_the_registry_with_every_hook():
    """Every kind of results file has one entry in ``studies.STUDIES`` (report, plot), and every
    ``store:`` one in ``sweeping.stores.STORES`` (plan, run, assemble), each giving every hook:
    the CLI and the planner ask the tables instead of testing the kind's name."""
    import dataclasses

    from clearsweep.outputs import RESULTS_KINDS as NAMED
    from clearsweep.studies import STUDIES, Refusal, StudyKind
    from clearsweep.sweeping.stores import CUDA_BATCH, ENSEMBLE, STORES, CaseFunctions

    assert tuple(STUDIES) == tuple(NAMED) == RESULTS_KINDS
    for name, study in STUDIES.items():
        assert isinstance(study, StudyKind) and study.name == name and study.described == NAMED[name]
        for hook in ("text_report", "table_report"):
            loader = getattr(study, hook)
            assert loader is None or callable(loader()), (name, hook)
        assert (study.report_reads is None) or study.text_report is not None
        assert all(isinstance(r, Refusal) for r in study.refusals.values())
    # the kinds report prints as text, and those whose text --metric replaces by a table
    assert [k for k, s in STUDIES.items() if s.text_report] == ["life", "reliability", "life-sweep"]
    assert [k for k, s in STUDIES.items() if s.metric_table] == ["reliability", "life-sweep"]
    assert [k for k, s in STUDIES.items() if s.table_report] == ["ensemble"]

    hooks = [f.name for f in dataclasses.fields(next(iter(STORES.values())))]
    for name, store in STORES.items():
        assert store.name == name and store.results_kind in STUDIES
        for hook in hooks:
            assert getattr(store, hook) is not None, (name, hook)
        functions = store.functions()
        assert isinstance(functions, CaseFunctions)
        assert all(f is None or callable(f) for f in dataclasses.astuple(functions))
        assert callable(store.check_case) and callable(store.check_base) and callable(store.members)
    assert [s.name for s in STORES.values() if s.runs_life] == ["life", "reliability"]
    assert {s.results_kind for s in STORES.values()} == {"sweep", "life-sweep", "reliability"}
    # the ensemble adds its statistics over a store without its own; the CUDA batch stores
    # its device cases' summaries and its --keep-series cases' series
    assert callable(ENSEMBLE.finish) and ENSEMBLE.key == "ensemble.member"
    assert not STORES[CUDA_BATCH.on_device].keeps_series and STORES[CUDA_BATCH.with_series].keeps_series
    assert STORES["full"].finish(CaseFunctions(), {"member": 2}) is ENSEMBLE.finish
    assert STORES["full"].finish(CaseFunctions(), {"B_coating": 2}) is None


@pytest.mark.parametrize("kind, ds", FILES, ids=[f"{k}-{i}" for i, (k, _) in enumerate(FILES)])
def test_the_figures_ask_one_table_what_each_kind_of_file_gives(kind, ds):
    """``plotting.common.FILE_FIGURES`` says, per kind of file, why it lacks a figure's
    variables, whether its runs keep Poincare sections, and whether wear-map reads its
    snapshots: the figure code asks it instead of testing the kind's name."""
    from clearsweep.plotting.common import FILE_FIGURES, PlotError, _require, file_figures

    assert tuple(sorted(FILE_FIGURES)) == tuple(sorted(RESULTS_KINDS))
    facts = file_figures(ds)
    assert facts is FILE_FIGURES[kind]
    assert facts.sections == (kind in ("run", "sweep"))
    assert facts.wear_map_snapshots == (kind == "life")
    with pytest.raises(PlotError) as err:
        _require(ds, ("wear_map",), "--kind wear-map")
    text = str(err.value)
    assert text.startswith("--kind wear-map needs wear_map, which this dataset lacks")
    if kind == "life":
        assert "a life run keeps its blocks' summaries and wear maps" in text
    elif kind == "sweep":
        assert ("summary-only sweep" in text) == (ds.attrs.get("sweep_store") != "full")
    elif kind != "run":
        from clearsweep.outputs import RESULTS_KINDS as NAMED

        assert text.endswith(f" (a file of {NAMED[kind]})")
