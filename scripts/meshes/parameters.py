"""Materials, triangle budgets and level-of-detail parameters of the meshes."""

import math



FMT = "%.6f"
LOD_FILE = "lod.json"
UNIT_BOX = ((-0.5, 0.5), (-0.5, 0.5), (0.0, 1.0))

# ----------------------------------------------------------------------------------------------
# Materials (Kd). "paint" differs per mesh (a plausible default; the renderer replaces it).
# ----------------------------------------------------------------------------------------------
KD = {
    "roof": (0.30, 0.28, 0.27),
    "trim": (0.93, 0.93, 0.90),
    "window": (0.20, 0.26, 0.32),
    "door": (0.42, 0.24, 0.15),
    "garage_door": (0.86, 0.85, 0.81),
    "chimney": (0.55, 0.30, 0.24),
    "trunk": (0.40, 0.28, 0.18),
    "foliage": (0.26, 0.46, 0.19),
    "tire": (0.08, 0.08, 0.08),
    "glass": (0.14, 0.19, 0.24),
    "light_front": (0.95, 0.95, 0.86),
    "light_rear": (0.75, 0.08, 0.06),
    "bumper": (0.18, 0.18, 0.19),
    "skin": (0.80, 0.62, 0.50),
    "hair": (0.20, 0.14, 0.10),
    "pants": (0.20, 0.25, 0.36),
    "shoe": (0.12, 0.12, 0.12),
    "frame": (0.16, 0.16, 0.17),
    "arm": (0.22, 0.22, 0.24),
    "motor": (0.55, 0.55, 0.58),
    "prop": (0.10, 0.10, 0.10),
    "camera": (0.05, 0.05, 0.06),
}


# Triangle budgets of the class meshes per level of detail (lod1, lod2: the coarse meshes; a
# mesh name overrides its class). The pickup's open bed is three more boxes.
LOD_BUDGET = {0: {"house": 400, "garage": 400, "tree": 400, "car": 400, "fence": 400},
              1: {"house": 150, "garage": 80, "tree": 150, "car": 200, "car_pickup": 230,
                  "fence": 24, "tree_pine": 50},
              2: {"house": 50, "garage": 30, "tree": 40, "car": 60, "tree_pine": 24}}


def budget(name, cls, lod):
    return LOD_BUDGET[lod].get(name, LOD_BUDGET[lod][cls])


# lod1 canopy icosahedra: vertex radius / icosphere radius. Chosen numerically: it minimises
# the two-sided deviation of the lod1 canopy to the fine one (0.165 m; 0.314 m with the vertices
# on the icosphere, scale 1.0). For a sphere the balance is 1.0777 (deviation 0.078 r).
ICO_LOD_SCALE = 1.083

# lod2 canopy: per icosphere of the deciduous canopy (in make_tree_deciduous's order), a
# polyhedron in the icosphere's unit frame (then scaled by its radii): ("octahedron", rotation,
# vertex radii of its three axes) or ("bipyramid", sides, rotation, ring radius, pole radius,
# ring phase); rotation (ax, ay, az): Rz(az) Ry(ay) Rx(ax), its columns the polyhedron's axes.
# Found by a random search that minimised each one's sampled two-sided distance to its
# icosphere, within the unit box (crown 0.43 m with a pentagonal bipyramid, 0.49 m with the best
# octahedron found; the others 0.41-0.43 m).
LOD2_CANOPY = [("bipyramid", 5, (0.9816, -0.4301, -0.3465), 1.1917, 1.1904, -1.1382),
               ("octahedron", (-0.5765, 0.9542, 0.5369), (1.2271, 1.2206, 1.2574)),
               ("octahedron", (-0.3875, 0.7604, 0.325), (1.22, 1.22, 1.22)),
               ("octahedron", (-0.3875, 0.7604, 0.325), (1.22, 1.22, 1.22))]

# lod2 roof sheets (houses, garages): the roof slab collapsed to one plane per slope, this
# fraction of the slab thickness below its top at the ridge and at the eaves (the ridge cap
# stands above the ridge, the fascia hangs below the eaves).
LOD2_ROOF_SHEET = (0.32, 0.625)
# lod2 cars: the body's front and rear faces move this far inside the bumpers' outer faces
# (halfway through the 0.2 m bumpers, which are dropped), and the cabin's bottom reaches this
# far below the simplified body's top (so that no crack opens between them).
LOD2_BUMPER_INSET = 0.1
LOD2_CABIN_SINK = 0.02
# lod2 trunks (deciduous, pine): a triangular pyramid, base corner radius / the fine trunk's
# base radius, apex height / the fine trunk's height
LOD2_TRUNK = (1.33, 1.0)
# pine levels: trunk (sides, phase, radius scale; None: lod2_trunk), then per cone (sides,
# phase, radius scale); chosen numerically (a small grid over phases and scales)
LOD_PINE = {1: ((3, math.pi / 2, 1.33), [(10, 0.0, 1.0), (8, math.pi / 8, 1.02),
                                         (6, math.pi / 12, 1.035)]),
            2: (None, [(4, math.pi / 4, 1.15), (4, 0.0, 1.15), (4, math.pi / 4, 1.15)])}
# lod2 cars that keep their mirrors (as sheets on the mirrors' mid-planes, facing out)
LOD2_MIRRORS = ("car_sedan", "car_suv", "car_hatchback", "car_van")
# lod2 wheels: square sheets on the tyre's two faces, half-size / tyre radius
LOD2_WHEEL = 0.9
