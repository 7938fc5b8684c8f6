#!/usr/bin/env python3
"""Generate the low-poly Wavefront OBJ/MTL meshes of hameritt's renderer (models/meshes/).

    /usr/bin/python3 scripts/make_meshes.py            # write models/meshes/*.obj|mtl, then check them
    /usr/bin/python3 scripts/make_meshes.py --check    # only check the files already there
    /usr/bin/python3 scripts/make_meshes.py --out DIR  # write somewhere else

Standard library only and deterministic: running it twice gives byte-identical files. Besides
the fine meshes it writes coarse levels of detail of the class meshes (<name>_lod1.obj and, for
the heaviest, <name>_lod2.obj, from the same builders with lod=1 or 2) and lod.json (an upper
bound on each level's deviation from the fine mesh).

Conventions (the renderer depends on them; see models/README.md):
* triangles only, every face "f v//vn" with its own (flat) normal, counter-clockwise seen from
  outside; every part is a closed convex solid (boxes, prisms, cylinders, cones, icospheres;
  at lod2 a few of them have faces of two materials), except the decals and sheets of coarse
  meshes (one planar convex polygon seen from one side: a thin slab's outer face or mid-plane).
* coarse meshes are normalized with their fine mesh's bounds: they lie within the unit box.
* class meshes: x forward (heading), y left, z up, origin at the centre of the bottom face; the
  vertices span exactly [-0.5, 0.5] x [-0.5, 0.5] x [0, 1] (the renderer scales each axis by the
  entity's box). Each part is designed in metres at a typical real size, then normalized.
* sentinel.obj (the UAV) stays in metres, base_link FLU frame, origin at the centre of mass.
* materials: one .mtl per .obj; "paint" is replaced by the entity colour at render time.
"""

import os
import sys

from meshes.parameters import LOD_FILE
from meshes.catalog import build_all
from meshes.lod import lod_json, lod_table, print_lod_table
from meshes.checks import report_levels, run_checks


def main(argv):
    here = os.path.dirname(os.path.abspath(__file__))
    outdir = os.path.join(os.path.dirname(here), "models", "meshes")
    check_only = False
    i = 0
    while i < len(argv):
        if argv[i] == "--check":
            check_only = True
        elif argv[i] == "--out" and i + 1 < len(argv):
            outdir = argv[i + 1]
            i += 1
        else:
            print(__doc__)
            return 2
        i += 1
    if check_only:
        # the files must be what this script writes now (so the in-memory part checks apply)
        import tempfile
        meshes = build_all()
        stale = []
        with tempfile.TemporaryDirectory() as tmp:
            for m in meshes:
                m.write(tmp)
            table = lod_table(meshes)
            with open(os.path.join(tmp, LOD_FILE), "w", newline="\n") as f:
                f.write(lod_json(table))
            for fn in [m.name + ext for m in meshes for ext in (".obj", ".mtl")] + [LOD_FILE]:
                old = os.path.join(outdir, fn)
                with open(os.path.join(tmp, fn), "rb") as f:
                    want = f.read()
                have = None
                if os.path.exists(old):
                    with open(old, "rb") as f:
                        have = f.read()
                if have != want:
                    stale.append(fn)
        ok = run_checks(outdir, meshes)
        ok = report_levels(table) and ok
        for fn in stale:
            print("STALE: %s differs from what the script generates (regenerate)" % fn)
        return 0 if ok and not stale else 1
    os.makedirs(outdir, exist_ok=True)
    meshes = build_all()
    for m in meshes:
        m.write(outdir)
    table = lod_table(meshes)
    with open(os.path.join(outdir, LOD_FILE), "w", newline="\n") as f:
        f.write(lod_json(table))
    print_lod_table(table)
    print()
    ok = run_checks(outdir, meshes)
    return 0 if report_levels(table) and ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
