;;;; Atomic actions: their grounding (one Prolog rule dispatching to GROUND-ACTION methods per
;;;; action type) and their plans, each performing motion designators.

(in-package :cram-mobile-pick-place-plans)

;;; ---- grounding ---------------------------------------------------------------------------------

(defvar *action-types* '()
  "The action types this package grounds.")

(defgeneric ground-action (type designator)
  (:documentation "The groundings of the action DESIGNATOR of TYPE (a keyword): a list of
(plan-function resolved-designator), best first. NIL when TYPE is not handled here."))

(defmethod ground-action (type designator)
  (declare (ignore type designator))
  nil)

(defun action-types ()
  "The action types (keywords) PP-PLANS grounds."
  (reverse *action-types*))

(defmacro def-action-grounding (type (designator) &body body)
  "Define how action designators of TYPE are grounded: BODY returns a list of groundings."
  `(progn
     (pushnew ,type *action-types*)
     (defmethod ground-action ((type (eql ,type)) ,designator)
       ,@body)))

(defun grounding-failed (condition)
  "The plan function of a grounding that could not be computed: signals CONDITION."
  (error condition))

(defun safe-ground-action (type designator)
  (handler-case (ground-action type designator)
    (error (e) (list (list 'grounding-failed e)))))

(defun handled-action-type-p (type)
  (and (member type *action-types*) t))

(def-fact-group pick-place-action-groundings (desig:action-grounding)
  (<- (desig:action-grounding ?designator ?grounding)
    (desig:desig-prop ?designator (:type ?type))
    (lisp-pred handled-action-type-p ?type)
    (lisp-fun safe-ground-action ?type ?designator ?groundings)
    (member ?grounding ?groundings)))

(defun prop (designator key &optional default)
  (multiple-value-bind (value found) (desig:desig-prop-value designator key)
    (if found value default)))

(defun resolved (plan type entries)
  "A grounding (PLAN resolved-action-designator) of TYPE with ENTRIES ((key value)...), the
entries with NIL values left out."
  (list plan (desig:make-designator
              :action (cons (list :type type)
                            (remove-if (lambda (e) (null (second e))) entries)))))

;;; ---- robot, frames and objects -------------------------------------------------------------

(defun current-robot-name ()
  "The name of the robot the plans move: ROB-INT's current robot, else the robot of the
belief state."
  (or rob-int:*robot-name*
      (let ((robot (ignore-errors (btr:get-robot-object))))
        (and robot (btr:name robot)))
      (pp-error "No robot: set one with ROB-INT:SET-ROBOT-NAME or spawn one in the belief state.")))

(defun robot-base-frame ()
  (or (ignore-errors (rob-int::first-solution-value
                      '?frame `(rob-int:robot-base-frame ,(current-robot-name) ?frame)))
      cram-tf:*robot-base-frame*))

(defun robot-pose-in-map ()
  "The robot's base pose in the fixed frame, from the belief state."
  (let ((robot (btr:get-robot-object)))
    (unless robot (pp-error "No robot in the belief state (BTR:*CURRENT-BULLET-WORLD*)."))
    (btr:pose robot)))

(defun base-frame-pose-in-map ()
  "The pose (fixed frame) of the robot's base frame: its link when the robot model has one
(the base frame need not be the model's root, e.g. Pepper's base_link above the footprint it
is rooted at), else the robot's pose."
  (let ((robot (btr:get-robot-object))
        (frame (robot-base-frame)))
    (if (and robot (btr:link-exists-p robot frame))
        (btr:link-pose robot frame)
        (robot-pose-in-map))))

(defun pose-in-map (pose)
  "POSE (a POSE-STAMPED in any frame, or a plain POSE taken to be in the fixed frame) as a
plain POSE in the fixed frame. Poses in the robot's base frame are placed with that frame's
pose in the belief state; other frames go through CRAM-TF:*TRANSFORMER*."
  (cond ((not (typep pose 'cl-transforms:pose))
         (pp-error "Expected a pose or pose-stamped, got ~s." pose))
        ((not (cl-transforms-stamped:pose-stamped-p pose)) pose)
        (t (let ((frame (string-left-trim "/" (cl-transforms-stamped:frame-id pose))))
             (cond ((string= frame cram-tf:*fixed-frame*)
                    (cl-transforms:make-pose (cl-transforms:origin pose)
                                             (cl-transforms:orientation pose)))
                   ((string= frame (robot-base-frame))
                    (man-int:transform-pose-by
                     (base-frame-pose-in-map)
                     (cl-transforms:pose->transform
                      (cl-transforms:make-pose (cl-transforms:origin pose)
                                               (cl-transforms:orientation pose)))))
                   (t (let ((p (cram-tf:ensure-pose-in-frame pose cram-tf:*fixed-frame*)))
                        (cl-transforms:make-pose (cl-transforms:origin p)
                                                 (cl-transforms:orientation p)))))))))

(defun map-stamped (pose)
  (cl-transforms-stamped:pose->pose-stamped cram-tf:*fixed-frame* 0d0 (pose-in-map pose)))

(defun object-designator-name (object)
  "The belief-state name of the perceived object designator OBJECT."
  (unless (typep object 'desig:object-designator)
    (pp-error "Expected an object designator, got ~s." object))
  (let ((current (desig:current-desig object)))
    (or (prop current :name)
        (ignore-errors (desig:object-identifier current))
        (pp-error "The object designator ~s has no name: detect it first." object))))

(defun object-designator-type (object)
  "The object type keyword of the object designator OBJECT (from its TYPE, or the belief)."
  (let* ((current (desig:current-desig object))
         (type (prop current :type)))
    (if (and type (keywordp type) (not (eq type t)))
        type
        (let ((o (btr:object btr:*current-bullet-world* (object-designator-name object))))
          (or (and o (btr:item-type o))
              (pp-error "Cannot tell the type of the object ~s." object))))))

(defun object-pose-in-map (object)
  "The current pose (fixed frame) of the object designator OBJECT: from the belief state when
the object is there, else from the designator's data."
  (let* ((name (object-designator-name object))
         (o (btr:object btr:*current-bullet-world* name)))
    (if o
        (btr:pose o)
        (let ((pose (or (ignore-errors (desig:object-pose (desig:current-desig object)))
                        (prop (desig:current-desig object) :pose))))
          (unless (typep pose 'cl-transforms:pose)
            (pp-error "The object ~s has no known pose." object))
          (pose-in-map pose)))))

(defun check-arm (arm)
  (let ((arms (rob-int::robot-arms (current-robot-name))))
    (unless (member arm arms)
      (pp-error "Unknown arm ~s: the robot ~s has the arms ~{~s~^, ~}." arm
                (current-robot-name) arms))
    arm))

(defun robot-arms ()
  (rob-int::robot-arms (current-robot-name)))

(defun arm-list (arms)
  (mapcar #'check-arm (if (listp arms) arms (list arms))))

;;; ---- atomic plans ----------------------------------------------------------------------------

(defun location-pose (location)
  (typecase location
    (desig:location-designator (desig:reference location))
    (cl-transforms:pose location)
    (t (pp-error "Expected a location designator or a pose as target, got ~s." location))))

(defun base-frame-stamped-p (pose)
  "True when POSE is a pose-stamped in the robot's base frame."
  (and (typep pose 'cl-transforms-stamped:pose-stamped)
       (string= (string-left-trim "/" (cl-transforms-stamped:frame-id pose))
                (string-left-trim "/" (robot-base-frame)))))

(defun navigate (&key target pose &allow-other-keys)
  "Drive the robot base to TARGET (a location designator) or POSE. A goal in the robot's base
frame goes to the going motion as it is: CRAM's projection takes its numbers as map
coordinates (see URDF-PROJ::NAVIGATION-GOAL-IN-MAP); goals in other frames are put in the map."
  (let* ((goal (or pose (location-pose target)))
         (?pose (if (base-frame-stamped-p goal) goal (map-stamped goal))))
    (exe:perform (desig:a motion (type going) (pose ?pose)))))

(def-action-grounding :going (d)
  (let ((target (prop d :target)) (pose (prop d :pose)))
    (unless (or target pose)
      (pp-error "The going action ~s needs a TARGET location designator." d))
    (list (resolved 'navigate :going `((:target ,target) (:pose ,pose))))))

(defun look-at (&key target object direction joint-states &allow-other-keys)
  "Point the robot's camera at TARGET (a location designator or pose), OBJECT (an object
designator), into DIRECTION (e.g. :FORWARD) or set the neck to JOINT-STATES. A neck that
cannot reach the goal is retried once."
  (cpl:with-retry-counters ((neck-retries 1))
    (cpl:with-failure-handling
        ((common-fail:ptu-low-level-failure (e)
           (cpl:log-message :warn '(pick-place look-at) "~a" e)
           (cpl:do-retry neck-retries
             (cpl:log-message :warn '(pick-place look-at) "Retrying.")
             (cpl:retry))))
      (cond (direction
             (let ((?direction direction))
               (exe:perform (desig:a motion (type looking) (direction ?direction)))))
            (joint-states
             (let ((?joint-states joint-states))
               (exe:perform (desig:a motion (type looking) (joint-states ?joint-states)))))
            (t
             (let ((?pose (map-stamped
                           (if object
                               (let ((p (object-pose-in-map object)))
                                 (cl-transforms:make-pose
                                  (cl-transforms:v+ (cl-transforms:origin p)
                                                    (cl-transforms:make-3d-vector 0 0 *look-z-offset*))
                                  (cl-transforms:orientation p)))
                               (location-pose target)))))
               (exe:perform (desig:a motion (type looking) (pose ?pose)))))))))

(def-action-grounding :looking (d)
  (let ((target (prop d :target)) (object (prop d :object))
        (direction (prop d :direction)) (joint-states (prop d :joint-states)))
    (unless (or target object direction joint-states)
      (pp-error "The looking action ~s needs a TARGET, OBJECT, DIRECTION or JOINT-STATES." d))
    (list (resolved 'look-at :looking `((:target ,target) (:object ,object)
                                         (:direction ,direction)
                                         (:joint-states ,joint-states))))))

(defun perceive (&key object &allow-other-keys)
  "Detect OBJECT (an object designator); the result designator is equated with OBJECT, an
OBJECT-PERCEIVED-EVENT is fired, and it is returned (a list for an ALL designator)."
  (let* ((?object object)
         (result (exe:perform (desig:a motion (type detecting) (object ?object)))))
    (dolist (perceived (if (listp result) result (list result)))
      (when (typep perceived 'desig:object-designator)
        (unless (or (listp result) (desig:desig-equal object perceived))
          (desig:equate object perceived))
        (coe:on-event (make-instance 'cpoe:object-perceived-event
                                     :object-designator perceived
                                     :perception-source :projection))))
    result))

(def-action-grounding :detecting (d)
  (let ((object (prop d :object)))
    (unless (typep object 'desig:object-designator)
      (pp-error "The detecting action ~s needs an OBJECT designator, got ~s." d object))
    (list (resolved 'perceive :detecting `((:object ,object))))))

(defun move-torso (&key joint-angle &allow-other-keys)
  "Move the torso joint to JOINT-ANGLE (a number, :UPPER-LIMIT, :LOWER-LIMIT or :MIDDLE)."
  (let ((?angle joint-angle))
    (exe:perform (desig:a motion (type moving-torso) (joint-angle ?angle)))))

(def-action-grounding :moving-torso (d)
  (let ((angle (prop d :joint-angle)))
    (unless (or (realp angle) (member angle '(:upper-limit :lower-limit :middle)))
      (pp-error "The moving-torso action ~s needs a JOINT-ANGLE: a number or one of ~
                 :UPPER-LIMIT, :LOWER-LIMIT, :MIDDLE; got ~s." d angle))
    (list (resolved 'move-torso :moving-torso `((:joint-angle ,angle))))))

(defun arm-configuration-joint-states (arm configuration)
  "Joint states ((name value)...) of ARM for CONFIGURATION: a named configuration of the
robot description (:PARK, :CARRY, :POINT ...) or joint states already."
  (cond ((null configuration) nil)
        ((consp configuration) configuration)
        ((symbolp configuration)
         (let ((name (intern (symbol-name configuration) :keyword)))
           (or (rob-int::first-solution-value
                '?states `(rob-int:robot-joint-states ,(current-robot-name) :arm ,arm ,name ?states))
               (pp-error "The robot ~s has no arm configuration ~s for the ~(~a~) arm." 
                         (current-robot-name) configuration arm))))
        (t (pp-error "Expected an arm configuration name or joint states, got ~s." configuration))))

(defun position-arms (&key left-configuration right-configuration &allow-other-keys)
  "Move the arms into the named configurations or joint states (NIL leaves an arm)."
  (let ((?left (arm-configuration-joint-states :left left-configuration))
        (?right (arm-configuration-joint-states :right right-configuration)))
    (when (or ?left ?right)
      (exe:perform (desig:a motion (type moving-arm-joints)
                            (desig:when ?left (left-joint-states ?left))
                            (desig:when ?right (right-joint-states ?right)))))
    (coe:on-event (make-instance 'cpoe:robot-state-changed))))

(def-action-grounding :positioning-arm (d)
  (let ((left (prop d :left-configuration)) (right (prop d :right-configuration)))
    (when left (arm-configuration-joint-states :left left))
    (when right (arm-configuration-joint-states :right right))
    (list (resolved 'position-arms :positioning-arm
                    `((:left-configuration ,left) (:right-configuration ,right))))))

(defparameter *arm-joints-convergence-delta* 0.17d0
  "Radians (about 10 degrees) within which an arm joint counts as at its goal for the occasion
CPOE:ARMS-POSITIONED-AT.")

(defun angle-difference (a b)
  "|A - B| wrapped into [0, pi] (radians; reals)."
  (let ((d (- (float a 1d0) (float b 1d0))))
    (declare (type double-float d))
    (abs (atan (sin d) (cos d)))))

(defun arms-positioned-p (left-configuration right-configuration
                          &optional (delta *arm-joints-convergence-delta*))
  "True when the robot's left and right arm joints are within DELTA of LEFT-CONFIGURATION and
RIGHT-CONFIGURATION (configuration names such as :PARK, or joint states); NIL as a
configuration asks nothing of that arm."
  (let ((robot (btr:get-robot-object))
        (joints nil))   ; every joint value of the robot, read once when a joint is asked for
    (and robot
         (loop for arm in '(:left :right)
               for configuration in (list left-configuration right-configuration)
               always (loop for (joint value) in (arm-configuration-joint-states arm configuration)
                            for index = (btr:joint-index robot joint)
                            always (< (angle-difference
                                       (aref (or joints (setf joints (btr:robot-joint-values robot)))
                                             index)
                                       value)
                                      delta))))))

(def-fact-group arm-occasions (cpoe:arms-positioned-at)
  (<- (cpoe:arms-positioned-at ?left-configuration ?right-configuration)
    (lisp-pred arms-positioned-p ?left-configuration ?right-configuration)))

(defun park-arms (&key (arms (robot-arms) arms-p) (arm nil arm-p) (configuration :park)
                  &allow-other-keys)
  "Bring ARMS (default: all arms of the robot; CRAM's keyword ARM is accepted too, an arm or a
list of arms) into CONFIGURATION (default :PARK). The action's goal is CPOE:ARMS-POSITIONED-AT,
so arms already there are not moved (\"Action goal ... already achieved.\")."
  (when (and arms-p arm-p)
    (pp-error "PARK-ARMS: give the arms either as :ARMS ~s or as :ARM ~s, not both." arms arm))
  (let* ((arms (arm-list (if arm-p arm arms)))
         (?left (and (member :left arms) configuration))
         (?right (and (member :right arms) configuration)))
    (exe:perform (desig:an action (type positioning-arm)
                           (desig:when ?left (left-configuration ?left))
                           (desig:when ?right (right-configuration ?right))
                           (goal (cpoe:arms-positioned-at ?left ?right))))))

(def-action-grounding :parking-arms (d)
  (let ((arms (arm-list (or (prop d :arms) (prop d :arm) (robot-arms)))))
    (list (resolved 'park-arms :parking-arms `((:arms ,arms))))))

(defun set-gripper (&key gripper position &allow-other-keys)
  "Set the GRIPPER (an arm or a list of arms) to POSITION: :OPEN, :CLOSE or metres."
  (dolist (?arm (arm-list gripper))
    (cond ((eq position :open)
           (exe:perform (desig:a motion (type opening-gripper) (gripper ?arm))))
          ((eq position :close)
           (exe:perform (desig:a motion (type closing-gripper) (gripper ?arm))))
          ((realp position)
           (let ((?position position))
             (exe:perform (desig:a motion (type moving-gripper-joint) (gripper ?arm)
                                   (joint-position ?position)))))
          (t (pp-error "Gripper position ~s: expected :OPEN, :CLOSE or metres." position)))))

(def-action-grounding :setting-gripper (d)
  (let ((gripper (or (prop d :gripper) (prop d :arm))) (position (prop d :position)))
    (arm-list gripper)
    (unless (or (realp position) (member position '(:open :close)))
      (pp-error "The setting-gripper action ~s needs a POSITION: :OPEN, :CLOSE or metres; ~
                 got ~s." d position))
    (list (resolved 'set-gripper :setting-gripper `((:gripper ,gripper) (:position ,position))))))

(defun release (&key gripper &allow-other-keys)
  "Open GRIPPER (an arm or a list of arms)."
  (set-gripper :gripper gripper :position :open))

(def-action-grounding :releasing (d)
  (let ((gripper (or (prop d :gripper) (prop d :arm))))
    (arm-list gripper)
    (list (resolved 'release :releasing `((:gripper ,gripper))))))

(defun grip (&key arm object grasp (effort 50) &allow-other-keys)
  "Close ARM's gripper on OBJECT with EFFORT (retried once on a gripper failure), then record
the grasp in the belief state with an OBJECT-ATTACHED-ROBOT event."
  (let ((?arm arm) (?effort effort))
    (cpl:with-retry-counters ((grip-retries 1))
      (cpl:with-failure-handling
          ((common-fail:gripper-low-level-failure (e)
             (cpl:log-message :warn '(pick-place grip) "~a" e)
             (cpl:do-retry grip-retries
               (cpl:log-message :warn '(pick-place grip) "Retrying")
               (cpl:retry))
             (cpl:log-message :warn '(pick-place grip) "Giving up")))
        (exe:perform (desig:a motion (type gripping) (gripper ?arm) (effort ?effort)))))
    (cpl:log-message :info '(pick-place grip) "Assert grasp into knowledge base")
    (note-gripped-object object)
    (coe:on-event (make-instance 'cpoe:object-attached-robot
                                 :arm arm :grasp grasp
                                 :object-name (object-designator-name object)
                                 :object-designator object))))

(def-action-grounding :gripping (d)
  (let ((arm (check-arm (or (prop d :arm) (prop d :gripper)))) (object (prop d :object)))
    (object-designator-name object)
    (list (resolved 'grip :gripping
                    `((:arm ,arm) (:object ,object) (:grasp ,(prop d :grasp))
                      (:effort ,(or (prop d :effort)
                                    (man-int:get-object-type-gripping-effort
                                     (object-designator-type object)))))))))

(defun move-arms-in-sequence (&key left-poses right-poses collision-mode move-base
                              &allow-other-keys)
  "Move the tool frames through LEFT-POSES and RIGHT-POSES (lists, aligned by index), one
MOVING-TCP motion per step. Failures of intermediate steps are logged and ignored; the last
step's failure propagates. Fires ROBOT-STATE-CHANGED at the end."
  (let ((n (max (length left-poses) (length right-poses))))
    (dotimes (i n)
      (let ((?left (and (nth i left-poses) (map-stamped (nth i left-poses))))
            (?right (and (nth i right-poses) (map-stamped (nth i right-poses))))
            (?mode collision-mode)
            (?move-base move-base))
        (flet ((move ()
                 (exe:perform (desig:a motion (type moving-tcp)
                                       (desig:when ?left (left-pose ?left))
                                       (desig:when ?right (right-pose ?right))
                                       (desig:when ?mode (collision-mode ?mode))
                                       (desig:when ?move-base (move-base ?move-base))))))
          (if (< i (1- n))
              (handler-case (move)
                (common-fail:manipulation-low-level-failure (e)
                  (cpl:log-message :warn '(pick-place move-arms-in-sequence) "~a~%Ignoring." e)))
              (move)))))
    (coe:on-event (make-instance 'cpoe:robot-state-changed))))

(defun pose-list (value what designator)
  (cond ((null value) nil)
        ((typep value 'cl-transforms:pose) (list value))
        ((and (listp value) (every (lambda (p) (typep p 'cl-transforms:pose)) value)) value)
        (t (pp-error "The ~(~a~) of ~s: expected a pose or a list of poses, got ~s."
                     what designator value))))

(defun ground-arm-action (type d)
  (let ((left (pose-list (prop d :left-poses) :left-poses d))
        (right (pose-list (prop d :right-poses) :right-poses d)))
    (unless (or left right)
      (pp-error "The ~(~a~) action ~s needs LEFT-POSES or RIGHT-POSES." type d))
    (list (resolved 'move-arms-in-sequence type
                    `((:left-poses ,left) (:right-poses ,right)
                      (:collision-mode ,(prop d :collision-mode))
                      (:move-base ,(prop d :move-base)))))))

(def-action-grounding :reaching (d) (ground-arm-action :reaching d))
(def-action-grounding :grasping (d) (ground-arm-action :grasping d))
(def-action-grounding :lifting (d) (ground-arm-action :lifting d))
(def-action-grounding :putting (d) (ground-arm-action :putting d))
(def-action-grounding :retracting (d) (ground-arm-action :retracting d))
