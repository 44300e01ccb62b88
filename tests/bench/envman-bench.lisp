;;;; Environment manipulation: opening and closing a kitchen drawer in projection (the robot
;;;; standing in front of it, warm), against the same robot moving its arm through the same
;;;; tool poses without the environment layer (the plain arm motions of the trajectory).

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

(defun arm-motions (poses)
  "The right arm through POSES (the opening and the closing trajectories), parked after each."
  (let ((?poses poses))
    (urdf-proj:with-simulated-robot
      (exe:perform (desig:an action (type reaching) (right-poses ?poses) (collision-mode :allow-hand)))
      (exe:perform (desig:an action (type parking-arms) (arms (:right)))))))

(defun trajectory-poses ()
  "The tool poses of opening the drawer by 0.3 m and closing it again, as the plans move through them."
  (let* ((container (env-man:find-container :sink-area-left-upper-drawer-main :iai-kitchen))
         (segments (env-man:container-trajectory container :open :front 0.3d0)))
    (loop for segment in segments append (man-int:traj-segment-poses segment))))

(define-benchmark envman ()
  (let ((cpl:*log-level* :warn))
    (handler-bind ((warning #'muffle-warning))
      (btw-tut:init-projection)
      ;; the first run drives in front of the drawer; the measured ones start there
      (open-and-close)
      (let* ((ours (time-per-call #'open-and-close :min-seconds 0.3d0))
             (poses (trajectory-poses))
             (peer (time-per-call (lambda () (arm-motions poses)) :min-seconds 0.3d0)))
        (unless (< (btr:joint-state (btr:get-environment-object) "sink_area_left_upper_drawer_main_joint")
                   1d-4)
          (error "The drawer did not close again."))
        (add-row "open + close a drawer (projection, warm; PR2 in front of the sink's upper drawer, 0.3 m)"
                 (format-seconds ours)
                 :peer-name "the same arm motions without ENV-MAN (reach, grasp, pull, retract, park)"
                 :peer (format-seconds peer) :ratio (/ ours peer) :goal "<= 5 ms"
                 :met (<= ours *goal-seconds*))))))
