;;;; Tests of cl-transforms' quaternion arithmetic (Q+, Q-, Q-NORM) and of reals as rotations.

(defpackage :cram-transforms-quaternion-tests
  (:use :cl :fiveam))

(in-package :cram-transforms-quaternion-tests)

(def-suite transforms-quaternions :in cram-plans-tests:all
  :description "Q+, Q-, Q-NORM and MAKE-TRANSFORM with a real rotation.")
(in-suite transforms-quaternions)

(defun near (a b &optional (tolerance 1d-9))
  (< (abs (- a b)) tolerance))

(test q-norm-of-quaternions-reals-and-lists
  (is (near 1 (cl-transforms:q-norm (cl-transforms:axis-angle->quaternion '(0 0 1) 0.7))))
  (is (near 2 (cl-transforms:q-norm -2)))
  (is (near 5 (cl-transforms:q-norm '(0 3 0 4))))
  (signals cl-transforms:transform-input-error (cl-transforms:q-norm "q"))
  (signals cl-transforms:transform-input-error (cl-transforms:q-norm '(1 2 3))))

(test q+-is-the-normalised-sum
  (let* ((a (cl-transforms:yaw 0.0))
         (b (cl-transforms:yaw 1.0))
         (sum (cl-transforms:q+ a b)))
    (is (typep sum 'cl-transforms:quaternion))
    (is (near 1 (cl-transforms:q-norm sum)))
    (is (near 0.5 (cl-transforms:get-yaw sum)) "half-way between two yaws"))
  (is (cl-transforms:q= (cl-transforms:make-identity-rotation) (cl-transforms:q+)))
  (is (cl-transforms:q= (cl-transforms:make-identity-rotation) (cl-transforms:q+ 1 2)))
  (let ((q (cl-transforms:yaw 0.3)))
    (signals cl-transforms:transform-input-error (cl-transforms:q+ q (cl-transforms:q- q)))))

(test q--subtracts-and-negates
  (let ((q (cl-transforms:yaw 0.4)))
    (is (cl-transforms:q= q (cl-transforms:q- q)) "-q is the same rotation")
    (is (near (- (cl-transforms:w q)) (cl-transforms:w (cl-transforms:q- q)))))
  (let ((d (cl-transforms:q- '(0 0 1 1) '(0 0 0 1))))
    (is (near 1 (cl-transforms:z d)))
    (is (near 0 (cl-transforms:w d))))
  (signals cl-transforms:transform-input-error
    (cl-transforms:q- (cl-transforms:yaw 0.2) (cl-transforms:yaw 0.2))))

(test make-transform-with-a-real-rotation
  (let ((tf (cl-transforms:make-transform (cl-transforms:make-3d-vector 1 2 3) 1)))
    (is (cl-transforms:q= (cl-transforms:make-identity-rotation) (cl-transforms:rotation tf)))
    (is (near 2 (cl-transforms:y (cl-transforms:transform-point
                                  tf (cl-transforms:make-3d-vector 0 0 0))))))
  (signals cl-transforms:transform-input-error
    (cl-transforms:make-transform (cl-transforms:make-3d-vector 0 0 0) 0))
  (signals cl-transforms:transform-input-error
    (cl-transforms:make-transform (cl-transforms:make-3d-vector 0 0 0) "identity")))

(test angle-around-map-z-is-a-yaw
  (let ((q (cram-tf:angle-around-map-z (/ pi 3))))
    (is (near (/ pi 3) (cl-transforms:get-yaw q)))
    (is (near 0 (cl-transforms:x q)))
    (is (cl-transforms:q= (cl-transforms:make-identity-rotation) (cram-tf:angle-around-map-z 0))))
  (signals cl-transforms:transform-input-error (cram-tf:angle-around-map-z "north")))
