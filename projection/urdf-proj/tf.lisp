;;;; TF of the simulated robot: the transformer of the projection environment is fed from the
;;;; belief state (map → odom → robot root → every link; map → each environment's links).
;;;; Also the bookkeeping every motion does: TF update, snapshot, ROBOT-STATE-CHANGED.

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

(defun publish-object-links (transformer object parent-frame stamp &key skip cache)
  "Write the root link of the articulated OBJECT under PARENT-FRAME (a frame that coincides
with the map) and every link under its parent link. Links of the same name as a link of the
articulated object SKIP are left out. With CACHE (MAKE-LINK-CACHE of OBJECT), a link whose pose relative to its parent is
unchanged is not written again."
  (let* ((layout (link-layout object))
         (names (link-layout-names layout))
         ;; on the stack: read here only (what is kept is copied)
         (poses (make-array (* 7 (length names)) :element-type 'double-float))
         (root-i (link-layout-root layout))
         (root (svref names root-i))
         (scratch (make-array 7 :element-type 'double-float)))
    (declare (dynamic-extent poses))
    (link-poses-vector object poses)
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

(defun update-tf-from-belief-state (&key (transformer cram-tf:*transformer*)
                                         (world btr:*current-bullet-world*) force)
  "Write the robot of WORLD into TRANSFORMER: map → odom frame (identity) → the robot's root
link → each link, and the links of the other articulated objects (the environment) under map,
those whose state changed since the last call (all with FORCE), as one update that lookups see
whole or not at all. Returns TRANSFORMER."
  (sb-thread:with-recursive-lock (*motion-lock*)
    (cl-transforms-stamped:with-transforms-batch (transformer)
      (%update-tf-from-belief-state transformer world force))))

(defun %update-tf-from-belief-state (transformer world force)
  (let* ((robot (robot-object world))
         (stamp (cram-tf-stamp))
         (odom (fact-value '?frame `(rob-int:robot-odom-frame ,(robot-name) ?frame)))
         (root (cl-urdf:name (cl-urdf:root-link (btr:urdf robot))))
         (parent (if (and odom (not (string= odom root)) (not (btr:link-exists-p robot odom)))
                     (progn (set-tf transformer cram-tf:*fixed-frame* odom
                                    (cl-transforms:make-identity-transform) stamp)
                            odom)
                     cram-tf:*fixed-frame*)))
    (let ((signatures (or *environment-tf-signatures* (make-hash-table :test 'eq))))
      ;; the robot's links under its own key (the robot object): only the changed ones
      (when force (remhash robot signatures))
      (publish-object-links transformer robot parent stamp
                            :cache (or (gethash robot signatures)
                                       (setf (gethash robot signatures) (make-link-cache robot))))
      (dolist (o (btr:objects world))
        (when (and (typep o 'btr:robot-object) (not (eq o robot)))
          (let ((signature (environment-signature o)))
            (when (or force (not (same-signature-p signature (gethash (btr:name o) signatures))))
              (publish-object-links transformer o cram-tf:*fixed-frame* stamp :skip robot)
              (setf (gethash (btr:name o) signatures) signature))))))
    transformer))

;;; ---- bookkeeping of every motion ------------------------------------------------------------

(defvar *after-motion-hooks* '()
  "Functions called with the motion's label after each motion (the viewer's replay recorder).")

(defvar *look-target-hooks* '()
  "Functions called with the target point (x y z) in the map of each LOOK-AT at a point.")

(defun after-motion (label)
  "Run after each motion (also a failed one): TF update inside the projection environment,
a snapshot labelled LABEL, *AFTER-MOTION-HOOKS*, and the ROBOT-STATE-CHANGED event."
  (when *tf-from-belief-state*
    (update-tf-from-belief-state))
  (cpl:note-picture (btr:snapshot label))
  (dolist (hook *after-motion-hooks*) (funcall hook label))
  (coe:on-event (make-instance 'cpoe:robot-state-changed)))

(defmacro with-motion ((label) &body body)
  "Run BODY as the motion LABEL (a string), holding *MOTION-LOCK*: AFTER-MOTION runs when BODY
is left, normally or by a failure."
  `(sb-thread:with-recursive-lock (*motion-lock*)
     (unwind-protect (progn ,@body)
       (after-motion ,label))))
