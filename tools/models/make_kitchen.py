#!/usr/bin/python3
"""Generate resources/iai_kitchen.urdf from the kitchen fact tables (facts_kitchen.py).

All 134 joints keep their names, types, origins, axes and limits, except two
deliberate layout decisions:

* `table_area_main` is a table (top and legs) whose top is at z TABLE_TOP and
  which spans TABLE_X x TABLE_Y in the world, so that the bottles the tutorials
  spawn at (-2.0 .. -1.1, -0.9, 0.86) stand on it, while the robot base poses
  of the tutorials stay clear of it;
* the kitchen island's counter top overhangs the island's front (+x) by
  ISLAND_OVERHANG, so that a bottle at x = -0.65 in front of the island stands.

Links whose upstream geometry is a mesh become box assemblies covering the
mesh's bounding box: hollow carcasses open towards the area's +x front,
drawers open at the top, an open sink basin, tables and chairs on legs; flat
parts (panels, doors, handles, the stove) are single boxes; knobs are cylinders.
"""

import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import facts_kitchen  # noqa: E402
import shapes as furniture  # noqa: E402
from urdfmodel import compose_xyz_rpy  # noqa: E402
from urdfwriter import UrdfWriter, Shape, box_from_bounds, parse_vec  # noqa: E402

ROOM_OFFSET_Y = 0.03          # world_room_joint: room_link is 0.03 along +y of world
TABLE_TOP = 0.759             # world z of the table top
TABLE_X = (-2.40, -0.85)      # world x range of the table top
TABLE_Y = (-1.09, -0.73)      # world y range of the table top
TABLE_LEGS_Y = (-0.915, -0.865)  # world y of the leg rows (in front of the low wall, and
                                 # behind the PR2 base at seed 001's (-2.0547, -0.481, -pi/2))
ISLAND_OVERHANG = 0.065

CARCASS_MESHES = {"SinkArea.obj": False, "IslandArea.obj": False, "OvenArea.obj": True,
                  "FridgeArea.obj": True, "DishWasher.obj": True, "OvenMain.obj": True,
                  "Fridge.obj": True}

MATERIALS = [("kitchen_white", (0.92, 0.92, 0.9, 1.0)),
             ("kitchen_counter", (0.3, 0.3, 0.32, 1.0)),
             ("kitchen_steel", (0.7, 0.72, 0.75, 1.0)),
             ("kitchen_wood", (0.62, 0.45, 0.28, 1.0)),
             ("kitchen_wall", (0.85, 0.83, 0.78, 1.0)),
             ("kitchen_black", (0.1, 0.1, 0.1, 1.0))]


def material_for(link):
    if link.startswith("kitchen_wall"):
        return "kitchen_wall"
    if link.endswith("_surface") or link == "kitchen_island_stove":
        return "kitchen_counter"
    if "handle" in link or "knob" in link or link == "sink_area_sink":
        return "kitchen_steel"
    if link.startswith("dining_area") or link == "table_area_main":
        return "kitchen_wood"
    if "oven_door" in link or "oven_panel" in link:
        return "kitchen_black"
    return "kitchen_white"


def parse_collision(row):
    """(kind, data, origin xyz, origin rpy) of one collision fact row."""
    geom, origin = row[1], row[2]
    oxyz, orpy = [parse_vec(p) for p in origin.split("/")]
    if geom.startswith("box "):
        return "box", parse_vec(geom[4:]), oxyz, orpy
    if geom.startswith("mesh "):
        mesh = geom.split()[1]
        nums = geom.split("min")[1].split("max")
        return mesh, (parse_vec(nums[0]), parse_vec(nums[1])), oxyz, orpy
    raise ValueError("unknown kitchen geometry %r" % geom)


def place(shapes, oxyz, orpy):
    out = []
    for s in shapes:
        xyz, rpy = compose_xyz_rpy((oxyz, orpy), (s.xyz, s.rpy))
        out.append(Shape(s.kind, s.dims, xyz, rpy))
    return out


def mesh_shapes(link, mesh, lo, hi):
    if mesh in CARCASS_MESHES:
        return furniture.carcass(lo, hi, top=CARCASS_MESHES[mesh])
    if mesh.startswith("Drawer_"):
        return furniture.drawer(lo, hi)
    if mesh == "Sink.obj":
        return furniture.basin(lo, hi)
    if mesh == "Knob.obj":
        return [furniture.cylinder_x(lo, hi)]
    if mesh == "JokkmokkTable.obj":
        return furniture.table(lo, hi)
    if mesh == "JokkmokkChair.obj":
        return furniture.chair(lo, hi, seat_height=0.45)
    return [box_from_bounds(lo, hi)]


def table_geometry():
    """Table top and legs in the table_area_main frame (yaw pi about its origin)."""
    cx, cy = sum(TABLE_X) / 2.0, sum(TABLE_Y) / 2.0
    hx, hy = (TABLE_X[1] - TABLE_X[0]) / 2.0, (TABLE_Y[1] - TABLE_Y[0]) / 2.0
    legs_world = [(x, y) for x in (TABLE_X[0] + 0.05, cx, TABLE_X[1] - 0.05) for y in TABLE_LEGS_Y]
    legs_local = [(-(x - cx), -(y - cy)) for x, y in legs_world]
    shapes = furniture.table((-hx, -hy, 0.0), (hx, hy, TABLE_TOP), legs=legs_local)
    joint_xyz = (cx, cy - ROOM_OFFSET_Y, 0.0)
    return shapes, joint_xyz


def link_geometry():
    geo = {}
    for row in facts_kitchen.COLLISION:
        link = row[0]
        kind, data, oxyz, orpy = parse_collision(row)
        if link == "table_area_main":
            continue
        if kind == "box":
            shapes = [Shape("box", data)]
            if link == "kitchen_island_surface":
                lo = [-data[0] / 2.0, -data[1] / 2.0, -data[2] / 2.0]
                hi = [data[0] / 2.0 + ISLAND_OVERHANG, data[1] / 2.0, data[2] / 2.0]
                shapes = [box_from_bounds(lo, hi)]
        else:
            shapes = mesh_shapes(link, kind, data[0], data[1])
        geo.setdefault(link, []).extend(place(shapes, oxyz, orpy))
    geo["table_area_main"] = table_geometry()[0]
    return geo


def build():
    w = UrdfWriter("iai_kitchen")
    for name, rgba in MATERIALS:
        w.material(name, rgba)
    geo = link_geometry()
    joints = []
    for name, jtype, parent, child, xyz, rpy, axis, lower, upper in facts_kitchen.JOINTS:
        j = dict(name=name, type=jtype, parent=parent, child=child,
                 xyz=parse_vec(xyz), rpy=parse_vec(rpy))
        if name == "table_area_main_joint":
            j["xyz"] = table_geometry()[1]
        if jtype != "fixed":
            j["axis"] = parse_vec(axis)
            j["lower"], j["upper"] = float(lower), float(upper)
            j["velocity"] = 0.5 if jtype == "prismatic" else 1.0
            j["effort"] = 100.0
        joints.append(j)
    order = [joints[0]["parent"]]
    for j in joints:
        if j["child"] not in order:
            order.append(j["child"])
    unknown = sorted(set(geo) - set(order))
    if unknown:
        raise ValueError("geometry for links without joints: %r" % unknown)
    for link in order:
        ss = geo.get(link, [])
        w.link(link, ss, material_for(link) if ss else None)
    for j in joints:
        w.joint(j["name"], j["type"], j["parent"], j["child"], j["xyz"], j["rpy"],
                j.get("axis"), j.get("lower"), j.get("upper"), j.get("velocity"), j.get("effort"))
    return w


def main(argv):
    root = argv[1] if len(argv) > 1 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "..")
    out = os.path.join(root, "resources", "iai_kitchen.urdf")
    w = build()
    w.write(out, "IAI kitchen generated by tools/models/make_kitchen.py; regenerate with tools/models/generate-all")
    print("%s: %d links, %d joints" % (os.path.normpath(out), len(w.link_names), len(w.joint_names)))


if __name__ == "__main__":
    main(sys.argv)
