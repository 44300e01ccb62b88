;;;; Tests of COMMON-FAIL:NEXT-DIFFERENT-LOCATION-SOLUTION, CRAM's name in failure handling.

(defpackage :cram-location-solution-tests
  (:use :cl :fiveam))

(in-package :cram-location-solution-tests)

(def-suite location-solutions :in cram-plans-tests:all
  :description "COMMON-FAIL:NEXT-DIFFERENT-LOCATION-SOLUTION.")
(in-suite location-solutions)

(defun pose-at (x)
  (cl-transforms:make-pose (cl-transforms:make-3d-vector x 0 0)
                           (cl-transforms:make-identity-rotation)))

(test next-different-location-solution-skips-close-solutions
  (let* ((d (desig:make-designator :location
                                   `((:poses ,(list (pose-at 0) (pose-at 0.01) (pose-at 0.5))))))
         (next (common-fail:next-different-location-solution d 0.1)))
    (is (< (abs (- 0.5 (cl-transforms:x (cl-transforms:origin (desig:reference next))))) 1d-9))
    (is (null (common-fail:next-different-location-solution next 0.1)) "no further solution"))
  (signals error (common-fail:next-different-location-solution
                  (desig:make-designator :location `((:pose ,(pose-at 0)))) -1))
  (signals error (common-fail:next-different-location-solution 42)))
