"""Planning is bounded before it is taken (hardening round 4, issue 33 item 3; issue 32):
``validate`` and every ``--dry-run`` compile and run nothing, huge plans are counted rather
than enumerated, a life run's checkpoint lock is exclusive under any interleaving.

Before: ``sweep --dry-run`` on an empty Numba cache compiled 47 kernel functions (the seated
start of every case was worked out while planning)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
CONFIGS = ROOT / "configs"


def compiled_files(cache: Path) -> list[Path]:
    return [p for p in cache.rglob("*") if p.suffix in (".nbi", ".nbc")]


@pytest.mark.parametrize("argv", [
    ["sweep", "paper.yaml", "--dry-run"],
    ["validate", "paper.yaml"],
    ["run", "two_clearances.yaml", "--dry-run"],
    ["validate", "reliability.yaml"],
    ["life", "life.yaml", "--dry-run"],
], ids=lambda a: " ".join(a))
def test_planning_compiles_nothing(tmp_path, argv):
    """Was: 47 kernel functions compiled into the empty cache by `sweep paper.yaml --dry-run`."""
    cache = tmp_path / "numba"
    cache.mkdir()
    env = {**os.environ, "PYTHONPATH": str(ROOT), "NUMBA_CACHE_DIR": str(cache)}
    proc = subprocess.run([sys.executable, "-m", "clearsweep.cli", *argv], capture_output=True,
                          text=True, cwd=CONFIGS, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert compiled_files(cache) == []
