;;;; Package CRAM-URDF-PROJECTION (nicknames URDF-PROJ, PR2-PROJ): the simulated robot.
;;;; Motions teleport the robot of the Bullet belief state between key poses; the projection
;;;; environment keeps a TF tree of the robot fed from the belief state.

(defpackage :cram-urdf-projection
  (:nicknames :urdf-proj :pr2-proj :cram-pr2-projection)
  (:use :cl)
  (:export
   ;; projection environment
   #:with-simulated-robot #:with-projected-robot #:urdf-bullet-projection-environment
   #:pr2-bullet-projection-environment #:update-tf-from-belief-state #:*ik-random-state*
   #:*ik-random-seed* #:reset-ik-random-state
   ;; process modules
   #:urdf-proj-navigation #:urdf-proj-torso #:urdf-proj-neck #:urdf-proj-perception
   #:urdf-proj-grippers #:urdf-proj-arms #:urdf-proj-noop
   ;; low level (also reachable as URDF-PROJ::NAME, as the tutorials write them)
   #:drive #:move-torso #:look-at #:look-at-pose-stamped #:detect #:gripper-action
   #:move-gripper-joint #:move-tcp #:move-joints #:position-arms
   ;; collision modes and checks
   #:*be-strict-with-collisions* #:robot-collisions #:robot-collides-p #:perform-collision-check #:*grasped-objects*
   #:*grasp-container-links* #:*placed-objects*
   ;; inverse kinematics
   #:arm-ik-chain #:ik-chain #:ik-chain-joint-names #:ik-chain-base-link
   #:ik-chain-tip-link #:solve-ik #:chain-forward-kinematics #:arm-ik
   #:*ik-position-tolerance* #:*ik-rotation-tolerance* #:clear-ik-chain-cache
   ;; perceived objects
   #:get-object-pose-in-base #:get-object-pose-in-map
   ;; robot helpers
   #:robot-object #:arm-joint-names #:end-effector-link #:tool-frame
   #:current-robot-state #:torso-joint #:neck-joints #:camera-frame))
