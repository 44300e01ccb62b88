;;;; Low level of the simulated robot, base and head: DRIVE, MOVE-TORSO, LOOK-AT, DETECT, and
;;;; the collision checks they use. Motions teleport the robot in the belief state.

(in-package :cram-urdf-projection)

;;; ---- collisions -----------------------------------------------------------------------------

;; what both collision checks leave out: the floor (static planes) and the carried objects
(defun collision-excepts (world robot)
  "The names of ROBOT's attached objects, those objects, and WORLD's static planes."
  (let ((attached (remove-duplicates (mapcar #'first (btr:attached-objects robot)))))
    (values attached
            (remove nil (mapcar (lambda (name) (btr:object world name)) attached))
            (remove :static-plane (btr:objects world) :key #'btr:object-kind :test-not #'eq))))

(defun attached-object-hits (world robot attached attached-objects intended)
  "The names of what ROBOT's ATTACHED objects touch besides the robot and each other."
  (let ((hits '()))
    (dolist (name attached (nreverse hits))
      (let ((o (btr:object world name)))
        (when o
          (loop for (a la b lb) in (btr::contact-records world o (cons robot attached-objects))
                for other = (if (eq a o) b a)
                for other-link = (if (eq a o) lb la)
                unless (or (eq other robot) (member (btr:name other) attached)
                           (intended-contact-p intended o nil other other-link))
                  do (pushnew (btr:name other) hits)))))))

(defun robot-collisions (&key (world btr:*current-bullet-world*) (robot (robot-object world))
                              ignore-links)
  "The names of the objects the robot collides with: contacts of its links (except the links
in IGNORE-LINKS) with anything but its attached objects, and contacts of its attached objects
with anything but the robot and each other. Contacts of the robot with the floor (static
planes) and the contacts the motion is meant to make (INTENDED-CONTACTS: the hands with the
objects being grasped, the objects being put down, *SWEEP-ALLOWED-CONTACTS*) do not count."
  (multiple-value-bind (attached attached-objects planes) (collision-excepts world robot)
    (let ((intended (intended-contacts robot))
          (hits '()))
      ;; the floor and the carried objects are not looked for: their contacts do not count
      (loop for (a la b lb) in (btr::contact-records world robot (append planes attached-objects))
            for other = (if (eq a robot) b a)
            for link = (if (eq a robot) la lb)
            for other-link = (if (eq a robot) lb la)
            unless (or (member (btr:name other) attached)
                       (eq (btr:object-kind other) :static-plane)
                       (and link (member link ignore-links :test #'string=))
                       (intended-contact-p intended robot link other other-link))
              do (pushnew (btr:name other) hits))
      (append (nreverse hits)
              (remove-if (lambda (name) (member name hits))
                         (attached-object-hits world robot attached attached-objects intended))))))

(defun robot-link-index (robot link)
  "The index of the link named LINK of ROBOT (an articulated object), or NIL when it has none."
  (values (gethash link (btr::km-link-index (btr::%model robot)))))

(defvar *last-allowed-triples* nil
  "(world robot intended triples objects): the last answer of ALLOWED-CONTACT-TRIPLES and the
\(name . handle) of the objects it names.")

(defun allowed-contact-triples (world robot intended)
  "The (MOVING HIT) pairs of INTENDED that concern ROBOT's links, as the native check's
\(link other other-link) triples (:ANY for any); pairs naming what is not there are left out.
The last answer is kept while the objects it names are the same: a motion's checks ask with
the same pairs again and again."
  (destructuring-bind (&optional w r i triples objects) *last-allowed-triples*
    (if (and (eq w world) (eq r robot) (or (eq i intended) (equal i intended))
             (loop for (name . handle) in objects
                   always (let ((o (btr:object world name)))
                            (and o (eql (btr:object-handle o) handle)))))
        triples
        (multiple-value-bind (triples objects) (compute-allowed-triples world robot intended)
          (setf *last-allowed-triples* (list world robot intended triples objects))
          triples))))

(defun compute-allowed-triples (world robot intended)
  (let ((objects '()))
    (flet ((handle (name)
             (let ((o (btr:object world name)))
               (when o
                 (pushnew (cons name (btr:object-handle o)) objects :test #'equal)
                 (btr:object-handle o)))))
      (values
       (loop for entry in intended
             for (m h) = (and (consp entry) (consp (cdr entry)) entry)
             for link = (cond ((eq m t) :any)
                              ((stringp m) (robot-link-index robot m)))
             for hit = (cond ((eq h t) (list :any :any))
                             ((and h (symbolp h))
                              (let ((handle (handle h))) (and handle (list handle :any))))
                             ((and (consp h) (stringp (second h)))
                              (let* ((o (btr:object world (first h)))
                                     (l (and o (btr:robot-object-p o)
                                             (robot-link-index o (second h)))))
                                (and l (list (handle (first h)) l)))))
             when (and link hit) collect (cons link hit))
       objects))))

(defun first-counted-contact (world robot skip-links)
  "The first contact (link other-handle other-link distance, as CRAM-NATIVE:OBJECT-FIRST-CONTACT)
of ROBOT's links but those of the indices SKIP-LINKS with anything but the planes and its
attached objects, contacts the motion intends allowed. Second to fourth values: the robot's
attachments, attached objects and intended contacts (COLLISION-EXCEPTS, INTENDED-CONTACTS)."
  (multiple-value-bind (attached attached-objects planes) (collision-excepts world robot)
    (let ((intended (intended-contacts robot)))
      (values (cram-native:object-first-contact
               (btr::world-handle world) (btr:object-handle robot)
               :except (mapcar #'btr:object-handle (append planes attached-objects))
               :skip-links skip-links
               :allowed (allowed-contact-triples world robot intended))
              attached attached-objects intended))))

(defun robot-collides-p (&key (world btr:*current-bullet-world*) (robot (robot-object world))
                              ignore-links)
  "True when ROBOT-COLLISIONS would name anything, found at less cost: the native check stops
at the first contact that counts."
  (multiple-value-bind (contact attached attached-objects intended)
      (first-counted-contact world robot
                             (remove nil (mapcar (lambda (l) (robot-link-index robot l)) ignore-links)))
    (cond ((null contact)
           (not (null (attached-object-hits world robot attached attached-objects intended))))
          ;; a body the belief state does not know: as ROBOT-COLLISIONS counts it
          ((btr::object-by-handle world (third contact)) t)
          (t (not (null (robot-collisions :world world :robot robot :ignore-links ignore-links)))))))

(defun other-links-collide-p (robot skip-links &key (world btr:*current-bullet-world*))
  "True when a link of ROBOT other than those of the link indices SKIP-LINKS touches a body the
belief state knows, in a contact that ROBOT-COLLIDES-P counts (the planes and the robot's
attached objects aside, intended contacts allowed): ROBOT-COLLIDES-P is then true however the
joints that move only SKIP-LINKS are set."
  (let ((contact (first-counted-contact world robot skip-links)))
    (and contact (btr::object-by-handle world (third contact)) t)))

;;; ---- navigation ---------------------------------------------------------------------------------

(defvar *warned-navigation-frames* '()
  "The frames of navigation goals whose frame DRIVE ignored and warned about (once each).")

(defun robot-base-frame-p (frame)
  "True when FRAME (a frame name, leading / ignored) is the robot's base frame or the root
link of the robot object (e.g. \"base_footprint\")."
  (let ((frame (string-left-trim "/" frame))
        (robot (btr:get-robot-object)))
    (or (string= frame (string-left-trim "/" cram-tf:*robot-base-frame*))
        (and robot (btr:urdf robot)
             (let ((root (ignore-errors (cl-urdf:name (cl-urdf:root-link (btr:urdf robot))))))
               (and root (string= frame root)))))))

(defun navigation-goal-in-map (pose)
  "The map pose the base drives to for the navigation goal POSE. As CRAM's projection does, a
pose-stamped in the robot's own base frame (e.g. the tutorial's *BASE-POSE-NEAR-COUNTER* in
\"base_footprint\") is taken with its numbers as map coordinates, not relative to where the
robot stands, so the same goal always leads to the same place; a warning says so the first
time for each frame. Goals in other frames are transformed into the map."
  (if (and (typep pose 'cl-transforms-stamped:pose-stamped)
           (robot-base-frame-p (cl-transforms-stamped:frame-id pose)))
      (let ((frame (cl-transforms-stamped:frame-id pose)))
        (unless (member frame *warned-navigation-frames* :test #'string=)
          (push frame *warned-navigation-frames*)
          (cpl:log-message :warn '(urdf-proj drive)
                           "Navigation goal ~a is in the robot's base frame ~s: as CRAM does, ~
                            its numbers are taken as map coordinates (the frame is ignored for ~
                            navigation). Give goals in ~s to make this explicit."
                           (pose-summary pose) frame cram-tf:*fixed-frame*))
        (cl-transforms:make-pose (cl-transforms:origin pose) (cl-transforms:orientation pose)))
      (pose-in-map pose "DRIVE goal")))

(defun drive (pose)
  "Teleport the robot's base to POSE (a pose-stamped, or a pose in the map; a pose-stamped in
the robot's base frame counts as map coordinates, see NAVIGATION-GOAL-IN-MAP). When the robot
then collides with anything but the floor and its attached objects, it is put back and
NAVIGATION-POSE-UNREACHABLE is signalled. Returns the joint states with the base as
odom_x_joint / odom_y_joint / odom_z_joint entries."
  (let* ((robot (robot-object))
         (goal (navigation-goal-in-map pose)))
    (with-motion ("going")
      ;; the state before, taken holding the motion lock: a motion of a concurrent branch may
      ;; come first
      (let ((before (btr:pose robot))
            (state (and *sweep-check* (robot-state-vectors robot))))
        (setf (btr:pose robot) goal)
        (let ((hits (robot-collisions :robot robot)))
          (when hits
            (setf (btr:pose robot) before)
            (cpl:fail 'common-fail:navigation-pose-unreachable
                      :description (format nil "Pose ~a is unreachable: the robot would collide with ~{~s~^, ~}."
                                           (pose-summary goal) hits))))
        (when state (check-motion-sweep state "going" :base :robot robot))
        (let ((o (cl-transforms:origin goal)))
          (append (mapcar (lambda (e) (list (car e) (cdr e))) (btr:joint-states robot))
                  (list (list "odom_x_joint" (cl-transforms:x o))
                        (list "odom_y_joint" (cl-transforms:y o))
                        (list "odom_z_joint" (cl-transforms:get-yaw (cl-transforms:orientation goal))))))))))

(defun pose-summary (pose)
  "A short text of POSE's position and yaw."
  (let ((o (cl-transforms:origin pose)))
    (format nil "(~,3f ~,3f ~,3f yaw ~,3f)" (cl-transforms:x o) (cl-transforms:y o) (cl-transforms:z o)
            (cl-transforms:get-yaw (cl-transforms:orientation pose)))))

;;; ---- torso ------------------------------------------------------------------------------------

(defun move-torso (joint-angle)
  "Set the torso joint to JOINT-ANGLE (a real, or :UPPER-LIMIT, :LOWER-LIMIT, :MIDDLE) clamped
to its limits. A numeric request outside the limits moves to the clamped value and then signals
TORSO-GOAL-NOT-REACHED. Returns the value set."
  (let ((robot (robot-object))
        (joint (torso-joint)))
    (unless (or (realp joint-angle) (member joint-angle '(:upper-limit :lower-limit :middle)))
      (projection-error "MOVE-TORSO: joint angle ~s, expected a real or one of :UPPER-LIMIT, ~
                         :LOWER-LIMIT, :MIDDLE." joint-angle))
    (when (and (realp joint-angle) (or (and (floatp joint-angle) (sb-ext:float-nan-p joint-angle)) (not (< (abs joint-angle) 1d6))))
      (projection-error "MOVE-TORSO: joint angle ~s is not a finite value." joint-angle))
    (with-motion ("moving-torso")
      (unless (movable-joint-p robot joint)
        (cpl:fail 'common-fail:torso-goal-not-reached
                  :description (format nil "Robot ~s has no movable torso joint (~s)."
                                       (robot-name) joint)))
      (multiple-value-bind (lo hi) (btr:joint-limits robot joint)
        (let* ((wanted (case joint-angle
                         (:upper-limit hi)
                         (:lower-limit lo)
                         (:middle (/ (+ lo hi) 2))
                         (t joint-angle)))
               (value (max lo (min hi wanted))))
          (with-sweep-check ("moving-torso" :torso :robot robot)
            (btr:set-robot-state-from-joints (list (list joint value)) robot))
          (when (> (abs (- value wanted)) 1d-9)
            (cpl:fail 'common-fail:torso-goal-not-reached
                      :description (format nil "Torso goal ~a is outside the limits [~a, ~a] of ~a; ~
                                                moved to ~a." wanted lo hi joint value)))
          value)))))

;;; ---- neck --------------------------------------------------------------------------------------

(defun v-rotate (quaternion vector)
  (cl-transforms:rotate quaternion vector))

(defun joint-axis-and-origin (robot joint)
  "The map direction of JOINT's axis and the map position of its frame (the child link's)."
  (let* ((j (or (gethash joint (cl-urdf:joints (btr:urdf robot)))
                (projection-error "Joint ~s is not a joint of ~s." joint (btr:name robot))))
         (pose (btr:link-pose robot (cl-urdf:name (cl-urdf:child j))))
         (axis (apply #'cl-transforms:make-3d-vector (cl-urdf:axis j))))
    (values (cl-transforms:normalize-vector (v-rotate (cl-transforms:orientation pose) axis))
            (cl-transforms:origin pose))))

(defun signed-angle (from to axis)
  "The angle about AXIS that turns FROM onto TO, both projected on the plane normal to AXIS
\(PLANE-PROJECTION; computed on the coordinates, in the same operations)."
  (let ((ax (cl-transforms:x axis)) (ay (cl-transforms:y axis)) (az (cl-transforms:z axis))
        (fx (cl-transforms:x from)) (fy (cl-transforms:y from)) (fz (cl-transforms:z from))
        (tx (cl-transforms:x to)) (ty (cl-transforms:y to)) (tz (cl-transforms:z to)))
    (declare (type double-float ax ay az fx fy fz tx ty tz))
    (flet ((norm (x y z)
             (declare (type double-float x y z))
             (if (< (max (abs x) (abs y) (abs z)) 1d150)
                 (sqrt (+ (* x x) (* y y) (* z z)))
                 (cl-transforms:v-norm (cl-transforms:make-3d-vector x y z)))))
      (let* ((sf (+ (* fx ax) (* fy ay) (* fz az)))
             (st (+ (* tx ax) (* ty ay) (* tz az)))
             ;; the projections on the plane
             (px (- fx (* sf ax))) (py (- fy (* sf ay))) (pz (- fz (* sf az)))
             (qx (- tx (* st ax))) (qy (- ty (* st ay))) (qz (- tz (* st az))))
        (declare (type double-float sf st px py pz qx qy qz))
        (if (or (< (norm px py pz) 1d-9) (< (norm qx qy qz) 1d-9))
            0d0
            (atan (+ (* ax (- (* py qz) (* pz qy)))
                     (* ay (- (* pz qx) (* px qz)))
                     (* az (- (* px qy) (* py qx))))
                  (+ (* px qx) (* py qy) (* pz qz))))))))

(defun normalize-angle (a)
  (atan (sin a) (cos a)))

(defvar *neck-answers* '()
  "NECK-ANGLES-TOWARDS' last answers, newest first (at most 8): entries (urdf joints camera key
values . clamped-values), KEY the map pose of the link the neck hangs from and the target, on
which alone the answer depends (the solver starts from the neck joints at zero): a robot that
looks at the same point from the same place again gets the same answer without solving.")

(defun joint-indices (robot joints)
  "The indices of the joints named JOINTS of ROBOT, as a vector for CRAM-NATIVE."
  (map '(simple-array (signed-byte 32) (*)) (lambda (j) (btr:joint-index robot j)) joints))

(defun neck-base-link (robot joints camera)
  "The link of ROBOT that the neck JOINTS hang from, when the path from it down to the CAMERA
link crosses every one of JOINTS and no other movable joint; NIL otherwise."
  (let ((links (cl-urdf:links (btr:urdf robot)))
        (left (copy-list joints)))
    (loop for link = (gethash camera links) then (cl-urdf:parent joint)
          for joint = (and link (cl-urdf:parent-joint link))
          do (cond ((null joint) (return nil))
                   ((member (cl-urdf:name joint) left :test #'string=)
                    (setf left (remove (cl-urdf:name joint) left :test #'string=))
                    (when (null left) (return (cl-urdf:name (cl-urdf:parent joint)))))
                   ((not (eq (cl-urdf:joint-type joint) :fixed)) (return nil))))))

(defun neck-answer-key (robot base target)
  "The map pose of ROBOT's link BASE and the point TARGET, as 10 doubles."
  (let ((key (make-array 10 :element-type 'double-float)))
    (replace key (cram-native:robot-link-pose (btr:world-handle (btr:world robot))
                                              (btr:object-handle robot)
                                              (btr:link-index robot base)))
    (setf (aref key 7) (float (cl-transforms:x target) 1d0)
          (aref key 8) (float (cl-transforms:y target) 1d0)
          (aref key 9) (float (cl-transforms:z target) 1d0))
    key))

(defun neck-angles-towards (robot joints camera target)
  "Joint values of the neck JOINTS that point the optical axis (z) of the CAMERA frame at the
map point TARGET, computed from the URDF joint axes and the link poses by turning each joint in
turn (exact for pan-tilt heads, also for cameras off the joint axes). The values may lie
outside the joints' limits; the joints are left at them clamped to the limits, without the
clamping's warnings (the solver passes through such values; its caller decides what a value
beyond a limit means)."
  (let* ((base (and (cl-transforms:3d-vector-p target) (stringp camera)
                    (alexandria:proper-list-p joints) (every #'stringp joints)
                    (neck-base-link robot joints camera)))
         (key (and base (neck-answer-key robot base target)))
         (urdf (btr:urdf robot)))
    (loop for (u js c k values . clamped) in *neck-answers*
          when (and key (eq u urdf) (equal js joints) (string= c camera) (every #'eql k key))
            do (cram-native:set-robot-joints
                (btr:world-handle (btr:world robot)) (btr:object-handle robot)
                (joint-indices robot joints)
                clamped)
               (return-from neck-angles-towards (copy-list values)))
    (let ((values (handler-bind ((warning #'muffle-warning))
                    (%neck-angles-towards robot joints camera target))))
      (when key
        (let ((clamped (map '(simple-array double-float (*)) (lambda (j) (btr:joint-state robot j))
                            joints)))
          (setf *neck-answers*
                (cons (list* urdf (copy-list joints) camera key (copy-list values) clamped)
                      (subseq *neck-answers* 0 (min (length *neck-answers*) 7))))))
      values)))

(defun %neck-angles-towards (robot joints camera target)
  (btr:set-robot-state-from-joints (mapcar (lambda (j) (list j 0d0)) joints) robot)
  ;; Each step turns one joint and reads the poses of its child link and of the camera with
  ;; the joints where the steps so far put them (clamped to their limits, as setting them in
  ;; the shim does): the shim computes those poses as it would after setting the joints, without
  ;; setting them (ROBOT-LINK-POSES-IF); the joints are set once, at the end.
  (let* ((world (btr:world-handle (btr:world robot)))
         (handle (btr:object-handle robot))
         (urdf-joints (cl-urdf:joints (btr:urdf robot)))
         ;; per joint: (joint child-link-index axis value)
         (steps (mapcar (lambda (j)
                          (let ((urdf-joint (or (gethash j urdf-joints)
                                                (projection-error "Joint ~s is not a joint of ~s."
                                                                  j (btr:name robot)))))
                            (list j (btr:link-index robot (cl-urdf:name (cl-urdf:child urdf-joint)))
                                  (apply #'cl-transforms:make-3d-vector (cl-urdf:axis urdf-joint))
                                  0d0)))
                        joints))
         (joint-indices (joint-indices robot joints))
         (index-list (coerce joint-indices 'list))
         ;; the joints' values in the shim as the steps leave them: at first what the zeros
         ;; were set to
         (current (map '(simple-array double-float (*)) (lambda (j) (btr:joint-state robot j))
                       joints))
         (links (make-array 2 :element-type '(signed-byte 32)
                              :initial-element (btr:link-index robot camera)))
         (poses (make-array 14 :element-type 'double-float))
         (forward-in-camera (cl-transforms:make-3d-vector 0 0 1)))
    (loop repeat 30
          for largest = 0d0
          do (loop for step in steps
                   for k from 0
                   for index in index-list
                   do (destructuring-bind (j child axis v) step
                        (setf (aref links 0) child)
                        (cram-native:robot-link-poses-if world handle joint-indices current links
                                                         poses)
                        (let* ((axis (cl-transforms:normalize-vector
                                      (v-rotate (cl-transforms:orientation (btr::vector->pose poses 0))
                                                axis)))
                               (cam (btr::vector->pose poses 7))
                               (forward (v-rotate (cl-transforms:orientation cam) forward-in-camera))
                               (to (cl-transforms:v- target (cl-transforms:origin cam)))
                               (delta (signed-angle forward to axis))
                               (new (normalize-angle (+ v delta))))
                          (setf largest (max largest (abs delta))
                                (fourth step) new
                                (aref current k) (btr::clamp-to-joint-limits robot j new index)))))
          until (< largest 1d-9))
    (cram-native:set-robot-joints world handle joint-indices current)
    (mapcar #'fourth steps)))

(defun apply-neck-joint-states (robot pairs)
  "Set the neck joints of PAIRS ((joint value)...) clamped to their limits; signals
PTU-GOAL-NOT-REACHED after moving when a value had to be clamped by more than 1e-5."
  (let* ((clamped (mapcar (lambda (p)
                            (destructuring-bind (j v) p
                              (unless (and (stringp j) (realp v) (not (and (floatp v) (sb-ext:float-nan-p v))) (< (abs v) 1d6))
                                (projection-error "Neck joint state ~s: expected (joint-name value)." p))
                              (list j (clamp-joint robot j v))))
                          pairs))
         (off (loop for (j v) in pairs for (nil c) in clamped
                    when (> (abs (- v c)) 1d-5) collect (list j v c))))
    (btr:set-robot-state-from-joints clamped robot)
    (when off
      (cpl:fail 'common-fail:ptu-goal-not-reached
                :description (format nil "Wanted to twist the neck beyond its limits: ~
                                          ~{~{~a wanted ~,4f, limited to ~,4f~}~^; ~}." off)))
    (mapcar #'second clamped)))

(defun look-at (target &optional configuration)
  "Point the robot's camera at TARGET: a pose-stamped (any known frame), a pose in the map, a
frame name, or a list of neck joint states ((joint value)...); or with TARGET NIL at the named
neck CONFIGURATION (e.g. :FORWARD). Neck angles are clamped to the joint limits;
PTU-GOAL-NOT-REACHED follows a clamped request. Returns the neck joint values."
  (let* ((robot (robot-object))
         (joints (neck-joints)))
    (unless joints
      (projection-error "Robot ~s has no ROBOT-NECK-JOINTS fact: it cannot look anywhere." (robot-name)))
    (with-motion ("looking")
      (cond ((and (null target) configuration)
             (apply-neck-joint-states robot (named-joint-states :neck nil configuration)))
            ((and (consp target) (every #'consp target) (every (lambda (e) (stringp (first e))) target))
             (apply-neck-joint-states robot (mapcar (lambda (e) (list (first e) (if (consp (cdr e)) (second e) (cdr e))))
                                                    target)))
            ((or (stringp target) (typep target 'cl-transforms-stamped:pose-stamped)
                 (cl-transforms:pose-p target) (consp target))
             (let* ((map-pose (if (stringp target) (frame-pose-in-map target)
                                  (pose-in-map target "LOOK-AT target")))
                    (values (neck-angles-towards robot joints (camera-frame robot)
                                                 (cl-transforms:origin map-pose))))
               (let ((o (cl-transforms:origin map-pose)))
                 (dolist (hook *look-target-hooks*)
                   (funcall hook (list (cl-transforms:x o) (cl-transforms:y o) (cl-transforms:z o)))))
               (apply-neck-joint-states robot (mapcar #'list joints values))))
            (t (projection-error "LOOK-AT: target ~s, expected a pose-stamped, a pose, a frame ~
                                  name or neck joint states, or NIL and a configuration name."
                                 target))))))

(defun look-at-pose-stamped (pose)
  "LOOK-AT the pose-stamped POSE (the name the older tutorials use)."
  (look-at pose))

;;; ---- perception ---------------------------------------------------------------------------------

(defun name-matches-p (wanted actual)
  (or (null wanted) (string-equal (string wanted) (string actual))))

(defun type-matches-p (wanted object)
  (or (null wanted) (string-equal (string wanted) "KITCHEN-OBJECT")
      (some (lambda (type) (string-equal (string wanted) (string type))) (btr:item-types object))))

(defun rosify (name)
  (substitute #\_ #\- (string-downcase (string name))))

(defun perceived-designator (input object camera-check-frame)
  "A copy of the object designator INPUT describing the item OBJECT as perceived: (type t)
(name n) and a (pose ((:pose base-pose) (:transform ...) (:pose-in-map ...) (:transform-in-map
...))) entry; its data is an OBJECT-DESIGNATOR-DATA with the name and the map pose."
  (declare (ignore camera-check-frame))
  (let* ((name (btr:name object))
         (frame (rosify name))
         (map-pose (btr:pose object))
         (base (robot-base-frame))
         (in-base (pose-in-frame map-pose base))
         (in-map (cl-transforms-stamped:make-pose-stamped cram-tf:*fixed-frame* (cram-tf-stamp)
                                                          (cl-transforms:origin map-pose)
                                                          (cl-transforms:orientation map-pose))))
    (desig:make-effective-designator
     input
     :new-properties `((:type ,(btr:item-type object))
                       (:name ,name)
                       (:pose ((:pose ,in-base)
                               (:transform ,(cram-tf:pose-stamped->transform-stamped in-base frame))
                               (:pose-in-map ,in-map)
                               (:transform-in-map ,(cram-tf:pose-stamped->transform-stamped in-map frame)))))
     :data-object (make-instance 'desig:object-designator-data :object-identifier name :pose in-map))))

(defun detect (object-designator)
  "Find the items matching OBJECT-DESIGNATOR's :NAME and :TYPE that are visible from the
robot's camera (BTR:*VISIBILITY-THRESHOLD* of their pixels unoccluded). Returns the perceived
designator of the first (quantifier :A / :AN) or a list of all (:ALL); signals
PERCEPTION-OBJECT-NOT-FOUND naming the designator when there is none."
  (unless (typep object-designator 'desig:object-designator)
    (projection-error "DETECT: expected an object designator, got ~s." object-designator))
  (with-motion ("detecting")
    (let* ((robot (robot-object))
           (world btr:*current-bullet-world*)
           (camera (btr:link-pose robot (camera-frame robot)))
           (wanted-name (desig:desig-prop-value object-designator :name))
           (wanted-type (desig:desig-prop-value object-designator :type))
           (hits (loop for o in (btr:objects world)
                       when (and (typep o 'btr:item)
                                 (name-matches-p wanted-name (btr:name o))
                                 (type-matches-p wanted-type o)
                                 (btr:object-visible-p world camera o))
                         collect o)))
      (unless hits
        (cpl:fail 'common-fail:perception-object-not-found
                  :object object-designator
                  :description (format nil "Could not find any object of type ~s~@[ named ~s~] ~
                                            in the field of view." wanted-type wanted-name)))
      (let ((perceived (mapcar (lambda (o) (perceived-designator object-designator o nil)) hits)))
        (if (eq (desig:quantifier object-designator) :all) perceived (first perceived))))))

(defun get-object-pose-in-base (object-designator)
  "The pose-stamped in the robot's base frame of a perceived OBJECT-DESIGNATOR."
  (second (assoc :pose (desig:desig-prop-value object-designator :pose))))

(defun get-object-pose-in-map (object-designator)
  "The pose-stamped in the map of a perceived OBJECT-DESIGNATOR."
  (second (assoc :pose-in-map (desig:desig-prop-value object-designator :pose))))
