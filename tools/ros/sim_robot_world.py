"""The ROS-free part of the simulated robot node (tools/ros/sim_robot.py).

Everything here is plain Python (no rospy), so it can be checked without a ROS master:

  parse_urdf(TEXT)          -> {joint name: Joint} of the URDF's non-fixed joints
  JointModel(joints)        joint positions, linear motions, limit checks, mimic joints
  BaseModel(x, y, yaw)      the base pose in map and its straight-line motion
  World                     the simulated objects, their attachments to the tool frames
  Faults                    the injected faults (block_navigation, hide_object, ...)
  pose math                 quaternions and 7-element poses [x, y, z, qx, qy, qz, qw]

Times are seconds of time.monotonic(); the node divides durations by its ~speed.
"""

import json
import math
import xml.etree.ElementTree as ET

LIMIT_EPSILON = 1e-6   # a commanded position this far outside a limit is still accepted


# ---- pose math -------------------------------------------------------------------------------

def quat_mul(a, b):
    """Hamilton product of quaternions (x, y, z, w)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def quat_conj(q):
    return (-q[0], -q[1], -q[2], q[3])


def quat_normalize(q):
    """Q scaled to unit length; None for a zero or non-finite quaternion."""
    n = math.sqrt(sum(c * c for c in q))
    if not math.isfinite(n) or n < 1e-9:
        return None
    return tuple(c / n for c in q)


def quat_rotate(q, v):
    """Vector V rotated by the unit quaternion Q."""
    x, y, z, _ = quat_mul(quat_mul(q, (v[0], v[1], v[2], 0.0)), quat_conj(q))
    return (x, y, z)


def yaw_quat(yaw):
    return (0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0))


def quat_yaw(q):
    x, y, z, w = q
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def pose_mul(a, b):
    """Pose A * pose B, both [x, y, z, qx, qy, qz, qw]."""
    p = quat_rotate(a[3:], b[:3])
    q = quat_mul(a[3:], b[3:])
    return [a[0] + p[0], a[1] + p[1], a[2] + p[2]] + list(q)


def pose_inverse(a):
    qi = quat_conj(a[3:])
    p = quat_rotate(qi, a[:3])
    return [-p[0], -p[1], -p[2]] + list(qi)


def angle_diff(a, b):
    """a - b wrapped to (-pi, pi]."""
    d = math.fmod(a - b, 2.0 * math.pi)
    if d > math.pi:
        d -= 2.0 * math.pi
    elif d <= -math.pi:
        d += 2.0 * math.pi
    return d


# ---- URDF ------------------------------------------------------------------------------------

class Joint(object):
    """One non-fixed URDF joint: type, limits (None for continuous), velocity limit, mimic."""

    def __init__(self, name, jtype, lower=None, upper=None, velocity=None, mimic=None):
        self.name, self.type = name, jtype
        self.lower, self.upper, self.velocity = lower, upper, velocity
        self.mimic = mimic   # (master joint, multiplier, offset) or None

    def limited(self):
        return self.lower is not None and self.upper is not None

    def within(self, value):
        return (not self.limited()
                or self.lower - LIMIT_EPSILON <= value <= self.upper + LIMIT_EPSILON)

    def clamp(self, value):
        return min(max(value, self.lower), self.upper) if self.limited() else value


def parse_urdf(text):
    """The non-fixed joints of the URDF TEXT as an ordered {name: Joint}."""
    root = ET.fromstring(text)
    joints = {}
    for j in root.findall('joint'):
        jtype = j.get('type')
        if jtype in (None, 'fixed', 'floating', 'planar'):
            continue
        lower = upper = velocity = None
        lim = j.find('limit')
        if lim is not None:
            velocity = float(lim.get('velocity')) if lim.get('velocity') else None
            if jtype != 'continuous':
                lower = float(lim.get('lower', 0.0))
                upper = float(lim.get('upper', 0.0))
        mimic = None
        m = j.find('mimic')
        if m is not None:
            mimic = (m.get('joint'), float(m.get('multiplier', 1.0)), float(m.get('offset', 0.0)))
        joints[j.get('name')] = Joint(j.get('name'), jtype, lower, upper, velocity, mimic)
    return joints


def urdf_root(text):
    """The root link of the URDF TEXT (the link that is no joint's child)."""
    root = ET.fromstring(text)
    children = set(c.get('link') for c in root.findall('joint/child'))
    for link in root.findall('link'):
        if link.get('name') not in children:
            return link.get('name')
    return None


# ---- joints ----------------------------------------------------------------------------------

class JointModel(object):
    """Positions of all non-fixed joints; each moves linearly towards its latest target."""

    def __init__(self, joints, initial=None):
        self.joints = joints
        self.names = list(joints)
        self.start = {}
        for name, j in joints.items():
            v = 0.0
            if j.limited() and not j.within(0.0):
                v = j.lower
            self.start[name] = v
        for name, v in (initial or {}).items():
            if name in joints:
                self.start[name] = joints[name].clamp(float(v))
        self.motion = {}   # name -> (from, to, t0, duration)
        self._apply_mimics(self.start)

    def _apply_mimics(self, values):
        for name, j in self.joints.items():
            if j.mimic and j.mimic[0] in values:
                values[name] = j.clamp(values[j.mimic[0]] * j.mimic[1] + j.mimic[2])

    def positions(self, now):
        """{name: position} at time NOW; finished motions are folded into the start values."""
        values = dict(self.start)
        for name, (a, b, t0, d) in list(self.motion.items()):
            if d <= 0 or now >= t0 + d:
                values[name] = b
                self.start[name] = b
                del self.motion[name]
            else:
                values[name] = a + (b - a) * max(0.0, now - t0) / d
        self._apply_mimics(values)
        return values

    def moving(self):
        return bool(self.motion)

    def check(self, names, positions):
        """Problems of a command, as a list of messages (empty when it can be executed)."""
        problems = []
        if len(names) != len(positions):
            return ['%d joint names but %d positions' % (len(names), len(positions))]
        for n, v in zip(names, positions):
            j = self.joints.get(n)
            if j is None:
                problems.append('unknown or fixed joint %s' % n)
            elif not math.isfinite(v):
                problems.append('joint %s: position %r is not finite' % (n, v))
            elif not j.within(v):
                problems.append('joint %s: position %.6g outside the limits [%.6g, %.6g]'
                                % (n, v, j.lower, j.upper))
        return problems

    def resolve(self, names, positions):
        """{master joint: target} for a checked command: mimic joints given without their master
        set the master; mimic joints given with it are ignored."""
        given = dict(zip(names, positions))
        targets = {}
        for n, v in given.items():
            j = self.joints[n]
            if j.mimic is None:
                targets[n] = v
        for n, v in given.items():
            j = self.joints[n]
            if j.mimic and j.mimic[0] not in given and j.mimic[0] in self.joints and j.mimic[1] != 0:
                master = self.joints[j.mimic[0]]
                targets.setdefault(master.name, master.clamp((v - j.mimic[2]) / j.mimic[1]))
        return targets

    def command(self, targets, duration, now, speed):
        """Move the joints of TARGETS to their values over DURATION seconds (at least what the
        velocity limits allow), divided by SPEED. Returns the duration used."""
        current = self.positions(now)
        needed = duration
        for n, v in targets.items():
            vel = self.joints[n].velocity
            if vel and vel > 0:
                needed = max(needed, abs(v - current[n]) / vel)
        d = needed / speed
        for n, v in targets.items():
            self.start[n] = current[n]
            self.motion[n] = (current[n], v, now, d)
        return d


# ---- base ------------------------------------------------------------------------------------

class BaseModel(object):
    """Pose (x, y, yaw) of the base frame in map, moving in a straight line to a goal."""

    def __init__(self, x=0.0, y=0.0, yaw=0.0):
        self.pose = (x, y, yaw)
        self.motion = None   # (from, to, t0, duration)

    def at(self, now):
        if self.motion is None:
            return self.pose
        a, b, t0, d = self.motion
        f = 1.0 if d <= 0 else min(1.0, max(0.0, (now - t0) / d))
        p = (a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f, a[2] + angle_diff(b[2], a[2]) * f)
        if f >= 1.0:
            self.pose, self.motion = b, None
        return p

    def go(self, x, y, yaw, now, speed, linear=0.5, angular=1.0):
        """Start a straight-line motion to (x, y, yaw); returns its duration."""
        a = self.at(now)
        d = max(math.hypot(x - a[0], y - a[1]) / linear, abs(angle_diff(yaw, a[2])) / angular) / speed
        self.pose, self.motion = a, (a, (x, y, yaw), now, d)
        return d

    def stop(self, now):
        self.pose, self.motion = self.at(now), None
        return self.pose


# ---- objects ---------------------------------------------------------------------------------

class SimObject(object):
    def __init__(self, name, otype, pose, size):
        self.name, self.type = name, otype
        self.pose = [float(c) for c in pose]
        self.size = [float(c) for c in size]
        self.attached = None   # (side, pose of the object in the tool frame)

    def width(self):
        """The width the fingers close on: the object's smallest extent."""
        return min(self.size)


def object_from_spec(spec):
    """A SimObject from a dict {name, type, pose: [x y z] or [x y z qx qy qz qw], size}."""
    name = str(spec['name'])
    pose = [float(c) for c in spec.get('pose', [0, 0, 0])]
    if len(pose) == 3:
        pose += [0.0, 0.0, 0.0, 1.0]
    if len(pose) != 7:
        raise ValueError('object %s: pose needs 3 or 7 numbers' % name)
    q = quat_normalize(pose[3:]) or (0.0, 0.0, 0.0, 1.0)
    size = [float(c) for c in spec.get('size', [0.05, 0.05, 0.1])]
    if len(size) != 3:
        raise ValueError('object %s: size needs 3 numbers' % name)
    return SimObject(name, str(spec.get('type', name.split('-')[0])).lower(), pose[:3] + list(q), size)


class World(object):
    """The simulated objects by name, in insertion order."""

    GRASP_DISTANCE = 0.06

    def __init__(self):
        self.objects = {}

    def add(self, obj):
        self.objects[obj.name] = obj

    def remove(self, name):
        return self.objects.pop(name, None)

    def attached_to(self, side):
        return [o for o in self.objects.values() if o.attached and o.attached[0] == side]

    def nearest_free(self, tool_pose, distance=None):
        """The unattached object whose centre is nearest TOOL_POSE, if within DISTANCE."""
        distance = self.GRASP_DISTANCE if distance is None else distance
        best, best_d = None, None
        for o in self.objects.values():
            if o.attached:
                continue
            d = math.sqrt(sum((o.pose[i] - tool_pose[i]) ** 2 for i in range(3)))
            if d <= distance and (best_d is None or d < best_d):
                best, best_d = o, d
        return best

    def attach(self, obj, side, tool_pose):
        """Attach OBJ to SIDE's tool frame at TOOL_POSE; with TOOL_POSE None the attachment is
        pending (the object is held but does not follow yet): anchor() completes it."""
        obj.attached = (side, None if tool_pose is None else pose_mul(pose_inverse(tool_pose), obj.pose))

    def anchor(self, side, tool_pose):
        """Complete the pending attachments of SIDE with its tool frame at TOOL_POSE."""
        for o in self.attached_to(side):
            if o.attached[1] is None:
                o.attached = (side, pose_mul(pose_inverse(tool_pose), o.pose))

    def follow(self, side, tool_pose):
        """Move the objects attached to SIDE with its tool frame at TOOL_POSE."""
        for o in self.attached_to(side):
            if o.attached[1] is not None:
                o.pose = pose_mul(tool_pose, o.attached[1])

    def release(self, side):
        released = self.attached_to(side)
        for o in released:
            o.attached = None
        return released


# ---- faults ----------------------------------------------------------------------------------

class Faults(object):
    """Injected faults; apply() takes the JSON text or dict of the sim_robot/faults topic."""

    def __init__(self):
        self.clear()

    def clear(self):
        self.block_navigation = 0
        self.reject_joint_goals = 0
        self.hidden = {}          # object name -> remaining count (-1: always)
        self.drop_until = 0.0     # monotonic time until which the node is silent

    def apply(self, spec, now):
        """Apply SPEC (JSON text or dict); returns a list of what was set. Raises ValueError."""
        if isinstance(spec, str):
            try:
                spec = json.loads(spec)
            except ValueError as e:
                raise ValueError('faults: not JSON: %s' % e)
        if not isinstance(spec, dict):
            raise ValueError('faults: expected a JSON object, got %r' % (spec,))
        done = []
        if spec.get('clear'):
            self.clear()
            done.append('clear')
        for key, value in spec.items():
            if key == 'clear':
                continue
            if key == 'block_navigation':
                self.block_navigation = int(value)
            elif key == 'reject_joint_goals':
                self.reject_joint_goals = int(value)
            elif key == 'drop_connection':
                self.drop_until = now + float(value)
            elif key == 'hide_object':
                items = value if isinstance(value, list) else [value]
                for item in items:
                    if isinstance(item, str):
                        item = {'name': item, 'count': -1}
                    self.hidden[str(item['name'])] = int(item.get('count', 1))
            else:
                raise ValueError('faults: unknown fault %r' % key)
            done.append('%s=%s' % (key, json.dumps(value)))
        return done

    def dropped(self, now):
        return now < self.drop_until

    def take(self, attr):
        """Consume one unit of the counter ATTR; True if the fault applies."""
        n = getattr(self, attr)
        if n > 0:
            setattr(self, attr, n - 1)
            return True
        return n < 0

    def hidden_names(self):
        return set(n for n, c in self.hidden.items() if c != 0)

    def consume_hidden(self):
        """One perception message went out to a subscriber: count down the hide_object faults."""
        for n, c in list(self.hidden.items()):
            if c > 0:
                self.hidden[n] = c - 1
            if self.hidden[n] == 0:
                del self.hidden[n]
