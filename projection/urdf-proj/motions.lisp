;;;; MOTION-GROUNDING rules of the robot-independent motions, and WAIT-PM.
;;;;
;;;; A motion designator is grounded to a command list (COMMAND argument...) whose command is
;;;; one of the symbols this package exports; process modules dispatch on it:
;;;;   going                  (location / pose)             → (drive pose)
;;;;   moving-torso           (joint-angle a)               → (move-torso a)
;;;;   looking                (target / pose / frame / direction / joint-states / object)
;;;;                                                        → (look-at target configuration)
;;;;   detecting              (object o)                    → (detect o)
;;;;   opening-gripper, closing-gripper, gripping, moving-gripper-joint
;;;;                          (gripper arm) [effort] [joint-position]
;;;;                                                        → (move-gripper-joint action arm effort)
;;;;   moving-tcp             (left-pose / left-poses) (right-pose / right-poses)
;;;;                          [collision-mode] [move-base] [fixed-torso]
;;;;                                                        → (move-tcp left right mode move-base fixed-torso)
;;;;   moving-arm-joints      (left-joint-states / left-configuration) (right-...)
;;;;                                                        → (move-joints left right)
;;;;   positioning-arm        (left-configuration) (right-configuration)
;;;;                                                        → (position-arms left right)
;;;;   monitoring-joint-state (joint-name) (joint-angle-threshold) [function]
;;;;                                                        → (monitor-joint-state name threshold function)
;;;;   waiting                (duration d)                  → (wait-for d)

(in-package :cram-common-designators)

(defparameter *known-motion-types*
  '(:going :moving-torso :looking :detecting :opening-gripper :closing-gripper :gripping
    :moving-gripper-joint :moving-tcp :moving-arm-joints :positioning-arm
    :monitoring-joint-state :waiting)
  "The motion types these MOTION-GROUNDING rules ground.")

(defun location-pose (designator)
  "The pose a location designator, pose-stamped or pose stands for."
  (if (typep designator 'desig:location-designator)
      (desig:reference designator)
      designator))

(defun object-map-pose (designator)
  "The map pose of an object designator: its perceived (pose ((pose-in-map p) ...)) entry, or
the pose of its data."
  (let ((entry (desig:desig-prop-value designator :pose)))
    (or (and (listp entry) (second (assoc :pose-in-map entry)))
        (and (listp entry) (second (assoc :pose entry)))
        (and (typep entry 'cl-transforms:pose) entry)
        (desig:object-pose (desig:reference designator)))))

(defun pose-like-p (value)
  (or (typep value 'cl-transforms:pose) (typep value 'desig:location-designator)
      (and (consp value) (= (length value) 2) (consp (first value)))))

(def-fact-group common-motion-groundings (desig:motion-grounding)

  (<- (desig:motion-grounding ?d (drive ?pose))
    (desig:desig-prop ?d (:type :going))
    (or (desig:desig-prop ?d (:pose ?target))
        (desig:desig-prop ?d (:target ?target)))
    (lisp-fun location-pose ?target ?pose))

  (<- (desig:motion-grounding ?d (move-torso ?angle))
    (desig:desig-prop ?d (:type :moving-torso))
    (desig:desig-prop ?d (:joint-angle ?angle)))

  (<- (desig:motion-grounding ?d (look-at ?pose nil))
    (desig:desig-prop ?d (:type :looking))
    (or (desig:desig-prop ?d (:target ?target))
        (desig:desig-prop ?d (:pose ?target)))
    (lisp-pred pose-like-p ?target)
    (lisp-fun location-pose ?target ?pose))
  (<- (desig:motion-grounding ?d (look-at ?pose nil))
    (desig:desig-prop ?d (:type :looking))
    (or (desig:desig-prop ?d (:object ?object))
        (desig:desig-prop ?d (:target ?object)))
    (lisp-pred typep ?object desig:object-designator)
    (lisp-fun object-map-pose ?object ?pose))
  (<- (desig:motion-grounding ?d (look-at ?frame nil))
    (desig:desig-prop ?d (:type :looking))
    (desig:desig-prop ?d (:frame ?frame)))
  (<- (desig:motion-grounding ?d (look-at nil ?direction))
    (desig:desig-prop ?d (:type :looking))
    (desig:desig-prop ?d (:direction ?direction)))
  (<- (desig:motion-grounding ?d (look-at ?joint-states nil))
    (desig:desig-prop ?d (:type :looking))
    (desig:desig-prop ?d (:joint-states ?joint-states)))

  (<- (desig:motion-grounding ?d (detect ?object))
    (desig:desig-prop ?d (:type :detecting))
    (desig:desig-prop ?d (:object ?object)))

  (<- (desig:motion-grounding ?d (move-gripper-joint :open ?arm nil))
    (desig:desig-prop ?d (:type :opening-gripper))
    (desig:desig-prop ?d (:gripper ?arm)))
  (<- (desig:motion-grounding ?d (move-gripper-joint :close ?arm nil))
    (desig:desig-prop ?d (:type :closing-gripper))
    (desig:desig-prop ?d (:gripper ?arm)))
  (<- (desig:motion-grounding ?d (move-gripper-joint :grip ?arm ?effort))
    (desig:desig-prop ?d (:type :gripping))
    (desig:desig-prop ?d (:gripper ?arm))
    (once (or (desig:desig-prop ?d (:effort ?effort)) (== ?effort nil))))
  (<- (desig:motion-grounding ?d (move-gripper-joint ?position ?arm nil))
    (desig:desig-prop ?d (:type :moving-gripper-joint))
    (desig:desig-prop ?d (:gripper ?arm))
    (desig:desig-prop ?d (:joint-position ?position)))

  (<- (desig:motion-grounding ?d (move-tcp ?left ?right ?mode ?move-base ?fixed-torso))
    (desig:desig-prop ?d (:type :moving-tcp))
    (once (or (desig:desig-prop ?d (:left-pose ?left)) (desig:desig-prop ?d (:left-poses ?left))
              (== ?left nil)))
    (once (or (desig:desig-prop ?d (:right-pose ?right)) (desig:desig-prop ?d (:right-poses ?right))
              (== ?right nil)))
    (or (lisp-pred identity ?left) (lisp-pred identity ?right))
    (once (or (desig:desig-prop ?d (:collision-mode ?mode)) (== ?mode nil)))
    (once (or (desig:desig-prop ?d (:move-base ?move-base)) (== ?move-base t)))
    (once (or (desig:desig-prop ?d (:fixed-torso ?fixed-torso)) (== ?fixed-torso nil))))

  (<- (desig:motion-grounding ?d (move-joints ?left ?right))
    (desig:desig-prop ?d (:type :moving-arm-joints))
    (once (or (desig:desig-prop ?d (:left-joint-states ?left))
              (desig:desig-prop ?d (:left-configuration ?left)) (== ?left nil)))
    (once (or (desig:desig-prop ?d (:right-joint-states ?right))
              (desig:desig-prop ?d (:right-configuration ?right)) (== ?right nil)))
    (or (lisp-pred identity ?left) (lisp-pred identity ?right)))

  (<- (desig:motion-grounding ?d (position-arms ?left ?right))
    (desig:desig-prop ?d (:type :positioning-arm))
    (once (or (desig:desig-prop ?d (:left-configuration ?left)) (== ?left nil)))
    (once (or (desig:desig-prop ?d (:right-configuration ?right)) (== ?right nil)))
    (or (lisp-pred identity ?left) (lisp-pred identity ?right)))

  (<- (desig:motion-grounding ?d (monitor-joint-state ?joint ?threshold ?function))
    (desig:desig-prop ?d (:type :monitoring-joint-state))
    (desig:desig-prop ?d (:joint-name ?joint))
    (desig:desig-prop ?d (:joint-angle-threshold ?threshold))
    (once (or (desig:desig-prop ?d (:function ?function)) (== ?function nil))))

  (<- (desig:motion-grounding ?d (wait-for ?duration))
    (desig:desig-prop ?d (:type :waiting))
    (desig:desig-prop ?d (:duration ?duration))
    (lisp-pred realp ?duration)))

(defun motion-command (grounding)
  "The command symbol of a motion GROUNDING (command argument...)."
  (first grounding))

(defun motion-arguments (grounding)
  "The arguments of a motion GROUNDING (command argument...)."
  (rest grounding))

(cpm:def-process-module wait-pm (motion-designator)
  "Executes WAITING motions: sleeps (with CPL:SLEEP) for the designator's duration in seconds."
  (destructuring-bind (command duration) (desig:reference motion-designator)
    (unless (eq command 'wait-for)
      (error "WAIT-PM: cannot execute the motion ~s (command ~s)." motion-designator command))
    (unless (and (realp duration) (>= duration 0))
      (error "WAIT-PM: duration ~s, expected a non-negative number of seconds." duration))
    (cpl:sleep duration)
    duration))

(def-fact-group wait-pm-matching (cpm:matching-process-module)
  (<- (cpm:matching-process-module ?d wait-pm)
    (desig:desig-prop ?d (:type :waiting))))
