;;;; Accessing and sealing a location: (in C) or (above C) opens or closes the container C —
;;;; its outer container first when accessing, last when sealing — standing at the robot
;;;; location (given, or in front of the handle), with CRAM's arm retries and base relocations.
;;;; (on X) needs nothing.

(in-package :cram-urdf-environment-manipulation)

(defparameter *relocation-retries* 50 "Extra robot locations tried before giving up.")
(defparameter *arm-retries* 1 "Extra arms tried at one robot location.")
(defparameter *fallback-base-pose-count* 5
  "How many base poses in front of a handle an accessing or sealing action without a
ROBOT-LOCATION tries at most (each found when it is needed).")

(defun location-container (location)
  "The container designator of LOCATION: the object of (in C) or (above C), or NIL."
  (or (location-reference location :in) (location-reference location :above)))

(defun robot-locations (robot-location container action arm distance)
  "A function returning the next base pose to try (a pose-stamped), or NIL when none is left:
the solutions of the location designator ROBOT-LOCATION, else base poses in front of
CONTAINER's handle."
  (if robot-location
      (let ((current robot-location) (first t))
        (lambda ()
          (if first
              (progn (setf first nil) (desig:reference current))
              (let ((next (ignore-errors (desig:next-solution current))))
                (when next (setf current next) (desig:reference next))))))
      (let ((next (container-base-pose-finder container action arm
                                              (container-opening-amount container action distance)))
            (left *fallback-base-pose-count*))
        ;; each pose looked for when it is asked for, in the robot's state then
        (lambda ()
          (when (plusp left)
            (decf left)
            (let ((found (funcall next)))
              (and found (map-stamped (first found)))))))))

(defun perform-container-action (action container-designator arm grasps distance)
  (let ((?object container-designator) (?arm arm) (?distance distance) (?grasps grasps)
        (?state (or distance (if (eq action :open) :open :closed))))
    (if (eq action :open)
        (exe:perform (desig:an action (type opening) (object ?object) (arm ?arm)
                               (desig:when ?distance (distance ?distance))
                               (desig:when ?grasps (grasps ?grasps))
                               (goal (cpoe:container-state ?object ?state))))
        (exe:perform (desig:an action (type closing) (object ?object) (arm ?arm)
                               (desig:when ?distance (distance ?distance))
                               (desig:when ?grasps (grasps ?grasps))
                               (goal (cpoe:container-state ?object ?state)))))))

(defun with-arms (action container-designator arms grasps distance)
  "Open or close with the first of ARMS, the next one after a failure."
  (let ((arms (copy-list arms)))
    (cpl:with-retry-counters ((arm-retries (min *arm-retries* (max 0 (1- (length arms))))))
      (cpl:with-failure-handling
          (((or common-fail:environment-unreachable common-fail:navigation-goal-in-collision
                common-fail:gripper-low-level-failure common-fail:manipulation-low-level-failure
                desig:designator-error) (e)
             (cpl:log-message :warn '(env-man access-or-seal) "~a" e)
             (let ((?arm (first arms)))
               (handler-case (exe:perform (desig:an action (type releasing) (gripper ?arm)))
                 (cpl:plan-failure (f)
                   (cpl:log-message :warn '(env-man access-or-seal) "Releasing failed: ~a" f))))
             (cpl:do-retry arm-retries
               (pop arms)
               (cpl:log-message :warn '(env-man access-or-seal) "Trying the ~(~a~) arm." (first arms))
               (cpl:retry))
             (cpl:fail 'common-fail:environment-unreachable
                       :description (format nil "~a" e))))
        (perform-container-action action container-designator (first arms) grasps distance)))))

(defun handle-outer-location (action location)
  (let ((?outer (outer-location (location-container location))))
    (when ?outer
      (if (eq action :open)
          (exe:perform (desig:an action (type accessing) (location ?outer)
                                 (goal (cpoe:location-accessible ?outer))))
          (exe:perform (desig:an action (type sealing) (location ?outer)
                                 (goal (cpoe:location-reset ?outer))))))))

(defun access-or-seal-location (&key action location arms grasps distance robot-location
                                &allow-other-keys)
  "Make LOCATION accessible (ACTION :OPEN, accessing) or reset it (:CLOSE, sealing): for (in C)
or (above C), open C to DISTANCE (default its opening distance) or close it, with ARMS in turn,
standing at ROBOT-LOCATION (a location designator; default: base poses in front of the
handle), relocating after ENVIRONMENT-UNREACHABLE. An outer container (C's own location) is
accessed first and sealed last. ENVIRONMENT-MANIPULATION-IMPOSSIBLE when every robot location
fails."
  (let ((container-designator (location-container location)))
    (unless container-designator
      (log-env 'access-or-seal "~a needs no ~:[sealing~;accessing~]." location (eq action :open))
      (return-from access-or-seal-location nil))
    (handler-case
        (progn
          (when (eq action :open) (handle-outer-location action location))
          (let* ((container (container-designator-container container-designator))
                 (arms (or arms (free-arms) (robot-arms)))
                 (next-location (robot-locations robot-location container action (first arms) distance))
                 (?base (funcall next-location)))
            (unless ?base
              (cpl:fail 'common-fail:environment-unreachable
                        :description (format nil "No robot location to ~(~a~) ~(~a~) from."
                                             action (container-name container))))
            (cpl:with-retry-counters ((relocations *relocation-retries*))
              (cpl:with-failure-handling
                  (((or common-fail:environment-unreachable common-fail:navigation-low-level-failure
                        common-fail:navigation-high-level-failure) (e)
                     (cpl:log-message :warn '(env-man access-or-seal) "~a" e)
                     (cpl:do-retry relocations
                       (let ((next (funcall next-location)))
                         (when next
                           (setf ?base next)
                           (cpl:log-message :warn '(env-man access-or-seal) "Relocating.")
                           (cpl:retry))))))
                (exe:perform (desig:an action (type parking-arms)))
                (exe:perform (desig:an action (type going) (target (desig:a location (pose ?base)))))
                (with-arms action container-designator arms grasps distance))))
          (when (eq action :close) (handle-outer-location action location)))
      ((or common-fail:environment-unreachable desig:designator-error) (e)
        (cpl:fail 'common-fail:environment-manipulation-impossible
                  :description (format nil "~:[Sealing~;Accessing~] ~a failed: ~a"
                                       (eq action :open) location e))))))
