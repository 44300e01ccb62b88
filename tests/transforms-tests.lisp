;;;; Tests of the transforms layer: maths identities, printing, bad input, package API.
;;;; The frame tree and CRAM-TF tests are in transforms-tf-tests.lisp.

(defpackage :cram-plans-tests.transforms
  (:use :cl :fiveam :cl-transforms :cl-transforms-stamped)
  (:export #:transforms))

(in-package :cram-plans-tests.transforms)

(def-suite transforms :in cram-plans-tests:all
  :description "cl-transforms, cl-transforms-stamped, cl-tf and cram-tf.")

(in-suite transforms)

;;; Helpers

(defparameter *tolerance* 1d-9)

(defun random-unit-quaternion (state)
  "A uniformly distributed random rotation drawn from the random STATE."
  ;; Shoemake's method
  (let* ((u1 (random 1d0 state)) (u2 (random (* 2 pi) state)) (u3 (random (* 2 pi) state))
         (a (sqrt (- 1d0 u1))) (b (sqrt u1)))
    (make-quaternion (* a (sin u2)) (* a (cos u2)) (* b (sin u3)) (* b (cos u3)))))

(defun random-vector (state &optional (scale 10d0))
  "A random 3D-VECTOR with coordinates in [-SCALE, SCALE)."
  (flet ((r () (- (random (* 2 scale) state) scale)))
    (make-3d-vector (r) (r) (r))))

(defun random-transform (state)
  "A random TRANSFORM."
  (make-transform (random-vector state) (random-unit-quaternion state)))

(defun transform-error (a b)
  "The larger of the translation distance and the rotation angle between transforms A and B."
  (max (v-dist (translation a) (translation b))
       (angle-between-quaternions (rotation a) (rotation b))))

(defun pose-error (a b)
  "The larger of the origin distance and the orientation angle between poses A and B."
  (max (v-dist (origin a) (origin b))
       (angle-between-quaternions (orientation a) (orientation b))))

(defun error-message (thunk)
  "The report of the error THUNK signals, or NIL when it returns normally."
  (handler-case (progn (funcall thunk) nil)
    (error (e) (princ-to-string e))))

(defmacro max-over-random ((var count seed) &body body)
  "The maximum of BODY (a real) over COUNT runs with VAR bound to a random state seeded by SEED."
  (let ((i (gensym)) (m (gensym)))
    `(let ((,var (sb-ext:seed-random-state ,seed)) (,m 0d0))
       (dotimes (,i ,count ,m)
         (setf ,m (max ,m (progn ,@body)))))))

;;; Construction and coercion

(test construction-coerces-to-double-floats
  (let ((v (make-3d-vector 1 1/2 0.25)))
    (is (typep (x v) 'double-float))
    (is (= 1d0 (x v)))
    (is (= 0.5d0 (y v)))
    (is (= 0.25d0 (z v))))
  ;; single floats keep their decimal value
  (is (= 0.1d0 (x (make-3d-vector 0.1 0 0))))
  (is (= -0.9d0 (y (make-3d-vector 0 -0.9 0))))
  (is (= 0.83d0 (z (make-3d-vector 0 0 0.83))))
  (let ((q (make-quaternion 0 0 0 1)))
    (is (every (lambda (c) (typep c 'double-float)) (list (x q) (y q) (z q) (w q))))
    (is (equal '(0d0 0d0 0d0 1d0) (list (x q) (y q) (z q) (w q))))))

(test quaternions-are-normalised-on-construction
  (let ((q (make-quaternion 0 0 1 1)))
    (is (< (abs (- (z q) (/ (sqrt 2d0) 2))) 1d-15))
    (is (< (abs (- (w q) (/ (sqrt 2d0) 2))) 1d-15))
    (is (is-normalized q)))
  (let ((q (make-quaternion 0 0 0 2)))
    (is (= 1d0 (w q))))
  (is (< (max-over-random (state 1000 11)
           (let* ((c (loop repeat 4 collect (- (random 2d0 state) 1d0)))
                  (q (apply #'make-quaternion c))
                  (n (sqrt (reduce #'+ (mapcar (lambda (a) (* a a)) c)))))
             (max (abs (- (q-dot q q) 1d0))
                  (abs (- (x q) (/ (first c) n)))
                  (abs (- (w q) (/ (fourth c) n))))))
         *tolerance*)))

(test identities-and-copies
  (is (equalp (make-3d-vector 0 0 0) (make-identity-vector)))
  (is (equalp (make-quaternion 0 0 0 1) (make-identity-rotation)))
  (is (equalp (make-pose (make-identity-vector) (make-identity-rotation)) (make-identity-pose)))
  (is (equalp (make-transform (make-identity-vector) (make-identity-rotation))
              (make-identity-transform)))
  (let ((v (make-3d-vector 1 2 3)))
    (is (equalp (make-3d-vector 1 5 3) (copy-3d-vector v :y 5)))
    (is (= 2d0 (y v)) "the original is unchanged"))
  (let* ((p (make-pose (make-3d-vector 1 2 3) (make-identity-rotation)))
         (q (euler->quaternion :az 1))
         (p2 (copy-pose p :orientation q)))
    (is (eq q (orientation p2)))
    (is (equalp (origin p) (origin p2))))
  (let* ((tr (make-transform (make-3d-vector 1 2 3) (make-identity-rotation)))
         (tr2 (copy-transform tr :translation (make-3d-vector 4 5 6))))
    (is (equalp (make-3d-vector 4 5 6) (translation tr2)))
    (is (equalp (rotation tr) (rotation tr2)))))

;;; Printing

(test printing-matches-cram
  (is (string= "#<3D-VECTOR (1.0d0 2.0d0 3.0d0)>"
               (prin1-to-string (make-3d-vector 1 2 3))))
  (is (string= "#<QUATERNION (0.0d0 0.0d0 0.0d0 1.0d0)>"
               (prin1-to-string (make-identity-rotation))))
  (is (string= (format nil "#<POSE ~%   #<3D-VECTOR (1.0d0 2.0d0 3.0d0)>~%   ~
                            #<QUATERNION (0.0d0 0.0d0 0.0d0 1.0d0)>>")
               (prin1-to-string (make-pose (make-3d-vector 1 2 3) (make-identity-rotation)))))
  (is (string= (format nil "#<TRANSFORM ~%   #<3D-VECTOR (1.0d0 0.0d0 0.0d0)>~%   ~
                            #<QUATERNION (0.0d0 0.0d0 0.0d0 1.0d0)>>")
               (prin1-to-string (make-transform (make-3d-vector 1 0 0)
                                                (make-identity-rotation)))))
  (is (string= (format nil "#<POSE-STAMPED ~%   FRAME-ID: \"map\", STAMP: 0.0~%   ~
                            #<3D-VECTOR (-2.0d0 -0.9d0 0.83d0)>~%   ~
                            #<QUATERNION (0.0d0 0.0d0 0.0d0 1.0d0)>>")
               (prin1-to-string (make-pose-stamped "map" 0.0 (make-3d-vector -2 -0.9 0.83)
                                                   (make-identity-rotation)))))
  (is (string= (format nil "#<TRANSFORM-STAMPED ~%   FRAME-ID: \"map\", CHILD-FRAME-ID: ~
                            \"base_footprint\", STAMP: 12.5~%   ~
                            #<3D-VECTOR (0.0d0 0.0d0 0.0d0)>~%   ~
                            #<QUATERNION (0.0d0 0.0d0 0.0d0 1.0d0)>>")
               (prin1-to-string (make-transform-stamped "/map" "base_footprint" 12.5
                                                        (make-identity-vector)
                                                        (make-identity-rotation)))))
  ;; the same whatever the float format the user reads with
  (let ((*read-default-float-format* 'double-float))
    (is (string= "#<3D-VECTOR (1.0d0 2.0d0 3.0d0)>"
                 (prin1-to-string (make-3d-vector 1 2 3)))))
  (is (eq :not-readable
          (handler-case (let ((*print-readably* t)) (prin1-to-string (make-3d-vector 1 2 3)))
            (print-not-readable () :not-readable)))))

;;; Random identities

(test transform-times-inverse-is-identity
  (let ((identity (make-identity-transform)))
    (is (< (max-over-random (state 1000 1)
             (let ((tr (random-transform state)))
               (max (transform-error (transform* tr (transform-inv tr)) identity)
                    (transform-error (transform* (transform-inv tr) tr) identity))))
           *tolerance*))))

(test transform-composition-is-associative
  (is (< (max-over-random (state 1000 2)
           (let ((a (random-transform state)) (b (random-transform state))
                 (c (random-transform state)))
             (max (transform-error (transform* (transform* a b) c)
                                   (transform* a (transform* b c)))
                  (transform-error (transform* a b c) (transform* a (transform* b c))))))
         *tolerance*)))

(test points-round-trip-through-transform-and-inverse
  (is (< (max-over-random (state 1000 3)
           (let ((tr (random-transform state)) (p (random-vector state)))
             (v-dist p (transform-point (transform-inv tr) (transform-point tr p)))))
         *tolerance*)))

(test transform-point-agrees-with-matrix-product
  (is (< (max-over-random (state 1000 4)
           (let* ((tr (random-transform state)) (p (random-vector state))
                  (m (transform->matrix tr))
                  (q (transform-point tr p))
                  (c (list (x p) (y p) (z p) 1d0)))
             (loop for i below 3
                   for expected = (loop for j below 4 sum (* (aref m i j) (nth j c)))
                   maximize (abs (- expected (nth i (list (x q) (y q) (z q))))))))
         *tolerance*))
  ;; rotation matrices are orthonormal
  (is (< (max-over-random (state 200 5)
           (let ((m (quaternion->matrix (random-unit-quaternion state))))
             (loop for i below 3
                   maximize (loop for j below 3
                                  maximize (abs (- (loop for k below 3
                                                         sum (* (aref m k i) (aref m k j)))
                                                   (if (= i j) 1d0 0d0)))))))
         *tolerance*)))

(test composition-matches-applying-in-turn
  (is (< (max-over-random (state 1000 6)
           (let ((a (random-transform state)) (b (random-transform state))
                 (p (random-vector state)))
             (v-dist (transform-point (transform* a b) p)
                     (transform-point a (transform-point b p)))))
         *tolerance*)))

(test rotations-preserve-length-and-compose
  (is (< (max-over-random (state 1000 7)
           (let ((q1 (random-unit-quaternion state)) (q2 (random-unit-quaternion state))
                 (v (random-vector state)))
             (max (abs (- (v-norm v) (v-norm (rotate q1 v))))
                  (v-dist (rotate (q* q1 q2) v) (rotate q1 (rotate q2 v)))
                  (v-dist v (rotate (q-inv q1) (rotate q1 v))))))
         *tolerance*)))

(test euler-round-trips
  ;; angles -> quaternion -> angles, pitch away from the singularity
  (is (< (max-over-random (state 1000 8)
           (let* ((ax (- (random (* 2 pi) state) pi))
                  (ay (- (random 3d0 state) 1.5d0))
                  (az (- (random (* 2 pi) state) pi))
                  (angles (quaternion->euler (euler->quaternion :ax ax :ay ay :az az)
                                             :just-values t)))
             (max (abs (- ax (first angles))) (abs (- ay (second angles)))
                  (abs (- az (third angles))))))
         *tolerance*))
  ;; quaternion -> angles -> quaternion, any rotation
  (is (< (max-over-random (state 1000 9)
           (let ((q (random-unit-quaternion state)))
             (angle-between-quaternions q (apply #'euler->quaternion (quaternion->euler q)))))
         *tolerance*))
  ;; the convention: roll about x, then pitch about y, then yaw about z (fixed axes)
  (is (< (max-over-random (state 200 10)
           (let ((ax (random 3d0 state)) (ay (random 1.5d0 state)) (az (random 3d0 state)))
             (angle-between-quaternions
              (euler->quaternion :ax ax :ay ay :az az)
              (q* (axis-angle->quaternion (make-3d-vector 0 0 1) az)
                  (axis-angle->quaternion (make-3d-vector 0 1 0) ay)
                  (axis-angle->quaternion (make-3d-vector 1 0 0) ax)))))
         *tolerance*))
  (is (< (abs (- 0.7d0 (get-yaw (euler->quaternion :az 0.7d0)))) *tolerance*)))

(test axis-angle-round-trips
  (is (< (max-over-random (state 1000 12)
           (let* ((axis (normalize-vector (random-vector state)))
                  (angle (+ 0.01d0 (random (- (* 2 pi) 0.02d0) state))))
             (multiple-value-bind (axis2 angle2)
                 (quaternion->axis-angle (axis-angle->quaternion axis angle))
               (max (abs (- angle angle2)) (v-dist axis axis2)))))
         *tolerance*))
  ;; a quarter turn about z takes x to y
  (is (< (v-dist (make-3d-vector 0 1 0)
                 (rotate (axis-angle->quaternion (make-3d-vector 0 0 1) (/ pi 2))
                         (make-3d-vector 1 0 0)))
         *tolerance*)))

(test matrix-round-trips
  (is (< (max-over-random (state 1000 13)
           (let ((tr (random-transform state)))
             (max (angle-between-quaternions
                   (rotation tr) (matrix->quaternion (quaternion->matrix (rotation tr))))
                  (transform-error tr (matrix->transform (transform->matrix tr))))))
         *tolerance*)))

(test angles-and-interpolation
  (let ((a (make-identity-rotation)) (b (euler->quaternion :az 1.2d0)))
    (is (< (abs (- 1.2d0 (angle-between-quaternions a b))) *tolerance*))
    (is (< (abs (- 0.6d0 (angle-between-quaternions a (slerp a b 0.5d0)))) *tolerance*))
    ;; q and -q are the same rotation
    (is (< (angle-between-quaternions b (make-quaternion (- (x b)) (- (y b)) (- (z b)) (- (w b))))
           *tolerance*)))
  (is (< (abs (- (- 0.5d0 pi) (normalize-angle (+ pi 0.5d0 (* 4 pi))))) *tolerance*))
  (is (< (abs (- -0.5d0 (normalize-angle (- (* 2 pi) 0.5d0)))) *tolerance*))
  (is (v= (make-3d-vector 2 3 4)
          (interpolate-vector (make-3d-vector 0 1 2) (make-3d-vector 4 5 6) 0.5) 1d-12))
  (is (< (transform-error (transform-diff (make-transform (make-3d-vector 1 0 0) (yaw 0.5))
                                          (make-transform (make-3d-vector 1 1 0) (yaw 0.7)))
                          (make-transform (make-3d-vector (sin 0.5d0) (cos 0.5d0) 0) (yaw 0.2)))
         *tolerance*)))

(test vector-arithmetic
  (let ((a (make-3d-vector 1 2 3)) (b (make-3d-vector -2 0.5 4)))
    (is (equalp (make-3d-vector -1 2.5 7) (v+ a b)))
    (is (equalp (make-3d-vector 3 1.5 -1) (v- a b)))
    (is (equalp (make-3d-vector 2 4 6) (v* a 2)))
    (is (equalp (make-3d-vector 0.5 1 1.5) (v/ a 2)))
    (is (equalp (make-3d-vector -1 -2 -3) (v-inv a)))
    (is (= 11d0 (dot-product a b)))
    (is (equalp (make-3d-vector 6.5 -10 4.5) (cross-product a b)))
    (is (= 0d0 (dot-product a (cross-product a b))))
    (is (< (abs (- (sqrt 14d0) (v-norm a))) 1d-15))
    (is (< (abs (- (v-norm (v- a b)) (v-dist a b))) 1d-15))
    (is (< (abs (- 1d0 (v-norm (normalize-vector b)))) 1d-15))))

(test pose-and-transform-conversions
  (let* ((p (make-pose (make-3d-vector 1 2 3) (euler->quaternion :az 0.3)))
         (tr (pose->transform p)))
    (is (equalp (origin p) (translation tr)))
    (is (equalp p (transform->pose tr)))
    (is (< (pose-error (transform-pose tr (make-identity-pose)) p) *tolerance*))
    (is (< (pose-error (make-2d-pose 1 2 0.3) (make-pose (make-3d-vector 1 2 0)
                                                         (euler->quaternion :az 0.3)))
           *tolerance*))))

;;; Bad input

(test bad-input-names-the-value
  (let ((m (error-message (lambda () (make-3d-vector "abc" 0 0)))))
    (is (search "\"abc\"" m))
    (is (search "real number" m)))
  (is (search "FOO" (error-message (lambda () (make-quaternion 0 0 'foo 1)))))
  (is (search "NIL" (error-message (lambda () (make-3d-vector 1 nil 3)))))
  (let ((m (error-message (lambda () (make-quaternion 0 0 0 0)))))
    (is (search "(0 0 0 0)" m))
    (is (search "non-zero" m)))
  (let ((m (error-message (lambda () (make-quaternion 0.0 0 0 0)))))
    (is (search "(0.0 0 0 0)" m)))
  (is (search "NaN" (error-message (lambda () (make-3d-vector 1 2 (sb-kernel:make-double-float
                                                                   -524288 0))))))
  (is (search "INFINITY" (string-upcase (error-message
                                         (lambda () (make-3d-vector
                                                     sb-ext:double-float-positive-infinity 0 0))))))
  (is (search "(1 2)" (error-message (lambda () (make-pose '(1 2) (make-identity-rotation))))))
  (is (search "(7)" (error-message (lambda () (make-transform (make-identity-vector) (list 7))))))
  (is (search "zero" (error-message (lambda () (axis-angle->quaternion (make-3d-vector 0 0 0) 1)))))
  (is (search "rotation matrix"
              (error-message (lambda () (matrix->quaternion
                                         (make-array '(3 3) :initial-element 1))))))
  (is (search ":W" (error-message (lambda () (euler->quaternion :ax :w)))))
  (is (search "(1 2 3 4)" (error-message (lambda () (x '(1 2 3 4))))))
  (is (search "MAP" (error-message (lambda () (make-pose-stamped 'map 0 (make-identity-vector)
                                                                 (make-identity-rotation))))))
  (is (search "\"later\"" (error-message (lambda () (make-pose-stamped
                                                     "map" "later" (make-identity-vector)
                                                     (make-identity-rotation))))))
  (signals transform-input-error (make-3d-vector 1 2 #c(1 2)))
  (signals transform-input-error (v/ (make-3d-vector 1 2 3) 0)))

;;; Packages

(test package-api
  (is (eq 'cl-tf:make-pose-stamped 'cl-transforms-stamped:make-pose-stamped))
  (is (eq 'cl-tf:make-3d-vector 'cl-transforms:make-3d-vector))
  (is (eq 'cl-tf:lookup-transform 'cl-transforms-stamped:lookup-transform))
  (is (eq 'cl-tf:transformer 'cl-transforms-stamped:transformer))
  (is (eq 'cl-transforms-stamped:make-identity-transform 'cl-transforms:make-identity-transform))
  (is (eq 'cl-tf:tf-connectivity-error 'cl-transforms-stamped:tf-connectivity-error))
  (let ((missing '()))
    (dolist (p '(:cl-transforms :cl-transforms-stamped))
      (do-external-symbols (s p)
        (unless (eq :external (nth-value 1 (find-symbol (symbol-name s) :cl-tf)))
          (push s missing))))
    (is (null missing) "not external in CL-TF: ~s" missing))
  (let ((missing '()))
    (do-external-symbols (s :cl-transforms)
      (unless (eq :external (nth-value 1 (find-symbol (symbol-name s) :cl-transforms-stamped)))
        (push s missing)))
    (is (null missing) "not external in CL-TRANSFORMS-STAMPED: ~s" missing))
  ;; a pose-stamped is a pose and a transform-stamped a transform
  (let ((ps (make-pose-stamped "map" 0 (make-3d-vector 1 2 3) (make-identity-rotation))))
    (is (typep ps 'pose))
    (is (equalp (make-3d-vector 1 2 3) (translation (pose->transform ps))))))

(test every-exported-symbol-is-documented
  (let ((undocumented '()))
    (dolist (p '(:cl-transforms :cl-transforms-stamped :cram-tf))
      (do-external-symbols (s p)
        (unless (or (and (fboundp s) (documentation s 'function))
                    (and (boundp s) (documentation s 'variable))
                    (and (find-class s nil) (documentation s 'type))
                    (documentation s 'type))
          (push s undocumented))))
    (is (null undocumented) "undocumented: ~s" undocumented)))
