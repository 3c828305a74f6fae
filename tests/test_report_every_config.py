"""``report`` and ``plot`` on every kind of results file the project writes (issue 40, items 1
and 5): every shipped config in configs/, run short, through ``report`` in every format
(``--reference`` too where it sweeps a design) and ``plot`` of every figure kind; and single
runs with clearance at every subset of the joints O, A, B and P, the empty one (the ideal
mechanism) included.

Before, ``report`` of configs/ideal.yaml's run (and of a run with clearance at P only, and
``--full`` and ``--reference`` of configs/paper.yaml's sweep, whose first case has no
clearance) ended in ``TypeError: 'int' object is not iterable``; csv and json of the ideal run
had no row; and the text report of a sweep whose cases have Poincaré sections in some cases
and none in others exited 2 with "cannot convert float NaN to integer".

A shipped config is cut to a short run here: 0.25 s at 600 r/min (2.5 revolutions: Poincaré
sections and a spectrum) where it does not sweep the speed or the duration (20 ms at 60 r/min
of the paper's preset), a coarse wear map, the first two values of each grid axis, two members
of an ensemble or a reliability design, two life blocks (one for a reliability member), a
Saltelli sample of n = 4; a zip group of more than four entries keeps its first and last
(configs/bifurcation.yaml: 50 and 640 r/min, at one fixed duration: the slower run has no
section, the faster one two settled ones).
"""

from __future__ import annotations

import csv
import io
import itertools
import json
from pathlib import Path

import pytest
import xarray as xr
import yaml
from click.testing import CliRunner
from conftest import made_once

from clearsweep.analysis import PERIOD_UNKNOWN, design_dims, results_kind
from clearsweep.choices import KINDS
from clearsweep.cli import main
from clearsweep.config import file_kind
from clearsweep.studies import STUDIES

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ROOT / "configs"

#: A short run: 2.5 crank revolutions at 600 r/min, 2 of them after the settling time.
SHORT = {"solver.duration": 0.25, "solver.dt": 1e-5, "metrics.settle_time": 0.05,
         "mechanism.speed_rpm": 600.0, "wear.map": [6, 12]}
#: The paper's preset (stiff contacts, coated joints) is stable at dt 1e-5 s at its own
#: 60 r/min only: 20 ms there, as tests/shipped.py's ``main_job`` runs configs/paper.yaml.
SHORT_PAPER = {"solver.duration": 0.02, "solver.dt": 1e-5, "solver.save_every": 1,
               "metrics.settle_time": 0.005, "wear.map": [6, 12]}
#: A short life: blocks of one revolution at 600 r/min, two of them, on a coarse map.
SHORT_LIFE = {"mechanism.speed_rpm": 600.0, "life.max_blocks": 2, "wear.map": [6, 12]}
#: A zip group longer than this keeps its first and last entries.
MAX_ZIP = 4


def invoke(*args) -> object:
    return CliRunner().invoke(main, [str(a) for a in args])


def _base(doc: dict) -> dict:
    """The case config of a config file: itself, or a sweep's base (read where it is a file)."""
    base = doc.get("base", doc) if "sweep" in doc or "store" in doc else doc
    return yaml.safe_load((CONFIGS / base).read_text()) if isinstance(base, str) else base


def _swept_keys(doc: dict) -> set[str]:
    sweep = doc.get("sweep") or {}
    keys = set((sweep.get("grid") or {}))
    keys |= set((sweep.get("sample") or {}).get("ranges") or {})
    for group in sweep.get("zip") or []:
        keys |= {k for k in group if k not in ("name", "labels")}
    return keys


def shortened(path: Path) -> tuple[dict, list[str]]:
    """The config file ``path`` cut short (the module docstring), and its ``--set`` items."""
    doc = yaml.safe_load(path.read_text())
    if isinstance(doc.get("base"), str):
        doc["base"] = str(CONFIGS / doc["base"])
    base = _base(doc)
    paper = (base.get("mechanism") or {}).get("preset") == "paper"
    sets = dict(SHORT_LIFE if "life" in base else SHORT_PAPER if paper else SHORT)
    if "reliability" in base:
        sets.update({"reliability.members": 2, "life.max_blocks": 1})
    if "ensemble" in base:
        sets["ensemble.members"] = 2
    sweep = doc.get("sweep") or {}
    for key, values in (sweep.get("grid") or {}).items():
        # a speed axis keeps its slowest and fastest speeds (sections in some cases only)
        sweep["grid"][key] = [values[0], values[-1]] if key == "mechanism.speed_rpm" else values[:2]
    if "sample" in sweep:
        sweep["sample"]["n"] = 4
    for group in [sweep.get("grid") or {}, *(sweep.get("zip") or [])]:
        if "materials_file" in group:   # taken from the config's folder, which the copy leaves
            group["materials_file"] = [str(CONFIGS / v) for v in group["materials_file"]]
    for group in sweep.get("zip") or []:
        keys = [k for k in group if k != "name"]
        if len(group[keys[0]]) > MAX_ZIP:
            for key in keys:
                group[key] = [group[key][0], group[key][-1]]
            for key in ("solver.duration", "metrics.settle_time"):
                if key in group:
                    group[key] = [SHORT[key]] * 2
    swept = _swept_keys(doc)
    return doc, [f"{k}={v}" for k, v in sets.items() if k not in swept]


def command(doc: dict) -> str:
    kind = file_kind(doc)
    return "sweep" if kind == "sweep" else "life" if "life" in doc else "run"


@pytest.fixture(scope="module")
def shipped(tmp_path_factory) -> dict[str, Path]:
    """Every shipped config's short results file, by the config's name: made once per test
    run (``conftest.made_once``), whichever worker process asks first."""

    def make(folder: Path) -> None:
        for path in sorted(CONFIGS.glob("*.yaml")):
            doc, sets = shortened(path)
            config = folder / path.name
            config.write_text(yaml.safe_dump(doc))
            verb = command(doc)
            extra = ["--no-progress", "--workers", "1"] if verb == "sweep" else []
            result = invoke(verb, config, *[a for s in sets for a in ("--set", s)], *extra,
                            "-q", "-o", folder / f"{path.stem}.nc")
            assert result.exit_code == 0, f"{path.name}: {result.output}"

    folder = made_once(tmp_path_factory, "shipped", make)
    return {path.stem: folder / f"{path.stem}.nc" for path in sorted(CONFIGS.glob("*.yaml"))}


def first(ds: xr.Dataset, *dims: str) -> list[str]:
    """``--select DIM=VALUE`` of each of ``dims`` at its first value."""
    return [a for d in dims for a in ("--select", f"{d}={ds[d].values[0]}")]


#: The figures each shipped config's short results must draw (with the options they need):
#: every other kind is refused in one line. A run draws its time series, its spectrum and
#: its sections, and the per-joint figures where a joint has clearance; a full sweep the
#: same, one case for the wear map; a summary sweep, an ensemble and a sampling sweep the
#: metric over the design; a life run and a reliability sweep their own figures.
FIGURES = {
    "bifurcation": lambda ds: {"poincare": [], "sweep": [], "bifurcation": []},
    "coating_clearance": lambda ds: {
        **dict.fromkeys(("slider", "forces", "wear-polar", "orbit", "poincare", "spectrum"), []),
        "wear-map": first(ds, "B_clearance", "B_coating", "clearance_joints"),
        "sweep": first(ds, "clearance_joints"),
        "bifurcation": ["--x", "B_clearance", *first(ds, "B_coating", "clearance_joints")]},
    "coating_ensemble": lambda ds: {"poincare": [], "sweep": []},
    "contact_laws": lambda ds: {
        **dict.fromkeys(("slider", "forces", "wear-polar", "orbit", "poincare", "spectrum",
                         "sweep", "bifurcation"), []),
        "wear-map": first(ds, "damping")},
    # a two-key grid cut to 80 and 110 r/min for 0.25 s: no case reaches a section, so the
    # map, the bifurcation and the sections are refused, saying so (tests/test_dynamics_map.py
    # draws a map of runs that do)
    "dynamics_map": lambda ds: {"sweep": first(ds, "B_clearance")},
    "ideal": lambda ds: dict.fromkeys(("slider", "forces", "spectrum", "poincare"), []),
    "life": lambda ds: {"wear-map": [], "life": []},
    "life_sweep": lambda ds: {"sweep": ["--metric", "cycles_reached"]},
    "measured_friction": lambda ds: {"poincare": [], "sweep": first(ds, "materials")},
    "mixed_clearances": lambda ds: {
        "sweep": first(ds, "O_clearance", "A_clearance", "B_clearance"), "effects": []},
    "one_clearance": lambda ds: dict.fromkeys(
        ("slider", "forces", "wear-map", "wear-polar", "orbit", "poincare", "spectrum"), []),
    "paper": lambda ds: {
        **dict.fromkeys(("slider", "forces", "wear-polar", "orbit", "sweep"), []),
        "wear-map": ["--select", "clearance_joints=AB", "--select", "coating_joints=AB"]},
    "reliability": lambda ds: {"reliability": []},
    "reliability_joints": lambda ds: {"reliability": []},
    "revolute_clearance": lambda ds: {
        **dict.fromkeys(("slider", "forces", "wear-polar", "orbit", "poincare", "spectrum"), []),
        "wear-map": first(ds, "O_clearance", "O_coating", "clearance_joints"),
        "sweep": first(ds, "clearance_joints"),
        "bifurcation": ["--x", "O_clearance", *first(ds, "O_coating", "clearance_joints")]},
    # the sample's points drawn against their position, one sweep dimension as any other
    "sensitivity": lambda ds: {"sweep": ["--metric", "slider_acceleration_rms_settled"],
                               "bifurcation": []},
    # the slider-crank's clearance x speed grid, cut to 2 x 2 cases of 0.25 s: each case
    # reaches settled sections, so the map and the bifurcation along either key draw
    "slider_crank_clearance_sweep": lambda ds: {
        "poincare": [], "sweep": [],
        "bifurcation": ["--x", "speed_rpm", *first(ds, "B_clearance")],
        "dynamics-map": ["--x", "speed_rpm", "--y", "B_clearance"]},
}
FIGURES |= {"two_clearances": FIGURES["one_clearance"],
            "slider_crank": FIGURES["one_clearance"],
            "slider_crank_ensemble": FIGURES["coating_ensemble"],
            "slider_crank_life": FIGURES["life"],
            "paper_case": lambda ds: dict.fromkeys(
                ("slider", "forces", "wear-map", "wear-polar", "orbit"), [])}


def test_every_shipped_config_is_covered():
    assert sorted(FIGURES) == sorted(p.stem for p in CONFIGS.glob("*.yaml"))


def one_error_line(result) -> str:
    assert result.exception is None or isinstance(result.exception, SystemExit), \
        f"{type(result.exception).__name__}: {result.exception}"
    assert "Traceback" not in result.output
    lines = result.stderr.strip().splitlines()
    assert result.exit_code == 2 and len(lines) == 1, result.output
    assert lines[0].startswith("clearsweep: error: ")
    return lines[0]


def strict_json(text: str) -> object:
    def refuse(token: str) -> None:
        raise AssertionError(f"{token} in the json")
    return json.loads(text, parse_constant=refuse)


@pytest.mark.parametrize("name", sorted(FIGURES))
def test_report_of_every_shipped_config_in_every_format(shipped, name):
    path = shipped[name]
    with xr.open_dataset(path) as ds:
        study = STUDIES[results_kind(ds)]
        dims = design_dims(ds)
        # against a design's second value: configs/paper.yaml's first case (no clearance) is
        # then compared with it
        reference = ([f"{dims[0]}={ds[dims[0]].values[min(1, ds.sizes[dims[0]] - 1)]}"]
                     if dims and dims[0] in ds.coords else [])
    text_only = study.text_report is not None
    result = invoke("report", path)
    assert result.exit_code == 0 and result.exception is None, result.output
    assert result.stdout.strip()
    options_tried = [["--full"], *(["--format", f] for f in ("markdown", "csv", "json"))]
    options_tried += [["--reference", r, "--format", f] for r in reference
                      for f in ("text", "csv", "json")]
    for options in options_tried:
        result = invoke("report", path, *options)
        if text_only:       # a life run, a life sweep, a reliability sweep: text only, said so
            assert "which report prints as text only" in one_error_line(result)
            continue
        assert result.exit_code == 0 and result.exception is None, (options, result.output)
        if options[-1] == "csv":
            rows = list(csv.reader(io.StringIO(result.stdout)))
            assert len(rows) >= 2 and all(len(r) == len(rows[0]) for r in rows)
        elif options[-1] == "json":
            assert strict_json(result.stdout)["rows"]


@pytest.mark.slow      # 12 figure kinds of 16 files: about 45 s on two cores
@pytest.mark.parametrize("name", sorted(FIGURES))
def test_plot_of_every_shipped_config_draws_its_figures_and_refuses_the_others(
        shipped, tmp_path, name):
    path = shipped[name]
    with xr.open_dataset(path) as ds:
        drawn = FIGURES[name](ds)
    for kind in KINDS:
        out = tmp_path / f"{kind}.png"
        result = invoke("plot", path, "--kind", kind, *drawn.get(kind, []), "--dpi", "20",
                        "-o", out, "-q")
        if kind in drawn:
            assert result.exit_code == 0 and result.exception is None, (kind, result.output)
            assert out.stat().st_size > 0
        else:
            assert result.exit_code != 0, f"--kind {kind} drew"
            one_error_line(result)
            assert not out.exists()


# --------------------------------------------------------------------------- item 5

def test_a_sweep_with_sections_in_some_cases_only_is_reported_in_every_format(shipped):
    """configs/bifurcation.yaml cut to 50 and 640 r/min for 0.25 s each: the slower run ends
    before its first section, the faster one holds two settled sections. Its period is
    undetermined, in every format (before: the text report exited 2 with "cannot convert
    float NaN to integer")."""
    path = shipped["bifurcation"]
    with xr.open_dataset(path) as ds:
        assert list(ds["speed_rpm"].values) == [50, 640]
        held = ds["poincare_time"].notnull().sum("revolution").values
    assert held[0] == 0 and held[1] >= 2
    for options in ([], ["--full"]):
        result = invoke("report", path, *options)
        assert result.exit_code == 0, result.output
        assert "- undetermined (fewer than 2 settled revolutions): 1 design: speed_rpm=50" \
            in result.stdout
    result = invoke("report", path, "--format", "csv")
    assert result.exit_code == 0, result.output
    periods = {r["speed_rpm"]: r["Period in revolutions (0: none, -1: n/a) [1]"]
               for r in csv.DictReader(io.StringIO(result.stdout))}
    assert periods["50"] == str(PERIOD_UNKNOWN) and int(periods["640"]) >= 0
    result = invoke("report", path, "--format", "json")
    assert result.exit_code == 0, result.output
    rows = strict_json(result.stdout)["rows"]
    by_speed = {r["speed_rpm"]: r["period"] for r in rows}
    assert by_speed[50] == PERIOD_UNKNOWN and isinstance(by_speed[640], int) and by_speed[640] >= 0
    result = invoke("report", path, "--metric", "period", "--format", "json")
    assert [r["period"] for r in strict_json(result.stdout)["rows"]][0] == PERIOD_UNKNOWN


# --------------------------------------------------------------------------- item 1

#: A clearance for each joint: radial at O, A and B, both of the guide's at P.
CLEARANCE = {"O": ["joints.O.clearance=1e-4"], "A": ["joints.A.clearance=2.5e-4"],
             "B": ["joints.B.clearance=2.5e-4"],
             "P": ["joints.P.clearance_y=1e-4", "joints.P.clearance_z=1e-4"]}
SUBSETS = ["".join(s) for n in range(5) for s in itertools.combinations("OABP", n)]


@pytest.fixture(scope="module")
def subsets(tmp_path_factory) -> dict[str, Path]:
    """A 20 ms run of configs/ideal.yaml with clearance at each subset of O, A, B and P, made
    once per test run (``conftest.made_once``)."""

    def make(folder: Path) -> None:
        for subset in SUBSETS:
            sets = ["solver.duration=0.02", "metrics.settle_time=0.005", "wear.map=[6,12]",
                    *(s for j in subset for s in CLEARANCE[j])]
            result = invoke("run", CONFIGS / "ideal.yaml",
                            *[a for s in sets for a in ("--set", s)], "-q", "-o",
                            folder / f"run_{subset or 'none'}.nc")
            assert result.exit_code == 0, result.output

    folder = made_once(tmp_path_factory, "subsets", make)
    return {subset: folder / f"run_{subset or 'none'}.nc" for subset in SUBSETS}


@pytest.mark.parametrize("subset", SUBSETS, ids=[s or "none" for s in SUBSETS])
def test_report_of_a_run_with_clearance_at_any_subset_of_the_joints(subsets, subset):
    path = subsets[subset]
    result = invoke("report", path)
    assert result.exit_code == 0 and result.exception is None, result.output
    text = result.stdout
    assert text.startswith("Slider and crank (every-step statistics")
    contacts = text.split("Contacts (", 1)[1].split("\n\n", 2)
    if subset:
        rows = contacts[1].splitlines()[1:]
        assert [r.split()[0] for r in rows if r[:1].isupper() and len(r.split()[0]) == 1] \
            == [j for j in "ABOP" if j in subset]
    else:
        assert contacts[0].endswith("none: every joint is ideal (joints.*.clearance 0)")
    wear = text.split("Wear prediction (", 1)[1]
    if not set(subset) - {"P"}:
        assert "none: " in wear.splitlines()[0]
    if subset == "P":
        assert "the wear of guide P is in the table of the wear at the end of the run" in wear
    for fmt in ("csv", "json"):
        result = invoke("report", path, "--format", fmt)
        assert result.exit_code == 0, result.output
        if fmt == "csv":
            rows = list(csv.DictReader(io.StringIO(result.stdout)))
        else:
            rows = strict_json(result.stdout)["rows"]
        joints = sorted({r["joint"] for r in rows})
        if subset:
            assert joints == sorted(subset)
        else:
            # one row of the case's own statistics, without joint or wear direction
            assert len(rows) == 1 and rows[0]["joint"] in ("", None)
            assert float(rows[0]["slider_acceleration_peak" if fmt == "json"
                                 else "Peak slider acc., whole run [m s-2]"]) > 0


# --------------------------------------------------------------------------- issue 45 item 1

def _title_parts(title: str) -> list[str]:
    """A figure title's parts (ended by ";" or the title's end), its wrapped lines rejoined."""
    return [p.strip() for p in " ".join(title.split()).split(";")]


def _configured(doc: dict) -> tuple[object, dict[str, float]]:
    """The start (``initial.joints``, seated by default) and each joint's radial clearance [m]
    (a guide's smaller of its two) that a config file gives its cases, read from the file."""
    base = _base(doc)
    start = (base.get("initial") or {}).get("joints", "seated")
    clearances = {}
    for joint in "OABP":
        spec = (base.get("joints") or {}).get(joint) or {}
        given = [float(spec[k]) for k in ("clearance", "clearance_y", "clearance_z") if k in spec]
        clearances[joint] = min(given) if given else 0.0
    return start, clearances


def _case_values(case: xr.Dataset, key: str) -> tuple[bool, object]:
    """(swept, its one value in ``case`` or None where the cases drawn differ) of ``key``."""
    coord = next((c for c in case.coords.values() if c.attrs.get("config_key") == key), None)
    if coord is None:
        return False, None
    values = set(coord.values.ravel().tolist())
    return True, values.pop() if len(values) == 1 else None


@pytest.mark.parametrize("name", sorted(FIGURES))
def test_every_figure_of_every_shipped_config_names_the_start_and_clearances_it_ran(shipped, name):
    """The title of each figure that the short results of a shipped config draw names the
    start and the joints with clearance that the config (its base, and the swept values of
    the cases drawn) gives them; a start or a set of joints the cases drawn differ in is not
    named. Every figure of configs/revolute_clearance.yaml and configs/contact_laws.yaml said
    "start: seated" of centred runs, and no title named the joints with clearance (issue 45)."""
    from clearsweep.analysis import select_cases
    from clearsweep.plotting import figure

    doc = yaml.safe_load((CONFIGS / f"{name}.yaml").read_text())
    if isinstance(doc.get("base"), str):
        doc["base"] = str(CONFIGS / doc["base"])
    start, clearances = _configured(doc)
    with xr.open_dataset(shipped[name]) as ds:
        ds = ds.load()
    for kind, args in FIGURES[name](ds).items():
        options = dict(zip(args[::2], args[1::2]))
        selects = [b for a, b in zip(args[::2], args[1::2]) if a == "--select"]
        parts = _title_parts(figure(ds, kind, selects or None, x=options.get("--x"),
                                    y=options.get("--y"),
                                    metric=options.get("--metric")).get_suptitle())
        case = select_cases(ds, selects) if selects else ds
        swept, value = _case_values(case, "initial.joints")
        expected_start = value if swept else start
        said_start = [p for p in parts if "start: " in p]
        if expected_start is None:
            assert not said_start, (kind, parts)
        else:
            assert len(said_start) == 1 and said_start[0].endswith(f"start: {expected_start}"), \
                (kind, parts)
        joints, known = [], True
        for joint, configured in clearances.items():
            key = f"joints.{joint}.clearance"
            found = [_case_values(case, k) for k in (key, key + "_y", key + "_z")]
            values = [v for s, v in found if s]
            if any(v is None for v in values):
                known = False           # the cases drawn differ in this joint's clearance
            elif (min(float(v) for v in values) if values else configured) > 0.0:
                joints.append(joint)
        said = [p for p in parts if p.startswith("clearance at") or p.startswith("no clearance")]
        if known:
            text = "clearance at " + ", ".join(sorted(joints)) if joints else "no clearance"
            assert len(said) == 1 and said[0].startswith(text), (kind, parts)
            assert said[0] == text or not joints, (kind, parts)


def test_a_zip_group_case_chosen_by_its_label_is_titled_with_the_values_it_ran(shipped):
    """configs/paper.yaml's case ``coating_joints=B`` was titled with the label alone, not
    the coatings it ran with (issue 45)."""
    from clearsweep.plotting import figure

    with xr.open_dataset(shipped["paper"]) as ds:
        ds = ds.load()
    title = " ".join(figure(ds, "wear-map", ["clearance_joints=AB", "coating_joints=B"])
                     .get_suptitle().split())
    assert "coating_joints=B (A_coating none, B_coating PTFE)" in title
    assert "clearance_joints=AB (A_clearance 0.25 mm, B_clearance 0.25 mm)" in title


# --------------------------------------------------------------------------- issue 45 item 6

def _drawn_figures(ds: xr.Dataset, name: str):
    """(kind, figure) of every figure the short results of shipped config ``name`` draw
    (:data:`FIGURES`), the reliability figure with and without ``--b10``."""
    from clearsweep.plotting import figure

    for kind, args in FIGURES[name](ds).items():
        options = dict(zip(args[::2], args[1::2]))
        selects = [b for a, b in zip(args[::2], args[1::2]) if a == "--select"]
        for b10 in ((False, True) if kind == "reliability" else (False,)):
            yield (f"{kind}{' --b10' if b10 else ''}",
                   figure(ds, kind, selects or None, x=options.get("--x"), y=options.get("--y"),
                          metric=options.get("--metric"), b10=b10))


@pytest.mark.slow      # every figure of 18 files at 100 dpi, drawn twice: about 2 min on two cores
@pytest.mark.parametrize("name", sorted(FIGURES))
def test_no_legend_of_a_shipped_configs_figure_covers_its_data(shipped, name):
    """A legend's box, drawn, against the lines, markers, bars, error bars and scatter points
    of every panel it lies over (tests/test_figure_layout.py, ``legends_over_data``), and
    every text inside the figure and apart (``layout_problems``), in every figure the shipped
    config's short results draw. Before: the case legends of the slider, forces and spectrum
    figures of coating_clearance, contact_laws, paper and revolute_clearance covered their
    lines (a gallery legend covered PTFE's error bars, issue 45); their wear-polar legend ran
    off the figure's sides, and a life figure's axis label into its title."""
    from test_figure_layout import layout_problems, legends_over_data

    with xr.open_dataset(shipped[name]) as ds:
        ds = ds.load()
    problems = {kind: found for kind, fig in _drawn_figures(ds, name)
                if (found := legends_over_data(fig) + layout_problems(fig))}
    assert not problems, problems
