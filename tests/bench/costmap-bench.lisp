;;;; Location costmap benchmarks: the first solution of a VISIBLE-FOR and of a REACHABLE-FOR
;;;; location designator in the IAI kitchen with a PR2 and a mug on the kitchen island (warm:
;;;; occupancy grids cached, a new designator and costmap per call).

(require :asdf)
(asdf:load-asd (merge-pathnames "../../cram-plans.asd" *load-truename*))
(asdf:load-system "cram-plans/tests/costmap")

(defpackage :cram-bench.costmap
  (:use :cl :cram-bench))

(in-package :cram-bench.costmap)

(defparameter *goal-seconds* 0.010d0 "The goal for one first solution (docs/anchors.md).")

(defun visible-for-mug ()
  (desig:a location (visible-for pr2) (object (desig:an object (type mug) (name mug-1)))))

(defun reachable-for-mug ()
  (desig:a location (reachable-for pr2) (object (desig:an object (type mug) (name mug-1)))))

(defun first-solution-seconds (make-designator)
  (let ((sink nil) (seed 0))
    (time-per-call (lambda ()
                     (costmap:seed-costmaps (incf seed))
                     (setf sink (desig:reference (funcall make-designator))))
                   :min-seconds 0.3d0)))

(defun row (measure ours peer-name peer)
  (add-row measure (format-seconds ours) :peer-name peer-name :peer (format-seconds peer)
                                         :ratio (/ ours peer) :goal "<= 10 ms"
                                         :met (<= ours *goal-seconds*)))

(define-benchmark costmap ()
  (let ((rob-int:*robot-name* :pr2)
        (btr:*current-bullet-world* (cram-costmap-tests::build-kitchen-world)))
    (desig:reference (visible-for-mug))
    (desig:reference (reachable-for-mug))
    (let ((ours (first-solution-seconds #'visible-for-mug))
          (peer (let ((costmap::*line-of-sight-stride* 1))
                  (first-solution-seconds #'visible-for-mug))))
      (row "visible-for location, first solution (kitchen, PR2, mug)" ours
           "same, one line-of-sight ray per cell" peer))
    (let ((ours (first-solution-seconds #'reachable-for-mug))
          (peer (first-solution-seconds (lambda ()
                                          (setf costmap::*occupancy-cache* '())
                                          (reachable-for-mug)))))
      (row "reachable-for location, first solution (kitchen, PR2, mug)" ours
           "same, occupancy rasterised every call" peer))))
