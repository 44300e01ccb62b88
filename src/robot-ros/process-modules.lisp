;;;; The robot process modules, matched by the same motion designators as projection's, the
;;;; environment REAL-ROBOT-ENVIRONMENT and WITH-REAL-ROBOT's implementation.

(in-package :cram-ros-pms)

(defvar *real-robot-active* nil
  "True inside WITH-REAL-ROBOT: the robot process modules may run.")
(pushnew '*real-robot-active* cpl:*inherited-specials*)
(pushnew '*connection* cpl:*inherited-specials*)

(defun execute-command (module designator allowed)
  "Run the grounded command of the motion DESIGNATOR on the robot, when its command is one of
ALLOWED (common-desig command symbols)."
  (unless (and *real-robot-active* *connection*)
    (error "Process module ~s runs only inside WITH-REAL-ROBOT." module))
  (multiple-value-bind (command arguments) (urdf-proj::grounded-command module designator allowed)
    (check-master *connection*)
    (unwind-protect
         (urdf-proj::dispatch-motion
          command arguments
          :drive #'drive :move-torso #'move-torso :look-at #'look-at :detect #'detect
          :gripper-action #'gripper-action :move-tcp #'move-tcp :move-joints #'move-joints
          :position-arms #'position-arms
          :monitor-joint-state
          (lambda (joint threshold function)
            (declare (ignore threshold function))
            (or (gethash joint (robot-joint-positions))
                (error "MONITOR-JOINT-STATE: ~s is not in /joint_states." joint))))
      (ignore-errors (urdf-proj::after-motion (string-downcase (symbol-name command)))))))

(cpm:def-process-module ros-navigation (motion-designator)
  "Executes GOING motions on the robot: a move_base goal in the map."
  (execute-command 'ros-navigation motion-designator '(common-desig:drive)))

(cpm:def-process-module ros-torso (motion-designator)
  "Executes MOVING-TORSO motions on the robot over torso_controller/command."
  (execute-command 'ros-torso motion-designator '(common-desig:move-torso)))

(cpm:def-process-module ros-neck (motion-designator)
  "Executes LOOKING motions on the robot over head_controller/command."
  (execute-command 'ros-neck motion-designator '(common-desig:look-at)))

(cpm:def-process-module ros-perception (motion-designator)
  "Executes DETECTING motions on the robot from perception/objects."
  (execute-command 'ros-perception motion-designator '(common-desig:detect)))

(cpm:def-process-module ros-grippers (motion-designator)
  "Executes the gripper motions on the robot over the gripper controllers."
  (execute-command 'ros-grippers motion-designator '(common-desig:move-gripper-joint)))

(cpm:def-process-module ros-arms (motion-designator)
  "Executes MOVING-TCP (in-process IK), MOVING-ARM-JOINTS and POSITIONING-ARM motions on the
robot over the arm controllers (and move_base and the torso for MOVING-TCP)."
  (execute-command 'ros-arms motion-designator
                   '(common-desig:move-tcp common-desig:move-joints common-desig:position-arms
                     common-desig:monitor-joint-state)))

(prolog:def-fact-group ros-pms-matching (cpm:matching-process-module)
  (prolog:<- (cpm:matching-process-module ?d ros-navigation)
    (desig:desig-prop ?d (:type :going)))
  (prolog:<- (cpm:matching-process-module ?d ros-torso)
    (desig:desig-prop ?d (:type :moving-torso)))
  (prolog:<- (cpm:matching-process-module ?d ros-neck)
    (desig:desig-prop ?d (:type :looking)))
  (prolog:<- (cpm:matching-process-module ?d ros-perception)
    (desig:desig-prop ?d (:type :detecting)))
  (prolog:<- (cpm:matching-process-module ?d ros-grippers)
    (desig:desig-prop ?d (:type ?type))
    (member ?type (:gripping :moving-gripper-joint :opening-gripper :closing-gripper)))
  (prolog:<- (cpm:matching-process-module ?d ros-arms)
    (desig:desig-prop ?d (:type ?type))
    (member ?type (:moving-tcp :moving-arm-joints :positioning-arm :monitoring-joint-state))))

(defparameter *process-module-names*
  '(ros-navigation ros-torso ros-neck ros-perception ros-grippers ros-arms common-desig:wait-pm)
  "The process modules running inside WITH-REAL-ROBOT.")

(cram-projection:define-projection-environment real-robot-environment
  :special-variable-initializers
  ((btr:*current-bullet-world* btr:*current-bullet-world*)
   (rob-int:*robot-name* (or rob-int:*robot-name* (urdf-proj::guess-robot-name)))
   (cram-tf:*transformer* (make-instance 'cl-transforms-stamped:transformer))
   (cram-tf:*tf-default-timeout* 0.1)
   (cram-tf:*robot-base-frame*
    (or (urdf-proj::belief-robot-root-link)
        (urdf-proj::robot-frame (list 'rob-int:robot-base-frame rob-int:*robot-name* '?f) '?f cram-tf:*robot-base-frame*)))
   (cram-tf:*odom-frame*
    (urdf-proj::robot-frame (list 'rob-int:robot-odom-frame rob-int:*robot-name* '?f) '?f cram-tf:*odom-frame*))
   (cram-tf:*robot-torso-frame*
    (urdf-proj::robot-frame (list 'rob-int:robot-torso-link-joint rob-int:*robot-name* '?f '?_) '?f cram-tf:*robot-torso-frame*))
   (cram-tf:*robot-torso-joint*
    (urdf-proj::robot-frame (list 'rob-int:robot-torso-link-joint rob-int:*robot-name* '?_ '?j) '?j cram-tf:*robot-torso-joint*))
   (cram-tf:*robot-left-tool-frame* (urdf-proj::arm-tool-frame :left cram-tf:*robot-left-tool-frame*))
   (cram-tf:*robot-right-tool-frame* (urdf-proj::arm-tool-frame :right cram-tf:*robot-right-tool-frame*))
   (desig:*default-role* :projection-role)
   (urdf-proj::*tf-from-belief-state* t)
   (urdf-proj::*environment-tf-signatures* (make-hash-table :test 'eq :synchronized t))
   (urdf-proj:*ik-random-state* (sb-ext:seed-random-state urdf-proj:*ik-random-seed*))
   (*real-robot-active* t))
  :process-module-definitions (ros-navigation ros-torso ros-neck ros-perception ros-grippers
                               ros-arms common-desig:wait-pm)
  :startup (progn (sync-belief-state) (urdf-proj:update-tf-from-belief-state :force t)))

;;; A plan written for projection wraps itself in URDF-PROJ:WITH-SIMULATED-ROBOT (move-bottle
;;; does). Inside WITH-REAL-ROBOT that environment stands for this one: its runner only calls the
;;; body, as a top-level of its own (the outer task waits for it).

(defun pass-through-runner (thunk)
  (let ((cpl-impl::*current-task* nil))
    (funcall thunk)))

(defun environments-for-real-robot ()
  "A copy of the projection environment table where the simulated robot's environments run
their bodies in the real robot's environment."
  (let ((table (make-hash-table :test 'eq)))
    (maphash (lambda (k v) (setf (gethash k table) v)) cram-projection::*projection-environments*)
    (dolist (name '(urdf-proj:urdf-bullet-projection-environment urdf-proj:pr2-bullet-projection-environment))
      (setf (gethash name table) (cons #'pass-through-runner *process-module-names*)))
    table))

(pushnew 'cram-projection::*projection-environments* cpl:*inherited-specials*)

(defun %call-with-real-robot (thunk)
  "WITH-REAL-ROBOT: connect, run THUNK as a top-level plan in REAL-ROBOT-ENVIRONMENT, disconnect."
  (when *connection*
    (error "WITH-REAL-ROBOT inside WITH-REAL-ROBOT: the robot is already connected."))
  (let* ((publisher (roslisp-utilities:belief-state-publisher-running-p))
         (connection nil))
    ;; the belief publisher's map → base edge would fight the robot's odometry on /tf
    (when publisher (roslisp-utilities:stop-belief-state-publisher))
    (unwind-protect
         (progn
           (setf connection (let ((rob-int:*robot-name* (or rob-int:*robot-name* (urdf-proj::guess-robot-name))))
                              (open-connection)))
           (let ((*connection* connection)
                 (cram-projection::*projection-environments* (environments-for-real-robot)))
             (cram-projection:with-projection-environment real-robot-environment
               (cpl:named-top-level (:name :top-level)
                 (funcall thunk)))))
      (when connection (close-connection connection))
      (when publisher (ignore-errors (roslisp-utilities:start-belief-state-publisher))))))
