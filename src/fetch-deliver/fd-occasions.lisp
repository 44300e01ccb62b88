;;;; Occasions the household plans test before each step, so that a step whose goal already
;;;; holds is skipped: an object in a hand, an object at a location, a location whose pose is
;;;; certain, the torso at a height, the robot at a location.

(in-package :cram-fetch-deliver-plans)

(defparameter *location-proximity* 0.05d0
  "Metres within which an object counts as at a location designator: of one of its POSE or
POSES, or of its costmap's places.")

(defun designator-object-name (object)
  "The belief-state name of the object designator (or name) OBJECT, or NIL when it has none."
  (cond ((typep object 'desig:object-designator)
         (let ((current (desig:current-desig object)))
           (or (prop current :name)
               (ignore-errors (desig:object-identifier current)))))
        ((and object (symbolp object)) object)))

(defun object-held-p (object &optional arm)
  "True when the robot holds OBJECT (an object designator or name), with ARM when given
(:LEFT-OR-RIGHT or NIL: any arm)."
  (let ((name (designator-object-name object)))
    (and name
         (find-if (lambda (held)
                    (and (eq (first held) name)
                         (or (null arm) (eq arm :left-or-right) (eq arm (second held)))))
                  (pp-plans::held-objects)))))

(defun location-poses (location)
  "The poses a location designator names with POSE or POSES, or NIL."
  (let ((pose (prop location :pose)) (poses (prop location :poses)))
    (cond (pose (list pose))
          ((and poses (listp poses)) poses))))

(defparameter *reference-object-keys*
  '(:in :on :above :of :right-of :left-of :behind :in-front-of :near :far-from :object)
  "The properties of a location designator naming the object it is relative to, in order.")

(defun location-reference-object (location)
  "The object designator LOCATION is relative to ((in C), (on S), (right-of B) ...), or NIL."
  (loop for key in *reference-object-keys*
        for value = (prop location key)
        when (typep value 'desig:object-designator) return value))

(defun environment-part-p (object)
  "True when the object designator OBJECT is (part of) the environment or the robot: CRAM's
kitchen parts count as robots, their poses are always known."
  (let ((part-of (prop object :part-of))
        (name (designator-object-name object)))
    (or part-of
        (and name (let ((o (btr:object btr:*current-bullet-world* name)))
                    (and o (btr:robot-object-p o)))))))

(defun perceived-p (object)
  "True when the object designator OBJECT has been perceived: its equation chain has an
effective designator (what perception equated it with)."
  (and (typep object 'desig:object-designator)
       (desig:newest-effective-designator object)
       t))

(defun location-certain-p (location)
  "CRAM's MAN-INT:LOCATION-CERTAIN: LOCATION has poses, or the object it is relative to is part
of the environment or the robot, or is held; or that object has been perceived (what searching
for the location does), so that a location next to a bowl on the table is certain once the
bowl was found."
  (and (typep location 'desig:location-designator)
       (or (location-poses location)
           (let ((reference (location-reference-object location)))
             (and reference
                  (or (environment-part-p reference)
                      (object-held-p reference)
                      (perceived-p reference)))))))

(defun object-at-location-p (object location)
  "True when the object OBJECT (designator or name) is in the belief state at LOCATION: within
*LOCATION-PROXIMITY* of one of its poses, or inside its costmap or within *LOCATION-PROXIMITY*
of it (a released object settles)."
  (let* ((name (designator-object-name object))
         (o (and name (btr:object btr:*current-bullet-world* name))))
    (when (and o (typep location 'desig:location-designator) (not (object-held-p name)))
      (let* ((pose (btr:pose o))
             (origin (cl-transforms:origin pose))
             (poses (location-poses location)))
        (if poses
            (some (lambda (p)
                    (< (cl-transforms:v-dist origin (cl-transforms:origin (pp-plans:pose-in-map p)))
                       *location-proximity*))
                  poses)
            (let ((costmap (ignore-errors (costmap:designator-costmap location))))
              (and costmap
                   (ignore-errors
                    ;; a released object settles: its place, or one within the proximity
                    (loop with x = (cl-transforms:x origin) and y = (cl-transforms:y origin)
                          for (dx dy) in '((0 0) (1 0) (-1 0) (0 1) (0 -1)
                                           (0.7071 0.7071) (0.7071 -0.7071)
                                           (-0.7071 0.7071) (-0.7071 -0.7071))
                            thereis (plusp (costmap:get-map-value
                                            costmap (+ x (* dx *location-proximity*))
                                            (+ y (* dy *location-proximity*)))))))))))))

(defun torso-at-p (joint-state)
  "True when the robot's torso is within 1 cm of JOINT-STATE (metres, :UPPER-LIMIT,
:LOWER-LIMIT or :MIDDLE)."
  (let* ((robot (btr:get-robot-object))
         (joint (rob-int::first-solution-value
                 '?joint `(rob-int:robot-torso-link-joint ,(robot-name) ?link ?joint))))
    (when (and robot joint)
      (multiple-value-bind (lower upper) (btr:joint-limits robot joint)
        (let ((goal (case joint-state
                      ((:upper-limit upper-limit) upper)
                      ((:lower-limit lower-limit) lower)
                      ((:middle middle) (and lower upper (/ (+ lower upper) 2)))
                      (t (and (realp joint-state) joint-state)))))
          (and goal (< (abs (- (btr:joint-state robot joint) goal)) 0.01d0)))))))

(def-fact-group household-occasions (cpoe:object-in-hand cpoe:object-at-location
                                     cpoe:torso-at man-int:location-certain)
  (<- (cpoe:object-in-hand ?object)
    (lisp-pred object-held-p ?object))
  (<- (cpoe:object-in-hand ?object ?arm)
    (bound ?arm)
    (lisp-pred object-held-p ?object ?arm))
  (<- (cpoe:object-at-location ?object ?location)
    (lisp-pred object-at-location-p ?object ?location))
  (<- (cpoe:torso-at ?joint-state)
    (lisp-pred torso-at-p ?joint-state))
  (<- (man-int:location-certain ?location)
    (lisp-pred location-certain-p ?location)))
