;;;; Poses, transforms and points stamped with a frame name and a time (seconds).
;;;; A stamped object is also the plain object: a POSE-STAMPED is a POSE, and so on.

(in-package :cl-transforms-stamped)

(defun normalize-frame-name (frame &optional (place 'frame-id))
  "FRAME, a string, without its leading slashes (\"/map\" and \"map\" name the same frame).
A non-string signals CL-TRANSFORMS:TRANSFORM-INPUT-ERROR naming it."
  (cond ((not (stringp frame))
         (cl-transforms::input-error frame "a frame name (a string)" place))
        ((and (plusp (length frame)) (char= (char frame 0) #\/))
         (coerce (string-left-trim "/" frame) 'simple-string))
        ((typep frame 'simple-string) frame)
        (t (coerce frame 'simple-string))))

(defun frame-name-arg (frame place)
  "FRAME normalised by NORMALIZE-FRAME-NAME for a constructor at PLACE; an empty name (\"\" or
only slashes) names no frame and signals TRANSFORM-INPUT-ERROR."
  (let ((name (normalize-frame-name frame place)))
    (when (zerop (length name))
      (cl-transforms::input-error frame "a non-empty frame name such as \"map\"" place))
    name))

(defun %stamp (stamp place)
  "STAMP, a real time in seconds, as a double float."
  (cl-transforms::ensure-double stamp place))

(defstruct (pose-stamped (:include pose)
                         (:constructor %make-pose-stamped (frame-id stamp origin orientation))
                         (:conc-name %ps-)
                         (:copier nil))
  "A POSE given relative to the frame FRAME-ID at time STAMP (seconds)."
  (frame-id "" :type simple-string :read-only t)
  (stamp 0d0 :type double-float :read-only t))

(defstruct (transform-stamped (:include transform)
                              (:constructor %make-transform-stamped
                                  (frame-id child-frame-id stamp translation rotation
                                   &aux (cl-transforms::tx (cl-transforms::%v-x translation))
                                        (cl-transforms::ty (cl-transforms::%v-y translation))
                                        (cl-transforms::tz (cl-transforms::%v-z translation))
                                        (cl-transforms::qx (cl-transforms::%q-x rotation))
                                        (cl-transforms::qy (cl-transforms::%q-y rotation))
                                        (cl-transforms::qz (cl-transforms::%q-z rotation))
                                        (cl-transforms::qw (cl-transforms::%q-w rotation))))
                              (:constructor %make-raw-transform-stamped
                                  (frame-id child-frame-id stamp
                                   cl-transforms::tx cl-transforms::ty cl-transforms::tz
                                   cl-transforms::qx cl-transforms::qy cl-transforms::qz
                                   cl-transforms::qw))
                              (:conc-name %ts-)
                              (:copier nil))
  "A TRANSFORM from the frame FRAME-ID to the frame CHILD-FRAME-ID at time STAMP: the pose of
CHILD-FRAME-ID in FRAME-ID; it maps points given in CHILD-FRAME-ID into FRAME-ID."
  (frame-id "" :type simple-string :read-only t)
  (child-frame-id "" :type simple-string :read-only t)
  (stamp 0d0 :type double-float :read-only t))

(defstruct (point-stamped (:include 3d-vector)
                          (:constructor %make-point-stamped (frame-id stamp x y z))
                          (:conc-name %pts-)
                          (:copier nil))
  "A point (a 3D-VECTOR) given in the frame FRAME-ID at time STAMP (seconds)."
  (frame-id "" :type simple-string :read-only t)
  (stamp 0d0 :type double-float :read-only t))

(setf (documentation 'pose-stamped-p 'function) "True when the object is a POSE-STAMPED."
      (documentation 'transform-stamped-p 'function) "True when the object is a TRANSFORM-STAMPED."
      (documentation 'point-stamped-p 'function) "True when the object is a POINT-STAMPED.")

(defmethod make-load-form ((object pose-stamped) &optional environment)
  (make-load-form-saving-slots object :environment environment))

(defmethod make-load-form ((object transform-stamped) &optional environment)
  (make-load-form-saving-slots object :environment environment))

(defmethod make-load-form ((object point-stamped) &optional environment)
  (make-load-form-saving-slots object :environment environment))

(defmethod print-object ((p pose-stamped) stream)
  (if *print-readably*
      (print-unreadable-object (p stream))
      (format stream "#<POSE-STAMPED ~%   FRAME-ID: ~s, STAMP: ~f~%   ~a~%   ~a>"
              (%ps-frame-id p) (%ps-stamp p) (origin p) (orientation p))))

(defmethod print-object ((tr transform-stamped) stream)
  (if *print-readably*
      (print-unreadable-object (tr stream))
      (format stream "#<TRANSFORM-STAMPED ~%   FRAME-ID: ~s, CHILD-FRAME-ID: ~s, STAMP: ~f~%   ~a~%   ~a>"
              (%ts-frame-id tr) (%ts-child-frame-id tr) (%ts-stamp tr)
              (translation tr) (rotation tr))))

(defmethod print-object ((p point-stamped) stream)
  (if *print-readably*
      (print-unreadable-object (p stream))
      (cl-transforms::with-double-printing
        (format stream "#<POINT-STAMPED ~%   FRAME-ID: ~s, STAMP: ~f~%   (~s ~s ~s)>"
                (%pts-frame-id p) (%pts-stamp p) (x p) (y p) (z p)))))

;;; Accessors shared by the stamped types

(declaim (inline frame-id stamp child-frame-id))
(defun frame-id (stamped)
  "The frame name of a POSE-STAMPED, POINT-STAMPED or TRANSFORM-STAMPED (for a transform, the
parent frame)."
  (typecase stamped
    (pose-stamped (%ps-frame-id stamped))
    (transform-stamped (%ts-frame-id stamped))
    (point-stamped (%pts-frame-id stamped))
    (t (cl-transforms::input-error stamped "a POSE-STAMPED, POINT-STAMPED or TRANSFORM-STAMPED"
                                   'frame-id))))

(defun stamp (stamped)
  "The time stamp (seconds, a double float) of a POSE-STAMPED, POINT-STAMPED or
TRANSFORM-STAMPED."
  (typecase stamped
    (pose-stamped (%ps-stamp stamped))
    (transform-stamped (%ts-stamp stamped))
    (point-stamped (%pts-stamp stamped))
    (t (cl-transforms::input-error stamped "a POSE-STAMPED, POINT-STAMPED or TRANSFORM-STAMPED"
                                   'stamp))))

(defun child-frame-id (transform-stamped)
  "The child frame name of a TRANSFORM-STAMPED."
  (if (transform-stamped-p transform-stamped)
      (%ts-child-frame-id transform-stamped)
      (cl-transforms::input-error transform-stamped "a TRANSFORM-STAMPED" 'child-frame-id)))

;;; Constructors

(defun make-pose-stamped (frame-id stamp origin orientation)
  "A POSE-STAMPED at ORIGIN (a 3D-VECTOR) with ORIENTATION (a QUATERNION) in the frame FRAME-ID
(a string; a leading \"/\" is dropped) at time STAMP (a real, seconds)."
  (%make-pose-stamped
   (frame-name-arg frame-id 'make-pose-stamped)
   (%stamp stamp "MAKE-POSE-STAMPED stamp")
   (cl-transforms::check-type-of origin '3d-vector "a 3D-VECTOR as origin" 'make-pose-stamped)
   (cl-transforms::check-type-of orientation 'quaternion "a QUATERNION as orientation"
                                 'make-pose-stamped)))

(defun pose->pose-stamped (frame-id stamp pose)
  "POSE (a POSE, or a list ((x y z) (qx qy qz qw))) as a POSE-STAMPED in FRAME-ID at STAMP."
  (let ((pose (cl-transforms::%ensure-pose pose 'pose->pose-stamped)))
    (make-pose-stamped frame-id stamp (origin pose) (orientation pose))))

(defun pose-stamped->pose (pose-stamped)
  "The plain POSE of POSE-STAMPED, without frame and stamp."
  (cl-transforms::check-type-of pose-stamped 'pose "a POSE-STAMPED" 'pose-stamped->pose)
  (make-pose (origin pose-stamped) (orientation pose-stamped)))

(defun copy-pose-stamped (pose &key origin orientation frame-id stamp)
  "A POSE-STAMPED like POSE with the given parts replaced. POSE may be a plain POSE when FRAME-ID
is given (its stamp then defaults to 0)."
  (cl-transforms::check-type-of pose 'pose "a POSE-STAMPED" 'copy-pose-stamped)
  (let ((stamped (pose-stamped-p pose)))
    (unless (or stamped frame-id)
      (cl-transforms::input-error pose "a POSE-STAMPED (or a :FRAME-ID for a plain POSE)"
                                  'copy-pose-stamped))
    (make-pose-stamped (or frame-id (%ps-frame-id pose))
                       (or stamp (if stamped (%ps-stamp pose) 0d0))
                       (or origin (origin pose))
                       (or orientation (orientation pose)))))

(defun ensure-pose-stamped (pose &optional (frame-id "map") (stamp 0d0))
  "POSE itself when it is a POSE-STAMPED; a plain POSE or a list ((x y z) (qx qy qz qw)) is
stamped with FRAME-ID and STAMP."
  (if (pose-stamped-p pose)
      pose
      (pose->pose-stamped frame-id stamp pose)))

(defun make-transform-stamped (frame-id child-frame-id stamp translation rotation)
  "A TRANSFORM-STAMPED from FRAME-ID to CHILD-FRAME-ID at time STAMP with TRANSLATION (a
3D-VECTOR) and ROTATION (a QUATERNION): the pose of CHILD-FRAME-ID in FRAME-ID."
  (%make-transform-stamped
   (frame-name-arg frame-id 'make-transform-stamped)
   (frame-name-arg child-frame-id 'make-transform-stamped)
   (%stamp stamp "MAKE-TRANSFORM-STAMPED stamp")
   (cl-transforms::check-type-of translation '3d-vector "a 3D-VECTOR as translation"
                                 'make-transform-stamped)
   (cl-transforms::check-type-of rotation 'quaternion "a QUATERNION as rotation"
                                 'make-transform-stamped)))

(defun transform->transform-stamped (frame-id child-frame-id stamp transform)
  "TRANSFORM as a TRANSFORM-STAMPED from FRAME-ID to CHILD-FRAME-ID at STAMP."
  (cl-transforms::check-type-of transform 'transform "a TRANSFORM" 'transform->transform-stamped)
  (make-transform-stamped frame-id child-frame-id stamp (translation transform) (rotation transform)))

(defun transform-stamped->transform (transform-stamped)
  "The plain TRANSFORM of TRANSFORM-STAMPED."
  (cl-transforms::check-type-of transform-stamped 'transform "a TRANSFORM-STAMPED"
                                'transform-stamped->transform)
  (make-transform (translation transform-stamped) (rotation transform-stamped)))

(defun copy-transform-stamped (transform &key frame-id child-frame-id stamp translation rotation)
  "A TRANSFORM-STAMPED like TRANSFORM with the given parts replaced."
  (cl-transforms::check-type-of transform 'transform-stamped "a TRANSFORM-STAMPED"
                                'copy-transform-stamped)
  (make-transform-stamped (or frame-id (%ts-frame-id transform))
                          (or child-frame-id (%ts-child-frame-id transform))
                          (or stamp (%ts-stamp transform))
                          (or translation (translation transform))
                          (or rotation (rotation transform))))

(defun make-point-stamped (frame-id stamp point)
  "A POINT-STAMPED at POINT (a 3D-VECTOR or a list (x y z)) in FRAME-ID at time STAMP."
  (let ((p (cl-transforms::%ensure-vector-like point "MAKE-POINT-STAMPED point")))
    (%make-point-stamped (frame-name-arg frame-id 'make-point-stamped)
                         (%stamp stamp "MAKE-POINT-STAMPED stamp")
                         (x p) (y p) (z p))))

(defun point-stamped->point (point-stamped)
  "The plain 3D-VECTOR of POINT-STAMPED."
  (cl-transforms::check-type-of point-stamped '3d-vector "a POINT-STAMPED" 'point-stamped->point)
  (make-3d-vector (x point-stamped) (y point-stamped) (z point-stamped)))

(defun copy-point-stamped (point &key frame-id stamp x y z)
  "A POINT-STAMPED like POINT with the given parts replaced."
  (cl-transforms::check-type-of point 'point-stamped "a POINT-STAMPED" 'copy-point-stamped)
  (make-point-stamped (or frame-id (%pts-frame-id point))
                      (or stamp (%pts-stamp point))
                      (make-3d-vector (or x (x point)) (or y (y point)) (or z (z point)))))
