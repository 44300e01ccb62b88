;;;; Rotation representations: axis-angle, Euler angles (roll pitch yaw), rotation matrices,
;;;; angles between rotations and spherical interpolation.

(in-package :cl-transforms)

(defun %ensure-vector-like (v place)
  "V as a 3D-VECTOR; a list (x y z) of reals is accepted too."
  (cond ((3d-vector-p v) v)
        ((and (alexandria:proper-list-p v) (= (length v) 3))
         (%make-3d-vector (ensure-double (first v) place) (ensure-double (second v) place)
                          (ensure-double (third v) place)))
        (t (input-error v "a 3D-VECTOR or a list (x y z)" place))))

(defun axis-angle->quaternion (axis angle)
  "The QUATERNION rotating by ANGLE radians about AXIS (a 3D-VECTOR or list (x y z) of any
non-zero length; it is normalised)."
  (let* ((axis (%ensure-vector-like axis "AXIS-ANGLE->QUATERNION axis"))
         (angle (ensure-double angle "AXIS-ANGLE->QUATERNION angle"))
         (n (v-norm axis)))
    (unless (> n 1d-300)
      (input-error axis "a rotation axis of non-zero length" 'axis-angle->quaternion))
    (let ((s (/ (sin (* 0.5d0 angle)) n)))
      (%unit-quaternion (* s (%v-x axis)) (* s (%v-y axis)) (* s (%v-z axis))
                        (cos (* 0.5d0 angle))))))

(defun quaternion->axis-angle (q)
  "The rotation Q as two values: a unit axis (3D-VECTOR) and an angle in [0, 2 pi] radians.
The identity gives the z axis and angle 0."
  (check-type-of q 'quaternion "a QUATERNION" 'quaternion->axis-angle)
  (with-quaternion-components ((x y z w) q)
    (let ((s (sqrt (+ (* x x) (* y y) (* z z)))))
      (if (< s 1d-300)
          (values (%make-3d-vector 0d0 0d0 1d0) 0d0)
          (values (%make-3d-vector (/ x s) (/ y s) (/ z s))
                  (* 2d0 (atan s w)))))))

(defun euler->quaternion (&key (ax 0d0) (ay 0d0) (az 0d0))
  "The QUATERNION of the roll AX, pitch AY and yaw AZ (radians) about the fixed x, y and z axes,
applied in that order (the rotation Rz(az) Ry(ay) Rx(ax))."
  (let* ((hx (* 0.5d0 (ensure-double ax "EULER->QUATERNION :ax")))
         (hy (* 0.5d0 (ensure-double ay "EULER->QUATERNION :ay")))
         (hz (* 0.5d0 (ensure-double az "EULER->QUATERNION :az")))
         (cr (cos hx)) (sr (sin hx))
         (cp (cos hy)) (sp (sin hy))
         (cy (cos hz)) (sy (sin hz)))
    (%unit-quaternion (- (* sr cp cy) (* cr sp sy))
                      (+ (* cr sp cy) (* sr cp sy))
                      (- (* cr cp sy) (* sr sp cy))
                      (+ (* cr cp cy) (* sr sp sy)))))

(defun %euler-angles (q)
  "Roll, pitch and yaw of the QUATERNION Q as three values (the inverse of EULER->QUATERNION)."
  (with-quaternion-components ((x y z w) q)
    (let* ((sinr-cosp (* 2d0 (+ (* w x) (* y z))))
           (cosr-cosp (- 1d0 (* 2d0 (+ (* x x) (* y y)))))
           (sinp (* 2d0 (- (* w y) (* z x))))
           (siny-cosp (* 2d0 (+ (* w z) (* x y))))
           (cosy-cosp (- 1d0 (* 2d0 (+ (* y y) (* z z))))))
      (values (atan sinr-cosp cosr-cosp)
              ;; cos(pitch) from the roll terms keeps full precision near +-pi/2
              (atan sinp (sqrt (+ (* sinr-cosp sinr-cosp) (* cosr-cosp cosr-cosp))))
              (atan siny-cosp cosy-cosp)))))

(defun quaternion->euler (q &key just-values)
  "The Euler angles of Q as the list (:AX roll :AY pitch :AZ yaw), or (roll pitch yaw) when
JUST-VALUES is true, in the convention of EULER->QUATERNION. Pitch lies in [-pi/2, pi/2]."
  (check-type-of q 'quaternion "a QUATERNION" 'quaternion->euler)
  (multiple-value-bind (ax ay az) (%euler-angles q)
    (if just-values
        (list ax ay az)
        (list :ax ax :ay ay :az az))))

(defun get-yaw (q)
  "The yaw (rotation about z, radians in [-pi, pi]) of the QUATERNION Q."
  (check-type-of q 'quaternion "a QUATERNION" 'get-yaw)
  (with-quaternion-components ((x y z w) q)
    (atan (* 2d0 (+ (* w z) (* x y))) (- 1d0 (* 2d0 (+ (* y y) (* z z)))))))

(defun yaw (angle)
  "The QUATERNION rotating by ANGLE radians about the z axis."
  (let ((h (* 0.5d0 (ensure-double angle "YAW angle"))))
    (%unit-quaternion 0d0 0d0 (sin h) (cos h))))

(defun normalize-angle (angle)
  "ANGLE (radians) wrapped into [-pi, pi)."
  (let ((a (ensure-double angle "NORMALIZE-ANGLE angle")))
    (- (mod (+ a pi) (* 2 pi)) pi)))

(defun angle-between-quaternions (q1 q2)
  "The angle in [0, pi] of the smallest rotation taking the orientation Q1 to Q2."
  (check-type-of q1 'quaternion "a QUATERNION" 'angle-between-quaternions)
  (check-type-of q2 'quaternion "a QUATERNION" 'angle-between-quaternions)
  (with-quaternion-components ((ax ay az aw) q1)
    (with-quaternion-components ((bx by bz bw) q2)
      (multiple-value-bind (x y z w) (%q*-components (- ax) (- ay) (- az) aw bx by bz bw)
        (* 2d0 (atan (sqrt (+ (* x x) (* y y) (* z z))) (abs w)))))))

(defun slerp (q1 q2 ratio)
  "Spherical linear interpolation along the shorter arc: Q1 at RATIO 0, Q2 at RATIO 1."
  (check-type-of q1 'quaternion "a QUATERNION" 'slerp)
  (check-type-of q2 'quaternion "a QUATERNION" 'slerp)
  (let* ((r (ensure-double ratio "SLERP ratio"))
         (d (q-dot q1 q2))
         (sign (if (minusp d) -1d0 1d0))
         (d (abs d)))
    (multiple-value-bind (s1 s2)
        (if (> d 0.9999999d0)
            (values (- 1d0 r) (* sign r))
            (let* ((theta (acos (min 1d0 d)))
                   (st (sin theta)))
              (values (/ (sin (* (- 1d0 r) theta)) st)
                      (* sign (/ (sin (* r theta)) st)))))
      (%unit-quaternion (+ (* s1 (%q-x q1)) (* s2 (%q-x q2)))
                        (+ (* s1 (%q-y q1)) (* s2 (%q-y q2)))
                        (+ (* s1 (%q-z q1)) (* s2 (%q-z q2)))
                        (+ (* s1 (%q-w q1)) (* s2 (%q-w q2)))))))

;;; Rotation matrices

(defun %fill-rotation-matrix (q matrix)
  "Write the rotation matrix of the QUATERNION Q into the upper-left 3x3 block of MATRIX."
  (with-quaternion-components ((x y z w) q)
    (let ((xx (* x x)) (yy (* y y)) (zz (* z z))
          (xy (* x y)) (xz (* x z)) (yz (* y z))
          (wx (* w x)) (wy (* w y)) (wz (* w z)))
      (setf (aref matrix 0 0) (- 1d0 (* 2d0 (+ yy zz)))
            (aref matrix 0 1) (* 2d0 (- xy wz))
            (aref matrix 0 2) (* 2d0 (+ xz wy))
            (aref matrix 1 0) (* 2d0 (+ xy wz))
            (aref matrix 1 1) (- 1d0 (* 2d0 (+ xx zz)))
            (aref matrix 1 2) (* 2d0 (- yz wx))
            (aref matrix 2 0) (* 2d0 (- xz wy))
            (aref matrix 2 1) (* 2d0 (+ yz wx))
            (aref matrix 2 2) (- 1d0 (* 2d0 (+ xx yy))))
      matrix)))

(defun quaternion->matrix (q)
  "The 3x3 rotation matrix (a double-float array) of the QUATERNION Q."
  (check-type-of q 'quaternion "a QUATERNION" 'quaternion->matrix)
  (%fill-rotation-matrix q (make-array '(3 3) :element-type 'double-float)))

(defun %matrix-entries (matrix place)
  "The upper-left 3x3 block of MATRIX (a 2D array of reals, at least 3x3) as a 3x3 double array."
  (unless (and (arrayp matrix) (= (array-rank matrix) 2)
               (>= (array-dimension matrix 0) 3) (>= (array-dimension matrix 1) 3))
    (input-error matrix "a 2D array of at least 3x3 reals" place))
  (let ((m (make-array '(3 3) :element-type 'double-float)))
    (dotimes (i 3 m)
      (dotimes (j 3)
        (setf (aref m i j) (ensure-double (aref matrix i j) place))))))

(defun %check-rotation-matrix (m original place)
  "Signal TRANSFORM-INPUT-ERROR naming ORIGINAL unless the 3x3 double array M is a rotation
(orthonormal columns within 1e-4 and a positive determinant)."
  (flet ((col-dot (i j) (+ (* (aref m 0 i) (aref m 0 j)) (* (aref m 1 i) (aref m 1 j))
                           (* (aref m 2 i) (aref m 2 j)))))
    (let ((det (- (+ (* (aref m 0 0) (aref m 1 1) (aref m 2 2))
                     (* (aref m 0 1) (aref m 1 2) (aref m 2 0))
                     (* (aref m 0 2) (aref m 1 0) (aref m 2 1)))
                  (* (aref m 0 2) (aref m 1 1) (aref m 2 0))
                  (* (aref m 0 1) (aref m 1 0) (aref m 2 2))
                  (* (aref m 0 0) (aref m 1 2) (aref m 2 1)))))
      (unless (and (> det 0d0)
                   (loop for i below 3
                         always (loop for j from i below 3
                                      always (< (abs (- (col-dot i j) (if (= i j) 1d0 0d0)))
                                                1d-4))))
        (input-error original "a rotation matrix (orthonormal, determinant +1)" place)))))

(defun matrix->quaternion (matrix)
  "The QUATERNION of the rotation in the upper-left 3x3 block of MATRIX (a 2D array of reals).
A block that is not a rotation signals TRANSFORM-INPUT-ERROR."
  (let ((m (%matrix-entries matrix 'matrix->quaternion)))
    (%check-rotation-matrix m matrix 'matrix->quaternion)
    (let ((m00 (aref m 0 0)) (m11 (aref m 1 1)) (m22 (aref m 2 2)))
      (let ((trace (+ m00 m11 m22)))
        ;; pick the largest of w, x, y, z as pivot for numerical stability
        (cond ((> trace (max m00 m11 m22))
               (let ((s (* 2d0 (sqrt (+ 1d0 trace)))))
                 (%unit-quaternion (/ (- (aref m 2 1) (aref m 1 2)) s)
                                   (/ (- (aref m 0 2) (aref m 2 0)) s)
                                   (/ (- (aref m 1 0) (aref m 0 1)) s)
                                   (* 0.25d0 s))))
              ((and (>= m00 m11) (>= m00 m22))
               (let ((s (* 2d0 (sqrt (max 1d-300 (- (+ 1d0 m00) m11 m22))))))
                 (%unit-quaternion (* 0.25d0 s)
                                   (/ (+ (aref m 0 1) (aref m 1 0)) s)
                                   (/ (+ (aref m 0 2) (aref m 2 0)) s)
                                   (/ (- (aref m 2 1) (aref m 1 2)) s))))
              ((>= m11 m22)
               (let ((s (* 2d0 (sqrt (max 1d-300 (- (+ 1d0 m11) m00 m22))))))
                 (%unit-quaternion (/ (+ (aref m 0 1) (aref m 1 0)) s)
                                   (* 0.25d0 s)
                                   (/ (+ (aref m 1 2) (aref m 2 1)) s)
                                   (/ (- (aref m 0 2) (aref m 2 0)) s))))
              (t
               (let ((s (* 2d0 (sqrt (max 1d-300 (- (+ 1d0 m22) m00 m11))))))
                 (%unit-quaternion (/ (+ (aref m 0 2) (aref m 2 0)) s)
                                   (/ (+ (aref m 1 2) (aref m 2 1)) s)
                                   (* 0.25d0 s)
                                   (/ (- (aref m 1 0) (aref m 0 1)) s)))))))))

;;; Quaternion arithmetic of cl-transforms' API. A real r stands for the quaternion (0 0 0 r), as
;;; in cl-transforms. QUATERNIONs of this library are rotations, always of unit length, so sums
;;; and differences come back normalised: (q+ a b) is the rotation half-way between A and B when
;;; they are close, (q- q) the same rotation as Q.

(defun %quaternion-components (q place)
  "The components of Q (a QUATERNION, a real r as (0 0 0 r), or a list (x y z w) of reals) as
four double-float values."
  (cond ((quaternion-p q) (values (%q-x q) (%q-y q) (%q-z q) (%q-w q)))
        ((realp q) (values 0d0 0d0 0d0 (ensure-double q place)))
        ((and (alexandria:proper-list-p q) (= (length q) 4))
         (values (ensure-double (first q) place) (ensure-double (second q) place)
                 (ensure-double (third q) place) (ensure-double (fourth q) place)))
        (t (input-error q "a QUATERNION, a real or a list (x y z w)" place))))

(defun q-norm (q)
  "The Euclidean norm of Q's four components: 1 for every QUATERNION of this library, |r| for a
real r, the length of a list (x y z w)."
  (multiple-value-bind (x y z w) (%quaternion-components q 'q-norm)
    (sqrt (+ (* x x) (* y y) (* z z) (* w w)))))

(defun %q-combine (function place quaternions)
  "The QUATERNION (normalised) of FUNCTION folded over the components of QUATERNIONS."
  (let ((sum (list 0d0 0d0 0d0 0d0)) (first t))
    (dolist (q quaternions)
      (let ((components (multiple-value-list (%quaternion-components q place))))
        (setf sum (if first components (mapcar function sum components))
              first nil)))
    (destructuring-bind (x y z w) sum
      (unless (> (+ (* x x) (* y y) (* z z) (* w w)) 1d-24)
        (input-error quaternions "quaternions whose combination is not zero" place))
      (apply #'make-quaternion sum))))

(defun q+ (&rest quaternions)
  "The component-wise sum of QUATERNIONS (QUATERNIONs, reals as (0 0 0 r), or lists (x y z w)),
normalised to a rotation; (q+) is the identity. A sum of zero (e.g. Q and -Q) is an error."
  (if (null quaternions)
      (make-identity-rotation)
      (%q-combine #'+ 'q+ quaternions)))

(defun q- (q &rest quaternions)
  "Q minus each of QUATERNIONS component-wise, normalised to a rotation; (q- q) negates Q's
components, which is the same rotation. A difference of zero is an error."
  (if (null quaternions)
      (multiple-value-bind (x y z w) (%quaternion-components q 'q-)
        (make-quaternion (- x) (- y) (- z) (- w)))
      (%q-combine #'- 'q- (cons q quaternions))))

(defun ensure-rotation (rotation place)
  "ROTATION as a QUATERNION: a QUATERNION as it is, a real r as the rotation of (0 0 0 r) (the
identity for r > 0), a list (x y z w) normalised."
  (if (quaternion-p rotation)
      rotation
      (multiple-value-bind (x y z w) (%quaternion-components rotation place)
        (make-quaternion x y z w))))
