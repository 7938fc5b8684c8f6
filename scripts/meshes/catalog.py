"""The class meshes with their builders and coarse levels, in file order."""

from .buildings import make_garage, make_house
from .fences import make_fence_chain_link, make_fence_vinyl, make_fence_wood
from .trees import make_tree_deciduous, make_tree_pine
from .cars import CARS, make_car, make_pickup_bed
from .pedestrian_uav import make_pedestrian, make_sentinel
from .aircraft import make_fixed_wing, make_quadrotor


# ----------------------------------------------------------------------------------------------
def make_car_named(name, lod):
    m = make_car(name, CARS[name], lod)
    if name == "car_pickup":
        make_pickup_bed(m)
    return m


# (class mesh, builder(lod), its coarse levels), in the order of the files and of lod.json
CLASS_MESHES = [
    ("house_1", lambda lod: make_house("house_1", 1, lod), (1, 2)),
    ("house_2", lambda lod: make_house("house_2", 2, lod), (1, 2)),
    ("garage_1", lambda lod: make_garage("garage_1", 1, lod), (1, 2)),
    ("garage_2", lambda lod: make_garage("garage_2", 2, lod), (1, 2)),
    ("fence_wood", make_fence_wood, (1,)),
    ("fence_vinyl", make_fence_vinyl, (1,)),
    ("fence_chain_link", make_fence_chain_link, (1,)),
    ("tree_deciduous", make_tree_deciduous, (1, 2)),
    ("tree_pine", make_tree_pine, (1, 2)),
] + [(name, lambda lod, name=name: make_car_named(name, lod), (1, 2)) for name in CARS] + [
    ("pedestrian", lambda lod: make_pedestrian(), ()),
    ("sentinel", lambda lod: make_sentinel(), ()),
    ("aircraft_fixed_wing", lambda lod: make_fixed_wing(), ()),
    ("aircraft_quadrotor", lambda lod: make_quadrotor(), ()),
]


def build_all():
    """The fine meshes, then the lod1 meshes, then the lod2 meshes (each coarse mesh normalized
    with its fine mesh's design bounds)."""
    fine = [build(0) for _, build, _ in CLASS_MESHES]
    coarse = []
    for lod in (1, 2):
        for f, (_, build, levels) in zip(fine, CLASS_MESHES):
            if lod in levels:
                m = build(lod)
                m.bounds_from = f
                coarse.append(m)
    return fine + coarse
