"""URDF reading, rigid-transform math and forward kinematics (standard library only).

Transforms are 4x4 row-major nested lists.  A parsed model is a `Model` holding
links (with their collision and visual geometry) and joints, and can compute
the pose of every link for a joint configuration, mimic joints included.
"""

import math
import xml.etree.ElementTree as ET


# ---------------------------------------------------------------- math

def identity():
    return [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)]
            for i in range(4)]


def rot_rpy(r, p, y):
    """Rotation of URDF fixed-axis roll, pitch, yaw: Rz(y) * Ry(p) * Rx(r)."""
    cr, sr = math.cos(r), math.sin(r)
    cp, sp = math.cos(p), math.sin(p)
    cy, sy = math.cos(y), math.sin(y)
    return [[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr]]


def transform(xyz=(0.0, 0.0, 0.0), rpy=(0.0, 0.0, 0.0)):
    r = rot_rpy(*rpy)
    return [[r[0][0], r[0][1], r[0][2], xyz[0]],
            [r[1][0], r[1][1], r[1][2], xyz[1]],
            [r[2][0], r[2][1], r[2][2], xyz[2]],
            [0.0, 0.0, 0.0, 1.0]]


def translation(x, y, z):
    return transform((x, y, z))


def axis_angle(axis, angle):
    """4x4 rotation about a (normalised here) axis through the origin."""
    n = math.sqrt(sum(a * a for a in axis))
    if n == 0.0:
        raise ValueError("rotation axis %r has zero length" % (axis,))
    x, y, z = (a / n for a in axis)
    c, s = math.cos(angle), math.sin(angle)
    t = 1.0 - c
    return [[t * x * x + c, t * x * y - s * z, t * x * z + s * y, 0.0],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x, 0.0],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c, 0.0],
            [0.0, 0.0, 0.0, 1.0]]


def apply(m, p):
    return tuple(m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + m[i][3]
                 for i in range(3))


def rotation_angle_between(a, b):
    """Angle (rad) of the relative rotation between the rotation parts of a and b."""
    tr = sum(a[k][i] * b[k][i] for i in range(3) for k in range(3))
    c = max(-1.0, min(1.0, (tr - 1.0) / 2.0))
    return math.acos(c)


def yaw_transform(x, y, yaw, z=0.0):
    return transform((x, y, z), (0.0, 0.0, yaw))


def quaternion_yaw(q):
    """Yaw (rad) of a quaternion (x y z w) that rotates about z only (not normalised)."""
    qx, qy, qz, qw = q
    return 2.0 * math.atan2(qz, qw)


# ---------------------------------------------------------------- parsing

def _floats(text, n, what):
    parts = (text or "").split()
    if len(parts) != n:
        raise ValueError("%s: expected %d numbers, got %r" % (what, n, text))
    vals = [float(p) for p in parts]
    for v in vals:
        if v != v or v in (float("inf"), float("-inf")):
            raise ValueError("%s: non-finite number in %r" % (what, text))
    return vals


def _origin(elem, what):
    o = elem.find("origin") if elem is not None else None
    if o is None:
        return identity()
    return transform(_floats(o.get("xyz", "0 0 0"), 3, what + " origin xyz"),
                     _floats(o.get("rpy", "0 0 0"), 3, what + " origin rpy"))


class Geometry(object):
    """One collision or visual element: kind is box, cylinder, sphere or mesh."""

    def __init__(self, kind, origin, size=None, radius=None, length=None,
                 filename=None, scale=None):
        self.kind = kind
        self.origin = origin
        self.size = size
        self.radius = radius
        self.length = length
        self.filename = filename
        self.scale = scale


def _geometry(elem, what):
    g = elem.find("geometry")
    if g is None or len(g) != 1:
        raise ValueError("%s: needs exactly one geometry child" % what)
    shape = g[0]
    origin = _origin(elem, what)
    if shape.tag == "box":
        return Geometry("box", origin, size=_floats(shape.get("size"), 3, what + " box size"))
    if shape.tag == "cylinder":
        return Geometry("cylinder", origin, radius=float(shape.get("radius")),
                        length=float(shape.get("length")))
    if shape.tag == "sphere":
        return Geometry("sphere", origin, radius=float(shape.get("radius")))
    if shape.tag == "mesh":
        sc = shape.get("scale")
        return Geometry("mesh", origin, filename=shape.get("filename"),
                        scale=_floats(sc, 3, what + " mesh scale") if sc else [1.0, 1.0, 1.0])
    raise ValueError("%s: unknown geometry %r" % (what, shape.tag))


class Link(object):
    def __init__(self, name, collisions, visuals, mass):
        self.name = name
        self.collisions = collisions
        self.visuals = visuals
        self.mass = mass


class Joint(object):
    def __init__(self, name, jtype, parent, child, origin, axis, lower, upper,
                 soft_lower, soft_upper, mimic):
        self.name = name
        self.type = jtype
        self.parent = parent
        self.child = child
        self.origin = origin
        self.axis = axis
        self.lower = lower
        self.upper = upper
        self.soft_lower = soft_lower
        self.soft_upper = soft_upper
        self.mimic = mimic  # (joint, multiplier, offset) or None


class Model(object):
    """A parsed URDF: links, joints, the root link and a child index."""

    def __init__(self, name, links, joints):
        self.name = name
        self.links = links
        self.joints = joints
        self.child_joint = {}
        for j in joints.values():
            if j.child in self.child_joint:
                raise ValueError("link %r has two parent joints" % j.child)
            if j.parent not in links or j.child not in links:
                raise ValueError("joint %r names an unknown link" % j.name)
            self.child_joint[j.child] = j
        roots = [n for n in links if n not in self.child_joint]
        if len(roots) != 1:
            raise ValueError("URDF %r must have exactly one root, has %r" % (name, roots))
        self.root = roots[0]
        self.children = {}
        for j in joints.values():
            self.children.setdefault(j.parent, []).append(j)

    def movable_joints(self):
        return [j for j in self.joints.values()
                if j.type in ("revolute", "continuous", "prismatic") and j.mimic is None]

    def joint_value(self, joint, values):
        if joint.mimic is not None:
            src, mult, off = joint.mimic
            if src not in self.joints:
                raise ValueError("joint %r mimics unknown joint %r" % (joint.name, src))
            return self.joint_value(self.joints[src], values) * mult + off
        return float(values.get(joint.name, 0.0))

    def joint_transform(self, joint, values):
        t = joint.origin
        if joint.type in ("revolute", "continuous"):
            return matmul(t, axis_angle(joint.axis, self.joint_value(joint, values)))
        if joint.type == "prismatic":
            q = self.joint_value(joint, values)
            n = math.sqrt(sum(a * a for a in joint.axis))
            return matmul(t, translation(*(a / n * q for a in joint.axis)))
        if joint.type == "fixed":
            return t
        raise ValueError("joint %r has unsupported type %r" % (joint.name, joint.type))

    def link_poses(self, values=None, root_pose=None):
        """Dictionary link name -> 4x4 pose in the root's parent frame."""
        values = values or {}
        poses = {self.root: root_pose or identity()}
        stack = [self.root]
        while stack:
            name = stack.pop()
            for j in self.children.get(name, []):
                poses[j.child] = matmul(poses[name], self.joint_transform(j, values))
                stack.append(j.child)
        return poses


def load(path):
    """Parse the URDF file at PATH into a Model."""
    root = ET.parse(path).getroot()
    if root.tag != "robot":
        raise ValueError("%s: root element is %r, expected robot" % (path, root.tag))
    links, joints = {}, {}
    for le in root.findall("link"):
        name = le.get("name")
        if not name or name in links:
            raise ValueError("%s: bad or duplicate link name %r" % (path, name))
        cols = [_geometry(c, "link %s collision" % name) for c in le.findall("collision")]
        vis = [_geometry(v, "link %s visual" % name) for v in le.findall("visual")]
        m = le.find("inertial/mass")
        links[name] = Link(name, cols, vis, float(m.get("value")) if m is not None else 0.0)
    for je in root.findall("joint"):
        name = je.get("name")
        if not name or name in joints:
            raise ValueError("%s: bad or duplicate joint name %r" % (path, name))
        ax = je.find("axis")
        axis = _floats(ax.get("xyz"), 3, "joint %s axis" % name) if ax is not None else [1.0, 0.0, 0.0]
        lim = je.find("limit")
        lower = float(lim.get("lower", "0")) if lim is not None else None
        upper = float(lim.get("upper", "0")) if lim is not None else None
        sc = je.find("safety_controller")
        slo = float(sc.get("soft_lower_limit")) if sc is not None and sc.get("soft_lower_limit") else None
        sup = float(sc.get("soft_upper_limit")) if sc is not None and sc.get("soft_upper_limit") else None
        mi = je.find("mimic")
        mimic = None
        if mi is not None:
            mimic = (mi.get("joint"), float(mi.get("multiplier", "1")), float(mi.get("offset", "0")))
        joints[name] = Joint(name, je.get("type"), je.find("parent").get("link"),
                             je.find("child").get("link"), _origin(je, "joint " + name),
                             axis, lower, upper, slo, sup, mimic)
    return Model(root.get("name"), links, joints)


def geometry_world_boxes(model, values=None, root_pose=None):
    """List of (link, kind, 4x4 world pose of the shape, half extents) for box,
    cylinder and sphere collision shapes.  Cylinders are reported with
    half extents (r, r, l/2) about their own z axis, spheres as (r, r, r)."""
    poses = model.link_poses(values, root_pose)
    out = []
    for name, link in model.links.items():
        for g in link.collisions:
            pose = matmul(poses[name], g.origin)
            if g.kind == "box":
                out.append((name, "box", pose, [s / 2.0 for s in g.size]))
            elif g.kind == "cylinder":
                out.append((name, "cylinder", pose, [g.radius, g.radius, g.length / 2.0]))
            elif g.kind == "sphere":
                out.append((name, "sphere", pose, [g.radius] * 3))
    return out


def world_aabb(pose, half):
    """Axis-aligned bounds (min, max) of an oriented box given its pose and half extents."""
    c = [pose[i][3] for i in range(3)]
    ext = [sum(abs(pose[i][k]) * half[k] for k in range(3)) for i in range(3)]
    return [c[i] - ext[i] for i in range(3)], [c[i] + ext[i] for i in range(3)]


def matrix_to_rpy(m):
    """URDF roll, pitch, yaw of the rotation part of a 4x4 transform."""
    sp = max(-1.0, min(1.0, -m[2][0]))
    pitch = math.asin(sp)
    if abs(sp) > 1.0 - 1e-12:
        roll = 0.0
        yaw = math.atan2(-m[0][1], m[1][1])
    else:
        roll = math.atan2(m[2][1], m[2][2])
        yaw = math.atan2(m[1][0], m[0][0])
    return roll, pitch, yaw


def compose_xyz_rpy(outer, inner):
    """Compose two (xyz, rpy) placements: OUTER applied after INNER."""
    m = matmul(transform(*outer), transform(*inner))
    return [m[0][3], m[1][3], m[2][3]], list(matrix_to_rpy(m))
