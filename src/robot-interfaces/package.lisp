;;;; Package CRAM-ROBOT-INTERFACES (nickname ROB-INT): the predicates every robot
;;;; description extends, and the notion of the current robot.

(defpackage :cram-robot-interfaces
  (:nicknames :rob-int)
  (:use :cl :cram-prolog)
  (:export
   ;; the current robot
   #:*robot-name* #:*robot-urdf* #:current-robot-name #:set-robot-name
   #:*robot-description-parameter* #:*environment-urdf* #:*environment-name-function*
   #:get-environment-name #:get-robot-name
   #:visibility-designator #:reachability-designator
   #:visibility-designator-p #:reachability-designator-p
   #:urdf-name->robot-name #:described-robot-names
   #:robot-interface-error
   ;; Lisp helpers over the facts
   #:get-arm-joints #:get-arm-links #:get-robot-joint-states
   ;; whole robot
   #:robot #:robot-base-frame #:robot-base-link #:robot-odom-frame
   #:robot-torso-link-joint #:robot-joint-states
   ;; arms and grippers
   #:arm #:arm-joints #:arm-links #:end-effector-link #:robot-tool-frame
   #:gripper-joint #:gripper-link #:gripper-meter-to-joint-multiplier
   #:standard-to-particular-gripper-transform #:tcp-in-ee-pose
   #:hand-links #:hand-link #:hand-finger-link
   ;; neck and cameras
   #:robot-neck-links #:robot-neck-joints #:robot-neck-base-link
   #:robot-neck-pan-joint-forward-facing-axis-sign
   #:robot-neck-tilt-joint-forward-facing-axis-sign
   #:camera-frame #:camera-minimal-height #:camera-maximal-height
   #:camera-horizontal-angle #:camera-vertical-angle #:camera-in-neck-ee-pose))
