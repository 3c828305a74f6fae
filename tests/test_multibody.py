"""The constrained solve's small systems (core/multibody.py, core/dynamics.py): the CPU's
arrangements for three rows (one ideal joint of the RSSP's A and B: a one-clearance case's
Schur complement, and its contact's mobility at a step's end), written out, and for six
(both ideal), the loops with their count a constant, compute what the loops compute,
operation for operation, so that results stay the same to the bit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clearsweep.core.dynamics import NZ, NZ_HELD, VZ_ROWS, back_substitute
from clearsweep.core.multibody import chol_solve, solve_spd


def spd(rng, scale):
    """A symmetric positive definite 3x3 matrix with entries of about ``scale``, as the
    Schur complement C M^-1 C^T of three rows of a constraint Jacobian."""
    a = rng.normal(size=(3, 5)) * scale
    return a @ a.T


def rows(rng):
    """vz's rows: 8 of NZ columns, entries over a few decades."""
    return rng.normal(size=(VZ_ROWS, NZ)) * 10.0 ** rng.uniform(-3, 3, size=(VZ_ROWS, NZ))


def chol_solve_reference(L, vz, b, nc):
    """L L^T x = vz[b] in place, the kernel's loops as plain Python floats (IEEE doubles,
    each sum in the loops' order, no fused multiply-add: what the compiled loops compute)."""
    x = [float(v) for v in vz[b, :nc]]
    for i in range(nc):
        acc = x[i]
        for k in range(i):
            acc -= float(L[i, k]) * x[k]
        x[i] = acc / float(L[i, i])
    for i in range(nc - 1, -1, -1):
        acc = x[i]
        for k in range(i + 1, nc):
            acc -= float(L[k, i]) * x[k]
        x[i] = acc / float(L[i, i])
    vz[b, :nc] = x


def solve_spd_reference(S, vz, b, nc, L):
    """The kernel's Cholesky loops (``solve_spd``) as plain Python floats; False where a
    pivot is not positive."""
    for i in range(nc):
        for j in range(i + 1):
            acc = float(S[i, j])
            for k in range(j):
                acc -= float(L[i, k]) * float(L[j, k])
            if i == j:
                if acc <= 0.0:
                    return False
                L[i, i] = math.sqrt(acc)
            else:
                L[i, j] = acc / float(L[j, j])
    chol_solve_reference(L, vz, b, nc)
    return True


@pytest.mark.parametrize("nc", [1, 2, 3, 4, 6])
@pytest.mark.parametrize("scale", [1e-4, 1.0, 1e3])
def test_the_solves_compute_the_loops_sums(nc, scale):
    """Three rows take the CPU's arrangement written out, six the loops with their count a
    constant, the other sizes the loops: each gives the loops' values to the bit."""
    rng = np.random.default_rng(42)
    for _ in range(100):
        a = rng.normal(size=(nc, nc + 2)) * scale
        S = np.zeros((NZ, NZ))
        S[:nc, :nc] = a @ a.T
        vz = rows(rng)
        b = int(rng.integers(VZ_ROWS))
        vz_ref = vz.copy()
        L = np.zeros((NZ, NZ))
        L_ref = np.zeros((NZ, NZ))
        assert solve_spd(S, vz, b, nc, L)
        assert solve_spd_reference(S, vz_ref, b, nc, L_ref)
        assert np.array_equal(L, L_ref)
        assert np.array_equal(vz, vz_ref)
        # the factor's solve alone (the contact mobility's, point_mobility)
        c = int(rng.integers(VZ_ROWS))
        chol_solve(L, vz, c, nc)
        chol_solve_reference(L, vz_ref, c, nc)
        assert np.array_equal(vz, vz_ref)


@pytest.mark.parametrize("row", [0, 1, 2])
def test_three_rows_not_positive_definite_fail_as_the_loops_do(row):
    rng = np.random.default_rng(7)
    S = np.zeros((NZ, NZ))
    S[:3, :3] = spd(rng, 1.0)
    # a pivot of zero at ``row``: the matrix is singular there
    S[row, :3] = 0.0
    S[:3, row] = 0.0
    vz = rows(rng)
    assert not solve_spd(S, vz.copy(), 4, 3, np.zeros((NZ, NZ)))
    assert not solve_spd_reference(S, vz.copy(), 4, 3, np.zeros((NZ, NZ)))


def back_substitute_reference(vz, f, C, lam, nc, minv, tmp):
    """vz[tmp] = vz[f] - C^T vz[lam] as plain Python floats, each sum in the kernel's order
    (IEEE doubles: what the compiled loops compute); the slider's two columns where it is
    free (minv[3] != 0)."""
    out = vz[tmp].copy()
    for k in range(NZ if minv[3] != 0.0 else NZ_HELD):
        acc = float(vz[f, k])
        for i in range(nc):
            acc -= float(C[i, k]) * float(vz[lam, i])
        out[k] = acc
    return out


@pytest.mark.parametrize("nc", [2, 3, 6])
@pytest.mark.parametrize("slider_free", [False, True])
def test_back_substitution_of_three_multipliers_is_the_loops_sum(nc, slider_free):
    rng = np.random.default_rng(nc)
    minv = (1 / 1.2, 1 / 0.8, 1 / 2.5 if slider_free else 0.0, 1 / 0.8 if slider_free else 0.0,
            1 / 1.2)
    mr_inv = (0.3, -0.01, -0.01, 0.2)
    for _ in range(100):
        vz = rows(rng)
        C = rng.normal(size=(NZ, NZ))
        expected = back_substitute_reference(vz, 0, C, 4, nc, minv, 5)
        back_substitute(vz, 0, C, 4, nc, minv, mr_inv, 5, 2)
        assert np.array_equal(vz[5, :NZ if slider_free else NZ_HELD],
                              expected[:NZ if slider_free else NZ_HELD])
