#!/bin/bash
# Self-test of the simulated robot node (tools/ros/sim_robot.py, launch/sim_robot.launch).
#
# Usage: tests/sim-robot-check.sh
#
# Starts a private roscore (own ROS_HOME in a temporary directory, free port on 127.0.0.1),
# launches launch/sim_robot.launch with speed:=10 and one bottle, and checks with a Python
# client: move_base reaches its goal (TF within 1 cm), block_navigation aborts the next goal,
# head commands move /joint_states, out-of-limit and reject_joint_goals commands are refused,
# perception/objects carries the bottle, closing the right gripper at the bottle attaches it
# (fingers stop at its width, the torso carries it), opening releases it, hide_object hides
# it, drop_connection silences /joint_states, the count parameters increase.
# Prints "ok ..." / "FAIL ..." lines and "sim-robot-check: N passed, M failed"; exits non-zero
# on a failure. Stops everything it started and verifies that nothing is left.
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
. "$root/tools/ros/ros-env.sh"

start_time=$SECONDS
passed=0
failed=0
ok()   { passed=$((passed + 1)); echo "ok   $*"; }
fail() { failed=$((failed + 1)); echo "FAIL $*"; }
finish() {
  echo "sim-robot-check: $passed passed, $failed failed ($((SECONDS - start_time)) s)"
  [ "$failed" = 0 ] && [ -n "${ROS_WORK:-}" ] && rm -rf "$ROS_WORK"
  [ "$failed" = 0 ]
}

ros_private_env
trap 'ros_stop_all' EXIT
trap 'exit 130' INT TERM
if ros_start_core; then ok "roscore on $ROS_MASTER_URI"; else fail "roscore did not start"; finish; exit 1; fi

ros_start sim roslaunch "$root/launch/sim_robot.launch" speed:=10 \
  objects:="[{name: bottle-1, type: bottle, pose: [1.5, 0.0, 0.8], size: [0.06, 0.06, 0.2]}]"
if ros_wait_for 40 rosparam get /sim_robot/counts/perception_requests; then
  ok "sim_robot.launch started"
else
  fail "sim_robot.launch did not start the node"; tail -30 "$ROS_WORK/sim.log"
fi

output=$(timeout 45 /usr/bin/python3 - <<'EOF' 2>&1
import json, math, sys, threading, time
import rospy, actionlib, tf2_ros
from actionlib_msgs.msg import GoalStatus
from move_base_msgs.msg import MoveBaseAction, MoveBaseGoal
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
from visualization_msgs.msg import Marker, MarkerArray

def ok(msg): print('ok   ' + msg, flush=True)
def fail(msg): print('FAIL ' + msg, flush=True)
def check(cond, msg, detail=''):
    (ok if cond else fail)(msg + ('' if cond or not detail else ': ' + detail))
    return cond

rospy.init_node('sim_robot_check', anonymous=True, disable_signals=True)
tf_buffer = tf2_ros.Buffer()
tf_listener = tf2_ros.TransformListener(tf_buffer)
joints, stamps = {}, []
def on_js(msg):
    joints.update(zip(msg.name, msg.position)); stamps.append(time.monotonic())
rospy.Subscriber('/joint_states', JointState, on_js)
pubs = dict((g, rospy.Publisher('%s_controller/command' % g, JointTrajectory, queue_size=5))
            for g in ('torso', 'head', 'right_gripper'))
faults = rospy.Publisher('sim_robot/faults', String, queue_size=5)
spawn = rospy.Publisher('sim_robot/spawn', Marker, queue_size=5)
time.sleep(1.0)   # connections

def count(k): return rospy.get_param('sim_robot/counts/' + k)
def command(group, names, positions, t=0.5):
    msg = JointTrajectory(joint_names=names)
    msg.points = [JointTrajectoryPoint(positions=positions, time_from_start=rospy.Duration(t))]
    pubs[group].publish(msg)
def wait_joints(target, timeout=3.0, tol=0.005):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if all(abs(joints.get(n, 1e9) - v) <= tol for n, v in target.items()):
            return True
        time.sleep(0.02)
    return False
def lookup(frame, parent='map'):
    t = tf_buffer.lookup_transform(parent, frame, rospy.Time(0), rospy.Duration(2.0))
    return t.transform
def fault(spec): faults.publish(String(data=json.dumps(spec))); time.sleep(0.2)
def perceived(timeout=2.0):
    return rospy.wait_for_message('perception/objects', MarkerArray, timeout=timeout)
def obj_pose(name): return rospy.get_param('sim_robot/objects/' + name)

client = actionlib.SimpleActionClient('move_base', MoveBaseAction)
check(client.wait_for_server(rospy.Duration(10)), 'move_base action server is up')
counts0 = dict((k, count(k)) for k in ('move_base', 'head', 'torso', 'right_gripper', 'perception_requests'))

def go(x, y, yaw, timeout=10):
    g = MoveBaseGoal()
    g.target_pose.header.frame_id = 'map'
    g.target_pose.pose.position.x, g.target_pose.pose.position.y = x, y
    g.target_pose.pose.orientation.z, g.target_pose.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    client.send_goal(g)
    client.wait_for_result(rospy.Duration(timeout))
    return client.get_state()

state = go(1.0, 0.5, 0.5)
check(state == GoalStatus.SUCCEEDED, 'move_base goal succeeds', 'state %d' % state)
time.sleep(0.2)
t = lookup('base_footprint')
yaw = 2 * math.atan2(t.rotation.z, t.rotation.w)
err = math.hypot(t.translation.x - 1.0, t.translation.y - 0.5)
check(err < 0.01 and abs(yaw - 0.5) < 0.01, 'TF map -> base_footprint at the goal within 1 cm',
      'error %.4f m, yaw %.4f' % (err, yaw))
fault({'block_navigation': 1})
state = go(1.2, 0.5, 0.0)
check(state == GoalStatus.ABORTED, 'block_navigation aborts the next goal', 'state %d' % state)
state = go(1.0, 0.5, 0.0)
check(state == GoalStatus.SUCCEEDED, 'the goal after it succeeds', 'state %d' % state)
g = MoveBaseGoal()
g.target_pose.header.frame_id = 'map'
g.target_pose.pose.position.x, g.target_pose.pose.position.y, g.target_pose.pose.orientation.w = 6.0, 0.5, 1.0
client.send_goal(g)
time.sleep(0.3)
client.cancel_goal()
client.wait_for_result(rospy.Duration(3))
time.sleep(0.2)
x = lookup('base_footprint').translation.x
check(client.get_state() == GoalStatus.PREEMPTED and 1.05 < x < 5.0, 'cancel stops the base on its way',
      'state %d, x %.3f' % (client.get_state(), x))
state = go(1.0, 0.5, 0.0)
check(state == GoalStatus.SUCCEEDED, 'and it drives back', 'state %d' % state)

command('head', ['head_pan_joint', 'head_tilt_joint'], [0.4, 0.3])
check(wait_joints({'head_pan_joint': 0.4, 'head_tilt_joint': 0.3}), 'head command reaches its target',
      'at %r %r' % (joints.get('head_pan_joint'), joints.get('head_tilt_joint')))
torso0 = joints['torso_lift_joint']
command('torso', ['torso_lift_joint'], [0.5])
time.sleep(0.6)
check(abs(joints['torso_lift_joint'] - torso0) < 1e-6, 'out-of-limit torso command refused, torso stays')
fault({'reject_joint_goals': 1})
command('head', ['head_pan_joint', 'head_tilt_joint'], [0.0, 0.0])
time.sleep(0.6)
check(abs(joints['head_pan_joint'] - 0.4) < 1e-6, 'reject_joint_goals refuses the next command')

m = perceived()
bottles = [x for x in m.markers if x.text == 'bottle-1']
check(bool(bottles) and bottles[0].ns == 'bottle' and bottles[0].header.frame_id == 'map'
      and bottles[0].type == Marker.CUBE and abs(bottles[0].scale.z - 0.2) < 1e-9,
      'perception/objects carries bottle-1 (ns bottle, CUBE, map, size)', repr([x.text for x in m.markers]))

# grasp: open the right gripper, put the bottle at the tool frame, close
fingers = ['r_gripper_l_finger_joint', 'r_gripper_r_finger_joint']
command('right_gripper', fingers, [0.548, 0.548])
check(wait_joints(dict((f, 0.548) for f in fingers)), 'right gripper opens')
tool = lookup('r_gripper_tool_frame')
mk = Marker(ns='bottle', text='bottle-1', type=Marker.CUBE, action=Marker.ADD)
mk.header.frame_id = 'map'
mk.pose.position.x, mk.pose.position.y, mk.pose.position.z = (tool.translation.x, tool.translation.y,
                                                               tool.translation.z)
mk.pose.orientation.w = 1.0
mk.scale.x, mk.scale.y, mk.scale.z = 0.06, 0.06, 0.2
spawn.publish(mk)
time.sleep(0.5)
p0 = obj_pose('bottle-1')
check(abs(p0[2] - tool.translation.z) < 1e-3, 'sim_robot/spawn moves bottle-1 to the tool frame', repr(p0))
command('right_gripper', fingers, [0.0, 0.0])
check(wait_joints(dict((f, 0.3) for f in fingers), tol=0.01), 'fingers stop at the bottle width (0.06 m x 5)',
      repr([joints.get(f) for f in fingers]))
command('torso', ['torso_lift_joint'], [torso0 + 0.1])
check(wait_joints({'torso_lift_joint': torso0 + 0.1}, timeout=4), 'torso moves up 0.1')
time.sleep(0.5)
p1 = obj_pose('bottle-1')
check(abs(p1[2] - p0[2] - 0.1) < 0.01, 'the attached bottle moves with the torso', 'z %.3f -> %.3f' % (p0[2], p1[2]))
command('right_gripper', fingers, [0.548, 0.548])
check(wait_joints(dict((f, 0.548) for f in fingers)), 'right gripper opens again')
command('torso', ['torso_lift_joint'], [torso0])
wait_joints({'torso_lift_joint': torso0}, timeout=4)
time.sleep(0.5)
p2 = obj_pose('bottle-1')
check(abs(p2[2] - p1[2]) < 1e-3, 'opening released the bottle (stays when the torso goes down)',
      'z %.3f -> %.3f' % (p1[2], p2[2]))

fault({'hide_object': {'name': 'bottle-1', 'count': -1}})
m = perceived()
check(not any(x.text == 'bottle-1' for x in m.markers), 'hide_object hides bottle-1')
fault({'clear': True})
m = perceived()
check(any(x.text == 'bottle-1' for x in m.markers), 'clear shows it again')

rospy.set_param('sim_robot/faults', json.dumps({'hide_object': {'name': 'bottle-1', 'count': 2}}))
time.sleep(1.3)
seen = []
sub = rospy.Subscriber('perception/objects', MarkerArray, lambda m: seen.append(any(x.text == 'bottle-1' for x in m.markers)))
time.sleep(1.0)
sub.unregister()
check(len(seen) >= 4 and not seen[0] and seen[-1], '~faults parameter: hide_object count 2 hides a few messages', repr(seen))

faults.publish(String(data=json.dumps({'drop_connection': 1.0})))
t_fault = time.monotonic()
time.sleep(0.1)   # messages already in flight
stamps[:] = []
time.sleep(1.6)
first = stamps[0] - t_fault if stamps else -1
check(first >= 0.8 and len(stamps) > 5, 'drop_connection 1 s stops /joint_states (then resumes)',
      'first message %.2f s after the fault, %d messages' % (first, len(stamps)))

rospy.sleep(0.3)
after = dict((k, count(k)) for k in counts0)
check( after['head'] - counts0['head'] == 2
      and after['torso'] - counts0['torso'] == 3 and after['move_base'] - counts0['move_base'] == 5 and after['right_gripper'] - counts0['right_gripper'] == 3
      and after['perception_requests'] > counts0['perception_requests'],
      'count parameters increase', 'before %r after %r' % (counts0, after))
EOF
)
echo "$output" | grep -E '^(ok|FAIL) ' 
passed=$((passed + $(echo "$output" | grep -c '^ok ')))
failed=$((failed + $(echo "$output" | grep -c '^FAIL ')))
if ! echo "$output" | grep -q 'count parameters'; then
  fail "the client did not finish:"; echo "$output" | grep -v -E '^(ok|FAIL) ' | tail -15 | sed 's/^/     /'
fi
if grep -q 'torso command refused: joint torso_lift_joint: position 0.5 outside the limits \[0, 0.33\]' "$ROS_WORK/sim.log"; then
  ok "the refusal is logged naming joint, value and limits"
else
  fail "no refusal error for torso_lift_joint 0.5 in the log"
fi
if grep -q -E 'has died|Traceback' "$ROS_WORK/sim.log"; then
  fail "errors in the launch log:"; grep -E -A5 'has died|Traceback' "$ROS_WORK/sim.log" | head -20
fi

ros_stop_all
if leftovers=$(ros_leftovers); then ok "nothing left running"; else fail "processes left running:"; echo "$leftovers"; fi
if pgrep -f -- "-p $ROS_PORT" > /dev/null || pgrep -f "__master:=.*:$ROS_PORT" > /dev/null; then
  fail "a process on port $ROS_PORT is still running"
fi
finish
