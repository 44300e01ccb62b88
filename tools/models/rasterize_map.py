#!/usr/bin/python3
"""Rasterise the collision geometry of a URDF into a map_server occupancy map.

Every box, cylinder and sphere (cylinders and spheres as their bounding boxes)
whose world z range overlaps [zmin, zmax] marks each grid cell its 2D
projection overlaps as occupied (0); all other cells are free (254).  Joints
are at 0; the URDF root is the map frame.  Writes PREFIX.pgm (binary P5) and
PREFIX.yaml.

usage: rasterize_map.py URDF PREFIX [--resolution 0.05] [--origin X Y]
                        [--size W H] [--zmin 0.05] [--zmax 1.9]
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import urdfmodel  # noqa: E402

OCCUPIED, FREE = 0, 254


def corners_2d(pose, half):
    pts = []
    for sx in (-1, 1):
        for sy in (-1, 1):
            for sz in (-1, 1):
                p = urdfmodel.apply(pose, (sx * half[0], sy * half[1], sz * half[2]))
                pts.append((p[0], p[1]))
    return convex_hull(pts)


def convex_hull(points):
    pts = sorted(set(points))
    if len(pts) <= 2:
        return pts

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


def _separated(axis, a, b):
    pa = [axis[0] * p[0] + axis[1] * p[1] for p in a]
    pb = [axis[0] * p[0] + axis[1] * p[1] for p in b]
    return max(pa) <= min(pb) or max(pb) <= min(pa)


def polygons_overlap(a, b):
    """Separating-axis test for two convex polygons (lists of 2D points)."""
    for poly in (a, b):
        n = len(poly)
        for i in range(n):
            p, q = poly[i], poly[(i + 1) % n]
            axis = (q[1] - p[1], p[0] - q[0])
            if axis == (0, 0):
                continue
            if _separated(axis, a, b):
                return False
    return True


def footprints(model, zmin, zmax, values=None, root_pose=None):
    """2D convex footprints (with link names) of the shapes overlapping zmin..zmax."""
    out = []
    for link, _kind, pose, half in urdfmodel.geometry_world_boxes(model, values, root_pose):
        lo, hi = urdfmodel.world_aabb(pose, half)
        if hi[2] < zmin or lo[2] > zmax:
            continue
        out.append((link, corners_2d(pose, half)))
    return out


def rasterize(model, resolution, origin, size, zmin, zmax):
    width = int(round(size[0] / resolution))
    height = int(round(size[1] / resolution))
    grid = [[FREE] * width for _ in range(height)]   # grid[row][col], row 0 = lowest y
    for _link, poly in footprints(model, zmin, zmax):
        xs = [p[0] for p in poly]
        ys = [p[1] for p in poly]
        c0 = max(0, int((min(xs) - origin[0]) / resolution))
        c1 = min(width - 1, int((max(xs) - origin[0]) / resolution))
        r0 = max(0, int((min(ys) - origin[1]) / resolution))
        r1 = min(height - 1, int((max(ys) - origin[1]) / resolution))
        for r in range(r0, r1 + 1):
            y0 = origin[1] + r * resolution
            for c in range(c0, c1 + 1):
                if grid[r][c] == OCCUPIED:
                    continue
                x0 = origin[0] + c * resolution
                cell = [(x0, y0), (x0 + resolution, y0), (x0 + resolution, y0 + resolution),
                        (x0, y0 + resolution)]
                if polygons_overlap(cell, poly):
                    grid[r][c] = OCCUPIED
    return grid


def write_map(prefix, grid, resolution, origin):
    height, width = len(grid), len(grid[0])
    with open(prefix + ".pgm", "wb") as f:
        f.write(("P5\n%d %d\n255\n" % (width, height)).encode("ascii"))
        for r in range(height - 1, -1, -1):
            f.write(bytes(grid[r]))
    with open(prefix + ".yaml", "w") as f:
        f.write("image: %s.pgm\n" % os.path.basename(prefix))
        f.write("resolution: %s\n" % repr(float(resolution)))
        f.write("origin: [%s, %s, 0.0]\n" % (repr(float(origin[0])), repr(float(origin[1]))))
        f.write("negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n")


def read_map(prefix):
    """(grid with row 0 = lowest y, resolution, origin) of a map written by write_map."""
    meta = {}
    with open(prefix + ".yaml") as f:
        for line in f:
            if ":" in line:
                k, v = line.split(":", 1)
                meta[k.strip()] = v.strip()
    res = float(meta["resolution"])
    origin = [float(x) for x in meta["origin"].strip("[]").split(",")[:2]]
    with open(os.path.join(os.path.dirname(prefix), meta["image"]), "rb") as f:
        data = f.read()
    parts = data.split(b"\n", 3)
    if parts[0] != b"P5":
        raise ValueError("%s.pgm is not a binary PGM" % prefix)
    width, height = [int(x) for x in parts[1].split()]
    pixels = parts[3]
    if len(pixels) != width * height:
        raise ValueError("%s.pgm: %d bytes of pixels, expected %d" % (prefix, len(pixels), width * height))
    grid = [list(pixels[(height - 1 - r) * width:(height - r) * width]) for r in range(height)]
    return grid, res, origin


def main(argv):
    args = list(argv[1:])
    if len(args) < 2:
        sys.stderr.write(__doc__)
        return 2
    urdf, prefix = args[0], args[1]
    res, origin, size, zmin, zmax = 0.05, [-6.0, -6.0], [12.0, 12.0], 0.05, 1.9
    rest = args[2:]
    while rest:
        a = rest.pop(0)
        if a == "--resolution":
            res = float(rest.pop(0))
        elif a == "--origin":
            origin = [float(rest.pop(0)), float(rest.pop(0))]
        elif a == "--size":
            size = [float(rest.pop(0)), float(rest.pop(0))]
        elif a == "--zmin":
            zmin = float(rest.pop(0))
        elif a == "--zmax":
            zmax = float(rest.pop(0))
        else:
            sys.stderr.write("rasterize_map: unknown argument %r\n" % a)
            return 2
    if res <= 0 or size[0] <= 0 or size[1] <= 0:
        sys.stderr.write("rasterize_map: resolution and size must be positive\n")
        return 2
    try:
        model = urdfmodel.load(urdf)
    except (OSError, ValueError) as e:
        sys.stderr.write("rasterize_map: cannot use %s: %s\n" % (urdf, e))
        return 2
    grid = rasterize(model, res, origin, size, zmin, zmax)
    write_map(prefix, grid, res, origin)
    occupied = sum(row.count(OCCUPIED) for row in grid)
    print("%s.pgm: %dx%d cells at %s m, %d occupied" % (os.path.normpath(prefix), len(grid[0]),
                                                         len(grid), res, occupied))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
