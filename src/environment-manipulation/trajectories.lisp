;;;; Handle grasps and the trajectories of opening and closing: reach the handle from 5 cm
;;;; back, grasp it, pull or push it along the drawer's axis or around the door's hinge, and
;;;; retract 5 cm. Tool frames follow the project's convention: x along the approach, the
;;;; fingers opening along y.

(in-package :cram-urdf-environment-manipulation)

(defparameter *handle-pregrasp-offset* 0.05d0
  "Metres a reaching pose lies back from the handle grasp, against the approach.")
(defparameter *handle-retract-offset* 0.05d0
  "Metres the gripper retracts from the handle along its approach axis after releasing it.")
(defparameter *revolute-trajectory-step* 0.1d0
  "Radians between the poses of a door's trajectory around its hinge.")

(defparameter *handle-grasps*
  ;; grasp  tool x (approach)  tool y (finger axis), in the handle frame
  '((:front (-1 0 0) (0 0 1))
    (:back (1 0 0) (0 0 1))
    (:left-side (0 -1 0) (1 0 0))
    (:right-side (0 1 0) (-1 0 0))
    (:front-along-y (-1 0 0) (0 -1 0)))
  "The handle grasps, CRAM's names, each with the tool frame's approach axis (x) and finger axis
(y) in the handle frame: FRONT approaches from outside with the fingers closing vertically (a
horizontal bar), FRONT-ALONG-Y with them closing horizontally (a vertical bar).")

(defun cross (a b)
  (destructuring-bind ((ax ay az) (bx by bz)) (list a b)
    (list (- (* ay bz) (* az by)) (- (* az bx) (* ax bz)) (- (* ax by) (* ay bx)))))

(defun handle-grasp-transform (grasp)
  "The tool frame of the handle GRASP (:FRONT, :BACK, :LEFT-SIDE, :RIGHT-SIDE, :FRONT-ALONG-Y)
in the handle frame, as a transform (no offset: the tool frame at the handle's origin)."
  (let ((entry (assoc grasp *handle-grasps*)))
    (unless entry
      (env-error "Handle grasp ~s: expected one of ~{~(~a~)~^, ~}." grasp
                 (mapcar #'first *handle-grasps*)))
    (destructuring-bind (x y) (rest entry)
      (let ((z (cross x y))
            (m (make-array '(3 3) :element-type 'double-float)))
        (loop for column in (list x y z) for j from 0
              do (loop for value in column for i from 0 do (setf (aref m i j) (d value))))
        (cl-transforms:make-transform (cl-transforms:make-3d-vector 0 0 0)
                                      (cl-transforms:matrix->quaternion m))))))

(defun handle-long-axis (container)
  "The index (0 x, 1 y, 2 z) of the longest side of the handle's first collision box, or NIL."
  (let* ((urdf (btr:urdf (container-environment container)))
         (link (gethash (container-handle container) (cl-urdf:links urdf)))
         (geometry (getf (first (cl-urdf:collision link)) :geometry))
         (size (and (eq (first geometry) :box) (getf (rest geometry) :size))))
    (and size (position (reduce #'max size) size))))

(defun container-grasps (container &optional grasps)
  "The handle grasps to try on CONTAINER, GRASPS (a grasp or a list) or all of *HANDLE-GRASPS*:
those whose approach and finger axes are across the handle bar first, approaching from
outside before from behind."
  (let* ((wanted (cond ((null grasps) (mapcar #'first *handle-grasps*))
                       ((listp grasps) grasps)
                       (t (list grasps))))
         (long (handle-long-axis container)))
    (dolist (g wanted) (handle-grasp-transform g))
    (flet ((score (grasp)
             (destructuring-bind (x y) (rest (assoc grasp *handle-grasps*))
               (+ (if (and long (or (/= 0 (nth long x)) (/= 0 (nth long y)))) 2 0)
                  (if (minusp (first x)) 0 1)))))
      (stable-sort (copy-list wanted) #'< :key #'score))))

;;; ---- poses ------------------------------------------------------------------------------------

(defun pose* (pose transform)
  (cl-transforms:transform->pose
   (cl-transforms:transform* (cl-transforms:pose->transform pose) transform)))

(defun translate-pose (pose vector)
  (cl-transforms:make-pose (cl-transforms:v+ (cl-transforms:origin pose) vector)
                           (cl-transforms:orientation pose)))

(defun tool-approach (pose)
  "The approach axis (the tool frame's x) of the tool POSE, in the map."
  (cl-transforms:rotate (cl-transforms:orientation pose) (cl-transforms:make-3d-vector 1 0 0)))

(defun back-off (pose distance)
  "POSE moved DISTANCE metres back against its approach axis."
  (translate-pose pose (cl-transforms:v* (tool-approach pose) (- distance))))

(defun joint-axis-in-map (container)
  "(values axis origin) of CONTAINER's joint in the map: the unit axis and a point on it (the
origin of the joint's child link)."
  (let* ((environment (container-environment container))
         (joint (gethash (container-joint container) (cl-urdf:joints (btr:urdf environment))))
         (child-pose (btr:link-pose environment (cl-urdf:name (cl-urdf:child joint))))
         (axis (apply #'cl-transforms:make-3d-vector (mapcar #'d (cl-urdf:axis joint)))))
    (values (cl-transforms:normalize-vector
             (cl-transforms:rotate (cl-transforms:orientation child-pose) axis))
            (cl-transforms:origin child-pose))))

(defun rotate-pose-about (pose axis point angle)
  "POSE turned by ANGLE radians about the line through POINT along the unit AXIS."
  (let ((q (cl-transforms:axis-angle->quaternion axis angle)))
    (cl-transforms:make-pose
     (cl-transforms:v+ point (cl-transforms:rotate q (cl-transforms:v- (cl-transforms:origin pose) point)))
     (cl-transforms:q* q (cl-transforms:orientation pose)))))

(defun revolute-angles (amount)
  "The angles of a door trajectory of AMOUNT radians: every *REVOLUTE-TRAJECTORY-STEP* from 0
while below |AMOUNT|, then AMOUNT itself (ceiling(|a| / step) + 1 angles), signed as AMOUNT."
  (let ((a (abs amount)) (sign (if (minusp amount) -1 1)))
    (append (loop for i from 0
                  for angle = (* i *revolute-trajectory-step*)
                  while (< angle (- a 1d-9))
                  collect (* sign angle))
            (list (d amount)))))

(defun handle-grasp-pose (container grasp)
  "The tool pose (map) of GRASP on CONTAINER's handle, in the belief state's current state."
  (pose* (btr:link-pose (container-environment container) (container-handle container))
         (handle-grasp-transform grasp)))

(defun container-trajectory (container action grasp amount)
  "The trajectory segments (MAN-INT:TRAJ-SEGMENT) of ACTION (:OPEN or :CLOSE) of CONTAINER by
AMOUNT (metres or radians, >= 0) with the handle GRASP: :REACHING (5 cm back), :GRASPING (the
handle), :OPENING or :CLOSING (a drawer: the grasp moved by axis × amount; a door: the grasp
turned about the hinge every 0.1 rad), :RETRACTING (5 cm back from the last pose)."
  (let* ((grasp-pose (handle-grasp-pose container grasp))
         (signed (if (eq action :open) amount (- amount)))
         (moving (multiple-value-bind (axis origin) (joint-axis-in-map container)
                   (if (eq (container-joint-type container) :prismatic)
                       (list (translate-pose grasp-pose (cl-transforms:v* axis signed)))
                       (mapcar (lambda (angle) (rotate-pose-about grasp-pose axis origin angle))
                               (revolute-angles signed))))))
    (list (man-int:make-traj-segment :reaching (list (back-off grasp-pose *handle-pregrasp-offset*)))
          (man-int:make-traj-segment :grasping (list grasp-pose))
          (man-int:make-traj-segment (if (eq action :open) :opening :closing) moving)
          (man-int:make-traj-segment :retracting
                                     (list (back-off (car (last moving)) *handle-retract-offset*))))))
