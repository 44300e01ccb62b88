;;;; Where the robot stands to open or close a container: whether the handle's trajectory is
;;;; within reach of the current base, and base poses in front of the handle (a drawer: a grid
;;;; beside its path; a door: a ring around the handle, clear of the door's sweep), each free of
;;;; collisions and with IK solutions for the grasp and the last pose of the trajectory.

(in-package :cram-urdf-environment-manipulation)

(defparameter *prismatic-stand-off* '(0.45d0 0.55d0 0.65d0 0.35d0 0.75d0)
  "Metres in front of a drawer's outermost handle position the base may stand, preferred first.")
(defparameter *prismatic-side-offset* '(0.2d0 0.1d0 0.3d0 0.0d0 0.4d0)
  "Metres towards the arm's side of the drawer's axis the handle may lie, preferred first.")
(defparameter *revolute-radii* '(0.6d0 0.7d0 0.5d0 0.8d0)
  "Distances (metres) from a door's handle at which the base may stand.")
(defparameter *revolute-directions* 16
  "Directions around a door's handle sampled for the base.")
(defparameter *door-clearance* 0.45d0
  "The least distance (metres) between the base's centre and a door at any angle of its
trajectory.")
(defparameter *reachability-ik-restarts* 4
  "Random restarts of each IK call that tests a base pose.")

(defun horizontal (vector)
  (let ((x (cl-transforms:x vector)) (y (cl-transforms:y vector)))
    (let ((n (sqrt (+ (* x x) (* y y)))))
      (if (< n 1d-9)
          (cl-transforms:make-3d-vector 1 0 0)
          (cl-transforms:make-3d-vector (/ x n) (/ y n) 0)))))

(defun base-pose-facing (x y direction-x direction-y)
  "A base pose at (X, Y) on the floor facing along (DIRECTION-X, DIRECTION-Y)."
  (cl-transforms:make-pose (cl-transforms:make-3d-vector x y 0)
                           (cl-transforms:axis-angle->quaternion
                            (cl-transforms:make-3d-vector 0 0 1) (atan direction-y direction-x))))

(defun trajectory-checkpoints (trajectory)
  "The poses whose reachability decides a base pose: the grasp and the first, middle and last
pose of the opening or closing segment."
  (let ((moving (man-int:traj-segment-poses (third trajectory))))
    (remove-duplicates
     (list (first (man-int:get-traj-poses-by-label trajectory :grasping))
           (first moving) (nth (floor (length moving) 2) moving) (car (last moving))))))

(defparameter *reach-base-offsets* '(0d0 0.1d0 -0.1d0 0.2d0 -0.2d0)
  "Shifts (metres, along the base's x axis) the arm motions may make the base take to reach a
pose, as MOVE-TCP does with its base offsets.")

(defun poses-reachable-p (arm poses robot)
  "True when ARM of ROBOT has IK solutions for every tool pose of POSES from where it stands, or
from the base shifted by one of *REACH-BASE-OFFSETS*, at one torso height for all of them (the
current one first, then the others MOVE-TCP would try). As MOVE-TCP, the wrist goals are made
once from the tool poses, and the IK chain is looked up once."
  (let* ((base (btr:pose robot))
         (torso (urdf-proj:torso-joint))
         (torso-value (and torso (member torso (btr:joint-names robot) :test #'string=)
                           (btr:joint-state robot torso)))
         (heights (or (and torso-value (urdf-proj::torso-candidates robot nil)) (list nil)))
         (chain (urdf-proj::arm-ik-chain arm robot))
         (end-effector (urdf-proj:end-effector-link arm))
         (first-child (urdf-proj::first-joint-child chain robot))
         (goals (mapcar (lambda (pose) (urdf-proj::tcp->ee-pose arm pose robot)) poses))
         (bases (mapcar (lambda (dx)
                          (translate-pose base (cl-transforms:rotate (cl-transforms:orientation base)
                                                                     (cl-transforms:make-3d-vector dx 0 0))))
                        *reach-base-offsets*)))
    (unwind-protect
         (some (lambda (height)
                 (when height
                   (btr:set-robot-state-from-joints (list (list torso height)) robot))
                 (every (lambda (goal)
                          (some (lambda (shifted)
                                  (setf (btr:pose robot) shifted)
                                  (urdf-proj::chain-ik-from-map chain end-effector first-child goal robot
                                                                nil *reachability-ik-restarts*))
                                bases))
                        goals))
               heights)
      (setf (btr:pose robot) base)
      (when torso-value
        (btr:set-robot-state-from-joints (list (list torso torso-value)) robot)))))

(defparameter *reachability-cache-size* 256
  "The most answers of REACHABLE-GRASP kept (the cache is emptied when it is full).")

(defvar *reachability-cache* (make-hash-table :test 'equal :synchronized t)
  "(robot model, base pose, torso, container state, action, arm, amount, grasps) → the answer
of REACHABLE-GRASP: IK depends on nothing else, so repeating an action where the robot stands
asks the solver once.")

(defun reachability-key (robot container action arm amount grasps)
  (let* ((base (btr:pose robot))
         (o (cl-transforms:origin base))
         (torso (urdf-proj:torso-joint)))
    (flet ((r (x) (round (* x 1d6))))
      (list (btr:urdf robot)
            (r (cl-transforms:x o)) (r (cl-transforms:y o)) (r (cl-transforms:z o))
            (r (cl-transforms:get-yaw (cl-transforms:orientation base)))
            (and torso (member torso (btr:joint-names robot) :test #'string=)
                 (r (btr:joint-state robot torso)))
            (btr:urdf (container-environment container)) (container-joint container)
            (r (container-joint-state container)) action arm (r amount) grasps))))

(defun reachable-grasp (container action arm amount grasps)
  "The first of GRASPS whose trajectory ARM reaches from the robot's current base, or NIL."
  (let* ((robot (urdf-proj:robot-object))
         (key (reachability-key robot container action arm amount grasps)))
    (multiple-value-bind (answer known) (gethash key *reachability-cache*)
      (if known
          answer
          (let ((answer (find-if (lambda (grasp)
                                   (poses-reachable-p arm (trajectory-checkpoints
                                                           (container-trajectory container action grasp amount))
                                                      robot))
                                 grasps)))
            (when (>= (hash-table-count *reachability-cache*) *reachability-cache-size*)
              (clrhash *reachability-cache*))
            (setf (gethash key *reachability-cache*) answer))))))

(defun prismatic-base-candidates (container action arm amount)
  (multiple-value-bind (axis) (joint-axis-in-map container)
    (let* ((handle (cl-transforms:origin (btr:link-pose (container-environment container)
                                                        (container-handle container))))
           (out (horizontal axis))
           ;; the outermost handle position of the motion
           (outermost (if (eq action :open) (cl-transforms:v+ handle (cl-transforms:v* axis amount)) handle))
           (facing (cl-transforms:v* out -1))
           ;; the robot's left when it faces the drawer
           (left (cl-transforms:make-3d-vector (- (cl-transforms:y facing)) (cl-transforms:x facing) 0))
           (side (if (eq arm :left) -1 1)))
      (loop for s in *prismatic-stand-off*
            nconc (loop for l in *prismatic-side-offset*
                        for p = (cl-transforms:v+ (cl-transforms:v+ outermost (cl-transforms:v* out s))
                                                  (cl-transforms:v* left (* side l)))
                        collect (base-pose-facing (cl-transforms:x p) (cl-transforms:y p)
                                                  (cl-transforms:x facing) (cl-transforms:y facing)))))))

(defun point-segment-distance-2d (p a b)
  (let* ((abx (- (cl-transforms:x b) (cl-transforms:x a))) (aby (- (cl-transforms:y b) (cl-transforms:y a)))
         (apx (- (cl-transforms:x p) (cl-transforms:x a))) (apy (- (cl-transforms:y p) (cl-transforms:y a)))
         (len2 (+ (* abx abx) (* aby aby)))
         (u (if (< len2 1d-12) 0d0 (max 0d0 (min 1d0 (/ (+ (* apx abx) (* apy aby)) len2)))))
         (dx (- apx (* u abx))) (dy (- apy (* u aby))))
    (sqrt (+ (* dx dx) (* dy dy)))))

(defun revolute-base-candidates (container trajectory)
  (multiple-value-bind (axis hinge) (joint-axis-in-map container)
    (declare (ignore axis))
    (let* ((handles (mapcar #'cl-transforms:origin (man-int:traj-segment-poses (third trajectory))))
           (middle (nth (floor (length handles) 2) handles)))
      (loop for r in *revolute-radii*
            nconc (loop for k below *revolute-directions*
                        for phi = (/ (* 2 pi k) *revolute-directions*)
                        for x = (+ (cl-transforms:x middle) (* r (cos phi)))
                        for y = (+ (cl-transforms:y middle) (* r (sin phi)))
                        for p = (cl-transforms:make-3d-vector x y 0)
                        when (every (lambda (h) (> (point-segment-distance-2d p hinge h) *door-clearance*))
                                    handles)
                          collect (base-pose-facing x y (- (cl-transforms:x middle) x)
                                                    (- (cl-transforms:y middle) y)))))))

(defun container-base-pose-finder (container action arm amount &key grasps)
  "A function returning, each time it is called, the next base pose (map, on the floor) from
which ARM can ACTION (:OPEN or :CLOSE) CONTAINER by AMOUNT, as (pose grasp) with the first of
GRASPS (default: all handle grasps) that works there: collision-free and with IK solutions
along the trajectory; NIL when no candidate is left. Each call checks only as many candidates
as it needs, in the robot's state at the time, and puts the robot back where it stood."
  (let* ((robot (urdf-proj:robot-object))
         (grasps (container-grasps container grasps))
         (candidates (if (eq (container-joint-type container) :prismatic)
                         (prismatic-base-candidates container action arm amount)
                         (revolute-base-candidates
                          container (container-trajectory container action (first grasps) amount)))))
    (lambda ()
      (let ((start (btr:pose robot)))
        (unwind-protect
             (loop for pose = (pop candidates)
                   while pose
                   do (setf (btr:pose robot) pose)
                      (unless (urdf-proj:robot-collides-p :robot robot)
                        (let ((grasp (reachable-grasp container action arm amount grasps)))
                          (when grasp (return (list pose grasp))))))
          (setf (btr:pose robot) start))))))

(defun container-base-poses (container action arm amount &key grasps (count 1))
  "Up to COUNT base poses (map, on the floor) from which ARM can ACTION (:OPEN or :CLOSE)
CONTAINER by AMOUNT, each as (pose grasp) with the first of GRASPS (default: all handle
grasps) that works there: collision-free and with IK solutions along the trajectory. The
robot is put back where it stood."
  (loop with next = (container-base-pose-finder container action arm amount :grasps grasps)
        repeat count
        for found = (funcall next)
        while found collect found))
