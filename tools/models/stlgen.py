"""Triangle meshes from simple solids, written as binary STL (standard library only).

A mesh is a list of triangles, each a tuple of three (x, y, z) vertices wound
counter-clockwise seen from outside.  Every solid here is a closed shell.
"""

import math
import struct


def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def normal(tri):
    n = _cross(_sub(tri[1], tri[0]), _sub(tri[2], tri[0]))
    length = math.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2)
    if length == 0.0:
        return (0.0, 0.0, 0.0)
    return (n[0] / length, n[1] / length, n[2] / length)


def signed_volume(tris):
    v = 0.0
    for a, b, c in tris:
        v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
              + a[2] * (b[0] * c[1] - b[1] * c[0]))
    return v / 6.0


def outward(tris):
    """Flip a closed shell's winding when its signed volume is negative."""
    if signed_volume(tris) < 0:
        return [(a, c, b) for a, b, c in tris]
    return tris


def _degenerate(tri):
    return tri[0] == tri[1] or tri[1] == tri[2] or tri[0] == tri[2]


def box(lo, hi):
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    v = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0),
         (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]
    faces = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    tris = []
    for a, b, c, d in faces:
        tris.append((v[a], v[b], v[c]))
        tris.append((v[a], v[c], v[d]))
    return outward(tris)


def revolve(profile, segments=32, sx=1.0, sy=1.0, cx=0.0, cy=0.0):
    """Solid of revolution about the z axis through (cx, cy).  PROFILE is a list
    of (r, z) from a point on the axis to another point on the axis; the cross
    section is scaled by SX and SY (an elliptic section when they differ)."""
    if profile[0][0] != 0 or profile[-1][0] != 0:
        raise ValueError("a revolved profile must start and end on the axis: %r" % (profile,))
    rings = []
    for r, z in profile:
        ring = []
        for k in range(segments):
            a = 2.0 * math.pi * k / segments
            ring.append((cx + sx * r * math.cos(a), cy + sy * r * math.sin(a), z))
        rings.append(ring)
    tris = []
    for i in range(len(rings) - 1):
        for k in range(segments):
            k2 = (k + 1) % segments
            a, b = rings[i][k], rings[i][k2]
            c, d = rings[i + 1][k2], rings[i + 1][k]
            for t in ((a, b, c), (a, c, d)):
                if not _degenerate(t):
                    tris.append(t)
    return outward(tris)


def prism_y(points_xz, y0, y1):
    """Convex polygon in the x-z plane (counter-clockwise) extruded from y0 to y1."""
    n = len(points_xz)
    front = [(x, y0, z) for x, z in points_xz]
    back = [(x, y1, z) for x, z in points_xz]
    tris = []
    for i in range(1, n - 1):
        tris.append((front[0], front[i], front[i + 1]))
        tris.append((back[0], back[i + 1], back[i]))
    for i in range(n):
        j = (i + 1) % n
        tris.append((front[i], back[i], back[j]))
        tris.append((front[i], back[j], front[j]))
    return outward(tris)


def sphere(centre, radius, rings=12, segments=24):
    profile = []
    for i in range(rings + 1):
        phi = math.pi * i / rings
        profile.append((radius * math.sin(phi) if 0 < i < rings else 0.0,
                        centre[2] - radius * math.cos(phi)))
    return revolve(profile, segments, cx=centre[0], cy=centre[1])


def cylinder_z(centre_xy, radius, z0, z1, segments=24):
    return revolve([(0.0, z0), (radius, z0), (radius, z1), (0.0, z1)], segments,
                   cx=centre_xy[0], cy=centre_xy[1])


def transform(tris, scale=1.0, offset=(0.0, 0.0, 0.0)):
    return [tuple(tuple(v[i] * scale + offset[i] for i in range(3)) for v in t) for t in tris]


def bounds(tris):
    lo = [min(v[i] for t in tris for v in t) for i in range(3)]
    hi = [max(v[i] for t in tris for v in t) for i in range(3)]
    return lo, hi


def write_stl(path, tris, name):
    """Write TRIS as a binary STL (little-endian float32) with NAME in the header."""
    header = ("binary STL %s, metres, z up" % name).encode("ascii")[:80].ljust(80, b" ")
    with open(path, "wb") as f:
        f.write(header)
        f.write(struct.pack("<I", len(tris)))
        for t in tris:
            f.write(struct.pack("<3f", *normal(t)))
            for v in t:
                f.write(struct.pack("<3f", *v))
            f.write(b"\x00\x00")


def read_stl(path):
    """Triangles of a binary STL file."""
    with open(path, "rb") as f:
        data = f.read()
    if len(data) < 84:
        raise ValueError("%s: too short for a binary STL" % path)
    n = struct.unpack("<I", data[80:84])[0]
    if len(data) != 84 + 50 * n:
        raise ValueError("%s: size %d does not match %d triangles" % (path, len(data), n))
    tris = []
    for i in range(n):
        o = 84 + 50 * i + 12
        tris.append(tuple(struct.unpack("<3f", data[o + 12 * k:o + 12 * k + 12]) for k in range(3)))
    return tris
