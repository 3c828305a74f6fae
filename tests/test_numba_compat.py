"""The Numba internals clearsweep relies on: each probed, each used from one module only,
and the Numba version inside the range pyproject.toml states."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from clearsweep.core import numba_compat

ROOT = Path(__file__).resolve().parents[1]

#: Each internal and the text that marks a use of it in the package's source.
INTERNALS = {"_nrt": r"[\"']_nrt[\"']", "simulator arrays": r"\._item\b|\._ary\b",
             "cache folder": r"config\.CACHE_DIR", "compile-only device": r"dispatcher\.get_current_device"}


def test_every_probe_passes_on_the_installed_numba():
    assert numba_compat.probes() == dict.fromkeys(numba_compat.PROBES)


@pytest.mark.parametrize("name, pattern", sorted(INTERNALS.items()))
def test_each_internal_is_used_from_the_compatibility_module_only(name, pattern):
    assert name in numba_compat.PROBES
    users = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "clearsweep").rglob("*.py")
                   if re.search(pattern, "\n".join(line for line in p.read_text().splitlines()
                                                   if not line.lstrip().startswith("#"))))
    assert users == ["clearsweep/core/numba_compat.py"]


def test_installed_numba_lies_in_the_tested_range_that_pyproject_states():
    text = (ROOT / "pyproject.toml").read_text()
    low, high = numba_compat.TESTED_NUMBA
    assert f'"numba>={low},<{high}"' in text
    assert numba_compat.numba_tested()


def test_a_probe_names_what_moved(monkeypatch):
    """A numba-cuda without ``get_current_device`` is reported, not met inside a compile."""
    pytest.importorskip("numba.cuda")
    from numba.cuda import dispatcher

    monkeypatch.delattr(dispatcher, "get_current_device")
    assert "get_current_device" in numba_compat.PROBES["compile-only device"]()


def test_no_runtime_option_is_what_every_kernel_function_carries():
    from clearsweep.core.compiled import OPTIONS

    assert numba_compat.NO_RUNTIME.items() <= OPTIONS.items()


def test_the_kernel_cache_follows_the_kernel_source(tmp_path, monkeypatch):
    """The cache folder is named by the kernel's sources and Numba's version, under
    NUMBA_CACHE_DIR: another tree gets another folder."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    folder = numba_compat.cache_dir()
    assert Path(folder).parent == tmp_path
    assert numba_compat.cache_dir() == folder            # deterministic
