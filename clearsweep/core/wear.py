"""Wear map over the socket sphere and the paper's per-axis projections (DESIGN 5).

The map stores the bin-averaged wear depth: a step's worn volume V = k F_N dS goes into the
bin under the contact point as V / (bin area), so that sum(depth * bin area) = sum(V) exactly.
The same bin is read back as h(n) for c_eff(n) = c + h(n) (nearest bin, no interpolation:
a worn direction sees exactly the depth it received).
"""

import math

from numba import njit


@njit(cache=True)
def map_bin(n, npolar, nazim):
    """Indices (polar, azimuth) of the map bin containing unit direction n (socket frame)."""
    cz = max(-1.0, min(1.0, n[2]))
    ip = int(math.acos(cz) / math.pi * npolar)
    if ip >= npolar:
        ip = npolar - 1
    ia = int((math.atan2(n[1], n[0]) + math.pi) / (2.0 * math.pi) * nazim)
    if ia >= nazim:
        ia = nazim - 1
    if ia < 0:
        ia = 0
    return ip, ia


@njit(cache=True)
def bin_area(ip, npolar, nazim, radius):
    """Area of polar row ip's bins on a sphere of the given radius [m^2]."""
    t0 = math.pi * ip / npolar
    t1 = math.pi * (ip + 1) / npolar
    return radius * radius * (math.cos(t0) - math.cos(t1)) * (2.0 * math.pi / nazim)


@njit(cache=True)
def angle_bin(y, x, nbins):
    """One-degree bin of atan2(y, x) over [-180, 180) degrees."""
    i = int((math.atan2(y, x) + math.pi) / (2.0 * math.pi) * nbins)
    if i >= nbins:
        i = nbins - 1
    if i < 0:
        i = 0
    return i


@njit(cache=True)
def projection_bins(n, nbins):
    """Projection bins about x, y, z: atan2(n_z, n_y), atan2(n_x, n_z), atan2(n_y, n_x)."""
    return (angle_bin(n[2], n[1], nbins), angle_bin(n[0], n[2], nbins), angle_bin(n[1], n[0], nbins))
