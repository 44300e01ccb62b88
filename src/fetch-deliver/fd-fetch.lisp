;;;; Fetching: drive to where the object can be reached, look at it, perceive it again and pick
;;;; it up, trying the arms and grasps in turn and new base poses (CRAM's retry levels).

(in-package :cram-fetch-deliver-plans)

(defun object-look-location (object)
  "A location designator at the current pose of the perceived OBJECT."
  (let ((?pose (cl-transforms-stamped:pose->pose-stamped
                cram-tf:*fixed-frame* 0d0 (pp-plans:object-pose-in-map object))))
    (desig:a location (pose ?pose))))

(defun fetching-robot-location (object arms)
  "CRAM's default base location of a fetch: where the robot reaches OBJECT (with the first of
ARMS) and sees it (REACHABLE-FOR and VISIBLE-FOR: a line of sight to it past what stands
around it)."
  (let ((?robot (robot-name)) (?object object) (?arm (first arms)))
    (if ?arm
        (desig:a location (reachable-for ?robot) (visible-for ?robot) (arm ?arm) (object ?object))
        (desig:a location (reachable-for ?robot) (visible-for ?robot) (object ?object)))))

(defun fetch (&key object arms grasps robot-location look-location &allow-other-keys)
  "Fetch the perceived OBJECT: drive to ROBOT-LOCATION, turn towards LOOK-LOCATION, perceive
the object again and pick it up with the first of ARMS and GRASPS (NIL: what picking up
chooses). An object the robot put down itself and that has not moved since is first fetched
from where it was put down from (PLACED-FROM-LOCATION). Retries: the next grasp (5), the
next arm (1), a new base pose (50, the torso raised) on navigation, perception, reach or
manipulation failures, re-perceiving and re-picking (2) on a misgrasp.
Returns the object designator; FETCHING-FAILED when all are used up."
  (let ((?object object)
        (?robot-location (reset-or-nil robot-location))
        (?look-location (reset-or-nil look-location))
        (placed-from (placed-from-location object arms))
        (all-arms arms) (all-grasps grasps))
    (cpl:with-failure-handling
        ((desig:designator-error (e)
           (cpl:fail 'common-fail:fetching-failed
                     :description (format nil "Fetching ~a: a designator could not be resolved: ~a"
                                          (object-text ?object) e))))
      (with-base-pose-verdicts ()
      (cpl:with-retry-counters ((relocation-retries 50))
        (cpl:with-failure-handling
            (((or common-fail:navigation-goal-in-collision
                  common-fail:looking-high-level-failure
                  common-fail:perception-low-level-failure
                  common-fail:object-unreachable
                  common-fail:manipulation-low-level-failure) (e)
               (when placed-from
                 ;; the base pose it was put down from did not do: the costmap's solutions
                 (log-fd :info 'fetch "Not from where ~a was put down: ~a" (object-text ?object) e)
                 (setf placed-from nil)
                 (cpl:retry))
               (common-fail:retry-with-loc-designator-solutions
                   ?robot-location relocation-retries
                   (:error-object-or-string
                    (format nil "Object ~a is unreachable: ~a" (object-text ?object) e)
                    :warning-namespace (fd-plans fetch)
                    :rethrow-failure 'common-fail:fetching-failed)
                 ;; look from higher up at the next base pose
                 (exe:perform (desig:an action (type moving-torso) (joint-angle upper-limit)
                                        (goal (cpoe:torso-at :upper-limit)))))))
          (let ((?location (or placed-from ?robot-location)))
            (exe:perform (desig:an action (type navigating) (location ?location) (see ?object)
                                   (grasp ?object))))
          (let ((?target ?look-location))
            (exe:perform (desig:an action (type turning-towards) (target ?target))))
          (cpl:with-retry-counters ((regrasp-retries 2))
            (cpl:with-failure-handling
                ((common-fail:gripper-low-level-failure (e)
                   (log-fd :warn 'fetch "Misgrasp: ~a" e)
                   (release-all-empty-grippers)
                   (cpl:do-retry regrasp-retries
                     (log-fd :info 'fetch "Re-perceiving and re-picking.")
                     (cpl:retry))
                   (cpl:fail 'common-fail:object-unreachable
                             :description "A misgrasp happened and retrying did not help.")))
              (let ((?perceived (exe:perform (desig:an action (type perceiving) (object ?object)))))
                (pick-up-with-alternatives ?perceived all-arms all-grasps)
                (desig:current-desig ?object))))))))))

(defun pick-up-with-alternatives (object all-arms all-grasps)
  "Pick up OBJECT with the arms of ALL-ARMS in turn (1 retry) and for each the grasps of
ALL-GRASPS in turn (5 retries; NIL: the object type's grasps for the arm). Each grasp is first
tried in the belief state (CHECK-PICKING-UP-COLLISIONS), so an unreachable one moves nothing."
  (let* ((arms (or all-arms (pp-plans::free-arms))) (?arm (first arms)))
    (cpl:with-retry-counters ((arm-retries 1))
      (cpl:with-failure-handling
          (((or common-fail:manipulation-low-level-failure
                common-fail:object-unreachable
                desig:designator-error) (e)
             (common-fail:retry-with-list-solutions
                 arms arm-retries
                 (:error-object-or-string (format nil "Manipulation failed: ~a.~%Next." e)
                  :warning-namespace (fd-plans fetch)
                  :rethrow-failure 'common-fail:object-unreachable)
               (setf ?arm (first arms)))))
        (let* ((grasps (or all-grasps (object-grasps object ?arm))) (?grasp (first grasps)))
          (cpl:with-retry-counters ((grasp-retries 5))
            (cpl:with-failure-handling
                (((or common-fail:manipulation-low-level-failure
                      common-fail:object-unreachable
                      desig:designator-error) (e)
                   (common-fail:retry-with-list-solutions
                       grasps grasp-retries
                       (:error-object-or-string (format nil "Picking up failed: ~a.~%Next." e)
                        :warning-namespace (fd-plans fetch))
                     (setf ?grasp (first grasps)))))
              (check-picking-up-collisions object :arms (list ?arm)
                                                  :grasps (and ?grasp (list ?grasp)))
              (let ((?object object))
                (exe:perform (desig:an action (type picking-up)
                                       (desig:when ?arm (arm ?arm))
                                       (desig:when ?grasp (grasp ?grasp))
                                       (object ?object)
                                       (goal (cpoe:object-in-hand ?object))))))))))))

(defun object-grasps (object arm)
  "The grasps of OBJECT's type for ARM, best first for the object's pose relative to the robot."
  (let* ((type (pp-plans:object-designator-type object))
         (in-base (pp-plans::relative-transform (pp-plans::robot-pose-in-map)
                                                (pp-plans:object-pose-in-map object))))
    (man-int:get-action-grasps type arm in-base)))

(defun release-all-empty-grippers ()
  "Open the grippers of the arms that hold nothing and park them (after a misgrasp), so that
the empty hand is out of the camera's view when the object is perceived again."
  (let ((?arms (pp-plans::free-arms)))
    (when ?arms
      (exe:perform (desig:an action (type releasing) (gripper ?arms)))
      (exe:perform (desig:an action (type parking-arms) (arms ?arms))))))
