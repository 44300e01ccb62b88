;;;; PR2-PP-PLANS (cram_pr2_pick_place_plans, 2017): the plans and poses the first Bullet world
;;;; tutorial calls, with that era's lambda lists (:?arm), over PP-PLANS.

(in-package :cram-pr2-pick-place-plans)

(defun arm-park-values (arm)
  (mapcar #'second (rob-int:get-robot-joint-states (rob-int:current-robot-name) :arm arm :park)))

(define-symbol-macro *pr2-left-arm-out-of-sight-joint-positions* (arm-park-values :left))
(define-symbol-macro *pr2-right-arm-out-of-sight-joint-positions* (arm-park-values :right))

(defparameter *meal-table-left-base-pose*
  (cl-transforms-stamped:make-pose-stamped
   "map" 0.0 (cl-transforms:make-3d-vector -1.12d0 -0.42d0 0.0)
   (cl-transforms:axis-angle->quaternion (cl-transforms:make-3d-vector 0 0 1) (/ pi -2)))
  "A base pose in front of the left side of the table.")
(defparameter *meal-table-right-base-pose*
  (cl-transforms-stamped:make-pose-stamped
   "map" 0.0 (cl-transforms:make-3d-vector -2.0547d0 -0.481d0 0.0d0)
   (cl-transforms:axis-angle->quaternion (cl-transforms:make-3d-vector 0 0 1) (/ pi -2)))
  "A base pose in front of the right side of the table.")
(defparameter *meal-table-left-base-look-pose*
  (cl-transforms-stamped:make-pose-stamped
   "base_footprint" 0.0 (cl-transforms:make-3d-vector 0.75d0 -0.12d0 1.11d0)
   (cl-transforms:make-identity-rotation))
  "Where to look from *MEAL-TABLE-LEFT-BASE-POSE*.")
(defparameter *meal-table-right-base-look-pose*
  (cl-transforms-stamped:make-pose-stamped
   "base_footprint" 0.0 (cl-transforms:make-3d-vector 0.65335d0 0.076d0 0.758d0)
   (cl-transforms:make-identity-rotation))
  "Where to look from *MEAL-TABLE-RIGHT-BASE-POSE*: down at the table top.")
(defparameter *meal-table-left-base-look-down-pose*
  (cl-transforms-stamped:make-pose-stamped
   "base_footprint" 0.0 (cl-transforms:make-3d-vector 0.7d0 -0.12d0 0.7578d0)
   (cl-transforms:make-identity-rotation))
  "Where to look down from *MEAL-TABLE-LEFT-BASE-POSE*.")

(defun perceive (?object-designator &key (object-chosing-function #'identity))
  "Detect ?OBJECT-DESIGNATOR (motion DETECTING, retried up to 5 times on
PERCEPTION-OBJECT-NOT-FOUND); the detected designator, passed through OBJECT-CHOSING-FUNCTION."
  (cpl:with-retry-counters ((perceive-retries 5))
    (cpl:with-failure-handling
        ((common-fail:perception-object-not-found (e)
           (declare (ignore e))
           (cpl:do-retry perceive-retries (cpl:retry))))
      (funcall object-chosing-function
               (exe:perform (desig:a motion (type detecting) (object ?object-designator)))))))

(defun drive-towards-object-plan (object-designator &key (?arm :right))
  "Drive to where ?ARM reaches OBJECT-DESIGNATOR (PP-PLANS's plan, the era's :?ARM key)."
  (pp-plans::drive-towards-object-plan object-designator :arm ?arm))

(defun drive-to-reach-pose (pose &key (?arm :right))
  "Drive to a base pose from which ?ARM reaches the pose-stamped POSE (a REACHABLE-FOR location)."
  (let* ((?pose (pp-plans:pose-in-map pose))
         (?robot (rob-int:current-robot-name))
         (?goal (desig:reference (desig:a location (reachable-for ?robot)
                                          (location (desig:a location (pose ?pose)))
                                          (arm ?arm)))))
    (exe:perform (desig:a motion (type going) (target (desig:a location (pose ?goal)))))))

(defun drive-and-pick-up-plan (?object-designator &key (?arm :right))
  "Drive towards ?OBJECT-DESIGNATOR, then look at it and pick it up with ?ARM."
  (drive-towards-object-plan ?object-designator :?arm ?arm)
  (cpl:par
    (exe:perform (desig:an action (type looking-at) (object ?object-designator)))
    (exe:perform (desig:an action (type picking-up) (arm ?arm) (object ?object-designator)))))
