"""The CUDA batch kernel built for a GPU without one (clearsweep.ptx): run_cases compiles to
PTX for sm_90 with numba-cuda's NVVM and assembles with the wheel's ptxas; its registers and
spills per thread are reported and bounded.

The figures show in the test report (``pytest -rA``: the "PTX" section). Needs numba-cuda
with the CUDA 12 wheels (clearsweep's ``test`` extra); about a minute on one core.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from clearsweep import ptx
from clearsweep.core import jointset

#: Spill stores [bytes per thread] for sm_90 of the batch kernel that sweeps launch, the
#: structure-of-arrays one (``python -m clearsweep.ptx``, capacity 16384): 2,052 with the
#: batch's shared parameter row and the maps of its clearance joints alone (issue 43 items 2
#: and 4), 2,532 before (issue 43 item 1; the case-by-case run_cases, ``--layout aos``,
#: 3,100: 1,224 before joint P, whose corner contacts NVVM inlines with the rest of the
#: right-hand side at each of its call sites:
#: 1,788 with P's right-hand side compiled out; 932 before joint O, the in-step peaks and
#: the Poincare sections, 916 before the contact laws; 4,544 before the kernel was reshaped
#: for the GPU, 2,696 before core/device.py handed advance its fixed-shape rows through
#: ``block`` and evaluate formed the frames in each contact on the device, see
#: benchmarks/README.md). The goal, below 1,024, is not met (benchmarks/README.md: what
#: stands in the way); the bound guards against the arrangements that double the spill, with
#: about 100 bytes of room for ptxas' allocation moving with unrelated edits.
#: Issue 41's physics raised it to 4,212 bytes: the guide's faces (3e06461, merged in
#: 0bbdb9f: 2,532 -> 4,044 on its own), whose ``prismatic.contact`` held both corners'
#: geometries of an edge line through the corners' forces; the seats' friction, the stop
#: and the bearing film cost nothing (a9b5643: 4,044). With the corners' geometries formed
#: one at a time (``prismatic.edge_loads``), 2,608 bytes, and with ``prismatic.accept``
#: reading the face's other line's penetrations alone (``line_deltas``), 2,456 (issue 43;
#: benchmarks/README.md). The bushing's five packed columns (N_JP 27) and the guide's own
#: two made it 2,536; ``dynamics.evaluate`` split into ``applied_loads``, ``assemble_qdd``
#: and ``end_diagnostics`` 2,648 (and the A,B build 1,192 -> 992); the integrators' dispatch
#: on the joint's type (core/jointkinds.py) left both as they were. The bound is that with
#: 5 % of room for ptxas' allocation moving with unrelated edits. The sub-step's acceptance
#: shared by the step's two attempts (``rk4.accept_end``): 2,424 -> 2,048.
SPILL_STORE_BOUND = 2780

#: The issue's goal for the two-clearance cases' build (A,B): below 1,024 bytes of spill
#: stores per thread; 992 since ``dynamics.evaluate`` was split (benchmarks/README.md), and
#: with the slider-crank's guide bit (p kept at an even length, N_P 52: at 51, 1,000); 968
#: since the joint types' elastic law, 996 since their stiff rate, became protocol functions;
#: 932 since the step's two attempts share their sub-step's acceptance (``rk4.accept_end``).
AB_SPILL_STORE_GOAL = 1024

#: The kernel built for clearance at A and B alone (the two-clearance cases' joint set, O and
#: P folded away: core/jointset.py) spills less than the generic one: 1,252 bytes against
#: 2,532 structure-of-arrays, 1,660 against 3,076 case by case (benchmarks/README.md,
#: "Builds per joint set"); 992 since evaluate was split, within the goal below.

LOG = """\
ptxas info    : Compiling entry function '_Z9run_cases' for 'sm_90'
ptxas info    : Function properties for _Z9run_cases
    1168 bytes stack frame, 4544 bytes spill stores, 10124 bytes spill loads
ptxas info    : Used 255 registers, used 0 barriers, 1168 bytes cumulative stack size
ptxas info    : Function properties for __internal_accurate_pow
    0 bytes stack frame, 0 bytes spill stores, 0 bytes spill loads
"""


def test_parse_ptxas_reads_the_entry_function():
    rep = ptx.parse_ptxas(LOG)
    assert (rep.registers, rep.stack_bytes, rep.spill_store_bytes, rep.spill_load_bytes) == (
        255, 1168, 4544, 10124)
    with pytest.raises(ValueError, match="no entry function"):
        ptx.parse_ptxas("ptxas info    : 0 bytes gmem\n")


def test_signature_matches_the_arrays_the_backend_allocates():
    """run_cases' PTX signature is the one gpu.py launches it with."""
    from numba import typeof

    from clearsweep.config import DEFAULTS, resolve_materials
    from clearsweep.gpu import _allocate
    from clearsweep.params import pack

    cfg = DEFAULTS.replace(solver__duration=0.001)
    from clearsweep.core.device import ARGS

    arrays = _allocate([pack(cfg, resolve_materials(cfg))])
    assert list(arrays) == list(ARGS)
    assert tuple(typeof(arrays[name]) for name in ARGS) == ptx.run_cases_signature()
    soa = _allocate([pack(cfg, resolve_materials(cfg))], "soa")
    assert tuple(typeof(soa[name]) for name in ARGS) == ptx.run_cases_signature("soa")


def test_block_addresses_what_numpy_slices():
    """run_cases hands advance its fixed-shape slices through core.device.block, built with
    the kernel's own code generation, here registered for the CPU: the same elements as
    numpy's slices of the case, for every case and block."""
    import numpy as np
    from numba import njit
    from numba.core.extending import intrinsic

    from clearsweep.core import device
    from clearsweep.core.layout import N_S, N_Y

    block = intrinsic(device.block_typer)

    @njit
    def blocks(vec, cstate, mats, ints, i):
        return (block(vec, i, 0, (N_Y,)).copy(), block(vec, i, 6, (N_Y,)).copy(),
                block(cstate, i, 1, (2, N_S)).copy(), block(mats, i, 2, (6, 6)).copy(),
                block(ints, i, 1, (3,)).copy())

    rng = np.random.default_rng(1)
    vec = rng.random((3, 7, N_Y))
    cstate = rng.random((3, 2, 2, N_S))
    mats = rng.random((3, 3, 6, 6))
    ints = rng.integers(0, 1000, (3, 2, 3))
    for i in range(3):
        got = blocks(vec, cstate, mats, ints, i)
        want = (vec[i, 0], vec[i, 6], cstate[i, 1], mats[i, 2], ints[i, 1])
        for g, w in zip(got, want):
            assert g.shape == w.shape and g.dtype == w.dtype
            assert np.array_equal(g, w)


def test_soa_block_addresses_what_numpy_slices():
    """The structure-of-arrays kernel hands advance strided views through
    core.device.soa_block, built with the kernel's own code generation, here registered for
    the CPU: element e of block k of case i at (k * size + e) * capacity + i, the same
    elements as numpy's slices of the case-first array, for every case and block, with the
    shape literal or read at run time (the wear map's bins); writes land in the batch."""
    import numpy as np
    from numba import njit
    from numba.core.extending import intrinsic

    from clearsweep.core import device
    from clearsweep.core.layout import N_S, N_Y
    from clearsweep.gpu import from_soa, to_soa

    soa_block = intrinsic(device.soa_block_typer)
    cap = 64

    @njit
    def blocks(vec, cstate, mats, ints, wmap, i):
        w = soa_block(wmap, i, 0, (2, wmap.shape[1], wmap.shape[2]), cap)
        w[1, 2, 3] = -1.0
        return (soa_block(vec, i, 0, (N_Y,), cap).copy(), soa_block(vec, i, 6, (N_Y,), cap).copy(),
                soa_block(cstate, i, 1, (2, N_S), cap).copy(),
                soa_block(mats, i, 2, (6, 6), cap).copy(), soa_block(ints, i, 1, (3,), cap).copy(),
                w.copy())

    rng = np.random.default_rng(1)
    n = 3
    aos = {"vec": rng.random((n, 7, N_Y)), "cstate": rng.random((n, 2, 2, N_S)),
           "mats": rng.random((n, 3, 6, 6)), "ints": rng.integers(0, 1000, (n, 2, 3)),
           "wmap": rng.random((n, 2, 5, 7))}
    soa = {name: to_soa(a, cap) for name, a in aos.items()}
    for name in aos:
        assert soa[name].shape == aos[name].shape[1:] + (cap,)
        assert np.array_equal(from_soa(soa[name], n), aos[name])
    for i in range(n):
        got = blocks(soa["vec"], soa["cstate"], soa["mats"], soa["ints"], soa["wmap"], i)
        aos["wmap"][i, 1, 2, 3] = -1.0
        want = (aos["vec"][i, 0], aos["vec"][i, 6], aos["cstate"][i, 1], aos["mats"][i, 2],
                aos["ints"][i, 1], aos["wmap"][i])
        for g, w in zip(got, want):
            assert g.shape == w.shape and g.dtype == w.dtype
            assert np.array_equal(g, w)
        assert np.array_equal(from_soa(soa["wmap"], n), aos["wmap"])


@pytest.mark.parametrize("present", [(True, True, False, False), (False, True, True, False),
                                     (False, False, True, True), (True, True, True, True)])
def test_soa_joint_rows_address_each_clearance_joints_rows(present):
    """The structure-of-arrays kernel's maps hold the batch's clearance joints' rows alone
    (gpu.joint_rows); core.device.soa_joint_rows, built with the kernel's own code
    generation and registered for the CPU here, reads and writes joint j's row r at row
    r0 + j * dj + r (r0 negative where joint A has none), the rows gpu.expand_joints gives
    back, for every case; the simulator's view addresses the same."""
    from numba import njit
    from numba.core.extending import intrinsic

    from clearsweep import gpu
    from clearsweep.core import device

    rows_of = intrinsic(device.soa_joint_rows_typer)
    cap, n, npolar, nazim = 64, 3, 5, 7
    rows = [gpu.MAP_ROWS[name](npolar) if c else 0 for name, c in zip(gpu.JOINT_NAMES, present)]
    r0, dj, total = gpu.joint_rows(rows)

    @njit
    def touch(a, i, r0, dj, npolar, rows):
        v = rows_of(a, i, r0, dj, npolar, cap)
        for j in range(4):
            for r in range(rows[j]):
                for c in range(v.shape[2]):
                    v[j, r, c] += 1000.0 * (j + 1) + 10.0 * r + 0.01 * c
        return v.shape

    compact = np.random.default_rng(2).random((total, nazim, cap))
    before = compact.copy()
    for i in range(n):
        assert touch(compact, i, r0, dj, npolar, np.array(rows)) == (4, npolar, nazim)
    for i in range(n):
        got = gpu.expand_joints(np.ascontiguousarray(compact[..., i]), r0, dj, rows, npolar)
        was = gpu.expand_joints(np.ascontiguousarray(before[..., i]), r0, dj, rows, npolar)
        for j, r in enumerate(rows):
            want = 1000.0 * (j + 1) + 10.0 * np.arange(r)[:, None] + 0.01 * np.arange(nazim)
            assert np.allclose(got[j, :r] - was[j, :r], want, rtol=0, atol=1e-9), (i, j)
    assert np.array_equal(compact[..., n:], before[..., n:])    # other cases untouched


def test_soa_capacities_agree_and_batches_fit():
    """gpu.py plans batches with the capacities core.device compiles for; a batch takes the
    smallest capacity that holds it, and never a capacity whose padded arrays exceed what
    fits the device's memory."""
    from clearsweep import gpu
    from clearsweep.core import device

    assert gpu.CAPACITIES == device.CAPACITIES and gpu.LAYOUTS == device.LAYOUTS
    assert (gpu.N_PJ, gpu.N_GEOM) == (device.N_PJ, device.N_GEOM)
    assert gpu.DEFAULT_LAYOUT == device.DEFAULT_LAYOUT == "soa"
    assert [gpu.capacity_for(n) for n in (1, 64, 65, 10_000, 30_000)] == [64, 64, 1024, 16384, 32768]
    with pytest.raises(ValueError, match="largest launch capacity"):
        gpu.capacity_for(40_000)
    assert gpu.batch_plan(10_000, 10**6) == (10_000, 16384)
    assert gpu.batch_plan(30_000, 10**6) == (30_000, 32768)
    assert gpu.batch_plan(100_000, 10**6) == (32768, 32768)
    assert gpu.batch_plan(10_000, 12_000) == (4096, 4096)     # 16384 padded would not fit
    assert gpu.batch_plan(5, 64) == (5, 64)
    assert gpu.batch_plan(100, 10) == (10, 64)                # the smallest, at worst
    for n, fit in ((10_000, 12_000), (3000, 5000), (70_000, 40_000)):
        size, cap = gpu.batch_plan(n, fit)
        assert size <= cap and (cap <= fit or cap == gpu.CAPACITIES[0])


def test_launch_refuses_shapes_that_run_cases_does_not_address():
    from clearsweep.config import DEFAULTS, resolve_materials
    from clearsweep.core import device
    from clearsweep.gpu import _allocate
    from clearsweep.params import pack

    cfg = DEFAULTS.replace(solver__duration=0.001)
    arrays = _allocate([pack(cfg, resolve_materials(cfg))])
    for name, shape in device.FIXED_SHAPES.items():
        assert arrays[name].shape[1:] == shape
    arrays["vec"] = arrays["vec"][:, :, :-1]
    with pytest.raises(ValueError, match="argument vec"):
        device.launch(arrays)
    del arrays["vec"]
    with pytest.raises(ValueError, match="missing \\['vec'\\]"):
        device.launch(arrays)
    soa = _allocate([pack(cfg, resolve_materials(cfg))], "soa")
    assert soa["p"].shape[-1] == 64 and soa["n_steps"].shape == (1,)
    for name, shape in device.FIXED_SHAPES.items():
        if name not in device.SOA_FREE and name not in device.BATCH_ROWS:
            assert soa[name].shape == shape + (64,)
    for name, shape in device.BATCH_ROWS.items():
        assert soa[name].shape == shape
    soa["pcols"] = soa["pcols"][:-1]
    with pytest.raises(ValueError, match="argument pcols: shape"):
        device.launch(soa, "soa")
    soa["pcols"] = np.zeros(device.N_PJ, dtype=np.int64)
    soa["stats"] = soa["stats"][..., :32]
    with pytest.raises(ValueError, match="argument stats: capacity 32"):
        device.launch(soa, "soa")
    with pytest.raises(ValueError, match="device layout 'xyz'"):
        device.launch(soa, "xyz")


def test_help_prints_usage_and_writes_no_file(tmp_path):
    """``python -m clearsweep.ptx --help`` prints its usage and exits 0 without compiling; it
    once took "--help" for the path to keep the PTX in and wrote a file of that name."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = str(Path(ptx.__file__).resolve().parents[1])
    proc = subprocess.run([sys.executable, "-m", "clearsweep.ptx", "--help"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120,
                          env={**os.environ, "PYTHONPATH": root})
    assert proc.returncode == 0, proc.stderr
    assert "usage: python -m clearsweep.ptx" in proc.stdout
    assert "output" in proc.stdout and "--arch" in proc.stdout
    assert list(tmp_path.iterdir()) == []


def test_main_keeps_the_ptx_where_asked(tmp_path, monkeypatch, capsys):
    """main's optional path keeps the PTX text; --arch picks the capability handed to the
    compile and to ptxas (the compile itself stubbed: it takes about a minute)."""
    calls = []

    def compile_stub(cc=ptx.DEFAULT_CC, layout="soa", capacity=ptx.DEFAULT_CAPACITY, spec=None):
        calls.append((cc, spec))
        layouts.append((layout, capacity))
        return "// PTX text"

    layouts: list = []

    monkeypatch.setattr(ptx, "compile_run_cases_ptx", compile_stub)
    monkeypatch.setattr(ptx, "ptxas_report", lambda text, arch="sm_90": ptx.parse_ptxas(
        LOG.replace("sm_90", arch), arch))
    out = tmp_path / "kernel.ptx"
    ptx.main([str(out), "--arch", "sm_80"])
    assert out.read_text() == "// PTX text"
    assert calls == [((8, 0), jointset.ALL)]
    assert "sm_80: 255 registers" in capsys.readouterr().out
    ptx.main([])
    assert calls[-1] == (ptx.DEFAULT_CC, jointset.ALL)
    ptx.main(["--layout", "aos"])
    ptx.main(["--capacity", "1024"])
    assert layouts == [("soa", 16384), ("soa", 16384), ("aos", 16384), ("soa", 1024)]
    capsys.readouterr()
    # --joints picks the joint set the kernel is built for
    ptx.main(["--joints", "A,B"])
    assert calls[-1] == (ptx.DEFAULT_CC, jointset.named("A", "B"))
    assert "clearance at A,B)" in capsys.readouterr().out
    ptx.main(["--joints", "none"])
    assert calls[-1] == (ptx.DEFAULT_CC, jointset.NONE)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kernel.ptx"]


@pytest.mark.parametrize("argv, message", [
    (["--arch", "90"], "--arch: expected sm_XY"),
    (["--no-such-option"], "unrecognized arguments"),
    (["--capacity", "1000"], "--capacity: expected one of"),
    (["--layout", "rows"], "invalid choice"),
    (["."], "is a folder"),
    (["--joints", "A,Q"], "--joints: no joint 'Q'"),
])
def test_bad_arguments_are_refused_before_the_compile(argv, message, monkeypatch, capsys):
    monkeypatch.setattr(ptx, "compile_run_cases_ptx", lambda *a, **k: pytest.fail("compiled"))
    with pytest.raises(SystemExit) as exc:
        ptx.main(argv)
    assert exc.value.code == 2
    assert message in capsys.readouterr().err


def _build_key(ptxas) -> str:
    """What the PTX build depends on: every clearsweep source file, the compilers' versions
    and the ptxas used. The same key builds the same PTX and the same ptxas figures."""
    import hashlib
    from importlib import metadata
    from pathlib import Path

    root = Path(ptx.__file__).resolve().parent
    digest = hashlib.sha256(str(ptxas).encode())
    for path in sorted(root.rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes())
    for dist in ("numba", "numba-cuda", "nvidia-cuda-nvcc-cu12", "nvidia-cuda-nvrtc-cu12"):
        try:
            digest.update(f"{dist}={metadata.version(dist)}".encode())
        except metadata.PackageNotFoundError:
            digest.update(f"{dist}=none".encode())
    return digest.hexdigest()


def _report(request, spec: int) -> ptx.PtxasReport:
    """ptxas' figures for run_cases built for the joint set ``spec``, built once per change
    of what the build depends on (:func:`_build_key`): kept in pytest's cache
    (.pytest_cache), as Numba keeps its compiled kernels, so a warm run skips the minutes of
    NVVM and ptxas."""
    try:
        ptxas = ptx.find_ptxas()
    except FileNotFoundError as exc:
        pytest.fail(str(exc))
    cache = getattr(request.config, "cache", None)        # None under -p no:cacheprovider
    key = f"clearsweep/ptxas_report/{_build_key(ptxas)}/{spec}"
    cached = cache.get(key, None) if cache is not None else None
    if cached is not None:
        return ptx.PtxasReport(**cached)
    built = ptx.ptxas_report(ptx.compile_run_cases_ptx(spec=spec))
    if cache is not None:
        cache.set(key, dataclasses.asdict(built))
    return built


@pytest.fixture(scope="module")
def report(request):
    """The generic build's figures (every joint tested at run time)."""
    return _report(request, jointset.ALL)


@pytest.mark.slow
def test_run_cases_compiles_and_assembles_for_sm_90(report, record_property, capsys):
    record_property("ptxas", report.line())
    with capsys.disabled():
        print(f"\nPTX {report.line()}")
    assert report.arch == "sm_90"
    assert 0 < report.registers <= 255
    assert report.spill_store_bytes < SPILL_STORE_BOUND, report.line()


@pytest.mark.slow
def test_the_build_for_a_and_b_spills_less_than_the_generic_one(request, report, capsys):
    """Folding O and P away (the two-clearance cases' build on the device) spills less."""
    built = _report(request, jointset.named("A", "B"))
    with capsys.disabled():
        print(f"\nPTX (clearance at A,B) {built.line()}")
    assert 0 < built.registers <= 255
    assert built.spill_store_bytes < report.spill_store_bytes, (built.line(), report.line())
    assert built.spill_store_bytes < AB_SPILL_STORE_GOAL, built.line()
