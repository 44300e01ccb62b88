;;;; The belief state of environment manipulation: container events move the joint (clamped,
;;;; rounded to 0.1 mm), objects attached to a moved link ride along; grasping an object detaches
;;;; it from the environment, putting it down attaches it to every environment link it rests on.

(in-package :cram-urdf-environment-manipulation)

(defvar *environment-joint-state-hooks* '()
  "Functions called with (environment-name joint-states) after a container event moved a joint
of the environment: JOINT-STATES is the alist (joint-name . value) of all its movable joints.
The ROS integration publishes them on kitchen/cram_joint_states while a node runs.")

(defparameter *resting-contact-distance* 0.005d0
  "Metres between an object and an environment link within which the object counts as resting
on the link when it is put down.")

(defun event-environment (event)
  "The environment object of the container EVENT: its ENVIRONMENT-NAME, else the belief state's
environment."
  (let ((name (cpoe:event-environment-name event)))
    (or (if name
            (environment-object name)
            (btr:get-environment-object))
        (env-error "The container event ~s names no environment and the belief state has none."
                   event))))

(defun round-joint-value (value direction)
  "VALUE rounded to 1e-4: down when DIRECTION is :OPEN, up when :CLOSE."
  (/ (ecase direction
       (:open (floor (+ (* value 1d4) 1d-6)))
       (:close (ceiling (- (* value 1d4) 1d-6))))
     1d4))

(defun move-joint-by-event (event direction)
  "Move the joint of the container EVENT by its distance (opening: up, closing: down), rounded
and clamped to the joint's limits (with a warning when beyond), then run
*ENVIRONMENT-JOINT-STATE-HOOKS*. Returns the new joint value."
  (let* ((environment (event-environment event))
         (joint (cpoe:event-joint-name event))
         (distance (or (cpoe:event-distance event) 0)))
    (unless (and (stringp joint) (member joint (btr:joint-names environment) :test #'string=))
      (env-error "The container event ~s names the joint ~s, which is no movable joint of ~s."
                 event joint (btr:name environment)))
    (let* ((current (btr:joint-state environment joint))
           (value (round-joint-value (if (eq direction :open) (+ current distance) (- current distance))
                                     direction)))
      (btr:set-robot-state-from-joints (list (list joint value)) environment)
      (let ((states (btr:joint-states environment)))
        (dolist (hook *environment-joint-state-hooks*)
          (funcall hook (btr:name environment) states)))
      (btr:joint-state environment joint))))

(defmethod coe:on-event env-man-open-container ((event cpoe:container-opening-event))
  (move-joint-by-event event :open))

(defmethod coe:on-event env-man-close-container ((event cpoe:container-closing-event))
  (move-joint-by-event event :close))

;;; ---- objects and environment links ----------------------------------------------------------

(defun event-object-name (event)
  (or (and (typep event '(or cpoe:object-attached-robot cpoe:object-detached-robot))
           (cpoe:event-object-name event))
      (let ((designator (cpoe:event-object-designator event)))
        (and designator
             (or (desig:desig-prop-value (desig:current-desig designator) :name)
                 (ignore-errors (desig:object-identifier (desig:current-desig designator))))))))

(defun belief-object (name)
  (and name (btr:object btr:*current-bullet-world* name)))

(defun detach-object-from-environment (object &optional (environment (btr:get-environment-object)))
  "Detach OBJECT (an object or its name) from every link of ENVIRONMENT; returns the links it
was attached to."
  (let ((object (if (typep object 'btr:object) object (belief-object object))))
    (when (and object environment)
      (let ((links (btr:object-attached environment object)))
        (when links (btr:detach-object environment object))
        links))))

(defun box-overlaps-link-p (lo hi boxes i margin)
  "True when the box LO HI (3D vectors) and the box of link I in BOXES (BTR:LINK-AABBS) are at
most MARGIN apart along every axis."
  (let ((k (* 6 i)))
    (and (<= (- (cl-transforms:x lo) margin) (aref boxes (+ k 3)))
         (<= (- (aref boxes k) margin) (cl-transforms:x hi))
         (<= (- (cl-transforms:y lo) margin) (aref boxes (+ k 4)))
         (<= (- (aref boxes (+ k 1)) margin) (cl-transforms:y hi))
         (<= (- (cl-transforms:z lo) margin) (aref boxes (+ k 5)))
         (<= (- (aref boxes (+ k 2)) margin) (cl-transforms:z hi)))))

(defun touched-environment-links (object environment)
  "The links of ENVIRONMENT within *RESTING-CONTACT-DISTANCE* of OBJECT, in link order: links
whose bounding box is that close are measured with the shim's closest distance."
  (let ((world (btr:world-handle (btr:world object)))
        (margin *resting-contact-distance*))
    (multiple-value-bind (lo hi) (btr:aabb object)
      (loop with boxes = (btr:link-aabbs environment)
            for link in (btr:link-names environment)
            for i from 0
            when (and (cram-native:robot-link-has-body-p world (btr:object-handle environment) i)
                      (box-overlaps-link-p lo hi boxes i margin)
                      (<= (cram-native:closest-distance world (btr:object-handle object)
                                                        (btr:object-handle environment)
                                                        :link-b i :max-distance (* 2 margin))
                          margin))
              collect link))))

(defun attach-object-to-touched-links (object &optional (environment (btr:get-environment-object)))
  "Attach OBJECT (an object or its name) to every link of ENVIRONMENT it rests on (touches), so
that it rides along when a joint moves those links; returns the links."
  (let ((object (if (typep object 'btr:object) object (belief-object object))))
    (when (and object environment (typep object 'btr:item))
      (let ((links (touched-environment-links object environment)))
        (dolist (link links)
          (btr:attach-object environment object :link link))
        links))))

(defmethod coe:on-event env-man-detach-grasped ((event cpoe:object-attached-robot))
  (detach-object-from-environment (event-object-name event)))

(defmethod coe:on-event env-man-attach-placed ((event cpoe:object-location-changed))
  (let ((object (belief-object (event-object-name event)))
        (robot (btr:get-robot-object)))
    ;; an object still in a hand is not put down
    (when (and object (not (and robot (btr:object-attached robot object))))
      (attach-object-to-touched-links object))))
