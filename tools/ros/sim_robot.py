#!/usr/bin/python3
"""A simulated robot behind the ROS interfaces of docs/robot-over-ros.md.

Usage: sim_robot.py [ROS remappings and _param:=value]    (normally from launch/sim_robot.launch)
       sim_robot.py --help

Reads the URDF from robot_description and serves, relative to the node's namespace:
  action move_base (move_base_msgs/MoveBaseAction)    straight line, 0.5 m/s and 1 rad/s / ~speed
  topics <group>_controller/command (trajectory_msgs/JointTrajectory) for the groups
         torso, head, left_arm, right_arm, left_gripper, right_gripper
  /joint_states at 50 Hz (all non-fixed joints), TF map -> ODOM -> BASE at 50 Hz
  perception/objects (visualization_msgs/MarkerArray, 10 Hz), sim_robot/spawn (Marker),
  sim_robot/faults (std_msgs/String, JSON), parameters sim_robot/counts/* and
  sim_robot/objects/<name>.

Private parameters (defaults fit the PR2):
  ~speed            time factor (10 = ten times faster than the robot), default 1
  ~initial_pose     [x, y, yaw] of the base frame in map, default [0, 0, 0]
  ~initial_joints   {joint: position}
  ~tool_frames      {left: l_gripper_tool_frame, right: r_gripper_tool_frame}
  ~gripper_joints   {left: [l_gripper_l_finger_joint, l_gripper_r_finger_joint], right: [...]}
  ~gripper_meter_to_joint  finger joint units per metre of opening, default 5.0 (the PR2 facts')
  ~objects          list of {name, type, pose, size}, or a YAML text / YAML file name of one
  ~faults           a fault JSON object (text or dict), applied and deleted when set
  ~base_frame, ~odom_frame, ~base_height   base_footprint, odom_combined, 0 (Pepper: base_link, odom, 0.82)
"""

import sys

if __name__ == '__main__' and any(a in ('-h', '--help') for a in sys.argv[1:]):
    print(__doc__)
    sys.exit(0)

import json
import os
import threading
import time
import warnings

import yaml
import rospy
import actionlib
import tf2_ros
from geometry_msgs.msg import TransformStamped
from move_base_msgs.msg import MoveBaseAction
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import Marker, MarkerArray

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sim_robot_world as sw   # noqa: E402

# Object names such as bottle-1 are not legal graph names, but work as parameter names.
warnings.filterwarnings('ignore', message='.*is not a legal ROS graph resource name')

GROUPS = ('torso', 'head', 'left_arm', 'right_arm', 'left_gripper', 'right_gripper')
COUNTS = ('move_base',) + GROUPS + ('perception_requests',)


class SimRobot(object):
    """The node: state under one lock, a 50 Hz loop publishing it, callbacks changing it."""

    def __init__(self):
        self.lock = threading.RLock()
        self.pending = {}          # side -> (attach or release, rospy.Time of the command, deadline)
        description = rospy.get_param('robot_description')
        self.speed = float(rospy.get_param('~speed', 1.0))
        if not self.speed > 0:
            rospy.logwarn('sim_robot: ~speed %r is not positive, using 1', self.speed)
            self.speed = 1.0
        self.joints = sw.JointModel(sw.parse_urdf(description), rospy.get_param('~initial_joints', {}))
        pose = list(rospy.get_param('~initial_pose', [0.0, 0.0, 0.0])) + [0.0, 0.0, 0.0]
        self.base = sw.BaseModel(float(pose[0]), float(pose[1]), float(pose[2]))
        self.base_frame = rospy.get_param('~base_frame', sw.urdf_root(description) or 'base_footprint')
        self.odom_frame = rospy.get_param('~odom_frame', 'odom_combined')
        self.base_height = float(rospy.get_param('~base_height', 0.0))
        self.tool_frames = rospy.get_param('~tool_frames', {'left': 'l_gripper_tool_frame',
                                                            'right': 'r_gripper_tool_frame'})
        self.gripper_joints = rospy.get_param('~gripper_joints', {
            'left': ['l_gripper_l_finger_joint', 'l_gripper_r_finger_joint'],
            'right': ['r_gripper_l_finger_joint', 'r_gripper_r_finger_joint']})
        self.gripper_multiplier = float(rospy.get_param('~gripper_meter_to_joint', 5.0))
        self.world = sw.World()
        self.faults = sw.Faults()
        self.counts = dict((k, 0) for k in COUNTS)
        self.published_objects = {}
        self.objects_dirty = True
        self.load_objects(rospy.get_param('~objects', []))

        self.tf_buffer = tf2_ros.Buffer(cache_time=rospy.Duration(10))
        self.tf_listener = tf2_ros.TransformListener(self.tf_buffer)
        self.tf_pub = tf2_ros.TransformBroadcaster()
        self.js_pub = rospy.Publisher('/joint_states', JointState, queue_size=10)
        self.perception_pub = rospy.Publisher('perception/objects', MarkerArray, queue_size=5)
        for k in COUNTS:
            self.set_count(k, 0)
        self.subs = [rospy.Subscriber('%s_controller/command' % g, JointTrajectory,
                                      self.on_command, callback_args=g, queue_size=10)
                     for g in GROUPS]
        self.subs.append(rospy.Subscriber('sim_robot/spawn', Marker, self.on_spawn, queue_size=50))
        self.subs.append(rospy.Subscriber('sim_robot/faults', String, self.on_faults, queue_size=10))
        self.apply_fault_param()
        self.action = actionlib.SimpleActionServer('move_base', MoveBaseAction,
                                                   execute_cb=self.on_goal, auto_start=False)
        self.action.start()
        self.silence_action_server()
        rospy.loginfo('sim_robot: %d joints, %d objects, speed %g', len(self.joints.names),
                      len(self.world.objects), self.speed)

    # ---- parameters ----------------------------------------------------------------------

    def load_objects(self, spec):
        """Add the objects of ~objects: a list, a YAML text, or the name of a YAML file."""
        if isinstance(spec, str):
            spec = spec.strip()
            if spec and os.path.isfile(spec):
                with open(spec) as f:
                    spec = yaml.safe_load(f)
            elif spec.endswith(('.yaml', '.yml')):
                rospy.logerr('sim_robot: ~objects: no file %s (give an absolute path)', spec)
                spec = []
            else:
                spec = yaml.safe_load(spec) if spec else []
        if isinstance(spec, dict):
            spec = spec.get('objects', [spec])
        for item in spec or []:
            try:
                self.world.add(sw.object_from_spec(item))
            except (KeyError, ValueError, TypeError) as e:
                rospy.logerr('sim_robot: bad object %r: %s', item, e)

    def set_count(self, key, value=None):
        if value is None:
            self.counts[key] += 1
        try:
            rospy.set_param('sim_robot/counts/%s' % key, self.counts[key])
        except Exception as e:   # a lost master must not stop the simulation
            rospy.logwarn_throttle(5, 'sim_robot: cannot set counts: %s' % e)

    def publish_object_params(self):
        """Set sim_robot/objects/<name> for objects that moved, delete those removed."""
        with self.lock:
            poses = dict((n, [round(c, 6) for c in o.pose]) for n, o in self.world.objects.items())
        try:
            for n, p in poses.items():
                old = self.published_objects.get(n)
                if old is None or max(abs(a - b) for a, b in zip(old, p)) > 1e-4:
                    rospy.set_param('sim_robot/objects/%s' % n, p)
                    self.published_objects[n] = p
            for n in [n for n in self.published_objects if n not in poses]:
                del self.published_objects[n]
                if rospy.has_param('sim_robot/objects/%s' % n):
                    rospy.delete_param('sim_robot/objects/%s' % n)
        except Exception as e:
            rospy.logwarn_throttle(5, 'sim_robot: cannot set object parameters: %s' % e)

    # ---- faults --------------------------------------------------------------------------

    def apply_faults(self, spec, source):
        with self.lock:
            try:
                done = self.faults.apply(spec, time.monotonic())
                rospy.loginfo('sim_robot: faults from %s: %s', source, ', '.join(done))
            except (ValueError, KeyError, TypeError) as e:
                rospy.logerr('sim_robot: %s: %s', source, e)

    def on_faults(self, msg):
        self.apply_faults(msg.data, 'sim_robot/faults')

    def apply_fault_param(self):
        """Apply ~faults when set, then delete it so the same faults can be set again."""
        try:
            if rospy.has_param('~faults'):
                spec = rospy.get_param('~faults')
                rospy.delete_param('~faults')
                if spec:
                    self.apply_faults(spec, '~faults')
        except Exception as e:
            rospy.logwarn_throttle(5, 'sim_robot: ~faults: %s' % e)

    def dropped(self):
        """Lock-free (the action server calls it holding its own lock)."""
        return self.faults.dropped(time.monotonic())

    def silence_action_server(self):
        """Wrap the action server's publishers so drop_connection silences them."""
        server = self.action.action_server
        for attr in ('status_pub', 'result_pub', 'feedback_pub'):
            pub = getattr(server, attr)
            original = pub.publish

            def publish(*args, _original=original, **kwargs):
                if not self.dropped():
                    _original(*args, **kwargs)
            pub.publish = publish

    # ---- base ----------------------------------------------------------------------------

    def goal_in_map(self, pose_stamped):
        """(x, y, yaw) of a goal PoseStamped in map, or raise ValueError."""
        p, o = pose_stamped.pose.position, pose_stamped.pose.orientation
        q = sw.quat_normalize((o.x, o.y, o.z, o.w))
        if q is None:
            raise ValueError('goal orientation is not a unit quaternion')
        pose = [p.x, p.y, p.z] + list(q)
        frame = pose_stamped.header.frame_id.lstrip('/')
        if frame not in ('map', self.odom_frame, ''):
            try:
                t = self.tf_buffer.lookup_transform('map', frame, rospy.Time(0), rospy.Duration(1.0))
            except (tf2_ros.LookupException, tf2_ros.ConnectivityException,
                    tf2_ros.ExtrapolationException) as e:
                raise ValueError('goal frame %s: %s' % (frame, e))
            pose = sw.pose_mul(transform_pose(t), pose)
        if not all(abs(c) < 1e6 for c in pose):
            raise ValueError('goal position out of range')
        return pose[0], pose[1], sw.quat_yaw(pose[3:])

    def on_goal(self, goal):
        """Execute one move_base goal (runs in the action server's thread)."""
        with self.lock:
            self.set_count('move_base')
            dropped = self.faults.dropped(time.monotonic())
            blocked = not dropped and self.faults.take('block_navigation')
        if dropped or blocked:
            rospy.loginfo('sim_robot: move_base goal aborted (%s)',
                          'connection dropped' if dropped else 'block_navigation fault')
            self.action.set_aborted(text='connection dropped' if dropped else 'navigation blocked (fault)')
            return
        try:
            x, y, yaw = self.goal_in_map(goal.target_pose)
        except ValueError as e:
            rospy.logerr('sim_robot: move_base goal refused: %s', e)
            self.action.set_aborted(text=str(e))
            return
        with self.lock:
            duration = self.base.go(x, y, yaw, time.monotonic(), self.speed)
        end = time.monotonic() + duration
        while not rospy.is_shutdown():
            if self.action.is_preempt_requested():
                with self.lock:
                    self.base.stop(time.monotonic())
                self.action.set_preempted(text='preempted')
                return
            if time.monotonic() >= end:
                break
            time.sleep(0.01)
        with self.lock:
            self.base.at(time.monotonic())
        self.action.set_succeeded(text='reached')

    # ---- joints and grippers ---------------------------------------------------------------

    def tool_pose(self, side, since=None):
        """Pose [x y z qx qy qz qw] of SIDE's tool frame in map from TF, or None; with SINCE (a
        rospy.Time), None unless TF holds the frame at SINCE or later."""
        frame = self.tool_frames.get(side)
        if not frame:
            return None
        try:
            t = self.tf_buffer.lookup_transform('map', frame, rospy.Time(0))
        except (tf2_ros.LookupException, tf2_ros.ConnectivityException,
                tf2_ros.ExtrapolationException):
            return None
        if since is not None and t.header.stamp < since:
            return None
        return transform_pose(t)

    def settle_gripper_events(self, now):
        """Attach and release where the gripper commands found the arm. The tool frame comes
        from TF (robot_state_publisher), which may lag the joints: an event waits, at most a
        second, for a tool pose stamped after its command, so that an object is not anchored or
        let go where the arm was while it still moved."""
        for side, (kind, stamp, deadline) in list(self.pending.items()):
            tool = self.tool_pose(side, since=stamp)
            if tool is None and now >= deadline:
                tool = self.tool_pose(side)
            if tool is None and now < deadline:
                continue
            del self.pending[side]
            if kind == 'attach' and tool is not None:
                self.world.anchor(side, tool)
            elif kind == 'release':
                if tool is not None:
                    self.world.follow(side, tool)
                for o in self.world.release(side):
                    rospy.loginfo('sim_robot: %s released by the %s gripper', o.name, side)
            self.objects_dirty = True

    def on_command(self, msg, group):
        """A JointTrajectory on <group>_controller/command."""
        with self.lock:
            self.set_count(group)
            now = time.monotonic()
            if self.faults.dropped(now):
                rospy.logwarn('sim_robot: %s command lost (connection dropped)', group)
                return
            if not msg.points:
                rospy.logerr('sim_robot: %s command without points refused', group)
                return
            point = msg.points[-1]
            names, positions = list(msg.joint_names), list(point.positions)
            problems = self.joints.check(names, positions)
            if not problems and self.faults.take('reject_joint_goals'):
                problems = ['rejected by a reject_joint_goals fault']
            if problems:
                rospy.logerr('sim_robot: %s command refused: %s', group, '; '.join(problems))
                return
            targets = self.joints.resolve(names, positions)
            if group.endswith('_gripper'):
                targets = self.gripper_targets(group[:-len('_gripper')], targets, now)
            self.joints.command(targets, max(0.0, point.time_from_start.to_sec()), now, self.speed)

    def gripper_targets(self, side, targets, now):
        """Attach, release, and stop the fingers at a grasped object's width."""
        fingers = [j for j in self.gripper_joints.get(side, []) if j in targets]
        if not fingers:
            return targets
        current = self.joints.positions(now)
        closing = any(targets[j] < current[j] - 1e-4 for j in fingers)
        opening = any(targets[j] > current[j] + 1e-4 for j in fingers)
        if opening and not closing:
            if self.world.attached_to(side):
                self.pending[side] = ('release', rospy.Time.now(), now + 1.0)
            return targets
        held = self.world.attached_to(side)
        if closing and not held:
            tool = self.tool_pose(side)
            obj = self.world.nearest_free(tool) if tool else None
            if tool is None:
                rospy.logwarn('sim_robot: no TF for the %s tool frame, nothing grasped', side)
            if obj:
                self.world.attach(obj, side, None)
                self.pending[side] = ('attach', rospy.Time.now(), now + 1.0)
                rospy.loginfo('sim_robot: %s attached to the %s gripper', obj.name, side)
                held = [obj]
        if held:
            width = max(o.width() for o in held) * self.gripper_multiplier
            for j in fingers:
                targets[j] = max(targets[j], self.joints.joints[j].clamp(width))
        return targets

    # ---- objects ---------------------------------------------------------------------------

    def on_spawn(self, m):
        """Add, move (action ADD/MODIFY) or remove (DELETE) an object."""
        name = m.text or '%s-%d' % (m.ns or 'object', m.id)
        with self.lock:
            if m.action == Marker.DELETE:
                self.world.remove(name)
            elif m.action == Marker.DELETEALL:
                self.world.objects.clear()
            else:
                p, o = m.pose.position, m.pose.orientation
                pose = [p.x, p.y, p.z, o.x, o.y, o.z, o.w]
                frame = m.header.frame_id.lstrip('/') or 'map'
                if frame != 'map':
                    try:
                        pose = sw.pose_mul(transform_pose(self.tf_buffer.lookup_transform(
                            'map', frame, rospy.Time(0), rospy.Duration(1.0))), pose)
                    except Exception as e:
                        rospy.logerr('sim_robot: spawn %s in %s: %s', name, frame, e)
                        return
                try:
                    self.world.add(sw.object_from_spec({
                        'name': name, 'type': m.ns or name.split('-')[0], 'pose': pose,
                        'size': [m.scale.x, m.scale.y, m.scale.z]}))
                except ValueError as e:
                    rospy.logerr('sim_robot: spawn: %s', e)
            self.objects_dirty = True
        self.publish_object_params()

    def perception_message(self, stamp):
        with self.lock:
            hidden = self.faults.hidden_names()
            objects = [o for o in self.world.objects.values() if o.name not in hidden]
            array = MarkerArray()
            for i, o in enumerate(objects):
                m = Marker()
                m.header.frame_id, m.header.stamp = 'map', stamp
                m.ns, m.id, m.text, m.type, m.action = o.type, i, o.name, Marker.CUBE, Marker.ADD
                (m.pose.position.x, m.pose.position.y, m.pose.position.z) = o.pose[:3]
                (m.pose.orientation.x, m.pose.orientation.y, m.pose.orientation.z,
                 m.pose.orientation.w) = o.pose[3:]
                m.scale.x, m.scale.y, m.scale.z = o.size
                m.color.r, m.color.g, m.color.b, m.color.a = 0.2, 0.6, 1.0, 0.8
                m.lifetime = rospy.Duration(0.5)
                array.markers.append(m)
            return array

    # ---- publishing loop -------------------------------------------------------------------

    def step(self, tick):
        now = time.monotonic()
        stamp = rospy.Time.now()
        with self.lock:
            positions = self.joints.positions(now)
            x, y, yaw = self.base.at(now)
            dropped = self.faults.dropped(now)
            self.settle_gripper_events(now)
            for side in self.tool_frames:
                if self.world.attached_to(side):
                    tool = self.tool_pose(side)
                    if tool:
                        self.world.follow(side, tool)
                        self.objects_dirty = True
        if dropped:
            return
        js = JointState()
        js.header.stamp = stamp
        js.name = self.joints.names
        js.position = [positions[n] for n in js.name]
        self.js_pub.publish(js)
        q = sw.yaw_quat(yaw)
        self.tf_pub.sendTransform([
            make_transform(stamp, 'map', self.odom_frame, (0, 0, 0), (0, 0, 0, 1)),
            make_transform(stamp, self.odom_frame, self.base_frame, (x, y, self.base_height), q)])
        if tick % 5 == 0:
            listening = self.perception_pub.get_num_connections() > 0
            self.perception_pub.publish(self.perception_message(stamp))
            if listening:
                with self.lock:
                    self.faults.consume_hidden()
                    self.set_count('perception_requests')
            if self.objects_dirty:
                self.objects_dirty = False
                self.publish_object_params()
        if tick % 50 == 0:
            self.apply_fault_param()

    def spin(self):
        rate = rospy.Rate(50)
        tick = 0
        while not rospy.is_shutdown():
            try:
                self.step(tick)
            except Exception as e:
                rospy.logerr_throttle(5, 'sim_robot: %s' % e)
            tick += 1
            try:
                rate.sleep()
            except rospy.ROSInterruptException:
                break


def transform_pose(t):
    """[x y z qx qy qz qw] of a geometry_msgs/TransformStamped."""
    p, q = t.transform.translation, t.transform.rotation
    return [p.x, p.y, p.z, q.x, q.y, q.z, q.w]


def make_transform(stamp, parent, child, xyz, q):
    t = TransformStamped()
    t.header.stamp, t.header.frame_id, t.child_frame_id = stamp, parent, child
    t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = xyz
    (t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z,
     t.transform.rotation.w) = q
    return t


def main():
    rospy.init_node('sim_robot')
    SimRobot().spin()


if __name__ == '__main__':
    main()
