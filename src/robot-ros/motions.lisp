;;;; The motions of the robot over ROS: going (move_base), moving the torso, looking, the arms
;;;; (joint goals, named configurations, tool-frame poses through the in-process IK), the
;;;; grippers, and detecting (perception/objects filtered by the camera's field of view).

(in-package :cram-ros-pms)

(defvar *navigation-timeout* 120
  "Seconds a move_base goal may take before it is cancelled (NAVIGATION-GOAL-NOT-REACHED).")

(defvar *camera-range* 4.0
  "Metres: perceived objects farther from the camera are not seen.")

(defvar *perception-timeout* 3
  "Seconds DETECT waits for a perception/objects message stamped after it started.")

(defvar *gripper-settle-time* 0.2
  "Seconds a closing or gripping motion waits before the fingers move: the arm comes to rest and
the tool frame's TF catches up with the joints (the simulated robot attaches what is near the
tool frame in TF when the fingers start closing).")

(defvar *before-detect-hooks* '()
  "Functions called without arguments when a detecting motion starts (tests inject perception
faults here). A hook that returns a ROS time moves the motion's start there: the motion takes
the first perception message stamped at or after it.")

;;; ---- navigation ----------------------------------------------------------------------------------

(defvar *action-clients* (make-hash-table :test 'equal)
  "Full action name → ACTION-CLIENT, kept for the life of the node (see *SUBSCRIPTIONS*).")

(defun action-client (name type)
  "The client of the action NAME (relative to *ROBOT-NAMESPACE*), made once per node."
  (let* ((full (robot-topic name))
         (client (gethash full *action-clients*)))
    (if (and client (subscription-live-p (format nil "~a/status" full)))
        client
        (setf (gethash full *action-clients*) (make-action-client full type)))))

(defun move-base-goal (pose)
  (let ((o (cl-transforms:origin pose)) (q (cl-transforms:orientation pose)))
    (roslisp:make-message "move_base_msgs/MoveBaseGoal"
                          (frame_id header target_pose) cram-tf:*fixed-frame*
                          (stamp header target_pose) (roslisp:ros-time)
                          (x position pose target_pose) (float (cl-transforms:x o) 1d0)
                          (y position pose target_pose) (float (cl-transforms:y o) 1d0)
                          (z position pose target_pose) (float (cl-transforms:z o) 1d0)
                          (x orientation pose target_pose) (float (cl-transforms:x q) 1d0)
                          (y orientation pose target_pose) (float (cl-transforms:y q) 1d0)
                          (z orientation pose target_pose) (float (cl-transforms:z q) 1d0)
                          (w orientation pose target_pose) (float (cl-transforms:w q) 1d0))))

(defun base-at-pose-p (goal &key (distance 1d-3) (angle 1d-3))
  "True when the robot's latest base pose (TF) is within DISTANCE metres (in x and y) and ANGLE
radians of GOAL (a pose in the map)."
  (let ((pose (robot-base-pose)))
    (and pose
         (< (let ((a (cl-transforms:origin pose)) (b (cl-transforms:origin goal)))
              (sqrt (+ (expt (- (cl-transforms:x a) (cl-transforms:x b)) 2)
                       (expt (- (cl-transforms:y a) (cl-transforms:y b)) 2))))
            distance)
         (< (cl-transforms:angle-between-quaternions (cl-transforms:orientation pose)
                                                     (cl-transforms:orientation goal))
            angle))))

(defun drive-to-map-pose (goal)
  "Send GOAL (a pose in the map) to move_base and wait: SUCCEEDED returns the pose reached;
ABORTED fails with NAVIGATION-POSE-UNREACHABLE; PREEMPTED, REJECTED or no result within
*NAVIGATION-TIMEOUT* s with NAVIGATION-GOAL-NOT-REACHED."
  (let* ((client (action-client "move_base" "move_base_msgs/MoveBase"))
         (id (send-goal client (move-base-goal goal))))
    (multiple-value-bind (status text)
        (wait-for-result client id :timeout *navigation-timeout* :connection *connection*)
      (when (eq status :succeeded)
        ;; the result may come before the TF that shows the base at the goal (another
        ;; connection): wait for it, briefly, so that the belief does not keep a pose from
        ;; mid-drive (at 10x speed a message late by 20 ms is 10 cm)
        (wait-until *connection* (lambda () (base-at-pose-p goal)) :timeout 1.0))
      (sync-belief-state)
      (case status
        (:succeeded (robot-base-pose))
        (:aborted
         (cpl:fail 'common-fail:navigation-pose-unreachable
                   :description (format nil "move_base aborted the goal ~a~@[: ~a~]."
                                        (urdf-proj::pose-summary goal) (and (plusp (length text)) text))))
        (t
         (cpl:fail 'common-fail:navigation-goal-not-reached
                   :description (format nil "move_base goal ~a: ~(~a~)~@[ (~a)~]."
                                        (urdf-proj::pose-summary goal) status
                                        (and (plusp (length text)) text))))))))

(defun drive (pose)
  "Drive the robot's base to POSE (as URDF-PROJ:DRIVE takes it) through move_base."
  (drive-to-map-pose (urdf-proj::navigation-goal-in-map pose)))

;;; ---- torso, neck, arms: plan in the belief, then move the robot ------------------------------------

(defun execute-planned-state (base-pose joints &key (what "motion") (failure 'common-fail:manipulation-goal-not-reached)
                                                   groups)
  "Move the robot to the state a motion produced in the belief: the base to BASE-POSE when it
differs by more than 5 mm or 0.01 rad (move_base), then each of GROUPS ((controller joints
failure-class)...) whose joints in JOINTS (an alist) differ from the robot's."
  (declare (ignore failure))
  (let ((current (robot-base-pose)))
    (when (and base-pose current
               (multiple-value-bind (d a) (btr::pose-distance base-pose current)
                 (or (> d 0.005) (> a 0.01))))
      (drive-to-map-pose base-pose)))
  (loop for (controller group-joints group-failure) in groups
        for pairs = (changed-pairs (robot-joint-positions) joints group-joints)
        when pairs
          do (move-joint-group controller pairs group-failure
                               (format nil "~a (~a)" what controller))))

(defun torso-joints ()
  (let ((j (urdf-proj:torso-joint))) (and j (list j))))

(defun groups-for (&key torso neck arms grippers)
  (append (and torso (torso-joints)
               (list (list "torso_controller" (torso-joints) 'common-fail:torso-goal-not-reached)))
          (and neck (list (list "head_controller" (urdf-proj:neck-joints) 'common-fail:ptu-goal-not-reached)))
          (loop for arm in arms
                collect (list (arm-controller arm) (urdf-proj:arm-joint-names arm)
                              'common-fail:manipulation-goal-not-reached))
          (loop for arm in grippers
                collect (list (gripper-controller arm) (urdf-proj::gripper-joints arm)
                              'common-fail:gripper-goal-not-reached))))

(defmacro with-planned-motion ((&key what groups) &body body)
  "Run BODY (a projection motion) on the belief robot, move the robot to the state it produced
through GROUPS, then signal BODY's plan failure, if any (as projection does after moving to
the clamped state). Returns BODY's value."
  (let ((pose (gensym)) (joints (gensym)) (result (gensym)) (failure (gensym)))
    `(progn
       (sync-belief-state)
       (multiple-value-bind (,pose ,joints ,result ,failure) (plan-in-belief (lambda () ,@body))
         (execute-planned-state ,pose ,joints :what ,what :groups ,groups)
         (when ,failure (error ,failure))
         ,result))))

(defun move-torso (joint-angle)
  "Move the torso as URDF-PROJ:MOVE-TORSO decides (limits, named values) over torso_controller."
  (with-planned-motion (:what "moving-torso" :groups (groups-for :torso t))
    (urdf-proj:move-torso joint-angle)))

(defun look-at (target &optional configuration)
  "Point the camera at TARGET (as URDF-PROJ:LOOK-AT takes it: pan and tilt computed on the
belief robot) over head_controller."
  (with-planned-motion (:what "looking" :groups (groups-for :neck t))
    (urdf-proj:look-at target configuration)))

(defun move-joints (left right)
  "Move the arms to the configurations LEFT and RIGHT (as URDF-PROJ:MOVE-JOINTS) over the arm
controllers."
  (with-planned-motion (:what "moving-arm-joints"
                        :groups (groups-for :arms (append (and left '(:left)) (and right '(:right)))))
    (urdf-proj:move-joints left right)))

(defun position-arms (left right)
  "Put the arms into named configurations over the arm controllers."
  (move-joints left right))

(defun check-tool-frames (left right)
  "MANIPULATION-GOAL-NOT-REACHED when a tool frame of the synced belief robot is off its goal."
  (loop for (arm goal) in (list (list :left left) (list :right right))
        when goal
          do (let* ((robot (urdf-proj:robot-object))
                    (tool (urdf-proj:tool-frame arm))
                    (reached (btr:link-pose robot tool))
                    (wanted (urdf-proj::pose-in-map goal "TCP goal")))
               (multiple-value-bind (d a) (btr::pose-distance reached wanted)
                 (when (or (> d 0.02) (> a 0.1))
                   (cpl:fail 'common-fail:manipulation-goal-not-reached
                             :description (format nil "The ~(~a~) tool frame ended ~,3f m and ~,3f rad ~
                                                       away from its goal on the robot." arm d a)))))))

(defun last-pose (poses)
  (cond ((null poses) nil)
        ((or (typep poses 'cl-transforms:pose) (typep poses 'cl-transforms-stamped:pose-stamped)) poses)
        ((and (consp poses) (= (length poses) 2) (every #'listp poses) (every #'realp (first poses))) poses)
        ((consp poses) (car (last poses)))
        (t poses)))

(defun move-tcp (left right &key collision-mode (move-base t) fixed-torso)
  "Bring the tool frames to LEFT and RIGHT: IK in process (URDF-PROJ:MOVE-TCP on the belief
robot, with base offsets and torso heights), then move_base, torso_controller and the arm
controllers bring the robot there; the tool frames are checked on the synced belief."
  (let ((lefts (if (and (consp left) (not (and (= (length left) 2) (every #'listp left) (every #'realp (first left)))))
                   left (and left (list left))))
        (rights (if (and (consp right) (not (and (= (length right) 2) (every #'listp right) (every #'realp (first right)))))
                    right (and right (list right)))))
    ;; one robot motion per step, as URDF-PROJ:MOVE-TCP steps through the poses
    (let ((steps (max (length lefts) (length rights))))
      (dotimes (i steps t)
        (let ((l (nth i lefts)) (r (nth i rights)))
          (flet ((one-step ()
                   (with-planned-motion (:what "moving-tcp"
                                         :groups (groups-for :torso t :arms (append (and l '(:left)) (and r '(:right)))))
                     (urdf-proj:move-tcp l r :collision-mode collision-mode :move-base move-base
                                             :fixed-torso fixed-torso))
                   (check-tool-frames l r)))
            (if (< i (1- steps))
                (handler-case (one-step)
                  (common-fail:manipulation-low-level-failure (f)
                    (cpl:log-message :warn '(ros-pms move-tcp) "Skipping intermediate pose ~d: ~a" i f)))
                (one-step))))))))

;;; ---- grippers --------------------------------------------------------------------------------------

(defun gripper-action (action arm &optional maximum-effort)
  "Open (:OPEN), close (:CLOSE), grip (:GRIP) or set (a real, metres) the gripper of ARM over
its gripper controller. :GRIP succeeds when the fingers stop on an object and fails with
GRIPPER-CLOSED-COMPLETELY when they close on nothing."
  (declare (ignore maximum-effort))
  (urdf-proj::check-arm arm)
  (unless (or (member action '(:open :close :grip))
              (and (realp action) (not (and (floatp action) (sb-ext:float-nan-p action))) (< (abs action) 1d6)))
    (error "GRIPPER-ACTION: action ~s, expected :OPEN, :CLOSE, :GRIP or a real." action))
  (sync-belief-state)
  (let* ((robot (urdf-proj:robot-object))
         (joints (urdf-proj::gripper-joints arm))
         (multiplier (or (urdf-proj::fact-value '?m `(rob-int:gripper-meter-to-joint-multiplier ,(urdf-proj::robot-name) ?m)) 1))
         (pairs (mapcar (lambda (j)
                          (multiple-value-bind (lo hi) (btr:joint-limits robot j)
                            (list j (case action
                                      (:open hi)
                                      ((:close :grip) lo)
                                      (t (clamp-goal j (* action multiplier)))))))
                        joints)))
    (when (member action '(:grip :close)) (sleep *gripper-settle-time*))
    (move-joint-group (gripper-controller arm) pairs
                      (if (eq action :open) 'common-fail:gripper-goal-not-reached
                          'common-fail:gripper-goal-not-reached)
                      (format nil "~(~a~) gripper ~(~a~)" arm action)
                      :settle (member action '(:grip :close)))
    (let ((reached (positions-of joints)))
      (when (and (eq action :grip)
                 (every (lambda (p r) (<= (joint-error (first p) (second p) (second r)) (* 2 *joint-tolerance*)))
                        pairs reached))
        (cpl:fail 'common-fail:gripper-closed-completely
                  :description (format nil "The ~(~a~) gripper closed completely: there was no object to grip."
                                       arm)))
      (mapcar #'second reached))))

;;; ---- perception ------------------------------------------------------------------------------------

(defun camera-angles ()
  "Full horizontal and vertical opening angles (radians) of the robot's camera facts."
  (let ((name (urdf-proj::robot-name)))
    (values (or (urdf-proj::fact-value '?a `(rob-int:camera-horizontal-angle ,name ?a)) 1.0)
            (or (urdf-proj::fact-value '?a `(rob-int:camera-vertical-angle ,name ?a)) 0.75))))

(defun in-field-of-view-p (camera-pose point)
  "True when the map POINT is inside the field of view of the camera at CAMERA-POSE (optical
frame: z forward, x right, y down) and within *CAMERA-RANGE*."
  (let* ((in-cam (cl-transforms:transform-point
                  (cl-transforms:transform-inv (cl-transforms:pose->transform camera-pose)) point))
         (x (cl-transforms:x in-cam)) (y (cl-transforms:y in-cam)) (z (cl-transforms:z in-cam)))
    (multiple-value-bind (h v) (camera-angles)
      (and (> z 0)
           (<= (cl-transforms:v-norm in-cam) *camera-range*)
           (<= (abs (atan x z)) (/ h 2))
           (<= (abs (atan y z)) (/ v 2))))))

(defun marker-record (marker)
  "(name type pose size frame) of a perception marker (pose as a CL-TRANSFORMS pose)."
  (let* ((p (visualization_msgs-msg:pose marker))
         (o (geometry_msgs-msg:position p)) (q (geometry_msgs-msg:orientation p))
         (s (visualization_msgs-msg:scale marker)))
    (list (visualization_msgs-msg:text marker)
          (visualization_msgs-msg:ns marker)
          (cl-transforms:make-pose
           (cl-transforms:make-3d-vector (geometry_msgs-msg:x o) (geometry_msgs-msg:y o) (geometry_msgs-msg:z o))
           (cl-transforms:make-quaternion (geometry_msgs-msg:x q) (geometry_msgs-msg:y q)
                                          (geometry_msgs-msg:z q) (geometry_msgs-msg:w q)))
          (list (geometry_msgs-msg:x s) (geometry_msgs-msg:y s) (geometry_msgs-msg:z s))
          (string-left-trim "/" (std_msgs-msg:frame_id (visualization_msgs-msg:header marker))))))

(defun belief-object-named (name)
  (find-if (lambda (o) (string-equal (string (btr:name o)) name)) (btr:objects btr:*current-bullet-world*)))

(defun assert-perceived-object (name type pose size)
  "Put the perceived object NAME of TYPE at POSE (map) in the belief state: an existing object
of that name is moved there (unless the robot holds it), a new one is added as a box of SIZE.
Returns the belief object."
  (let ((existing (belief-object-named name))
        (robot (urdf-proj:robot-object)))
    (cond ((and existing (btr:object-attached robot existing)) existing)
          (existing (setf (btr:pose existing) pose) existing)
          (t (btr:add-object btr:*current-bullet-world* :box (intern (string-upcase name) :keyword) pose
                             :size (mapcar (lambda (s) (max 0.005d0 (float s 1d0))) size)
                             :mass 0.2 :types (list (intern (string-upcase type) :keyword)))))))

(defun detect (object-designator)
  "Detect objects matching OBJECT-DESIGNATOR's :TYPE and :NAME: the first perception/objects
message stamped after the call, its markers inside the camera's field of view, asserted into the
belief state nearest first. Returns the perceived designator (a list of them for quantifier
:ALL); PERCEPTION-OBJECT-NOT-FOUND when there is none."
  (unless (typep object-designator 'desig:object-designator)
    (error "DETECT: expected an object designator, got ~s." object-designator))
  (sync-belief-state)
  (let* ((c *connection*)
         (start (let ((hook-times (remove-if-not #'realp (mapcar #'funcall *before-detect-hooks*))))
                  (if hook-times (reduce #'max hook-times) (roslisp:ros-time))))
         (message (wait-until c (lambda () (find-if (lambda (m) (>= (first m) start))
                                                    (reverse (connection-perception c))))
                              :timeout *perception-timeout* :name (robot-topic "perception/objects")
                              :reason "no perception message stamped after the detecting motion started"))
         (robot (urdf-proj:robot-object))
         (camera (btr:link-pose robot (urdf-proj:camera-frame robot)))
         (wanted-type (desig:desig-prop-value object-designator :type))
         (wanted-name (desig:desig-prop-value object-designator :name))
         (seen (loop for marker across (second message)
                     for (name type pose size frame) = (marker-record marker)
                     for map-pose = (if (string= frame cram-tf:*fixed-frame*) pose
                                        (urdf-proj::pose-in-map
                                         (cl-transforms-stamped:make-pose-stamped
                                          frame 0d0 (cl-transforms:origin pose) (cl-transforms:orientation pose))))
                     when (and (or (null wanted-type) (string-equal (string wanted-type) "KITCHEN-OBJECT")
                                   (string-equal (string wanted-type) type))
                               (or (null wanted-name) (string-equal (string wanted-name) name))
                               (in-field-of-view-p camera (cl-transforms:origin map-pose)))
                       collect (list name type map-pose size))))
    (unless seen
      (cpl:fail 'common-fail:perception-object-not-found
                :object object-designator
                :description (format nil "Could not find any object of type ~s~@[ named ~s~] in the ~
                                          field of view (~d object~:p on ~a)."
                                     wanted-type wanted-name (length (second message))
                                     (robot-topic "perception/objects"))))
    (let* ((origin (cl-transforms:origin camera))
           (sorted (sort seen #'< :key (lambda (s) (cl-transforms:v-dist origin (cl-transforms:origin (third s))))))
           (perceived (sb-thread:with-recursive-lock (urdf-proj::*motion-lock*)
                        (loop for (name type pose size) in sorted
                              for object = (assert-perceived-object name type pose size)
                              collect (urdf-proj::perceived-designator object-designator object nil)))))
      (when (and urdf-proj::*tf-from-belief-state* cram-tf:*transformer*)
        (urdf-proj:update-tf-from-belief-state))
      (if (eq (desig:quantifier object-designator) :all) perceived (first perceived)))))
