"""Deterministic URDF text emission for the model generators."""

import math


def num(x):
    """Shortest stable decimal text for a float (10 decimals at most, no -0)."""
    x = float(x)
    if x != x or x in (float("inf"), float("-inf")):
        raise ValueError("non-finite number %r in a model" % x)
    s = ("%.10f" % x).rstrip("0").rstrip(".")
    if s in ("-0", ""):
        s = "0"
    return s


def vec(v):
    return " ".join(num(x) for x in v)


def parse_vec(text, n=3):
    parts = text.replace(",", " ").split()
    if len(parts) != n:
        raise ValueError("expected %d numbers in %r" % (n, text))
    return [float(p) for p in parts]


class Shape(object):
    """A primitive: kind box (size), cylinder (radius, length) or sphere (radius),
    placed at xyz/rpy in its link frame."""

    def __init__(self, kind, dims, xyz=(0, 0, 0), rpy=(0, 0, 0)):
        if kind not in ("box", "cylinder", "sphere", "mesh"):
            raise ValueError("unknown shape kind %r" % kind)
        self.kind = kind
        self.dims = dims
        self.xyz = list(xyz)
        self.rpy = list(rpy)

    def geometry_xml(self):
        if self.kind == "box":
            return '<box size="%s"/>' % vec(self.dims)
        if self.kind == "cylinder":
            return '<cylinder radius="%s" length="%s"/>' % (num(self.dims[0]), num(self.dims[1]))
        if self.kind == "sphere":
            return '<sphere radius="%s"/>' % num(self.dims[0])
        return '<mesh filename="%s"/>' % self.dims

    def volume(self):
        if self.kind == "box":
            return self.dims[0] * self.dims[1] * self.dims[2]
        if self.kind == "cylinder":
            return math.pi * self.dims[0] ** 2 * self.dims[1]
        if self.kind == "sphere":
            return 4.0 / 3.0 * math.pi * self.dims[0] ** 3
        return 0.0


def box_from_bounds(lo, hi, rpy=(0, 0, 0)):
    """Box shape covering the axis-aligned bounds lo..hi of its link frame."""
    size = [max(h - l, 1e-4) for l, h in zip(lo, hi)]
    centre = [(l + h) / 2.0 for l, h in zip(lo, hi)]
    return Shape("box", size, centre, rpy)


class UrdfWriter(object):
    """Collects materials, links and joints and renders a URDF document."""

    def __init__(self, robot_name):
        self.name = robot_name
        self.materials = []
        self.lines = []
        self.link_names = []
        self.joint_names = []

    def material(self, name, rgba):
        self.materials.append('  <material name="%s"><color rgba="%s"/></material>' % (name, vec(rgba)))

    def link(self, name, shapes=(), material=None, mass=None, visual=True):
        if name in self.link_names:
            raise ValueError("duplicate link %r" % name)
        self.link_names.append(name)
        if not shapes and mass is None:
            self.lines.append('  <link name="%s"/>' % name)
            return
        out = ['  <link name="%s">' % name]
        if mass is not None and mass > 0:
            out.extend(self._inertial(shapes, mass))
        for s in shapes:
            if visual:
                out.append('    <visual>')
                out.append('      <origin xyz="%s" rpy="%s"/>' % (vec(s.xyz), vec(s.rpy)))
                out.append('      <geometry>%s</geometry>' % s.geometry_xml())
                if material:
                    out.append('      <material name="%s"/>' % material)
                out.append('    </visual>')
        for s in shapes:
            out.append('    <collision>')
            out.append('      <origin xyz="%s" rpy="%s"/>' % (vec(s.xyz), vec(s.rpy)))
            out.append('      <geometry>%s</geometry>' % s.geometry_xml())
            out.append('    </collision>')
        out.append('  </link>')
        self.lines.extend(out)

    def _inertial(self, shapes, mass):
        """Inertial of a solid box enclosing the shapes' centres and sizes
        (uniform density approximation about the centroid)."""
        vols = [max(s.volume(), 1e-9) for s in shapes] or [1.0]
        tot = sum(vols)
        if shapes:
            com = [sum(s.xyz[i] * v for s, v in zip(shapes, vols)) / tot for i in range(3)]
            ext = []
            for i in range(3):
                lo = min(s.xyz[i] - _half(s, i) for s in shapes)
                hi = max(s.xyz[i] + _half(s, i) for s in shapes)
                ext.append(max(hi - lo, 0.01))
        else:
            com, ext = [0, 0, 0], [0.05, 0.05, 0.05]
        ixx = mass / 12.0 * (ext[1] ** 2 + ext[2] ** 2)
        iyy = mass / 12.0 * (ext[0] ** 2 + ext[2] ** 2)
        izz = mass / 12.0 * (ext[0] ** 2 + ext[1] ** 2)
        return ['    <inertial>',
                '      <origin xyz="%s" rpy="0 0 0"/>' % vec(com),
                '      <mass value="%s"/>' % num(mass),
                '      <inertia ixx="%s" ixy="0" ixz="0" iyy="%s" iyz="0" izz="%s"/>'
                % (num(max(ixx, 1e-6)), num(max(iyy, 1e-6)), num(max(izz, 1e-6))),
                '    </inertial>']

    def joint(self, name, jtype, parent, child, xyz=(0, 0, 0), rpy=(0, 0, 0), axis=None,
              lower=None, upper=None, velocity=None, effort=None, soft=None, mimic=None):
        if name in self.joint_names:
            raise ValueError("duplicate joint %r" % name)
        if jtype not in ("fixed", "revolute", "continuous", "prismatic"):
            raise ValueError("joint %r: unsupported type %r" % (name, jtype))
        self.joint_names.append(name)
        out = ['  <joint name="%s" type="%s">' % (name, jtype),
               '    <parent link="%s"/>' % parent,
               '    <child link="%s"/>' % child,
               '    <origin xyz="%s" rpy="%s"/>' % (vec(xyz), vec(rpy))]
        if jtype != "fixed":
            out.append('    <axis xyz="%s"/>' % vec(axis))
            attrs = []
            if jtype in ("revolute", "prismatic"):
                attrs.append('lower="%s" upper="%s"' % (num(lower), num(upper)))
            attrs.append('effort="%s" velocity="%s"' % (num(effort if effort is not None else 100),
                                                         num(velocity if velocity is not None else 1)))
            out.append('    <limit %s/>' % " ".join(attrs))
            if soft is not None:
                out.append('    <safety_controller soft_lower_limit="%s" soft_upper_limit="%s"'
                           ' k_position="100" k_velocity="10"/>' % (num(soft[0]), num(soft[1])))
            if mimic is not None:
                out.append('    <mimic joint="%s" multiplier="%s" offset="%s"/>'
                           % (mimic[0], num(mimic[1]), num(mimic[2])))
        out.append('  </joint>')
        self.lines.extend(out)

    def render(self, comment=None):
        head = ['<?xml version="1.0"?>']
        if comment:
            head.append("<!-- %s -->" % comment)
        head.append('<robot name="%s">' % self.name)
        return "\n".join(head + self.materials + self.lines + ["</robot>", ""])

    def write(self, path, comment=None):
        with open(path, "w") as f:
            f.write(self.render(comment))


def _half(shape, i):
    if shape.kind == "box":
        return shape.dims[i] / 2.0
    if shape.kind in ("cylinder", "sphere"):
        return shape.dims[0]
    return 0.0
