;;;; Poses and rigid transforms, their composition, inversion and matrices.

(in-package :cl-transforms)

(declaim (inline %make-pose %make-transform %make-raw-transform))

(defstruct (pose (:constructor %make-pose (origin orientation))
                 (:conc-name nil)
                 (:copier nil))
  "A position (ORIGIN, a 3D-VECTOR) and an ORIENTATION (a unit QUATERNION); immutable."
  (origin +zero-vector+ :type 3d-vector :read-only t)
  (orientation +identity-quaternion+ :type quaternion :read-only t))

(setf (documentation 'origin 'function) "The position (a 3D-VECTOR) of a POSE."
      (documentation 'orientation 'function) "The orientation (a QUATERNION) of a POSE.")

(defstruct (transform (:constructor %make-raw-transform (tx ty tz qx qy qz qw))
                      (:constructor %make-transform
                          (translation rotation
                           &aux (tx (%v-x translation)) (ty (%v-y translation))
                                (tz (%v-z translation)) (qx (%q-x rotation))
                                (qy (%q-y rotation)) (qz (%q-z rotation)) (qw (%q-w rotation))))
                      (:conc-name %tr-)
                      (:copier nil))
  "A rigid transform: first ROTATION (a unit QUATERNION), then TRANSLATION (a 3D-VECTOR).
Applied to a point p it gives rotation(p) + translation; immutable. The components are stored
inline, so that composing transforms allocates one object."
  (tx 0d0 :type double-float :read-only t)
  (ty 0d0 :type double-float :read-only t)
  (tz 0d0 :type double-float :read-only t)
  (qx 0d0 :type double-float :read-only t)
  (qy 0d0 :type double-float :read-only t)
  (qz 0d0 :type double-float :read-only t)
  (qw 1d0 :type double-float :read-only t))

(defmacro with-transform-components (((tx ty tz qx qy qz qw) transform) &body body)
  "Bind TX TY TZ to the translation and QX QY QZ QW to the rotation of the TRANSFORM around BODY."
  (let ((g (gensym "TR")))
    `(let* ((,g ,transform)
            (,tx (%tr-tx ,g)) (,ty (%tr-ty ,g)) (,tz (%tr-tz ,g))
            (,qx (%tr-qx ,g)) (,qy (%tr-qy ,g)) (,qz (%tr-qz ,g)) (,qw (%tr-qw ,g)))
       (declare (type double-float ,tx ,ty ,tz ,qx ,qy ,qz ,qw)
                (ignorable ,tx ,ty ,tz ,qx ,qy ,qz ,qw))
       ,@body)))

(declaim (inline translation rotation))
(defun translation (transform)
  "The translation (a 3D-VECTOR) of a TRANSFORM."
  (unless (transform-p transform) (input-error transform "a TRANSFORM" 'translation))
  (%make-3d-vector (%tr-tx transform) (%tr-ty transform) (%tr-tz transform)))

(defun rotation (transform)
  "The rotation (a QUATERNION) of a TRANSFORM."
  (unless (transform-p transform) (input-error transform "a TRANSFORM" 'rotation))
  (%make-quaternion (%tr-qx transform) (%tr-qy transform) (%tr-qz transform)
                    (%tr-qw transform)))

(declaim (inline %unit-transform))
(defun %unit-transform (tx ty tz qx qy qz qw)
  "A TRANSFORM from the double floats TX TY TZ and QX QY QZ QW, the quaternion scaled to unit norm
(kept as it is when its norm is 1 to within rounding)."
  (declare (type double-float tx ty tz qx qy qz qw) (optimize (speed 3) (safety 0) (debug 0)))
  (if (%unit-norm-p qx qy qz qw)
      (%make-raw-transform tx ty tz qx qy qz qw)
      (let ((s (%unit-scale qx qy qz qw nil)))
        (declare (type double-float s))
        (%make-raw-transform tx ty tz (* qx s) (* qy s) (* qz s) (* qw s)))))

(setf (documentation 'pose-p 'function) "True when the object is a POSE (stamped or not)."
      (documentation 'transform-p 'function)
      "True when the object is a TRANSFORM (stamped or not).")

(defun %print-pair (name first second stream)
  "Print NAME followed by the objects FIRST and SECOND on indented lines, as #<NAME ...>."
  (format stream "#<~a ~%   ~a~%   ~a>" name first second))

(defmethod print-object ((p pose) stream)
  (if *print-readably*
      (print-unreadable-object (p stream))
      (%print-pair "POSE" (origin p) (orientation p) stream)))

(defmethod print-object ((tr transform) stream)
  (if *print-readably*
      (print-unreadable-object (tr stream))
      (%print-pair "TRANSFORM" (translation tr) (rotation tr) stream)))

(defmethod make-load-form ((p pose) &optional environment)
  (make-load-form-saving-slots p :environment environment))

(defmethod make-load-form ((tr transform) &optional environment)
  (make-load-form-saving-slots tr :environment environment))

;;; Constructors

(defun make-pose (origin orientation)
  "A POSE at ORIGIN (a 3D-VECTOR) with ORIENTATION (a QUATERNION)."
  (%make-pose (check-type-of origin '3d-vector "a 3D-VECTOR as origin" 'make-pose)
              (check-type-of orientation 'quaternion "a QUATERNION as orientation" 'make-pose)))

(defun make-identity-pose ()
  "The POSE at the origin with the identity orientation."
  (%make-pose +zero-vector+ +identity-quaternion+))

(defun make-2d-pose (x y theta)
  "A POSE at (X Y 0) turned by THETA radians about the z axis."
  (%make-pose (make-3d-vector x y 0) (yaw theta)))

(defun make-transform (translation rotation)
  "A TRANSFORM with TRANSLATION (a 3D-VECTOR) and ROTATION (a QUATERNION; a real r stands for
the quaternion (0 0 0 r), as in cl-transforms, so 1 is the identity)."
  (%make-transform
   (check-type-of translation '3d-vector "a 3D-VECTOR as translation" 'make-transform)
   (if (quaternion-p rotation)
       rotation
       (if (realp rotation)
           (ensure-rotation rotation 'make-transform)
           (input-error rotation "a QUATERNION or a real as rotation" 'make-transform)))))

(defun make-identity-transform ()
  "The identity TRANSFORM."
  (%make-raw-transform 0d0 0d0 0d0 0d0 0d0 0d0 1d0))

(defun copy-pose (pose &key origin orientation)
  "A POSE like POSE with ORIGIN and/or ORIENTATION replaced."
  (check-type-of pose 'pose "a POSE" 'copy-pose)
  (make-pose (or origin (origin pose)) (or orientation (orientation pose))))

(defun copy-transform (transform &key translation rotation)
  "A TRANSFORM like TRANSFORM with TRANSLATION and/or ROTATION replaced."
  (check-type-of transform 'transform "a TRANSFORM" 'copy-transform)
  (make-transform (or translation (translation transform)) (or rotation (rotation transform))))

(declaim (inline pose->transform transform->pose))
(defun pose->transform (pose)
  "The TRANSFORM taking the reference frame to POSE (same origin and orientation)."
  (unless (pose-p pose) (input-error pose "a POSE" 'pose->transform))
  (%make-transform (origin pose) (orientation pose)))

(defun transform->pose (transform)
  "The POSE that TRANSFORM moves the reference frame to."
  (unless (transform-p transform) (input-error transform "a TRANSFORM" 'transform->pose))
  (%make-pose (translation transform) (rotation transform)))

(defun reference-transform (pose)
  "The TRANSFORM of POSE relative to its reference frame (same as POSE->TRANSFORM)."
  (pose->transform pose))

;;; Composition and inversion

(declaim (inline %transform*2 %transform-inv))
(defun %transform*2 (a b)
  "The composition A B of two TRANSFORMs (unchecked): first B, then A."
  (declare (type transform a b) (optimize (speed 3) (safety 0) (debug 0)))
  (with-transform-components ((atx aty atz ax ay az aw) a)
    (with-transform-components ((btx bty btz bx by bz bw) b)
      (multiple-value-bind (rx ry rz) (%rotate-components ax ay az aw btx bty btz)
        (multiple-value-bind (x y z w) (%q*-components ax ay az aw bx by bz bw)
          (%unit-transform (+ rx atx) (+ ry aty) (+ rz atz) x y z w))))))

(defun %transform-inv (tr)
  "The inverse of the TRANSFORM TR (unchecked)."
  (declare (type transform tr) (optimize (speed 3) (safety 0) (debug 0)))
  (with-transform-components ((vx vy vz x y z w) tr)
    ;; the translation is -(v rotated by the conjugate): with t = 2 (u x v), u = (x y z), that is
    ;; (w t - v) - u x t, which rounds exactly like rotating by (-x -y -z w) and negating
    (let* ((tx (* 2d0 (- (* y vz) (* z vy))))
           (ty (* 2d0 (- (* z vx) (* x vz))))
           (tz (* 2d0 (- (* x vy) (* y vx)))))
      (%make-raw-transform (- (- (* w tx) vx) (- (* y tz) (* z ty)))
                           (- (- (* w ty) vy) (- (* z tx) (* x tz)))
                           (- (- (* w tz) vz) (- (* x ty) (* y tx)))
                           (- x) (- y) (- z) w))))

(defun transform* (transform &rest more)
  "The composition of the TRANSFORMs from left to right: (transform* a b) applies B first, then
A, so (transform* map->base base->hand) is map->hand."
  (unless (transform-p transform) (input-error transform "a TRANSFORM" 'transform*))
  (let ((result transform))
    (dolist (next more result)
      (unless (transform-p next) (input-error next "a TRANSFORM" 'transform*))
      (setf result (%transform*2 result next)))))

(define-compiler-macro transform* (&whole form transform &rest more)
  (if (= (length more) 1)
      (let ((a (gensym "A")) (b (gensym "B")))
        `(let ((,a ,transform) (,b ,(first more)))
           (unless (transform-p ,a) (input-error ,a "a TRANSFORM" 'transform*))
           (unless (transform-p ,b) (input-error ,b "a TRANSFORM" 'transform*))
           (%transform*2 ,a ,b)))
      form))

(declaim (inline transform-inv))
(defun transform-inv (transform)
  "The inverse TRANSFORM: (transform* tr (transform-inv tr)) is the identity."
  (unless (transform-p transform) (input-error transform "a TRANSFORM" 'transform-inv))
  (%transform-inv transform))

(defun transform-diff (from to)
  "The TRANSFORM d with (transform* FROM d) = TO: TO expressed relative to FROM."
  (check-type-of from 'transform "a TRANSFORM" 'transform-diff)
  (check-type-of to 'transform "a TRANSFORM" 'transform-diff)
  (%transform*2 (%transform-inv from) to))

(declaim (inline transform-point))
(defun transform-point (transform point)
  "The 3D-VECTOR POINT mapped by TRANSFORM: rotation(point) + translation."
  (unless (transform-p transform) (input-error transform "a TRANSFORM" 'transform-point))
  (unless (3d-vector-p point) (input-error point "a 3D-VECTOR" 'transform-point))
  (locally (declare (optimize (speed 3) (safety 0) (debug 0)))
    (with-transform-components ((tx ty tz qx qy qz qw) transform)
      (with-vector-components ((vx vy vz) point)
        ;; the rotation is a unit quaternion: small coordinates (see %EXPONENT-FLAGS) cannot
        ;; overflow, so only the others pay for a handler
        (if (not (logtest (logior (%exponent-flags tx) (%exponent-flags ty) (%exponent-flags tz)
                                  (%exponent-flags vx) (%exponent-flags vy) (%exponent-flags vz))
                          -2048))
            (multiple-value-bind (rx ry rz) (%rotate-components qx qy qz qw vx vy vz)
              (%make-3d-vector (+ rx tx) (+ ry ty) (+ rz tz)))
            (handler-case
                (multiple-value-bind (rx ry rz) (%rotate-components qx qy qz qw vx vy vz)
                  (%make-3d-vector (+ rx tx) (+ ry ty) (+ rz tz)))
              (floating-point-overflow ()
                (input-error (list transform point)
                             "a transform and a point whose result is within double-float range"
                             'transform-point))))))))

(defun transform-pose (transform pose)
  "The POSE that results from moving POSE by TRANSFORM (POSE expressed in TRANSFORM's parent
frame when TRANSFORM is the child frame's transform)."
  (unless (transform-p transform) (input-error transform "a TRANSFORM" 'transform-pose))
  (unless (pose-p pose) (input-error pose "a POSE" 'transform-pose))
  (handler-case (%transform-pose transform pose)
    (floating-point-overflow ()
      (input-error (list transform pose) "a transform and a pose whose result is within double-float range" 'transform-pose))))

(defun %transform-pose (transform pose)
  (locally (declare (optimize (speed 3) (safety 0) (debug 0)))
    (with-transform-components ((tx ty tz ax ay az aw) transform)
      (with-vector-components ((vx vy vz) (origin pose))
        (with-quaternion-components ((bx by bz bw) (orientation pose))
          (multiple-value-bind (rx ry rz) (%rotate-components ax ay az aw vx vy vz)
            (%make-pose (%make-3d-vector (+ rx tx) (+ ry ty) (+ rz tz))
                        (multiple-value-bind (x y z w)
                            (%q*-components ax ay az aw bx by bz bw)
                          (%unit-quaternion x y z w)))))))))

;;; Matrices

(defun transform->matrix (transform)
  "The homogeneous 4x4 matrix (a double-float array) of TRANSFORM."
  (check-type-of transform 'transform "a TRANSFORM" 'transform->matrix)
  (let ((m (make-array '(4 4) :element-type 'double-float :initial-element 0d0)))
    (%fill-rotation-matrix (rotation transform) m)
    (setf (aref m 0 3) (%tr-tx transform) (aref m 1 3) (%tr-ty transform)
          (aref m 2 3) (%tr-tz transform) (aref m 3 3) 1d0)
    m))

(defun pose->matrix (pose)
  "The homogeneous 4x4 matrix (a double-float array) of the transform of POSE."
  (transform->matrix (pose->transform pose)))

(defun matrix->transform (matrix)
  "The TRANSFORM of a homogeneous matrix: a 2D array of reals, at least 3x4, whose upper-left
3x3 block is a rotation and whose fourth column holds the translation."
  (unless (and (arrayp matrix) (= (array-rank matrix) 2)
               (>= (array-dimension matrix 0) 3) (>= (array-dimension matrix 1) 4))
    (input-error matrix "a 2D array of at least 3x4 reals" 'matrix->transform))
  (%make-transform (make-3d-vector (aref matrix 0 3) (aref matrix 1 3) (aref matrix 2 3))
                   (matrix->quaternion matrix)))

(defun matrix->pose (matrix)
  "The POSE of a homogeneous matrix, as for MATRIX->TRANSFORM."
  (transform->pose (matrix->transform matrix)))

(defun %ensure-pose (pose place)
  "POSE when it is a POSE; a list ((x y z) (qx qy qz qw)) of reals becomes a POSE; anything else
signals TRANSFORM-INPUT-ERROR naming it and PLACE."
  (cond ((pose-p pose) pose)
        ((and (alexandria:proper-list-p pose) (= (length pose) 2)
              (alexandria:proper-list-p (first pose)) (= (length (first pose)) 3)
              (alexandria:proper-list-p (second pose)) (= (length (second pose)) 4))
         (%make-pose (apply #'make-3d-vector (first pose))
                     (apply #'make-quaternion (second pose))))
        (t (input-error pose "a POSE or a list ((x y z) (qx qy qz qw))" place))))
