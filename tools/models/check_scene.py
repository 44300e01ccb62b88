#!/usr/bin/python3
"""Geometric checks of the generated kitchen, shop, meshes and maps.

1. Every kitchen and shop link spans the world bounding box of the facts
   (except the two links the kitchen generator deliberately changes).
2. The bottles the tutorials spawn stand on a surface: the top of the
   supporting box is at the bottle's bottom (within BOTTLE_GAP) and the bottle's
   centre lies over it.
3. The PR2 base (a 0.668 m square) at every tutorial base pose overlaps no
   kitchen shape in 2D (below a given height for a pose under a table's edge),
   and those cells are free in the kitchen map, while the cells under the table
   and the island are occupied.
4. The object meshes are closed shells with the extents of the facts.
Exits 1 when a check fails.
"""

import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import facts_kitchen  # noqa: E402
import facts_pr2  # noqa: E402
import facts_shop  # noqa: E402
import rasterize_map  # noqa: E402
import stlgen  # noqa: E402
import urdfmodel  # noqa: E402
from urdfwriter import parse_vec  # noqa: E402

REPO = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
RES = os.path.join(REPO, "resources")
AABB_TOL = 0.002
BOTTLE_GAP = (-0.0005, 0.005)
PR2_HALF = 0.3341
CHANGED_LINKS = ("table_area_main", "kitchen_island_surface")

# name, (x, y, z) of the bottle origin, expected supporting link
BOTTLE_POSES = [
    ("move-bottle", (-1.6, -0.9, 0.86), "table_area_main"),
    ("move-bottle, out of view", (-2.0, -0.9, 0.86), "table_area_main"),
    ("move-bottle, other arm", (-1.1, -0.9, 0.86), "table_area_main"),
    ("move-bottle, near edge", (-1.1, -0.75, 0.86), "table_area_main"),
    ("spawn-two-bottles bottle-1", (-2.0, -0.9, 0.861667), "table_area_main"),
    ("spawn-two-bottles bottle-2", (-0.65, 2.0, 0.955), "kitchen_island_surface"),
]
# name, x, y, yaw of the PR2 base_footprint
BASE_POSES = [
    ("spawn", 0.0, 0.0, 0.0),
    ("*base-pose-near-table*", -1.447, -0.150, -math.pi / 2),
    ("*base-pose-near-counter*", -0.15, 2.0, math.pi),
    ("grasp-base-pose (counter)", -1.8547, -0.381, -math.pi / 2),
    # the 2017 tutorial's pose in front of the right side of the table: the base stands
    # under the edge of the table top (0.729 .. 0.759 m), clear of its legs
    ("seed 001 meal-table right", -2.0547, -0.481, -math.pi / 2, 0.70),
    ("sink navigation goal", 0.75, 0.70, 0.0),
    ("island navigation goal", -0.2, 1.5, math.pi),
    ("integration-test goal", 0.7, 0.7, 0.0),
]
# mesh, expected extent (x, y, z), expected (zmin)
MESHES = [("bottle", (0.071, 0.073, 0.181), -0.1008), ("cup", (0.081, 0.081, 0.150), -0.075),
          ("bowl", (0.166, 0.166, 0.100), -0.0502), ("mug", (0.122, 0.083, 0.096), -0.048),
          ("fork_plastic", (0.165, 0.019, 0.010), -0.0038),
          ("breakfast_cereal", (0.148, 0.058, 0.224), -0.1019),
          ("milk", (0.064, 0.065, 0.194), -0.0877), ("somat", (0.146, 0.096, 0.182), -0.085),
          ("denkmit", (0.058, 0.028, 0.143), -0.0715)]


class Report(object):
    def __init__(self):
        self.failures = 0
        self.passes = 0

    def check(self, ok, text):
        if ok:
            self.passes += 1
        else:
            self.failures += 1
            print("FAIL: " + text)


def link_aabbs(model):
    agg = {}
    for link, _kind, pose, half in urdfmodel.geometry_world_boxes(model):
        lo, hi = urdfmodel.world_aabb(pose, half)
        if link in agg:
            a = agg[link]
            agg[link] = ([min(p, q) for p, q in zip(a[0], lo)], [max(p, q) for p, q in zip(a[1], hi)])
        else:
            agg[link] = (lo, hi)
    return agg


def check_aabbs(rep, model, rows, rename=lambda n: n, skip=()):
    agg = link_aabbs(model)
    worst = (0.0, None)
    for row in rows:
        link = rename(row[0])
        if link in skip:
            continue
        flo, fhi = parse_vec(row[3]), parse_vec(row[4])
        if link not in agg:
            rep.check(False, "%s: link %s has no geometry" % (model.name, link))
            continue
        lo, hi = agg[link]
        err = max(abs(a - b) for a, b in zip(lo + hi, flo + fhi))
        rep.check(err <= AABB_TOL, "%s: %s AABB differs from the facts by %.4f m" % (model.name, link, err))
        worst = max(worst, (err, link))
    print("%s: %d link AABBs against the facts, max deviation %.4f m (%s)"
          % (model.name, len(rows) - len(skip), worst[0], worst[1]))


def inside_2d(pose, half, x, y, margin):
    inv_x = x - pose[0][3]
    inv_y = y - pose[1][3]
    lx = pose[0][0] * inv_x + pose[1][0] * inv_y
    ly = pose[0][1] * inv_x + pose[1][1] * inv_y
    return abs(lx) <= half[0] - margin and abs(ly) <= half[1] - margin


def check_bottles(rep, kitchen):
    shapes = urdfmodel.geometry_world_boxes(kitchen)
    bottom = -min(v[2] for t in stlgen.read_stl(os.path.join(RES, "meshes", "bottle.stl")) for v in t)
    for name, (x, y, z), expected in BOTTLE_POSES:
        zb = z - bottom
        best = None
        for link, kind, pose, half in shapes:
            if kind != "box" or not inside_2d(pose, half, x, y, 0.0):
                continue
            top = urdfmodel.world_aabb(pose, half)[1][2]
            if top <= zb + 0.02 and (best is None or top > best[1]):
                best = (link, top, pose, half)
        if best is None:
            rep.check(False, "%s: nothing under the bottle at %r" % (name, (x, y, z)))
            continue
        gap = zb - best[1]
        supported = inside_2d(best[2], best[3], x, y, 0.01)
        rep.check(best[0] == expected and BOTTLE_GAP[0] <= gap <= BOTTLE_GAP[1] and supported,
                  "%s: bottle at %r rests on %s with gap %.4f m (expected %s)"
                  % (name, (x, y, z), best[0], gap, expected))
        print("bottle %-28s on %-24s top %.4f, bottle bottom %.4f, gap %+.4f m"
              % (name, best[0], best[1], zb, gap))


def check_fork_in_drawer(rep, kitchen):
    """The fork spawned at (1.0, 0.9, 0.75) lies in the sink-area upper drawer opened 0.4 m."""
    tris = stlgen.read_stl(os.path.join(RES, "meshes", "fork_plastic.stl"))
    lo, hi = stlgen.bounds(tris)
    flo = [a + b for a, b in zip(lo, (1.0, 0.9, 0.75))]
    fhi = [a + b for a, b in zip(hi, (1.0, 0.9, 0.75))]
    values = {"sink_area_left_upper_drawer_main_joint": 0.4}
    hits, below = [], None
    for link, _kind, pose, half in urdfmodel.geometry_world_boxes(kitchen, values):
        blo, bhi = urdfmodel.world_aabb(pose, half)
        if all(blo[i] < fhi[i] and flo[i] < bhi[i] for i in range(3)):
            hits.append(link)
        elif (all(blo[i] < fhi[i] and flo[i] < bhi[i] for i in range(2)) and bhi[2] <= flo[2]
              and (below is None or bhi[2] > below[1])):
            below = (link, bhi[2])
    rep.check(not hits and below is not None and below[0] == "sink_area_left_upper_drawer_main",
              "fork in the opened drawer: overlaps %r, rests on %r" % (hits, below))
    print("fork in opened drawer overlaps %r, falls %.4f m onto %s" % (hits, flo[2] - below[1], below[0]))


def pr2_square(x, y, yaw):
    c, s = math.cos(yaw), math.sin(yaw)
    return [(x + c * px - s * py, y + s * px + c * py)
            for px, py in ((-PR2_HALF, -PR2_HALF), (PR2_HALF, -PR2_HALF),
                           (PR2_HALF, PR2_HALF), (-PR2_HALF, PR2_HALF))]


def clearance(square, poly):
    """Smallest distance between the vertices of one polygon and the edges of the other."""
    def seg_dist(p, a, b):
        ab = (b[0] - a[0], b[1] - a[1])
        ap = (p[0] - a[0], p[1] - a[1])
        t = max(0.0, min(1.0, (ap[0] * ab[0] + ap[1] * ab[1]) / max(ab[0] ** 2 + ab[1] ** 2, 1e-12)))
        return math.hypot(ap[0] - t * ab[0], ap[1] - t * ab[1])
    d = float("inf")
    for P, Q in ((square, poly), (poly, square)):
        for p in P:
            for i in range(len(Q)):
                d = min(d, seg_dist(p, Q[i], Q[(i + 1) % len(Q)]))
    return d


def check_bases(rep, kitchen, grid, res, origin):
    for name, x, y, yaw, *top in BASE_POSES:
        # shapes from the floor up to 1.9 m, or up to TOP for a pose under a table's edge
        feet = rasterize_map.footprints(kitchen, 0.0, top[0] if top else 1.9)
        square = pr2_square(x, y, yaw)
        hits = [link for link, poly in feet if rasterize_map.polygons_overlap(square, poly)]
        near = min((clearance(square, poly), link) for link, poly in feet)
        rep.check(not hits, "PR2 base at %s (%.3f %.3f) overlaps %r" % (name, x, y, sorted(set(hits))))
        c, r = int((x - origin[0]) / res), int((y - origin[1]) / res)
        rep.check(grid[r][c] == rasterize_map.FREE, "map cell of %s is not free" % name)
        print("PR2 base %-28s free: %s, nearest %s at %.3f m" % (name, not hits, near[1], near[0]))
    for what, x, y in (("table", -1.6, -0.9), ("island", -1.07, 1.7), ("fridge", 1.55, -1.0)):
        c, r = int((x - origin[0]) / res), int((y - origin[1]) / res)
        rep.check(grid[r][c] == rasterize_map.OCCUPIED, "map cell of the %s is not occupied" % what)


def check_meshes(rep):
    for name, extent, zmin in MESHES + [("body", None, None)]:
        tris = stlgen.read_stl(os.path.join(RES, "meshes", name + ".stl"))
        lo, hi = stlgen.bounds(tris)
        edges = {}
        for t in tris:
            for i in range(3):
                a, b = t[i], t[(i + 1) % 3]
                edges[(a, b)] = edges.get((a, b), 0) + 1
        closed = all(edges.get((b, a), 0) == n for (a, b), n in edges.items())
        rep.check(closed and stlgen.signed_volume(tris) > 0, "%s.stl is not a closed outward shell" % name)
        if extent is not None:
            ext = [h - l for l, h in zip(lo, hi)]
            rep.check(all(abs(e - f) <= 0.003 for e, f in zip(ext, extent)) and abs(lo[2] - zmin) <= 0.001,
                      "%s.stl extent %r / zmin %.4f differ from %r / %.4f" % (name, ext, lo[2], extent, zmin))
        else:
            height = (hi[2] - lo[2]) * 0.3
            rep.check(abs(height - 1.75) < 0.01 and abs(lo[2] * 0.3 + 1.0) < 1e-6,
                      "body.stl scaled by 0.3 is %.3f m tall with feet at %.3f" % (height, lo[2] * 0.3 + 1.0))


def main():
    rep = Report()
    kitchen = urdfmodel.load(os.path.join(RES, "iai_kitchen.urdf"))
    shop = urdfmodel.load(os.path.join(RES, "dm_shelves.urdf"))
    pr2 = urdfmodel.load(os.path.join(REPO, "robots", "pr2", "pr2.urdf"))
    check_aabbs(rep, pr2, [(r[0], r[1], r[2], r[5], r[6]) for r in facts_pr2.LINK_AABB])
    check_aabbs(rep, kitchen, facts_kitchen.COLLISION, skip=CHANGED_LINKS)
    check_aabbs(rep, shop, facts_shop.COLLISION, rename=lambda n: n.replace("shelf_2_shelf_2_", "shelf_2_"))
    for n in range(1, 6):
        for s in (1, 2):
            rep.check("shelf_%d_level_%d_link" % (s, n) in shop.links, "shop lacks shelf_%d_level_%d_link" % (s, n))
    check_bottles(rep, kitchen)
    check_fork_in_drawer(rep, kitchen)
    grid, res, origin = rasterize_map.read_map(os.path.join(RES, "maps", "kitchen"))
    check_bases(rep, kitchen, grid, res, origin)
    check_meshes(rep)
    print("check_scene: %d passed, %d failed" % (rep.passes, rep.failures))
    return 1 if rep.failures else 0


if __name__ == "__main__":
    sys.exit(main())
