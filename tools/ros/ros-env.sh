# Shell functions for scripts that start a private ROS master and nodes.
# Source it from bash:  . tools/ros/ros-env.sh
#
#   ros_private_env         Debian's python3 first on PATH, a fresh ROS_HOME in a
#                           temporary directory, a master on a free loopback port
#   ros_start NAME CMD...   start CMD in its own process group, output to $ROS_WORK/NAME.log
#   ros_start_core          roscore on $ROS_MASTER_URI, waits until it answers
#   ros_start_xvfb          Xvfb on a free display, sets DISPLAY
#   ros_stop_all            SIGINT to every group started, then SIGTERM/SIGKILL to stragglers
#   ros_leftovers           prints the processes still alive in those groups; status 1 if any
#
# Every process started through ros_start is recorded in ROS_GROUPS (its pid is its
# process group id), so cleanup never touches processes this script did not start.

ROS_GROUPS=()

ros_private_env() {
  export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
  ROS_WORK=$(mktemp -d "${TMPDIR:-/tmp}/cram-ros.XXXXXX")
  export ROS_HOME=$ROS_WORK/ros_home
  export ROS_LOG_DIR=$ROS_HOME/log
  mkdir -p "$ROS_LOG_DIR"
  local port
  port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
  export ROS_MASTER_URI=http://127.0.0.1:$port ROS_IP=127.0.0.1
  unset ROS_HOSTNAME
  ROS_PORT=$port
}

ros_start() {
  local name=$1; shift
  setsid "$@" > "$ROS_WORK/$name.log" 2>&1 < /dev/null &
  local pid=$!
  ROS_GROUPS+=("$pid")
  eval "ROS_PID_$name=$pid"
}

ros_wait_for() {   # ros_wait_for SECONDS CMD...: poll CMD every 0.2 s until it succeeds
  local limit=$1; shift
  local end=$((SECONDS + limit))
  until "$@" > /dev/null 2>&1; do
    [ $SECONDS -ge $end ] && return 1
    sleep 0.2
  done
}

ros_start_core() {
  ros_start roscore roscore -p "$ROS_PORT"
  if ! ros_wait_for 30 rosparam list; then
    echo "roscore did not answer on $ROS_MASTER_URI within 30 s; log:" >&2
    cat "$ROS_WORK/roscore.log" >&2
    return 1
  fi
}

ros_start_xvfb() {
  local size=${1:-1024x768x24}
  : > "$ROS_WORK/display"
  setsid Xvfb -displayfd 3 -screen 0 "$size" -nolisten tcp 3> "$ROS_WORK/display" \
    > "$ROS_WORK/xvfb.log" 2>&1 < /dev/null &
  ROS_GROUPS+=("$!")
  if ! ros_wait_for 20 test -s "$ROS_WORK/display"; then
    echo "Xvfb did not start; log:" >&2
    cat "$ROS_WORK/xvfb.log" >&2
    return 1
  fi
  export DISPLAY=:$(tr -d '[:space:]' < "$ROS_WORK/display")
}

ros_group_alive() {
  pgrep -g "$1" > /dev/null 2>&1
}

ros_stop_group() {   # ros_stop_group PGID: SIGINT, wait up to 10 s, then SIGTERM, then SIGKILL
  local g=$1 i
  ros_group_alive "$g" || return 0
  kill -INT -- "-$g" 2> /dev/null
  for i in $(seq 50); do ros_group_alive "$g" || return 0; sleep 0.2; done
  kill -TERM -- "-$g" 2> /dev/null
  for i in $(seq 15); do ros_group_alive "$g" || return 0; sleep 0.2; done
  kill -KILL -- "-$g" 2> /dev/null
  sleep 0.2
}

ros_stop_all() {   # stops groups in reverse start order (nodes before the master)
  local k
  for ((k = ${#ROS_GROUPS[@]} - 1; k >= 0; k--)); do
    ros_stop_group "${ROS_GROUPS[k]}"
  done
  wait 2> /dev/null
}

ros_leftovers() {
  local g found=0
  for g in "${ROS_GROUPS[@]}"; do
    if ros_group_alive "$g"; then
      pgrep -a -g "$g"
      found=1
    fi
  done
  return $found
}
