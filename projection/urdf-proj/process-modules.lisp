;;;; Process modules of the simulated robot and the rules that match motions to them.

(in-package :cram-urdf-projection)

(defun dispatch-motion (command arguments &key drive move-torso look-at detect gripper-action
                                                move-tcp move-joints position-arms
                                                monitor-joint-state)
  "Call the function given for the grounded motion COMMAND (a common-desig command symbol)
with the motion's ARGUMENTS: MOVE-TCP gets (left right &key collision-mode move-base
fixed-torso), MONITOR-JOINT-STATE (joint threshold function), the others the arguments as
they are. Shared by the process modules of the simulated and of the real robot."
  (ecase command
    (common-desig:drive (apply drive arguments))
    (common-desig:move-torso (apply move-torso arguments))
    (common-desig:look-at (apply look-at arguments))
    (common-desig:detect (apply detect arguments))
    (common-desig:move-gripper-joint (apply gripper-action arguments))
    (common-desig:move-tcp
     (destructuring-bind (left right mode move-base fixed-torso) arguments
       (funcall move-tcp left right :collision-mode mode :move-base move-base :fixed-torso fixed-torso)))
    (common-desig:move-joints (apply move-joints arguments))
    (common-desig:position-arms (apply position-arms arguments))
    (common-desig:monitor-joint-state (apply monitor-joint-state arguments))))

(defun grounded-command (module designator allowed)
  "(values command arguments) of the motion DESIGNATOR's grounding, when its command is one of
ALLOWED; an error naming MODULE and the motion otherwise."
  (let* ((grounding (desig:reference designator))
         (command (common-desig:motion-command grounding)))
    (unless (member command allowed)
      (error "Process module ~s cannot execute the motion ~s (command ~s; it executes ~s)."
             module designator command allowed))
    (values command (common-desig:motion-arguments grounding))))

(defun execute-command (module designator allowed)
  "Run the grounded command of the motion DESIGNATOR with the low-level function of the same
name, when its command is one of ALLOWED (common-desig command symbols)."
  (multiple-value-bind (command arguments) (grounded-command module designator allowed)
    (dispatch-motion
     command arguments
     :drive #'drive :move-torso #'move-torso :look-at #'look-at :detect #'detect
     :gripper-action #'gripper-action :move-tcp #'move-tcp :move-joints #'move-joints
     :position-arms #'position-arms
     :monitor-joint-state
     (lambda (joint threshold function)
       (declare (ignore function))
       (unless (movable-joint-p (robot-object) joint)
         (projection-error "MONITOR-JOINT-STATE: ~s is not a movable joint of the robot." joint))
       (unless (realp threshold)
         (projection-error "MONITOR-JOINT-STATE: threshold ~s, expected a real." threshold))
       (btr:joint-state (robot-object) joint)))))

(cpm:def-process-module urdf-proj-navigation (motion-designator)
  "Executes GOING motions of the simulated robot (DRIVE)."
  (execute-command 'urdf-proj-navigation motion-designator '(common-desig:drive)))

(cpm:def-process-module urdf-proj-torso (motion-designator)
  "Executes MOVING-TORSO motions of the simulated robot (MOVE-TORSO)."
  (execute-command 'urdf-proj-torso motion-designator '(common-desig:move-torso)))

(cpm:def-process-module urdf-proj-neck (motion-designator)
  "Executes LOOKING motions of the simulated robot (LOOK-AT)."
  (execute-command 'urdf-proj-neck motion-designator '(common-desig:look-at)))

(cpm:def-process-module urdf-proj-perception (motion-designator)
  "Executes DETECTING motions of the simulated robot (DETECT)."
  (execute-command 'urdf-proj-perception motion-designator '(common-desig:detect)))

(cpm:def-process-module urdf-proj-grippers (motion-designator)
  "Executes the gripper motions of the simulated robot (GRIPPER-ACTION)."
  (execute-command 'urdf-proj-grippers motion-designator '(common-desig:move-gripper-joint)))

(cpm:def-process-module urdf-proj-arms (motion-designator)
  "Executes the arm motions of the simulated robot (MOVE-TCP, MOVE-JOINTS, POSITION-ARMS)."
  (execute-command 'urdf-proj-arms motion-designator
                   '(common-desig:move-tcp common-desig:move-joints common-desig:position-arms)))

(cpm:def-process-module urdf-proj-noop (motion-designator)
  "Executes MONITORING-JOINT-STATE motions: in projection the joint is already where it is;
returns its value."
  (execute-command 'urdf-proj-noop motion-designator '(common-desig:monitor-joint-state)))

(prolog:def-fact-group urdf-proj-matching-pms (cpm:matching-process-module)
  (prolog:<- (cpm:matching-process-module ?d urdf-proj-navigation)
    (desig:desig-prop ?d (:type :going)))
  (prolog:<- (cpm:matching-process-module ?d urdf-proj-torso)
    (desig:desig-prop ?d (:type :moving-torso)))
  (prolog:<- (cpm:matching-process-module ?d urdf-proj-neck)
    (desig:desig-prop ?d (:type :looking)))
  (prolog:<- (cpm:matching-process-module ?d urdf-proj-perception)
    (desig:desig-prop ?d (:type :detecting)))
  (prolog:<- (cpm:matching-process-module ?d urdf-proj-grippers)
    (desig:desig-prop ?d (:type ?type))
    (member ?type (:gripping :moving-gripper-joint :opening-gripper :closing-gripper)))
  (prolog:<- (cpm:matching-process-module ?d urdf-proj-arms)
    (desig:desig-prop ?d (:type ?type))
    (member ?type (:moving-tcp :moving-arm-joints :positioning-arm :pulling :pushing)))
  (prolog:<- (cpm:matching-process-module ?d urdf-proj-noop)
    (desig:desig-prop ?d (:type :monitoring-joint-state))))
