#!/usr/bin/python3
"""Generate the object meshes in resources/meshes/ (binary STL, metres, z up).

Each object keeps the extent and origin convention of the household objects
the tutorials use: the origin lies inside the bounding box near its centre;
for the bottle it is 0.1008 m above the bottom, for the cereal box 0.1019 m.
The file name with _ replaced by - is the mesh keyword (fork_plastic.stl ->
:fork-plastic).

The human (body.stl) is authored 1/0.3 times life size, because the shop
scene spawns it with :scale 0.3: after scaling it is a standing adult of
HUMAN_HEIGHT, its feet 1.0 m below the origin (the scene places it at z 1.0),
facing -y (its front turns to +x under the scene's 90 degree yaw).
"""

import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import stlgen  # noqa: E402
from stlgen import box, revolve, prism_y, sphere, cylinder_z  # noqa: E402

HUMAN_HEIGHT = 1.75
HUMAN_SCALE = 0.3
HUMAN_ORIGIN_HEIGHT = 1.0


def bottle():
    profile = [(0.0, -0.1008), (0.033, -0.1008), (0.0357, -0.097), (0.0357, 0.045),
               (0.033, 0.055), (0.022, 0.066), (0.0145, 0.070), (0.0145, 0.0735),
               (0.0158, 0.0738), (0.0158, 0.0802), (0.0, 0.0802)]
    return revolve(profile, 40, sx=1.0, sy=0.0367 / 0.0357)


def cup():
    profile = [(0.0, -0.075), (0.030, -0.075), (0.0403, 0.075), (0.0373, 0.075),
               (0.0272, -0.0715), (0.0, -0.0715)]
    return revolve(profile, 40)


def bowl():
    outer, inner = [], []
    for i in range(9):
        a = (math.pi / 2.0) * i / 8.0
        outer.append((0.045 + 0.038 * math.sin(a), 0.0502 - 0.09 * math.cos(a)))
        inner.append((0.043 + 0.0372 * math.sin(a), 0.0502 - 0.086 * math.cos(a)))
    profile = [(0.0, -0.0502), (0.04, -0.0502), (0.045, -0.0398)] + outer[1:]
    profile += [(0.0803, 0.0502)] + list(reversed(inner[1:])) + [(0.043, -0.0358), (0.0, -0.0358)]
    return revolve(profile, 48)


def mug():
    cx, r = 0.0195, 0.0414
    body = revolve([(0.0, -0.048), (r, -0.048), (r, 0.048), (r - 0.004, 0.048),
                    (r - 0.004, -0.043), (0.0, -0.043)], 32, cx=cx)
    handle = (box((-0.061, -0.006, -0.038), (-0.051, 0.006, 0.039))
              + box((-0.061, -0.006, 0.029), (-0.018, 0.006, 0.039))
              + box((-0.061, -0.006, -0.038), (-0.018, 0.006, -0.028)))
    return body + handle


def fork_plastic():
    tris = box((-0.1097, -0.0085, -0.0038), (-0.014, 0.0085, 0.0))
    tris += box((-0.016, -0.0095, -0.0025), (0.016, 0.0095, 0.0025))
    for k in range(4):
        y0 = -0.0094 + k * 0.00527
        tris += box((0.014, y0, 0.0014), (0.0557, y0 + 0.003, 0.0064))
    return tris


def spoon():
    """A table spoon 0.2167 x 0.0463 x 0.0189 m, the bowl towards +x: an elliptic dish whose
    bottom is the lowest point (z -0.0063), and a handle that rises from the dish's rim to a
    flat end (top z 0.0126) at x -0.1105."""
    rx, ry, cy = 0.036, 0.02315, -0.00015
    cx = 0.1062 - rx
    k = rx / ry
    outer = [(0.0, -0.0063), (0.012, -0.0052), (0.019, -0.0025), (ry, 0.0030)]
    inner = [(0.0205, 0.0030), (0.017, -0.0008), (0.010, -0.0035), (0.0, -0.0043)]
    dish = revolve(outer + inner, 40, sx=k, sy=1.0, cx=cx, cy=cy)
    neck = prism_y([(-0.025, 0.0096), (0.047, 0.0002), (0.047, 0.0032), (-0.025, 0.0126)],
                   -0.0040, 0.0040)
    handle = box((-0.1105, -0.0065, 0.0096), (-0.020, 0.0065, 0.0126))
    return dish + neck + handle


def breakfast_cereal():
    return box((-0.074, -0.029, -0.1019), (0.074, 0.029, 0.1221))


def milk():
    hx, hy = 0.032, 0.0325
    body = box((-hx, -hy, -0.0877), (hx, hy, 0.075))
    gable = prism_y([(-hx, 0.075), (hx, 0.075), (0.0, 0.097)], -hy, hy)
    fin = box((-0.003, -hy, 0.093), (0.003, hy, 0.1063))
    return body + gable + fin


def somat():
    return box((-0.073, -0.0557, -0.085), (0.073, 0.0403, 0.097))


def denkmit():
    return box((-0.029, -0.014, -0.0715), (0.029, 0.014, 0.0715))


def body():
    """Standing human (HUMAN_HEIGHT) facing -y, scaled and shifted for the scene's :scale."""
    h = HUMAN_HEIGHT / 1.75
    parts = []
    for sx in (-1.0, 1.0):
        parts += cylinder_z((sx * 0.09 * h, 0.0), 0.07 * h, 0.07 * h, 0.93 * h)          # legs
        parts += box((sx * 0.09 * h - 0.05 * h, -0.2 * h, 0.0),
                     (sx * 0.09 * h + 0.05 * h, 0.07 * h, 0.07 * h))                    # feet
        parts += cylinder_z((sx * 0.22 * h, 0.0), 0.045 * h, 0.85 * h, 1.43 * h)         # arms
        parts += sphere((sx * 0.22 * h, 0.0, 0.83 * h), 0.05 * h, 6, 12)               # hands
    parts += box((-0.17 * h, -0.1 * h, 0.86 * h), (0.17 * h, 0.1 * h, 1.0 * h))        # pelvis
    parts += box((-0.2 * h, -0.11 * h, 0.93 * h), (0.2 * h, 0.11 * h, 1.43 * h))       # torso
    parts += box((-0.245 * h, -0.09 * h, 1.36 * h), (0.245 * h, 0.09 * h, 1.45 * h))   # shoulders
    parts += cylinder_z((0.0, 0.0), 0.055 * h, 1.42 * h, 1.56 * h)                     # neck
    parts += sphere((0.0, 0.0, 1.64 * h), 0.11 * h)                                    # head
    parts += box((-0.015 * h, -0.125 * h, 1.61 * h), (0.015 * h, -0.09 * h, 1.65 * h))  # nose
    scale = 1.0 / HUMAN_SCALE
    return stlgen.transform(parts, scale, (0.0, 0.0, -HUMAN_ORIGIN_HEIGHT * scale))


OBJECTS = [("bottle", bottle), ("cup", cup), ("bowl", bowl), ("mug", mug),
           ("fork_plastic", fork_plastic), ("breakfast_cereal", breakfast_cereal),
           ("milk", milk), ("spoon", spoon), ("somat", somat), ("denkmit", denkmit), ("body", body)]


def main(argv):
    root = argv[1] if len(argv) > 1 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "..")
    outdir = os.path.join(root, "resources", "meshes")
    if not os.path.isdir(outdir):
        os.makedirs(outdir)
    for name, fn in OBJECTS:
        tris = fn()
        path = os.path.join(outdir, name + ".stl")
        stlgen.write_stl(path, tris, name)
        lo, hi = stlgen.bounds(tris)
        print("%s: %d triangles, extent %.3f x %.3f x %.3f, z %.4f .. %.4f"
              % (os.path.normpath(path), len(tris), hi[0] - lo[0], hi[1] - lo[1],
                 hi[2] - lo[2], lo[2], hi[2]))


if __name__ == "__main__":
    main(sys.argv)
