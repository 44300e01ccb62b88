;;;; Poses and rigid transforms, their composition, inversion and matrices.

(in-package :cl-transforms)

(declaim (inline %make-pose %make-transform))

(defstruct (pose (:constructor %make-pose (origin orientation))
                 (:conc-name nil)
                 (:copier nil))
  "A position (ORIGIN, a 3D-VECTOR) and an ORIENTATION (a unit QUATERNION); immutable."
  (origin +zero-vector+ :type 3d-vector :read-only t)
  (orientation +identity-quaternion+ :type quaternion :read-only t))

(setf (documentation 'origin 'function) "The position (a 3D-VECTOR) of a POSE."
      (documentation 'orientation 'function) "The orientation (a QUATERNION) of a POSE.")

(defstruct (transform (:constructor %make-transform (translation rotation))
                      (:conc-name nil)
                      (:copier nil))
  "A rigid transform: first ROTATION (a unit QUATERNION), then TRANSLATION (a 3D-VECTOR).
Applied to a point p it gives rotation(p) + translation; immutable."
  (translation +zero-vector+ :type 3d-vector :read-only t)
  (rotation +identity-quaternion+ :type quaternion :read-only t))

(setf (documentation 'translation 'function) "The translation (a 3D-VECTOR) of a TRANSFORM."
      (documentation 'rotation 'function) "The rotation (a QUATERNION) of a TRANSFORM.")

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
  "A TRANSFORM with TRANSLATION (a 3D-VECTOR) and ROTATION (a QUATERNION)."
  (%make-transform
   (check-type-of translation '3d-vector "a 3D-VECTOR as translation" 'make-transform)
   (check-type-of rotation 'quaternion "a QUATERNION as rotation" 'make-transform)))

(defun make-identity-transform ()
  "The identity TRANSFORM."
  (%make-transform +zero-vector+ +identity-quaternion+))

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
  (let ((ta (translation a)) (qa (rotation a)) (tb (translation b)) (qb (rotation b)))
    (with-quaternion-components ((ax ay az aw) qa)
      (with-quaternion-components ((bx by bz bw) qb)
        (with-vector-components ((vx vy vz) tb)
          (multiple-value-bind (rx ry rz) (%rotate-components ax ay az aw vx vy vz)
            (%make-transform
             (%make-3d-vector (+ rx (%v-x ta)) (+ ry (%v-y ta)) (+ rz (%v-z ta)))
             (multiple-value-bind (x y z w) (%q*-components ax ay az aw bx by bz bw)
               (%unit-quaternion x y z w)))))))))

(defun %transform-inv (tr)
  "The inverse of the TRANSFORM TR (unchecked)."
  (with-quaternion-components ((x y z w) (rotation tr))
    (with-vector-components ((vx vy vz) (translation tr))
      (multiple-value-bind (rx ry rz) (%rotate-components (- x) (- y) (- z) w vx vy vz)
        (%make-transform (%make-3d-vector (- rx) (- ry) (- rz))
                         (%make-quaternion (- x) (- y) (- z) w))))))

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
  (let ((tr (translation transform)))
    (with-quaternion-components ((qx qy qz qw) (rotation transform))
      (with-vector-components ((vx vy vz) point)
        (multiple-value-bind (rx ry rz) (%rotate-components qx qy qz qw vx vy vz)
          (%make-3d-vector (+ rx (%v-x tr)) (+ ry (%v-y tr)) (+ rz (%v-z tr))))))))

(defun transform-pose (transform pose)
  "The POSE that results from moving POSE by TRANSFORM (POSE expressed in TRANSFORM's parent
frame when TRANSFORM is the child frame's transform)."
  (unless (transform-p transform) (input-error transform "a TRANSFORM" 'transform-pose))
  (unless (pose-p pose) (input-error pose "a POSE" 'transform-pose))
  (transform->pose (%transform*2 transform (pose->transform pose))))

;;; Matrices

(defun transform->matrix (transform)
  "The homogeneous 4x4 matrix (a double-float array) of TRANSFORM."
  (check-type-of transform 'transform "a TRANSFORM" 'transform->matrix)
  (let ((m (make-array '(4 4) :element-type 'double-float :initial-element 0d0))
        (tr (translation transform)))
    (%fill-rotation-matrix (rotation transform) m)
    (setf (aref m 0 3) (%v-x tr) (aref m 1 3) (%v-y tr) (aref m 2 3) (%v-z tr)
          (aref m 3 3) 1d0)
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
