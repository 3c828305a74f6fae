"""The RK4 step with one ``evaluate`` call site, for a device build to compare (issue 43 item 6).

A GPU build inlines every device function wherever it is called. ``rk4.advance`` calls
:func:`dynamics.evaluate` from three sites in its step: the stage loop of
``rk4.rk4_substep`` (the three stage derivatives, one site since a loop holds them), the
sub-step's end in ``rk4.attempt_step``, and the same again there after an accepted sub-step
changed the contact state; ``rk4.begin_case`` calls it once more, before the first step. So
the kernel holds four copies of evaluate, three of them in the step.

:func:`attempt_step_one_call` is ``rk4.attempt_step`` with ``rk4_substep`` folded in and its
evaluations in one loop of phases (0-2 the stages, 3 the sub-step's end, 4 the same after a
change of contact state): one call site, which the loop reaches four or five times a
sub-step, with the same arguments, the same arithmetic in the same order, and so the same
bits (tests/test_onestep.py runs both on the CPU kernel's Python source). :data:`advance_one_call`
is ``rk4.advance`` itself, its code and every function it calls, with that attempt in place
of ``rk4.attempt_step``. The two attempts share the sub-step's acceptance
(``rk4.accept_end``) and its sample and section (``rk4.finish_substep``): nothing of the
step's rules is written a second time but the loop of evaluations.

The CPU kernel does not use it. ``core.device.soa_kernel(..., one_evaluate=True)`` builds it
for the device (``python -m clearsweep.ptx --one-evaluate`` gives its registers and spills
against the kernel's own, ``gpu.run_packed(..., layout="soa-one-evaluate")`` runs it): a
device build's arrangement to time, not a change of the physics.
"""

import types as _pytypes

from numba import njit

from . import rk4
from .compiled import OPTIONS, compiled
from .dynamics import evaluate
from .jointkinds import multi_free
from .layout import P_DT
from .rk4 import (
    ST_OK,
    accept_end,
    clear_attempt,
    copy_into,
    finish_substep,
    keep_ends,
    section_in,
)

#: Phases of a sub-step's evaluations: the three stage derivatives (0, 1, 2), the
#: sub-step's end (3), the same again after a change of the contact state (4).
PHASE_END = 3
PHASE_AGAIN = 4


@compiled(inline="always")
def attempt_step_one_call(t, level, last, model, solve, wear, out, work, kept, spec, step_end,
                          stage):
    """``rk4.attempt_step`` (same arguments, same returns, same bits) with
    ``rk4.rk4_substep`` folded in and every evaluation of the attempt at one call site."""
    y = work.y
    k1 = work.k1
    dg = work.dg
    ksum = work.ksum
    kst = work.kst
    yt = work.yt
    slides = multi_free(spec, model.jp)    # a multi-contact joint with clearance
    n = y.shape[0]
    nsub = 1 << level
    hs = model.p[P_DT] / nsub
    nbuf = 0
    need = -1
    status = ST_OK
    clear_attempt(work.cur, slides)
    sub = 0
    phase = 0
    ts = t
    in_settled = False
    while True:
        if phase == 0:
            ts = t + sub * hs
            if sub == 0:
                keep_ends(work.prev, dg, y, spec)      # the step's start (again after a rejection)
            due, _ = section_in(work.secnext, t, sub, hs, last and sub == nsub - 1)
            if due:
                # a section in this sub-step: its start for the cubic Hermite
                copy_into(work.ysub, y)
                copy_into(work.k1sub, k1)
            copy_into(kst, k1)
        # the one call site: a stage (its state yt into kst, the derivative alone) or the
        # sub-step's end (y into k1, energies and stiff rates too)
        if phase < PHASE_END:
            c = 1.0 if phase == 2 else 0.5
            for i in range(n):
                yt[i] = y[i] + c * hs * kst[i]
            te = ts + c * hs
            ye = yt
            ke = kst
            flag = stage
        else:
            te = ts + hs
            ye = y
            ke = k1
            flag = step_end
        st = evaluate(te, ye, model, ke, dg, flag, solve, spec)
        if st != ST_OK:
            status = st
            break
        if phase < PHASE_END:
            if phase == 0:
                copy_into(ksum, kst)
            elif phase == 1:
                for i in range(n):
                    ksum[i] += kst[i]
            else:
                for i in range(n):
                    y[i] += hs / 6.0 * (k1[i] + 2.0 * ksum[i] + kst[i])
            phase += 1
            continue
        if phase == PHASE_END:
            need, in_settled, kept, changed, nbuf = accept_end(ts, hs, nsub, kept, nbuf, slides,
                                                               model, wear, out, work, spec)
            if need >= 0:
                break
            if changed:
                phase = PHASE_AGAIN
                continue
        finish_substep(t, sub, ts, hs, nsub, last, in_settled, model, out, work, spec)
        sub += 1
        if sub == nsub:
            break
        phase = 0
    return status, need, nbuf, nsub, kept


def _advance_with(attempt):
    """``rk4.advance``'s code with ``attempt`` in place of ``rk4.attempt_step`` (its globals
    otherwise rk4's), compiled as advance is but not cached on disk (its code object is
    advance's: the cache would take one for the other)."""
    source = getattr(rk4.advance, "py_func", rk4.advance)
    names = dict(source.__globals__, attempt_step=attempt)
    func = _pytypes.FunctionType(source.__code__, names, "advance_one_call",
                                 source.__defaults__, source.__closure__)
    func.__doc__ = source.__doc__
    func.__qualname__ = "advance_one_call"
    if not hasattr(rk4.advance, "py_func"):     # NUMBA_DISABLE_JIT: the Python source
        return func
    return njit(func, **dict(OPTIONS, cache=False), locals=rk4._NOT_LITERAL)


#: ``rk4.advance`` stepping with :func:`attempt_step_one_call`.
advance_one_call = _advance_with(attempt_step_one_call)
