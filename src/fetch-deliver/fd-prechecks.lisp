;;;; Projection pre-checks: before a manipulation is committed, its tool poses are tried in the
;;;; belief state (inverse kinematics and collisions, as the motion itself would do) and the
;;;; robot is put back; only a solution that works is performed.

(in-package :cram-fetch-deliver-plans)

(defparameter *picking-up-check-samples* 30
  "How many (arm, grasp) solutions of a picking-up action the pre-check tries.")
(defparameter *placing-check-samples* 20
  "How many solutions of a placing target the pre-check tries.")

(defun call-restoring-robot (thunk)
  "Call THUNK and put the robot's base, joints and attached objects back afterwards."
  (let* ((robot (btr:get-robot-object))
         (state (urdf-proj::robot-state-vectors robot)))
    (unwind-protect (funcall thunk)
      (urdf-proj::restore-robot-state robot state))))

(defparameter *precheck-base-offsets* '(0d0 -0.1d0 0.1d0)
  "The base offsets (metres) the pre-checks try, fewer than the motions do
(URDF-PROJ::*BASE-OFFSETS*): a pre-check may reject what the motion would reach, never the
reverse, and gives up an unreachable pose sooner.")

(defparameter *precheck-torso-step* 0.15d0
  "The step (metres) between the torso heights the pre-checks try, coarser than the motions'
(URDF-PROJ::*TORSO-STEP*).")

(defparameter *precheck-ik-restarts* 3
  "Random restarts of each IK call of the coarse pre-checks (the motions make
URDF-PROJ::*REACH-IK-RESTARTS*, 8): of the goals the pre-checks of seeded household runs
reached, 1 % needed more than 3 restarts, and a goal that no start reaches takes 4 descents
instead of 9.")

(defun tcp-poses-reachable-p (arm poses &key (coarse t))
  "True when the tool frame of ARM reaches each of POSES in turn in the belief state as the
moving-tcp motion would (base offsets, torso heights, collision check; with COARSE, only the
base offsets of *PRECHECK-BASE-OFFSETS* and torso heights *PRECHECK-TORSO-STEP* apart); the
robot is put back. The path to each pose is checked for sweeps only under
URDF-PROJ:*SWEEP-CHECK* :FAIL, where a sweep would fail the motion: under :WARN the motion
itself reports them, when it is performed."
  (call-restoring-robot
   (lambda ()
     (handler-case
         (urdf-proj::with-tcp-in-ee-kept
          (let ((urdf-proj::*base-offsets* (if coarse *precheck-base-offsets*
                                               urdf-proj::*base-offsets*))
                (urdf-proj::*torso-step* (if coarse *precheck-torso-step* urdf-proj::*torso-step*))
                (urdf-proj::*reach-ik-restarts* (if coarse *precheck-ik-restarts*
                                                    urdf-proj::*reach-ik-restarts*))
                (urdf-proj:*sweep-check* (and (eq urdf-proj:*sweep-check* :fail) :fail)))
            (dolist (pose poses t)
              (urdf-proj::reach-tcp-poses (list (cons arm (pp-plans:pose-in-map pose))) nil t nil))))
       (common-fail:manipulation-low-level-failure () nil)))))

(defun trajectory-reachable-p (arm trajectory labels &key (coarse t))
  (tcp-poses-reachable-p arm (loop for label in labels
                                   append (man-int:get-traj-poses-by-label trajectory label))
                         :coarse coarse))

(defun call-with-gripper-opening (arm opening thunk)
  "Call THUNK with the gripper of ARM opened to OPENING (metres, as the setting-gripper action
the picking-up action opens it to while reaching; NIL: as it is), and put the gripper back
afterwards. Checked in the belief state."
  (if (null opening)
      (funcall thunk)
      (let* ((robot (btr:get-robot-object))
             (before (mapcar (lambda (j) (list j (btr:joint-state robot j)))
                             (urdf-proj::gripper-joints arm))))
        (unwind-protect
             (progn
               (btr:set-robot-state-from-joints
                (urdf-proj::gripper-joint-states arm opening robot) robot)
               (funcall thunk))
          (btr:set-robot-state-from-joints before robot)))))

(defun check-picking-up-collisions (object &key arms grasps any)
  "The first (arm grasp) of picking up OBJECT, for ARMS and GRASPS (NIL: any), whose grasp
poses the arm reaches free of collisions with its gripper opened as the action opens it, among
up to *PICKING-UP-CHECK-SAMPLES*; signals OBJECT-UNREACHABLE when none does. With ANY (when
only whether some grasp is reachable matters) the grasps are first tried with the pre-checks'
coarse base offsets and torso heights, which find a reachable grasp sooner when there is one
(the coarse candidates are some of the full ones), and only when none is found there with all
candidates: the answer can then be another grasp than the first reachable one. ANY :COARSE
tries the coarse candidates only."
  (let* ((?object object)
         (groundings (pp-plans:ground-action
                      :picking-up (desig:an action (type picking-up) (object ?object))))
         (tried 0))
    (flet ((try (coarse)
             (setf tried 0)
             (dolist (grounding groundings)
               (let* ((resolved (second grounding))
                      (arm (desig:desig-prop-value resolved :arm))
                      (grasp (desig:desig-prop-value resolved :grasp)))
                 (when (and (or (null arms) (member arm arms)) (or (null grasps) (member grasp grasps)))
                   (when (>= (incf tried) *picking-up-check-samples*) (return))
                   ;; the hand as it closes in on the object: open as wide as the action opens it
                   (when (call-with-gripper-opening
                          arm (desig:desig-prop-value resolved :gripper-opening)
                          (lambda ()
                            (pp-plans::with-object-being-grasped (object)
                              (trajectory-reachable-p arm (desig:desig-prop-value resolved :trajectory)
                                                      '(:grasping) :coarse coarse))))
                     (return-from check-picking-up-collisions (list arm grasp))))))))
      (when any (try t))
      (unless (eq any :coarse) (try nil)))
    (cpl:fail 'common-fail:object-unreachable
              :description (format nil "No grasp of ~a with the ~{~(~a~)~^ or ~} arm is reachable ~
                                        free of collisions from here (~d tried)."
                                   (object-text object) (or arms (pp-plans::robot-arms)) tried))))

(defun placeable-at-p (object arm candidate regrasp)
  "True when ARM puts OBJECT down at the current solution of the location designator CANDIDATE
free of collisions, as CHECK-PLACING-COLLISIONS checks a sample (with REGRASP, also that the
object can be grasped again there)."
  (let ((?object object) (?arm arm) (?target candidate))
    (and (within-placing-reach-p (desig:reference candidate))
         (let* ((grounding (first (pp-plans:ground-action
                                   :placing (desig:an action (type placing)
                                                      (object ?object) (arm ?arm)
                                                      (target ?target)))))
                (trajectory (desig:desig-prop-value (second grounding) :trajectory)))
           (and (pp-plans::with-object-being-placed (object candidate)
                  (trajectory-reachable-p arm trajectory '(:reaching :putting :retracting)))
                (object-fits-at-p object candidate)
                (or (not regrasp) (regraspable-at-candidate-p object candidate)))))))

(defun regraspable-at-candidate-p (object candidate)
  "True when OBJECT, put down at the current solution of the location designator CANDIDATE,
can be grasped again from where the robot stands (OBJECT-REGRASPABLE-AT-P)."
  (object-regraspable-at-p object (pp-plans:pose-in-map (desig:reference candidate))))

(defvar *placing-fallback* nil
  "NIL, or a cons whose car CHECK-PLACING-COLLISIONS sets when it finds no sample that leaves
*PLACES-TO-LEAVE* room while *REQUIRE-ROOM* is true: :NONE when no sample could be put down,
else the function of no arguments (FIND-PLACING-SAMPLE's second value) that finds the sample it
would have taken without that requirement, asking the re-grasp check only then
\(PLACING-FALLBACK-POSE calls it with the robot where the check had it).")

(defun check-placing-collisions (object arm target &key first)
  "The first of up to *PLACING-CHECK-SAMPLES* solutions of TARGET (a location designator) at
which ARM puts OBJECT down free of collisions (the designator of that solution; samples beyond
*PLACING-REACH* of the base are not tried; while *PLACES-TO-LEAVE* is not empty, the first that
also leaves them room, see FIND-PLACING-SAMPLE): as CRAM's check, the hand reaches the approach,
the put-down and the retreat poses (so the hand can also come back for the object the way it
left). FIRST (a map pose, a sample of TARGET a pre-check accepted from where the robot stands)
is tried before the others; when it passes, the result is a location designator of that pose,
with T as a second value.
Signals OBJECT-UNDELIVERABLE when none passes, so that the delivery tries another base pose."
  (urdf-proj::with-tcp-in-ee-kept
    (%check-placing-collisions object arm target first)))

(defun %check-placing-collisions (object arm target first)
  (let ((regrasp (regrasp-check-target-p target)))
    (when first
      (let* ((?pose first) (candidate (desig:a location (pose ?pose))))
        (when (placeable-at-p object arm candidate regrasp)
          (return-from %check-placing-collisions (values candidate t)))))
    (multiple-value-bind (found best)
        (find-placing-sample (lambda (candidate)
                               (placeable-at-p object arm candidate nil))
                             target *placing-check-samples*
                             ;; the dearest test last, and only of a sample that could be taken
                             :final (and regrasp (lambda (candidate)
                                                   (regraspable-at-candidate-p object candidate)))
                             :score (and *places-to-leave*
                                         (lambda (candidate)
                                           (room-left object candidate)))
                             :best (length *places-to-leave*)
                             :require-best *require-room*)
      (when found (return-from %check-placing-collisions found))
      (when *placing-fallback*
        ;; what a check that does not require room would take from these samples, found only
        ;; when such a check asks for it (a later base pose that leaves room makes it moot)
        (setf (car *placing-fallback*) (or best :none))))
    (cpl:fail 'common-fail:object-undeliverable
              :description (format nil "~a cannot be put down with the ~(~a~) arm at any sample of ~
                                        ~a from here." (object-text object) arm target))))

;;; An object put down on a surface (the table being set) is picked up from there again later
;;; (the table is cleared in reverse order, so whatever could block it then is already there
;;; when it is put down): a place from which no grasp of it is reachable is rejected when it
;;; is chosen, so that another sample or base pose is taken.

(defparameter *check-regrasping* t
  "When true, the placing pre-check also requires that the object, once put down at a sample
of a surface target (REGRASP-CHECK-TARGET-P), can be grasped again from where the robot
stands (OBJECT-REGRASPABLE-AT-P), with its gripper opened as picking it up opens it. The
table is cleared in reverse order, so what stands around the object when it is put down still
stands there when it is fetched; together with the base pose it was put down from (offered
first to that fetch), a place the open hand cannot reach again is not taken. NIL: any place
the object can be put down at.")

(defvar *regrasp-grasps* '()
  "An alist of object type -> the grasps a later fetch of an object of that type, put down now,
will be limited to (as a table is cleared with fewer grasps than it was set with); the re-grasp
check (OBJECT-REGRASPABLE-AT-P) tries only those. Types not listed: any grasp.")

(defun regrasp-grasps (object)
  "The grasps of *REGRASP-GRASPS* for the type of the object designator OBJECT (NIL: any)."
  (let ((type (desig:desig-prop-value object :type)))
    (and type (second (assoc type *regrasp-grasps*
                             :test (lambda (a b) (string= (symbol-name a) (symbol-name b))))))))

(defun surface-place-p (target)
  "True when TARGET is a location designator of a place on a surface (ON it, or relative to an
object there), neither stable (TARGET-STABLE-P: attachments, ABOVE) nor IN a container, nor
given poses (POSE, POSES)."
  (and (typep target 'desig:location-designator)
       (not (prop target :pose))
       (not (prop target :poses))
       (not (target-stable-p target))
       (not (prop target :in))))

(defun regrasp-check-target-p (target)
  "True when an object put down at TARGET (a location designator) must be graspable there
again: *CHECK-REGRASPING* is on and TARGET is a place on a surface (SURFACE-PLACE-P). A target
of given poses is the caller's choice and not checked."
  (and *check-regrasping* (surface-place-p target)))

(defun call-with-object-let-go-at (object pose thunk)
  "Call THUNK with OBJECT (an object designator of the belief state, held by the robot) let go
and standing at POSE (map); afterwards the object is put back and attached as it was, and the
robot is put back. Returns THUNK's value, or T when there is no such object or robot."
  (let* ((name (designator-object-name object))
         (robot (btr:get-robot-object))
         (o (and name (btr:object btr:*current-bullet-world* name))))
    (if (or (null o) (null robot))
        t                               ; nothing to check against
        (let ((attachments (remove name (btr:attached-objects robot)
                                   :key #'first :test-not #'eq))
              (before (btr:pose o)))
          (call-restoring-robot
           (lambda ()
             (unwind-protect
                  (progn
                    (btr:detach-object robot o)
                    (setf (btr:pose o) pose)
                    (funcall thunk o))
               (setf (btr:pose o) before)
               (dolist (a attachments)
                 (destructuring-bind (n link loose grasp) a
                   (declare (ignore n))
                   (btr:attach-object robot o :link link :loose loose :grasp grasp))))))))))

(defun resting-pose (object pose)
  "POSE (map), a costmap's sample for putting OBJECT (an object designator of the belief state,
held) down upright, lowered to where OBJECT comes to rest: the sample's height above the
surface is the larger of its upright height and its height as held (COSTMAP::OBJECT-FOOTPRINT),
and a flat object held from below (a spoon) drops the difference when it is let go."
  (let* ((name (designator-object-name object))
         (o (and name (btr:object btr:*current-bullet-world* name))))
    (if (null o)
        pose
        (let ((lift (nth-value 1 (costmap::object-footprint o)))
              (upright (- (cl-transforms:z (btr:local-aabb o))))
              (origin (cl-transforms:origin pose)))
          (cl-transforms:make-pose
           (cl-transforms:make-3d-vector (cl-transforms:x origin) (cl-transforms:y origin)
                                         (- (cl-transforms:z origin) (max 0d0 (- lift upright))))
           (cl-transforms:orientation pose))))))

(defun object-regraspable-at-p (object pose)
  "True when OBJECT (an object designator of the belief state, held by the robot), let go at
POSE (map) and come to rest below it (RESTING-POSE), can be grasped by the robot from where it
stands, with any arm and any grasp a later fetch may use (REGRASP-GRASPS), with the pre-checks'
coarse base offsets and torso heights as the fetch's choice of a base pose checks it
\(CHECK-PICKING-UP-COLLISIONS :ANY :COARSE, OBJECT-GRASPABLE-FROM-P), and is seen from there
\(OBJECT-VISIBLE-FROM-P: the fetch perceives it again before it grasps it). Checked in the
belief state (CALL-WITH-OBJECT-LET-GO-AT)."
  (call-with-object-let-go-at
   object (resting-pose object pose)
   (lambda (o)
     (declare (ignore o))
     (and (handler-case (progn (check-picking-up-collisions object :grasps (regrasp-grasps object)
                                                                   :any :coarse)
                               t)
            ((or common-fail:object-unreachable pp-plans:pick-place-error) () nil))
          (object-visible-from-p object (btr:pose (btr:get-robot-object)))))))

(defparameter *placing-penetration* 0.01d0
  "Metres an object put down may reach into another body (the surface it is put on aside, the
put-down pose rests on it) before the place counts as taken.")

(defun supporting-part-p (object link-index height)
  "True when the part LINK-INDEX of OBJECT (-1: the whole body) has its top below HEIGHT: a
surface under what stands at HEIGHT, not a wall beside it."
  (multiple-value-bind (lo hi) (if (and (btr:robot-object-p object) (>= link-index 0))
                                   (btr:aabb object link-index)
                                   (btr:aabb object))
    (declare (ignore lo))
    (< (cl-transforms:z hi) height)))

(defun object-penetrations (object pose)
  "What OBJECT (held by the robot), let go at POSE (map), reaches into by more than
*PLACING-PENETRATION*, the robot and the surfaces under the object's origin aside (a put-down
pose rests on its surface; settling lifts it out): a list of (object-name link-name). Checked
in the belief state (CALL-WITH-OBJECT-LET-GO-AT)."
  (let ((robot (btr:get-robot-object))
        (height (cl-transforms:z (cl-transforms:origin pose))))
    (call-with-object-let-go-at
     object pose
     (lambda (o)
       (let ((world btr:*current-bullet-world*))
         (remove-duplicates
          (loop for (nil nil other other-link) in (cram-native:object-contacts
                                                   (btr::world-handle world) (btr:object-handle o)
                                                   :threshold (- *placing-penetration*)
                                                   :except (and robot (list (btr:object-handle robot))))
                for other-object = (btr::object-by-handle world other)
                when (and other-object (not (supporting-part-p other-object other-link height)))
                  collect (list (btr:name other-object) (btr::link-name-of other-object other-link)))
          :test #'equal))))))

(defun object-fits-at-p (object target)
  "True when OBJECT (held by the robot), put down at the current solution of TARGET as placing
puts it (PP-PLANS::PLACING-TARGET-POSE), reaches into nothing: a release inside a shelf board
or the dishwasher tray's wall would make the physics throw it out."
  (let ((penetrations (object-penetrations
                       object (pp-plans::placing-target-pose
                               object (pp-plans:object-designator-type object) target))))
    (or (eq penetrations t) (null penetrations))))

(defun object-visible-from-p (object pose)
  "True when the robot, standing at POSE (map) and looking at OBJECT (an object designator of
the belief state), sees it (BTR:OBJECT-VISIBLE-P, the neck clamped to its limits). Checked in
the belief state; the robot is put back."
  (let* ((name (designator-object-name object))
         (o (and name (btr:object btr:*current-bullet-world* name))))
    (or (null o)                        ; nothing to check against
        (call-restoring-robot
         (lambda ()
           (let* ((robot (btr:get-robot-object))
                  (joints (urdf-proj:neck-joints))
                  (camera (urdf-proj:camera-frame robot)))
             (setf (btr:pose robot) (pp-plans:pose-in-map pose))
             ;; the neck solver passes through values beyond the limits: no warnings of those
             (let ((values (handler-bind ((warning #'muffle-warning))
                             (urdf-proj::neck-angles-towards robot joints camera
                                                             (cl-transforms:origin (btr:pose o))))))
               (btr:set-robot-state-from-joints
                (mapcar (lambda (j v) (list j (urdf-proj::clamp-joint robot j v))) joints values)
                robot))
             (btr:object-visible-p btr:*current-bullet-world*
                                   (btr:link-pose robot camera) o)))))))

(defun object-graspable-from-p (object pose &key arms grasps)
  "True when the robot, standing at POSE (map), reaches a grasp of OBJECT with one of ARMS and
GRASPS (NIL: any) free of collisions with the pre-checks' coarse base offsets and torso heights
\(CHECK-PICKING-UP-COLLISIONS :ANY :COARSE): a base pose from which a grasp needs the base
moved farther or the torso at a height between those is passed over for the next one, which
costs less than searching every candidate of every grasp where none is reachable. Checked in the
belief state; the robot is put back."
  (call-restoring-robot
   (lambda ()
     (setf (btr:pose (btr:get-robot-object)) (pp-plans:pose-in-map pose))
     (handler-case (progn (check-picking-up-collisions object :arms arms :grasps grasps :any :coarse) t)
       (common-fail:object-unreachable () nil)))))

(defparameter *placing-base-check-samples* 8
  "How many target samples the choice of a delivery's base pose tries from each candidate pose
\(two places when a surface gives each place in four orientations). A third place rarely
rescues a base pose whose first two fail, and a rejected base pose costs every sample: in 81
seeded household runs, 8 samples instead of 12 made 27 % fewer placing checks and 12 % fewer
IK calls, and 81 runs succeeded instead of 80.")

(defparameter *placing-reach* 1.0d0
  "Metres (horizontally, from the base's origin) beyond which the placing pre-check does not
try a target sample: no arm of the robot reaches that far.")

(defun within-placing-reach-p (pose)
  "True when the map POSE is within *PLACING-REACH* of the robot's base horizontally."
  (let ((p (cl-transforms:origin (pp-plans:pose-in-map pose)))
        (b (cl-transforms:origin (btr:pose (btr:get-robot-object)))))
    (<= (sqrt (+ (expt (- (cl-transforms:x p) (cl-transforms:x b)) 2)
                 (expt (- (cl-transforms:y p) (cl-transforms:y b)) 2)))
        *placing-reach*)))

(defun target-reachable-from (target from)
  "TARGET (a location designator), at its current solution's description, restricted to the
places reachable from FROM (the robot's name or a base pose): CRAM's T' = target +
(reachable-from robot). A fresh designator, not equated with TARGET."
  (desig:extend-designator-properties (desig:current-desig target) `((:reachable-from ,from))))

(defun placing-fallback-key (object arm target pose)
  "The key under which *BASE-POSE-VERDICTS* keeps what the placing check at the base POSE
found without room for the later objects (OBJECT-PLACEABLE-FROM-P)."
  (list* :placing-fallback (base-pose-key pose) (robot-joints-key)
         (place-key (list object arm target))))

(defun object-placeable-from-p (object arm target pose)
  "The map pose of the first of *PLACING-BASE-CHECK-SAMPLES* solutions of TARGET within reach
(TARGET-REACHABLE-FROM) at which the robot, standing at POSE (map), puts OBJECT held in ARM
down free of collisions; NIL when there is none. Checked in the belief state; the robot is put
back. Within WITH-BASE-POSE-VERDICTS, a check while *REQUIRE-ROOM* is true that finds no
sample leaving the later objects room keeps what it would have taken without that requirement
\(or that nothing could be put down), and the check of the same base pose, robot state and
place without the requirement answers from that instead of drawing samples again. The samples'
re-grasp checks that this answer still needs are made only then (PLACING-FALLBACK-POSE): when
another base pose leaves room, they are never made."
  (let* ((key (and (base-pose-verdicts-p) (placing-fallback-key object arm target pose)))
         (kept (and key (not *require-room*) (base-pose-verdict key))))
    (when (functionp kept)
      (setf kept (setf (base-pose-verdict key) (placing-fallback-pose kept pose))))
    (cond ((eq kept :none) nil)
          (kept (cl-transforms-stamped:pose->pose-stamped cram-tf:*fixed-frame* 0d0 kept))
          (t (let* ((*placing-fallback* (and key *require-room* (list nil)))
                    (found (check-placing-from object arm target pose)))
               (when (and *placing-fallback* (car *placing-fallback*))
                 (setf (base-pose-verdict key) (car *placing-fallback*)))
               found)))))

(defun placing-fallback-pose (find pose)
  "The map pose of the sample FIND, a placing check's deferred fallback (*PLACING-FALLBACK*),
finds with the robot standing at the base POSE (map) as that check had it, or :NONE when it
finds none; NIL when its checks fail as a placing check's failures are caught
\(CHECK-PLACING-FROM), so that the check is made afresh. The robot is put back."
  (call-restoring-robot
   (lambda ()
     (setf (btr:pose (btr:get-robot-object)) (pp-plans:pose-in-map pose))
     (handler-case (let ((sample (urdf-proj::with-tcp-in-ee-kept (funcall find))))
                     (if sample (pp-plans:pose-in-map (desig:reference sample)) :none))
       ((or common-fail:object-undeliverable desig:designator-error) () nil)))))

(defun check-placing-from (object arm target pose)
  (call-restoring-robot
   (lambda ()
     (let ((base (pp-plans:pose-in-map pose)))
       (setf (btr:pose (btr:get-robot-object)) base)
       (let ((*placing-check-samples* *placing-base-check-samples*)
             (here (target-reachable-from target (cl-transforms-stamped:pose->pose-stamped
                                                  cram-tf:*fixed-frame* 0d0 base))))
         (unwind-protect
              (handler-case
                  (let ((accepted (check-placing-collisions object arm here)))
                    (cl-transforms-stamped:pose->pose-stamped
                     cram-tf:*fixed-frame* 0d0 (pp-plans:pose-in-map (desig:reference accepted))))
                ((or common-fail:object-undeliverable desig:designator-error) () nil))
           ;; one costmap per candidate base pose: not kept in the cache
           (costmap:forget-designator-costmap here)))))))
