#!/bin/bash
# Take a screenshot of rviz showing one of the launch files' worlds.
#
# Usage: tools/ros/rviz-screenshot.sh [world|pepper] [OUT.png] [roslaunch arg:=value ...]
#   default: world docs/rviz-world.png   (pepper: docs/rviz-pepper.png)
#   RVIZ_WAIT=seconds to let rviz draw before the screenshot (default 15)
#
# Starts its own Xvfb, a private roscore on a free loopback port, the launch file
# with rviz:=true and robot_tf:=true (so the robot is drawn without the Lisp side),
# waits, captures the screen with ImageMagick's import, and stops everything again.
set -u
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
. "$here/ros-env.sh"

which=${1:-world}
case $which in
  world|pepper) ;;
  *) echo "usage: $0 [world|pepper] [OUT.png] [arg:=value ...]" >&2; exit 2 ;;
esac
out=${2:-$root/docs/rviz-$which.png}
shift $(($# >= 2 ? 2 : $#))
wait_s=${RVIZ_WAIT:-15}

ros_private_env
trap 'ros_stop_all' EXIT
trap 'exit 130' INT TERM
mkdir -p "$(dirname "$out")"
ros_start_xvfb 1024x768x24 || exit 1
ros_start_core || exit 1
ros_start launch roslaunch "$root/launch/$which.launch" rviz:=true robot_tf:=true "$@"
if ! ros_wait_for 60 grep -q 'RViz is ready\|rviz-[0-9]*.*started' "$ROS_WORK/launch.log"; then
  echo "roslaunch did not start rviz; log:" >&2
  cat "$ROS_WORK/launch.log" >&2
  exit 1
fi
sleep "$wait_s"
if ! ros_group_alive "$ROS_PID_launch"; then
  echo "roslaunch exited early; log:" >&2
  cat "$ROS_WORK/launch.log" >&2
  exit 1
fi
import -window root "$out" || exit 1
echo "wrote $out"
grep -i -E 'error|exception' "$ROS_WORK/launch.log" | grep -v 'media_export' || true
ros_stop_all
if ! ros_leftovers; then
  echo "processes left running after the screenshot" >&2
  exit 1
fi
rm -rf "$ROS_WORK"
