;;;; The belief state follows the robot, and joint groups move over ROS: trajectories to the
;;;; controllers, success judged from /joint_states within a tolerance and a timeout.

(in-package :cram-ros-pms)

(defvar *stall-timeout* 2
  "Seconds the joints of a commanded group may stand still away from the goal before its
goal-not-reached failure (a controller that refused the command, or a blocked joint).")

(defvar *joint-tolerance* 0.01
  "Radians (metres for prismatic joints) within which a joint counts as at its goal.")

(defvar *joint-speed* 1.0
  "Radians (metres) per second the trajectories are timed with (the controller may be slower:
it respects the joints' velocity limits).")

;;; ---- the belief state follows the robot ----------------------------------------------------------

(defun sync-belief-state (&key (connection *connection*) (world btr:*current-bullet-world*))
  "Write the robot's latest joint positions (/joint_states) and base pose (TF map → base
frame) into the robot of the belief state WORLD (attached objects follow), then the TF of the
environment. Returns the robot object."
  (let* ((robot (urdf-proj:robot-object world))
         (positions (robot-joint-positions connection))
         (pose (robot-base-pose connection))
         (pairs (loop for name in (btr:joint-names robot)
                      for value = (gethash name positions)
                      when value collect (list name value))))
    (sb-thread:with-recursive-lock (urdf-proj::*motion-lock*)
      (handler-bind ((warning #'muffle-warning))
        (when pairs (btr:set-robot-state-from-joints pairs robot))
        (when pose (setf (btr:pose robot) pose)))
      (when (and urdf-proj::*tf-from-belief-state* cram-tf:*transformer*)
        (urdf-proj:update-tf-from-belief-state)))
    robot))

(defun belief-robot-state (&optional (robot (urdf-proj:robot-object)))
  "(base-pose joint-alist) of ROBOT in the belief state."
  (list (btr:pose robot) (btr:joint-states robot)))

(defun restore-belief-robot-state (state &optional (robot (urdf-proj:robot-object)))
  (destructuring-bind (pose joints) state
    (handler-bind ((warning #'muffle-warning))
      (setf (btr:pose robot) pose)
      (btr:set-robot-state-from-joints joints robot))))

(defun plan-in-belief (thunk)
  "Run THUNK (a projection motion on the belief robot) and return the robot state it produced
as (values base-pose joint-alist result failure); the belief robot is put back where it was (the
robot, not the belief, is to move). A plan failure of THUNK is returned, not signalled."
  (sb-thread:with-recursive-lock (urdf-proj::*motion-lock*)
    (let* ((robot (urdf-proj:robot-object))
           (before (belief-robot-state robot))
           (result nil) (failure nil))
      (unwind-protect
           (let ((urdf-proj::*tf-from-belief-state* nil)
                 (urdf-proj::*after-motion-hooks* '()))
             (handler-case (setf result (funcall thunk))
               (cpl:plan-failure (f) (setf failure f)))
             (values (btr:pose robot) (btr:joint-states robot) result failure))
        (restore-belief-robot-state before robot)))))

;;; ---- joint groups ----------------------------------------------------------------------------------

(defun continuous-joint-p (joint &optional (robot (urdf-proj:robot-object)))
  (multiple-value-bind (lo hi) (btr:joint-limits robot joint)
    (not (and lo hi))))

(defun joint-error (joint goal actual)
  (if (continuous-joint-p joint)
      (abs (urdf-proj::normalize-angle (- goal actual)))
      (abs (- goal actual))))

(defun clamp-goal (joint value &optional (robot (urdf-proj:robot-object)))
  "VALUE within the URDF limits of JOINT (the controllers refuse anything outside)."
  (multiple-value-bind (lo hi) (btr:joint-limits robot joint)
    (if (and lo hi (< lo hi)) (max lo (min hi value)) value)))

(defun trajectory-message (pairs duration)
  (roslisp:make-message "trajectory_msgs/JointTrajectory"
                        (stamp header) (roslisp:ros-time)
                        joint_names (map 'vector #'first pairs)
                        points (vector (make-instance 'trajectory_msgs-msg:JointTrajectoryPoint
                                                      :positions (map 'vector (lambda (p) (float (second p) 1d0)) pairs)
                                                      :time_from_start (float duration 1d0)))))

(defun send-joint-command (controller pairs)
  "Publish a one-point trajectory to CONTROLLER/command moving the joints of PAIRS ((joint
goal)...) there, timed with *JOINT-SPEED* from their current positions."
  (let* ((current (robot-joint-positions))
         (largest (loop for (j g) in pairs
                        maximize (let ((c (gethash j current))) (if c (joint-error j g c) 0d0))))
         (duration (max 0.2d0 (/ largest *joint-speed*))))
    (publish-when-connected *connection* (robot-topic (format nil "~a/command" controller))
                            "trajectory_msgs/JointTrajectory" (trajectory-message pairs duration))))

(defun move-joint-group (controller pairs failure what &key (timeout *motion-timeout*) settle)
  "Command CONTROLLER to move the joints of PAIRS ((joint goal)...) and wait on /joint_states
until each is within *JOINT-TOLERANCE* of its goal. The failure class FAILURE is signalled (its
description naming WHAT, the joints and the values) when they stand still away from the goal for
*STALL-TIMEOUT* s or TIMEOUT s pass. With SETTLE, standing still anywhere ends the motion
(grippers closing on an object). Standing still is seen in messages: the time counts only while
/joint_states keeps arriving (at least half of them at 50 Hz), so a robot whose messages are late
(a loaded machine) is not taken for one that stopped. Syncs the belief state; returns the
positions reached."
  (let* ((c *connection*)
         (joints (mapcar #'first pairs))
         (start (now))
         (last-positions nil) (last-change start) (messages-at-change 0)
         (reached nil))
    (when (null pairs) (return-from move-joint-group nil))
    (send-joint-command controller pairs)
    (flet ((positions () (let ((p (robot-joint-positions c))) (mapcar (lambda (j) (gethash j p)) joints)))
           (still-for-p (seconds)
             ;; no change for SECONDS of wall time, seen in at least 25 messages per second
             (and (> (- (now) last-change) seconds)
                  (>= (- (connection-joint-messages c) messages-at-change) (ceiling (* 25 seconds))))))
      (loop
        (wait-until c (lambda () nil) :timeout 0.05)
        (let ((now (positions)))
          (when (some #'null now)
            (connection-fail "/joint_states" "the joints ~{~a~^, ~} of ~a are missing from it."
                             (loop for j in joints for v in now unless v collect j) what))
          (when (or (null last-positions)
                    (loop for a in now for b in last-positions thereis (> (abs (- a b)) 1d-4)))
            (setf last-positions now last-change (now)
                  messages-at-change (connection-joint-messages c)))
          ;; within the tolerance, the controller is let finish its trajectory (a tenth of the
          ;; tolerance, the joints still, or half a second) so that the next motion starts from
          ;; where this one was meant to end: a gripper opened early would let go elsewhere
          (flet ((within-p (tolerance)
                   (every (lambda (p v) (<= (joint-error (first p) (second p) v) tolerance)) pairs now)))
            (when (and (not reached) (within-p *joint-tolerance*))
              (setf reached (now)))
            (when (and reached (or (within-p (/ *joint-tolerance* 10)) (still-for-p 0.1)
                                   (> (- (now) reached) 0.5)))
              (return)))
          (when (and settle (> (- (now) start) 0.5) (still-for-p 0.3))
            (return))
          (when (and (not reached) (or (still-for-p *stall-timeout*) (> (- (now) start) timeout)))
            (sync-belief-state)
            (cpl:fail failure
                      :description
                      (format nil "~a did not reach its goal (~:[joints stopped for ~,1f s~*~;~*timeout ~a s~]): ~
                                   ~{~{~a wanted ~,4f, at ~,4f~}~^; ~}."
                              what (> (- (now) start) timeout) (- (now) last-change) timeout
                              (loop for (j g) in pairs for v in now collect (list j g v))))))))
    (sync-belief-state)
    (values (positions-of joints) (and reached t))))

(defun positions-of (joints)
  (let ((p (robot-joint-positions))) (mapcar (lambda (j) (list j (gethash j p))) joints)))

(defun changed-pairs (before after joints &key (threshold 1d-4))
  "The (joint value) pairs of AFTER (an alist) for JOINTS that differ from BEFORE (a hash table
of the robot's positions) by more than THRESHOLD."
  (loop for j in joints
        for new = (cdr (assoc j after :test #'string=))
        for old = (gethash j before)
        when (and new (or (null old) (> (joint-error j new old) threshold)))
          collect (list j (clamp-goal j new))))

(defun arm-controller (arm) (format nil "~(~a~)_arm_controller" arm))
(defun gripper-controller (arm) (format nil "~(~a~)_gripper_controller" arm))
