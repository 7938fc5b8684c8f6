"""Houses and garages: gable buildings with windows, doors and their coarse levels."""

from .parameters import LOD2_ROOF_SHEET, budget
from .geometry import hexa_faces
from .mesh import Mesh


# ----------------------------------------------------------------------------------------------
# Houses and garages: a gable building (walls = pentagonal prism, two roof slabs, fascia boards,
# ridge cap). `along` is the ridge axis ("y" for houses, "x" for garages).
# ----------------------------------------------------------------------------------------------
def gable_building(m, along, half_across_wall, half_along_wall, half_across_roof, half_along_roof,
                   wall_h, height, roof_t, fascia=0.04, ridge_cap=True):
    """lod 1: the fascia boards become decals on their outer (eave) faces, no ridge cap.
    lod 2: each roof slab and its fascia become one sheet from the ridge to the eaves,
    LOD2_ROOF_SHEET of the slab's thickness below its top (no fascia, no ridge cap)."""
    def P(a, b, z):  # (across, along, z) -> (x, y, z)
        return (a, b, z) if along == "y" else (b, a, z)

    # slope chosen so that the roof underside meets the wall top at the wall line
    s = (height - roof_t - wall_h) / half_across_wall
    ridge_under = height - roof_t
    wa, wb = half_across_wall, half_along_wall
    prof = [(-wa, 0.0), (wa, 0.0), (wa, wall_h), (0.0, ridge_under), (-wa, wall_h)]
    m.extrude("paint", [P(a, -wb, z) for a, z in prof], P(0.0, 2 * wb, 0.0))
    ra, rb = half_across_roof, half_along_roof
    if m.lod >= 2:
        z_ridge = height - LOD2_ROOF_SHEET[0] * roof_t
        z_eave = height - s * ra - LOD2_ROOF_SHEET[1] * roof_t
        for sg in (-1.0, 1.0):
            m.sheet("roof", [P(0.0, -rb, z_ridge), P(sg * ra, -rb, z_eave), P(sg * ra, rb, z_eave),
                             P(0.0, rb, z_ridge)], P(0.0, 0.0, 0.0))
        return s
    slab_end = ra - fascia
    for sg in (-1.0, 1.0):
        def top(a):
            return height - s * a

        bottom = [P(0.0, -rb, height - roof_t), P(sg * slab_end, -rb, top(slab_end) - roof_t),
                  P(sg * slab_end, rb, top(slab_end) - roof_t), P(0.0, rb, height - roof_t)]
        topq = [P(0.0, -rb, height), P(sg * slab_end, -rb, top(slab_end)),
                P(sg * slab_end, rb, top(slab_end)), P(0.0, rb, height)]
        m.hexa("roof", bottom, topq)
        if fascia > 0:
            drop = roof_t + 0.05
            fb = [P(sg * slab_end, -rb, top(slab_end) - drop), P(sg * ra, -rb, top(ra) - drop),
                  P(sg * ra, rb, top(ra) - drop), P(sg * slab_end, rb, top(slab_end) - drop)]
            ft = [P(sg * slab_end, -rb, top(slab_end)), P(sg * ra, -rb, top(ra)),
                  P(sg * ra, rb, top(ra)), P(sg * slab_end, rb, top(slab_end))]
            if m.lod:
                m.decal("trim", hexa_faces(fb, ft), 3)  # the face at sg * ra
            else:
                m.hexa("trim", fb, ft)
    if ridge_cap and not m.lod:
        w = 0.13
        cap = [(-w, height - s * w - 0.02), (w, height - s * w - 0.02), (w, height - s * w + 0.05),
               (0.0, height + 0.06), (-w, height - s * w + 0.05)]
        m.extrude("roof", [P(a, -rb - 0.01, z) for a, z in cap], P(0.0, 2 * rb + 0.02, 0.0))
    return s


def wall_slab(m, mat, face, center, w, z0, z1, proud, inset=0.03):
    """A window/door slab on a house wall. face: ('x', x_wall, sign) or ('y', y_wall, sign);
    center: coordinate along the wall; w: width; z0..z1; proud: how far it stands out.
    lod > 0: a decal on the slab's outer face."""
    axis, wall, sg = face
    lo_o, hi_o = sorted((wall - sg * inset, wall + sg * proud))
    if axis == "x":
        m.box_or_decal(mat, (lo_o, center - w / 2, z0), (hi_o, center + w / 2, z1), (axis, sg))
    else:
        m.box_or_decal(mat, (center - w / 2, lo_o, z0), (center + w / 2, hi_o, z1), (axis, sg))


# lod2 windows: per (wall, row), groups of windows (indices into that row's list) each drawn as
# ONE decal of the same total area (width: the group's window widths added up, centred on the
# mean of their centres, the row's height); a window in no group is dropped. Rows are merged
# where the gaps are about a window width (house_1); house_2 (19 windows, 12 triangles left for
# them) keeps one band per storey and wall where it can and drops its front's lone downstairs
# window and its gable ends' upstairs windows.
LOD2_WINDOWS = {
    "house_1": {("front", 0): [(0,), (1, 2)], ("back", 0): [(0, 1, 2, 3)],
                ("left", 0): [(0,), (1,)], ("right", 0): [(0,), (1,)]},
    "house_2": {("front", 0): [(1, 2)], ("front", 1): [(0, 1, 2, 3)],
                ("back", 0): [(0, 1, 2)], ("back", 1): [(0, 1, 2)],
                ("left", 0): [(0, 1)], ("right", 0): [(0, 1)]},
}


def house_windows(storeys, ri):
    """Window centres along the wall of row ri: front (y), back (y), gable ends (x)."""
    fy = [-3.5, 1.3, 3.5] if ri == 0 else [-3.5, -0.9, 1.3, 3.5]  # beside/above the door
    by = [-3.6, -1.2, 1.2, 3.6] if storeys == 1 else [-3.3, 0.0, 3.3]
    sx = [-2.2, 2.2] if ri == 0 else [0.0]
    return fy, by, sx


def make_house(name, storeys, lod=0):
    """lod 2: walls, roof sheets, the lod1 chimney, the door and merged window decals, the
    step and house_2's belt course as sheets at mid-height (no trim, no corner boards)."""
    m = Mesh(name, budget(name, "house", lod), paint=(0.86, 0.82, 0.70), lod=lod)
    L, W = 10.0, 11.0
    H = 5.2 if storeys == 1 else 8.0
    wall_h = 2.9 if storeys == 1 else 5.6
    wx, wy = 4.6, 5.2          # walls (inset so the eaves touch +-L/2, gable overhang in y)
    rx, ry = L / 2, 5.5
    s = gable_building(m, "y", wx, wy, rx, ry, wall_h, H, 0.2)
    front, back = ("x", -wx, -1.0), ("x", wx, 1.0)
    left, right = ("y", wy, 1.0), ("y", -wy, -1.0)
    # front door, its frame and a step (door faces the street, -x)
    door_y = -0.9
    step = ((-rx, door_y - 0.85, 0.0), (-wx + 0.01, door_y + 0.85, 0.18))
    if lod < 2:
        wall_slab(m, "trim", front, door_y, 1.3, 0.15, 2.35, 0.03)
    wall_slab(m, "door", front, door_y, 1.0, 0.18, 2.25, 0.06)
    if lod < 2:
        m.box("trim", *step)
    else:
        m.box_sheet("trim", step[0], step[1], ("z", 1), 0.5)
    rows = [(0.9, 2.2)] if storeys == 1 else [(0.95, 2.25), (3.75, 5.0)]
    win_w = 1.2
    for ri, (z0, z1) in enumerate(rows):
        fy, by, sx = house_windows(storeys, ri)
        if lod >= 2:
            for wall, face, cs in (("front", front, fy), ("back", back, by), ("left", left, sx),
                                   ("right", right, sx)):
                for group in LOD2_WINDOWS[name].get((wall, ri), []):
                    c = sum(cs[i] for i in group) / len(group)
                    wall_slab(m, "window", face, c, win_w * len(group), z0, z1, 0.045)
            continue
        for y in fy:
            if storeys == 1:  # one-storey: trimmed front windows
                wall_slab(m, "trim", front, y, win_w + 0.2, z0 - 0.12, z1 + 0.1, 0.025)
            wall_slab(m, "window", front, y, win_w, z0, z1, 0.045)
        for y in by:
            wall_slab(m, "window", back, y, win_w, z0, z1, 0.045)
        for x in sx:
            wall_slab(m, "window", left, x, win_w, z0, z1, 0.045)
            wall_slab(m, "window", right, x, win_w, z0, z1, 0.045)
    belt = ((-wx - 0.04, -wy - 0.04, 2.75), (wx + 0.04, wy + 0.04, 2.95))
    if storeys == 1 and lod < 2:  # corner boards
        for sx_ in (-1, 1):
            for sy_ in (-1, 1):
                x0, x1 = sorted((sx_ * (wx + 0.05), sx_ * (wx - 0.18)))
                y0, y1 = sorted((sy_ * (wy + 0.05), sy_ * (wy - 0.18)))
                m.box("trim", (x0, y0, 0.0), (x1, y1, wall_h - 0.02))
    elif storeys != 1 and lod < 2:  # belt course between the storeys
        m.box("trim", *belt)
    elif storeys != 1:  # (lod2: its mid-plane; its top and bottom run through the whole house)
        m.box_sheet("trim", belt[0], belt[1], ("z", 1), 0.5)
    # chimney on the back slope, through the ridge height, with a cap
    cx0, cx1, cy0, cy1 = 1.3, 2.0, 3.0, 3.8
    z_in = H - s * cx1 - 0.6
    top = H + 0.3
    if lod:  # chimney and cap as one box halfway between them (sides +0.03, top +0.04)
        m.box("chimney", (cx0 - 0.03, cy0 - 0.03, z_in), (cx1 + 0.03, cy1 + 0.03, top + 0.04))
    else:
        m.box("chimney", (cx0, cy0, z_in), (cx1, cy1, top))
        m.box("chimney", (cx0 - 0.06, cy0 - 0.06, top), (cx1 + 0.06, cy1 + 0.06, top + 0.08))
    return m


def make_garage(name, doors, lod=0):
    """lod 2: walls, roof sheets, the lod1 door, garage door and window decals, no trim."""
    m = Mesh(name, budget(name, "garage", lod), paint=(0.86, 0.82, 0.70), lod=lod)
    L = 6.7
    W = 3.9 if doors == 1 else 6.6
    H, wall_h = 3.1, 2.6
    wx, wy = L / 2 - 0.15, W / 2 - 0.15
    gable_building(m, "x", wy, wx, W / 2, L / 2, wall_h, H, 0.15, fascia=0.04)
    front = ("x", -wx, -1.0)
    door_w = 2.7 if doors == 1 else 2.5
    centres = [0.0] if doors == 1 else [-1.45, 1.45]
    gap, dz, nslab = 0.035, 2.2, 4
    sh = (dz - gap * (nslab - 1)) / nslab
    for yc in centres:
        if lod < 2:
            wall_slab(m, "trim", front, yc, door_w + 0.16, 0.0, dz + 0.1, 0.03)
        if lod:  # one decal over the panels (the 3.5 cm gaps between them are sub-pixel)
            wall_slab(m, "garage_door", front, yc, door_w, 0.01, dz, 0.07)
            continue
        for k in range(nslab):
            z0 = k * (sh + gap)
            wall_slab(m, "garage_door", front, yc, door_w, z0 + (0.01 if k == 0 else 0.0),
                      z0 + sh, 0.07)
    # side door near the back and a window on the +y wall, a window on the back wall
    if lod < 2:
        wall_slab(m, "trim", ("y", wy, 1.0), 1.9, 1.05, 0.0, 2.15, 0.03)
    wall_slab(m, "door", ("y", wy, 1.0), 1.9, 0.9, 0.01, 2.05, 0.06)
    wall_slab(m, "window", ("y", wy, 1.0), -0.8, 1.0, 1.1, 1.9, 0.045)
    wall_slab(m, "window", ("x", wx, 1.0), 0.0, 1.0, 1.1, 1.9, 0.045)
    return m
