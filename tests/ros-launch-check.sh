#!/bin/bash
# Integration check of launch/world.launch and launch/pepper.launch.
#
# Usage: tests/ros-launch-check.sh
#   The model files checked can be overridden with PR2_URDF, KITCHEN_URDF,
#   KITCHEN_MAP, PEPPER_URDF, SHELF_URDF and SHOP_MAP.
#
# Starts a private roscore (own ROS_HOME in a temporary directory, free port on
# 127.0.0.1), then each launch file in turn, and checks:
#   - the description parameters hold exactly the URDF files' text,
#   - /map is latched with the width, height, resolution and origin of the map's
#     YAML and PGM files (read here with ImageMagick's identify), frame map,
#   - every link of each model is in TF, connected to map (kitchen links with the
#     iai_kitchen/ prefix), and the joint states carry the models' movable joints.
# Stops everything it started and verifies that nothing is left; exits non-zero
# on any failure.
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
tools=$root/tools/ros
. "$tools/ros-env.sh"

PR2_URDF=${PR2_URDF:-$root/robots/pr2/pr2.urdf}
KITCHEN_URDF=${KITCHEN_URDF:-$root/resources/iai_kitchen.urdf}
KITCHEN_MAP=${KITCHEN_MAP:-$root/resources/maps/kitchen.yaml}
PEPPER_URDF=${PEPPER_URDF:-$root/robots/pepper/pepper.urdf}
SHELF_URDF=${SHELF_URDF:-$root/resources/dm_shelves.urdf}
SHOP_MAP=${SHOP_MAP:-$root/resources/maps/shop.yaml}

passed=0
failed=0
ok()   { passed=$((passed + 1)); echo "ok   $*"; }
fail() { failed=$((failed + 1)); echo "FAIL $*"; }
check() {   # check DESCRIPTION CMD...
  local what=$1; shift
  local output
  if output=$("$@" 2>&1); then ok "$what"; else fail "$what"; echo "$output" | sed 's/^/     /' | tail -15; fi
}

for f in "$PR2_URDF" "$KITCHEN_URDF" "$KITCHEN_MAP" "$PEPPER_URDF" "$SHELF_URDF" "$SHOP_MAP"; do
  [ -r "$f" ] || { echo "FAIL missing input file $f"; exit 1; }
done

start_time=$SECONDS
ros_private_env
trap 'ros_stop_all' EXIT
trap 'exit 130' INT TERM
ros_start_core || { echo "FAIL roscore did not start"; exit 1; }
ok "roscore on $ROS_MASTER_URI"

param_is_file() {   # param_is_file PARAM FILE
  /usr/bin/python3 - "$1" "$2" <<'EOF'
import sys, rosgraph
param, path = sys.argv[1], sys.argv[2]
value = rosgraph.Master('/ros_launch_check').getParam(param)
text = open(path).read()
if value != text:
    sys.exit('%s: %d characters, %s: %d characters' % (param, len(value), path, len(text)))
EOF
}

map_matches() {   # map_matches YAML: /map's info against the YAML and the PGM it names
  local yaml=$1 image size
  image=$(sed -n 's/^image:[[:space:]]*//p' "$yaml" | tr -d "\"'")
  case $image in /*) ;; *) image=$(dirname "$yaml")/$image ;; esac
  size=$(identify -format '%w %h' "$image") || return 1
  timeout 10 /usr/bin/python3 - "$yaml" $size <<'EOF'
import sys, yaml, rospy
from nav_msgs.msg import OccupancyGrid
spec = yaml.safe_load(open(sys.argv[1]))
width, height = int(sys.argv[2]), int(sys.argv[3])
rospy.init_node('map_check', anonymous=True, disable_signals=True)
grid = rospy.wait_for_message('/map', OccupancyGrid, timeout=8)
info = grid.info
problems = []
if (info.width, info.height) != (width, height):
    problems.append('size %dx%d, image %dx%d' % (info.width, info.height, width, height))
if abs(info.resolution - spec['resolution']) > 1e-6:
    problems.append('resolution %r, yaml %r' % (info.resolution, spec['resolution']))
if abs(info.origin.position.x - spec['origin'][0]) > 1e-9 or abs(info.origin.position.y - spec['origin'][1]) > 1e-9:
    problems.append('origin %r %r, yaml %r' % (info.origin.position.x, info.origin.position.y, spec['origin']))
if len(grid.data) != width * height:
    problems.append('%d cells for %dx%d' % (len(grid.data), width, height))
if grid.header.frame_id != 'map':
    problems.append('frame %r' % grid.header.frame_id)
if not any(v == 100 for v in grid.data) or not any(v == 0 for v in grid.data):
    problems.append('no occupied or no free cell')
if problems:
    sys.exit('; '.join(problems))
print('%dx%d at %g m' % (width, height, info.resolution))
EOF
}

joint_states_match() {   # joint_states_match TOPIC URDF...: names on TOPIC cover each URDF's movable joints
  local topic=$1; shift
  local expected
  expected=$(for u in "$@"; do "$tools/urdf_frames.py" "$u" joints; done | sort -u)
  timeout 10 /usr/bin/python3 - "$topic" "$expected" <<'EOF'
import sys, rospy
from sensor_msgs.msg import JointState
topic, expected = sys.argv[1], set(sys.argv[2].split())
rospy.init_node('joint_state_check', anonymous=True, disable_signals=True)
seen = set()
end = rospy.Time.now() + rospy.Duration(3)
while not expected <= seen and rospy.Time.now() < end:
    seen |= set(rospy.wait_for_message(topic, JointState, timeout=3).name)
missing = sorted(expected - seen)
if missing:
    sys.exit('%s lacks %d joints: %s' % (topic, len(missing), ' '.join(missing[:10])))
EOF
}

tf_has_all() {   # tf_has_all PREFIX URDF: all links of URDF in TF, each connected to map
  local prefix=$1 urdf=$2 args=()
  local link
  while read -r link; do args+=(--chain map "$link"); done < <("$tools/urdf_frames.py" "$urdf" links ${prefix:+--prefix "$prefix"})
  timeout 20 "$tools/tf_frames.py" 2.0 "${args[@]}" | grep MISSING
  [ "${PIPESTATUS[0]}" = 0 ]
}

run_launch() {   # run_launch NAME FILE ARGS...: start roslaunch, wait until its nodes are up
  local name=$1 file=$2; shift 2
  ros_start "$name" roslaunch "$file" "$@"
  if ros_wait_for 30 rostopic info /map; then
    ok "roslaunch $(basename "$file") started"
  else
    fail "roslaunch $(basename "$file") did not publish /map"
    tail -20 "$ROS_WORK/$name.log"
    return 1
  fi
}

stop_launch() {
  local pid_var=ROS_PID_$1
  ros_stop_group "${!pid_var}"
  if ros_group_alive "${!pid_var}"; then fail "$1 still running after SIGINT/SIGTERM/SIGKILL"; else ok "$1 stopped"; fi
  if grep -q -E 'process has died|required node.*has died' "$ROS_WORK/$1.log"; then
    fail "a node of $1 died:"; grep -E 'has died' "$ROS_WORK/$1.log"
  fi
}

# --- world.launch
if run_launch world "$root/launch/world.launch" \
     robot_urdf:="$PR2_URDF" kitchen_urdf:="$KITCHEN_URDF" map:="$KITCHEN_MAP"; then
  check "/robot_description is $(basename "$PR2_URDF")" param_is_file /robot_description "$PR2_URDF"
  check "/kitchen_description is $(basename "$KITCHEN_URDF")" param_is_file /kitchen_description "$KITCHEN_URDF"
  check "/map matches $(basename "$KITCHEN_MAP")" map_matches "$KITCHEN_MAP"
  check "/map_metadata is published" timeout 10 rostopic echo -n 1 /map_metadata/width
  check "TF: map -> iai_kitchen/$("$tools/urdf_frames.py" "$KITCHEN_URDF" root) -> every kitchen link" \
        tf_has_all iai_kitchen "$KITCHEN_URDF"
  check "/kitchen/joint_states carries the kitchen's movable joints" \
        joint_states_match /kitchen/joint_states "$KITCHEN_URDF"
  check "no unprefixed kitchen frames in TF" \
        bash -c "! timeout 20 '$tools/tf_frames.py' 1.0 | grep -q -E ' (room_link|$("$tools/urdf_frames.py" "$KITCHEN_URDF" root))\$'"
  stop_launch world
fi

# --- world.launch with robot_tf:=true (the configuration rviz-screenshot.sh uses)
if run_launch world_robot "$root/launch/world.launch" robot_tf:=true \
     robot_urdf:="$PR2_URDF" kitchen_urdf:="$KITCHEN_URDF" map:="$KITCHEN_MAP"; then
  check "TF: map -> every PR2 link" tf_has_all "" "$PR2_URDF"
  stop_launch world_robot
fi

# --- pepper.launch
if run_launch pepper "$root/launch/pepper.launch" \
     robot_urdf:="$PEPPER_URDF" shelf_urdf:="$SHELF_URDF" map:="$SHOP_MAP"; then
  check "/robot_description is $(basename "$PEPPER_URDF")" param_is_file /robot_description "$PEPPER_URDF"
  check "/shelf_description is $(basename "$SHELF_URDF")" param_is_file /shelf_description "$SHELF_URDF"
  check "/map matches $(basename "$SHOP_MAP")" map_matches "$SHOP_MAP"
  check "TF: map -> every Pepper link" tf_has_all "" "$PEPPER_URDF"
  check "TF: map -> every shelf link" tf_has_all "" "$SHELF_URDF"
  check "/joint_states carries Pepper's and the shelves' movable joints" \
        joint_states_match /joint_states "$PEPPER_URDF" "$SHELF_URDF"
  stop_launch pepper
fi

ros_stop_all
if leftovers=$(ros_leftovers); then
  ok "no processes left"
else
  fail "processes left running:"; echo "$leftovers"
fi
elapsed=$((SECONDS - start_time))
[ "$failed" = 0 ] && rm -rf "$ROS_WORK"
echo "$passed passed, $failed failed (${elapsed} s)"
[ "$failed" = 0 ]
