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

(defun check-navigating-collisions (location &key (accept (constantly t)))
  "The projection pre-check of navigating: the first of up to *NAVIGATION-CHECK-SAMPLES*
solutions of LOCATION (a location designator) at which the robot is free of collisions and
that ACCEPT (a function of the base pose) accepts: the designator of that solution, equated
with LOCATION. Signals NAVIGATION-GOAL-IN-COLLISION when there is none."
  (let ((current location))
    (loop repeat *navigation-check-samples*
          while current
          do (let ((pose (handler-case (desig:reference current)
                           (desig:designator-error () (return)))))
               (let ((hits (base-pose-collisions pose)))
                 (when (and (null hits) (funcall accept pose))
                   (return-from check-navigating-collisions current))
                 (when hits
                   (log-fd :warn 'navigate "Navigation goal ~a collides with ~{~s~^, ~}; trying ~
                                            the next solution." (urdf-proj::pose-summary pose) hits)))
               (setf current (desig:next-solution current))))
    (cpl:fail 'common-fail:navigation-goal-in-collision
              :description (format nil "No solution of ~a is free of collisions for the robot."
                                   location))))

(defun navigate (&key location (park-arms t) see grasp place &allow-other-keys)
  "Park the arms (unless PARK-ARMS is NIL), pre-check LOCATION for a collision-free base pose
(NAVIGATION-GOAL-IN-COLLISION when there is none) from which the object designator SEE (when
given) is visible, the object designator GRASP (when given) can be grasped and PLACE (when
given: (object arm target)) can be put down, and drive there.
A low-level navigation failure is logged and ignored, as on a real base that plans around
obstacles."
  (when park-arms
    (exe:perform (desig:an action (type parking-arms))))
  (let ((?location (desig:current-desig
                    (check-navigating-collisions
                     location :accept (lambda (pose)
                                        (and (or (null see) (object-visible-from-p see pose))
                                             (or (null grasp)
                                                 (object-graspable-from-p grasp pose))
                                             (or (null place)
                                                 (apply #'object-placeable-from-p
                                                        (append place (list pose))))))))))
    (handler-case
        (exe:perform (desig:an action (type going) (target ?location)))
      (common-fail:navigation-low-level-failure (e)
        (log-fd :warn 'navigate "Low-level navigation failed: ~a~%Ignoring." e)))))

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
