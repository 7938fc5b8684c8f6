"""Trees (deciduous, pine) and their coarse levels."""

import math

from .parameters import LOD2_CANOPY, LOD2_TRUNK, LOD_PINE, budget
from .geometry import add, cross, lerp, mul, sub, unit
from .mesh import Mesh


# ----------------------------------------------------------------------------------------------
# Trees
# ----------------------------------------------------------------------------------------------
def make_tree_deciduous(lod=0):
    """lod 1: square trunk, triangular branches, icosahedra. lod 2: a triangular pyramid trunk
    (lod2_trunk), each branch one triangle (a sheet through its axis, facing up), the canopy
    an octahedron or bipyramid per icosphere (LOD2_CANOPY)."""
    m = Mesh("tree_deciduous", budget("tree_deciduous", "tree", lod), lod=lod)
    D, H = 5.0, 9.0
    r_tr = 0.06 * D / math.cos(math.pi / 8)   # octagon across flats = 12% of the width
    if lod >= 2:
        lod2_trunk(m, 0.45 * H * LOD2_TRUNK[1], r_tr * LOD2_TRUNK[0])
    elif lod:  # square trunk with the octagon's corner radius
        m.frustum("trunk", (0, 0, 0), (0, 0, 0.45 * H), r_tr, r_tr * 0.8, 4, phase=math.pi / 4)
    else:
        m.frustum("trunk", (0, 0, 0), (0, 0, 0.45 * H), r_tr, r_tr * 0.8, 8, phase=math.pi / 8)
    for ang, z0, z1, reach in ((20.0, 2.3, 3.9, 1.3), (145.0, 2.7, 4.1, 1.2),
                               (260.0, 2.5, 3.7, 1.25)):
        a = math.radians(ang)
        d = (math.cos(a), math.sin(a), 0.0)
        tip = (reach * d[0], reach * d[1], z1)
        if lod >= 2:
            side = (-d[1] * 0.11, d[0] * 0.11, 0.0)
            base = (0.0, 0.0, z0)
            up = unit(cross(sub(tip, base), side))
            m.sheet("trunk", [sub(base, side), add(base, side), tip],
                    sub(lerp(base, tip, 0.5), mul(up, 0.1)))
        elif lod:  # triangular, with the square beam's corner radius
            m.frustum("trunk", (0.0, 0.0, z0), tip, 0.11 * math.sqrt(2.0), 0.06 * math.sqrt(2.0), 3,
                      u_hint=(-d[1], d[0], 0.0))
        else:
            m.beam("trunk", (0.0, 0.0, z0), tip, (-d[1], d[0], 0.0), 0.11, 0.11, 0.06, 0.06)
    # canopy: 4 overlapping icospheres; their union spans exactly +-D/2 in x and y,
    # from 35% to 100% of the height
    h = D / 2
    blobs = [((-0.85, 0.10, 6.9), (h - 0.85, 1.65, 2.1)),    # crown: min x, top
             ((1.05, 0.30, 5.4), (h - 1.05, 1.45, 1.9)),     # max x
             ((-0.15, 1.10, 5.25), (1.40, h - 1.10, 1.85)),  # max y
             ((0.25, -1.05, 5.0), (1.45, h - 1.05, 1.85))]   # min y, bottom (3.15 = 35%)
    for (c, r), shape in zip(blobs, LOD2_CANOPY):
        m.ellipsoid("foliage", c, r, shape)
    return m


def lod2_trunk(m, height, r):
    """A triangular pyramid standing on the ground, base corner radius r, as three side sheets
    facing out (its base would lie on the ground, never seen)."""
    base = [(r * math.cos(math.pi / 2 + 2 * math.pi * k / 3),
             r * math.sin(math.pi / 2 + 2 * math.pi * k / 3), 0.0) for k in range(3)]
    for k in range(3):
        m.sheet("trunk", [base[k], base[(k + 1) % 3], (0.0, 0.0, height)], (0.0, 0.0, height / 3))


def make_tree_pine(lod=0):
    """lod 1, 2: fewer trunk and cone sides (LOD_PINE: sides, phase and radius scale); lod 2:
    the trunk a triangular pyramid (lod2_trunk)."""
    m = Mesh("tree_pine", budget("tree_pine", "tree", lod), lod=lod)
    m.kd_override["foliage"] = (0.13, 0.31, 0.16)
    D, H = 4.0, 10.0
    r = D / 2
    if lod:
        trunk, cones = LOD_PINE[lod]
        if trunk is None:
            lod2_trunk(m, 0.45 * H * LOD2_TRUNK[1], 0.22 * LOD2_TRUNK[0])
        else:
            n, ph, sc = trunk
            m.frustum("trunk", (0, 0, 0), (0, 0, 0.45 * H), 0.22 * sc, 0.15 * sc, n, phase=ph)
    else:
        m.frustum("trunk", (0, 0, 0), (0, 0, 0.45 * H), 0.22, 0.15, 8, phase=math.pi / 8)
    # three stacked 12-sided cones; the bottom one has vertices on the axes (extent +-D/2)
    for k, (zb, zt, rr, ph) in enumerate(((0.15 * H, 0.62 * H, r, 0.0),
                                          (0.38 * H, 0.82 * H, 0.78 * r, math.pi / 12),
                                          (0.60 * H, H, 0.55 * r, 0.0))):
        if lod:
            n, ph, sc = cones[k]
            m.cone("foliage", (0, 0, zb), (0, 0, zt), rr * sc, n, phase=ph)
        else:
            m.cone("foliage", (0, 0, zb), (0, 0, zt), rr, 12, phase=ph)
    return m
