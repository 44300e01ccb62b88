;;;; Projection clocks, as CRAM's CRAM-PROJECTION has them: a LINEAR-CLOCK adds up every wait; a
;;;; PARTIALLY-ORDERED-CLOCK lets waits of parallel tasks overlap, advancing its time to the
;;;; earliest end of the waits pending; and special projection variables that every projection
;;;; environment binds afresh.

(in-package :cram-projection)

(defgeneric clock-time (clock)
  (:documentation "The current time of CLOCK, in seconds.")
  (:method ((clock t))
    (error "CLOCK-TIME: ~s is not a clock (e.g. a LINEAR-CLOCK or PARTIALLY-ORDERED-CLOCK)."
           clock)))

(defgeneric clock-wait (clock duration)
  (:documentation "Wait DURATION seconds of CLOCK: afterwards CLOCK-TIME is at least DURATION
more than before.")
  (:method ((clock t) duration)
    (declare (ignore duration))
    (error "CLOCK-WAIT: ~s is not a clock (e.g. a LINEAR-CLOCK or PARTIALLY-ORDERED-CLOCK)."
           clock)))

(defun check-duration (duration function)
  (unless (and (realp duration) (>= duration 0) (< duration most-positive-fixnum))
    (error "~s: the duration ~s is not a non-negative number of seconds." function duration)))

(defclass linear-clock ()
  ((time :initarg :initial-time :initform 0 :reader clock-time)
   (lock :initform (sb-thread:make-mutex :name "linear clock") :reader clock-lock))
  (:documentation "A clock whose waits return at once and add their durations to its time:
waits of parallel tasks add up."))

(defmethod clock-wait ((clock linear-clock) duration)
  (check-duration duration 'clock-wait)
  (sb-thread:with-mutex ((clock-lock clock))
    (incf (slot-value clock 'time) duration)))

(defclass partially-ordered-clock ()
  ((time :initarg :initial-time :initform 0 :reader clock-time)
   (increment-delay :initarg :increment-delay :initform 0.05 :reader increment-delay
                    :documentation "Real seconds the clock waits before each step of its time,
so that the waits of tasks running in parallel are all pending when it steps.")
   (waits :initform '() :accessor clock-waits :documentation "(id . end-time) of pending waits.")
   (disablers :initform 0 :accessor clock-disablers)
   (lock :initform (sb-thread:make-mutex :name "partially ordered clock") :reader clock-lock)
   (changed :initform (sb-thread:make-waitqueue) :reader clock-changed))
  (:documentation "A clock whose time jumps to the earliest end of the waits pending: waits of
tasks running in parallel overlap, as they would in real time. It does not step while a
WITH-PARTIALLY-ORDERED-CLOCK-DISABLED form runs."))

(defgeneric partially-ordered-clock-enabled (clock)
  (:documentation "True when CLOCK may step (no WITH-PARTIALLY-ORDERED-CLOCK-DISABLED runs).")
  (:method ((clock partially-ordered-clock))
    (sb-thread:with-mutex ((clock-lock clock))
      (zerop (clock-disablers clock)))))

(defun call-with-clock-disabled (clock thunk)
  (unless (typep clock 'partially-ordered-clock)
    (error "WITH-PARTIALLY-ORDERED-CLOCK-DISABLED: ~s is not a partially ordered clock." clock))
  (sb-thread:with-mutex ((clock-lock clock)) (incf (clock-disablers clock)))
  (unwind-protect (funcall thunk)
    (sb-thread:with-mutex ((clock-lock clock))
      (decf (clock-disablers clock))
      (sb-thread:condition-broadcast (clock-changed clock)))))

(defmacro with-partially-ordered-clock-disabled (clock &body body)
  "Run BODY while CLOCK (a PARTIALLY-ORDERED-CLOCK) does not step."
  `(call-with-clock-disabled ,clock (lambda () ,@body)))

(defmethod clock-wait ((clock partially-ordered-clock) duration)
  (check-duration duration 'clock-wait)
  (let ((id (list 'wait)) (lock (clock-lock clock)))
    (sb-thread:with-mutex (lock)
      (push (cons id (+ (clock-time clock) duration)) (clock-waits clock)))
    (unwind-protect
         ;; a wait of the plan: under ordered starts the siblings of this task may start
         ;; (and register their waits) meanwhile
         (cpl:with-task-waiting (clock)
          (loop
           (when (sb-thread:with-mutex (lock)
                   (<= (cdr (assoc id (clock-waits clock))) (clock-time clock)))
             (return))
           ;; let the other tasks register their waits, then step
           (sleep (increment-delay clock))
           (sb-thread:with-mutex (lock)
             (loop until (zerop (clock-disablers clock))
                   do (sb-thread:condition-wait (clock-changed clock) lock))
             ;; step to the earliest end of the pending waits, but only once every wait that
             ;; has ended has left: it ends at the time it asked for
             (let ((now (clock-time clock)))
               (unless (find-if (lambda (end) (<= end now)) (clock-waits clock) :key #'cdr)
                 (let ((next (loop for (nil . end) in (clock-waits clock) minimize end)))
                   (when (> next now)
                     (setf (slot-value clock 'time) next))))))))
      (sb-thread:with-mutex (lock)
        (setf (clock-waits clock) (remove id (clock-waits clock) :key #'car))))
    (clock-time clock)))

;;; Special projection variables

(defvar *special-projection-variables* '()
  "Alist (variable . function returning its value) of DEFINE-SPECIAL-PROJECTION-VARIABLE.")

(defmacro define-special-projection-variable (name value)
  "Make every WITH-PROJECTION-ENVIRONMENT bind the special variable NAME to a fresh value of the
form VALUE (evaluated when the environment is entered), also in the plan tasks it starts."
  (check-type name (and symbol (not null)))
  `(progn
     (pushnew ',name cpl:*inherited-specials*)
     (setf *special-projection-variables*
           (acons ',name (lambda () ,value)
                  (remove ',name *special-projection-variables* :key #'car)))
     ',name))

(defun call-with-special-projection-variables (thunk)
  (progv (mapcar #'car *special-projection-variables*)
      (mapcar (lambda (entry) (funcall (cdr entry))) *special-projection-variables*)
    (funcall thunk)))
