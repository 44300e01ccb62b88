;;;; The occasions of environment manipulation: CPOE:CONTAINER-STATE, CPOE:LOCATION-ACCESSIBLE
;;;; and CPOE:LOCATION-RESET, as CRAM's plans test them for goals.

(in-package :cram-urdf-environment-manipulation)

(defun container-state-p (designator state)
  "True when the container of the object DESIGNATOR is at STATE: a number (its joint within
*CONTAINER-STATE-CONVERGENCE-DELTA* of the number clipped to the limits), :CLOSED (within the
delta of the lower limit) or :OPEN (not within it)."
  (let* ((container (container-designator-container designator))
         (value (container-joint-state container))
         (delta *container-state-convergence-delta*))
    (flet ((near (target) (<= (abs (- value target)) delta)))
      (cond ((eq state :closed) (near (container-lower container)))
            ((eq state :open) (not (near (container-lower container))))
            ((realp state) (near (max (container-lower container)
                                      (min (container-upper container) (d state)))))
            (t (env-error "CPOE:CONTAINER-STATE: state ~s, expected :OPEN, :CLOSED or a joint ~
                           value." state))))))

(defun location-reference (location key)
  "The object designator of LOCATION's KEY property (:IN, :ABOVE, :ON), or NIL."
  (and (typep location 'desig:location-designator)
       (let ((value (desig:desig-prop-value (desig:current-desig location) key)))
         (and (typep value 'desig:object-designator) value))))

(defun designator-type (designator)
  (let ((type (designator-property designator :type)))
    (and (keywordp type) type)))

(defun container-designator-p (designator)
  "True for an object designator of a container type with a URDF-NAME."
  (and designator (container-type-p (designator-type designator))
       (designator-property designator :urdf-name) t))

(defun part-of-robot-p (designator)
  "True when the object DESIGNATOR is (part of) the robot."
  (let ((robot (ignore-errors (rob-int:current-robot-name)))
        (part-of (designator-property designator :part-of)))
    (and robot part-of (string-equal (string part-of) (string robot)))))

(defun prismatic-designator-p (designator)
  (let ((type (designator-type designator)))
    (or (and type (man-int:object-type-subtype-p :container-prismatic type))
        (and (designator-property designator :urdf-name)
             (eq (container-joint-type (container-designator-container designator)) :prismatic)))))

(defun outer-location (designator)
  "The location of the object DESIGNATOR (its own LOCATION property), or NIL."
  (let ((location (designator-property designator :location)))
    (and (typep location 'desig:location-designator) location)))

(defun location-accessible-p (location)
  "CRAM's accessibility: (in C) when C is (part of) the robot or open; (above C) when C is no
drawer or open; otherwise when the reference object's own location is accessible, or true."
  (let ((in (location-reference location :in))
        (above (location-reference location :above)))
    (cond ((and in (part-of-robot-p in)) t)
          ((and in (container-designator-p in)) (container-state-p in :open))
          ((and above (container-designator-p above) (prismatic-designator-p above))
           (container-state-p above :open))
          (t (let* ((reference (or in above (location-reference location :on)))
                    (outer (and reference (outer-location reference))))
               (if outer (location-accessible-p outer) t))))))

(defun location-reset-p (location)
  "CRAM's reset: (in C) with C a container, or (above C) with C a drawer, when C is closed;
(on X) when X's own location is reset; otherwise true."
  (let ((in (location-reference location :in))
        (above (location-reference location :above))
        (on (location-reference location :on)))
    (cond ((and in (container-designator-p in) (not (part-of-robot-p in)))
           (container-state-p in :closed))
          ((and above (container-designator-p above) (prismatic-designator-p above))
           (container-state-p above :closed))
          ((and on (outer-location on)) (location-reset-p (outer-location on)))
          (t t))))

(def-fact-group environment-manipulation-occasions (cpoe:container-state cpoe:location-accessible
                                                    cpoe:location-reset)
  (<- (cpoe:container-state ?container-designator ?state)
    (bound ?container-designator)
    (bound ?state)
    (lisp-pred container-state-p ?container-designator ?state))
  (<- (cpoe:location-accessible ?location)
    (bound ?location)
    (lisp-pred location-accessible-p ?location))
  (<- (cpoe:location-reset ?location)
    (bound ?location)
    (lisp-pred location-reset-p ?location)))

(setf (documentation 'cpoe:location-accessible 'function)
      "Occasion (cpoe:location-accessible ?location): what ?location names can be reached — (in
C) with C open or part of the robot, (above C) with C open or no drawer, else the reference
object's own location accessible.")
(setf (documentation 'cpoe:location-reset 'function)
      "Occasion (cpoe:location-reset ?location): the container of ?location is closed again —
(in C), (above C) with C a drawer — or (on X) with X's own location reset; else true.")
