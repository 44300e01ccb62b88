;;;; The TF transformer: a thread-safe tree of frames connected by the latest transform of each
;;;; child frame in its parent; lookups compose transforms along any path in the tree.

(in-package :cl-transforms-stamped)

(define-condition transform-stamped-error (error)
  ((target-frame :initarg :target-frame :initform nil
                 :reader transform-stamped-error-target-frame)
   (source-frame :initarg :source-frame :initform nil
                 :reader transform-stamped-error-source-frame)
   (description :initarg :description :initform nil :reader transform-stamped-error-description))
  (:report (lambda (c stream)
             (format stream "No transform from frame ~s to frame ~s~@[: ~a~]."
                     (transform-stamped-error-source-frame c)
                     (transform-stamped-error-target-frame c)
                     (transform-stamped-error-description c))))
  (:documentation "The root of the errors a TRANSFORMER signals when it cannot answer a lookup.
The report names the source and target frames and the reason."))

(setf (documentation 'transform-stamped-error-target-frame 'function)
      "The target frame of the failed lookup of a TRANSFORM-STAMPED-ERROR."
      (documentation 'transform-stamped-error-source-frame 'function)
      "The source frame of the failed lookup of a TRANSFORM-STAMPED-ERROR.")

(define-condition tf-lookup-error (transform-stamped-error) ()
  (:documentation "A lookup named a frame the transformer has never heard of."))

(define-condition tf-connectivity-error (transform-stamped-error) ()
  (:documentation "Both frames are known, but they are not connected: they lie in different
trees."))

(define-condition tf-extrapolation-error (transform-stamped-error) ()
  (:documentation "A transform was asked for at a time the data does not cover. This transformer
answers every lookup with the latest transforms, so it has no such failure of its own; handlers
for it are harmless."))

(defstruct (tf-frame (:constructor make-tf-frame (name)))
  "A frame of a TRANSFORMER: its NAME, its PARENT frame (NIL for a root) and the latest
TRANSFORM from the parent to it, STATIC when set as such."
  (name "" :type simple-string :read-only t)
  (parent nil :type (or null tf-frame))
  (transform nil :type (or null transform-stamped))
  (static nil :type boolean))

(defclass transformer ()
  ((lock :initform (bt:make-lock "cl-tf transformer") :reader transformer-lock)
   (changed :initform (bt:make-condition-variable :name "cl-tf transformer changed")
            :reader transformer-changed)
   (waiters :initform 0 :type fixnum :accessor transformer-waiters
            :documentation "How many lookups wait for a change.")
   (frames :initform (make-hash-table :test 'equal) :reader transformer-frames
           :documentation "Frame name -> TF-FRAME, for every frame seen as parent or child."))
  (:documentation "A buffer of TRANSFORM-STAMPEDs forming a frame tree (each frame has at most one
parent). SET-TRANSFORM adds or replaces the transform of a child frame; LOOKUP-TRANSFORM,
TRANSFORM-POSE-STAMPED and TRANSFORM-POINT-STAMPED answer with the latest data along the path
between two frames. Safe to update from one thread while others query."))

(defmethod print-object ((tf transformer) stream)
  (print-unreadable-object (tf stream :type t :identity t)
    (format stream "~d frames" (hash-table-count (transformer-frames tf)))))

(defun %check-transformer (transformer place)
  "Signal TRANSFORM-INPUT-ERROR naming TRANSFORMER unless it is a TRANSFORMER."
  (unless (typep transformer 'transformer)
    (cl-transforms::input-error transformer "a CL-TF:TRANSFORMER" place)))

(defun %frame-name (frame place)
  "FRAME as a normalised, non-empty frame name."
  (let ((name (normalize-frame-name frame place)))
    (when (zerop (length name))
      (cl-transforms::input-error frame "a non-empty frame name" place))
    name))

(defun %timeout (timeout place)
  "TIMEOUT in seconds as a non-negative double float; NIL means 0."
  (if timeout
      (let ((d (cl-transforms::ensure-double timeout place)))
        (when (minusp d) (cl-transforms::input-error timeout "a non-negative timeout" place))
        d)
      0d0))

(defun %intern-frame (frames name)
  "The TF-FRAME called NAME in the table FRAMES, created when new."
  (or (gethash name frames)
      (setf (gethash name frames) (make-tf-frame name))))

(defun set-transform (transformer transform &key static (authority "default_authority"))
  "Store TRANSFORM (a TRANSFORM-STAMPED from its FRAME-ID to its CHILD-FRAME-ID) as the latest
transform of the child frame, replacing any earlier one (also one with another parent). STATIC
marks it as part of the fixed structure, which CLEAR keeps. A transform that would close a loop in
the frame tree signals TF-CONNECTIVITY-ERROR. Returns TRANSFORM."
  (declare (ignore authority))
  (%check-transformer transformer 'set-transform)
  (unless (transform-stamped-p transform)
    (cl-transforms::input-error transform "a TRANSFORM-STAMPED" 'set-transform))
  (let ((parent-name (%frame-name (%ts-frame-id transform) 'set-transform))
        (child-name (%frame-name (%ts-child-frame-id transform) 'set-transform))
        (frames (transformer-frames transformer)))
    (when (string= parent-name child-name)
      (cl-transforms::input-error transform "a transform between two different frames"
                                  'set-transform))
    (sb-thread:with-recursive-lock ((transformer-lock transformer))
      (let ((parent (%intern-frame frames parent-name))
            (child (%intern-frame frames child-name)))
        ;; the new link must not make CHILD an ancestor of itself
        (loop for frame = parent then (tf-frame-parent frame)
              while frame
              when (eq frame child)
                do (error 'tf-connectivity-error
                          :target-frame parent-name :source-frame child-name
                          :description (format nil "setting ~s as the parent of ~s would close ~
                                                    a loop in the frame tree"
                                               parent-name child-name)))
        (setf (tf-frame-parent child) parent
              (tf-frame-transform child) transform
              (tf-frame-static child) (and static t)))
      (when (plusp (transformer-waiters transformer))
        (sb-thread:condition-broadcast (transformer-changed transformer))))
    transform))

(declaim (inline %depth))
(defun %depth (frame)
  "The number of ancestors of FRAME."
  (declare (type tf-frame frame))
  (let ((n 0))
    (declare (type fixnum n))
    (loop for f = (tf-frame-parent frame) then (tf-frame-parent f)
          while f do (incf n))
    n))

(defun %solve (source target)
  "The transform mapping points of the TF-FRAME SOURCE into the TF-FRAME TARGET, composed along
the tree path through their nearest common ancestor, as a TRANSFORM and the oldest stamp of the
non-static links used (0 when there are none); NIL when the frames lie in different trees."
  (declare (type tf-frame source target)
           (optimize (speed 3) (safety 0)))
  (let ((s source) (g target)
        (ds (%depth source)) (dg (%depth target))
        (stamp most-positive-double-float)
        ;; source -> ancestor and target -> ancestor, as translation and quaternion
        (sx 0d0) (sy 0d0) (sz 0d0) (sqx 0d0) (sqy 0d0) (sqz 0d0) (sqw 1d0)
        (gx 0d0) (gy 0d0) (gz 0d0) (gqx 0d0) (gqy 0d0) (gqz 0d0) (gqw 1d0))
    (declare (type fixnum ds dg) (type double-float stamp sx sy sz sqx sqy sqz sqw
                                                     gx gy gz gqx gqy gqz gqw))
    (macrolet ((climb (frame x y z qx qy qz qw)
                 ;; (x y z q) := link(frame) * (x y z q); frame := parent(frame)
                 `(let ((tr (tf-frame-transform ,frame)))
                    (cl-transforms::with-transform-components
                        ((ltx lty ltz lqx lqy lqz lqw) tr)
                      (multiple-value-bind (rx ry rz)
                          (cl-transforms::%rotate-components lqx lqy lqz lqw ,x ,y ,z)
                        (setf ,x (+ rx ltx) ,y (+ ry lty) ,z (+ rz ltz)))
                      (multiple-value-setq (,qx ,qy ,qz ,qw)
                        (cl-transforms::%q*-components lqx lqy lqz lqw ,qx ,qy ,qz ,qw)))
                    (unless (tf-frame-static ,frame)
                      (setf stamp (min stamp (%ts-stamp tr))))
                    (setf ,frame (tf-frame-parent ,frame)))))
      (loop while (> ds dg) do (climb s sx sy sz sqx sqy sqz sqw) (decf ds))
      (loop while (> dg ds) do (climb g gx gy gz gqx gqy gqz gqw) (decf dg))
      (loop until (eq s g)
            do (when (null (tf-frame-parent s))
                 (return-from %solve nil))
               (climb s sx sy sz sqx sqy sqz sqw)
               (climb g gx gy gz gqx gqy gqz gqw))
      ;; target <- source = inverse(ancestor <- target) * (ancestor <- source)
      (multiple-value-bind (rx ry rz)
          (cl-transforms::%rotate-components (- gqx) (- gqy) (- gqz) gqw
                                             (- sx gx) (- sy gy) (- sz gz))
        (multiple-value-bind (qx qy qz qw)
            (cl-transforms::%q*-components (- gqx) (- gqy) (- gqz) gqw sqx sqy sqz sqw)
          (values (cl-transforms::%unit-transform rx ry rz qx qy qz qw)
                  (if (= stamp most-positive-double-float) 0d0 stamp)))))))

(defun %try-lookup (transformer target source)
  "Under the lock: (values transform stamp) mapping SOURCE points into TARGET, or
(values nil error-class description) when the frames are unknown or not connected."
  (let* ((frames (transformer-frames transformer))
         (s (gethash source frames))
         (g (gethash target frames)))
    (cond ((string= target source)
           (values (cl-transforms:make-identity-transform) 0d0))
          ((null s)
           (values nil 'tf-lookup-error (format nil "frame ~s does not exist" source)))
          ((null g)
           (values nil 'tf-lookup-error (format nil "frame ~s does not exist" target)))
          (t
           (multiple-value-bind (tr stamp) (%solve s g)
             (if tr
                 (values tr stamp)
                 (values nil 'tf-connectivity-error
                         "the frames are not connected in the frame tree")))))))

(defun %lookup (transformer target source timeout place)
  "The transform mapping SOURCE points into TARGET, the oldest stamp used and the normalised
target and source names, waiting up to TIMEOUT seconds for the frames to be connected; signals a
TRANSFORM-STAMPED-ERROR otherwise."
  (let* ((target (%frame-name target place))
         (source (%frame-name source place))
         (timeout (%timeout timeout place))
         (lock (transformer-lock transformer))
         (deadline nil))
    (sb-thread:with-recursive-lock (lock)
      (loop
        (multiple-value-bind (result stamp-or-class description)
            (%try-lookup transformer target source)
          (when result
            (return (values result stamp-or-class target source)))
          (unless deadline
            (setf deadline (+ (get-internal-real-time)
                              (round (* timeout internal-time-units-per-second)))))
          (let ((remaining (/ (- deadline (get-internal-real-time))
                              (float internal-time-units-per-second 1d0))))
            (unless (plusp remaining)
              (error stamp-or-class :target-frame target :source-frame source
                                    :description description))
            (incf (transformer-waiters transformer))
            (unwind-protect
                 (bt:condition-wait (transformer-changed transformer) lock :timeout remaining)
              (decf (transformer-waiters transformer)))))))))

(defun lookup-transform (transformer target-frame source-frame &key time timeout)
  "The TRANSFORM-STAMPED from TARGET-FRAME to SOURCE-FRAME: the pose of SOURCE-FRAME in
TARGET-FRAME, which maps points given in SOURCE-FRAME into TARGET-FRAME. The path may go up to the
common ancestor and down again. The latest transforms are used whatever TIME says; a positive TIME
becomes the stamp of the result, otherwise the stamp is the oldest one of the non-static
transforms used. When the frames are unknown or unconnected, waits up to TIMEOUT seconds for them
to appear, then signals TF-LOOKUP-ERROR (unknown frame) or TF-CONNECTIVITY-ERROR (no path) naming
both frames."
  (%check-transformer transformer 'lookup-transform)
  (let ((time (and time (cl-transforms::ensure-double time "LOOKUP-TRANSFORM :time"))))
    (multiple-value-bind (tr stamp target source)
        (%lookup transformer target-frame source-frame timeout 'lookup-transform)
      (cl-transforms::with-transform-components ((tx ty tz qx qy qz qw) tr)
        (%make-raw-transform-stamped target source (if (and time (plusp time)) time stamp)
                                     tx ty tz qx qy qz qw)))))

(defun can-transform (transformer target-frame source-frame &key time timeout)
  "True when LOOKUP-TRANSFORM with the same frames would succeed (waiting up to TIMEOUT)."
  (declare (ignore time))
  (%check-transformer transformer 'can-transform)
  (handler-case (progn (%lookup transformer target-frame source-frame timeout 'can-transform) t)
    (transform-stamped-error () nil)))

(defun wait-for-transform (transformer &key target-frame source-frame time (timeout 1d0))
  "Wait up to TIMEOUT seconds until TARGET-FRAME and SOURCE-FRAME are connected; true if they
are."
  (can-transform transformer target-frame source-frame :time time :timeout timeout))

(defun transform-pose-stamped (transformer &key target-frame pose timeout use-current-ros-time)
  "POSE (a POSE-STAMPED) expressed in TARGET-FRAME, as a POSE-STAMPED with the stamp of POSE.
Errors as for LOOKUP-TRANSFORM. USE-CURRENT-ROS-TIME is accepted for compatibility; the latest
transforms are always used."
  (declare (ignore use-current-ros-time))
  (%check-transformer transformer 'transform-pose-stamped)
  (unless (pose-stamped-p pose)
    (cl-transforms::input-error pose "a POSE-STAMPED as :pose" 'transform-pose-stamped))
  (multiple-value-bind (tr stamp target)
      (%lookup transformer target-frame (%ps-frame-id pose) timeout 'transform-pose-stamped)
    (declare (ignore stamp))
    (let ((result (transform-pose tr pose)))
      (%make-pose-stamped target (%ps-stamp pose) (origin result) (orientation result)))))

(defun transform-point-stamped (transformer &key target-frame point timeout use-current-ros-time)
  "POINT (a POINT-STAMPED) expressed in TARGET-FRAME, as a POINT-STAMPED with the stamp of POINT.
Errors as for LOOKUP-TRANSFORM."
  (declare (ignore use-current-ros-time))
  (%check-transformer transformer 'transform-point-stamped)
  (unless (point-stamped-p point)
    (cl-transforms::input-error point "a POINT-STAMPED as :point" 'transform-point-stamped))
  (multiple-value-bind (tr stamp target)
      (%lookup transformer target-frame (%pts-frame-id point) timeout 'transform-point-stamped)
    (declare (ignore stamp))
    (let ((p (transform-point tr point)))
      (%make-point-stamped target (%pts-stamp point) (x p) (y p) (z p)))))

(defmacro with-transforms-batch ((transformer) &body body)
  "Run BODY, which sets transforms of TRANSFORMER, as one update: a lookup in another thread sees
all of BODY's transforms or none of them. Returns the values of BODY."
  `(sb-thread:with-recursive-lock ((transformer-lock ,transformer))
     ,@body))

(defun frame-exists (transformer frame)
  "True when FRAME has appeared in a transform given to TRANSFORMER."
  (%check-transformer transformer 'frame-exists)
  (let ((name (%frame-name frame 'frame-exists)))
    (sb-thread:with-recursive-lock ((transformer-lock transformer))
      (values (gethash name (transformer-frames transformer))))))

(defun known-frames (transformer)
  "The names of every frame TRANSFORMER knows, sorted."
  (%check-transformer transformer 'known-frames)
  (sb-thread:with-recursive-lock ((transformer-lock transformer))
    (sort (alexandria:hash-table-keys (transformer-frames transformer)) #'string<)))

(defun clear (transformer &key static)
  "Forget every transform that was not set as static (all of them when STATIC is true), and the
frames no remaining transform mentions. Returns TRANSFORMER."
  (%check-transformer transformer 'clear)
  (sb-thread:with-recursive-lock ((transformer-lock transformer))
    (let ((frames (transformer-frames transformer))
          (used (make-hash-table :test 'eq)))
      (loop for frame being the hash-values of frames
            when (and (tf-frame-parent frame) (or static (not (tf-frame-static frame))))
              do (setf (tf-frame-parent frame) nil
                       (tf-frame-transform frame) nil
                       (tf-frame-static frame) nil))
      (loop for frame being the hash-values of frames
            when (tf-frame-parent frame)
              do (setf (gethash frame used) t
                       (gethash (tf-frame-parent frame) used) t))
      (loop for name in (alexandria:hash-table-keys frames)
            unless (gethash (gethash name frames) used)
              do (remhash name frames))))
  transformer)
