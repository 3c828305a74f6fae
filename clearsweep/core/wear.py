"""Wear map over the socket sphere and the paper's per-axis projections (docs/physics.md 5).

The map stores the bin-averaged wear depth. A step's worn volume V = k F_N dS is spread over
the bins that the contact cap (area A, centred on the contact direction) overlaps, in
proportion to the overlap: a bin inside the cap deepens by V / A, the Archard depth
increment, whatever the bin's size; sum(depth * bin area) = sum(V) to rounding. The bin
containing a direction n is read back as h(n) for c_eff(n) = c + h(n).
"""

import math

from .compiled import compiled
from .layout import S_HINT_CZ_HI, S_HINT_CZ_LO, S_HINT_EDGE, S_HINT_IA, S_HINT_IP
from .target import on_device

#: How far inside its bin's edges a direction must lie for :func:`map_bin_near` to take the
#: bin from its hint: a cosine, and a sine relative to |x| + |y|; both bound the angle to
#: the edge from below, far above the bins' rounding (some 1e-15 rad; tests/test_wear_map.py).
BIN_MARGIN = 1e-9

# 4-point Gauss-Legendre rule on [-1, 1]: nodes and weights
_GX0 = 0.3399810435848563
_GX1 = 0.8611363115940526
_GW0 = 0.6521451548625461
_GW1 = 0.3478548451374538


@compiled
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


@compiled
def map_bin_near(n, npolar, nazim, s, j):
    """:func:`map_bin` (the same integers) of unit direction n, read from the bin that the
    hint in row j of the contact state s holds (``layout.S_HINT_*``) where n lies inside it
    by more than :data:`BIN_MARGIN`, and computed otherwise, the hint then set to n's bin.

    A contact moves little from one evaluation to the next, so the hint nearly always holds
    and the step saves an arccosine and an arctangent per contact. The hint tests with the
    bin's edges what the bin's formula decides with the angles: the polar bin ip holds
    cos(theta) in (cos((ip + 1) pi / npolar), cos(ip pi / npolar)], the azimuth bin ia the
    directions between its edges at -pi + 2 pi ia / nazim and the next (cross products,
    whose sign says the side). Inside by the margin, the angle is at least 1e-9 rad from an
    edge (|d theta / d cos theta| >= 1; sin x <= x), where the formula's rounding is some
    1e-15: both give the same bin. A direction near an edge, a pole or the azimuth's cut, a
    NaN, or an empty hint (all zero: no bounds hold) falls through to :func:`map_bin`. A
    device build (``target.on_device``) keeps :func:`map_bin`, its registers unchanged.
    """
    if on_device():
        return map_bin(n, npolar, nazim)
    cz = n[2]
    if (s[j, S_HINT_CZ_LO] < cz and cz < s[j, S_HINT_CZ_HI]
            and in_azimuth_hint(n[1], n[0], s, j)):
        return int(s[j, S_HINT_IP]), int(s[j, S_HINT_IA])
    ip, ia = map_bin(n, npolar, nazim)
    s[j, S_HINT_IP] = ip
    s[j, S_HINT_CZ_LO] = math.cos((ip + 1) * math.pi / npolar) + BIN_MARGIN
    s[j, S_HINT_CZ_HI] = math.cos(ip * math.pi / npolar) - BIN_MARGIN
    keep_azimuth_hint(s, j, ia, nazim)
    return ip, ia


@compiled
def angle_bin_near(y, x, nbins, s, j):
    """:func:`angle_bin` (the same integer) of the direction (x, y), read from the azimuth
    bin that the hint in row j of the contact state s holds where the direction lies inside
    it by more than :data:`BIN_MARGIN`, and computed otherwise, the hint then set to its bin:
    a bearing map's :func:`map_bin_near` (its polar columns unused). A device build keeps
    :func:`angle_bin`."""
    if on_device():
        return angle_bin(y, x, nbins)
    if in_azimuth_hint(y, x, s, j):
        return int(s[j, S_HINT_IA])
    ia = angle_bin(y, x, nbins)
    keep_azimuth_hint(s, j, ia, nbins)
    return ia


@compiled(inline="always")
def in_azimuth_hint(y, x, s, j):
    """Whether the direction (x, y) lies between the azimuth bin edges that row j of s holds
    (``layout.S_HINT_EDGE``: their (x, y), each bin's first edge first) by more than
    :data:`BIN_MARGIN`: each cross product's sign says the side of an edge, and against
    BIN_MARGIN (|x| + |y|) its size bounds the angle to the edge from below."""
    tol = BIN_MARGIN * (abs(x) + abs(y))
    return (s[j, S_HINT_EDGE] * y - s[j, S_HINT_EDGE + 1] * x > tol
            and x * s[j, S_HINT_EDGE + 3] - y * s[j, S_HINT_EDGE + 2] > tol)


@compiled(inline="always")
def keep_azimuth_hint(s, j, ia, nbins):
    """Azimuth bin ia of ``nbins`` as row j's hint: its index and its two edges' directions,
    at -pi + 2 pi ia / nbins and the next, as the bin formula puts them."""
    s[j, S_HINT_IA] = ia
    for k in range(2):
        edge = -math.pi + 2.0 * math.pi * (ia + k) / nbins
        s[j, S_HINT_EDGE + 2 * k] = math.cos(edge)
        s[j, S_HINT_EDGE + 2 * k + 1] = math.sin(edge)


@compiled
def map_interp(wmap, j, n):
    """Depth [m] of joint j's map in unit direction n (socket frame), bilinear between the
    bin centres (azimuth periodic, polar clamped at the poles): a worn surface without
    steps; and its surface gradient, a tangent 3-vector (socket frame) [m per rad]:
    dh/dtheta e_theta + (1 / sin theta) dh/dphi e_phi, theta the polar angle from +z and phi
    the azimuth of n. Zero at the poles (within 1e-9 rad) and across a clamped polar row.
    """
    npolar = wmap.shape[1]
    nazim = wmap.shape[2]
    cz = max(-1.0, min(1.0, n[2]))
    u = math.acos(cz) / math.pi * npolar - 0.5
    v = (math.atan2(n[1], n[0]) + math.pi) / (2.0 * math.pi) * nazim - 0.5
    i0 = int(math.floor(u))
    fu = u - i0
    clamped = False
    if i0 < 0:
        i0 = 0
        fu = 0.0
        clamped = True
    if i0 >= npolar - 1:
        i0 = npolar - 1
        fu = 0.0
        clamped = True
    i1 = min(i0 + 1, npolar - 1)
    k = int(math.floor(v))
    fv = v - k
    k0 = k % nazim
    k1 = (k + 1) % nazim
    w00 = wmap[j, i0, k0]
    w01 = wmap[j, i0, k1]
    w10 = wmap[j, i1, k0]
    w11 = wmap[j, i1, k1]
    h = ((1.0 - fu) * ((1.0 - fv) * w00 + fv * w01)
         + fu * ((1.0 - fv) * w10 + fv * w11))
    rho2 = n[0] * n[0] + n[1] * n[1]
    if not rho2 > 1e-18:
        return h, (0.0, 0.0, 0.0)
    dh_du = 0.0 if clamped else ((1.0 - fv) * w10 + fv * w11) - ((1.0 - fv) * w00 + fv * w01)
    dh_dv = (1.0 - fu) * (w01 - w00) + fu * (w11 - w10)
    dh_dtheta = dh_du * npolar / math.pi
    dh_dphi = dh_dv * nazim / (2.0 * math.pi)
    rho = math.sqrt(rho2)
    # e_theta = (cz nx, cz ny, -rho^2) / rho; e_phi / sin(theta) = (-ny, nx, 0) / rho^2
    a = dh_dtheta / rho
    b = dh_dphi / rho2
    return h, (a * cz * n[0] - b * n[1], a * cz * n[1] + b * n[0], -a * rho2)


@compiled
def bin_area(ip, npolar, nazim, radius):
    """Area of polar row ip's bins on a sphere of the given radius [m^2]."""
    t0 = math.pi * ip / npolar
    t1 = math.pi * (ip + 1) / npolar
    return radius * radius * (math.cos(t0) - math.cos(t1)) * (2.0 * math.pi / nazim)


@compiled
def angle_bin(y, x, nbins):
    """Bin of atan2(y, x) among ``nbins`` over [-180, 180) degrees (one-degree bins for the
    projections; a bearing map's azimuth bins)."""
    i = int((math.atan2(y, x) + math.pi) / (2.0 * math.pi) * nbins)
    if i >= nbins:
        i = nbins - 1
    if i < 0:
        i = 0
    return i


@compiled
def projection_bins(n, nbins):
    """Projection bins about x, y, z: atan2(n_z, n_y), atan2(n_x, n_z), atan2(n_y, n_x)."""
    return (angle_bin(n[2], n[1], nbins), angle_bin(n[0], n[2], nbins), angle_bin(n[1], n[0], nbins))


@compiled
def cap_half_width(theta, cos_tc, sin_tc, cos_psi):
    """Azimuthal half-width [rad] of a cap (centre polar angle tc, angular radius psi) at polar
    angle theta: the cap holds the directions with cos(angle to the centre) >= cos psi."""
    st = math.sin(theta)
    ct = math.cos(theta)
    den = st * sin_tc
    num = cos_psi - ct * cos_tc
    if den <= 0.0:
        return math.pi if num <= 0.0 else 0.0
    x = num / den
    if x <= -1.0:
        return math.pi
    if x >= 1.0:
        return 0.0
    return math.acos(x)


@compiled
def arc_to_bins(wmap, j, ip, phi_c, half, weight, nazim, dmax):
    """Add weight * (overlap of the arc [phi_c - half, phi_c + half] with each azimuth bin,
    in bin widths) to row ip of joint j's map; returns the largest value written (and dmax)."""
    dphi = 2.0 * math.pi / nazim
    u0 = (phi_c - half + math.pi) / dphi
    u1 = (phi_c + half + math.pi) / dphi
    k = int(math.floor(u0))
    kend = int(math.floor(u1))
    while k <= kend:
        lo = max(float(k), u0)
        hi = min(float(k + 1), u1)
        if hi > lo:
            ia = k % nazim
            wmap[j, ip, ia] += weight * (hi - lo)
            dmax = max(dmax, wmap[j, ip, ia])
        k += 1
    return dmax


@compiled
def deposit(wmap, j, n, vol, area, radius, scratch):
    """Spread the worn volume ``vol`` [m^3] over the bins overlapped by the contact cap of
    area ``area`` [m^2] centred on the unit direction n (socket frame), on a sphere of the
    given radius; each bin's depth grows by its share of the volume over its area.

    The overlap is integrated over polar angle with a 4-point Gauss rule per bin row and
    exactly in azimuth; the weights are normalised by their sum, so the volume is kept to
    rounding whatever the grid. A cap smaller than the quadrature resolves falls into the bin
    under its centre. A negative ``vol`` undoes an earlier deposit of the same cap.
    ``wmap`` holds every joint's map (joint, polar, azimuth), j picks one: the whole array
    is passed, never a view of it (a new view at every call).
    ``scratch`` is a float64[4 * npolar, 3] work array.

    Returns the largest depth of a bin written [m].
    """
    npolar = wmap.shape[1]
    nazim = wmap.shape[2]
    cz = max(-1.0, min(1.0, n[2]))
    tc = math.acos(cz)
    phi_c = math.atan2(n[1], n[0])
    cos_tc = math.cos(tc)
    sin_tc = math.sin(tc)
    # 1 - cos psi = A / (2 pi r^2); psi = 2 asin(sqrt(A / (4 pi r^2))) without cancellation
    frac = min(1.0, max(0.0, area / (4.0 * math.pi * radius * radius)))
    psi = 2.0 * math.asin(math.sqrt(frac))
    cos_psi = 1.0 - 2.0 * frac
    dtheta = math.pi / npolar
    ip0 = max(0, int(math.floor((tc - psi) / dtheta)))
    ip1 = min(npolar - 1, int(math.floor((tc + psi) / dtheta)))
    # pass 1: Gauss nodes (row, azimuthal half-width, weight) and their total, the cap's
    # area over r^2 as the quadrature sees it
    total = 0.0
    nn = 0
    for ip in range(ip0, ip1 + 1):
        a = max(ip * dtheta, tc - psi)
        b = min((ip + 1) * dtheta, tc + psi)
        if b <= a:
            continue
        mid = 0.5 * (a + b)
        hw = 0.5 * (b - a)
        for g in range(4):
            x = _GX0 if g < 2 else _GX1
            w = _GW0 if g < 2 else _GW1
            th = mid + (x if g % 2 == 0 else -x) * hw
            half = cap_half_width(th, cos_tc, sin_tc, cos_psi)
            if half > 0.0:
                wt = w * hw * math.sin(th)
                scratch[nn, 0] = ip
                scratch[nn, 1] = half
                scratch[nn, 2] = wt
                nn += 1
                total += wt * 2.0 * half
    if not total > 0.0:
        ip, ia = map_bin(n, npolar, nazim)
        wmap[j, ip, ia] += vol / bin_area(ip, npolar, nazim, radius)
        return wmap[j, ip, ia]
    # pass 2: each node's arc, in bin widths, times its share of the volume over bin area
    dmax = 0.0
    scale = vol * (2.0 * math.pi / nazim) / total
    for k in range(nn):
        ip = int(scratch[k, 0])
        weight = scale * scratch[k, 2] / bin_area(ip, npolar, nazim, radius)
        dmax = arc_to_bins(wmap, j, ip, phi_c, scratch[k, 1], weight, nazim, dmax)
    return dmax


@compiled
def worn_surface(wmap, j, n, coat, feedback, interp, hint=None):
    """What joint j's worn socket is in unit direction n (socket frame): (h, grad, worn).

    h [m] is the wear depth the contact adds to the clearance, c_eff(n) = c + h
    (docs/physics.md 3.1): 0 without ``feedback``, else read bilinearly between bin centres
    (``interp``, :func:`map_interp`) or from the bin holding n. ``grad`` is h's surface
    gradient [m per rad] (socket frame, tangent to the sphere): the bilinear surface's, zero
    for the bin read (a stepped surface, flat inside each bin). ``worn`` says whether the
    coating of thickness ``coat`` [m] (inf: none) is worn through there: the bin's depth
    reaches it. The one reading of a worn socket: the kernel's contact and the seated start
    both call it. ``hint``: None, or the contact state whose row j holds the last bin read,
    where the stepped read takes its bin (:func:`map_bin_near`, the same bin).
    """
    h = 0.0
    grad = (0.0, 0.0, 0.0)
    worn = False
    if feedback or coat < math.inf:
        if hint is None or interp:
            ip, ia = map_bin(n, wmap.shape[1], wmap.shape[2])
        else:
            ip, ia = map_bin_near(n, wmap.shape[1], wmap.shape[2], hint, j)
        if feedback:
            if interp:
                h, grad = map_interp(wmap, j, n)
            else:
                h = wmap[j, ip, ia]
        worn = coating_worn(wmap[j, ip, ia], coat)
    return h, grad, worn


@compiled
def coating_worn(depth, coat):
    """Whether a bin worn to ``depth`` [m] has lost its coating of thickness ``coat`` [m]
    (inf: none to lose): the one place the wear-through rule is written, for every joint
    type's surface."""
    return depth >= coat
