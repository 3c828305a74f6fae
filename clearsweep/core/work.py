"""The kernel's arrays by name: named tuples of arrays, which Numba compiles for the CPU and,
as device-function arguments, for CUDA (the CUDA kernel ``device.run_cases`` keeps its own
launch arguments positional and builds these tuples inside).

A function handed a tuple reads its arrays by field (``work.dg``); no kernel function takes
more than about a dozen arguments. Each tuple is a value: its arrays stay owned by the caller
(the allocating entry points ``rk4.integrate`` and ``dopri5.integrate_dopri5``, or the batch
arrays of ``device.run_cases``), so building one allocates nothing.
"""

from collections import namedtuple

#: What the right-hand side reads besides the state (``dynamics.evaluate``): the packed
#: parameters p (layout.P_*) and jp (layout.J_*, one row per joint), the discrete contact
#: state s (layout.S_*, one row per joint) and the wear map (joint x polar x azimuth) [m].
Model = namedtuple("Model", ["p", "jp", "s", "wmap"])

#: Work arrays of the right-hand side's constrained solve: C, S, L (6 x 6) and the named
#: rows ``dynamics.VZ_*`` of vz (VZ_ROWS x 6).
Solve = namedtuple("Solve", ["C", "S", "L", "vz"])

#: One case's inputs and the wear it accumulates in place: p, jp, the initial state y0
#: (layout.N_Y), the wear map wmap [m], the per-axis projections proj (joint x 3 x
#: N_ANGLE_BINS) [m] and the worn volume wvol (per joint) [m^3].
Case = namedtuple("Case", ["p", "jp", "y0", "wmap", "proj", "wvol"])

#: What an integrator writes: the output rows t, y, d, wmax (n_save rows; ``keep_rows``
#: False leaves them untouched), the counters info (layout.I_*), the running statistics
#: stats (layout.M_*, whole run and settled window), the energy tracking track (layout.T_*)
#: and each joint's first impact time first [s] (-1: none); the Poincare sections sec
#: (revolutions x layout.N_SEC, the rows ``rk4.section_count`` gives, or fewer: those are
#: taken; every row is written, NaN where no section is taken).
Out = namedtuple("Out", ["t", "y", "d", "wmax", "info", "stats", "track", "first", "sec"])

#: The wear of accepted steps on its way to the map: the projections and worn volume (as
#: in :data:`Case`), the wear of the step being taken ``cur`` and the wear waiting to be
#: spread ``pend`` (joint x 6: sum V n (3), sum V, sum V A, R_i), the undo buffer buf_i,
#: buf_v (undo rows x 4: the step's wear, to undo a rejected step), the deepest bin written
#: per joint wmax [m] and the scratch of ``wear.deposit`` (4 npolar x 3).
Wear = namedtuple("Wear", ["proj", "wvol", "cur", "pend", "buf_i", "buf_v", "wmax", "scratch"])

#: Work arrays of ``rk4.advance``: y, ysave, k1, k1save, ksum, kst, yt (N_Y each: the
#: state, its copy at the step's start, the derivative at the (sub-)step's start and its
#: copy, the sum k2 + k3 of the stage derivatives, the stage derivative and the stage state);
#: dg, dgsave (N_D: diagnostics and copy); s, ssave (joint x N_S: contact state and copy);
#: msave (2 x N_M: statistics at the step's start); ddot_prev, ddot_prev_save, wmax,
#: first_save (one per joint: approach rates and copy, the deepest bin written, the first
#: impact times' copy); C, S, L, vz (:data:`Solve`); buf_i, buf_v, cur, pend, scratch (as in
#: :data:`Wear`); ysub, k1sub (N_Y: the state and its derivative at the start of a sub-step
#: that holds a Poincare section); prev (N_D, of which ``rk4.N_PV`` used: the sub-step
#: start's values that the in-step peaks of ``rk4.record_sample`` read) and secnext (N_Y, of which
#: the first 3 used, ``rk4.SN_*``: the next section's time and row, its slider
#: acceleration).
Rk4Work = namedtuple("Rk4Work", [
    "y", "ysave", "k1", "k1save", "ksum", "kst", "yt", "dg", "dgsave", "s", "ssave", "msave",
    "ddot_prev", "ddot_prev_save", "wmax", "first_save", "C", "S", "L", "vz", "buf_i",
    "buf_v", "cur", "pend", "scratch", "ysub", "prev", "k1sub", "secnext"])

#: Work arrays of ``dopri5.advance_dopri5``: y, y1, yt (N_Y: the state, the trial step's
#: 5th-order solution, the stage state); k1 ... k7, kt (N_Y: stage derivatives, the
#: derivative at a dense-output row); row (1 x N_Y) and yrow (N_Y): a dense-output state;
#: dg, dg1, dgo (N_D: diagnostics at the step's start, its end, a dense-output row); s,
#: ddot_prev, wmax, C, S, L, vz, buf_i, buf_v, cur, pend, scratch, prev as in
#: :data:`Rk4Work`.
Dopri5Work = namedtuple("Dopri5Work", [
    "y", "y1", "yt", "k1", "k2", "k3", "k4", "k5", "k6", "k7", "kt", "row", "yrow", "dg",
    "dg1", "dgo", "s", "ddot_prev", "wmax", "C", "S", "L", "vz", "buf_i", "buf_v", "cur",
    "pend", "scratch", "prev"])

