#!/usr/bin/python3
"""Generate robots/pr2/pr2.urdf from the PR2 fact tables (facts_pr2.py).

Kinematics (names, origins, axes, limits, soft limits, mimics) come from the
joint table.  Collision and visual geometry are boxes sized from each link's
link-frame bounding box, and cylinders for the caster wheels.
"""

import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import facts_pr2  # noqa: E402
from urdfwriter import UrdfWriter, Shape, box_from_bounds, parse_vec  # noqa: E402

TOTAL_MASS = 266.1
CASTER_XY = 0.2246
CASTER_Z = 0.0282
WHEEL_Y = 0.049
WHEEL_RADIUS = 0.074792
WHEEL_LENGTH = 0.034

# Fixed joints whose origins follow from the bounding-box table (the box of the
# child sits centred on the joint origin) rather than from the joint table.
EXTRA_FIXED = [
    ("base_bellow_joint", "base_link", "base_bellow_link", (-0.29, 0.0, 0.8)),
    ("l_gripper_motor_accelerometer_joint", "l_gripper_palm_link",
     "l_gripper_motor_accelerometer_link", (0.0, 0.0, 0.0)),
    ("r_gripper_motor_accelerometer_joint", "r_gripper_palm_link",
     "r_gripper_motor_accelerometer_link", (0.0, 0.0, 0.0)),
    ("head_mount_prosilica_joint", "head_mount_link", "head_mount_prosilica_link",
     (-0.0464, 0.0125, 0.0889)),
]

MATERIALS = [
    ("pr2_grey", (0.62, 0.62, 0.64, 1.0)),
    ("pr2_white", (0.93, 0.93, 0.93, 1.0)),
    ("pr2_dark", (0.25, 0.25, 0.27, 1.0)),
    ("pr2_black", (0.08, 0.08, 0.08, 1.0)),
    ("pr2_red", (0.75, 0.12, 0.1, 1.0)),
]


def material_for(link):
    if "caster" in link:
        return "pr2_black"
    if "finger" in link or "palm" in link or "wrist" in link or "accelerometer" in link:
        return "pr2_dark"
    if link in ("head_pan_link", "head_tilt_link", "laser_tilt_mount_link", "base_bellow_link"):
        return "pr2_dark"
    if "upper_arm_link" in link or "forearm_link" in link or "shoulder_lift" in link:
        return "pr2_white"
    if link == "head_plate_frame":
        return "pr2_red"
    return "pr2_grey"


def link_shapes():
    """Dictionary link -> list of Shape, for both arms and the casters."""
    shapes = {}
    for row in facts_pr2.LINK_AABB:
        name, geom, _tris, lo, hi = row[0], row[1], row[2], row[3], row[4]
        lo, hi = parse_vec(lo), parse_vec(hi)
        if geom.startswith("cylinder"):
            shapes[name] = [Shape("cylinder", [WHEEL_RADIUS, WHEEL_LENGTH], (0, 0, 0),
                                  (math.pi / 2, 0, 0))]
        elif geom.startswith("sphere"):
            shapes[name] = [Shape("sphere", [(hi[0] - lo[0]) / 2.0],
                                  [(a + b) / 2.0 for a, b in zip(lo, hi)])]
        else:
            shapes[name] = [box_from_bounds(lo, hi)]
        if name.startswith("l_"):
            # Both arms use the same hardware, so the link-frame bounds agree.
            shapes["r_" + name[2:]] = shapes[name]
    return shapes


def limits_of(row):
    lower = float(row[7]) if row[7] else None
    upper = float(row[8]) if row[8] else None
    vel = float(row[9]) if row[9] else None
    eff = float(row[10]) if row[10] else None
    soft = None
    if row[11]:
        a, b = row[11].split("..")
        soft = (float(a), float(b))
    return lower, upper, vel, eff, soft


def mimic_of(note):
    if not note.startswith("mimic "):
        return None
    _, joint, expr = note.split()
    mult, off = expr[1:].split("+")
    return (joint, float(mult), float(off))


def build():
    w = UrdfWriter("pr2")
    for name, rgba in MATERIALS:
        w.material(name, rgba)
    shapes = link_shapes()
    volumes = {n: sum(s.volume() for s in ss) for n, ss in shapes.items()
               if n != "base_footprint" and "accelerometer" not in n}
    total_volume = sum(volumes.values())

    joints = []
    for row in facts_pr2.JOINTS:
        lower, upper, vel, eff, soft = limits_of(row)
        axis = parse_vec(row[6]) if row[6] != "-" else None
        joints.append(dict(name=row[0], type=row[1], parent=row[2], child=row[3],
                           xyz=parse_vec(row[4]), rpy=parse_vec(row[5]), axis=axis,
                           lower=lower, upper=upper, velocity=vel, effort=eff, soft=soft,
                           mimic=mimic_of(row[12])))
    for corner, sx, sy in (("fl", 1, 1), ("fr", 1, -1), ("bl", -1, 1), ("br", -1, -1)):
        joints.append(dict(name="%s_caster_rotation_joint" % corner, type="continuous",
                           parent="base_link", child="%s_caster_rotation_link" % corner,
                           xyz=(sx * CASTER_XY, sy * CASTER_XY, CASTER_Z), rpy=(0, 0, 0),
                           axis=(0, 0, 1), velocity=10.0, effort=6.5))
        for side, wy in (("l", WHEEL_Y), ("r", -WHEEL_Y)):
            joints.append(dict(name="%s_caster_%s_wheel_joint" % (corner, side),
                               type="continuous", parent="%s_caster_rotation_link" % corner,
                               child="%s_caster_%s_wheel_link" % (corner, side),
                               xyz=(0, wy, 0), rpy=(0, 0, 0), axis=(0, 1, 0),
                               velocity=100.0, effort=7.0))
    for name, parent, child, xyz in EXTRA_FIXED:
        joints.append(dict(name=name, type="fixed", parent=parent, child=child, xyz=xyz,
                           rpy=(0, 0, 0)))

    # Links in tree order: root first, then every child as its joint appears.
    order = ["base_footprint"]
    for j in joints:
        if j["child"] not in order:
            order.append(j["child"])
    for link in order:
        ss = shapes.get(link, [])
        mass = None
        if link in volumes:
            mass = round(TOTAL_MASS * volumes[link] / total_volume, 4)
        elif "accelerometer" in link:
            mass = 0.001
        w.link(link, ss, material_for(link) if ss else None, mass)
    for j in joints:
        w.joint(j["name"], j["type"], j["parent"], j["child"], j["xyz"], j["rpy"],
                j.get("axis"), j.get("lower"), j.get("upper"), j.get("velocity"),
                j.get("effort"), j.get("soft"), j.get("mimic"))
    return w


def main(argv):
    root = argv[1] if len(argv) > 1 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "..")
    out = os.path.join(root, "robots", "pr2", "pr2.urdf")
    w = build()
    w.write(out, "PR2 generated by tools/models/make_pr2.py; regenerate with tools/models/generate-all")
    print("%s: %d links, %d joints" % (os.path.normpath(out), len(w.link_names), len(w.joint_names)))


if __name__ == "__main__":
    main(sys.argv)
