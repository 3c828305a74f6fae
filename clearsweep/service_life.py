"""Service life by cycle jumps with geometry update (docs/service_life.md).

A life run alternates a dynamic block (``life.block_revolutions`` crank revolutions
simulated from a seated start on the worn sockets; the wear map records the block's wear)
with a jump that adds dN revolutions' worth of that wear to the map, dN chosen so that no
bin's depth grows by more than ``life.jump_clearance_fraction`` of the joint's clearance,
nor, while a bin still has coating, by more than ``life.jump_coating_fraction`` of its
remaining coating (Mukras et al., Wear 268, 2010; Flores, Mech. Mach. Theory 44, 2009).
The next block starts from the worn map; where a bin is worn through its coating, the
kernel's contact uses the base material there. It stops at ``life.cycles`` revolutions,
when a limit is crossed, or after ``life.max_blocks`` blocks.
"""

from __future__ import annotations

import functools
import json
import math
import os
import time
import zipfile
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import xarray as xr

from .budget import (
    MAX_OUTPUT_BYTES,
    Estimate,
    check_budget,
    duration_text,
    estimate,
    format_bytes,
    life_seconds,
    memory_limit,
    plan_costs,
    steps_text,
)
from .config import Config, ConfigError, dump_config, load_config, parse_yaml, resolve_materials
from .core import layout as L
from .dataset import ForeignLock, history_line, lock_exclusively, replaced_on_success, with_command_line
from .jointtypes import describe
from .params import Packed, identity_changes, joint_attributes, joint_configs, kernel_build, pack, run_identity
from .simulation import KernelRun, preflight, prepare_kernel, run_kernel
from .variables import JOINTS, format_length, length_unit
from .version import IDENTITY_VERSION

#: A bin counts as worn for the mean depth when deeper than this fraction of the largest.
WORN_FRACTION = 1e-2

#: Criteria of a life run: name -> (config key, the row variable it watches).
CRITERIA = {
    "clearance_growth": ("life.max_clearance_growth", "wear_depth_max"),
    "normal_force": ("life.max_normal_force", "normal_force_peak_settled"),
    "rms_acceleration": ("life.max_rms_acceleration", "slider_acceleration_rms_settled"),
    "motion_error": ("life.max_motion_error", "slider_motion_error_settled"),
}

#: Most steps between the saved rows of a block (rows the motion error is read from).
BLOCK_ROW_STRIDE = 10


def row_stride(n_block: int, most: int = BLOCK_ROW_STRIDE) -> int:
    """Steps between the saved rows of a block of ``n_block`` steps: the largest divisor of
    ``n_block`` up to ``most``, so that saving rows never lengthens the block (the kernel
    rounds the steps up to whole rows). The steps and statistics do not depend on it."""
    return next(s for s in range(min(most, n_block), 0, -1) if n_block % s == 0)


def block_steps(cfg: Config) -> int:
    """RK4 steps of one dynamic block of a life run: ``life.block_revolutions`` revolutions
    in whole steps."""
    period = 60.0 / cfg.mechanism.speed_rpm
    return int(math.ceil(cfg.life.block_revolutions * period / cfg.solver.dt - 1e-9))


def block_config(cfg: Config) -> Config:
    """The config of one dynamic block of a life run: :func:`block_steps` steps, with rows
    every few steps (the motion error is read from them)."""
    n_block = block_steps(cfg)
    return cfg.replace(**{"solver__duration": n_block * cfg.solver.dt,
                          "solver__save_every": row_stride(n_block)})


#: Wear maps a life run holds besides its snapshots: the map, the one before the block,
#: the kernel's, the rate and the one after a jump.
_WORKING_MAPS = 5
#: Copies of each snapshot a life run holds at its peak, an upper bound: the list kept,
#: the array the checkpoint and the dataset stack them into, and the writing. Measured: 2.25
#: (40 blocks on a 300 x 600 map, 16 snapshots kept: 87 MiB of peak memory above 2 kept,
#: 2.75 MiB a map).
_SNAPSHOT_COPIES = 3
#: float64 of one block's row in a checkpoint (scalars, and two per joint).
_ROW_VALUES = 32


@dataclass(frozen=True)
class LifeCost:
    """What a life run holds besides one block's arrays, counted before it runs.

    Attributes
    ----------
    snapshots : int
        Wear-map snapshots kept at most: ``min(life.snapshots, life.max_blocks) + 1``
        (the final map is always kept).
    map_bytes : int
        One wear map of every joint (N_JOINTS x polar x azimuth float64).
    memory_bytes : int
        Its largest memory beyond the block's arrays: the snapshots :data:`_SNAPSHOT_COPIES`
        times (the list kept, the array the checkpoint and the dataset stack them into, and
        what writing them takes) and the working maps.
    checkpoint_bytes : int
        The checkpoint at its largest: the map, the snapshots and every block's row; it is
        rewritten after every block.
    """

    snapshots: int
    map_bytes: int
    memory_bytes: int
    checkpoint_bytes: int


def life_cost(cfg: Config) -> LifeCost:
    """The snapshots, memory and checkpoint of the life run ``cfg`` at ``life.max_blocks``
    blocks (the map size x the snapshots actually kept x every joint)."""
    lc = cfg.life
    polar, azimuth = cfg.wear.map
    map_bytes = L.N_JOINTS * polar * azimuth * 8
    kept = min(lc.snapshots, lc.max_blocks) + 1
    rows = lc.max_blocks * _ROW_VALUES * 8
    return LifeCost(kept, map_bytes, (_SNAPSHOT_COPIES * kept + _WORKING_MAPS) * map_bytes + rows,
                    (kept + 1) * map_bytes + rows)


def check_life_cost(cfg: Config, block: Estimate, *, allow_large: bool = False,
                    source: str = "<config>") -> LifeCost:
    """Refuse a life run whose block arrays and snapshots together pass
    :data:`clearsweep.budget.MAX_OUTPUT_BYTES` (unless ``allow_large``; then more than this
    machine's memory), naming ``life.snapshots`` or ``wear.map``."""
    cost = life_cost(cfg)
    total = block.output_bytes + cost.memory_bytes
    limit = memory_limit(allow_large)
    if limit is None or total <= limit:
        return cost
    lc = cfg.life
    key, value = (("life.snapshots", lc.snapshots) if cost.snapshots > 2 * _WORKING_MAPS
                  else ("wear.map", list(cfg.wear.map)))
    where = (f"this machine's memory ({format_bytes(limit)} free)" if allow_large
             else format_bytes(MAX_OUTPUT_BYTES))
    raise ConfigError(
        key, value, f"a life run whose arrays fit in {where}: fewer life.snapshots or "
        "life.max_blocks, or a coarser "
        "wear.map" + ("" if allow_large else ", or --allow-large if the machine can take it"),
        source, got=f"{value!r} ({cost.snapshots:,} snapshots kept of a "
                    f"{cfg.wear.map[0]} x {cfg.wear.map[1]} wear map of {L.N_JOINTS} joints, "
                    f"{format_bytes(cost.map_bytes)} each: {format_bytes(total)} in all, with the "
                    f"block's {format_bytes(block.output_bytes)})")


#: The limits whose crossing follows the deepest bin's wear depth alone: what a plan can
#: forecast before a run (:func:`forecast_blocks`); the others depend on the dynamics.
DEPTH_LIMITS = ("clearance_growth", "wear_through")


@dataclass(frozen=True)
class LifeForecast:
    """The blocks a life run is expected to take, before it runs (:func:`forecast_blocks`).

    Attributes
    ----------
    blocks : int
        Blocks expected: the fewer of ``to_limits`` and ``to_cycles``, at most ``bound``.
    bound : int
        Most blocks: ``life.max_blocks``.
    limits : tuple of str
        The limits of :data:`DEPTH_LIMITS` the forecast walks to; empty where the run
        watches none of them (or nothing wears).
    to_limits : int
        Blocks to those limits, each jump growing the bin that limits it by its allowance
        whatever the wear rate; ``bound`` (or the blocks that reach ``life.cycles`` without
        a jump) where ``limits`` is empty.
    to_cycles : int or None
        Blocks to ``life.cycles`` at the wear pace of the plan costs
        (:class:`clearsweep.budget.WearPace`), each jump as long as the run's rule makes it
        at that pace; None where no pace is known (a joint other than a ball in its socket
        has clearance, nothing wears, or the plan costs have no pace).
    """

    blocks: int
    bound: int
    limits: tuple[str, ...]
    to_limits: int = 0
    to_cycles: int | None = None

    @property
    def known(self) -> bool:
        """Whether anything but the bound is forecast (a wear limit or ``life.cycles``)."""
        return bool(self.limits) or self.to_cycles is not None

    def describe(self, cfg: Config) -> str:
        """``"40 blocks to 1e+06 revolutions at the wear pace of benchmarks/calibrate_plan.py's
        reference run, ...; 101 to the wear limit (life.max_clearance_growth); ..."`` or
        ``"11 blocks to the wear limit (life.max_clearance_growth) at jumps of 1 % of the
        clearance, fewer if it reaches 1e+06 revolutions (40 at the reference's wear pace)
        or another limit first"``."""
        lc = cfg.life
        if not self.known:
            return (f"{self.blocks:,} blocks (no wear limit watched and no wear pace to forecast "
                    "from: life.cycles or a dynamic limit ends it, at a pace the plan cannot know)")
        if self.to_cycles is not None and self.to_cycles < self.to_limits:
            limits = (f"; {self.to_limits:,} to the wear limit{'s' if len(self.limits) > 1 else ''} "
                      f"({limit_keys(self.limits)})" if self.limits else "")
            return (f"{self.blocks:,} blocks to {lc.cycles:.4g} revolutions at the wear pace of "
                    "benchmarks/calibrate_plan.py's reference run, scaled by Archard's k and "
                    "the clearance (not by the loads or speed: a run that wears faster ends "
                    f"sooner){limits}; fewer if a dynamic limit comes first")
        coating = (f" or {100 * lc.jump_coating_fraction:.3g} % of the coating left"
                   if "wear_through" in self.limits else "")
        cycles = ("" if self.to_cycles is None else
                  f" ({self.to_cycles:,} at the reference's wear pace)")
        return (f"{self.blocks:,} blocks to the wear limit{'s' if len(self.limits) > 1 else ''} "
                f"({limit_keys(self.limits)}) at jumps of {100 * lc.jump_clearance_fraction:.3g} % "
                f"of the clearance{coating}, fewer if it reaches {lc.cycles:.4g} revolutions"
                f"{cycles} or another limit first")


def limit_keys(names) -> str:
    """``"life.max_clearance_growth, life.stop_at_wear_through"``: the config keys of the
    limits ``names`` (:data:`CRITERIA` and ``wear_through``)."""
    return ", ".join("life.stop_at_wear_through" if name == "wear_through" else CRITERIA[name][0]
                     for name in names)


#: The joint types whose wear a :class:`clearsweep.budget.WearPace` describes: a ball in
#: its socket (the reference run's joint B).
PACED_TYPES = ("spherical",)


def wear_pace(cfg: Config) -> list[tuple[float, float, float, float, float, float]] | None:
    """Each clearance joint's (clearance, coating, r0, K on the coating, r0, K on the base)
    at the plan costs' wear pace (:meth:`clearsweep.budget.WearPace.scaled`: Archard's k of
    the surface worn, times ``wear.amplification``, and the clearance); None where the pace
    is unknown: no pace in the plan costs, no wear, or a joint with clearance that is not a
    ball in its socket (the bearing O, the guide P, the slider-crank's pins A and B), whose
    pace no run has measured."""
    from .core.joints import row_types
    from .params import BASE_MATERIAL, surface_material

    pace = plan_costs().wear_pace
    if pace is None or not cfg.wear.enabled:
        return None
    materials = resolve_materials(cfg)
    out = []
    types = row_types(cfg.mechanism.kind == "slider_crank")
    for (_, joint), kind in zip(joint_configs(cfg), types, strict=True):
        if joint.clearance <= 0.0:
            continue
        if kind not in PACED_TYPES or getattr(joint, "type", kind) not in PACED_TYPES:
            return None
        k = joint.wear_coefficient
        k = surface_material(joint, materials).wear_coefficient_m2_per_N if k is None else k
        coated = joint.coating != "none"
        k_base = materials[BASE_MATERIAL].wear_coefficient_m2_per_N if coated else k
        amp = cfg.wear.amplification
        r0, growth = pace.scaled(joint.clearance, k * amp)
        r0_base, growth_base = pace.scaled(joint.clearance, k_base * amp)
        out.append((joint.clearance, joint.coating_thickness if coated else math.inf,
                    r0, growth, r0_base, growth_base))
    return out or None


def pace_rate(depth: float, coating: float, r0: float, growth: float, r0_base: float,
              growth_base: float) -> float:
    """The deepest bin's wear per revolution [m] at ``depth`` (:class:`clearsweep.budget.WearPace`:
    K / (K / r0 + h)), the coating's pace while it holds, the base's past it."""
    if depth >= coating:
        r0, growth = r0_base, growth_base
    if r0 <= 0.0 or growth <= 0.0:
        return 0.0
    return growth / (growth / r0 + depth)


def forecast_blocks(cfg: Config, every_limit: bool = False) -> LifeForecast:
    """The blocks the life run ``cfg`` takes, before it runs.

    Two walks, each by the run's own jump rule, and the fewer blocks of the two: the run
    ends at whichever end comes first.

    To the wear limits: a jump grows the bin whose wear rate limits it by exactly what
    :func:`jump_revolutions` allows (``life.jump_clearance_fraction`` of the clearance,
    less while coating remains), whatever the wear rate; taking that bin for the deepest
    one, the depth after each block follows from the config alone, and with it the block at
    which a limit of :data:`DEPTH_LIMITS` is crossed: ``life.max_clearance_growth`` and,
    with ``life.stop_at_wear_through``, the coating's thickness. Each clearance joint is
    walked as if it set the pace, and the slowest walk is taken: a jump ends where any
    joint's bin reaches its allowance, so the joint with the smallest allowance can cut
    every jump. ``every_limit``: a reliability member, which runs until every watched limit
    is crossed (the dynamic ones taken to come no later); else the first.

    To ``life.cycles``: when that comes is set by the wear rate, which the plan takes from
    the plan costs' wear pace (:func:`wear_pace`); each jump is the allowance over the
    pace's rate at the depth reached, cut to end one block short of ``life.cycles`` as the
    run cuts it, and the slowest joint's walk is taken.

    The forecast is at most ``life.max_blocks``, and at most the blocks that reach
    ``life.cycles`` without a jump. A dynamic limit, or a run that wears faster than the
    pace, ends sooner.
    """
    lc = cfg.life
    most = min(lc.max_blocks, max(1, math.ceil(lc.cycles / lc.block_revolutions - 1e-9)))
    watched = [name for name in DEPTH_LIMITS
               if (lc.max_clearance_growth is not None if name == "clearance_growth"
                   else lc.stop_at_wear_through)]
    joints = tuple((j.clearance, j.coating_thickness if j.coating != "none" else math.inf)
                   for _, j in joint_configs(cfg) if j.clearance > 0.0)
    paced = wear_pace(cfg) if joints else None
    to_cycles = None
    if paced is not None:
        to_cycles = max(_walk_to_cycles(c, coat, lc.jump_clearance_fraction,
                                        lc.jump_coating_fraction, most, float(lc.cycles),
                                        float(lc.block_revolutions), (r0, g, r0b, gb))
                        for c, coat, r0, g, r0b, gb in paced)
    if not (cfg.wear.enabled and joints and watched):
        bound = lc.max_blocks if to_cycles is None else min(to_cycles, lc.max_blocks)
        return LifeForecast(bound, lc.max_blocks, (), lc.max_blocks, to_cycles)
    per_limit = []
    for name in watched:
        found = [_walk(c, coat, lc.max_clearance_growth if name == "clearance_growth"
                       else coat, lc.jump_clearance_fraction,
                       lc.jump_coating_fraction, most) for c, coat in joints]
        # a jump ends where any clearance joint's bin has grown by its allowance, so the joint
        # with the smallest allowance sets the pace wherever it wears: its walk, the longest
        # (configs/reliability_joints.yaml, O and P at 0.1 mm against A and B at 0.25 mm:
        # about 24 blocks a member measured, 9 by A's or B's walk, 21 by O's or P's)
        per_limit.append(max(found))
    to_limits = max(per_limit) if every_limit else min(per_limit)
    blocks = to_limits if to_cycles is None else min(to_limits, to_cycles)
    return LifeForecast(blocks, lc.max_blocks, tuple(watched), to_limits, to_cycles)


def _allowance(reached: float, clearance: float, coating: float, clearance_fraction: float,
               coating_fraction: float) -> float:
    """What a jump may deepen a bin at depth ``reached`` by (:func:`jump_revolutions`)."""
    step = clearance_fraction * clearance
    if reached < coating:
        step = min(step, coating_fraction * max(coating - reached, coating_fraction * coating))
    return step


@functools.lru_cache(maxsize=1024)
def _walk(clearance: float, coating: float, depth: float, clearance_fraction: float,
          coating_fraction: float, most: int) -> int:
    """Blocks until the deepest bin of a joint reaches ``depth`` [m] (at most ``most``; inf
    depth: ``most``), each block but the last followed by the largest jump
    :func:`jump_revolutions` allows that bin."""
    reached, blocks = 0.0, 1
    while blocks < most and reached < depth * (1.0 - 1e-9):
        reached += _allowance(reached, clearance, coating, clearance_fraction, coating_fraction)
        blocks += 1
    return blocks


@functools.lru_cache(maxsize=1024)
def _walk_to_cycles(clearance: float, coating: float, clearance_fraction: float,
                    coating_fraction: float, most: int, cycles: float, revs: float,
                    pace: tuple[float, float, float, float]) -> int:
    """Blocks until a run whose deepest bin wears at ``pace`` (:func:`pace_rate`'s r0 and K
    on the coating and on the base) reaches ``cycles`` revolutions (at most ``most``), by
    :func:`_life`'s rule: each block of ``revs`` revolutions wears the bin at the rate of
    the depth it starts from, the jump after it is the bin's allowance
    (:func:`jump_revolutions`) over that rate, cut to end one block short of ``cycles``,
    and the run ends at the block after which another would pass ``cycles``."""
    rate = pace_rate(0.0, coating, *pace)
    reached, done, blocks = rate * revs, revs, 1
    while blocks < most and done + revs <= cycles * (1.0 + 1e-12):
        step = _allowance(reached, clearance, coating, clearance_fraction, coating_fraction)
        jump = step / rate if rate > 0.0 else math.inf
        jump = max(0.0, min(jump, cycles - done - revs))
        reached += jump * rate
        done += jump
        rate = pace_rate(reached, coating, *pace)
        reached += rate * revs
        done += revs
        blocks += 1
    return blocks


def life_plan_text(cfg: Config, source: str, *, allow_large: bool = False) -> str:
    """What ``clearsweep life CONFIG --dry-run`` prints: the blocks, their RK4 steps and
    memory, the snapshots and checkpoint, and the time of the longest run
    (``life.max_blocks`` blocks); nothing runs."""
    lc = cfg.life
    est = check_budget(block_config(cfg), allow_large=allow_large, source=source)
    cost = check_life_cost(cfg, est, allow_large=allow_large, source=source)
    return (f"{source}: a life run to {lc.cycles:.4g} revolutions, at most {lc.max_blocks:,} "
            f"blocks of {lc.block_revolutions:g} revolutions ({est.steps:,} RK4 steps each, "
            f"memory up to {est.describe()}); up to {cost.snapshots:,} wear-map snapshots of "
            f"{format_bytes(cost.map_bytes)}: memory up to "
            f"{format_bytes(est.output_bytes + cost.memory_bytes)} in all; a checkpoint of up "
            f"to {format_bytes(cost.checkpoint_bytes)} rewritten after every block (up to "
            f"{format_bytes(lc.max_blocks * cost.checkpoint_bytes)} written); "
            f"{life_time_text(cfg, est.steps)} (each block's progress line gives the time left "
            "at the pace so far); nothing run (--dry-run)")


def life_time_text(cfg: Config, steps_per_block: int) -> str:
    """The time of the life run ``cfg``, bound and expected (:func:`forecast_blocks`):
    ``"at most 2e+07 RK4 steps, at most about 1.33 min on one core (...); expected about
    11 s: 40 blocks to 1e+06 revolutions at the wear pace of ..."``."""
    steps = cfg.life.max_blocks * steps_per_block
    forecast = forecast_blocks(cfg)
    start = plan_costs().run_start_s
    bound = start + life_seconds(cfg, cfg.life.max_blocks, steps_per_block)
    expected = start + life_seconds(cfg, forecast.blocks, steps_per_block)
    return (f"at most {steps:.3g} RK4 steps, at most about {duration_text(bound)} on one core "
            f"({steps_text([cfg])} and {plan_costs().block_s:.2g} s per block's jump; "
            f"benchmarks/calibrate_plan.py); expected about {duration_text(expected)}: "
            f"{forecast.describe(cfg)}")


def check_settled_window(cfg: Config, block_s: float, source: str = "<config>") -> None:
    """Refuse a life run whose blocks end before their settled window begins while a limit
    reads that window (``life.max_normal_force``, ``max_rms_acceleration``,
    ``max_motion_error``): each block's settled statistics would be NaN and the limit never
    reached, as at a fast crank's few milliseconds a revolution with the default
    ``metrics.settle_time`` (0.05 s: 4 revolutions at 5000 r/min). ConfigError naming the
    settle key the config set."""
    settled = [key for key, var in CRITERIA.values()
               if var.endswith("_settled") and cfg.get(key) is not None]
    settle = cfg.metrics.settle_time
    if not settled or settle < block_s:
        return
    key = ("metrics.settle_revolutions" if cfg.metrics.settle_revolutions is not None
           else "metrics.settle_time")
    raise ConfigError(
        key, cfg.get(key),
        f"a settled window inside each life block ({block_s:.3g} s: life.block_revolutions "
        f"{cfg.life.block_revolutions:g} at {cfg.mechanism.speed_rpm:g} r/min), a shorter "
        f"{key} or more life.block_revolutions: {', '.join(settled)} "
        f"{'reads' if len(settled) == 1 else 'read'} the settled window and could never be "
        "reached", source,
        got=f"{cfg.get(key)!r} (the settled window starts {settle:.3g} s into the block)")


def life_block(cfg: Config, *, allow_large: bool = False,
               source: str = "<config>") -> tuple[Config, Packed]:
    """The config of one dynamic block of the life run ``cfg`` and its packed inputs, once
    the block's work and memory are checked (:func:`clearsweep.simulation.preflight`);
    nothing is compiled or run: the packed inputs have no seated start (each block packs
    its own, on the worn sockets).

    Raises
    ------
    ConfigError
        Naming what the user set, ``life.block_revolutions``, where the block's derived
        ``solver.duration`` is too long; the settle key where a settled limit's window lies
        beyond the block (:func:`check_settled_window`); other keys as :func:`preflight`
        names them.
    """
    lc = cfg.life
    block_cfg = block_config(cfg)
    n_block = round(block_cfg.solver.duration / cfg.solver.dt)
    check_settled_window(cfg, block_cfg.solver.duration, source)
    try:
        packed = preflight(block_cfg, allow_large=allow_large, seat=False)
    except ConfigError as exc:
        if exc.key not in ("solver.duration", "solver.save_every"):
            raise ConfigError(exc.key, exc.value, exc.expected, source, exc.suggestion,
                              exc.got) from None
        raise ConfigError(
            "life.block_revolutions", lc.block_revolutions,
            f"{exc.expected.split(';')[0]} per block: fewer life.block_revolutions, a larger "
            "solver.dt or mechanism.speed_rpm" + ("" if allow_large else ", or --allow-large"),
            source, got=f"{lc.block_revolutions!r} ({lc.block_revolutions} revolutions at "
                        f"{cfg.mechanism.speed_rpm:g} r/min with solver.dt = {cfg.solver.dt:g} s "
                        f"are {n_block:.3g} steps per block)") from None
    check_life_cost(cfg, estimate(block_cfg), allow_large=allow_large, source=source)
    return block_cfg, packed


def settled_motion_error(cfg: Config, raw: KernelRun) -> float:
    """Largest settled ``|s - s_ideal(theta)|`` [m] of a block's saved rows, s the slider's
    position along its guide (x for the RSSP, y for the slider-crank): the slider's motion
    error (docs/physics.md section 1, the ideal mechanism's slider position at the crank
    angle reached); NaN when no saved row lies in the settled window."""
    from .params import PRESETS, ideal_slider_position

    preset = PRESETS[cfg.mechanism.preset]
    n = int(raw.n_saved)
    t, y = raw.t[:n], raw.y[:n]
    settled = t >= cfg.metrics.settle_time
    if not settled.any():
        return math.nan
    theta = y[settled, L.Y_CRANK_ANGLE]
    ideal = ideal_slider_position(preset, theta)
    return float(np.max(np.abs(y[settled, L.Y_R4 + preset.guide_axis] - ideal)))


def bin_areas(shape: tuple[int, int], radius: float) -> np.ndarray:
    """Area [m^2] of each bin of a polar x azimuth map on a sphere of ``radius``: the
    kernel's own ``core.wear.bin_area``, row by row."""
    from .core.wear import bin_area

    npolar, nazim = shape
    row = np.array([bin_area(ip, npolar, nazim, radius) for ip in range(npolar)])
    return np.repeat(row[:, None], nazim, axis=1)


def jump_revolutions(depth: np.ndarray, rate: np.ndarray, clearance: np.ndarray,
                     coating: np.ndarray, clearance_fraction: float,
                     coating_fraction: float) -> float:
    """Largest jump dN [revolutions] under the depth-growth limits.

    ``depth`` and ``rate`` (per revolution) are [2, npolar, nazim] maps [m]; ``clearance``
    and ``coating`` per joint [m] (coating inf where uncoated). A bin may deepen by at most
    ``clearance_fraction * c`` and, while it holds coating (remaining r > 0), by at most
    ``coating_fraction * max(r, coating_fraction * l_c)``: the floor keeps the approach to
    wear-through finite (a bin crosses it within a few jumps). inf when nothing wears.
    """
    dn = math.inf
    for j in range(len(clearance)):
        grows = rate[j] > 0.0
        if clearance[j] <= 0.0 or not grows.any():
            continue
        limit = np.full(depth[j].shape, clearance_fraction * clearance[j])
        if math.isfinite(coating[j]):
            remaining = coating[j] - depth[j]
            coated = remaining > 0.0
            floor = coating_fraction * coating[j]
            limit[coated] = np.minimum(limit[coated],
                                       coating_fraction * np.maximum(remaining[coated], floor))
        dn = min(dn, float(np.min(limit[grows] / rate[j][grows])))
    return dn


def first_crossing(before: np.ndarray, after: np.ndarray, level: float) -> tuple[float, int, int] | None:
    """Where a map first reaches ``level`` between two states of it that differ linearly:
    (fraction of the way, polar index, azimuth index) of the earliest bin, or None."""
    crossed = (before < level) & (after >= level)
    if not crossed.any():
        return None
    frac = np.full(before.shape, np.inf)
    frac[crossed] = (level - before[crossed]) / (after[crossed] - before[crossed])
    ip, ia = np.unravel_index(int(np.argmin(frac)), frac.shape)
    return float(frac[ip, ia]), int(ip), int(ia)


def crossing_cycle(cycles: np.ndarray, values: np.ndarray, limit: float) -> float:
    """Revolutions at which ``values`` (sampled at ``cycles``) first reaches ``limit``,
    interpolated linearly between the rows either side; NaN if it never does."""
    for k, value in enumerate(values):
        if np.isfinite(value) and value >= limit:
            if k == 0 or not np.isfinite(values[k - 1]):
                return float(cycles[k])
            v0, v1 = float(values[k - 1]), float(value)
            return float(cycles[k - 1] + (cycles[k] - cycles[k - 1]) * (limit - v0) / (v1 - v0))
    return math.nan


@dataclass
class LifeState:
    """What a life run carries from block to block, and its rows."""

    wmap: np.ndarray
    wvol: np.ndarray
    cycles: float = 0.0
    rows: list[dict[str, Any]] = field(default_factory=list)
    snapshots: list[tuple[float, np.ndarray]] = field(default_factory=list)
    wear_through: list[tuple[float, int, int] | None] = field(default_factory=lambda: [None] * L.N_JOINTS)
    block_volumes: list[np.ndarray] = field(default_factory=list)
    #: Wall time [s] of the earlier sessions of a resumed run.
    wall_before: float = 0.0


# --------------------------------------------------------------------------- checkpoints

#: Layout of a checkpoint file; one of another layout is refused (2: the materials values
#: it was made with are kept beside the config).
CHECKPOINT_FORMAT = 2
#: A life run writing OUT keeps its checkpoint beside it: ``OUT`` + this suffix.
CHECKPOINT_SUFFIX = ".life-checkpoint"


class CheckpointError(RuntimeError):
    """A checkpoint that cannot be used as asked (an earlier run's, another config's, unreadable)."""


class LifeInterrupted(KeyboardInterrupt):
    """A life run stopped (Ctrl-C); the blocks finished before are kept in its checkpoint.

    Attributes
    ----------
    blocks : int
        Blocks in the checkpoint (0: none was kept).
    checkpoint : pathlib.Path or None
        The checkpoint file.
    """

    def __init__(self, blocks: int, checkpoint: Path | None):
        super().__init__(f"life run interrupted: {blocks} blocks kept in {checkpoint}")
        self.blocks, self.checkpoint = blocks, checkpoint


def checkpoint_path_for(out: str | os.PathLike) -> Path:
    """The checkpoint of the life run that writes ``out``: ``OUT.life-checkpoint`` beside it."""
    out = Path(out)
    return out.with_name(out.name + CHECKPOINT_SUFFIX)


def _config_json(cfg: Config) -> str:
    """The config part of a life run's identity (:func:`clearsweep.params.run_identity`: the
    resolved config without the materials file's path) as canonical JSON."""
    return _canonical(run_identity(cfg)["config"])


def _canonical(value: Any) -> str:
    return json.dumps(value, sort_keys=True, separators=(",", ":"))


def _materials_json(cfg: Config) -> str:
    """The materials values a life run reads (:func:`clearsweep.params.run_identity`) as JSON."""
    return _canonical(run_identity(cfg)["materials"])


def save_checkpoint(path: str | os.PathLike, cfg: Config, state: LifeState, wall: float) -> Path:
    """Write ``state`` (after a block and its jump) to ``path`` atomically: a temporary file
    beside it, flushed to disk, renamed into place; a kill leaves the previous checkpoint.

    Holds the config it belongs to, the materials values it read and the clearsweep version
    (:func:`clearsweep.params.run_identity`), the worn maps and volumes, the cycle count, every row,
    the map snapshots, the wear-through records, each block's worn volume and the wall time
    so far (``wall`` [s] in this session); a life run has no random state (an ensemble
    member's perturbation is drawn from ``(seed, member)`` in the config).
    """
    path = Path(path)
    rows = state.rows
    arrays: dict[str, Any] = {
        "format": np.array(CHECKPOINT_FORMAT), "config": np.array(_config_json(cfg)),
        "materials": np.array(_materials_json(cfg)), "version": np.array(IDENTITY_VERSION),
        "cycles": np.array(state.cycles),
        "wall": np.array(state.wall_before + wall), "wmap": state.wmap, "wvol": state.wvol,
        "row_keys": np.array(list(rows[0])),
        "snapshot_cycle": np.array([c for c, _ in state.snapshots]),
        "snapshot_map": np.array([m for _, m in state.snapshots]),
        "wear_through": np.array([w if w is not None else (np.nan,) * 3 for w in state.wear_through],
                                 dtype=float),
        "block_volumes": np.array(state.block_volumes),
    }
    for key in rows[0]:
        arrays[f"row_{key}"] = np.array([r[key] for r in rows])
    with replaced_on_success(path) as tmp, open(tmp, "wb") as f:
        np.savez(f, **arrays)
        f.flush()
        os.fsync(f.fileno())
    return path


def _unreadable(path: Path, reason: str) -> CheckpointError:
    remedy = ("pass --discard-checkpoint to delete it" if _is_checkpoint_archive(path) else
              "clearsweep deletes only its own files: move it away, or write to another output "
              "file")
    return CheckpointError(f"{path} is not a readable life checkpoint ({reason}); {remedy}")


def _is_checkpoint_archive(path: Path) -> bool:
    """Whether ``path`` is an archive that :func:`save_checkpoint` wrote (of any layout): a
    zip file holding ``format.npy``; only such a file is deleted by ``--discard-checkpoint``."""
    try:
        with zipfile.ZipFile(path) as archive:
            return "format.npy" in archive.namelist()
    except (OSError, zipfile.BadZipFile):
        return False


def _checkpoint_layout_problem(saved: dict[str, np.ndarray], keys: list[str],
                               columns: dict[str, np.ndarray], cfg: Config) -> str | None:
    """What makes the arrays of a checkpoint other than :func:`save_checkpoint` writes them
    for ``cfg``, in words, or None: an edited or damaged checkpoint stopped a resumed run
    with numpy's or xarray's traceback, or ran on from an empty or ragged state."""
    from .variables import JOINTS

    maps = (len(JOINTS), *cfg.wear.map)
    n_snap = saved["snapshot_cycle"].shape[0] if saved["snapshot_cycle"].ndim == 1 else -1
    shapes = {"cycles": (), "wall": (), "wmap": maps, "wvol": (len(JOINTS),),
              "snapshot_cycle": (n_snap,), "snapshot_map": (n_snap, *maps),
              "wear_through": (len(JOINTS), 3)}
    for name, shape in shapes.items():
        array = saved[name]
        if array.dtype.kind not in "fiu":
            return f"{name} holds {array.dtype} values, not numbers"
        if array.shape != shape:
            return f"{name} has shape {array.shape}, expected {shape}"
    if not (np.isfinite(saved["cycles"]) and saved["cycles"] >= 0 and np.isfinite(saved["wall"])):
        return f"cycles {saved['cycles']} and wall {saved['wall']} are not finite numbers >= 0"
    if not keys:
        return "no block rows"
    lengths = {len(c) if c.ndim else -1 for c in columns.values()}
    if len(lengths) != 1 or min(lengths) < 1:
        return f"block rows of lengths {sorted(lengths)}, expected one length of at least 1"
    for key, column in columns.items():
        if (column.dtype.kind in "US") != (key == "block_status"):
            return f"row {key} holds {column.dtype} values"
    return _checkpoint_invariant_problem(saved, columns, min(lengths))


def _checkpoint_invariant_problem(saved: dict[str, np.ndarray], columns: dict[str, np.ndarray],
                                  blocks: int) -> str | None:
    """What breaks the invariants of a life run's state in a checkpoint of the right layout,
    naming the field, or None: wear only adds (depths and volumes non-negative, the volumes
    non-decreasing from block to block, each block's volume non-negative), the cycles increase,
    every block has its volume, and each block's status is one the kernel reports. A
    hand-edited checkpoint was resumed, some with exit 0 (issue 40, item 8)."""
    from .variables import JOINTS

    volumes = saved["block_volumes"]
    if volumes.dtype.kind not in "fiu" or volumes.shape != (blocks, len(JOINTS)):
        return (f"block_volumes has shape {volumes.shape}, expected {(blocks, len(JOINTS))} "
                "(one row of joint volumes a block)")
    for name, array in (("wmap", saved["wmap"]), ("wvol", saved["wvol"]),
                        ("block_volumes", volumes)):
        if not (np.isfinite(array).all() and (array >= 0.0).all()):
            return f"{name} holds values that are not finite numbers >= 0"
    worn = columns.get("wear_volume")
    if worn is not None:
        if worn.dtype.kind not in "fiu" or not (np.isfinite(worn).all() and (worn >= 0.0).all()):
            return "row wear_volume holds values that are not finite numbers >= 0"
        if (np.diff(worn, axis=0) < 0.0).any() or (saved["wvol"] < worn[-1]).any():
            return "row wear_volume decreases from one block to the next (wear only adds)"
    cycle = columns.get("cycle")
    if cycle is not None and (cycle.dtype.kind not in "fiu" or cycle.ndim != 1
                              or not np.isfinite(cycle).all() or (cycle <= 0.0).any()
                              or (np.diff(cycle) <= 0.0).any()
                              or cycle[-1] > saved["cycles"]):
        return ("row cycle is not increasing positive revolutions up to the checkpoint's "
                "cycles")
    snapshots = saved["snapshot_cycle"]
    if not np.isfinite(snapshots).all() or (np.diff(snapshots) <= 0.0).any():
        return "snapshot_cycle is not increasing"
    status = columns.get("block_status")
    known = set(L.STATUS_NAMES.values())
    if status is not None:
        unknown = sorted({str(s) for s in np.ravel(status)} - known)
        if unknown:
            return (f"row block_status holds {unknown[0]!r}, not one of "
                    f"{', '.join(sorted(known))}")
    return None


def load_checkpoint(path: str | os.PathLike, cfg: Config) -> LifeState:
    """The state saved by :func:`save_checkpoint` at ``path`` for the life run of ``cfg``.

    Raises
    ------
    CheckpointError
        The file is not a readable checkpoint, or it belongs to another config, other
        materials values or another clearsweep version (the first differences named).
    """
    path = Path(path)
    try:
        if not zipfile.is_zipfile(path):    # else numpy reads text as pickled data
            raise ValueError("not a checkpoint archive (empty, truncated or another file)")
        with np.load(path, allow_pickle=False) as data:
            saved = {k: data[k] for k in data.files}
        layout = int(saved["format"])
        if layout != CHECKPOINT_FORMAT:
            raise _unreadable(path, f"layout {layout}, this version reads {CHECKPOINT_FORMAT}")
        saved_identity = {"config": json.loads(str(saved["config"])),
                          "materials": json.loads(str(saved["materials"])),
                          "version": str(saved["version"])}
        keys = [str(k) for k in saved["row_keys"]]
        columns = {k: saved[f"row_{k}"] for k in keys}
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
        raise _unreadable(path, f"{type(exc).__name__}: {exc}") from None
    identity = run_identity(cfg)
    if _canonical(saved_identity) != _canonical(identity):
        what = ("another config" if saved_identity["config"] != identity["config"]
                else "other inputs")
        raise CheckpointError(f"{path} holds the blocks of a life run of {what} "
                              f"({identity_changes(saved_identity, identity)}); a resumed run "
                              "would mix the results of two inputs: run with those inputs to "
                              "continue it, write to another output file, or pass "
                              "--discard-checkpoint to delete it")

    problem = _checkpoint_layout_problem(saved, keys, columns, cfg)
    if problem:
        raise _unreadable(path, problem)

    def value(column: np.ndarray, i: int) -> Any:
        return column[i].copy() if column.ndim > 1 else column[i].item()

    rows = [{k: value(columns[k], i) for k in keys} for i in range(len(columns[keys[0]]))]
    return LifeState(
        wmap=saved["wmap"], wvol=saved["wvol"], cycles=float(saved["cycles"]), rows=rows,
        snapshots=[(float(c), m) for c, m in zip(saved["snapshot_cycle"], saved["snapshot_map"])],
        wear_through=[None if np.isnan(w[0]) else (float(w[0]), int(w[1]), int(w[2]))
                      for w in saved["wear_through"]],
        block_volumes=list(saved["block_volumes"]), wall_before=float(saved["wall"]))


def claim_checkpoint(path: str | os.PathLike, cfg: Config, *, resume: bool = False,
                     discard: bool = False) -> LifeState | None:
    """Take the checkpoint at ``path`` for the life run of ``cfg``, as a sweep takes its
    parts: the state to continue from, or None to start at block 0.

    A checkpoint is never deleted unless ``discard``: without ``resume`` an existing one
    makes the run refuse; with ``resume`` one of other inputs (or unreadable) does. A file
    that is not a checkpoint archive at all is refused, ``discard`` or not, and left alone.

    Raises
    ------
    CheckpointError
        The checkpoint is there and cannot be used as asked.
    """
    path = Path(path)
    if not path.exists():
        return None
    if not path.is_file():
        raise CheckpointError(f"{path} is where this run keeps its checkpoint, and it is not a "
                              "file; move it away or write to another output file")
    if not _is_checkpoint_archive(path):     # not ours: neither read nor deleted
        raise _unreadable(path, "not a checkpoint archive: empty, truncated or another file")
    if resume:
        try:
            return load_checkpoint(path, cfg)
        except CheckpointError:
            if not discard:
                raise
    elif not discard:
        raise CheckpointError(f"{path} holds the finished blocks of an earlier life run; pass "
                              "--resume to continue it, or --discard-checkpoint to delete it and "
                              "start again")
    path.unlink()
    return None


def checkpoint_blocks(path: str | os.PathLike) -> int:
    """Blocks held by the checkpoint at ``path`` (0 when there is none or it is unreadable)."""
    try:
        with np.load(path, allow_pickle=False) as data:
            return int(data["row_cycle"].size)
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
        return 0


def _block_row(cfg: Config, raw: KernelRun, state: LifeState, revs: float, jp: np.ndarray) -> dict[str, Any]:
    """One row of the life dataset from a finished block (map and volume after it)."""
    from .simulation import statistics_from_raw

    clearance = jp[:, L.J_C]
    coat = jp[:, L.J_COAT]
    stats = statistics_from_raw(raw.stats, clearance > 0.0)
    settled_revs = raw.stats[L.W_SETTLED, L.M_TIME] * cfg.mechanism.speed_rpm / 60.0
    depth_max = state.wmap.reshape(L.N_JOINTS, -1).max(axis=1)
    mean = np.zeros(L.N_JOINTS)
    for j in range(L.N_JOINTS):
        worn = state.wmap[j] > WORN_FRACTION * depth_max[j]
        if worn.any():
            # a guide's bins hold the depth of the corners' tracks, each over the same
            # length along the guide (docs/physics.md 5.7): their plain mean
            areas = (np.ones(state.wmap.shape[1:])
                     if describe(JOINTS[j]).equal_bins
                     else bin_areas(state.wmap.shape[1:], jp[j, L.J_RI]))
            mean[j] = float((state.wmap[j] * areas)[worn].sum() / areas[worn].sum())
    ideal = clearance <= 0.0
    row = {
        "cycle": state.cycles,
        "block_revolutions": revs,
        "wear_depth_max": depth_max,
        "wear_depth_mean": mean,
        "wear_volume": state.wvol.copy(),
        "clearance_effective": np.where(ideal, np.nan, clearance + depth_max),
        "coating_remaining": np.where(np.isfinite(coat), np.maximum(coat - depth_max, 0.0), np.nan),
        "normal_force_peak_settled": stats["normal_force_peak_settled"],
        "slider_acceleration_rms_settled": stats["slider_acceleration_rms_settled"],
        "slider_acceleration_peak_settled": stats["slider_acceleration_peak_settled"],
        "slider_motion_error_settled": settled_motion_error(cfg, raw),
        "impacts_per_revolution": np.where(
            ideal, np.nan, stats["impact_count_settled"] / settled_revs if settled_revs > 0 else np.nan),
        "block_status": raw.status,
        "energy_residual_relative": (raw.residual_max / raw.ke_peak if raw.ke_peak > 0
                                     else np.nan),
        "jump_revolutions": 0.0,
    }
    for j in range(L.N_JOINTS):
        if ideal[j]:
            row["wear_depth_max"][j] = row["wear_depth_mean"][j] = np.nan
    return row


def _snapshot_due(cycle: float, kept: list[tuple[float, np.ndarray]], first: float, last: float,
                  count: int) -> bool:
    """Keep a map when ``cycle`` has passed the next of ``count`` log-spaced marks between the
    first block's cycle and the target (the final map is always added at the end)."""
    if not kept:
        return True
    if last <= first:
        return False
    marks = np.geomspace(first, last, count)
    return bool(np.searchsorted(marks, cycle, side="right") > np.searchsorted(marks, kept[-1][0], side="right"))


def life(config, overrides=(), *, allow_large: bool = False,
         progress: Callable[[dict[str, Any]], None] | None = None,
         stop_rule: Callable[[Config, dict[str, Any], LifeState], str | None] | None = None,
         checkpoint: str | os.PathLike | None = None, resume: bool = False,
         discard_checkpoint: bool = False,
         resumed: Callable[[LifeState], None] | None = None) -> xr.Dataset:
    """Run a service-life estimate by cycle jumps (docs/service_life.md).

    Parameters
    ----------
    config
        A :class:`clearsweep.config.Config`, a YAML path or a config dict; the ``life``
        section drives the run, ``solver.duration`` is replaced by the block length.
    overrides
        ``"dotted.key=VALUE"`` strings.
    allow_large
        Lift the work and memory bounds of one block.
    progress
        Called with each block's row as it is finished.
    stop_rule
        ``stop_rule(cfg, row, state)`` after each block: the name of what stops the run, or
        None to go on. Default: the first limit crossed (a reliability member runs on until
        every limit it watches is crossed: :mod:`clearsweep.reliability`).
    checkpoint
        Keep the run's state in this file after every block (:func:`save_checkpoint`;
        :func:`checkpoint_path_for` names the one beside an output file). The caller
        deletes it once the dataset is safely written.
    resume
        Continue from ``checkpoint`` (:func:`claim_checkpoint`); the dataset is the one an
        uninterrupted run gives, bit for bit (``wall_time`` aside).
    discard_checkpoint
        Delete a ``checkpoint`` that cannot be continued instead of refusing.
    resumed
        Called with the state a resumed run continues from.

    Returns
    -------
    xr.Dataset
        Dimension ``cycle`` (revolutions at the end of each block), per joint the wear and
        the settled dynamics of each block, wear-map snapshots, when and where each coating
        was first worn through, the revolutions to each limit and ``stop_reason``.

    Raises
    ------
    CheckpointError
        ``checkpoint`` exists and cannot be used as asked (:func:`claim_checkpoint`).
    LifeInterrupted
        Ctrl-C; the blocks finished before are in ``checkpoint``.
    """
    start = time.perf_counter()
    cfg = load_config(config, overrides)
    with checkpoint_lock(checkpoint):
        earlier = (claim_checkpoint(checkpoint, cfg, resume=resume, discard=discard_checkpoint)
                   if checkpoint is not None else None)
        if earlier is not None and resumed is not None:
            resumed(earlier)
        try:
            return _life(cfg, allow_large, progress, checkpoint, earlier, start, stop_rule)
        except KeyboardInterrupt:
            kept = checkpoint_blocks(checkpoint) if checkpoint is not None else 0
            raise LifeInterrupted(kept, Path(checkpoint) if checkpoint is not None else None) from None


@contextmanager
def checkpoint_lock(checkpoint: str | os.PathLike | None) -> Iterator[None]:
    """Hold ``CHECKPOINT.lock`` (an exclusive ``flock``) while a life run uses its checkpoint,
    as a sweep holds its parts folder: a second life run to the same output is refused
    instead of writing over the first one's checkpoint. The lock file is removed after,
    while still locked.

    A lock is held only once the file locked is the one at the path: a run that opened the
    file just before the holder removed it, and locked it after, holds a file no longer
    there, which a third run could re-create and lock as well; it opens the path again
    instead. So at most one run holds the lock, whatever the interleaving.

    Raises
    ------
    CheckpointError
        Another life run holds the lock.
    """
    if checkpoint is None:
        yield
        return
    lock = Path(checkpoint).with_name(Path(checkpoint).name + ".lock")
    try:
        fd = lock_exclusively(lock)
    except ForeignLock as exc:
        raise CheckpointError(str(exc)) from None
    if fd is None:
        raise CheckpointError(f"{checkpoint} is in use by another life run writing the same "
                              "output; wait for it to finish or write to another output file")
    try:
        yield
    finally:
        lock.unlink(missing_ok=True)
        os.close(fd)


def _life(cfg: Config, allow_large: bool, progress: Callable[[dict[str, Any]], None] | None,
          checkpoint: str | os.PathLike | None, earlier: LifeState | None,
          start: float,
          stop_rule: Callable[[Config, dict[str, Any], LifeState], str | None] | None = None
          ) -> xr.Dataset:
    """:func:`life` from ``earlier`` (None: from block 0)."""
    lc = cfg.life
    period = 60.0 / cfg.mechanism.speed_rpm
    block_cfg, packed = life_block(cfg, allow_large=allow_large)
    materials = resolve_materials(block_cfg)
    prepare_kernel(cfg.solver.method, kernel_build(block_cfg))
    jp = packed.jp
    clearance = np.where(jp[:, L.J_CLEARANCE] != 0.0, jp[:, L.J_C], 0.0)
    coat = np.where(clearance > 0.0, jp[:, L.J_COAT], math.inf)
    revs = packed.n_steps * packed.p[L.P_DT] / period
    state = (earlier if earlier is not None
             else LifeState(wmap=np.zeros((L.N_JOINTS,) + packed.map_shape), wvol=np.zeros(L.N_JOINTS)))
    stop = "cycles"
    first_cycle = revs
    while True:
        if len(state.rows) >= lc.max_blocks:
            stop = "max_blocks"
            break
        before = state.wmap
        raw = run_kernel(pack(block_cfg, materials, before), before, state.wvol)
        state.block_volumes.append(raw.wvol - state.wvol)
        rate = (raw.wmap - before) / revs
        _note_wear_through(state, before, raw.wmap, coat, state.cycles, revs)
        state.wmap, state.wvol = raw.wmap, raw.wvol
        state.cycles += revs
        row = _block_row(cfg, raw, state, revs, jp)
        state.rows.append(row)
        if _snapshot_due(state.cycles, state.snapshots, first_cycle, lc.cycles, lc.snapshots):
            state.snapshots.append((state.cycles, state.wmap.copy()))
        if progress is not None:
            progress(row)
        if raw.status != "ok":
            stop = f"block_status:{raw.status}"
            break
        reached = (stop_rule or _limit_reached)(cfg, row, state)
        if reached:
            stop = reached
            break
        if state.cycles + revs > lc.cycles * (1.0 + 1e-12):
            break
        if len(state.rows) >= lc.max_blocks:
            # no block would follow the jump: the run ends on the last block's map (kept in
            # the checkpoint, as after every block: a run whose output write failed is
            # finished by --resume without running it again)
            stop = "max_blocks"
            if checkpoint is not None:
                save_checkpoint(checkpoint, cfg, state, time.perf_counter() - start)
            break
        dn = jump_revolutions(state.wmap, rate, clearance, coat, lc.jump_clearance_fraction,
                              lc.jump_coating_fraction)
        dn = max(0.0, min(dn, lc.cycles - state.cycles - revs))
        if dn > 0.0:
            after = state.wmap + dn * rate
            _note_wear_through(state, state.wmap, after, coat, state.cycles, dn)
            state.wmap = after
            state.wvol = state.wvol + dn * state.block_volumes[-1] / revs
            state.cycles += dn
            row["jump_revolutions"] = dn
        if checkpoint is not None:
            save_checkpoint(checkpoint, cfg, state, time.perf_counter() - start)
    if not state.snapshots or state.snapshots[-1][0] != state.rows[-1]["cycle"]:
        # the loop ends after a block, so the map is the last row's
        state.snapshots.append((state.rows[-1]["cycle"], state.wmap.copy()))
    return _life_dataset(cfg, state, stop, state.wall_before + time.perf_counter() - start,
                         joint_attributes(block_cfg, packed))


def _note_wear_through(state: LifeState, before: np.ndarray, after: np.ndarray, coat: np.ndarray,
                       cycle0: float, span: float) -> None:
    """Record the first wear-through of each coated joint between two maps ``span``
    revolutions apart, starting at ``cycle0`` (linear in between)."""
    for j in range(len(coat)):
        if state.wear_through[j] is not None or not math.isfinite(coat[j]):
            continue
        hit = first_crossing(before[j], after[j], coat[j])
        if hit is not None:
            state.wear_through[j] = (cycle0 + hit[0] * span, hit[1], hit[2])


def _limit_reached(cfg: Config, row: dict[str, Any], state: LifeState) -> str | None:
    """Name of the first criterion this block's row has crossed, or None."""
    lc = cfg.life
    for name, (key, var) in CRITERIA.items():
        limit = cfg.get(key)
        value = np.nanmax(np.atleast_1d(row[var])) if np.isfinite(row[var]).any() else math.nan
        if limit is not None and value >= limit:
            return name
    if lc.stop_at_wear_through and any(w is not None for w in state.wear_through):
        return "wear_through"
    return None


def _life_dataset(cfg: Config, state: LifeState, stop: str, wall: float,
                  joints: dict[str, Any]) -> xr.Dataset:
    """The life run's dataset; ``joints``: each joint's attributes
    (:func:`clearsweep.params.joint_attributes`), as a run's dataset carries them."""
    import xarray as xr

    from .dataset import bin_centres_deg, versions
    from .variables import JOINTS, LIFE_VARIABLES

    rows = state.rows
    cycles = np.array([r["cycle"] for r in rows])
    data: dict[str, Any] = {}
    for name, spec in LIFE_VARIABLES.items():
        if spec.dims and spec.dims[0] == "cycle" and name != "cycle":
            data[name] = (spec.dims, np.array([r[name] for r in rows]))
    npolar, nazim = state.wmap.shape[1:]
    polar = bin_centres_deg(npolar, 0.0, 180.0)
    azimuth = bin_centres_deg(nazim, -180.0, 180.0)
    data["wear_map_snapshot"] = (("snapshot", "joint", "polar", "azimuth"),
                                 np.array([m for _, m in state.snapshots]))
    data["snapshot_cycle"] = (("snapshot",), np.array([c for c, _ in state.snapshots]))
    data["wear_map"] = (("joint", "polar", "azimuth"), state.wmap)
    wt = state.wear_through
    data["wear_through_cycle"] = (("joint",), np.array([w[0] if w else np.nan for w in wt]))
    data["wear_through_polar"] = (("joint",), np.array([polar[w[1]] if w else np.nan for w in wt]))
    data["wear_through_azimuth"] = (("joint",), np.array([azimuth[w[2]] if w else np.nan for w in wt]))
    for name, (key, var) in CRITERIA.items():
        limit = cfg.get(key)
        values = data[var][1]
        first = ""
        if values.ndim == 2 and limit is not None:
            # each joint against the limit: the one that crosses it first
            per_joint = [crossing_cycle(cycles, values[:, j], limit) for j in range(values.shape[1])]
            if np.isfinite(per_joint).any():
                first = JOINTS[int(np.nanargmin(per_joint))]
        values = values if values.ndim == 1 else np.nanmax(np.where(np.isfinite(values), values, -np.inf),
                                                             axis=1)
        data[f"cycles_to_{name}"] = ((), np.nan if limit is None else crossing_cycle(cycles, values, limit))
        data[f"first_joint_to_{name}"] = ((), first)
    through = data["wear_through_cycle"][1]
    data["cycles_to_wear_through"] = ((), float(np.nanmin(through)) if np.isfinite(through).any() else np.nan)
    data["first_joint_to_wear_through"] = ((), JOINTS[int(np.nanargmin(through))]
                                           if np.isfinite(through).any() else "")
    data["wall_time"] = ((), wall)
    ds = xr.Dataset({k: (v[0], v[1]) for k, v in data.items()},
                    coords={"cycle": ("cycle", cycles), "joint": ("joint", list(JOINTS)),
                            "polar": ("polar", polar), "azimuth": ("azimuth", azimuth)})
    for key in [*ds.data_vars, "cycle", "joint", "polar", "azimuth"]:
        info = LIFE_VARIABLES.get(str(key))
        if info is not None:
            ds[key].attrs.update(units=info.units, long_name=info.long_name)
            if info.description:
                ds[key].attrs["description"] = info.description
    ds["stop_reason"] = ((), stop, {"long_name": "why the life run stopped",
                                    "description": "cycles, max_blocks, a criterion name, "
                                                   "wear_through or block_status:<status>"})
    ds.attrs.update({
        "title": "clearsweep service life by cycle jumps",
        "mechanism": cfg.mechanism.kind,
        "Conventions": "CF-1.8",
        "source": "clearsweep",
        "history": with_command_line(history_line("created by clearsweep life")),
        "config": dump_config(cfg),
        "life_method": "cycle-jump extrapolation with geometry update: dynamic blocks of "
                       "life.block_revolutions revolutions from a seated start on the worn "
                       "sockets, jumps adding dN times the block's wear per revolution",
        "wear_amplification": cfg.wear.amplification,
        "settle_time_s": cfg.metrics.settle_time,
        **joints,
    })
    ds.attrs.update(versions())
    return ds


def life_summary_text(ds: xr.Dataset) -> str:
    """Text report of a life dataset: revolutions to each limit, wear-through, last block."""
    lines = [f"life run: {ds.sizes['cycle']} blocks, {float(ds.cycle[-1]):.4g} revolutions, "
             f"stopped by {ds['stop_reason'].values}"]
    try:
        cfg = load_config(parse_yaml(ds.attrs.get("config") or "", "config") or {})
    except ConfigError:
        cfg = None
    joints = cfg.joints if cfg is not None else None
    for name, (key, _) in CRITERIA.items():
        value = float(ds[f"cycles_to_{name}"])
        unset = cfg is not None and getattr(cfg.life, key.split(".", 1)[1]) is None
        text = f"{value:.4g}" if math.isfinite(value) else "not set" if unset else "not reached"
        first = str(ds[f"first_joint_to_{name}"].values) if f"first_joint_to_{name}" in ds else ""
        lines.append(f"  revolutions to {key}: {text}" + (f" (joint {first} first)" if first else ""))
    for j, joint in enumerate(ds.joint.values):
        cyc = float(ds.wear_through_cycle[j])
        spec = getattr(joints, str(joint), None) if joints is not None else None
        if spec is not None and (spec.clearance == 0.0 or spec.coating == "none"):
            continue        # an ideal or uncoated joint has no coating to wear through
        if math.isfinite(cyc):
            lines.append(f"  coating of {joint} worn through at {cyc:.4g} revolutions, polar "
                         f"{float(ds.wear_through_polar[j]):.4g} deg, azimuth "
                         f"{float(ds.wear_through_azimuth[j]):.4g} deg")
        else:
            lines.append(f"  coating of {joint}: not worn through")
    last = ds.isel(cycle=-1)
    for j, joint in enumerate(ds.joint.values):
        depth = float(last.wear_depth_max[j])
        if math.isfinite(depth):
            lines.append(f"  {joint} at the end: max depth {format_length(depth)}, effective "
                         f"clearance {format_length(float(last.clearance_effective[j]))},")
            lines.append(f"    settled peak normal force {float(last.normal_force_peak_settled[j]):.4g}"
                         f" N, {float(last.impacts_per_revolution[j]):.3g} impacts per revolution")
    lines.append(f"  settled RMS slider acceleration at the end: "
                 f"{float(last.slider_acceleration_rms_settled):.4g} m s-2")
    return "\n".join(lines)


#: Per-joint variables of a life run whose final value a life sweep keeps.
FINAL_VARIABLES = ("wear_depth_max", "wear_volume", "clearance_effective", "coating_remaining")


def life_time_left(cfg: Config, cycles: float, blocks: int, elapsed_s: float,
                   depths: Sequence[tuple[float, float]] = (),
                   before: tuple[int, float] = (0, 0.0)) -> str:
    """The expected time left of a life run whose ``blocks`` blocks of this process reached
    ``cycles`` revolutions in ``elapsed_s`` (``before``: the blocks and revolutions of a
    checkpoint it resumed from): the lesser of the time at the pace so far in revolutions
    (the jumps lengthen, so rather too long) and the time per block so far times the
    blocks expected to be left (:func:`blocks_left`); ``""`` when done."""
    lc = cfg.life
    done, start = before
    total = done + blocks
    if blocks <= 0 or cycles <= start or cycles >= lc.cycles or total >= lc.max_blocks:
        return ""
    by_pace = elapsed_s * (lc.cycles - cycles) / (cycles - start)
    by_blocks = elapsed_s * blocks_left(cfg, total, depths) / blocks
    return f"about {duration_text(min(by_pace, by_blocks))} left at this pace"


def blocks_left(cfg: Config, blocks: int, depths: Sequence[tuple[float, float]] = ()) -> float:
    """The blocks a life run is expected to take after its first ``blocks``.

    At most ``life.max_blocks``, and those :func:`forecast_blocks` gives to the wear limits
    while the run is short of them (the cap). ``depths``: (revolutions, deepest bin [m]) at
    the end of each block so far. From three blocks on, the depth is taken to grow as a power of the
    revolutions, h = h_k (N / N_k)^beta, beta from the last two blocks (a socket running in
    wears ever slower: beta 0.5 in configs/life.yaml), and each further block to add the
    mean depth of the last blocks' jumps; the run then ends at ``life.cycles`` with the depth
    h(life.cycles), or at the cap if that comes first (the wear limits' blocks). Without
    that (fewer blocks, no wear), the blocks :func:`forecast_blocks` expects (to
    ``life.cycles`` at the plan's wear pace, or to the cap), less those run.
    """
    lc = cfg.life
    forecast = forecast_blocks(cfg)
    cap = forecast.to_limits if forecast.limits and blocks < forecast.to_limits else lc.max_blocks
    guess = forecast.blocks if forecast.known and blocks < forecast.blocks else cap
    left, guessed = float(max(cap - blocks, 0)), float(max(min(guess, cap) - blocks, 0))
    if len(depths) < 3:
        return guessed
    (_, h0), (n1, h1), (n2, h2) = depths[-3], depths[-2], depths[-1]
    if not (0.0 < n1 < n2 < lc.cycles and 0.0 < h1 < h2 and h0 < h1):
        return guessed
    beta = math.log(h2 / h1) / math.log(n2 / n1)
    step = (h2 - h0) / 2.0                          # the mean depth of the last two jumps
    growth = beta * math.log(lc.cycles / n2)        # log of h(life.cycles) / h2
    if not growth < math.log(1.0 + left * step / h2):
        return left          # past the cap (or a steep fit whose power would overflow)
    return min(left, max(0.0, h2 * math.expm1(growth) / step))


def life_stop_hint(cfg: Config, stop: str) -> str:
    """Why a life run whose block stopped (``stop``: ``block_status:<status>``) may have
    stopped, where the config says it: ``""`` otherwise."""
    if stop.startswith("block_status:") and cfg.wear.enabled and not cfg.wear.interpolate:
        return ("hint: the worn socket is read bin by bin (wear.interpolate: false), whose steps "
                "grow with the wear until a block cannot run; life runs read it smoothly with "
                "--set wear.interpolate=true (docs/service_life.md, 'Smooth worn surface')")
    return ""


def life_case(config) -> xr.Dataset:
    """One life run as a sweep case (``store: life``): :func:`life` with ``status`` (``ok``,
    or the status of the block that stopped it) and ``message``."""
    import xarray as xr

    ds = life(config, allow_large=True)     # the sweep checked every case's budget
    stop = str(ds["stop_reason"].values)
    status = stop.split(":", 1)[1] if stop.startswith("block_status:") else "ok"
    ds["status"] = xr.DataArray(status, attrs={"long_name": "life run status"})
    if status != "ok":
        ds["message"] = xr.DataArray(f"a dynamic block stopped with status {status!r} at "
                                     f"{float(ds.cycle[-1]):.6g} revolutions")
    return ds


def life_summary(ds: xr.Dataset) -> xr.Dataset:
    """What a life sweep keeps of one life run: revolutions to each limit and to
    wear-through, revolutions reached, why it stopped, and each joint's final wear depth,
    worn volume, effective clearance, remaining coating and first wear-through."""
    import xarray as xr

    from .variables import LIFE_VARIABLES

    out = {str(name): ds[name] for name in ds.data_vars
           if str(name).startswith(("cycles_to_", "first_joint_to_"))
           or name in ("status", "stop_reason", "wall_time",
                                                             "wear_through_cycle")}
    for name in FINAL_VARIABLES:
        spec = LIFE_VARIABLES[name]
        out[f"{name}_final"] = ds[name].isel(cycle=-1, drop=True).assign_attrs(
            units=spec.units, long_name=f"{spec.long_name} at the end of the life run")
    out["cycles_reached"] = xr.DataArray(float(ds.cycle[-1]), attrs={
        "units": "1", "long_name": "crank revolutions reached"})
    summary = xr.Dataset(out)
    summary.attrs = dict(ds.attrs)
    return summary


def life_sweep_text(ds: xr.Dataset) -> str:
    """A life sweep's designs ranked by revolutions to the first limit the config sets
    (else by the final wear depth): revolutions reached, why each stopped, revolutions to
    each limit and to wear-through, and the final largest wear depth per joint."""
    dims = [d for d in ds["status"].dims]
    flat = ds.stack(design=dims) if dims else ds.expand_dims(design=[0])
    limits = [str(n) for n in ds.data_vars if str(n).startswith("cycles_to_")
              and np.isfinite(ds[n].values).any()]
    rows = []
    for k in range(flat.sizes["design"]):
        case = flat.isel(design=k)
        label = ", ".join(f"{d}={case[d].values.item()}" for d in dims) or "case"
        depth = case["wear_depth_max_final"].values if "wear_depth_max_final" in case else []
        rows.append((label, str(case["status"].values),
                     float(case["cycles_reached"]) if "cycles_reached" in case else math.nan,
                     str(case["stop_reason"].values) if "stop_reason" in case else "",
                     [float(case[n]) for n in limits],
                     float(np.nanmax(depth)) if np.isfinite(depth).any() else math.nan))
    key = ((lambda r: -np.nan_to_num(r[4][0], nan=np.inf)) if limits
           else (lambda r: np.nan_to_num(r[5], nan=np.inf)))
    rows.sort(key=key)
    factor, symbol = length_unit([r[5] for r in rows])
    head = ["design", "status", "revolutions reached", "stopped by", *limits,
            f"largest final depth [{symbol}]"]
    table = [head] + [[r[0], r[1], f"{r[2]:.4g}", r[3], *(f"{v:.4g}" if np.isfinite(v) else "not reached"
                                                         for v in r[4]), f"{r[5] / factor:.3g}"]
                      for r in rows]
    widths = [max(len(row[i]) for row in table) for i in range(len(head))]
    lines = ["Service life per design (ranked: " + (f"most revolutions to {limits[0][10:]} first"
                                                 if limits else "least final wear depth first") + ")"]
    lines += ["  ".join(c.ljust(w) for c, w in zip(row, widths)).rstrip() for row in table]
    return "\n".join(lines)
