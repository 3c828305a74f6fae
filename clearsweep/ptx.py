"""The CUDA batch kernel built for a GPU without one: PTX from NVVM, resources from ptxas.

:func:`compile_run_cases_ptx` compiles ``core.device.run_cases`` to PTX for a compute
capability (sm_90 by default) with numba-cuda's NVVM, on a machine without a CUDA device:
numba-cuda asks the current device for its compute capability when it compiles the
device functions that the kernel calls, so a stand-in device of the requested capability
answers while the compile runs. :func:`ptxas_report` assembles the PTX with the ``ptxas``
of the ``nvidia-cuda-nvcc`` wheel (what ``numba-cuda[cu12]`` installs) and reads its
resource figures per thread: registers, stack frame, spill stores and loads.

``python -m clearsweep.ptx [PTX_FILE] [--arch sm_XY] [--layout soa|aos|soa-local|soa-one-evaluate] [--capacity N]
[--joints A,B]`` prints them for the kernel built for a joint set (``core.jointset``; default
every joint, the generic build), keeping the PTX text in PTX_FILE if given
(tests/test_ptx.py checks them in CI; benchmarks/README.md records them).
"""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

#: The compute capability that the checks build for (H100: sm_90).
DEFAULT_CC = (9, 0)


#: Dimensions of run_cases' arguments (the case first) but the work arrays', by name.
_NDIM = {"p": 2, "jp": 3, "y0": 2, "n_steps": 1, "save_every": 1, "wmap": 4, "proj": 4,
         "wvol": 2, "info": 2, "stats": 3, "track": 2, "sec": 3, "rows_t": 2, "rows_y": 3, "rows_d": 3,
         "rows_wmax": 3, "pcols": 1, "geom": 1}
#: Where the structure-of-arrays kernel's dimensions differ (``core.device.soa_kernel``):
#: the shared parameter row jp, the maps' rows of the batch's clearance joints.
_NDIM_SOA = {"jp": 1, "wmap": 3, "proj": 3}
#: run_cases' int64 arguments but the work arrays' (``rk4.INT_WORK``).
_INT = frozenset({"n_steps", "save_every", "info", "pcols", "geom"})


def run_cases_signature(layout: str = "aos") -> tuple:
    """Numba types of ``run_cases``' arguments, in order (``core.device.ARGS``: C-contiguous
    arrays with the case as first axis, as ``gpu._allocate`` builds them): p, jp, y0,
    n_steps, save_every; the results wmap, proj, wvol, info, stats, track, sec; the work arrays
    of ``rk4.work_shapes``; the row placeholders rows_t, rows_y, rows_d, rows_wmax."""
    from numba import types

    from .core.device import ARGS
    from .core.rk4 import INT_WORK, work_shapes

    ndim = dict(_NDIM, **{name: 1 + len(shape) for name, shape in work_shapes(0, 1).items()})
    if layout != "aos":
        ndim.update(_NDIM_SOA)
    ints = _INT | INT_WORK
    return tuple(types.Array(types.int64 if name in ints else types.float64, ndim[name], "C")
                 for name in ARGS)


class _StandInDevice:
    """What numba-cuda's dispatcher reads of the current device while compiling."""

    def __init__(self, cc: tuple[int, int]):
        self.compute_capability = cc
        self.id = 0
        self.name = f"sm_{cc[0]}{cc[1]} (no device: compile only)".encode()


def _device_of_capability(cc: tuple[int, int]):
    """numba-cuda's dispatcher sees a device of capability cc (restored on exit)."""
    from .core.numba_compat import stand_in_device

    return stand_in_device(_StandInDevice(cc))


#: The launch capacity that the structure-of-arrays figures are built for (any of
#: ``core.device.CAPACITIES``: the capacity only scales constant strides).
DEFAULT_CAPACITY = 16384


def compile_run_cases_ptx(cc: tuple[int, int] = DEFAULT_CC, layout: str = "soa",
                          capacity: int = DEFAULT_CAPACITY, spec: int | None = None) -> str:
    """PTX of the batch kernel of ``layout`` built for the joint set ``spec``
    (``core.jointset``; None: every joint, the generic build) for compute capability cc:
    "soa", ``core.device.soa_kernel(capacity, spec)`` (the default), "soa-local" (the same
    with its fixed-size work arrays in each thread's local memory), "soa-one-evaluate" (the
    same as "soa", each step's evaluations at one call site: ``core.onestep``), or "aos",
    ``core.device.aos_kernel(spec)`` (the arrays of either have the same dimensions). Needs
    numba-cuda with NVVM (``pip install numba-cuda[cu12]``), no device. About a minute on
    one core: the whole kernel is compiled, every device function inlined."""
    from numba import cuda

    from .core import device

    if device.SIMULATED:
        raise RuntimeError("NUMBA_ENABLE_CUDASIM is set: the simulator compiles no PTX")
    if layout not in device.LAYOUTS:
        raise ValueError(f"layout {layout!r}: expected one of {device.LAYOUTS}")
    from .core.jointset import ALL

    spec = ALL if spec is None else spec
    kernel = (device.aos_kernel(spec) if layout == "aos"
              else device.soa_kernel(capacity, spec, local=layout == "soa-local",
                                     one_evaluate=layout == "soa-one-evaluate"))
    with _device_of_capability(cc):
        ptx, _ = cuda.compile_ptx(kernel.py_func, run_cases_signature(layout), cc=cc)
    return ptx


def build_kernel(layout: str = "soa", capacity: int = DEFAULT_CAPACITY) -> float:
    """Compile the batch kernel of ``layout`` (and ``capacity``) for the current CUDA device
    with the launch signature, as a sweep's first launch would; seconds taken. With
    ``CLEARSWEEP_CUDA_CACHE=1`` the build lands in Numba's on-disk cache, which later
    processes load (benchmarks/device_suite.py builds each kernel so, in parallel)."""
    from .core import device

    kernel = (device.run_cases if layout == "aos"
              else device.soa_kernel(capacity, local=layout == "soa-local",
                                     one_evaluate=layout == "soa-one-evaluate"))
    began = time.perf_counter()
    kernel.compile(run_cases_signature(layout))
    return time.perf_counter() - began


def find_ptxas() -> Path:
    """The ``ptxas`` of the nvidia-cuda-nvcc wheel; FileNotFoundError saying what to install."""
    spec = importlib.util.find_spec("nvidia.cuda_nvcc") if importlib.util.find_spec("nvidia") else None
    for root in (spec.submodule_search_locations or []) if spec else []:
        exe = Path(root) / "bin" / ("ptxas.exe" if sys.platform == "win32" else "ptxas")
        if exe.is_file():
            return exe
    raise FileNotFoundError("no ptxas: the nvidia-cuda-nvcc wheel is not installed "
                            "(pip install 'numba-cuda[cu12]', or clearsweep's 'test' extra)")


@dataclass(frozen=True)
class PtxasReport:
    """ptxas -v resource figures of a kernel, per thread."""

    arch: str
    registers: int
    stack_bytes: int
    spill_store_bytes: int
    spill_load_bytes: int
    seconds: float
    log: str

    def line(self) -> str:
        return (f"{self.arch}: {self.registers} registers, {self.stack_bytes} bytes stack frame, "
                f"{self.spill_store_bytes} bytes spill stores, {self.spill_load_bytes} bytes "
                f"spill loads per thread (ptxas {self.seconds:.0f} s)")


_FRAME = re.compile(r"(\d+) bytes stack frame, (\d+) bytes spill stores, (\d+) bytes spill loads")
_REGS = re.compile(r"Used (\d+) registers")


def parse_ptxas(log: str, arch: str = "sm_90", seconds: float = 0.0) -> PtxasReport:
    """The kernel entry's figures from a ``ptxas -v`` log (one entry function: run_cases).
    ValueError if the log holds none."""
    entry = log.split("Compiling entry function", 1)
    if len(entry) != 2:
        raise ValueError(f"no entry function in the ptxas log:\n{log}")
    frame = _FRAME.search(entry[1])
    regs = _REGS.search(entry[1])
    if frame is None or regs is None:
        raise ValueError(f"no resource figures in the ptxas log:\n{log}")
    return PtxasReport(arch, int(regs.group(1)), int(frame.group(1)), int(frame.group(2)),
                       int(frame.group(3)), seconds, log)


def ptxas_report(ptx: str, arch: str = "sm_90") -> PtxasReport:
    """Assemble ptx for arch with the wheel's ``ptxas -v``; its resource figures.
    RuntimeError with ptxas' messages if it fails."""
    exe = find_ptxas()
    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / "kernel.ptx"
        src.write_text(ptx)
        began = time.perf_counter()
        proc = subprocess.run([str(exe), f"-arch={arch}", "-v", str(src), "-o",
                               str(Path(tmp) / "kernel.cubin")], capture_output=True, text=True)
        seconds = time.perf_counter() - began
    log = proc.stdout + proc.stderr
    if proc.returncode != 0:
        raise RuntimeError(f"ptxas failed (exit {proc.returncode}):\n{log[-4000:]}")
    return parse_ptxas(log, arch, seconds)


def parse_args(argv: list[str] | None = None):
    """The command line of ``python -m clearsweep.ptx``: an optional path to keep the PTX in
    and the compute capability to build for."""
    import argparse

    from .core.device import CAPACITIES

    parser = argparse.ArgumentParser(
        prog="python -m clearsweep.ptx",
        description="Compile core.device.run_cases to PTX for a GPU without one (numba-cuda's "
                    "NVVM, about a minute) and print ptxas' resource figures per thread: "
                    "registers, stack frame, spill stores and loads.")
    parser.add_argument("output", nargs="?", type=Path, default=None,
                        help="a file to keep the PTX text in (default: not kept)")
    parser.add_argument("--arch", default=f"sm_{DEFAULT_CC[0]}{DEFAULT_CC[1]}",
                        help="the compute capability to build for, as sm_XY "
                             "(default: %(default)s, an H100)")
    parser.add_argument("--layout", choices=("soa", "aos", "soa-local", "soa-one-evaluate"),
                        default="soa",
                        help="the device layout: structure of arrays (the default), case by "
                             "case, the work arrays in each thread's local memory, or one "
                             "evaluate call site per step")
    parser.add_argument("--capacity", type=int, default=DEFAULT_CAPACITY,
                        help="the launch capacity of the soa layout (default: %(default)s; "
                             f"one of {', '.join(map(str, CAPACITIES))})")
    parser.add_argument("--joints", default="all",
                        help="the joint set to build the kernel for: the joints with "
                             "clearance, comma-separated (A,B), 'none', or 'all' (default: "
                             "%(default)s, the generic build)")
    parser.add_argument("--mechanism", choices=("rssp", "slider_crank"), default="rssp",
                        help="the mechanism the kernel is built for (default: %(default)s)")
    args = parser.parse_args(argv)
    if args.capacity not in CAPACITIES:
        parser.error(f"--capacity: expected one of {', '.join(map(str, CAPACITIES))}, "
                     f"got {args.capacity}")
    match = re.fullmatch(r"sm_(\d+)(\d)", args.arch)
    if match is None:
        parser.error(f"--arch: expected sm_XY (for example sm_90), got {args.arch!r}")
    args.cc = (int(match.group(1)), int(match.group(2)))
    from .core import jointset

    try:
        args.spec = (jointset.ALL if args.joints == "all" else jointset.NONE if args.joints == "none"
                     else jointset.named(*(name.strip() for name in args.joints.split(","))))
    except ValueError as exc:
        parser.error(f"--joints: {exc}")
    if args.mechanism == "slider_crank":
        args.spec |= jointset.SLIDER_CRANK
    if args.output is not None and args.output.is_dir():
        parser.error(f"output: {str(args.output)!r} is a folder; give a file path for the PTX")
    return args


def main(argv: list[str] | None = None) -> None:
    """Print the figures of run_cases (``--help``: the arguments; argv: sys.argv[1:] by
    default)."""
    args = parse_args(argv)
    began = time.perf_counter()
    ptx = compile_run_cases_ptx(args.cc, args.layout, args.capacity, args.spec)
    from .core.jointset import label

    what = "%s, capacity %d" % (args.layout, args.capacity) if args.layout != "aos" else "aos"
    what += f", clearance at {label(args.spec)}"
    print(f"PTX ({what}): {len(ptx):,} characters in {time.perf_counter() - began:.0f} s")
    if args.output is not None:
        args.output.write_text(ptx)
        print(f"PTX kept in {args.output}")
    print(ptxas_report(ptx, args.arch).line())


if __name__ == "__main__":
    main()
