;;;; Delivering: drive to where the target can be reached, look at it and place the object
;;;; there, with new target samples and base poses on failures (CRAM's retry levels), a
;;;; stability pre-check of unstable targets, and the fallback of dropping at the sink.

(in-package :cram-fetch-deliver-plans)

(defparameter *stability-max-displacement* 0.2d0
  "Metres the dropped copy may move before the target pose counts as unstable.")
(defparameter *stability-seconds* 1d0
  "Seconds of physics the stability check simulates (CRAM: 500 + 100 steps of 1/600 s).")

(defparameter *unreachable-target-retries* 20
  "How many further target samples a delivery tries when no base pose can be found for a
sample (apart from CRAM's 4 retries of undeliverable targets).")

(defun delivering-robot-location (target arm)
  "CRAM's default base location of a delivery: where the robot reaches TARGET with ARM."
  (let ((?robot (robot-name)) (?target target) (?arm arm))
    (if ?arm
        (desig:a location (reachable-for ?robot) (location ?target) (arm ?arm))
        (desig:a location (reachable-for ?robot) (location ?target)))))

(defun check-placing-pose-stability (object target)
  "Drop a copy of OBJECT at a sample of TARGET in a copy of the belief state as a release
settles it (PP-PLANS::SETTLE-RELEASED-OBJECT, for *STABILITY-SECONDS*); signal a
HIGH-LEVEL-FAILURE \"Pose unstable.\" when it moves more than *STABILITY-MAX-DISPLACEMENT*."
  (let* ((name (designator-object-name object))
         (o (and name (btr:object btr:*current-bullet-world* name)))
         (pose (ignore-errors (pp-plans:pose-in-map (desig:reference target)))))
    (when (and o pose)
      (let* ((world (btr:copy-world btr:*current-bullet-world*))
             (copy (btr:object world name)))
        (unwind-protect
             (let ((robot (find-if #'btr:robot-object-p (btr:objects world))))
               (when robot (btr:detach-all-objects robot))
               (setf (btr:pose copy) pose)
               ;; as a release comes to rest: lowered onto the surface below, the robot out
               ;; of the physics (standing in the way, it would catch what the release throws)
               (let ((btr:*current-bullet-world* world)
                     (pp-plans::*settling-seconds* *stability-seconds*))
                 (pp-plans::settle-released-object name))
               (let ((moved (cl-transforms:v-dist (cl-transforms:origin (btr:pose copy))
                                                  (cl-transforms:origin pose))))
                 (when (> moved *stability-max-displacement*)
                   (cpl:fail 'common-fail:high-level-failure
                             :description (format nil "Pose unstable: ~a moved ~,2f m when ~
                                                       dropped at ~a." name moved target)))))
          (btr:destroy-world world))))))

(defun target-stable-p (target)
  "CRAM's stable targets: a location with ATTACHMENT(S) or ABOVE needs no stability check."
  (or (prop target :attachment) (prop target :attachments) (prop target :above)))

(defun solution-stable-p (target)
  "True when the current solution of TARGET needs no stability check: one of its predefined
ATTACHMENTS poses (a sample of the costmap of the same designator, when the attachments were
rejected, is dropped in a copy as any other), any solution of a singular ATTACHMENT, or of an
ABOVE target without attachments."
  (cond ((prop target :attachments)
         (let ((pose (ignore-errors (pp-plans:pose-in-map (desig:reference target)))))
           (and pose
                (some (lambda (attachment)
                        (< (cl-transforms:v-dist (cl-transforms:origin pose)
                                                 (cl-transforms:origin
                                                  (pp-plans:pose-in-map attachment)))
                           1d-3))
                      (ignore-errors (costmap::attachment-poses target))))))
        (t (target-stable-p target))))

(defun deliver (&key object arm target robot-location &allow-other-keys)
  "Deliver the held OBJECT to TARGET (a location designator) with ARM (NIL: the arm holding
it), standing at ROBOT-LOCATION, at a sample of TARGET within the robot's reach there
(TARGET-REACHABLE-FROM). Retries: a new sample of the target (4) as placing fails, a
new base pose (15) on navigation collisions, undeliverable or manipulation failures, a new
target (4, outermost), and a new target (*UNREACHABLE-TARGET-RETRIES*) when no base pose for
the target sample can be found (a designator error). Returns the object designator; DELIVERING-FAILED when all are used up."
  (let ((?object object)
        (?target (reset-or-nil target))
        (?robot-location (reset-or-nil robot-location))
        (?arm (or arm (first (pp-plans::arms-holding (designator-object-name object)))))
        (stood nil))
    (cpl:with-failure-handling
        ((desig:designator-error (e)
           (cpl:fail 'common-fail:delivering-failed
                     :description (format nil "Delivering ~a: a designator could not be resolved: ~a"
                                          (object-text ?object) e))))
      (with-base-pose-verdicts ()
      (let ((*placing-hint* (list nil)))
      (cpl:with-retry-counters ((outer-target-retries 4)
                                (unreachable-target-retries *unreachable-target-retries*))
        (cpl:with-failure-handling
            ((common-fail:object-undeliverable (e)
               ;; CRAM's outer target level
               (common-fail:retry-with-loc-designator-solutions
                   ?target outer-target-retries
                   (:error-object-or-string
                    (format nil "Undeliverable. Trying another target location.~%~a" e)
                    :warning-namespace (fd-plans deliver)
                    :reset-designators (remove nil (list ?robot-location))
                    :rethrow-failure 'common-fail:delivering-failed)
                 ;; the reset robot location, relative to the new target sample
                 (setf ?robot-location (and ?robot-location
                                            (desig:current-desig ?robot-location)))))
             (desig:designator-error (e)
               ;; a target sample no base pose reaches (the robot location cannot be resolved
               ;; for it, nothing was tried): the next sample, on a budget of its own
               (common-fail:retry-with-loc-designator-solutions
                   ?target unreachable-target-retries
                   (:error-object-or-string
                    (format nil "No base pose reaches this target sample; trying another.~%~a" e)
                    :warning-namespace (fd-plans deliver)
                    :reset-designators (remove nil (list ?robot-location))
                    :rethrow-failure 'common-fail:delivering-failed)
                 (setf ?robot-location (and ?robot-location
                                            (desig:current-desig ?robot-location))))))
          (cpl:with-retry-counters ((relocation-retries 15))
            (cpl:with-failure-handling
                (((or common-fail:navigation-goal-in-collision
                      common-fail:object-undeliverable
                      common-fail:manipulation-low-level-failure) (e)
                   (common-fail:retry-with-loc-designator-solutions
                       ?robot-location relocation-retries
                       (:error-object-or-string
                        (format nil "Object is undeliverable from this base location.~%~a" e)
                        :warning-namespace (fd-plans deliver)
                        :reset-designators (list ?target)
                        :rethrow-failure 'common-fail:object-undeliverable))))
              (let ((?location ?robot-location)
                    (?place (list ?object ?arm ?target)))
                (exe:perform (desig:an action (type navigating) (location ?location)
                                       (place ?place))))
              ;; CRAM's T' = target + (reachable-from robot): the samples within reach of
              ;; where the robot now stands
              (let ((?target (target-reachable-from ?target (robot-name))))
               (handler-case (desig:reference ?target)
                 (desig:designator-error ()
                   (cpl:fail 'common-fail:object-undeliverable
                             :description (format nil "No sample of ~a is within reach of the ~
                                                       robot here." target))))
               (cpl:with-retry-counters ((target-retries 4))
                (cpl:with-failure-handling
                    (((or common-fail:looking-high-level-failure
                          common-fail:object-unreachable
                          common-fail:high-level-failure) (e)
                       (common-fail:retry-with-loc-designator-solutions
                           ?target target-retries
                           (:error-object-or-string (format nil "Placing failed: ~a" e)
                            :warning-namespace (fd-plans deliver)
                            :reset-designators (remove nil (list ?robot-location))
                            :rethrow-failure 'common-fail:object-undeliverable))))
                  (let ((?look ?target))
                    (exe:perform (desig:an action (type turning-towards) (target ?look))))
                  ;; the sample the navigation pre-check put the object down at from here
                  ;; first (once), then the target's samples in turn
                  (let ((?at (multiple-value-bind (at hinted)
                                 (check-placing-collisions ?object ?arm ?target
                                                           :first (take-placing-hint))
                               (unless hinted (setf ?target at))
                               at)))
                    (unless (solution-stable-p ?at)
                      (check-placing-pose-stability ?object ?at))
                    (setf stood (btr:pose (btr:get-robot-object)))
                    (handler-case
                        (exe:perform (desig:an action (type placing) (arm ?arm) (object ?object)
                                               (target ?at)))
                      (common-fail:manipulation-low-level-failure (e)
                        (cpl:fail 'common-fail:object-unreachable
                                  :description (format nil "Placing ~a at ~a failed: ~a"
                                                       (object-text ?object) ?at e)))))
                  ;; where it stood before placing moved the base to reach: the pose the
                  ;; pre-checks judged
                  (remember-placing ?object ?arm stood)
                  (desig:current-desig ?object)))))))))))))

(defun drop-at-sink ()
  "CRAM's fallback after a failed delivery: drive to the map origin facing -y and put the held
object down in front of the robot; failures of both steps are ignored."
  (let ((?pose (cl-transforms-stamped:make-pose-stamped
                cram-tf:*fixed-frame* 0d0 (cl-transforms:make-3d-vector 0 0 0)
                (cl-transforms:axis-angle->quaternion (cl-transforms:make-3d-vector 0 0 1)
                                                      (/ pi -2)))))
    (handler-case
        (exe:perform (desig:an action (type going) (target (desig:a location (pose ?pose)))))
      (cpl:plan-failure (e) (log-fd :warn 'drop-at-sink "~a~%Ignoring." e)))
    (let ((held (pp-plans::held-objects)))
      (when held
        (let* ((?arm (second (first held)))
               (?down (cl-transforms-stamped:make-pose-stamped
                       cram-tf:*fixed-frame* 0d0
                       (cl-transforms:v+ (cl-transforms:origin
                                          (btr:pose (btr:get-robot-object)))
                                         (cl-transforms:make-3d-vector 0 -0.7 0.9))
                       (cl-transforms:make-identity-rotation))))
          (handler-case
              (exe:perform (desig:an action (type placing) (arm ?arm)
                                     (target (desig:a location (pose ?down)))))
            ((or cpl:plan-failure desig:designator-error pp-plans:pick-place-error) (e)
              (log-fd :warn 'drop-at-sink "~a~%Ignoring." e))))))))
