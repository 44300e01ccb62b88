;;;; Picking up and placing: groundings (arms x grasps as lazy alternatives, trajectories from
;;;; MAN-INT) and the plans, logging each step in CRAM's words.

(in-package :cram-mobile-pick-place-plans)

;;; ---- helpers over the belief state --------------------------------------------------------------

(defun tool-frame (arm)
  (or (rob-int::first-solution-value
       '?frame `(rob-int:robot-tool-frame ,(current-robot-name) ,arm ?frame))
      (pp-error "The robot ~s has no tool frame for the arm ~s." (current-robot-name) arm)))

(defun end-effector-link (arm)
  (rob-int::first-solution-value
   '?link `(rob-int:end-effector-link ,(current-robot-name) ,arm ?link)))

(defun tool-pose-in-map (arm)
  (btr:link-pose (btr:get-robot-object) (tool-frame arm)))

(defun arms-holding (object-name)
  "The arms whose end-effector carries the object OBJECT-NAME in the belief state."
  (let ((robot (btr:get-robot-object)))
    (when robot
      (let ((links (btr:object-attached robot object-name)))
        (loop for arm in (robot-arms)
              when (member (end-effector-link arm) links :test #'equal)
                collect arm)))))

(defun free-arms ()
  "The arms whose end-effector carries nothing."
  (let ((robot (btr:get-robot-object)))
    (if robot
        (let ((busy (mapcar #'second (btr:attached-objects robot))))
          (remove-if (lambda (arm) (member (end-effector-link arm) busy :test #'equal))
                     (robot-arms)))
        (robot-arms))))

(defun relative-transform (from-pose to-pose)
  "TO-POSE expressed in the frame of FROM-POSE, as a transform."
  (cl-transforms:transform* (cl-transforms:transform-inv (cl-transforms:pose->transform from-pose))
                            (cl-transforms:pose->transform to-pose)))

(defun support-height-below (x y z &key (ignore '()))
  "The highest top (z) of an environment link or item below height Z whose bounding box covers
(X, Y), or NIL."
  (let ((x (float x 1d0)) (y (float y 1d0)) (limit (+ (float z 1d0) 1d-3)) (best nil))
    (declare (type double-float x y limit))
    (flet ((consider (x0 y0 x1 y1 top)
             (declare (type double-float x0 y0 x1 y1 top))
             (when (and (<= x0 x x1) (<= y0 y y1) (<= top limit) (or (null best) (> top best)))
               (setf best top))))
      (declare (inline consider))
      (let ((env (btr:get-environment-object)))
        (when (typep env 'btr:robot-object)
          (let ((n (btr:link-count env)))
            (cram-native:with-scratch-vector (boxes (* 6 n) double-float (* 6 512))
              (when (ignore-errors (btr:link-aabbs env boxes))
                (loop for k of-type fixnum from 0 below (* 6 n) by 6
                      do (consider (aref boxes k) (aref boxes (+ k 1))
                                   (aref boxes (+ k 3)) (aref boxes (+ k 4))
                                   (aref boxes (+ k 5)))))))))
      (dolist (o (btr:objects))
        (when (and (typep o 'btr:item) (not (member (btr:name o) ignore)))
          (multiple-value-bind (lo hi) (btr:aabb o)
            (consider (float (cl-transforms:x lo) 1d0) (float (cl-transforms:y lo) 1d0)
                      (float (cl-transforms:x hi) 1d0) (float (cl-transforms:y hi) 1d0)
                      (float (cl-transforms:z hi) 1d0))))))
    best))

;;; ---- picking up --------------------------------------------------------------------------------

(defun picking-up-groundings (d)
  (let* ((object (prop d :object))
         (name (object-designator-name object))
         (type (object-designator-type object))
         (arms (let ((arm (prop d :arm)))
                 (cond ((and arm (listp arm)) (arm-list arm))
                       (arm (list (check-arm arm)))
                       (t (or (free-arms) (pp-error "No free arm to pick up ~s." name))))))
         (object-pose (object-pose-in-map object))
         (in-base (relative-transform (robot-pose-in-map) object-pose))
         (location-type (man-int:get-object-location-type object))
         (opening (man-int:get-object-type-gripper-opening type))
         (effort (man-int:get-object-type-gripping-effort type)))
    (loop for arm in arms
          nconc (loop for grasp in (let ((g (prop d :grasp)))
                                     (if g
                                         (progn (man-int:get-object-type-to-gripper-transform
                                                 type name arm g)
                                                (list g))
                                         (man-int:get-action-grasps type arm in-base)))
                      for trajectory = (man-int:get-action-trajectory
                                        :picking-up arm grasp type object-pose
                                        :location-type location-type)
                      collect (resolved 'pick-up :picking-up
                                        `((:arm ,arm) (:grasp ,grasp) (:object ,object)
                                          (:gripper-opening ,opening) (:effort ,effort)
                                          (:trajectory ,trajectory)
                                          (:look-pose ,(map-stamped object-pose))))))))

(def-action-grounding :picking-up (d)
  (unless (typep (prop d :object) 'desig:object-designator)
    (pp-error "The picking-up action ~s needs an OBJECT designator, got ~s." d (prop d :object)))
  (picking-up-groundings d))

(defun arm-poses (arm poses)
  (ecase arm
    (:left (values poses nil))
    (:right (values nil poses))))

(defun perform-arm-action (?type arm poses &key ignore-failures (log-tag 'pick-up))
  (multiple-value-bind (?left ?right) (arm-poses arm poses)
    (flet ((run ()
             (exe:perform (desig:an action (type ?type)
                                    (desig:when ?left (left-poses ?left))
                                    (desig:when ?right (right-poses ?right))))))
      (if ignore-failures
          (handler-case (run)
            (common-fail:manipulation-low-level-failure (e)
              (cpl:log-message :warn `(pick-place ,log-tag) "~a~%Ignoring." e)))
          (run)))))

(defun log-pp (tag control &rest arguments)
  (apply #'cpl:log-message :info `(pick-place ,tag) control arguments))

(defun moving-part-links (link-name &optional (env (btr:get-environment-object)))
  "The links of the environment ENV that move with its link LINK-NAME: the subtree of the link
below the nearest movable joint above it (a drawer's bottom, walls and boards), or LINK-NAME
alone when no joint above it moves (a table top)."
  (let* ((model (and env (btr:urdf env)))
         (link (and model (gethash link-name (cl-urdf:links model)))))
    (when link
      (labels ((below (l)
                 (cons (cl-urdf:name l)
                       (loop for j in (cl-urdf:child-joints l) append (below (cl-urdf:child j)))))
               (moving-root (l)
                 (let ((j (cl-urdf:parent-joint l)))
                   (cond ((null j) nil)
                         ((member (cl-urdf:joint-type j) '(:prismatic :revolute :continuous)) l)
                         (t (moving-root (cl-urdf:parent j)))))))
        (let ((root (moving-root link)))
          (if root (below root) (list link-name)))))))

(defparameter *flat-object-height* 0.03d0
  "Metres: an object no higher than this, resting on a surface (a spoon on the table), is
grasped with the fingertips on the surface; the hands may touch the surface it rests on.")

(defun flat-object-support-links (object env)
  "The links of the environment ENV that OBJECT rests on (touching it, their tops below its
origin) when OBJECT is no higher than *FLAT-OBJECT-HEIGHT* in its own frame; else NIL."
  (multiple-value-bind (lo hi) (btr:local-aabb object)
    (let ((middle (cl-transforms:z (cl-transforms:origin (btr:pose object)))))
      (when (<= (- (cl-transforms:z hi) (cl-transforms:z lo)) *flat-object-height*)
        (loop for (nil nil other other-link) in (cram-native:object-contacts
                                                 (btr::world-handle btr:*current-bullet-world*)
                                                 (btr:object-handle object) :threshold 0.005d0)
              when (and (eql other (btr:object-handle env)) (>= other-link 0)
                        (< (cl-transforms:z (nth-value 1 (btr:aabb env other-link))) middle))
                collect (btr::link-name-of env other-link))))))

(defun container-links (object-name)
  "The environment links around the object OBJECT-NAME when it lies in or on the environment:
the moving parts of the links it is attached to (MOVING-PART-LINKS), and for a flat object the
surface it rests on (FLAT-OBJECT-SUPPORT-LINKS). NIL for an object in neither case."
  (let* ((env (btr:get-environment-object))
         (object (btr:object btr:*current-bullet-world* object-name)))
    (when (and env object)
      (remove-duplicates (append (loop for link in (btr:object-attached env object)
                                       append (moving-part-links link env))
                                 (flat-object-support-links object env))
                         :test #'string=))))

(defmacro with-object-being-grasped ((object) &body body)
  "Run BODY while the hands may touch OBJECT and the container it lies in
(URDF-PROJ:*GRASPED-OBJECTS*, URDF-PROJ:*GRASP-CONTAINER-LINKS*): closing in on an object is a
grasp, not a collision. Set globally, as motions run in process-module threads."
  (let ((name (gensym "NAME")) (links (gensym "LINKS")))
    `(let* ((,name (object-designator-name ,object))
            (,links (container-links ,name)))
       (unwind-protect
            (progn (push ,name urdf-proj:*grasped-objects*)
                   (setf urdf-proj:*grasp-container-links*
                         (append ,links urdf-proj:*grasp-container-links*))
                   ,@body)
         (setf urdf-proj:*grasped-objects* (remove ,name urdf-proj:*grasped-objects* :count 1)
               urdf-proj:*grasp-container-links*
               (nthcdr (length ,links) urdf-proj:*grasp-container-links*))))))

(defun target-container-links (target)
  "The moving parts of the environment link a placing TARGET (a location designator) is in, on
or above (its URDF-NAME), or NIL."
  (when (typep target 'desig:location-designator)
    (let* ((reference (find-if (lambda (v) (typep v 'desig:object-designator))
                               (mapcar (lambda (key) (desig:desig-prop-value target key))
                                       '(:in :on :above))))
           (urdf-name (and reference (desig:desig-prop-value reference :urdf-name))))
      (when urdf-name
        (moving-part-links (substitute #\_ #\- (string-downcase (string urdf-name))))))))

(defmacro with-object-being-placed ((object &optional target) &body body)
  "Run BODY while OBJECT, held, may touch what it is put on (URDF-PROJ:*PLACED-OBJECTS*), and
the hands the container TARGET is in (URDF-PROJ:*GRASP-CONTAINER-LINKS*). Set globally, as
motions run in process-module threads."
  (let ((name (gensym "NAME")) (links (gensym "LINKS")))
    `(let ((,name (object-designator-name ,object))
           (,links (target-container-links ,target)))
       (unwind-protect
            (progn (push ,name urdf-proj:*placed-objects*)
                   (push ,name urdf-proj:*grasped-objects*)
                   (setf urdf-proj:*grasp-container-links*
                         (append ,links urdf-proj:*grasp-container-links*))
                   ,@body)
         (setf urdf-proj:*placed-objects* (remove ,name urdf-proj:*placed-objects* :count 1)
               urdf-proj:*grasped-objects* (remove ,name urdf-proj:*grasped-objects* :count 1)
               urdf-proj:*grasp-container-links*
               (nthcdr (length ,links) urdf-proj:*grasp-container-links*))))))

(defun pick-up (&key arm grasp object gripper-opening effort trajectory look-pose
                &allow-other-keys)
  "Pick up OBJECT with ARM using GRASP along TRAJECTORY (MAN-INT segments :REACHING,
:GRASPING, :LIFTING): look, open the gripper while reaching, grasp, grip (recording the grasp
in the belief), lift and park the arm. Failures of reaching, grasping and lifting are logged
and ignored; a failed grip propagates (e.g. COMMON-FAIL:GRIPPER-CLOSED-COMPLETELY)."
  (let ((?look-pose look-pose) (?arm arm) (?opening gripper-opening)
        (?object object) (?grasp grasp) (?effort effort))
    (log-pp 'pick-up "Looking")
    (handler-case
        (exe:perform (desig:an action (type looking)
                               (target (desig:a location (pose ?look-pose)))))
      (common-fail:ptu-low-level-failure (e)
        (cpl:log-message :warn '(pick-place pick-up) "~a~%Ignoring." e)))
    (log-pp 'pick-up "Opening gripper and reaching")
    (cpl:par
      (exe:perform (desig:an action (type setting-gripper) (gripper ?arm) (position ?opening)))
      (perform-arm-action :reaching arm (man-int:get-traj-poses-by-label trajectory :reaching)
                          :ignore-failures t))
    (log-pp 'pick-up "Grasping")
    (with-object-being-grasped (object)
      (perform-arm-action :grasping arm (man-int:get-traj-poses-by-label trajectory :grasping)
                          :ignore-failures t)
      (log-pp 'pick-up "Gripping")
      (exe:perform (desig:an action (type gripping) (arm ?arm) (object ?object)
                             (grasp ?grasp) (effort ?effort))))
    (log-pp 'pick-up "Lifting")
    (perform-arm-action :lifting arm (man-int:get-traj-poses-by-label trajectory :lifting)
                        :ignore-failures t)
    (log-pp 'pick-up "Parking")
    (exe:perform (desig:an action (type parking-arms) (arms (?arm))))
    object))

;;; ---- placing ------------------------------------------------------------------------------------

(defun bottom-offset-at (object orientation)
  "How far the bottom of the belief-state OBJECT lies below its origin when it is turned to
ORIENTATION (a quaternion in the map): the lowest corner of its box in its own frame
(BTR:LOCAL-AABB), turned. Not how it hangs in a hand now, which may be on its side."
  (multiple-value-bind (lo hi) (btr:local-aabb object)
    (- (loop for x in (list (cl-transforms:x lo) (cl-transforms:x hi))
             minimize (loop for y in (list (cl-transforms:y lo) (cl-transforms:y hi))
                            minimize (loop for z in (list (cl-transforms:z lo) (cl-transforms:z hi))
                                           minimize (cl-transforms:z
                                                     (cl-transforms:rotate
                                                      orientation
                                                      (cl-transforms:make-3d-vector x y z)))))))))

(defun placing-target-pose (object type target)
  "The object pose (fixed frame) for placing OBJECT at TARGET: a rotationally symmetric object
keeps its orientation in hand; an object whose bottom, turned as it is put down
(BOTTOM-OFFSET-AT), would sink into the surface below the target is raised to rest on it."
  (let* ((name (object-designator-name object))
         (current (object-pose-in-map object))
         (goal (pose-in-map (location-pose target)))
         (goal (if (man-int:object-rotationally-symmetric-p type)
                   (cl-transforms:make-pose (cl-transforms:origin goal)
                                            (cl-transforms:orientation current))
                   goal))
         (o (btr:object btr:*current-bullet-world* name)))
    (if (null o)
        goal
        (let* ((bottom-offset (bottom-offset-at o (cl-transforms:orientation goal)))
               (gx (cl-transforms:x (cl-transforms:origin goal)))
               (gy (cl-transforms:y (cl-transforms:origin goal)))
               (gz (cl-transforms:z (cl-transforms:origin goal)))
               (bottom (- gz bottom-offset))
               (support (support-height-below gx gy (+ bottom 0.1d0) :ignore (list name))))
          (if (and support (< bottom support))
              (cl-transforms:make-pose
               (cl-transforms:make-3d-vector gx gy (+ support bottom-offset 0.002d0))
               (cl-transforms:orientation goal))
              goal)))))

;;; What the hands hold: placing without an OBJECT takes it from the hand, and without a TARGET
;;; puts it back where it was picked up from (CRAM's object-in-hand and old object pose).

(defvar *gripped-objects* (make-hash-table :test 'eq :synchronized t)
  "Object name -> (DESIGNATOR . POSE): the designator the object was gripped with and its map
pose at that moment, where a placing action without a target puts it back.")

(defun note-gripped-object (object)
  "Record the object designator OBJECT and its current map pose as it is gripped."
  (let ((name (object-designator-name object)))
    (setf (gethash name *gripped-objects*)
          (cons object (ignore-errors (object-pose-in-map object))))))

(defun held-objects (&optional arm)
  "The objects an end effector of the robot carries, as (NAME ARM GRASP), for ARM or all arms."
  (let ((robot (btr:get-robot-object)))
    (when robot
      (loop for (name link nil grasp) in (btr:attached-objects robot)
            for holder = (find link (robot-arms) :key #'end-effector-link :test #'equal)
            when (and holder (or (null arm) (eq holder arm)))
              collect (list name holder grasp)))))

(defun held-object-designator (name)
  "The designator NAME was gripped with, or a fresh one naming it and its type."
  (let ((record (gethash name *gripped-objects*)))
    (if record
        (car record)
        (let ((o (btr:object btr:*current-bullet-world* name)))
          (desig:make-designator :object `((:type ,(or (and o (btr:item-type o)) :object))
                                           (:name ,name)))))))

(defun placing-object-and-arm (d)
  "The object designator and the arm of the placing action D: as given, else from the hand."
  (let* ((object (prop d :object))
         (given (prop d :arm))
         (arm (cond ((and given (listp given)) (check-arm (first given)))
                    (given (check-arm given)))))
    (when (and object (not (typep object 'desig:object-designator)))
      (pp-error "The placing action ~s: OBJECT is ~s, expected an object designator, or no ~
                 OBJECT to place what the hand holds." d object))
    (if object
        (values object
                (or arm (first (arms-holding (object-designator-name object)))
                    (pp-error "The placing action ~s: no ARM given and no arm holds ~s."
                              d (object-designator-name object))))
        (let ((held (held-objects arm)))
          (cond ((null held)
                 (pp-error "The placing action ~s has no OBJECT, and ~:[no arm holds ~
                            anything~;~:*the ~s arm holds nothing~]." d arm))
                ((rest held)
                 (pp-error "The placing action ~s has no OBJECT, and the arms hold ~{~s~^ and ~}: ~
                            say which with (arm ...)." d (mapcar #'first held)))
                (t (values (held-object-designator (first (first held)))
                           (second (first held)))))))))

(defun placing-default-target (object)
  "A location designator at the pose OBJECT had when it was gripped."
  (let* ((name (object-designator-name object))
         (pose (cdr (gethash name *gripped-objects*))))
    (unless pose
      (pp-error "A placing action without TARGET puts the object back where it was picked up, ~
                 but that is not known for ~s (it was not gripped by a picking-up action); ~
                 give (target (a location (pose ...)))." name))
    (let ((?pose (map-stamped pose)))
      (desig:a location (pose ?pose)))))

(defun placing-groundings (d)
  (multiple-value-bind (object arm) (placing-object-and-arm d)
    (let* ((target (or (prop d :target) (placing-default-target object)))
           (type (object-designator-type object))
           (grasp (or (prop d :grasp)
                      (third (find (object-designator-name object) (held-objects arm) :key #'first))
                      (first (man-int:object-type-grasps type arm))))
           (target-pose (placing-target-pose object type target))
           (hold (relative-transform (object-pose-in-map object) (tool-pose-in-map arm)))
           (trajectory (man-int:get-action-trajectory :placing arm grasp type target-pose
                                                      :object-to-gripper hold)))
      (list (resolved 'place :placing
                      `((:arm ,arm) (:grasp ,grasp) (:object ,object) (:target ,target)
                        (:target-pose ,(map-stamped target-pose))
                        (:trajectory ,trajectory)))))))

(def-action-grounding :placing (d)
  (placing-groundings d))

;;; Coming to rest: a released object falls onto what is below it, as in CRAM, where the
;;; belief state simulates the world after a release.

(defparameter *settling-seconds* 2d0
  "Seconds of physics simulated after an object is released.")
(defparameter *settling-drop* 0.2d0
  "The largest gap (metres) between a released object and the surface below it that is closed
by lowering the object before the simulation; a larger gap is left to the physics.")

(defun settle-released-object (name)
  "Let the released object NAME come to rest: when it hovers above a surface (up to
*SETTLING-DROP*), lower it onto it, then simulate *SETTLING-SECONDS* of physics, the robot
taking no part in it."
  (let* ((world btr:*current-bullet-world*)
         (o (btr:object world name)))
    (when o
      (multiple-value-bind (lo hi) (btr:aabb o)
        (let* ((x (/ (+ (cl-transforms:x lo) (cl-transforms:x hi)) 2))
               (y (/ (+ (cl-transforms:y lo) (cl-transforms:y hi)) 2))
               (bottom (cl-transforms:z lo))
               (support (support-height-below x y (+ bottom 0.005d0) :ignore (list name)))
               (gap (and support (- bottom support))))
          (when (and gap (< 0 gap *settling-drop*))
            (let ((pose (btr:pose o)))
              (setf (btr:pose o)
                    (cl-transforms:make-pose
                     (cl-transforms:v- (cl-transforms:origin pose)
                                       (cl-transforms:make-3d-vector 0 0 (- gap 0.0005d0)))
                     (cl-transforms:orientation pose)))))))
      ;; the robot takes no part: its open gripper still stands around the object (and may
      ;; touch a neighbour), and as a body that never yields it would throw them about
      (let ((robot (btr:get-robot-object)))
        (if robot
            (btr:call-without-collisions robot (lambda () (btr:simulate world *settling-seconds*)))
            (btr:simulate world *settling-seconds*))))))

(defun place (&key arm object target target-pose trajectory &allow-other-keys)
  "Put OBJECT held by ARM at TARGET-POSE along TRAJECTORY (:REACHING, :PUTTING, :RETRACTING):
look, reach and put (failures propagate), open the gripper, record the release in the belief,
where the object comes to rest on the surface below it, record its new location, retract
(failures ignored) and park the arm."
  (let ((?target-pose target-pose) (?arm arm))
    (log-pp 'place "Looking")
    (handler-case
        (exe:perform (desig:an action (type looking)
                               (target (desig:a location (pose ?target-pose)))))
      (common-fail:ptu-low-level-failure (e)
        (cpl:log-message :warn '(pick-place place) "~a~%Ignoring." e)))
    (log-pp 'place "Reaching")
    (perform-arm-action :reaching arm (man-int:get-traj-poses-by-label trajectory :reaching)
                        :log-tag 'place)
    (log-pp 'place "Putting")
    (with-object-being-placed (object target)
      (perform-arm-action :putting arm (man-int:get-traj-poses-by-label trajectory :putting)
                          :log-tag 'place))
    (log-pp 'place "Opening gripper")
    (exe:perform (desig:an action (type releasing) (gripper ?arm)))
    (log-pp 'place "Retract grasp in knowledge base")
    (coe:on-event (make-instance 'cpoe:object-detached-robot
                                 :arm arm :object-name (object-designator-name object)
                                 :object-designator object))
    (remhash (object-designator-name object) *gripped-objects*)
    (settle-released-object (object-designator-name object))
    (log-pp 'place "Updating object location in knowledge base")
    (coe:on-event (make-instance 'cpoe:object-location-changed
                                 :object-designator object
                                 :location-designator (and (typep target 'desig:designator)
                                                           target)))
    (log-pp 'place "Retracting")
    (perform-arm-action :retracting arm (man-int:get-traj-poses-by-label trajectory :retracting)
                        :ignore-failures t :log-tag 'place)
    (log-pp 'place "Parking")
    (exe:perform (desig:an action (type parking-arms) (arms (?arm))))
    object))

;;; ---- getting into reach ---------------------------------------------------------------------

(defparameter *reach-forward* 0.6d0
  "Metres in front of the base at which DRIVE-TOWARDS-OBJECT-PLAN puts the object.")
(defparameter *reach-sideways* 0.15d0
  "Metres towards the arm's side at which DRIVE-TOWARDS-OBJECT-PLAN puts the object.")

(defun drive-towards-object-plan (object &key (arm :right) &allow-other-keys)
  "Drive, keeping the robot's heading, so that OBJECT lies *REACH-FORWARD* metres ahead and
*REACH-SIDEWAYS* metres towards ARM's side of the base."
  (check-arm arm)
  (let* ((robot (robot-pose-in-map))
         (q (cl-transforms:orientation robot))
         (object-position (cl-transforms:origin (object-pose-in-map object)))
         (offset (cl-transforms:rotate
                  q (cl-transforms:make-3d-vector *reach-forward*
                                                  (if (eq arm :left) *reach-sideways*
                                                      (- *reach-sideways*))
                                                  0)))
         (goal (cl-transforms:v- object-position offset))
         (?pose (cl-transforms-stamped:make-pose-stamped
                 cram-tf:*fixed-frame* 0d0
                 (cl-transforms:make-3d-vector (cl-transforms:x goal) (cl-transforms:y goal) 0)
                 q)))
    (exe:perform (desig:an action (type going) (target (desig:a location (pose ?pose)))))))
