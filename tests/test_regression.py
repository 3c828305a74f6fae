"""The kernel reproduces tests/data/two_clearances_0p2s.npz bit for bit (see tests/regression.py)."""

from pathlib import Path

import numpy as np
from regression import simulate_reference, snapshot

REFERENCE = Path(__file__).parent / "data" / "two_clearances_0p2s.npz"

def test_two_clearances_bit_identical():
    got = snapshot(simulate_reference())
    with np.load(REFERENCE) as ref:
        assert sorted(got) == sorted(ref.files)
        for key in ref.files:
            # equal values (NaN where NaN), not close ones: a refactor must not move a bit
            assert np.array_equal(got[key], ref[key], equal_nan=ref[key].dtype.kind == "f"), key
