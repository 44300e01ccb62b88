#!/usr/bin/python3
"""A user's own gripper behind an actionlib action server, for the example process module of
the README ("Your own robot: actionlib"). The action is actionlib/TestAction (Debian ships its
messages for Python and Lisp): the goal is the opening to reach in millimetres (0 to 90), each
feedback the current opening, the result the opening reached. The gripper moves 10 mm per
step (every 0.1 s); a goal outside 0..90 is aborted, a cancelled goal is preempted where the
gripper stands.

  tools/ros/gripper_action_server.py [__name:=my_gripper] [_action:=/my_gripper/command]
"""
import rospy
import actionlib
from actionlib.msg import TestAction, TestFeedback, TestResult

STEP_MM = 10
STEP_S = 0.1


class Gripper:
    def __init__(self, name):
        self.opening = 0
        self.goals = 0
        self.server = actionlib.SimpleActionServer(name, TestAction, self.execute, auto_start=False)
        self.server.start()

    def execute(self, goal):
        self.goals += 1
        rospy.set_param("~goals", self.goals)
        target = goal.goal
        if not 0 <= target <= 90:
            self.server.set_aborted(TestResult(result=self.opening),
                                    "opening %d mm is outside 0..90" % target)
            return
        while self.opening != target:
            if self.server.is_preempt_requested():
                self.server.set_preempted(TestResult(result=self.opening), "cancelled")
                return
            delta = max(-STEP_MM, min(STEP_MM, target - self.opening))
            self.opening += delta
            self.server.publish_feedback(TestFeedback(feedback=self.opening))
            rospy.sleep(STEP_S)
        rospy.set_param("~opening", self.opening)
        self.server.set_succeeded(TestResult(result=self.opening), "reached %d mm" % target)


if __name__ == "__main__":
    rospy.init_node("my_gripper")
    Gripper(rospy.get_param("~action", "/my_gripper/command"))
    rospy.spin()
