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
           :documentation "Frame name -> TF-FRAME, for every frame seen as parent or child.")
   (name-cache :initform (make-array 16 :initial-element 0) :reader transformer-name-cache
               :type simple-vector
               :documentation "Pairs (name . TF-FRAME) of recently used frames whose name is
the very string object of the frame's key in FRAMES, found by EQ without hashing the name.")
   (name-cache-next :initform 0 :type fixnum :accessor transformer-name-cache-next)
   (deferred :initform nil :accessor transformer-deferred
             :documentation "NIL, or a function of no arguments that sets transforms of the
transformer: an update DEFER-UPDATE put off until the transformer is next read or written."))
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

(defun %frame-name-slow (frame place)
  "FRAME as a normalised, non-empty frame name."
  (let ((name (normalize-frame-name frame place)))
    (when (zerop (length name))
      (cl-transforms::input-error frame "a non-empty frame name" place))
    name))

(declaim (inline %frame-name))
(defun %frame-name (frame place)
  "FRAME as a normalised, non-empty frame name: FRAME itself when it is a simple string that
needs no normalisation (the common case), otherwise as NORMALIZE-FRAME-NAME makes it."
  (if (and (simple-string-p frame) (plusp (length frame)) (char/= (schar frame 0) #\/))
      frame
      (%frame-name-slow frame place)))

(defmacro %with-transformer-lock ((transformer) &body body)
  "Run BODY holding the lock of TRANSFORMER; returns its values. Uncontended, the lock is taken
with interrupts deferred around BODY (which must be short and must not wait or signal): that
costs a third of WITH-RECURSIVE-LOCK. A thread that already holds the lock (inside
WITH-TRANSFORMS-BATCH) runs BODY directly; a contended lock is waited for as
WITH-RECURSIVE-LOCK does."
  (let ((lock (gensym "LOCK")) (fn (gensym "BODY")))
    `(let ((,lock (transformer-lock ,transformer)))
       (flet ((,fn () ,@body))
         (declare (dynamic-extent #',fn))
         (if (sb-thread:holding-mutex-p ,lock)
             (,fn)
             (block locked
               (sb-sys:without-interrupts
                 (when (sb-thread:grab-mutex ,lock :waitp nil)
                   (return-from locked
                     (unwind-protect (,fn) (sb-thread:release-mutex ,lock)))))
               (sb-thread:with-recursive-lock (,lock) (,fn))))))))

(defun %run-deferred (transformer)
  "Run the update deferred in TRANSFORMER, if any, holding its lock (lookups in other threads
see all of it or none)."
  (sb-thread:with-recursive-lock ((transformer-lock transformer))
    (let ((update (transformer-deferred transformer)))
      (when update
        (setf (transformer-deferred transformer) nil)
        (funcall update)))))

(declaim (inline %settle))
(defun %settle (transformer)
  "Before TRANSFORMER is read or written: run the update deferred in it, if any."
  (when (transformer-deferred transformer)
    (%run-deferred transformer)))

(defun defer-update (transformer update)
  "Put off UPDATE, a function of no arguments that sets transforms of TRANSFORMER, until
TRANSFORMER is next read or written (a lookup, SET-TRANSFORM, FRAME-EXISTS, KNOWN-FRAMES,
CLEAR): every reader sees its transforms as though it had run now, and an update nobody reads
costs nothing. UPDATE replaces an update deferred before that has not run yet, so it must write
what that one would have written too. Runs UPDATE at once when a lookup is waiting for a
change. Returns TRANSFORMER."
  (%check-transformer transformer 'defer-update)
  (unless (functionp update)
    (cl-transforms::input-error update "a function of no arguments" 'defer-update))
  (sb-thread:with-recursive-lock ((transformer-lock transformer))
    (setf (transformer-deferred transformer) update)
    (when (plusp (transformer-waiters transformer))
      (%run-deferred transformer)))
  transformer)

(defun %timeout (timeout place)
  "TIMEOUT in seconds as a non-negative double float; NIL means 0."
  (if timeout
      (let ((d (cl-transforms::ensure-double timeout place)))
        (when (minusp d) (cl-transforms::input-error timeout "a non-negative timeout" place))
        d)
      0d0))

(defun %find-frame (transformer name)
  "Under the lock: the TF-FRAME of TRANSFORMER called NAME (a normalised frame name), or NIL.
A NAME that is the string object of a frame's own name (its key) is found by EQ in a small
cache, without hashing; the other names through the table."
  (declare (optimize (speed 3) (safety 0)))
  (let ((cache (transformer-name-cache transformer)))
    (declare (type (simple-vector 16) cache))
    (loop for i of-type fixnum from 0 below 16 by 2
          when (eq (svref cache i) name)
            do (return-from %find-frame (svref cache (1+ i))))
    (let ((frame (gethash name (transformer-frames transformer))))
      (when (and frame (eq (tf-frame-name frame) name))
        (let ((i (transformer-name-cache-next transformer)))
          (declare (type fixnum i))
          (setf (svref cache (1+ i)) frame
                (svref cache i) name
                (transformer-name-cache-next transformer) (logand (+ i 2) 15))))
      frame)))

(defun %flush-name-cache (transformer)
  "Under the lock: forget every cached frame (after frames were removed)."
  (fill (transformer-name-cache transformer) 0))

(defun %intern-frame (transformer name)
  "The TF-FRAME of TRANSFORMER called NAME, created when new."
  (or (%find-frame transformer name)
      (setf (gethash name (transformer-frames transformer)) (make-tf-frame name))))

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
        (static (and static t)))
    (declare (type simple-string parent-name child-name))
    (when (and (= (length parent-name) (length child-name)) (string= parent-name child-name))
      (cl-transforms::input-error transform "a transform between two different frames"
                                  'set-transform))
    (%settle transformer)
    (unless (%with-transformer-lock (transformer)
              (let ((parent (%intern-frame transformer parent-name))
                    (child (%intern-frame transformer child-name)))
                ;; the new link must not make CHILD an ancestor of itself
                (when (loop for frame = parent then (tf-frame-parent frame)
                            while frame
                            never (eq frame child))
                  (setf (tf-frame-parent child) parent
                        (tf-frame-transform child) transform
                        (tf-frame-static child) static)
                  (when (plusp (transformer-waiters transformer))
                    (sb-thread:condition-broadcast (transformer-changed transformer)))
                  t)))
      (error 'tf-connectivity-error
             :target-frame parent-name :source-frame child-name
             :description (format nil "setting ~s as the parent of ~s would close ~
                                       a loop in the frame tree"
                                  parent-name child-name)))
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

;;; A lookup writes its result into a scratch buffer of double floats on the caller's stack: the
;;; translation and rotation of the transform (x y z qx qy qz qw) at 0..6 and the stamp at 7;
;;; 8..15 hold the target side's accumulators while the path is composed.

(deftype %lookup-buffer () '(simple-array double-float (16)))

(defmacro %with-lookup-buffer ((var) &body body)
  "Bind VAR to a fresh %LOOKUP-BUFFER allocated on the stack around BODY."
  `(let ((,var (make-array 16 :element-type 'double-float)))
     (declare (dynamic-extent ,var))
     ,@body))

(defun %climb (frame steps buffer base)
  "Compose the links of STEPS frames up from the TF-FRAME FRAME onto the accumulated transform
at BASE of BUFFER (x y z qx qy qz qw, then the oldest stamp of the non-static links):
accumulated := link(frame) * accumulated, frame := parent(frame), STEPS times."
  (declare (type tf-frame frame) (type fixnum steps base) (type %lookup-buffer buffer)
           (optimize (speed 3) (safety 0) (debug 0)))
  (let ((x (aref buffer base)) (y (aref buffer (+ base 1))) (z (aref buffer (+ base 2)))
        (qx (aref buffer (+ base 3))) (qy (aref buffer (+ base 4)))
        (qz (aref buffer (+ base 5))) (qw (aref buffer (+ base 6)))
        (stamp (aref buffer (+ base 7))))
    (declare (type double-float x y z qx qy qz qw stamp))
    (loop repeat steps
          do (let ((tr (tf-frame-transform frame)))
               (cl-transforms::with-transform-components ((ltx lty ltz lqx lqy lqz lqw) tr)
                 (multiple-value-bind (rx ry rz)
                     (cl-transforms::%rotate-components lqx lqy lqz lqw x y z)
                   (setf x (+ rx ltx) y (+ ry lty) z (+ rz ltz)))
                 (multiple-value-setq (qx qy qz qw)
                   (cl-transforms::%q*-components lqx lqy lqz lqw qx qy qz qw)))
               (unless (tf-frame-static frame)
                 (setf stamp (min stamp (%ts-stamp tr))))
               (setf frame (tf-frame-parent frame))))
    (setf (aref buffer base) x (aref buffer (+ base 1)) y (aref buffer (+ base 2)) z
          (aref buffer (+ base 3)) qx (aref buffer (+ base 4)) qy
          (aref buffer (+ base 5)) qz (aref buffer (+ base 6)) qw
          (aref buffer (+ base 7)) stamp)
    nil))

(declaim (inline %identity-into))
(defun %identity-into (buffer base)
  "Store the identity transform and the stamp most-positive-double-float at BASE of BUFFER."
  (declare (type %lookup-buffer buffer) (type fixnum base))
  (setf (aref buffer base) 0d0 (aref buffer (+ base 1)) 0d0 (aref buffer (+ base 2)) 0d0
        (aref buffer (+ base 3)) 0d0 (aref buffer (+ base 4)) 0d0 (aref buffer (+ base 5)) 0d0
        (aref buffer (+ base 6)) 1d0 (aref buffer (+ base 7)) most-positive-double-float))

(defun %solve (source target buffer)
  "Store into BUFFER the transform mapping points of the TF-FRAME SOURCE into the TF-FRAME
TARGET, composed along the tree path through their nearest common ancestor (the quaternion not
yet renormalised), and the oldest stamp of the non-static links used (0 when there are none).
True on success; NIL when the frames lie in different trees."
  (declare (type tf-frame source target) (type %lookup-buffer buffer)
           (optimize (speed 3) (safety 0)))
  (let ((ds (%depth source)) (dg (%depth target)) (a source) (b target))
    (declare (type fixnum ds dg))
    ;; the nearest common ancestor, and how many links lie on each side of it
    (let ((da ds) (db dg))
      (declare (type fixnum da db))
      (loop while (> da db) do (setf a (tf-frame-parent a)) (decf da))
      (loop while (> db da) do (setf b (tf-frame-parent b)) (decf db))
      (loop until (eq a b)
            do (when (null (tf-frame-parent a))
                 (return-from %solve nil))
               (setf a (tf-frame-parent a) b (tf-frame-parent b))
               (decf da))
      ;; source -> ancestor at 0, target -> ancestor at 8
      (%identity-into buffer 0)
      (%identity-into buffer 8)
      (%climb source (- ds da) buffer 0)
      (%climb target (- dg da) buffer 8))
    ;; target <- source = inverse(ancestor <- target) * (ancestor <- source)
    (let ((sx (aref buffer 0)) (sy (aref buffer 1)) (sz (aref buffer 2))
          (sqx (aref buffer 3)) (sqy (aref buffer 4)) (sqz (aref buffer 5)) (sqw (aref buffer 6))
          (gx (aref buffer 8)) (gy (aref buffer 9)) (gz (aref buffer 10))
          (gqx (aref buffer 11)) (gqy (aref buffer 12)) (gqz (aref buffer 13))
          (gqw (aref buffer 14))
          (stamp (min (aref buffer 7) (aref buffer 15))))
      (multiple-value-bind (rx ry rz)
          (cl-transforms::%rotate-components (- gqx) (- gqy) (- gqz) gqw
                                             (- sx gx) (- sy gy) (- sz gz))
        (multiple-value-bind (qx qy qz qw)
            (cl-transforms::%q*-components (- gqx) (- gqy) (- gqz) gqw sqx sqy sqz sqw)
          (setf (aref buffer 0) rx (aref buffer 1) ry (aref buffer 2) rz
                (aref buffer 3) qx (aref buffer 4) qy (aref buffer 5) qz (aref buffer 6) qw
                (aref buffer 7) (if (= stamp most-positive-double-float) 0d0 stamp))
          t)))))

(defun %try-lookup (transformer target source buffer)
  "Under the lock: true when the transform mapping SOURCE points into TARGET and its stamp are
now in BUFFER; otherwise (values nil error-class description) when the frames are unknown or not
connected."
  (let ((s (%find-frame transformer source))
        (g (%find-frame transformer target)))
    (cond ((if (and s g) (eq s g) (string= target source))
           (%identity-into buffer 0)
           (setf (aref buffer 7) 0d0)
           t)
          ((null s)
           (values nil 'tf-lookup-error (format nil "frame ~s does not exist" source)))
          ((null g)
           (values nil 'tf-lookup-error (format nil "frame ~s does not exist" target)))
          ((%solve s g buffer) t)
          (t
           (values nil 'tf-connectivity-error
                   "the frames are not connected in the frame tree")))))

(defun %wait-and-lookup (transformer target source timeout buffer)
  "Wait up to TIMEOUT seconds for %TRY-LOOKUP of TARGET and SOURCE to succeed: true then, else
(values nil error-class description)."
  (let ((lock (transformer-lock transformer))
        (deadline (+ (get-internal-real-time)
                     (round (* timeout internal-time-units-per-second)))))
    (sb-thread:with-recursive-lock (lock)
      (loop
        (multiple-value-bind (ok class description)
            (%try-lookup transformer target source buffer)
          (when ok
            (return t))
          (let ((remaining (/ (- deadline (get-internal-real-time))
                              (float internal-time-units-per-second 1d0))))
            (unless (plusp remaining)
              (return (values nil class description)))
            (incf (transformer-waiters transformer))
            (unwind-protect
                 (bt:condition-wait (transformer-changed transformer) lock :timeout remaining)
              (decf (transformer-waiters transformer)))))))))

(defun %lookup (transformer target source timeout place buffer)
  "Store the transform mapping SOURCE points into TARGET and the oldest stamp used into
BUFFER (see %SOLVE), waiting up to TIMEOUT seconds for the frames to be connected, and return
the normalised target and source names; signals a TRANSFORM-STAMPED-ERROR otherwise."
  (let* ((target (%frame-name target place))
         (source (%frame-name source place))
         (timeout (%timeout timeout place)))
    (%settle transformer)
    (multiple-value-bind (ok class description)
        (%with-transformer-lock (transformer) (%try-lookup transformer target source buffer))
      (unless ok
        (if (plusp timeout)
            (multiple-value-setq (ok class description)
              (%wait-and-lookup transformer target source timeout buffer))
            (setf ok nil)))
      (unless ok
        (error class :target-frame target :source-frame source :description description))
      (values target source))))

(defmacro %with-buffer-transform (((tx ty tz qx qy qz qw) buffer) &body body)
  "Bind TX .. QW to the transform in BUFFER, its quaternion scaled to unit norm as
CL-TRANSFORMS::%UNIT-TRANSFORM does, around BODY."
  (let ((b (gensym "BUFFER")) (s (gensym "S")))
    `(let* ((,b ,buffer)
            (,tx (aref ,b 0)) (,ty (aref ,b 1)) (,tz (aref ,b 2))
            (,qx (aref ,b 3)) (,qy (aref ,b 4)) (,qz (aref ,b 5)) (,qw (aref ,b 6)))
       (declare (type %lookup-buffer ,b) (type double-float ,tx ,ty ,tz ,qx ,qy ,qz ,qw))
       (unless (cl-transforms::%unit-norm-p ,qx ,qy ,qz ,qw)
         (let ((,s (cl-transforms::%unit-scale ,qx ,qy ,qz ,qw nil)))
           (declare (type double-float ,s))
           (setf ,qx (* ,qx ,s) ,qy (* ,qy ,s) ,qz (* ,qz ,s) ,qw (* ,qw ,s))))
       ,@body)))

(defun %buffer-transform (buffer)
  "The TRANSFORM in BUFFER."
  (%with-buffer-transform ((tx ty tz qx qy qz qw) buffer)
    (cl-transforms::%make-raw-transform tx ty tz qx qy qz qw)))

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
    (%with-lookup-buffer (buffer)
      (multiple-value-bind (target source)
          (%lookup transformer target-frame source-frame timeout 'lookup-transform buffer)
        (%with-buffer-transform ((tx ty tz qx qy qz qw) buffer)
          (%make-raw-transform-stamped target source
                                       (if (and time (plusp time)) time (aref buffer 7))
                                       tx ty tz qx qy qz qw))))))

(defun can-transform (transformer target-frame source-frame &key time timeout)
  "True when LOOKUP-TRANSFORM with the same frames would succeed (waiting up to TIMEOUT)."
  (declare (ignore time))
  (%check-transformer transformer 'can-transform)
  (%with-lookup-buffer (buffer)
    (handler-case (progn (%lookup transformer target-frame source-frame timeout 'can-transform
                                  buffer)
                         t)
      (transform-stamped-error () nil))))

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
  (%with-lookup-buffer (buffer)
    (let* ((target (%lookup transformer target-frame (%ps-frame-id pose) timeout
                            'transform-pose-stamped buffer))
           (result (transform-pose (%buffer-transform buffer) pose)))
      (%make-pose-stamped target (%ps-stamp pose) (origin result) (orientation result)))))

(defun transform-point-stamped (transformer &key target-frame point timeout use-current-ros-time)
  "POINT (a POINT-STAMPED) expressed in TARGET-FRAME, as a POINT-STAMPED with the stamp of POINT.
Errors as for LOOKUP-TRANSFORM."
  (declare (ignore use-current-ros-time))
  (%check-transformer transformer 'transform-point-stamped)
  (unless (point-stamped-p point)
    (cl-transforms::input-error point "a POINT-STAMPED as :point" 'transform-point-stamped))
  (%with-lookup-buffer (buffer)
    (let* ((target (%lookup transformer target-frame (%pts-frame-id point) timeout
                            'transform-point-stamped buffer))
           (p (transform-point (%buffer-transform buffer) point)))
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
    (%settle transformer)
    (sb-thread:with-recursive-lock ((transformer-lock transformer))
      (values (gethash name (transformer-frames transformer))))))

(defun known-frames (transformer)
  "The names of every frame TRANSFORMER knows, sorted."
  (%check-transformer transformer 'known-frames)
  (%settle transformer)
  (sb-thread:with-recursive-lock ((transformer-lock transformer))
    (sort (alexandria:hash-table-keys (transformer-frames transformer)) #'string<)))

(defun clear (transformer &key static)
  "Forget every transform that was not set as static (all of them when STATIC is true), and the
frames no remaining transform mentions. Returns TRANSFORMER."
  (%check-transformer transformer 'clear)
  (%settle transformer)
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
              do (remhash name frames))
      (%flush-name-cache transformer)))
  transformer)
