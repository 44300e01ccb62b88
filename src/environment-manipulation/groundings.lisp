;;;; Action groundings of environment manipulation: OPENING and CLOSING (an object designator
;;;; of a container), ACCESSING and SEALING (a location designator), PULLING and PUSHING (arm
;;;; poses). Bad input is reported when the designator is grounded, naming what was written.

(in-package :cram-urdf-environment-manipulation)

(defparameter *environment-action-types* '(:opening :closing :accessing :sealing :pulling :pushing)
  "The action types ENV-MAN grounds.")

(defun prop (designator key)
  (desig:desig-prop-value designator key))

(defun arm-list (value what designator)
  (let ((arms (if (listp value) value (list value))))
    (dolist (arm arms)
      (unless (member arm (robot-arms))
        (env-error "The ~(~a~) of ~s is ~s: expected one of the robot's arms ~{~(~a~)~^, ~}."
                   what designator value (robot-arms))))
    arms))

(defun resolved (plan entries)
  (list plan (desig:make-designator :action (remove-if (lambda (e) (null (second e))) entries))))

(defun ground-opening-or-closing (type d)
  (let* ((object (prop d :object))
         (container (container-designator-container object))
         (action (if (eq type :opening) :open :close))
         (arm (let ((arm (prop d :arm)))
                (cond ((null arm) (or (first (free-arms))
                                      (env-error "The ~(~a~) action ~s has no ARM and every hand is ~
                                                  full." type d)))
                      ((and (listp arm) arm) (first (arm-list arm :arm d)))
                      (t (check-arm arm)))))
         (grasps (let ((g (or (prop d :grasps) (prop d :grasp))))
                   (and g (container-grasps container g))))
         (distance (check-distance (prop d :distance))))
    ;; a distance beyond the joint's limits is clipped with a warning when the plan runs
    (list (resolved 'manipulate-container
                    `((:type ,type) (:action ,action) (:object ,object) (:arm ,arm)
                      (:grasps ,grasps) (:distance ,distance))))))

(defun ground-accessing-or-sealing (type d)
  (let ((location (prop d :location)))
    (unless (typep location 'desig:location-designator)
      (env-error "The ~(~a~) action ~s needs a LOCATION designator such as (a location (in ~
                  (an object (type drawer) (urdf-name ...) (part-of iai-kitchen)))), got ~s."
                 type d location))
    (let ((container (location-container location))
          (robot-location (prop d :robot-location)))
      (when container (container-designator-container container))
      (when (and robot-location (not (typep robot-location 'desig:location-designator)))
        (env-error "The ROBOT-LOCATION of ~s is ~s: expected a location designator." d robot-location))
      (list (resolved 'access-or-seal-location
                      `((:type ,type) (:action ,(if (eq type :accessing) :open :close))
                        (:location ,location)
                        (:arms ,(let ((arms (or (prop d :arms) (prop d :arm))))
                                  (and arms (arm-list arms :arms d))))
                        (:grasps ,(let ((g (or (prop d :grasps) (prop d :grasp))))
                                    (and g container
                                         (container-grasps (container-designator-container container) g))))
                        (:distance ,(check-distance (prop d :distance)))
                        (:robot-location ,robot-location)))))))

(defun ground-pulling-or-pushing (type d)
  (let ((left (prop d :left-poses)) (right (prop d :right-poses)))
    (unless (or left right)
      (env-error "The ~(~a~) action ~s needs LEFT-POSES or RIGHT-POSES." type d))
    (list (resolved 'pp-plans:move-arms-in-sequence
                    `((:type ,type) (:left-poses ,left) (:right-poses ,right)
                      (:collision-mode ,(prop d :collision-mode)))))))

(defun signal-grounding-error (condition)
  "The plan function of a grounding that could not be computed: signals CONDITION."
  (error condition))

(defun ground-environment-action (type designator)
  "The groundings of the ENV-MAN action DESIGNATOR of TYPE; a grounding that signals the error
when the designator is bad."
  (handler-case
      (ecase type
        ((:opening :closing) (ground-opening-or-closing type designator))
        ((:accessing :sealing) (ground-accessing-or-sealing type designator))
        ((:pulling :pushing) (ground-pulling-or-pushing type designator)))
    (error (e) (list (list 'signal-grounding-error e)))))

(def-fact-group environment-manipulation-groundings (desig:action-grounding)
  (<- (desig:action-grounding ?designator ?grounding)
    (desig:desig-prop ?designator (:type ?type))
    (member ?type (:opening :closing :accessing :sealing :pulling :pushing))
    (lisp-fun ground-environment-action ?type ?designator ?groundings)
    (member ?grounding ?groundings)))
