;;;; The events plans fire and the occasion predicates they test. The occasion predicates fail
;;;; until a belief-state layer extends them.

(in-package :cram-plan-occasions-events)

(defun check-slot (event slot value predicate expected)
  (unless (funcall predicate value)
    (error "~s: slot ~(~a~) is ~s: expected ~a." (type-of event) slot value expected)))

(defun optional-symbol-or-string-p (value)
  (or (null value) (symbolp value) (stringp value)))

(defun optional-designator-p (value)
  (or (null value) (typep value 'desig:designator)))

(defclass robot-state-changed (event) ()
  (:documentation "Fired after the robot moved (base, torso, arms, neck or grippers)."))

(defclass object-perceived-event (event)
  ((object-designator :initarg :object-designator :initform nil
                      :reader event-object-designator)
   (perception-source :initarg :perception-source :initform nil
                      :reader event-perception-source))
  (:documentation "Fired after perception found an object; OBJECT-DESIGNATOR is the perceived
designator, PERCEPTION-SOURCE a keyword naming the perception system."))

(defclass object-attachment-event (event)
  ((object-name :initarg :object-name :initform nil :reader event-object-name)
   (object-designator :initarg :object-designator :initform nil
                      :reader event-object-designator)
   (arm :initarg :arm :initform nil :reader event-arm)
   (link :initarg :link :initform nil :reader event-link)
   (grasp :initarg :grasp :initform nil :reader event-grasp)
   (not-loose :initarg :not-loose :initform nil :reader event-not-loose))
  (:documentation "The common slots of OBJECT-ATTACHED-ROBOT and OBJECT-DETACHED-ROBOT."))

(defclass object-attached-robot (object-attachment-event) ()
  (:documentation "Fired after the robot grasped an object: OBJECT-NAME (the object's name in
the belief state), OBJECT-DESIGNATOR, ARM (:left / :right), GRASP, optional LINK and
NOT-LOOSE."))

(defclass object-detached-robot (object-attachment-event) ()
  (:documentation "Fired after the robot let go of an object: OBJECT-NAME,
OBJECT-DESIGNATOR, ARM, optional LINK."))

(defclass object-attached-object (event)
  ((object-name :initarg :object-name :initform nil :reader event-object-name)
   (object-designator :initarg :object-designator :initform nil
                      :reader event-object-designator)
   (other-object-name :initarg :other-object-name :initform nil
                      :reader event-other-object-name)
   (attachment-type :initarg :attachment-type :initform nil
                    :reader event-attachment-type))
  (:documentation "Fired when an object was connected to another one (assemblage)."))

(defclass object-detached-object (object-attached-object) ()
  (:documentation "Fired when an object was disconnected from another one."))

(defclass object-location-changed (event)
  ((object-designator :initarg :object-designator :initform nil
                      :reader event-object-designator)
   (location-designator :initarg :location-designator :initform nil
                        :reader event-location-designator))
  (:documentation "Fired after an object was put somewhere: OBJECT-DESIGNATOR and the
LOCATION-DESIGNATOR of its new place."))

(defclass environment-manipulation-event (event)
  ((joint-name :initarg :joint-name :initform nil :reader event-joint-name)
   (environment-name :initarg :environment-name :initform nil
                     :reader event-environment-name)
   (environment-designator :initarg :environment-designator :initform nil
                           :reader event-environment-designator)
   (arm :initarg :arm :initform nil :reader event-arm)
   (distance :initarg :distance :initform nil :reader event-distance))
  (:documentation "The common slots of container opening and closing events: JOINT-NAME,
ENVIRONMENT-NAME, ENVIRONMENT-DESIGNATOR, ARM and the DISTANCE (metres or radians)."))

(defclass container-opening-event (environment-manipulation-event) ()
  (:documentation "Fired after a drawer or door was opened by DISTANCE."))

(defclass container-closing-event (environment-manipulation-event) ()
  (:documentation "Fired after a drawer or door was closed by DISTANCE."))

(defmethod initialize-instance :after ((event object-attachment-event) &key)
  (check-slot event 'object-name (event-object-name event) #'optional-symbol-or-string-p
              "a symbol or string naming the object")
  (check-slot event 'object-designator (event-object-designator event)
              #'optional-designator-p "an object designator or NIL")
  (check-slot event 'arm (event-arm event) #'symbolp "an arm keyword such as :LEFT")
  (unless (or (event-object-name event) (event-object-designator event))
    (error "~s needs an :OBJECT-NAME or an :OBJECT-DESIGNATOR." (type-of event))))

(defmethod initialize-instance :after ((event object-attached-object) &key)
  (check-slot event 'object-name (event-object-name event) #'optional-symbol-or-string-p
              "a symbol or string naming the object")
  (check-slot event 'other-object-name (event-other-object-name event)
              #'optional-symbol-or-string-p "a symbol or string naming the other object"))

(defmethod initialize-instance :after ((event object-perceived-event) &key)
  (check-slot event 'object-designator (event-object-designator event)
              (lambda (v) (typep v 'desig:object-designator)) "an object designator"))

(defmethod initialize-instance :after ((event object-location-changed) &key)
  (check-slot event 'object-designator (event-object-designator event)
              (lambda (v) (typep v 'desig:object-designator)) "an object designator")
  (check-slot event 'location-designator (event-location-designator event)
              #'optional-designator-p "a location designator or NIL"))

(defmethod initialize-instance :after ((event environment-manipulation-event) &key)
  (check-slot event 'distance (event-distance event) (lambda (v) (or (null v) (realp v)))
              "a real number or NIL"))

;;; Occasion predicates: interfaces that fail until a belief layer adds rules.

(prolog:def-fact-group occasion-declarations (object-in-hand object-at-location
                                              robot-at-location looking-at torso-at
                                              arms-positioned-at tool-frames-at
                                              gripper-joint-at gripper-opened gripper-closed
                                              container-state object-attached-to)
  (prolog:<- (object-in-hand ?object) (prolog:fail))
  (prolog:<- (object-in-hand ?object ?arm) (prolog:fail))
  (prolog:<- (object-in-hand ?object ?arm ?grasp) (prolog:fail))
  (prolog:<- (object-in-hand ?object ?arm ?grasp ?link) (prolog:fail))
  (prolog:<- (object-at-location ?object-designator ?location-designator) (prolog:fail))
  (prolog:<- (robot-at-location ?location-designator) (prolog:fail))
  (prolog:<- (looking-at ?location-or-object-designator) (prolog:fail))
  (prolog:<- (torso-at ?joint-state) (prolog:fail))
  (prolog:<- (arms-positioned-at ?left-configuration ?right-configuration) (prolog:fail))
  (prolog:<- (tool-frames-at ?left-poses ?right-poses) (prolog:fail))
  (prolog:<- (gripper-joint-at ?arm ?joint-state) (prolog:fail))
  (prolog:<- (gripper-opened ?arm) (prolog:fail))
  (prolog:<- (gripper-closed ?arm) (prolog:fail))
  (prolog:<- (container-state ?container-designator ?joint-state) (prolog:fail))
  (prolog:<- (object-attached-to ?object-name ?other-name) (prolog:fail)))

(loop for (name text) in
      '((event-object-name "The name of the object an event is about (symbol or string).")
        (event-object-designator "The object designator an event is about.")
        (event-other-object-name "The name of the other object of an object-object event.")
        (event-attachment-type "The kind of connection of an object-object event.")
        (event-arm "The arm (:LEFT, :RIGHT ...) of an attachment or manipulation event.")
        (event-grasp "The grasp (:FRONT, :LEFT-SIDE ...) of an attachment event.")
        (event-link "The robot link of an attachment event, or NIL for the arm's default.")
        (event-not-loose "True when an attachment must not be loose.")
        (event-perception-source "The perception system that perceived the object.")
        (event-location-designator "The location designator of an OBJECT-LOCATION-CHANGED.")
        (event-joint-name "The joint an environment manipulation event moved.")
        (event-environment-name "The name of the environment object that was manipulated.")
        (event-environment-designator "The designator of the manipulated container.")
        (event-distance "How far a container was opened or closed (metres or radians)."))
      do (setf (documentation name 'function) text))

(loop for (name text) in
      '((object-in-hand "Occasion (object-in-hand ?object [?arm [?grasp [?link]]]): the robot
holds the object.")
        (object-at-location "Occasion (object-at-location ?object-designator ?location-designator).")
        (robot-at-location "Occasion (robot-at-location ?location-designator): the base is there.")
        (looking-at "Occasion (looking-at ?location-or-object-designator): the camera points there.")
        (torso-at "Occasion (torso-at ?joint-state): the torso joint has that value or name.")
        (arms-positioned-at "Occasion (arms-positioned-at ?left-configuration ?right-configuration).")
        (tool-frames-at "Occasion (tool-frames-at ?left-poses ?right-poses).")
        (gripper-joint-at "Occasion (gripper-joint-at ?arm ?joint-state).")
        (gripper-opened "Occasion (gripper-opened ?arm).")
        (gripper-closed "Occasion (gripper-closed ?arm).")
        (container-state "Occasion (container-state ?container-designator ?joint-state).")
        (object-attached-to "Occasion (object-attached-to ?object-name ?other-name)."))
      do (setf (documentation name 'function)
               (concatenate 'string text " Extendable; fails until a belief layer adds rules.")))
