"""Furniture built from boxes: hollow carcasses, drawers, basins, tables and chairs.

Every function takes bounds (lo, hi) in a link frame (before the collision
origin) and returns Shapes whose union spans exactly those bounds.
"""

from urdfwriter import box_from_bounds, Shape

PLATE = 0.02
DRAWER_WALL = 0.012


def _box(lo, hi):
    return box_from_bounds(lo, hi)


def carcass(lo, hi, top=True, t=PLATE):
    """Cabinet body open towards +x: back, two sides, bottom and (optionally) top."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    out = [_box((x0, y0, z0), (x0 + t, y1, z1)),          # back
           _box((x0, y0, z0), (x1, y0 + t, z1)),          # side at -y
           _box((x0, y1 - t, z0), (x1, y1, z1)),          # side at +y
           _box((x0, y0, z0), (x1, y1, z0 + t))]          # bottom
    if top:
        out.append(_box((x0, y0, z1 - t), (x1, y1, z1)))
    return out


def drawer(lo, hi, t=DRAWER_WALL):
    """Drawer open at the top, its front panel at +x."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    front = min(t, (x1 - x0) / 4.0)
    return [_box((x1 - front, y0, z0), (x1, y1, z1)),       # front panel
            _box((x0, y0, z0), (x0 + t, y1, z1)),           # back
            _box((x0, y0, z0), (x1, y0 + t, z1)),           # side at -y
            _box((x0, y1 - t, z0), (x1, y1, z1)),           # side at +y
            _box((x0, y0, z0), (x1, y1, z0 + t))]           # bottom


def basin(lo, hi, t=PLATE / 2):
    """Open-topped basin (sink)."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    return [_box((x0, y0, z0), (x1, y1, z0 + t)),
            _box((x0, y0, z0), (x0 + t, y1, z1)),
            _box((x1 - t, y0, z0), (x1, y1, z1)),
            _box((x0, y0, z0), (x1, y0 + t, z1)),
            _box((x0, y1 - t, z0), (x1, y1, z1))]


def table(lo, hi, top_thickness=0.03, leg=0.05, legs=None):
    """Table top spanning lo..hi in x and y with its top at hi z, on legs to lo z.
    LEGS, when given, lists (x, y) leg centres; the default puts one in each corner."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    out = [_box((x0, y0, z1 - top_thickness), (x1, y1, z1))]
    if legs is None:
        legs = [(x, y) for x in (x0 + leg, x1 - leg) for y in (y0 + leg, y1 - leg)]
    h = leg / 2.0
    for (x, y) in legs:
        out.append(_box((x - h, y - h, z0), (x + h, y + h, z1 - top_thickness)))
    return out


def chair(lo, hi, seat_height, back=0.04, seat=0.04, leg=0.04):
    """Chair facing +x: seat at SEAT_HEIGHT above lo z, backrest along the -x edge up to hi z."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    zs = z0 + seat_height
    out = [_box((x0, y0, zs - seat), (x1, y1, zs)),
           _box((x0, y0, zs), (x0 + back, y1, z1))]
    h = leg / 2.0
    for x in (x0 + h, x1 - h):
        for y in (y0 + h, y1 - h):
            out.append(_box((x - h, y - h, z0), (x + h, y + h, zs - seat)))
    return out


def cylinder_x(lo, hi):
    """Cylinder along x covering the bounds (knobs)."""
    import math
    r = max(hi[1] - lo[1], hi[2] - lo[2]) / 2.0
    c = [(a + b) / 2.0 for a, b in zip(lo, hi)]
    return Shape("cylinder", [r, hi[0] - lo[0]], c, (0, math.pi / 2, 0))
