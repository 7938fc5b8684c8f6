"""Fences (wood, vinyl, chain link) and their coarse levels."""

from .parameters import budget
from .mesh import Mesh


# ----------------------------------------------------------------------------------------------
# Fences: runs along x, every part spans the whole length (the renderer stretches x to 3-30 m)
# except the two end posts.
# ----------------------------------------------------------------------------------------------
def make_fence_wood(lod=0):
    """lod 1: one box (board panel, rails, trim board and posts are all paint), from the boards'
    face to halfway between the boards' back and the posts' back, from halfway up the gap under
    the boards."""
    m = Mesh("fence_wood", budget("fence_wood", "fence", lod), paint=(0.56, 0.40, 0.25), lod=lod)
    hl, H = 5.0, 1.8
    if lod:
        m.box("paint", (-hl, -0.06, 0.025), (hl, 0.5 * (-0.035 + 0.06), H))
        return m
    m.box("paint", (-hl, -0.06, 0.05), (hl, -0.035, H))              # board panel
    for z0 in (0.30, 1.38):                                          # two back rails
        m.box("paint", (-hl, -0.036, z0), (hl, 0.035, z0 + 0.10))
    m.box("paint", (-hl, -0.065 + 0.005, H - 0.06), (hl, -0.02, H - 0.01))  # top trim board
    for sg in (-1, 1):                                               # end posts
        x0, x1 = sorted((sg * hl, sg * (hl - 0.1)))
        m.box("paint", (x0, -0.036, 0.0), (x1, 0.06, H - 0.05))
    return m


def make_fence_vinyl(lod=0):
    """lod 1: a paint box for panel, posts and bottom rail (halfway between the panel's and the
    posts' thickness, from halfway up the bottom rail's gap) and a trim box for the cap rail
    and post caps (the cap rail's width, up to halfway between their tops)."""
    m = Mesh("fence_vinyl", budget("fence_vinyl", "fence", lod), paint=(0.95, 0.95, 0.93),
             lod=lod)
    hl, H = 5.0, 1.8
    if lod:
        hw = 0.5 * (0.02 + 0.055)
        m.box("paint", (-hl, -hw, 0.02), (hl, hw, 1.64))
        m.box("trim", (-hl, -0.045, 1.62), (hl, 0.045, 0.5 * (1.72 + H)))
        return m
    m.box("paint", (-hl, -0.02, 0.08), (hl, 0.02, 1.64))             # privacy panel
    m.box("trim", (-hl, -0.035, 0.04), (hl, 0.035, 0.14))             # bottom rail
    m.box("trim", (-hl, -0.045, 1.62), (hl, 0.045, 1.72))             # cap rail
    for sg in (-1, 1):
        x0, x1 = sorted((sg * hl, sg * (hl - 0.07)))
        m.box("paint", (x0, -0.055, 0.0), (x1, 0.055, 1.75))         # end post
        m.box("trim", (x0, -0.06, 1.75), (x1, 0.06, H))               # post cap
    return m


def make_fence_chain_link(lod=0):
    """lod 1: a paint box for the mesh panel, wire and posts (halfway between the panel's and
    the posts' thickness, from just under the wire) and a frame box for the top rail (up to
    the posts' top)."""
    m = Mesh("fence_chain_link", budget("fence_chain_link", "fence", lod),
             paint=(0.36, 0.37, 0.38), lod=lod)
    hl, H = 5.0, 1.5
    if lod:
        hw = 0.5 * (0.006 + 0.06)
        m.box("paint", (-hl, -hw, 0.015), (hl, hw, H - 0.07))
        m.box("frame", (-hl, -hw, H - 0.07), (hl, hw, H))
        return m
    m.box("paint", (-hl, -0.006, 0.04), (hl, 0.006, H - 0.06))        # mesh panel
    m.box("frame", (-hl, -0.025, H - 0.07), (hl, 0.025, H - 0.02))    # top rail
    m.box("frame", (-hl, -0.01, 0.03), (hl, 0.01, 0.06))              # bottom tension wire
    for sg in (-1, 1):
        x0, x1 = sorted((sg * hl, sg * (hl - 0.06)))
        m.box("frame", (x0, -0.06, 0.0), (x1, 0.06, H))              # end posts
    return m
