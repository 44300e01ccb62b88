;;;; TF of the simulated robot: the transformer of the projection environment is fed from the
;;;; belief state (map → odom → robot root → every link; map → each environment's links).
;;;; Also the bookkeeping every motion does: TF update (written when TF is next read),
;;;; snapshot, ROBOT-STATE-CHANGED.

(in-package :cram-urdf-projection)

(defvar *tf-from-belief-state* nil
  "True inside the projection environment: motions then update CRAM-TF:*TRANSFORMER* from the
belief state after they ran.")

(defvar *environment-tf-signatures* nil
  "Hash table object name → joint and pose signature last written to TF, for the environment
objects (unchanged ones are not written again). Bound per projection environment.")

(defstruct (link-layout (:constructor make-link-layout (names root tree)))
  "What PUBLISH-OBJECT-LINKS needs of a URDF: the link names as a simple vector (in
BTR:LINK-NAMES order), the index of the root link among them, and the (parent-index .
child-index) pairs of every joint."
  (names #() :type simple-vector)
  (root nil)
  (tree #() :type simple-vector))

(defvar *layout-cache* (make-hash-table :test 'eq :weakness :key :synchronized t)
  "CL-URDF:ROBOT → its LINK-LAYOUT.")

(defun link-layout (robot)
  "The LINK-LAYOUT of the URDF of the articulated object ROBOT (made once per URDF)."
  (let ((model (btr:urdf robot)))
    (or (gethash model *layout-cache*)
        (setf (gethash model *layout-cache*)
              (let ((names (coerce (btr:link-names robot) 'simple-vector))
                    (index (make-hash-table :test 'equal)))
                (loop for n across names for i from 0 do (setf (gethash n index) i))
                (make-link-layout
                 names
                 (position (cl-urdf:name (cl-urdf:root-link model)) names :test #'string=)
                 (coerce (loop for j being the hash-values of (cl-urdf:joints model)
                               for p = (gethash (cl-urdf:name (cl-urdf:parent j)) index)
                               for c = (gethash (cl-urdf:name (cl-urdf:child j)) index)
                               when (and p c) collect (cons p c))
                         'simple-vector)))))))

(defun link-tree (robot)
  "The (parent-index . child-index) pairs of every joint of ROBOT's URDF, link indices as in
BTR:LINK-NAMES."
  (link-layout-tree (link-layout robot)))

(defun link-poses-vector (robot &optional out)
  "All link poses of ROBOT as one double vector, 7 per link in BTR:LINK-NAMES order (or into
OUT)."
  (cram-native:robot-link-poses (btr:world-handle (btr:world robot)) (btr:object-handle robot)
                                out))

(defun vector-transform (v i)
  "The CL-TRANSFORMS:TRANSFORM of pose number I of the pose vector V."
  (let ((o (* 7 i)))
    (cl-transforms:make-transform
     (cl-transforms:make-3d-vector (aref v o) (aref v (+ o 1)) (aref v (+ o 2)))
     (cl-transforms:make-quaternion (aref v (+ o 3)) (aref v (+ o 4)) (aref v (+ o 5)) (aref v (+ o 6))))))

(defun set-tf (transformer parent child transform stamp &optional static)
  (cl-transforms-stamped:set-transform
   transformer
   (cl-transforms-stamped:make-transform-stamped parent child stamp
                                                 (cl-transforms:translation transform)
                                                 (cl-transforms:rotation transform))
   :static static))

(defun relative-pose-into (v p c out)
  "Fill OUT (7 doubles) with pose number C of the pose vector V expressed in pose number P:
inverse(P) * C, translation and quaternion."
  (declare (type (simple-array double-float (*)) v out) (type fixnum p c)
           (optimize (speed 3) (safety 0)))
  (let* ((i (* 7 p)) (j (* 7 c))
         (px (aref v i)) (py (aref v (+ i 1))) (pz (aref v (+ i 2)))
         ;; conjugate of P's rotation
         (qx (- (aref v (+ i 3)))) (qy (- (aref v (+ i 4)))) (qz (- (aref v (+ i 5)))) (qw (aref v (+ i 6)))
         (dx (- (aref v j) px)) (dy (- (aref v (+ j 1)) py)) (dz (- (aref v (+ j 2)) pz))
         (cx (aref v (+ j 3))) (cy (aref v (+ j 4))) (cz (aref v (+ j 5))) (cw (aref v (+ j 6))))
    (declare (type double-float px py pz qx qy qz qw dx dy dz cx cy cz cw))
    ;; rotate d by q: d + 2w(q×d) + 2 q×(q×d)
    (let* ((tx (* 2 (- (* qy dz) (* qz dy))))
           (ty (* 2 (- (* qz dx) (* qx dz))))
           (tz (* 2 (- (* qx dy) (* qy dx)))))
      (setf (aref out 0) (+ dx (* qw tx) (- (* qy tz) (* qz ty)))
            (aref out 1) (+ dy (* qw ty) (- (* qz tx) (* qx tz)))
            (aref out 2) (+ dz (* qw tz) (- (* qx ty) (* qy tx)))))
    (setf (aref out 3) (+ (* qw cx) (* qx cw) (- (* qy cz) (* qz cy)))
          (aref out 4) (+ (* qw cy) (* qy cw) (- (* qz cx) (* qx cz)))
          (aref out 5) (+ (* qw cz) (* qz cw) (- (* qx cy) (* qy cx)))
          (aref out 6) (- (* qw cw) (* qx cx) (* qy cy) (* qz cz)))
    out))

(defun pose-vector-transform (v)
  "The CL-TRANSFORMS:TRANSFORM of the 7 doubles V."
  (cl-transforms:make-transform
   (cl-transforms:make-3d-vector (aref v 0) (aref v 1) (aref v 2))
   (cl-transforms:make-quaternion (aref v 3) (aref v 4) (aref v 5) (aref v 6))))

(defun same-pose-vector-p (a b)
  (declare (type (simple-array double-float (*)) a b) (optimize (speed 3) (safety 0)))
  (loop for i of-type fixnum below 7 always (< (abs (- (aref a i) (aref b i))) 1d-10)))

(defun make-link-cache (object)
  "A cache for PUBLISH-OBJECT-LINKS of the articulated OBJECT: per link index, the last 7
doubles written (NIL: none yet)."
  (make-array (length (link-layout-names (link-layout object))) :initial-element nil))

(defun publish-object-links (transformer object parent-frame stamp poses &key skip cache)
  "Write the root link of the articulated OBJECT under PARENT-FRAME (a frame that coincides
with the map) and every link under its parent link, from POSES (LINK-POSES-VECTOR of OBJECT).
Links of the same name as a link of the articulated object SKIP are left out. With CACHE
\(MAKE-LINK-CACHE of OBJECT), a link whose pose relative to its parent is unchanged is not
written again."
  (let* ((layout (link-layout object))
         (names (link-layout-names layout))
         (root-i (link-layout-root layout))
         (root (svref names root-i))
         (scratch (make-array 7 :element-type 'double-float)))
    (flet ((write-link (parent child-index relative)
             (let ((last (and cache (svref cache child-index))))
               (unless (and last (same-pose-vector-p last relative))
                 (set-tf transformer parent (svref names child-index)
                         (pose-vector-transform relative) stamp)
                 (when cache (setf (svref cache child-index) (copy-seq relative)))))))
      (unless (and skip (btr:link-exists-p skip root))
        (write-link parent-frame root-i (subseq poses (* 7 root-i) (* 7 (1+ root-i)))))
      (loop for (p . c) across (link-layout-tree layout)
            unless (and skip (btr:link-exists-p skip (svref names c)))
              do (write-link (svref names p) c (relative-pose-into poses p c scratch))))
    object))


(defun environment-signature (object)
  "The joint values and the pose of the articulated OBJECT, as two double vectors."
  (cons (cram-native:robot-joints (btr:world-handle (btr:world object)) (btr:object-handle object))
        (coerce (btr::pose->vector (btr:pose object)) '(simple-array double-float (*)))))

(defun same-doubles-p (a b)
  (declare (type (simple-array double-float (*)) a b) (optimize (speed 3) (safety 0)))
  (and (= (length a) (length b))
       (loop for i of-type fixnum below (length a) always (= (aref a i) (aref b i)))))

(defun same-signature-p (a b)
  "True when the environment signatures A and B (or NIL) are equal."
  (and a b (same-doubles-p (car a) (car b)) (same-doubles-p (cdr a) (cdr b))))

(defvar *motion-lock* (sb-thread:make-mutex :name "projection motion")
  "Held while a motion of the simulated robot runs, its TF update included: motions of
concurrent plan branches (CPL:PAR) change the belief state one after the other, and none sees
another half done.")

(defstruct (tf-snapshot (:constructor make-tf-snapshot ()))
  "What the TF of the belief state has to show and has not written yet: the STAMP, the frame
the robot's root link hangs from (PARENT; ODOM, when that is an odom frame under the map), the
ROBOT and its link poses (ROBOT-POSES, 7 doubles per link), OBJECTS ((object . link-poses)
...), the environment's articulated objects that changed, and the SIGNATURES table their
changes are told by. PENDING while not written."
  (pending nil) (stamp 0d0) (odom nil) (parent nil) (robot nil) (robot-poses nil)
  (objects '()) (signatures nil))

(defvar *tf-snapshots* (make-hash-table :test 'eq :weakness :key :synchronized t)
  "CL-TF:TRANSFORMER → its TF-SNAPSHOT.")

(defun tf-snapshot (transformer)
  "The TF-SNAPSHOT of TRANSFORMER (made on first use)."
  (or (gethash transformer *tf-snapshots*)
      (setf (gethash transformer *tf-snapshots*) (make-tf-snapshot))))

(defun capture-tf (snapshot world force)
  "Take into SNAPSHOT what the TF has to show of WORLD now: the robot's link poses, and those of
each other articulated object whose joints or pose changed since the last capture (every one
with FORCE). A capture while SNAPSHOT is pending adds to it: what it has not written is kept
unless captured anew."
  (let* ((robot (robot-object world))
         (frame (fact-value '?frame `(rob-int:robot-odom-frame ,(robot-name) ?frame)))
         (root (cl-urdf:name (cl-urdf:root-link (btr:urdf robot))))
         ;; an odom frame of its own, between the map and the robot's root link
         (odom (and frame (not (string= frame root)) (not (btr:link-exists-p robot frame)) frame))
         (signatures (or *environment-tf-signatures* (make-hash-table :test 'eq)))
         (size (* 7 (length (link-layout-names (link-layout robot)))))
         (poses (tf-snapshot-robot-poses snapshot)))
    (unless (and poses (eq robot (tf-snapshot-robot snapshot)) (= (length poses) size))
      (setf poses (make-array size :element-type 'double-float)))
    (link-poses-vector robot poses)
    (when force (remhash robot signatures))
    (dolist (o (btr:objects world))
      (when (and (typep o 'btr:robot-object) (not (eq o robot)))
        (let ((signature (environment-signature o)))
          (when (or force (not (same-signature-p signature (gethash (btr:name o) signatures))))
            (setf (tf-snapshot-objects snapshot)
                  (acons o (link-poses-vector o)
                         (remove o (tf-snapshot-objects snapshot) :key #'car)))
            (setf (gethash (btr:name o) signatures) signature)))))
    (setf (tf-snapshot-stamp snapshot) (cram-tf-stamp)
          (tf-snapshot-odom snapshot) odom
          (tf-snapshot-parent snapshot) (or odom cram-tf:*fixed-frame*)
          (tf-snapshot-robot snapshot) robot
          (tf-snapshot-robot-poses snapshot) poses
          (tf-snapshot-signatures snapshot) signatures
          (tf-snapshot-pending snapshot) t)
    snapshot))

(defun write-tf (snapshot transformer)
  "Write what SNAPSHOT holds into TRANSFORMER, when it is pending: map → odom frame (identity)
→ the robot's root link → each link, only the links that moved relative to their parent since
the last write; the captured environment objects' links under map."
  (when (tf-snapshot-pending snapshot)
    (let* ((stamp (tf-snapshot-stamp snapshot))
           (robot (tf-snapshot-robot snapshot))
           (signatures (tf-snapshot-signatures snapshot))
           (cache (or (gethash robot signatures)
                      (setf (gethash robot signatures) (make-link-cache robot)))))
      (when (tf-snapshot-odom snapshot)
        (set-tf transformer cram-tf:*fixed-frame* (tf-snapshot-odom snapshot)
                (cl-transforms:make-identity-transform) stamp))
      (publish-object-links transformer robot (tf-snapshot-parent snapshot) stamp
                            (tf-snapshot-robot-poses snapshot) :cache cache)
      (loop for (o . poses) in (reverse (tf-snapshot-objects snapshot))
            do (publish-object-links transformer o cram-tf:*fixed-frame* stamp poses :skip robot))
      (setf (tf-snapshot-objects snapshot) '()
            (tf-snapshot-pending snapshot) nil))))

(defun update-tf-from-belief-state (&key (transformer cram-tf:*transformer*)
                                         (world btr:*current-bullet-world*) force)
  "Write the robot of WORLD into TRANSFORMER: map → odom frame (identity) → the robot's root
link → each link, and the links of the other articulated objects (the environment) under map,
those whose state changed since the last call (all with FORCE), as one update that lookups see
whole or not at all. Returns TRANSFORMER."
  (sb-thread:with-recursive-lock (*motion-lock*)
    (cl-transforms-stamped:with-transforms-batch (transformer)
      (write-tf (capture-tf (tf-snapshot transformer) world force) transformer)))
  transformer)

(defun defer-tf-from-belief-state (&key (transformer cram-tf:*transformer*)
                                        (world btr:*current-bullet-world*) force)
  "As UPDATE-TF-FROM-BELIEF-STATE, of WORLD as it is now, but written only when TRANSFORMER is
next read or written (CL-TF:DEFER-UPDATE): after each motion, TF costs nothing until a plan
looks something up. Returns TRANSFORMER."
  (sb-thread:with-recursive-lock (*motion-lock*)
    (cl-transforms-stamped:with-transforms-batch (transformer)
      (let ((snapshot (capture-tf (tf-snapshot transformer) world force)))
        (cl-transforms-stamped:defer-update transformer
                                            (lambda () (write-tf snapshot transformer))))))
  transformer)

;;; ---- bookkeeping of every motion ------------------------------------------------------------

(defvar *after-motion-hooks* '()
  "Functions called with the motion's label after each motion (the viewer's replay recorder).")

(defvar *look-target-hooks* '()
  "Functions called with the target point (x y z) in the map of each LOOK-AT at a point.")

(defun after-motion (label)
  "Run after each motion (also a failed one): TF update inside the projection environment
\(DEFER-TF-FROM-BELIEF-STATE: written when the transformer is next read or written),
a snapshot labelled LABEL, *AFTER-MOTION-HOOKS*, and the ROBOT-STATE-CHANGED event."
  (when *tf-from-belief-state*
    (defer-tf-from-belief-state))
  (cpl:note-picture (btr:snapshot label))
  (dolist (hook *after-motion-hooks*) (funcall hook label))
  (coe:on-event (make-instance 'cpoe:robot-state-changed)))

(defmacro with-motion ((label) &body body)
  "Run BODY as the motion LABEL (a string), holding *MOTION-LOCK*: AFTER-MOTION runs when BODY
is left, normally or by a failure."
  `(sb-thread:with-recursive-lock (*motion-lock*)
     (unwind-protect (progn ,@body)
       (after-motion ,label))))
