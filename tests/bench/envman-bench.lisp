;;;; Environment manipulation: opening and closing a kitchen drawer in projection (the robot
;;;; standing in front of it, warm), against the same robot performing the same motions directly
;;;; (looking, grippers, the tool poses of both trajectories, parking) without the environment
;;;; layer: the ratio is what grounding, reachability, events and goals add.

(require :asdf)
(asdf:load-asd (merge-pathnames "../../cram-plans.asd" *load-truename*))
(asdf:load-system "cram-plans/tests/environment-manipulation")

(defpackage :cram-bench.envman
  (:use :cl :cram-bench))

(in-package :cram-bench.envman)

(defparameter *goal-seconds* 0.005d0 "The goal for one opening and closing of a drawer.")

(defun drawer ()
  (desig:make-designator :object '((:type :drawer) (:urdf-name :sink-area-left-upper-drawer-main)
                                   (:part-of :iai-kitchen))))

(defun open-and-close ()
  (let ((?drawer (drawer)))
    (urdf-proj:with-simulated-robot
      (exe:perform (desig:an action (type opening) (arm right) (object ?drawer) (distance 0.3)))
      (exe:perform (desig:an action (type closing) (arm right) (object ?drawer))))))

(defun same-motions (segments-of-open segments-of-close look-pose width)
  "The motions the plans perform for opening and closing, performed directly: look at the
handle, open the gripper, reach, grasp, grip, pull or push, release, retract, park."
  (let ((?look look-pose) (?width width))
    (urdf-proj:with-simulated-robot
      (dolist (segments (list segments-of-open segments-of-close))
        (exe:perform (desig:an action (type looking) (target (desig:a location (pose ?look)))))
        (exe:perform (desig:an action (type setting-gripper) (gripper right) (position 0.06)))
        (loop for segment in segments
              for ?poses = (mapcar (lambda (p) (cl-transforms-stamped:pose->pose-stamped "map" 0d0 p))
                                   (man-int:traj-segment-poses segment))
              for i from 0
              do (exe:perform (desig:an action (type reaching) (right-poses ?poses)
                                        (collision-mode :allow-hand)))
                 (case i
                   (1 (exe:perform (desig:an action (type setting-gripper) (gripper right) (position ?width))))
                   (2 (exe:perform (desig:an action (type releasing) (gripper right))))))
        (exe:perform (desig:an action (type parking-arms) (arms (:right))))))))

(defun trajectories ()
  "The trajectory segments of opening the drawer by 0.3 m, and of closing it from there."
  (let* ((kitchen (btr:get-environment-object))
         (joint "sink_area_left_upper_drawer_main_joint")
         (container (env-man:find-container :sink-area-left-upper-drawer-main :iai-kitchen))
         (open (env-man:container-trajectory container :open :front 0.3d0)))
    (btr:set-robot-state-from-joints `((,joint 0.3d0)) kitchen)
    (prog1 (values open (env-man:container-trajectory container :close :front 0.3d0))
      (btr:set-robot-state-from-joints `((,joint 0d0)) kitchen))))

(define-benchmark envman ()
  (let ((cpl:*log-level* :warn))
    (handler-bind ((warning #'muffle-warning))
      (btw-tut:init-projection)
      ;; the first run drives in front of the drawer; the measured ones start there
      (open-and-close)
      (let* ((ours (time-per-call #'open-and-close :min-seconds 0.3d0))
             (look (cl-transforms-stamped:pose->pose-stamped
                    "map" 0d0 (btr:link-pose (btr:get-environment-object) "sink_area_left_upper_drawer_handle")))
             (peer (multiple-value-bind (open close) (trajectories)
                     (time-per-call (lambda () (same-motions open close look 0.0157d0)) :min-seconds 0.3d0))))
        (unless (< (btr:joint-state (btr:get-environment-object) "sink_area_left_upper_drawer_main_joint")
                   1d-4)
          (error "The drawer did not close again."))
        (add-row "open + close a drawer (projection, warm; PR2 in front of the sink's upper drawer, 0.3 m)"
                 (format-seconds ours)
                 :peer-name "the same motions performed directly, without ENV-MAN (look, grippers, reach, grasp, pull, push, retract, park)"
                 :peer (format-seconds peer) :ratio (/ ours peer) :goal "<= 5 ms"
                 :met (<= ours *goal-seconds*))))))
