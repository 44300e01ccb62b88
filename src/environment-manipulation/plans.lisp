;;;; The plan of opening and closing a container: stand where the handle's trajectory is within
;;;; reach, look, open the gripper while reaching, grasp the handle, grip it, pull or push it
;;;; (watching for the handle slipping out), move the joint in the belief state through a
;;;; container event, release, retract and park. Handle grasps are tried in turn.

(in-package :cram-urdf-environment-manipulation)

(defparameter *reach-retries* 2 "Extra attempts at reaching for the handle.")
(defparameter *grasp-retries* 2 "Extra attempts at grasping the handle.")
(defparameter *handle-grip-width* nil
  "Metres the gripper closes to on a handle; NIL: the thickness of the handle bar across the
fingers (its smallest side).")
(defparameter *handle-slip-threshold* 1d-4
  "A gripper whose finger joints are within this of their lower limits has closed completely:
the handle slipped out.")

(defun robot-arms ()
  (let ((robot (rob-int:current-robot-name)))
    (mapcar (lambda (b) (cut:var-value '?arm b))
            (cut:force-ll (prolog `(rob-int:arm ,robot ?arm))))))

(defun check-arm (arm)
  (unless (member arm (robot-arms))
    (env-error "ARM is ~s: expected one of the robot's arms ~{~(~a~)~^, ~}." arm (robot-arms)))
  arm)

(defun free-arms ()
  "The arms whose hand holds nothing."
  (let* ((robot (btr:get-robot-object))
         (busy (and robot (mapcar #'second (btr:attached-objects robot)))))
    (remove-if (lambda (arm) (member (urdf-proj:end-effector-link arm) busy :test #'equal))
               (robot-arms))))

(defun map-stamped (pose)
  (cl-transforms-stamped:pose->pose-stamped cram-tf:*fixed-frame* 0d0 pose))

(defun handle-grip-width (container)
  (or *handle-grip-width*
      (let* ((urdf (btr:urdf (container-environment container)))
             (link (gethash (container-handle container) (cl-urdf:links urdf)))
             (geometry (getf (first (cl-urdf:collision link)) :geometry))
             (size (and (eq (first geometry) :box) (getf (rest geometry) :size))))
        (if size (d (reduce #'min size)) 0.02d0))))

(defun handle-slipped-p (arm)
  "True when ARM's gripper has closed completely (every finger joint at its lower limit)."
  (let ((robot (urdf-proj:robot-object)))
    (every (lambda (joint)
             (<= (btr:joint-state robot joint)
                 (+ (btr:joint-lower-limit robot joint) *handle-slip-threshold*)))
           (urdf-proj::gripper-joints arm))))

(defun perform-arm-motion (type arm poses &key ignore-failures)
  "Perform the arm action TYPE (:REACHING, :GRASPING, :PULLING, :PUSHING, :RETRACTING) of ARM
through POSES, the hand allowed to touch the handle."
  (let ((?type type) (?poses (mapcar #'map-stamped poses)))
    (flet ((run ()
             (if (eq arm :left)
                 (exe:perform (desig:an action (type ?type) (left-poses ?poses) (collision-mode :allow-hand)))
                 (exe:perform (desig:an action (type ?type) (right-poses ?poses) (collision-mode :allow-hand))))))
      (if ignore-failures
          (handler-case (run)
            (common-fail:manipulation-low-level-failure (e)
              (cpl:log-message :warn '(env-man manipulate-container) "~a~%Ignoring." e)))
          (run)))))

(defmacro with-retries ((count what) &body body)
  "Run BODY, retrying it COUNT times on a MANIPULATION-LOW-LEVEL-FAILURE (logged with WHAT)."
  (let ((retries (gensym "RETRIES")))
    `(cpl:with-retry-counters ((,retries ,count))
       (cpl:with-failure-handling
           ((common-fail:manipulation-low-level-failure (e)
              (cpl:log-message :warn '(env-man manipulate-container) "~a failed: ~a" ,what e)
              (cpl:do-retry ,retries
                (cpl:log-message :warn '(env-man manipulate-container) "Retrying ~a." ,what)
                (cpl:retry))))
         ,@body))))

(defun drive-to-handle (container action arm amount grasps)
  "Drive to a base pose from which ARM reaches CONTAINER's handle along its trajectory, with the
arms parked; returns the grasp that works there. ENVIRONMENT-UNREACHABLE when there is none."
  (let ((found (first (container-base-poses container action arm amount :grasps grasps))))
    (unless found
      (cpl:fail 'common-fail:environment-unreachable
                :description (format nil "No base pose from which the ~(~a~) arm can ~(~a~) ~(~a~)."
                                     arm action (container-name container))))
    (let ((?pose (map-stamped (first found))))
      (log-env 'manipulate-container "Driving in front of the handle of ~(~a~)" (container-name container))
      (exe:perform (desig:an action (type parking-arms)))
      (exe:perform (desig:an action (type going) (target (desig:a location (pose ?pose))))))
    (second found)))

(defun container-event (container action arm amount designator)
  (make-instance (if (eq action :open) 'cpoe:container-opening-event 'cpoe:container-closing-event)
                 :joint-name (container-joint container)
                 :environment-name (container-environment-name container)
                 :environment-designator designator
                 :arm arm :distance amount))

(defun container-moving-parts (container)
  "The (MOVING HIT) contact pairs (as URDF-PROJ:*SWEEP-ALLOWED-CONTACTS* takes them) of anything
of the robot with what CONTAINER's joint moves: the links below the joint, and the objects
attached to them (a cup on a dishwasher tray)."
  (let* ((environment (container-environment container))
         (name (btr:name environment))
         (joint (gethash (container-joint container) (cl-urdf:joints (btr:urdf environment))))
         (links (labels ((below (link)
                           (cons (cl-urdf:name link)
                                 (loop for j in (cl-urdf:child-joints link) append (below (cl-urdf:child j))))))
                  (below (cl-urdf:child joint)))))
    (append (mapcar (lambda (link) (list t (list name link))) links)
            (loop for (object link) in (btr:attached-objects environment)
                  when (member link links :test #'string=) collect (list t object)))))

(defmacro with-container-moving ((container) &body body)
  "Run BODY, a motion that moves CONTAINER with the hand (gripping its handle, pushing it),
with the robot's contacts with what the container's joint moves allowed: in the belief state the
container moves only after the motion (the container event), while in the motion it goes along
with the hand, ahead of the arm."
  `(let ((urdf-proj:*sweep-allowed-contacts*
           (append (container-moving-parts ,container) urdf-proj:*sweep-allowed-contacts*)))
     ,@body))

(defun manipulate-with-grasp (container action arm grasp amount designator)
  "One attempt at ACTION of CONTAINER with ARM and the handle GRASP (see MANIPULATE-CONTAINER)."
  (let* ((trajectory (container-trajectory container action grasp amount))
         (?arm arm)
         (?opening (man-int:get-object-type-gripper-opening :container))
         (?look (map-stamped (btr:link-pose (container-environment container) (container-handle container)))))
    (log-env 'manipulate-container "Looking")
    (handler-case (exe:perform (desig:an action (type looking) (target (desig:a location (pose ?look)))))
      (common-fail:ptu-low-level-failure (e)
        (cpl:log-message :warn '(env-man manipulate-container) "~a~%Ignoring." e)))
    (log-env 'manipulate-container "Opening gripper and reaching with grasp ~(~a~)" grasp)
    (with-retries (*reach-retries* "Reaching")
      (exe:perform (desig:an action (type setting-gripper) (gripper ?arm) (position ?opening)))
      (perform-arm-motion :reaching arm (man-int:get-traj-poses-by-label trajectory :reaching)))
    (log-env 'manipulate-container "Grasping")
    (with-retries (*grasp-retries* "Grasping")
      (perform-arm-motion :grasping arm (man-int:get-traj-poses-by-label trajectory :grasping)))
    (log-env 'manipulate-container "Gripping")
    (let ((?width (handle-grip-width container)))
      (with-container-moving (container)
        (exe:perform (desig:an action (type setting-gripper) (gripper ?arm) (position ?width)))))
    (when (handle-slipped-p arm)
      (cpl:fail 'common-fail:gripper-closed-completely :description "Handle slipped"))
    (log-env 'manipulate-container "~:[Closing~;Opening~]" (eq action :open))
    (handler-case
        (let ((poses (man-int:traj-segment-poses (third trajectory))))
          ;; pulling: the container comes towards the arm, which its state after the motion
          ;; does not show, so nothing is allowed
          (if (eq action :open)
              (perform-arm-motion :pulling arm poses)
              (with-container-moving (container) (perform-arm-motion :pushing arm poses))))
      (common-fail:manipulation-low-level-failure (e)
        (exe:perform (desig:an action (type releasing) (gripper ?arm)))
        (cpl:fail 'common-fail:environment-manipulation-goal-not-reached
                  :description (format nil "~:[Pushing~;Pulling~] ~(~a~) failed: ~a"
                                       (eq action :open) (container-name container) e))))
    (when (handle-slipped-p arm)
      (cpl:fail 'common-fail:gripper-closed-completely :description "Handle slipped"))
    (coe:on-event (container-event container action arm amount designator))
    (log-env 'manipulate-container "Releasing")
    (exe:perform (desig:an action (type releasing) (gripper ?arm)))
    (log-env 'manipulate-container "Retracting")
    (perform-arm-motion :retracting arm (man-int:get-traj-poses-by-label trajectory :retracting)
                        :ignore-failures t)
    (log-env 'manipulate-container "Parking")
    (exe:perform (desig:an action (type parking-arms) (arms (?arm))))
    (container-joint-state container)))

(defun manipulate-container (&key action object arm grasps distance &allow-other-keys)
  "Open (ACTION :OPEN) or close (:CLOSE) the container OBJECT (an object designator with
URDF-NAME and PART-OF) with ARM to the absolute joint value DISTANCE (default: its opening
distance or upper limit, or its lower limit), trying the handle GRASPS in turn. When the
container is there already nothing moves. When the handle's trajectory is out of reach the
robot first drives in front of it. Failures: ENVIRONMENT-UNREACHABLE (no base pose or no grasp
works), ENVIRONMENT-MANIPULATION-GOAL-NOT-REACHED (pulling or pushing failed),
GRIPPER-CLOSED-COMPLETELY (\"Handle slipped\"). Returns the joint's new value."
  (let ((container (container-designator-container object))
        (arm (if arm
                 (check-arm arm)
                 (or (first (free-arms)) (env-error "No free arm to ~(~a~) ~s with." action object)))))
    (multiple-value-bind (amount target) (container-opening-amount container action distance)
      (when (< amount 1d-4)
        (log-env 'manipulate-container "~(~a~) is at ~,4f already (target ~,4f): nothing to ~(~a~)."
                 (container-name container) (container-joint-state container) target action)
        (return-from manipulate-container (container-joint-state container)))
      (let* ((grasps (container-grasps container grasps))
             (reachable (reachable-grasp container action arm amount grasps))
             (first-grasp (or reachable (drive-to-handle container action arm amount grasps)))
             (order (cons first-grasp (remove first-grasp grasps)))
             (last-failure nil))
        (dolist (grasp order)
          (handler-case
              (return-from manipulate-container
                (manipulate-with-grasp container action arm grasp amount object))
            ((and common-fail:manipulation-low-level-failure
                  (not common-fail:environment-manipulation-goal-not-reached)) (e)
              (setf last-failure e)
              (cpl:log-message :warn '(env-man manipulate-container)
                               "Grasp ~(~a~) of ~(~a~) failed: ~a" grasp (container-name container) e))))
        (cpl:fail 'common-fail:environment-unreachable
                  :description (format nil "No handle grasp of ~(~a~) worked with the ~(~a~) arm~@[: ~a~]."
                                       (container-name container) arm last-failure))))))
