;;;; Navigating (with a collision pre-check of the base pose) and turning towards a target (the
;;;; base turns when the neck cannot reach it).

(in-package :cram-fetch-deliver-plans)

(defparameter *navigation-check-samples* 30
  "How many solutions of a navigation location the pre-check tries before it gives up.")

(defun base-pose-collisions (pose)
  "The names of what the robot, standing at POSE (map), touches but the floor and what it
holds. Checked in the belief state; the robot is put back where it was."
  (let* ((robot (btr:get-robot-object))
         (before (btr:pose robot)))
    (unwind-protect
         (progn (setf (btr:pose robot) (pp-plans:pose-in-map pose))
                (urdf-proj::robot-collisions :robot robot))
      (setf (btr:pose robot) before))))

(defvar *base-pose-verdicts* nil
  "NIL, or an EQUAL hash table of the base pose verdicts of the navigation pre-checks of one
fetch or delivery (WITH-BASE-POSE-VERDICTS): (pose robot-joints what-is-checked) -> whether the
pose was accepted. Its retry levels walk overlapping runs of the same solutions (a relocation
takes the next solution, the pre-check then tries up to *NAVIGATION-CHECK-SAMPLES* from there);
a pose already judged in the same state is not checked again.")

(defvar *base-pose-verdicts-lock* (sb-thread:make-mutex :name "base pose verdicts"))

(defun base-pose-verdicts-p ()
  "True within WITH-BASE-POSE-VERDICTS."
  (and *base-pose-verdicts* t))

(defun base-pose-verdict (key)
  "What *BASE-POSE-VERDICTS* keeps under KEY (NIL: nothing, or outside WITH-BASE-POSE-VERDICTS);
second value: whether it keeps anything."
  (if *base-pose-verdicts*
      (sb-thread:with-mutex (*base-pose-verdicts-lock*) (gethash key *base-pose-verdicts*))
      (values nil nil)))

(defun (setf base-pose-verdict) (value key)
  "Keep VALUE under KEY in *BASE-POSE-VERDICTS* (nothing outside WITH-BASE-POSE-VERDICTS)."
  (when *base-pose-verdicts*
    (sb-thread:with-mutex (*base-pose-verdicts-lock*)
      (setf (gethash key *base-pose-verdicts*) value)))
  value)

(defmacro with-base-pose-verdicts (() &body body)
  "Run BODY with a fresh *BASE-POSE-VERDICTS* table (kept when one is already bound)."
  `(let ((*base-pose-verdicts* (or *base-pose-verdicts* (make-hash-table :test 'equal))))
     ,@body))

(defun rounded (x &optional (unit 1d-4))
  (round x unit))

(defun base-pose-key (pose)
  "The map POSE as integers (0.1 mm, 1e-4 rad of yaw)."
  (let* ((p (pp-plans:pose-in-map pose)) (o (cl-transforms:origin p)))
    (list (rounded (cl-transforms:x o)) (rounded (cl-transforms:y o))
          (rounded (cl-transforms:get-yaw (cl-transforms:orientation p))))))

(defun robot-joints-key ()
  "The robot's joint positions as integers (1e-4), for the verdict cache: a verdict holds only
for the arms, torso and grippers it was found with."
  (let ((robot (btr:get-robot-object)))
    (map 'list (lambda (x) (round (* (the double-float x) 1d4)))
         (the (simple-array double-float (*)) (btr:robot-joint-values robot)))))

(defun judge-base-pose (pose accept what)
  "(values accepted hits) for the robot standing at POSE: HITS, what it touches there, and
ACCEPTED, NIL unless it is free there and ACCEPT (a function of the pose) accepts it (then
ACCEPT's value). A pose judged before within *BASE-POSE-VERDICTS* for the same robot joints
and WHAT (a list naming what ACCEPT checks) gives the same verdict without a check."
  (let ((key (and (base-pose-verdicts-p) (list* (base-pose-key pose) (robot-joints-key) what))))
    (multiple-value-bind (verdict found) (base-pose-verdict key)
      (if found
          (values (car verdict) (cdr verdict))
          (let* ((hits (base-pose-collisions pose))
                 (accepted (and (null hits) (or (funcall accept pose) nil))))
            (setf (base-pose-verdict key) (cons accepted hits))
            (values accepted hits))))))

(defun check-navigating-collisions (location &key (accept (constantly t)) what)
  "The projection pre-check of navigating: the first of up to *NAVIGATION-CHECK-SAMPLES*
solutions of LOCATION (a location designator) at which the robot is free of collisions and
that ACCEPT (a function of the base pose) accepts: the designator of that solution, equated
with LOCATION, and ACCEPT's value there as a second value. Signals
NAVIGATION-GOAL-IN-COLLISION when there is none. WHAT names what ACCEPT checks (a list,
compared with EQUAL): verdicts are reused within WITH-BASE-POSE-VERDICTS for the same WHAT."
  (let ((current location))
    (loop repeat *navigation-check-samples*
          while current
          do (let ((pose (handler-case (desig:reference current)
                           (desig:designator-error () (return)))))
               (multiple-value-bind (accepted hits) (judge-base-pose pose accept what)
                 (when accepted
                   (return-from check-navigating-collisions (values current accepted)))
                 (when hits
                   (log-fd :warn 'navigate "Navigation goal ~a collides with ~{~s~^, ~}; trying ~
                                            the next solution." (urdf-proj::pose-summary pose) hits)))
               (setf current (desig:next-solution current))))
    (cpl:fail 'common-fail:navigation-goal-in-collision
              :description (format nil "No solution of ~a is free of collisions for the robot."
                                   location))))

(defun object-key (object)
  "For the verdict cache: OBJECT's (an object designator or NIL) name and map pose (0.1 mm)."
  (let* ((name (and object (designator-object-name object)))
         (o (and name (btr:object btr:*current-bullet-world* name))))
    (cond (o (let ((p (cl-transforms:origin (btr:pose o))))
               (list name (rounded (cl-transforms:x p)) (rounded (cl-transforms:y p))
                     (rounded (cl-transforms:z p)))))
          (object (list object)))))

(defun place-key (place)
  "For the verdict cache: PLACE ((object arm target)) as the object's key, the arm and the
target's description. Whether the object can be put down from a base pose does not depend on
which of the target's samples is current (the check draws its own within reach), so the
verdicts hold across a delivery's retries of new target samples."
  (destructuring-bind (object arm target) place
    (list (object-key object) arm (desig:properties (desig:current-desig target)))))

(defvar *placing-hint* nil
  "NIL, or a cons whose car NAVIGATE sets, when it pre-checks a base pose for putting an object
down, to (base-pose . sample-pose): the base pose it drives to and the map pose of the target
sample the check put the object down at from there. Bound by DELIVER, which tries that sample
first (TAKE-PLACING-HINT).")

(defun take-placing-hint ()
  "The sample pose of *PLACING-HINT* when the robot stands at its base pose (0.1 mm, 1e-4 rad);
else NIL. The hint is used up either way."
  (let ((hint (and *placing-hint* (shiftf (car *placing-hint*) nil))))
    (when (and hint (cdr hint) (equal (base-pose-key (car hint))
                                      (base-pose-key (btr:pose (btr:get-robot-object)))))
      (cdr hint))))

(defun navigate (&key location (park-arms t) see grasp place &allow-other-keys)
  "Park the arms (unless PARK-ARMS is NIL), pre-check LOCATION for a collision-free base pose
(NAVIGATION-GOAL-IN-COLLISION when there is none) from which the object designator SEE (when
given) is visible, the object designator GRASP (when given) can be grasped and PLACE (when
given: (object arm target)) can be put down, and drive there; while *PLACES-TO-LEAVE* is not
empty, a base pose from which the object is put down leaving them room is looked for first.
A low-level navigation failure is logged and ignored, as on a real base that plans around
obstacles."
  (when park-arms
    (exe:perform (desig:an action (type parking-arms))))
  (multiple-value-bind (checked accepted)
      (flet ((check ()
               (check-navigating-collisions
                location :what (list (object-key see) (object-key grasp)
                                     (and place (place-key place)) *require-room*)
                         ;; the rendered visibility check last: the grasp and place checks
                         ;; reject more base poses, and a rejected pose then costs no picture
                         ;; (81 seeded household runs: median 508 -> 492 ms, no more IK
                         ;; calls); the value is the place check's (the sample it put the
                         ;; object down at)
                         :accept (lambda (pose)
                                   (let ((placed (and (or (null grasp)
                                                          (object-graspable-from-p grasp pose))
                                                      (or (null place)
                                                          (apply #'object-placeable-from-p
                                                                 (append place (list pose)))))))
                                     (and placed
                                          (or (null see) (object-visible-from-p see pose))
                                          placed))))))
        (if (and place *places-to-leave*)
            ;; a base pose from which the object leaves the later objects room, else any
            (handler-case (let ((*require-room* t)) (check))
              (common-fail:navigation-goal-in-collision () (check)))
            (check)))
    (let ((?location (desig:current-desig checked)))
      (when (and place *placing-hint*)
        ;; the sample of the target the check put the object down at from there
        (setf (car *placing-hint*) (cons (desig:reference ?location) accepted)))
      (handler-case
          (exe:perform (desig:an action (type going) (target ?location)))
        (common-fail:navigation-low-level-failure (e)
          (log-fd :warn 'navigate "Low-level navigation failed: ~a~%Ignoring." e))))))

(defun turn-towards (&key target robot-location &allow-other-keys)
  "Look at TARGET (a location designator). When the neck cannot reach it, turn the base
towards it (driving to ROBOT-LOCATION when given, else turning in place) and look again; a
second neck failure is ignored. An unresolvable target or a failed turn of the base is a
LOOKING-HIGH-LEVEL-FAILURE."
  (handler-case
      (cpl:with-retry-counters ((turn-around-retries 1))
        (cpl:with-failure-handling
            ((common-fail:ptu-low-level-failure (e)
               (log-fd :warn 'turn-towards "~a~%Turning around." e)
               (cpl:do-retry turn-around-retries
                 (turn-base-towards target robot-location)
                 (cpl:retry))
               (log-fd :warn 'turn-towards "Turning around did not help; ignoring the failure.")
               (return-from turn-towards nil)))
          (let ((?target target))
            (exe:perform (desig:an action (type looking) (target ?target))))))
    (desig:designator-error (e)
      (cpl:fail 'common-fail:looking-high-level-failure
                :description (format nil "The look target ~a could not be resolved: ~a" target e)))
    (common-fail:navigation-high-level-failure (e)
      (cpl:fail 'common-fail:looking-high-level-failure
                :description (format nil "Turning towards ~a failed: ~a" target e)))))

(defun turn-base-towards (target robot-location)
  "Turn the robot's base to face TARGET (a location designator), at ROBOT-LOCATION when given."
  (if robot-location
      (let ((?location robot-location))
        (exe:perform (desig:an action (type navigating) (location ?location))))
      (let* ((goal (cl-transforms:origin (pp-plans:pose-in-map (desig:reference target))))
             (here (btr:pose (btr:get-robot-object)))
             (origin (cl-transforms:origin here))
             (yaw (atan (- (cl-transforms:y goal) (cl-transforms:y origin))
                        (- (cl-transforms:x goal) (cl-transforms:x origin))))
             (?pose (cl-transforms-stamped:make-pose-stamped
                     cram-tf:*fixed-frame* 0d0 origin
                     (cl-transforms:axis-angle->quaternion
                      (cl-transforms:make-3d-vector 0 0 1) yaw))))
        (exe:perform (desig:an action (type navigating)
                               (location (desig:a location (pose ?pose)))))))
  (exe:perform (desig:an action (type looking) (direction forward))))
