;;;; Asynchronous process modules, as CRAM has them: PM-EXECUTE hands a designator to the module
;;;; and returns at once; the module's worker thread calls ON-INPUT for each designator in turn;
;;;; the module reports with FINISH-PROCESS-MODULE or FAIL-PROCESS-MODULE (from any thread),
;;;; and MONITOR-PROCESS-MODULE waits for that, signalling the failures.

(in-package :cram-process-modules)

(defclass asynchronous-process-module ()
  ((name :initarg :name :reader asynchronous-process-module-name
         :documentation "The name (or alias) the module runs under.")
   (queue :initform '() :accessor module-queue :documentation "Designators not yet given to ON-INPUT.")
   (processing :initform '() :accessor module-processing
               :documentation "Designators given to ON-INPUT and not yet finished or failed.")
   (failures :initform '() :accessor module-failures
             :documentation "(condition . designator) of failed designators not yet monitored.")
   (lock :initform (sb-thread:make-mutex :name "asynchronous process module") :reader module-lock)
   (changed :initform (sb-thread:make-waitqueue :name "asynchronous process module")
            :reader module-changed)
   (stopping :initform nil :accessor module-stopping)
   (worker :initform nil :accessor module-worker))
  (:documentation "The base class of the process modules DEF-ASYNCHRONOUS-PROCESS-MODULE
defines: one instance runs (with a worker thread) while WITH-PROCESS-MODULES-RUNNING names it."))

(defmethod print-object ((module asynchronous-process-module) stream)
  (print-unreadable-object (module stream :type t)
    (format stream "~s" (asynchronous-process-module-name module))))

(defgeneric on-input (module designator)
  (:documentation "Called in MODULE's worker thread for each designator given to it, one at a
time; the module later calls FINISH-PROCESS-MODULE or FAIL-PROCESS-MODULE for it. An error
escaping ON-INPUT fails the designator."))

(defgeneric on-cancel (module designator)
  (:documentation "Called for the designators MODULE processes when it is stopped before
finishing them. The default does nothing.")
  (:method ((module asynchronous-process-module) designator)
    (declare (ignore designator))
    nil))

(defgeneric on-run (module)
  (:documentation "Called in MODULE's worker thread when it starts. The default does nothing.")
  (:method ((module asynchronous-process-module)) nil))

(defgeneric synchronization-fluent (module designator)
  (:documentation "A fluent (or a value) that PM-EXECUTE waits to be true before it hands
DESIGNATOR to MODULE, e.g. until another motion is done. The default is T: no waiting.")
  (:method ((module asynchronous-process-module) designator)
    (declare (ignore designator))
    t))

(defclass asynchronous-module-definition (process-module)
  ((instance-class :initarg :instance-class :reader instance-class))
  (:documentation "The registered process module of an asynchronous module class."))

(defvar *asynchronous-modules* '()
  "Alist (name-or-alias . running ASYNCHRONOUS-PROCESS-MODULE instance).")

(pushnew '*asynchronous-modules* cpl:*inherited-specials*)

(defun running-module (module function)
  "MODULE (an instance, or the name or alias of a running asynchronous module) as an instance."
  (cond ((typep module 'asynchronous-process-module) module)
        ((cdr (assoc module *asynchronous-modules*)))
        (t (error 'process-module-error
                  :name module
                  :reason (format nil "~s: it is not a running asynchronous process module."
                                  function)))))

(defun notify (module)
  (sb-thread:condition-broadcast (module-changed module)))

(defun worker-loop (module)
  (on-run module)
  (loop
    (let ((designator
            (sb-thread:with-mutex ((module-lock module))
              (loop until (or (module-stopping module) (module-queue module))
                    do (sb-thread:condition-wait (module-changed module) (module-lock module)))
              (when (module-stopping module) (return))
              (let ((next (pop (module-queue module))))
                (push next (module-processing module))
                (notify module)
                next))))
      (handler-case (on-input module designator)
        (serious-condition (e) (fail-process-module module e :designator designator))))))

(defmethod call-with-process-module-running ((definition asynchronous-module-definition)
                                             alias thunk)
  (let* ((module (make-instance (instance-class definition) :name alias))
         (*asynchronous-modules* (acons alias module *asynchronous-modules*))
         (bindings (mapcar (lambda (s) (cons s (symbol-value s)))
                           (remove-if-not #'boundp cpl:*inherited-specials*))))
    (setf (module-worker module)
          (sb-thread:make-thread
           (lambda ()
             (progv (mapcar #'car bindings) (mapcar #'cdr bindings)
               (worker-loop module)))
           :name (format nil "process module ~(~a~)" alias)))
    (unwind-protect (funcall thunk)
      (let ((left (sb-thread:with-mutex ((module-lock module))
                    (setf (module-stopping module) t)
                    (notify module)
                    (module-processing module))))
        (dolist (designator left) (ignore-errors (on-cancel module designator)))
        (sb-thread:join-thread (module-worker module) :default nil)))))

(defmacro def-asynchronous-process-module (name direct-slots &rest options)
  "Define the class NAME of an asynchronous process module (a subclass of
ASYNCHRONOUS-PROCESS-MODULE with DIRECT-SLOTS and the DEFCLASS OPTIONS) and register it as the
process module NAME. Define ON-INPUT (and maybe ON-RUN, ON-CANCEL, SYNCHRONIZATION-FLUENT) for
it; PM-EXECUTE of it returns as soon as the designator is handed over."
  (check-type name (and symbol (not null)))
  `(progn
     (defclass ,name (asynchronous-process-module) ,direct-slots ,@options)
     (setf (gethash ',name *process-modules*)
           (make-instance 'asynchronous-module-definition
                          :name ',name :instance-class ',name
                          :function (lambda (designator)
                                      (submit-input (running-module *executing-process-module*
                                                                    'pm-execute)
                                                    designator))))
     ',name))

(defun submit-input (module designator)
  "Hand DESIGNATOR to MODULE once its synchronization fluent is true; return DESIGNATOR."
  (cpl:wait-for (synchronization-fluent module designator))
  (sb-thread:with-mutex ((module-lock module))
    (setf (module-queue module) (append (module-queue module) (list designator)))
    (notify module))
  designator)

(defun finish-process-module (module &key designator)
  "Report that MODULE (an instance, or the name of a running asynchronous module) finished
DESIGNATOR, or, without it, everything it was processing."
  (let ((module (running-module module 'finish-process-module)))
    (sb-thread:with-mutex ((module-lock module))
      (when (and designator (not (member designator (module-processing module))))
        (error 'process-module-error
               :name (asynchronous-process-module-name module)
               :reason (format nil "FINISH-PROCESS-MODULE: ~s is not being processed." designator)))
      (setf (module-processing module)
            (if designator (remove designator (module-processing module)) '()))
      (notify module))
    module))

(defun fail-process-module (module error &key designator)
  "Report that MODULE failed with ERROR (a condition) on DESIGNATOR, or, without it, on
everything it was processing; MONITOR-PROCESS-MODULE signals ERROR."
  (unless (typep error 'condition)
    (error "FAIL-PROCESS-MODULE: ~s is not a condition." error))
  (let ((module (running-module module 'fail-process-module)))
    (sb-thread:with-mutex ((module-lock module))
      (let ((failed (if designator (list designator) (module-processing module))))
        (setf (module-processing module)
              (set-difference (module-processing module) failed)
              (module-failures module)
              (append (module-failures module)
                      (mapcar (lambda (d) (cons error d)) (or failed (list nil))))))
      (notify module))
    module))

(defun monitor-process-module (module &key designators)
  "Wait until MODULE (an instance, or the name of a running asynchronous module) has finished
DESIGNATORS (a designator or a list; all it was given when NIL) and return; a failure reported
for one of them is signalled here (a plan failure with CPL:FAIL)."
  (let ((module (running-module module 'monitor-process-module))
        (designators (if (listp designators) designators (list designators))))
    (flet ((pending-p (d) (or (member d (module-queue module))
                              (member d (module-processing module)))))
      (let ((failure
              (sb-thread:with-mutex ((module-lock module))
                (loop
                  (let ((failure (find-if (lambda (f) (or (null designators)
                                                          (member (cdr f) designators)))
                                          (module-failures module))))
                    (when failure
                      (setf (module-failures module) (remove failure (module-failures module)))
                      (return failure))
                    (when (if designators
                              (notany #'pending-p designators)
                              (and (null (module-queue module)) (null (module-processing module))))
                      (return nil))
                    (sb-thread:condition-wait (module-changed module) (module-lock module)))))))
        (when failure
          (if (typep (car failure) 'cpl:plan-failure)
              (cpl:fail (car failure))
              (error (car failure))))
        t))))

(setf (documentation 'asynchronous-process-module-name 'function)
      "The name (or alias) a running asynchronous process module runs under.")
