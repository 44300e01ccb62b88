;;;; Inverse kinematics of kinematic chains built from the URDF: a damped least squares solver
;;;; with joint limits and seeded random restarts, cross-checked with (and backed up by) the
;;;; native KDL chain of the same links (CRAM-NATIVE:MAKE-CHAIN / CHAIN-IK).

(in-package :cram-urdf-projection)

(defvar *ik-random-seed* 20240607
  "Seed of *IK-RANDOM-STATE* (RESET-IK-RANDOM-STATE and each projection environment use it).")

(defvar *ik-random-state* (sb-ext:seed-random-state *ik-random-seed*)
  "The random state IK restarts draw from; bound to a freshly seeded state in each projection
environment, so projections are repeatable.")

(defun reset-ik-random-state (&optional (seed *ik-random-seed*))
  "Set *IK-RANDOM-STATE* to a fresh state seeded with SEED (an integer). Returns it."
  (check-type seed (integer 0))
  (setf *ik-random-state* (sb-ext:seed-random-state seed)))

(defparameter *ik-position-tolerance* 1d-3 "Largest accepted IK position error (metres).")
(defparameter *ik-rotation-tolerance* 1d-2 "Largest accepted IK orientation error (radians).")
(defparameter *ik-max-restarts* 40 "Random restarts of one IK call after the seeded attempt.")
(defparameter *ik-max-iterations* 60 "Iterations of one IK attempt.")
(defparameter *ik-fallback-restarts* nil
  "What the Lisp solver tries after the native solver of the chain failed (from the same seed
and with *IK-MAX-RESTARTS* random restarts of its own): NIL nothing, N its seeded attempt and N
random restarts. Measured on randomized move-bottle runs: the seeded attempt solved none of
2 348 goals the native solver had failed on, 40 random restarts 1 of 1 111 (at 9 ms per run).")

(deftype dvec () '(simple-array double-float (*)))

(defstruct (ik-chain (:constructor %make-ik-chain))
  "A serial chain of movable joints from BASE-LINK to TIP-LINK of a URDF model."
  (base-link "" :type string)
  (tip-link "" :type string)
  (joint-names #() :type simple-vector)
  (prismatic #() :type simple-vector)
  (continuous #() :type simple-vector)
  (origins (make-array 0 :element-type 'double-float) :type dvec)   ; 12 per joint: R row-major, p
  (axes (make-array 0 :element-type 'double-float) :type dvec)      ; 3 per joint, in joint frame
  (tail (make-array 12 :element-type 'double-float) :type dvec)     ; last joint frame → tip
  (lower (make-array 0 :element-type 'double-float) :type dvec)
  (upper (make-array 0 :element-type 'double-float) :type dvec)
  (reach 0d0 :type double-float)
  (native nil)
  (lock (sb-thread:make-mutex :name "ik chain")))

(setf (documentation 'ik-chain-joint-names 'function) "The movable joint names of an IK-CHAIN, base first."
      (documentation 'ik-chain-base-link 'function) "The link an IK-CHAIN's poses are expressed in."
      (documentation 'ik-chain-tip-link 'function) "The link an IK-CHAIN places.")

(declaim (inline dvec) (ftype (function ((integer 0 100000)) dvec) dvec))
(defun dvec (n)
  "A fresh double-float vector of N zeros."
  (make-array n :element-type 'double-float :initial-element 0d0))

(defun transform-12 (origin)
  "The 12-double transform (rotation row-major, then translation) of a URDF origin
((x y z) (qx qy qz qw))."
  (destructuring-bind ((x y z) (qx qy qz qw)) origin
    (let ((m (cl-transforms:quaternion->matrix (cl-transforms:make-quaternion qx qy qz qw)))
          (v (dvec 12)))
      (dotimes (r 3) (dotimes (c 3) (setf (aref v (+ (* 3 r) c)) (coerce (aref m r c) 'double-float))))
      (setf (aref v 9) (coerce x 'double-float) (aref v 10) (coerce y 'double-float)
            (aref v 11) (coerce z 'double-float))
      v)))

(declaim (inline t12-mul))
(defun t12-mul (a b out)
  "OUT = A * B for 12-double transforms (OUT must not be A or B)."
  (declare (type dvec a b out) (optimize (speed 3) (safety 0)))
  (dotimes (r 3)
    (dotimes (c 3)
      (setf (aref out (+ (* 3 r) c))
            (+ (* (aref a (* 3 r)) (aref b c))
               (* (aref a (+ (* 3 r) 1)) (aref b (+ 3 c)))
               (* (aref a (+ (* 3 r) 2)) (aref b (+ 6 c))))))
    (setf (aref out (+ 9 r))
          (+ (aref a (+ 9 r))
             (* (aref a (* 3 r)) (aref b 9))
             (* (aref a (+ (* 3 r) 1)) (aref b 10))
             (* (aref a (+ (* 3 r) 2)) (aref b 11)))))
  out)

(declaim (ftype (function () dvec) identity-12))
(defun identity-12 ()
  (let ((v (dvec 12))) (setf (aref v 0) 1d0 (aref v 4) 1d0 (aref v 8) 1d0) v))

(defun make-ik-chain (robot base-link tip-link)
  "Build the IK-CHAIN of ROBOT (a BTR robot object) from BASE-LINK to TIP-LINK from its URDF;
fixed joints are folded into the transforms. Errors name unknown links or a broken path."
  (let* ((model (btr:urdf robot))
         (links (cl-urdf:links model))
         (tip (or (gethash tip-link links)
                  (projection-error "IK chain: tip link ~s is not a link of ~s." tip-link (btr:name robot))))
         (base (or (gethash base-link links)
                   (projection-error "IK chain: base link ~s is not a link of ~s." base-link (btr:name robot))))
         (path '()))
    (loop for l = tip then (cl-urdf:parent j)
          for j = (cl-urdf:parent-joint l)
          until (eq l base)
          do (unless j
               (projection-error "IK chain: link ~s is not above link ~s in ~s." base-link tip-link
                                 (btr:name robot)))
             (push j path))
    (let ((acc (identity-12)) (tmp (dvec 12)) (names '()) (prism '()) (cont '()) (origins '())
          (axes '()) (lower '()) (upper '()) (reach 0d0))
      (dolist (j path)
        (let ((o (transform-12 (cl-urdf:origin j))))
          (t12-mul acc o tmp)
          (replace acc tmp)
          (when (member (cl-urdf:joint-type j) '(:revolute :continuous :prismatic))
            (when names (incf reach (sqrt (+ (expt (aref acc 9) 2) (expt (aref acc 10) 2)
                                             (expt (aref acc 11) 2)))))
            (push (cl-urdf:name j) names)
            (push (eq (cl-urdf:joint-type j) :prismatic) prism)
            (let ((lo (cl-urdf:lower j)) (hi (cl-urdf:upper j)))
              (push (and (or (eq (cl-urdf:joint-type j) :continuous) (null lo) (null hi) (>= lo hi)) t) cont)
              (push (if (car cont) (- pi) (coerce lo 'double-float)) lower)
              (push (if (car cont) pi (coerce hi 'double-float)) upper))
            (push (copy-seq acc) origins)
            (push (mapcar (lambda (x) (coerce x 'double-float)) (cl-urdf:axis j)) axes)
            (setf acc (identity-12)))))
      (unless names
        (projection-error "IK chain from ~s to ~s of ~s has no movable joint." base-link tip-link
                          (btr:name robot)))
      (incf reach (sqrt (+ (expt (aref acc 9) 2) (expt (aref acc 10) 2) (expt (aref acc 11) 2))))
      (%make-ik-chain :base-link base-link :tip-link tip-link
                      :joint-names (coerce (reverse names) 'simple-vector)
                      :prismatic (coerce (reverse prism) 'simple-vector)
                      :continuous (coerce (reverse cont) 'simple-vector)
                      :origins (apply #'concatenate 'dvec (reverse origins))
                      :axes (coerce (apply #'append (reverse axes)) 'dvec)
                      :tail acc
                      :lower (coerce (reverse lower) 'dvec) :upper (coerce (reverse upper) 'dvec)
                      :reach (coerce reach 'double-float)
                      :native (let ((native (ignore-errors
                                             (cram-native:make-chain (btr:world-handle (btr:world robot))
                                                                     (btr:object-handle robot)
                                                                     base-link tip-link))))
                                (when native (install-kept-reach-map native))
                                native)))))

(defvar *chain-cache* (make-hash-table :test 'equal)
  "(URDF model, base link, tip link) → IK-CHAIN.")

(defvar *chain-cache-lock* (sb-thread:make-mutex :name "ik chain cache"))

(defvar *arm-ik-chains* '()
  "ARM-IK-CHAIN's answers, entries (database-generation urdf robot-name arm . chain): each valid
while the Prolog database is the same (the arm facts it read are plain facts).")

(defun ik-chain (robot base-link tip-link)
  "The cached IK-CHAIN of ROBOT from BASE-LINK to TIP-LINK (one per URDF model and links)."
  (let ((key (list (btr:urdf robot) base-link tip-link)))
    (sb-thread:with-recursive-lock (*chain-cache-lock*)
      (or (gethash key *chain-cache*)
          (setf (gethash key *chain-cache*) (make-ik-chain robot base-link tip-link))))))

(defun clear-ik-chain-cache ()
  "Forget every cached IK chain (and free their native chains)."
  (sb-thread:with-recursive-lock (*chain-cache-lock*)
    (loop for c being the hash-values of *chain-cache*
          when (ik-chain-native c) do (ignore-errors (cram-native:destroy-chain (ik-chain-native c))))
    (clrhash *chain-cache*)
    (setf *arm-ik-chains* '())))

(defvar *kept-reach-maps* '()
  "Reach maps of native IK chains (CRAM-NATIVE:CHAIN-REACH-MAP) kept by KEEP-REACH-MAPS, so that
a chain made again (in the process a saved core starts) takes its map instead of building it
at its first IK call.")

(defun install-kept-reach-map (native)
  "Give the native chain NATIVE the first of *KEPT-REACH-MAPS* that is a map of it (the shim
checks its joints, limits and tip); true when one was."
  (some (lambda (map) (cram-native:set-chain-reach-map native map)) *kept-reach-maps*))

(defun keep-reach-maps ()
  "Keep the reach maps of the cached IK chains (*CHAIN-CACHE*) in *KEPT-REACH-MAPS*, for the
chains made after the native ones are gone (a saved core): returns how many are kept."
  (sb-thread:with-recursive-lock (*chain-cache-lock*)
    (loop for c being the hash-values of *chain-cache*
          for native = (ik-chain-native c)
          when native
            do (let ((map (cram-native:chain-reach-map native)))
                 (unless (find (car map) *kept-reach-maps* :key #'car :test #'equalp)
                   (push map *kept-reach-maps*)))))
  (length *kept-reach-maps*))

;;; ---- forward kinematics -----------------------------------------------------------------------

(defun chain-fk-into (chain q frames tip)
  "Forward kinematics: the frame of each joint (after its origin, before its motion) into
FRAMES (12 per joint) and the tip transform into TIP."
  (declare (type ik-chain chain) (type dvec q frames tip) (optimize (speed 3) (safety 0)))
  (let* ((n (length (ik-chain-joint-names chain)))
         (origins (ik-chain-origins chain)) (axes (ik-chain-axes chain))
         (prism (ik-chain-prismatic chain))
         (cur (identity-12)) (tmp (dvec 12)) (o (dvec 12)) (m (dvec 12)))
    (declare (type dvec cur tmp o m) (type (integer 0 64) n))
    (dotimes (i n)
      (replace o origins :start2 (* 12 i) :end2 (* 12 (1+ i)))
      (t12-mul cur o tmp)
      (replace frames tmp :start1 (* 12 i))
      (let ((ax (aref axes (* 3 i))) (ay (aref axes (+ 1 (* 3 i)))) (az (aref axes (+ 2 (* 3 i))))
            (a (aref q i)))
        (fill m 0d0)
        (if (svref prism i)
            (setf (aref m 0) 1d0 (aref m 4) 1d0 (aref m 8) 1d0
                  (aref m 9) (* a ax) (aref m 10) (* a ay) (aref m 11) (* a az))
            (let* ((c (cos a)) (s (sin a)) (k (- 1d0 c)))
              (setf (aref m 0) (+ c (* k ax ax)) (aref m 1) (- (* k ax ay) (* s az)) (aref m 2) (+ (* k ax az) (* s ay))
                    (aref m 3) (+ (* k ax ay) (* s az)) (aref m 4) (+ c (* k ay ay)) (aref m 5) (- (* k ay az) (* s ax))
                    (aref m 6) (- (* k ax az) (* s ay)) (aref m 7) (+ (* k ay az) (* s ax)) (aref m 8) (+ c (* k az az)))))
        (t12-mul tmp m cur)))
    (t12-mul cur (ik-chain-tail chain) tip)
    tip))

(defun transform->12 (transform)
  (transform-12 (let ((p (cl-transforms:translation transform)) (q (cl-transforms:rotation transform)))
                  (list (list (cl-transforms:x p) (cl-transforms:y p) (cl-transforms:z p))
                        (list (cl-transforms:x q) (cl-transforms:y q) (cl-transforms:z q) (cl-transforms:w q))))))

(defun t12->pose (v)
  (let ((m (make-array '(3 3))))
    (dotimes (r 3) (dotimes (c 3) (setf (aref m r c) (aref v (+ (* 3 r) c)))))
    (cl-transforms:make-pose (cl-transforms:make-3d-vector (aref v 9) (aref v 10) (aref v 11))
                             (cl-transforms:matrix->quaternion m))))

(defun chain-forward-kinematics (chain joint-values)
  "The pose of CHAIN's tip link in its base link frame for JOINT-VALUES (a sequence)."
  (let* ((n (length (ik-chain-joint-names chain)))
         (q (coerce (map 'list (lambda (x) (coerce x 'double-float)) joint-values) 'dvec)))
    (unless (= (length q) n)
      (projection-error "Chain ~a→~a has ~d joints, got ~d values ~s." (ik-chain-base-link chain)
                        (ik-chain-tip-link chain) n (length q) joint-values))
    (t12->pose (chain-fk-into chain q (dvec (* 12 n)) (dvec 12)))))
