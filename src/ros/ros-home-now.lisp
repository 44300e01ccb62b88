;;;; Loaded before roslisp (system roslisp-utilities/ros-home): make the ROS home directory.

(in-package :roslisp-utilities)

(ensure-ros-home)
