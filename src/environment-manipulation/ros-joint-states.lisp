;;;; With a ROS node running, every container event publishes the environment's joint states on
;;;; kitchen/cram_joint_states (sensor_msgs/JointState, latched), the topic CRAM's belief state uses, so
;;;; that a robot_state_publisher of the kitchen (and rviz) follows the drawers and doors.

(in-package :cram-urdf-environment-manipulation)

(defparameter *environment-joint-state-topic* "kitchen/cram_joint_states"
  "The topic the environment's joint states go to after a container event while a node runs.")

(defun joint-state-publication ()
  "The latched publication of *ENVIRONMENT-JOINT-STATE-TOPIC* in the running node (advertised on
first use; the node's publications are forgotten when it stops)."
  (bt:with-recursive-lock-held (roslisp-utilities::*publish-lock*)
    (or (cdr (assoc *environment-joint-state-topic* roslisp-utilities::*publications* :test #'string=))
        (let ((publication (roslisp:advertise *environment-joint-state-topic* "sensor_msgs/JointState"
                                              :latch t)))
          (push (cons *environment-joint-state-topic* publication) roslisp-utilities::*publications*)
          publication))))

(defun publish-environment-joint-states (environment-name joint-states)
  "Publish JOINT-STATES ((name . value) ...) of ENVIRONMENT-NAME on
*ENVIRONMENT-JOINT-STATE-TOPIC* when a ROS node runs; returns true when published."
  (declare (ignore environment-name))
  (when (roslisp-utilities:ros-running-p)
    (roslisp:publish
     (joint-state-publication)
     (make-instance 'sensor_msgs-msg:JointState
                    :header (make-instance 'std_msgs-msg:Header :stamp (roslisp:ros-time))
                    :name (map 'vector #'car joint-states)
                    :position (map 'vector (lambda (s) (coerce (cdr s) 'double-float)) joint-states)
                    :velocity (make-array 0) :effort (make-array 0)))
    t))

(pushnew 'publish-environment-joint-states *environment-joint-state-hooks*)
