#!/usr/bin/python3
"""Generate robots/pepper/pepper.urdf from the Pepper fact tables (facts_pepper.py).

Kinematics come from the joint table.  Geometry is primitive: boxes for the
hip, pelvis, torso and neck, a cylinder for the wheeled base (Tibia), a sphere
for the head, cylinders along x for the arm links and spheres for the wheels,
all sized from the link-frame bounding boxes.  Added to the tabulated joints:
the optical frames of the bottom and depth cameras, the thumb links (mimicking
the hand joints) and the hand-opening joints left/right_gripper_joint that the
CRAM Pepper description names as its gripper joints.
"""

import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import facts_pepper  # noqa: E402
from urdfwriter import UrdfWriter, Shape, box_from_bounds, parse_vec  # noqa: E402

TOTAL_MASS = 28.7
HALF_PI = math.pi / 2.0
OPTICAL_RPY = (-HALF_PI, 0.0, -HALF_PI)
THUMB_MIMIC = 0.872665
HAND_OPENING = 0.1

EXTRA_JOINTS = [
    dict(name="CameraBottom_optical_frame_fixedjoint", type="fixed", parent="CameraBottom_frame",
         child="CameraBottom_optical_frame", xyz=(0, 0, 0), rpy=OPTICAL_RPY),
    dict(name="CameraDepth_optical_frame_fixedjoint", type="fixed", parent="CameraDepth_frame",
         child="CameraDepth_optical_frame", xyz=(0, 0, 0), rpy=OPTICAL_RPY),
]
for _s, _side, _hand, _wrist, _sign in (("L", "left", "LHand", "l_wrist", 1.0),
                                         ("R", "right", "RHand", "r_wrist", -1.0)):
    EXTRA_JOINTS += [
        dict(name="%sThumb1" % _s, type="continuous", parent=_wrist, child="%sThumb1_link" % _s,
             xyz=(0.0482, -0.0357 * _sign, -0.0199),
             rpy=(-1.95836 if _s == "L" else -1.18323, 0.60626, 0.533978 * _sign),
             axis=(0, 0, 1), velocity=12.56, effort=0.144, mimic=(_hand, THUMB_MIMIC, 0.0)),
        dict(name="%sThumb2" % _s, type="continuous", parent="%sThumb1_link" % _s,
             child="%sThumb2_link" % _s, xyz=(0.022, 0, 0), rpy=(0, 0, -1.0472),
             axis=(0, 0, 1), velocity=12.56, effort=0.144, mimic=(_hand, THUMB_MIMIC, 0.0)),
        dict(name="%s_gripper_joint" % _side, type="prismatic", parent="%s_gripper" % _s.lower(),
             child="%s_gripper_tip_frame" % _side, xyz=(0, 0, 0), rpy=(0, 0, 0),
             axis=(0, 1, 0), lower=0.0, upper=HAND_OPENING, velocity=0.1, effort=0.144),
    ]

ARM_LINKS = ("Shoulder", "Bicep", "Elbow", "ForeArm")

MATERIALS = [("pepper_white", (0.95, 0.95, 0.95, 1.0)),
             ("pepper_grey", (0.35, 0.35, 0.38, 1.0)),
             ("pepper_black", (0.1, 0.1, 0.1, 1.0))]


def along_x(lo, hi):
    """Cylinder along the link's x axis covering the bounds lo..hi."""
    radius = max(hi[1] - lo[1], hi[2] - lo[2]) / 2.0
    centre = [(a + b) / 2.0 for a, b in zip(lo, hi)]
    return Shape("cylinder", [radius, hi[0] - lo[0]], centre, (0, HALF_PI, 0))


def link_shapes():
    shapes = {}
    for name, _tris, lo, hi, _wlo, _whi in facts_pepper.LINK_AABB:
        lo, hi = parse_vec(lo), parse_vec(hi)
        if name == "Tibia":
            # base_footprint is 0.334 below Tibia; the base spans z 0.03..0.385 above the floor.
            z0, z1 = 0.03 - 0.334, 0.385 - 0.334
            shapes[name] = [Shape("cylinder", [0.24, z1 - z0], (-0.035, 0.0, (z0 + z1) / 2.0))]
        elif name == "Head":
            shapes[name] = [Shape("sphere", [0.105], ((lo[0] + hi[0]) / 2.0, 0.0, 0.11))]
        elif name.startswith("Wheel"):
            shapes[name] = [Shape("sphere", [0.07], (0, 0, 0))]
        elif name[1:] in ARM_LINKS or name in ("l_wrist", "r_wrist"):
            shapes[name] = [along_x(lo, hi)]
        else:
            shapes[name] = [box_from_bounds(lo, hi)]
    for s in ("L", "R"):
        shapes["%sThumb1_link" % s] = [Shape("cylinder", [0.009, 0.022], (0.011, 0, 0), (0, HALF_PI, 0))]
        shapes["%sThumb2_link" % s] = [Shape("cylinder", [0.008, 0.02], (0.01, 0, 0), (0, HALF_PI, 0))]
    return shapes


def material_for(link):
    if link.startswith("Wheel") or "Thumb" in link:
        return "pepper_black"
    if link in ("Neck", "LElbow", "RElbow", "l_wrist", "r_wrist"):
        return "pepper_grey"
    return "pepper_white"


def build():
    w = UrdfWriter("pepper")
    for name, rgba in MATERIALS:
        w.material(name, rgba)
    shapes = link_shapes()
    volumes = {n: sum(s.volume() for s in ss) for n, ss in shapes.items()}
    total_volume = sum(volumes.values())
    joints = []
    for row in facts_pepper.JOINTS:
        jtype = row[1]
        j = dict(name=row[0], type=jtype, parent=row[2], child=row[3],
                 xyz=parse_vec(row[4]), rpy=parse_vec(row[5]))
        if jtype != "fixed":
            j["axis"] = parse_vec(row[6])
            j["velocity"], j["effort"] = float(row[9]), float(row[10])
            if jtype == "revolute":
                j["lower"], j["upper"] = float(row[7]), float(row[8])
        joints.append(j)
    joints.extend(EXTRA_JOINTS)
    order = ["base_link"]
    for j in joints:
        if j["child"] not in order:
            order.append(j["child"])
    for link in order:
        ss = shapes.get(link, [])
        mass = round(TOTAL_MASS * volumes[link] / total_volume, 4) if link in volumes else None
        w.link(link, ss, material_for(link) if ss else None, mass)
    for j in joints:
        w.joint(j["name"], j["type"], j["parent"], j["child"], j["xyz"], j["rpy"],
                j.get("axis"), j.get("lower"), j.get("upper"), j.get("velocity"),
                j.get("effort"), None, j.get("mimic"))
    return w


def main(argv):
    root = argv[1] if len(argv) > 1 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "..")
    out = os.path.join(root, "robots", "pepper", "pepper.urdf")
    w = build()
    w.write(out, "Pepper generated by tools/models/make_pepper.py; regenerate with tools/models/generate-all")
    print("%s: %d links, %d joints" % (os.path.normpath(out), len(w.link_names), len(w.joint_names)))


if __name__ == "__main__":
    main(sys.argv)
