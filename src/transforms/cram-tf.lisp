;;;; CRAM-TF: the robot's frame conventions, the global transformer, and pose helpers.

(in-package :cram-tf)

(defvar *transformer* (make-instance 'transformer)
  "The TRANSFORMER that robot code and the projection use for frame lookups.")

(defvar *fixed-frame* "map"
  "The world-fixed frame that navigation goals and object poses are given in.")

(defvar *odom-frame* "odom_combined"
  "The odometry frame of the robot.")

(defvar *robot-base-frame* "base_footprint"
  "The frame of the robot's base, on the floor under its centre.")

(defvar *robot-torso-frame* "torso_lift_link"
  "The frame of the robot's torso link.")

(defvar *robot-torso-joint* "torso_lift_joint"
  "The joint that raises the robot's torso.")

(defvar *robot-left-tool-frame* "l_gripper_tool_frame"
  "The tool frame (tool centre point) of the robot's left gripper.")

(defvar *robot-right-tool-frame* "r_gripper_tool_frame"
  "The tool frame (tool centre point) of the robot's right gripper.")

(defvar *tf-default-timeout* 2.0
  "Seconds a lookup through the cram-tf helpers waits for missing frames before it fails.")

(defun robot-current-pose ()
  "The POSE-STAMPED of *ROBOT-BASE-FRAME* in *FIXED-FRAME*, looked up in *TRANSFORMER*."
  (transform-pose-stamped *transformer*
                          :target-frame *fixed-frame*
                          :pose (make-pose-stamped *robot-base-frame* 0d0
                                                   (make-identity-vector)
                                                   (make-identity-rotation))
                          :timeout *tf-default-timeout*))

(defun frame-to-pose-in-fixed-frame (frame-name)
  "The POSE-STAMPED of the origin of FRAME-NAME in *FIXED-FRAME*, looked up in *TRANSFORMER*."
  (transform-pose-stamped *transformer*
                          :target-frame *fixed-frame*
                          :pose (make-pose-stamped frame-name 0d0
                                                   (make-identity-vector)
                                                   (make-identity-rotation))
                          :timeout *tf-default-timeout*))

(defun %axis-vector (axis)
  "The unit 3D-VECTOR of AXIS, one of :X, :Y, :Z."
  (case axis
    (:x (make-3d-vector 1 0 0))
    (:y (make-3d-vector 0 1 0))
    (:z (make-3d-vector 0 0 1))
    (t (cl-transforms::input-error axis "one of the axes :X, :Y, :Z" 'rotate-pose))))

(defun rotate-pose (pose axis angle)
  "POSE (a POSE or POSE-STAMPED) with its orientation turned by ANGLE radians about AXIS (:X, :Y
or :Z) of its reference frame; the origin stays. Returns the same kind of pose."
  (cl-transforms::check-type-of pose 'pose "a POSE or POSE-STAMPED" 'rotate-pose)
  (let ((orientation (q* (axis-angle->quaternion (%axis-vector axis) angle)
                         (orientation pose))))
    (if (pose-stamped-p pose)
        (copy-pose-stamped pose :orientation orientation)
        (copy-pose pose :orientation orientation))))

(defun angle-around-map-z (angle)
  "The QUATERNION turning by ANGLE radians about the z axis of the map (a yaw)."
  (axis-angle->quaternion (make-3d-vector 0 0 1)
                          (cl-transforms::ensure-double angle "ANGLE-AROUND-MAP-Z angle")))

(defun %offset-vector (vector x-offset y-offset z-offset)
  "VECTOR moved by the offsets along the axes of its own frame."
  (v+ vector (make-3d-vector x-offset y-offset z-offset)))

(defun translate-pose (pose &key (x-offset 0d0) (y-offset 0d0) (z-offset 0d0))
  "POSE (a POSE or POSE-STAMPED) with its origin moved by the offsets along the axes of its
reference frame. Returns the same kind of pose."
  (cl-transforms::check-type-of pose 'pose "a POSE or POSE-STAMPED" 'translate-pose)
  (let ((origin (%offset-vector (origin pose) x-offset y-offset z-offset)))
    (if (pose-stamped-p pose)
        (copy-pose-stamped pose :origin origin)
        (copy-pose pose :origin origin))))

(defun translate-transform-stamped (transform &key (x-offset 0d0) (y-offset 0d0) (z-offset 0d0))
  "TRANSFORM (a TRANSFORM-STAMPED) with its translation moved by the offsets."
  (cl-transforms::check-type-of transform 'transform-stamped "a TRANSFORM-STAMPED"
                                'translate-transform-stamped)
  (copy-transform-stamped
   transform :translation (%offset-vector (translation transform) x-offset y-offset z-offset)))

(defun pose-stamped->transform-stamped (pose-stamped child-frame-id)
  "The TRANSFORM-STAMPED from the frame of POSE-STAMPED to CHILD-FRAME-ID, a frame located at
POSE-STAMPED."
  (cl-transforms::check-type-of pose-stamped 'pose-stamped "a POSE-STAMPED"
                                'pose-stamped->transform-stamped)
  (make-transform-stamped (frame-id pose-stamped) child-frame-id (stamp pose-stamped)
                          (origin pose-stamped) (orientation pose-stamped)))

(defun transform-stamped->pose-stamped (transform-stamped)
  "The POSE-STAMPED of the child frame of TRANSFORM-STAMPED in its parent frame."
  (cl-transforms::check-type-of transform-stamped 'transform-stamped "a TRANSFORM-STAMPED"
                                'transform-stamped->pose-stamped)
  (make-pose-stamped (frame-id transform-stamped) (stamp transform-stamped)
                     (translation transform-stamped) (rotation transform-stamped)))

(defun strip-transform-stamped (transform-stamped)
  "The POSE-STAMPED of the child frame of TRANSFORM-STAMPED in its parent frame (as
TRANSFORM-STAMPED->POSE-STAMPED)."
  (transform-stamped->pose-stamped transform-stamped))

(defun pose->transform-stamped (parent-frame child-frame stamp pose)
  "The TRANSFORM-STAMPED from PARENT-FRAME to CHILD-FRAME at STAMP with the origin and orientation
of POSE."
  (let ((pose (cl-transforms::%ensure-pose pose 'pose->transform-stamped)))
    (make-transform-stamped parent-frame child-frame stamp (origin pose) (orientation pose))))

(defun transform-stamped-inv (transform-stamped)
  "The inverse of TRANSFORM-STAMPED, from its child frame to its parent frame."
  (cl-transforms::check-type-of transform-stamped 'transform-stamped "a TRANSFORM-STAMPED"
                                'transform-stamped-inv)
  (transform->transform-stamped (child-frame-id transform-stamped) (frame-id transform-stamped)
                                (stamp transform-stamped) (transform-inv transform-stamped)))

(defun multiply-transform-stampeds (x-frame z-frame x-y-transform y-z-transform
                                    &key (result-as-pose-or-transform :transform))
  "The product xTy * yTz = xTz of two TRANSFORM-STAMPEDs, from X-FRAME to Z-FRAME, stamped with
the older stamp. The frames must chain: X-Y-TRANSFORM goes from X-FRAME to some y, Y-Z-TRANSFORM
from that y to Z-FRAME; otherwise an error names the mismatch. RESULT-AS-POSE-OR-TRANSFORM
:POSE returns the pose of Z-FRAME in X-FRAME instead."
  (dolist (tr (list x-y-transform y-z-transform))
    (cl-transforms::check-type-of tr 'transform-stamped "a TRANSFORM-STAMPED"
                                  'multiply-transform-stampeds))
  (flet ((same (a b) (string= (normalize-frame-name a) (normalize-frame-name b))))
    (unless (same (frame-id x-y-transform) x-frame)
      (cl-transforms::input-error x-y-transform (format nil "a transform from frame ~s" x-frame)
                                  'multiply-transform-stampeds))
    (unless (same (child-frame-id y-z-transform) z-frame)
      (cl-transforms::input-error y-z-transform (format nil "a transform to frame ~s" z-frame)
                                  'multiply-transform-stampeds))
    (unless (same (child-frame-id x-y-transform) (frame-id y-z-transform))
      (cl-transforms::input-error y-z-transform
                                  (format nil "a transform from frame ~s"
                                          (child-frame-id x-y-transform))
                                  'multiply-transform-stampeds)))
  (let ((product (transform* x-y-transform y-z-transform))
        (stamp (min (stamp x-y-transform) (stamp y-z-transform))))
    (ecase result-as-pose-or-transform
      (:transform (transform->transform-stamped x-frame z-frame stamp product))
      (:pose (pose->pose-stamped x-frame stamp (transform->pose product))))))

(defun apply-transform (left-hand-side right-hand-side)
  "The TRANSFORM-STAMPED LEFT-HAND-SIDE * RIGHT-HAND-SIDE, from the parent frame of the first to
the child frame of the second."
  (multiply-transform-stampeds (frame-id left-hand-side) (child-frame-id right-hand-side)
                               left-hand-side right-hand-side))

(defun ensure-pose-in-frame (pose frame &key use-current-ros-time use-zero-time)
  "POSE as a POSE-STAMPED in FRAME, transformed through *TRANSFORMER*. A plain POSE is taken to be
in FRAME already. NIL gives NIL. USE-ZERO-TIME stamps the result 0."
  (when pose
    (let* ((stamped (ensure-pose-stamped pose frame 0d0))
           (stamped (if use-zero-time (copy-pose-stamped stamped :stamp 0d0) stamped)))
      (transform-pose-stamped *transformer* :pose stamped :target-frame frame
                                            :timeout *tf-default-timeout*
                                            :use-current-ros-time use-current-ros-time))))

(defun ensure-point-in-frame (point frame &key use-current-ros-time use-zero-time)
  "POINT as a POINT-STAMPED in FRAME, transformed through *TRANSFORMER*. A plain 3D-VECTOR is
taken to be in FRAME already. USE-ZERO-TIME stamps the result 0."
  (let* ((stamped (if (point-stamped-p point) point (make-point-stamped frame 0d0 point)))
         (stamped (if use-zero-time (copy-point-stamped stamped :stamp 0d0) stamped)))
    (transform-point-stamped *transformer* :point stamped :target-frame frame
                                           :timeout *tf-default-timeout*
                                           :use-current-ros-time use-current-ros-time)))

;;; Poses as lists

(defun pose->list (pose)
  "POSE as the list ((x y z) (qx qy qz qw))."
  (cl-transforms::check-type-of pose 'pose "a POSE" 'pose->list)
  (let ((o (origin pose)) (q (orientation pose)))
    (list (list (x o) (y o) (z o)) (list (x q) (y q) (z q) (w q)))))

(defun list->pose (list)
  "The POSE of a list ((x y z) (qx qy qz qw))."
  (cl-transforms::%ensure-pose list 'list->pose))

(defun pose->flat-list (pose)
  "POSE as the list (x y z qx qy qz qw)."
  (apply #'append (pose->list pose)))

(defun flat-list->pose (list)
  "The POSE of a list (x y z qx qy qz qw)."
  (if (and (alexandria:proper-list-p list) (= (length list) 7))
      (list->pose (list (subseq list 0 3) (subseq list 3)))
      (cl-transforms::input-error list "a list (x y z qx qy qz qw)" 'flat-list->pose)))

(defun pose->flat-list-w-first (pose)
  "POSE as the list (x y z qw qx qy qz)."
  (destructuring-bind ((x y z) (qx qy qz qw)) (pose->list pose)
    (list x y z qw qx qy qz)))

(defun flat-list-w-first->pose (list)
  "The POSE of a list (x y z qw qx qy qz)."
  (if (and (alexandria:proper-list-p list) (= (length list) 7))
      (destructuring-bind (x y z qw qx qy qz) list
        (list->pose (list (list x y z) (list qx qy qz qw))))
      (cl-transforms::input-error list "a list (x y z qw qx qy qz)" 'flat-list-w-first->pose)))

(defun pose-stamped->list (pose-stamped)
  "POSE-STAMPED as the list (frame-id stamp ((x y z) (qx qy qz qw)))."
  (cl-transforms::check-type-of pose-stamped 'pose-stamped "a POSE-STAMPED" 'pose-stamped->list)
  (list (frame-id pose-stamped) (stamp pose-stamped) (pose->list pose-stamped)))

(defun list->pose-stamped (list)
  "The POSE-STAMPED of a list (frame-id stamp ((x y z) (qx qy qz qw)))."
  (if (and (alexandria:proper-list-p list) (= (length list) 3))
      (destructuring-bind (frame stamp pose) list
        (pose->pose-stamped frame stamp pose))
      (cl-transforms::input-error list "a list (frame-id stamp ((x y z) (qx qy qz qw)))"
                                  'list->pose-stamped)))

;;; Comparisons

(defun poses-equal-p (pose-1 pose-2 dist-sigma ang-sigma)
  "True when the origins of POSE-1 and POSE-2 are at most DIST-SIGMA metres apart and their
orientations at most ANG-SIGMA radians. Stamped poses must share the frame."
  (cl-transforms::check-type-of pose-1 'pose "a POSE" 'poses-equal-p)
  (cl-transforms::check-type-of pose-2 'pose "a POSE" 'poses-equal-p)
  (when (and (pose-stamped-p pose-1) (pose-stamped-p pose-2)
             (string/= (frame-id pose-1) (frame-id pose-2)))
    (cl-transforms::input-error pose-2 (format nil "a pose in frame ~s" (frame-id pose-1))
                                'poses-equal-p))
  (and (<= (v-dist (origin pose-1) (origin pose-2)) dist-sigma)
       (<= (angle-between-quaternions (orientation pose-1) (orientation pose-2)) ang-sigma)))

(defun tf-frame-converged (goal-frame goal-pose-stamped delta-xy delta-theta)
  "True when GOAL-POSE-STAMPED, expressed in GOAL-FRAME, lies within DELTA-XY metres (along x
and y) and DELTA-THETA radians (yaw) of GOAL-FRAME's origin."
  (let* ((pose (ensure-pose-in-frame goal-pose-stamped goal-frame :use-zero-time t))
         (o (origin pose)))
    (and (<= (max (abs (x o)) (abs (y o))) delta-xy)
         (<= (abs (normalize-angle (get-yaw (orientation pose)))) delta-theta))))
