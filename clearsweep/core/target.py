"""Which build a kernel function is compiled into: the CPU's or a CUDA device's.

:func:`on_device` is False in the CPU build and True in the device build of
``core/device.py`` (which registers that answer for numba's CUDA target). A function that
holds one rule in two arrangements, one faster on a CPU and one leaner in a GPU thread's
registers, picks between them with ``if on_device():``; each build folds the test away,
so the rule is written once and each target compiles only its own arrangement. Both
arrangements compute the same values in the same order: results do not depend on the
build (tests/test_gpu.py runs the device arrangement in the simulator against the CPU's).
"""

import numba
from numba.core.extending import overload


def on_device():
    """True in a CUDA device build. As plain Python (``NUMBA_DISABLE_JIT=1``) True under
    numba's CUDA simulator, so that the simulator runs the device arrangement."""
    return bool(numba.config.ENABLE_CUDASIM)


@overload(on_device, inline="always")
def _on_device_cpu():
    """The CPU build: False, a constant."""
    return lambda: False
