;;;; The simple mobile manipulation plan: fetch a bottle from the table and put it on the
;;;; kitchen island, recovering from perception, arm and grasp failures.

(in-package :cram-bullet-world-tutorial)

(defparameter *bottle-pose-in-view* '((-1.6 -0.9 0.86) (0 0 0 1))
  "A bottle pose on the table in front of *BASE-POSE-NEAR-TABLE*: seen at the first look.")
(defparameter *bottle-pose-out-of-view* '((-2.0 -0.9 0.86) (0 0 0 1))
  "A bottle pose right of the robot: only a new look direction finds it.")
(defparameter *bottle-pose-hard-to-grasp* '((-1.85 -0.92 0.86) (0 0 1 0))
  "A bottle pose right of the robot (0.4 m to the right of *BASE-POSE-NEAR-TABLE*, 0.77 m
ahead), turned half round about its axis. Grasps are defined in the bottle's frame, so its
left side now faces away from the robot: the first choice, the LEFT-SIDE grasp with the right
arm, would bring the gripper back towards the robot from behind the bottle. No sample of base
offset, torso height and arm configuration reaches those poses free of collision, reaching and
grasping fail, gripping closes on nothing (GRIPPER-CLOSED-COMPLETELY) and the RIGHT-SIDE grasp,
from the side facing the robot, takes the bottle. The samples follow a seeded random state, so
the same recovery happens every run.")

(defparameter *final-object-destination*
  (cl-transforms-stamped:make-pose-stamped
   "map" 0.0 (cl-transforms:make-3d-vector -0.8 2.0 0.952) (cl-transforms:make-identity-rotation))
  "Where the bottle goes: on the kitchen island (top at 0.851 m; the bottle's origin is 0.1008
m above its bottom).")

(defparameter *base-pose-near-table*
  (cl-transforms-stamped:make-pose-stamped
   "map" 0.0 (cl-transforms:make-3d-vector -1.447d0 -0.150d0 0.0d0)
   (cl-transforms:axis-angle->quaternion (cl-transforms:make-3d-vector 0 0 1) (/ pi -2)))
  "Where the robot stands to look at the table, facing -y.")

(defparameter *base-pose-near-counter*
  (cl-transforms-stamped:make-pose-stamped
   "map" 0.0 (cl-transforms:make-3d-vector -0.15d0 2.0d0 0.0d0)
   (cl-transforms:make-quaternion 0.0d0 0.0d0 -1.0d0 0.0d0))
  "Where the robot stands in front of the kitchen island, facing -x.")

(defparameter *downward-look-coordinate*
  (cl-transforms-stamped:make-pose-stamped
   "base_footprint" 0.0 (cl-transforms:make-3d-vector 0.65335d0 0.076d0 0.758d0)
   (cl-transforms:make-identity-rotation))
  "Look straight ahead and down onto a table.")

(defparameter *left-downward-look-coordinate*
  (cl-transforms-stamped:make-pose-stamped
   "base_footprint" 0.0 (cl-transforms:make-3d-vector 0.65335d0 0.76d0 0.758d0)
   (cl-transforms:make-identity-rotation))
  "Look ahead-left and down onto a table.")

(defparameter *right-downward-look-coordinate*
  (cl-transforms-stamped:make-pose-stamped
   "base_footprint" 0.0 (cl-transforms:make-3d-vector 0.65335d0 -0.76d0 0.758d0)
   (cl-transforms:make-identity-rotation))
  "Look ahead-right and down onto a table.")

(defun spawn-bottle (&optional (spawn-pose *bottle-pose-in-view*))
  "Put the red BOTTLE-1 at SPAWN-POSE ((x y z) (qx qy qz qw)) and let it settle."
  (unless (assoc :bottle btr:*mesh-files*)
    (add-objects-to-mesh-list))
  (btr-utils:spawn-object 'bottle-1 :bottle :color '(1 0 0) :pose spawn-pose)
  (btr:simulate btr:*current-bullet-world* 10))

(defun get-preferred-arm-for-direction (direction-looked)
  "The arm for an object found looking into DIRECTION-LOOKED: :LEFT on the left, else :RIGHT."
  (let ((preferred-arm :right))
    (when (eq direction-looked *left-downward-look-coordinate*)
      (setf preferred-arm :left))
    preferred-arm))

(defun find-object (?object-type)
  "Look straight, then left, then right until an object of ?OBJECT-TYPE is detected.
Returns the perceived designator and the arm preferred for that direction."
  (let* ((possible-look-directions `(,*downward-look-coordinate*
                                     ,*left-downward-look-coordinate*
                                     ,*right-downward-look-coordinate*))
         (?looking-direction (first possible-look-directions)))
    (setf possible-look-directions (cdr possible-look-directions))
    (exe:perform (desig:an action (type looking)
                           (target (desig:a location (pose ?looking-direction)))))
    (cpl:with-failure-handling
        ((common-fail:perception-object-not-found (e)
           (when possible-look-directions
             (cpl:log-message :warn '(perception-failure) "~a~%Turning head." e)
             (exe:perform (desig:a motion (type looking) (direction forward)))
             (setf ?looking-direction (first possible-look-directions))
             (setf possible-look-directions (cdr possible-look-directions))
             (exe:perform (desig:an action (type looking)
                                    (target (desig:a location (pose ?looking-direction)))))
             (cpl:retry))
           (cpl:fail 'common-fail:looking-high-level-failure
                     :description (format nil "No ~(~a~) in any look direction." ?object-type))))
      (let ((?perceived-bottle
              (exe:perform (desig:an action (type detecting)
                                     (object (desig:an object (type ?object-type)))))))
        (values ?perceived-bottle (get-preferred-arm-for-direction ?looking-direction))))))

(defun pick-up-object (?perceived-object ?grasping-arm)
  "Pick up ?PERCEIVED-OBJECT with ?GRASPING-ARM, trying the grasps in turn and then the other
arm. A grasp is given up on a manipulation or gripper failure (an unreachable pose, a gripper
closing on nothing) or when the action designator cannot be resolved; an arm when none of its
grasps worked (OBJECT-UNREACHABLE). Returns the arm holding the object."
  (let ((?possible-arms '(:right :left)))
    (cpl:with-retry-counters ((arm-change-retry 1))
      (cpl:with-failure-handling
          ((common-fail:object-unreachable (e)
             (cpl:log-message :warn '(arm-failure) "Manipulation failed: ~a" e)
             (cpl:do-retry arm-change-retry
               (setf ?grasping-arm (car (remove ?grasping-arm ?possible-arms)))
               (cpl:log-message :info '(trying-new-arm) "Trying the ~(~a~) arm" ?grasping-arm)
               (cpl:retry))
             (cpl:log-message :warn '(arm-failures) "No more retries left")))
        (let* ((?possible-grasps '(:left-side :right-side :front :back))
               (?grasp (cut:lazy-car ?possible-grasps)))
          (cpl:with-retry-counters ((grasp-retries 3))
            (cpl:with-failure-handling
                (((or common-fail:manipulation-low-level-failure
                      common-fail:gripper-low-level-failure
                      desig:designator-error) (e)
                   (cpl:log-message :warn '(grasp-failure)
                                    "~a~%Failed to grasp from ~a using ~a arm" e ?grasp
                                    ?grasping-arm)
                   (cpl:do-retry grasp-retries
                     (when (cut:lazy-car (cut:lazy-cdr ?possible-grasps))
                       (setf ?possible-grasps (cut:lazy-cdr ?possible-grasps))
                       (setf ?grasp (cut:lazy-car ?possible-grasps))
                       (cpl:log-message :info '(trying-new-grasp)
                                        "Trying to grasp from ~a using ~a arm" ?grasp
                                        ?grasping-arm)
                       (cpl:retry)))
                   (cpl:log-message :warn '(grasp-failures) "No more retries left")
                   (cpl:fail 'common-fail:object-unreachable
                             :description (format nil "No grasp of ~a with the ~(~a~) arm."
                                                  (desig:desig-prop-value ?perceived-object :name)
                                                  ?grasping-arm))))
              (exe:perform (desig:an action (type picking-up) (arm ?grasping-arm)
                                     (grasp ?grasp) (object ?perceived-object))))))))
    ?grasping-arm))

(defun move-bottle (&optional (bottle-spawn-pose *bottle-pose-in-view*))
  "Spawn the bottle at BOTTLE-SPAWN-POSE and, in projection, fetch it from the table and put
it at *FINAL-OBJECT-DESTINATION*. Returns the perceived bottle designator."
  (spawn-bottle bottle-spawn-pose)
  (urdf-proj:with-simulated-robot
    (let ((?navigation-goal *base-pose-near-table*))
      (cpl:par
        (exe:perform (desig:a motion (type moving-torso) (joint-angle 0.3)))
        (pp-plans::park-arms)
        (exe:perform (desig:an action (type going)
                               (target (desig:a location (pose ?navigation-goal)))))))
    (multiple-value-bind (?perceived-bottle ?grasping-arm) (find-object :bottle)
      (setf ?grasping-arm (pick-up-object ?perceived-bottle ?grasping-arm))
      (exe:perform (desig:an action (type parking-arms) (arms (?grasping-arm))))
      (let ((?nav-goal *base-pose-near-counter*))
        (exe:perform (desig:an action (type going)
                               (target (desig:a location (pose ?nav-goal))))))
      (coe:on-event (make-instance 'cpoe:robot-state-changed))
      (exe:perform (desig:a motion (type moving-torso) (joint-angle 0.3)))
      (let ((?drop-pose *final-object-destination*))
        (exe:perform (desig:an action (type placing) (arm ?grasping-arm)
                               (object ?perceived-bottle)
                               (target (desig:a location (pose ?drop-pose))))))
      (exe:perform (desig:an action (type parking-arms) (arms (?grasping-arm))))
      ?perceived-bottle)))
