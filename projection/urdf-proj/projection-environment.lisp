;;;; The projection environment of the simulated robot and WITH-SIMULATED-ROBOT.

(in-package :cram-urdf-projection)

(defun guess-robot-name ()
  "The described robot whose URDF name matches an articulated object of the current world,
or NIL."
  (let ((described (rob-int:described-robot-names)))
    (loop for o in (btr:objects btr:*current-bullet-world*)
          for urdf-name = (and (typep o 'btr:robot-object) (cl-urdf:name (btr:urdf o)))
          for match = (and urdf-name
                           (find-if (lambda (r) (or (string-equal (symbol-name r) urdf-name)
                                                    (string-equal (symbol-name r) (symbol-name (btr:name o)))))
                                    described))
          when match return match)))

(defun robot-frame (query variable default)
  "The value of VARIABLE in the first solution of QUERY (about the current robot), or DEFAULT."
  (or (and rob-int:*robot-name* (ignore-errors (fact-value variable query))) default))

(defun belief-robot-root-link ()
  "The root link of the robot in the belief state, or NIL without one: CRAM-TF's base frame in
the projection. The robot's pose in the belief state is the pose of that link (navigation moves
it, CRAM-TF:ROBOT-CURRENT-POSE reports it), also when a setup re-rooted the URDF at another link
than the ROBOT-BASE-FRAME fact names (Pepper: base_footprint on the floor, base_link 0.82 m up)."
  (let ((robot (ignore-errors (btr:get-robot-object))))
    (and robot (cl-urdf:name (cl-urdf:root-link (btr:urdf robot))))))

(defun arm-tool-frame (arm default)
  (robot-frame `(rob-int:robot-tool-frame ,rob-int:*robot-name* ,arm ?f) '?f default))

(defun start-projection ()
  "Startup of the projection environment: check that there is a robot and give TF the belief
state (written when TF is first read)."
  (robot-object)
  (defer-tf-from-belief-state :force t))

(defmacro define-simulated-robot-environment (name)
  "Define the projection environment NAME of the simulated robot: a TF transformer fed from
the belief state, the robot frames of the current robot's facts, a seeded IK random state, and
the process modules URDF-PROJ-NAVIGATION, -TORSO, -NECK, -PERCEPTION, -GRIPPERS, -ARMS, -NOOP
and COMMON-DESIG:WAIT-PM."
  `(cram-projection:define-projection-environment ,name
    :special-variable-initializers
    ((btr:*current-bullet-world* btr:*current-bullet-world*)
     (rob-int:*robot-name* (or rob-int:*robot-name* (guess-robot-name)))
     (cram-tf:*transformer* (make-instance 'cl-transforms-stamped:transformer))
     (cram-tf:*tf-default-timeout* 0.1)
     (cram-tf:*robot-base-frame*
      (or (belief-robot-root-link)
          (robot-frame (list 'rob-int:robot-base-frame rob-int:*robot-name* '?f) '?f cram-tf:*robot-base-frame*)))
     (cram-tf:*odom-frame*
      (robot-frame (list 'rob-int:robot-odom-frame rob-int:*robot-name* '?f) '?f cram-tf:*odom-frame*))
     (cram-tf:*robot-torso-frame*
      (robot-frame (list 'rob-int:robot-torso-link-joint rob-int:*robot-name* '?f '?_) '?f cram-tf:*robot-torso-frame*))
     (cram-tf:*robot-torso-joint*
      (robot-frame (list 'rob-int:robot-torso-link-joint rob-int:*robot-name* '?_ '?j) '?j cram-tf:*robot-torso-joint*))
     (cram-tf:*robot-left-tool-frame* (arm-tool-frame :left cram-tf:*robot-left-tool-frame*))
     (cram-tf:*robot-right-tool-frame* (arm-tool-frame :right cram-tf:*robot-right-tool-frame*))
     (desig:*default-role* :projection-role)
     (*tf-from-belief-state* t)
     (*environment-tf-signatures* (make-hash-table :test 'eq :synchronized t))
     (*ik-random-state* (sb-ext:seed-random-state *ik-random-seed*))
     (*reach-memory* (make-reach-memory)))
    :process-module-definitions (urdf-proj-navigation urdf-proj-torso urdf-proj-neck
                                 urdf-proj-perception urdf-proj-grippers urdf-proj-arms
                                 urdf-proj-noop common-desig:wait-pm)
    :startup (start-projection)))

(define-simulated-robot-environment urdf-bullet-projection-environment)
(define-simulated-robot-environment pr2-bullet-projection-environment)

(defmacro with-simulated-robot (&body body)
  "Run BODY as a top-level plan (CPL:NAMED-TOP-LEVEL :TOP-LEVEL) in the projection
environment URDF-BULLET-PROJECTION-ENVIRONMENT: motions are performed by the simulated robot
of the belief state, CRAM-TF:*TRANSFORMER* holds its frames. Returns the first value of BODY."
  `(values
    (cram-projection:with-projection-environment urdf-bullet-projection-environment
      (cpl:named-top-level (:name :top-level)
        ,@body))))

(defmacro with-projected-robot (&body body)
  "Same as WITH-SIMULATED-ROBOT."
  `(with-simulated-robot ,@body))

;;; Object designators named after belief-state objects resolve to those objects in projection.

(defmethod desig:resolve-designator ((designator desig:object-designator) (role (eql :projection-role)))
  (let ((name (desig:desig-prop-value designator :name)))
    (when name
      (let ((object (find-if (lambda (o) (string-equal (string (btr:name o)) (string name)))
                             (btr:objects btr:*current-bullet-world*))))
        (when object
          (make-instance 'desig:object-designator-data
                         :object-identifier (btr:name object)
                         :pose (let ((p (btr:pose object)))
                                 (cl-transforms-stamped:make-pose-stamped
                                  cram-tf:*fixed-frame* (cram-tf-stamp)
                                  (cl-transforms:origin p) (cl-transforms:orientation p)))))))))
