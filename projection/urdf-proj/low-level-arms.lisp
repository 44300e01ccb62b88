;;;; Low level of the simulated robot, arms and grippers: MOVE-JOINTS, POSITION-ARMS,
;;;; GRIPPER-ACTION, MOVE-TCP with IK over base and torso offsets, and the attachment events.

(in-package :cram-urdf-projection)

(defparameter *joint-convergence-tolerance* 0.17d0
  "Radians (metres) a requested arm joint value may lie outside its limits and still count as
reached after clamping.")

;;; ---- arm joints -------------------------------------------------------------------------------

(defun arm-configuration-pairs (arm configuration)
  "CONFIGURATION of ARM as ((joint value)...): a keyword naming a ROBOT-JOINT-STATES entry
(:park, :point ...), a list of values in ARM-JOINTS order, or a list of (joint value) pairs."
  (let ((joints (arm-joint-names arm)))
    (cond ((null configuration) nil)
          ((and (symbolp configuration) configuration)
           (named-joint-states :arm arm (intern (symbol-name configuration) :keyword)))
          ((and (listp configuration) (every #'realp configuration))
           (unless (= (length configuration) (length joints))
             (projection-error "Arm ~s has ~d joints ~s, got ~d values ~s." arm (length joints)
                               joints (length configuration) configuration))
           (mapcar #'list joints configuration))
          ((and (listp configuration)
                (every (lambda (e) (and (consp e) (stringp (first e)))) configuration))
           (mapcar (lambda (e) (list (first e) (if (consp (cdr e)) (second e) (cdr e)))) configuration))
          (t (projection-error "Arm configuration ~s for ~s: expected a configuration name, ~
                                values in ARM-JOINTS order or (joint value) pairs." configuration arm)))))

(defun set-arm-joints (robot pairs)
  "Set the arm joint PAIRS ((joint value)...) clamped to their limits; returns the pairs that
had to be moved by more than *JOINT-CONVERGENCE-TOLERANCE* as (joint wanted set)."
  (let ((clamped '()) (off '()))
    (loop for (j v) in pairs
          do (unless (and (stringp j) (realp v) (not (and (floatp v) (sb-ext:float-nan-p v))) (< (abs v) 1d6))
               (projection-error "Joint state ~s: expected (joint-name finite-value)." (list j v)))
             (unless (movable-joint-p robot j)
               (projection-error "Joint ~s is not a movable joint of ~s." j (btr:name robot)))
             (let ((c (clamp-joint robot j v)))
               (push (list j c) clamped)
               (when (> (abs (- c v)) *joint-convergence-tolerance*) (push (list j v c) off))))
    (btr:set-robot-state-from-joints (nreverse clamped) robot)
    (nreverse off)))

(defun move-joints (left-configuration right-configuration)
  "Move the arms to LEFT-CONFIGURATION and RIGHT-CONFIGURATION (NIL: that arm stays): each a
configuration name, values in ARM-JOINTS order, or (joint value) pairs. Values are clamped to
the joint limits; a value that lies more than *JOINT-CONVERGENCE-TOLERANCE* outside signals
MANIPULATION-GOAL-NOT-REACHED after moving. Returns the arm joint states."
  (let ((robot (robot-object))
        (pairs (append (arm-configuration-pairs :left left-configuration)
                       (arm-configuration-pairs :right right-configuration))))
    (with-motion ("moving-arm-joints")
      (let ((off (with-sweep-check ("moving-arm-joints" :arm :robot robot)
                   (set-arm-joints robot pairs))))
        (when off
          (cpl:fail 'common-fail:manipulation-goal-not-reached
                    :description (format nil "Arm joints out of their limits: ~
                                              ~{~{~a wanted ~,4f, set ~,4f~}~^; ~}." off))))
      (mapcar (lambda (p) (list (first p) (btr:joint-state robot (first p)))) pairs))))

(defun position-arms (left-configuration right-configuration)
  "Put the arms into the named configurations (e.g. :PARK, :POINT, :POINT-AHEAD), as MOVE-JOINTS."
  (move-joints left-configuration right-configuration))

;;; ---- grippers --------------------------------------------------------------------------------------

(defun gripper-joint-states (arm action &optional (robot (robot-object)))
  "The (joint value) pairs of ARM's gripper for ACTION: :OPEN the joints' upper limits, :CLOSE
or :GRIP their lower limits, a real n (metres) n times the robot's gripper metre-to-joint
multiplier, clamped to the limits."
  (let ((multiplier (or (fact-value '?m `(rob-int:gripper-meter-to-joint-multiplier ,(robot-name) ?m)) 1)))
    (mapcar (lambda (j)
              (multiple-value-bind (lo hi) (btr:joint-limits robot j)
                (list j (case action
                          (:open hi)
                          ((:close :grip) lo)
                          (t (clamp-joint robot j (* action multiplier)))))))
            (gripper-joints arm))))

(defun gripper-action (action arm &optional maximum-effort)
  "Move the gripper of ARM: ACTION :OPEN (joints to their upper limits), :CLOSE or :GRIP (to
their lower limits), or a real n (each joint to n × the gripper metre-to-joint multiplier,
clamped). After :GRIP a hand link must touch an item, otherwise GRIPPER-CLOSED-COMPLETELY is
signalled. MAXIMUM-EFFORT is accepted and has no effect in projection. Returns the joint values."
  (declare (ignore maximum-effort))
  (check-arm arm)
  (unless (or (member action '(:open :close :grip)) (and (realp action) (not (and (floatp action) (sb-ext:float-nan-p action))) (< (abs action) 1d6)))
    (projection-error "GRIPPER-ACTION: action ~s, expected :OPEN, :CLOSE, :GRIP or a real." action))
  (let ((robot (robot-object)))
    (with-motion ("gripping")
      (let ((pairs (gripper-joint-states arm action robot)))
        (with-sweep-check ("gripping" :gripper :robot robot)
          (btr:set-robot-state-from-joints pairs robot))
        (when (eq action :grip)
          (let ((hand (hand-links arm robot)))
            (unless (loop for (a la b lb) in (btr::contact-records btr:*current-bullet-world* robot)
                          for link = (if (eq a robot) la lb)
                          for other = (if (eq a robot) b a)
                          thereis (and (typep other 'btr:item) link (member link hand :test #'string=)))
              (cpl:fail 'common-fail:gripper-closed-completely
                        :description (format nil "There was no object to grip in the ~(~a~) gripper." arm)))))
        (mapcar #'second pairs)))))

(defun move-gripper-joint (action arm &optional effort)
  "GRIPPER-ACTION under CRAM's motion command name."
  (gripper-action action arm effort))

;;; ---- attachments through events -----------------------------------------------------------------

(defun event-object (event)
  (let ((name (or (cpoe:event-object-name event)
                  (let ((d (cpoe:event-object-designator event)))
                    (or (desig:desig-prop-value d :name)
                        (ignore-errors (desig:object-identifier d)))))))
    (and name (or (btr:object btr:*current-bullet-world* name)
                  (find-if (lambda (o) (string-equal (string (btr:name o)) (string name)))
                           (btr:objects btr:*current-bullet-world*))
                  (projection-error "Attachment event ~s names the object ~s, which is not in the ~
                                     belief state." event name)))))

(defmethod coe:on-event urdf-proj-attach-object ((event cpoe:object-attached-robot))
  (let ((robot (btr:get-robot-object)) (object (event-object event)))
    (when (and robot object)
      (let ((link (or (cpoe:event-link event) (end-effector-link (or (cpoe:event-arm event) :right)))))
        (btr:attach-object robot object :link link :grasp (cpoe:event-grasp event))
        link))))

(defmethod coe:on-event urdf-proj-detach-object ((event cpoe:object-detached-robot))
  (let ((robot (btr:get-robot-object)) (object (event-object event)))
    (when (and robot object)
      (btr:detach-object robot object :link (cpoe:event-link event))
      t)))
