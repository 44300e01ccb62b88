;;;; Tests of CRAM-MATH: matrices, determinant and inverse, the Gaussian, sampling, polygons.

(defpackage :cram-math-tests
  (:use :cl :fiveam))

(in-package :cram-math-tests)

(def-suite cram-math :in cram-plans-tests:all
  :description "CRAM-MATH (CMA): matrices, sampling, the Gaussian, polygons.")
(in-suite cram-math)

(defun near (a b &optional (tolerance 1d-9)) (< (abs (- a b)) tolerance))

(test matrices-have-width-and-height
  (let ((m (cma:make-double-matrix 3 2 :initial-contents '((1 2 3) (4 5 6)))))
    (is (typep m 'cma:double-matrix))
    (is (= 3 (cma:width m)))
    (is (= 2 (cma:height m)))
    (is (= 6d0 (cma:mref m 1 2)))
    (setf (cma:mref m 0 0) 7)
    (is (= 7d0 (aref m 0 0)))
    (is (= 4 (cma:double-vector-size (cma:make-double-vector 4))))
    (is (equalp #2A((1d0 4d0) (2d0 5d0) (3d0 6d0))
                (cma:double-matrix-transpose (cma:make-double-matrix 3 2 :initial-contents
                                                                     '((1 2 3) (4 5 6))))))
    (signals error (cma:make-double-matrix 0 2))
    (signals error (cma:make-double-matrix 2 2 :initial-contents '(1 2 3)))
    (signals error (cma:double-vector-size m))
    (signals error (cma:width '(1 2)))))

(test matrix-arithmetic
  (let ((a (cma:make-double-matrix 2 2 :initial-contents '((1 2) (3 4))))
        (b (cma:make-double-matrix 2 2 :initial-contents '((5 6) (7 8)))))
    (is (equalp #2A((6d0 8d0) (10d0 12d0)) (cma:m+ a b)))
    (is (equalp #2A((5d0 12d0) (21d0 32d0)) (cma:m* a b)) "element-wise")
    (is (equalp #2A((19d0 22d0) (43d0 50d0)) (cma:double-matrix-product a b)))
    (is (equalp #2A((2d0 4d0) (6d0 8d0)) (cma:m.* a 2)))
    (is (equalp #2A((0d0 1d0) (2d0 3d0)) (cma:m.- a 1)))
    (is (equalp #2A((1d0 4d0) (9d0 16d0)) (cma:map-double-matrix (lambda (x) (* x x)) a)))
    (signals error (cma:m+ a (cma:make-double-matrix 3 2)))
    (signals error (cma:double-matrix-product a (cma:make-double-matrix 2 3)))
    (signals error (cma:m.+ a "1"))))

(test determinant-and-inverse
  (let ((a (cma:make-double-matrix 3 3 :initial-contents '((2 0 1) (1 3 2) (1 1 2)))))
    (is (near 6 (cma:determinant a)))
    (multiple-value-bind (inverse det) (cma:invert-matrix a)
      (is (near 6 det))
      (let ((identity (cma:double-matrix-product a inverse)))
        (dotimes (r 3) (dotimes (c 3) (is (near (if (= r c) 1 0) (aref identity r c)))))))
    (is (= 0 (cma:determinant (cma:make-double-matrix 2 2 :initial-contents '((1 2) (2 4))))))
    (signals error (cma:invert-matrix (cma:make-double-matrix 2 2 :initial-contents '((1 2) (2 4)))))
    (signals error (cma:determinant (cma:make-double-matrix 3 2)))))

(test gauss-is-the-normal-density
  (let* ((cov (cma:make-double-matrix 2 2 :initial-contents '((1 0) (0 4))))
         (mean (cma:make-double-vector 2 :initial-contents '(1 2)))
         (f (cma:gauss cov mean)))
    (is (near (/ 1 (* 2 pi 2)) (funcall f mean)))
    (is (near (* (/ 1 (* 2 pi 2)) (exp -0.5)) (funcall f (cma:make-double-vector 2 :initial-contents '(2 2)))))
    (signals error (funcall f (cma:make-double-vector 3)))
    (signals error (cma:gauss (cma:make-double-matrix 2 2 :initial-contents '((1 2) (2 1))) mean))))

(test sampling-from-a-distribution-matrix
  (let ((m (cma:make-double-matrix 3 3)))
    (setf (aref m 2 1) 1d0)
    (is (every (lambda (cell) (equal '(1 2) cell))
               (loop repeat 50 collect (cma:sample-from-distribution-matrix m)))))
  (let ((m (cma:make-double-matrix 2 1 :initial-contents '((0.25 0.75)))))
    (cma:seed-sampling 4)
    (let ((ones (loop repeat 4000 count (equal '(1 0) (cma:sample-from-distribution-matrix m)))))
      (is (< 2850 ones 3150) "about 3/4 of the samples in the heavier cell: ~d" ones)))
  (signals cma:invalid-probability-distribution
    (cma:sample-from-distribution-matrix (cma:make-double-matrix 2 2))))

(test sampling-is-seeded
  (flet ((draws () (cma:seed-sampling 9)
           (loop repeat 20 collect (cma:sample-discrete '((a . 0.2) (b . 0.5) (c . 0.3))))))
    (is (equal (draws) (draws))))
  (cma:seed-sampling 2)
  (let ((draws (loop repeat 3000 collect (cma:sample-discrete '((a . 0.1) (b . 0.9))))))
    (is (< 2500 (count 'b draws))))
  (is (= 3 (cma:sample (lambda (u) (declare (ignore u)) 3) (constantly 1))))
  (signals error (cma:sample (constantly 1) (constantly 0) 10))
  (signals cma:invalid-probability-distribution (cma:sample-discrete '((a . 0))))
  (signals error (cma:sample-discrete '((a . 2)))))

(test points-in-polygons
  (flet ((p (x y) (make-instance 'cma:2d-point :x x :y y)))
    (let ((square (make-instance 'cma:polygon :vertices (list (p 0 0) (p 2 0) (p 2 2) (p 0 2))))
          (ell (make-instance 'cma:polygon :vertices (list (p 0 0) (p 3 0) (p 3 1) (p 1 1) (p 1 3) (p 0 3)))))
      (is-true (cma:point-in-polygon (p 1 1) square))
      (is-false (cma:point-in-polygon (p 3 1) square))
      (is-true (cma:point-in-polygon (p 0.5 2.5) ell))
      (is-false (cma:point-in-polygon (p 2 2) ell) "the notch of the L")
      (signals error (make-instance 'cma:polygon :vertices (list (p 0 0) (p 1 1))))
      (signals error (cma:point-in-polygon '(1 1) square))))
  (is (near pi (cma:degrees->radians 180)))
  (is (near 90 (cma:radians->degrees (/ pi 2)))))
