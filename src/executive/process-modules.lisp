;;;; Process modules: named executors of motion designators. A module runs a designator in the
;;;; calling thread (so it sees the caller's dynamic environment), one designator at a time per
;;;; module; WITH-PROCESS-MODULES-RUNNING decides which modules are available.

(in-package :cram-process-modules)

(defclass process-module ()
  ((name :initarg :name :reader process-module-name)
   (function :initarg :function :reader process-module-function)
   (documentation :initarg :documentation :initform nil)
   (lock :initform (sb-thread:make-mutex :name "process module")
         :reader process-module-lock))
  (:documentation "A named executor of motion designators, defined with DEF-PROCESS-MODULE."))

(setf (documentation 'process-module-name 'function) "The symbol naming a process module.")

(defmethod print-object ((module process-module) stream)
  (print-unreadable-object (module stream :type t)
    (format stream "~s" (process-module-name module))))

(defvar *process-modules* (make-hash-table :test 'eq)
  "All defined process modules by name.")

(defvar *running-process-modules* '()
  "The names of the process modules available in the current dynamic context.")

(pushnew '*running-process-modules* cpl:*inherited-specials*)

(define-condition process-module-error (error)
  ((name :initarg :name :reader process-module-error-name)
   (reason :initarg :reason :reader process-module-error-reason))
  (:report (lambda (condition stream)
             (format stream "Process module ~s: ~a" (process-module-error-name condition)
                     (process-module-error-reason condition))))
  (:documentation "Signalled for an unknown or not running process module."))

(setf (documentation 'process-module-error-name 'function)
      "The process module name a PROCESS-MODULE-ERROR is about.")

(define-condition no-matching-process-module (cpl:simple-plan-failure)
  ((designator :initarg :designator :reader no-matching-process-module-designator))
  (:report (lambda (condition stream)
             (let ((*print-length* 20) (*print-level* 6))
               (format stream "No matching process module found for ~s~%~
                               Running process modules: ~:[none~;~:*~{~(~a~)~^, ~}~]. Run ~
                               the plan inside a projection environment (for example ~
                               URDF-PROJ:WITH-SIMULATED-ROBOT) or WITH-PROCESS-MODULES-RUNNING, ~
                               and check the MATCHING-PROCESS-MODULE rules for its type."
                       (no-matching-process-module-designator condition)
                       *running-process-modules*))))
  (:documentation "The plan failure of performing a motion designator that no running process
module matches."))

(setf (documentation 'no-matching-process-module-designator 'function)
      "The motion designator no running process module matched.")

(defun find-process-module (name &optional (errorp t))
  "The process module named NAME; with ERRORP an unknown NAME signals a PROCESS-MODULE-ERROR."
  (or (gethash name *process-modules*)
      (and errorp
           (error 'process-module-error
                  :name name
                  :reason (format nil "no such process module; defined ones: ~{~(~a~)~^, ~}."
                                  (process-module-names))))))

(defun process-module-names ()
  "The names of all defined process modules, sorted."
  (sort (loop for name being the hash-keys of *process-modules* collect name)
        #'string< :key #'symbol-name))

(defmacro def-process-module (name (designator-variable) &body body)
  "Define (or redefine) the process module NAME. When a motion designator is executed by it,
BODY runs with DESIGNATOR-VARIABLE bound to the designator and its value is the result. A
leading docstring in BODY documents the module."
  (check-type name (and symbol (not null)))
  (check-type designator-variable (and symbol (not null)))
  (let ((documentation (and (stringp (first body)) (rest body) (first body))))
    `(progn
       (setf (gethash ',name *process-modules*)
             (make-instance 'process-module
                            :name ',name
                            :documentation ,documentation
                            :function (lambda (,designator-variable)
                                        ,@(if documentation (rest body) body))))
       ',name)))

(defun running-process-modules ()
  "The names of the process modules running in the current dynamic context."
  *running-process-modules*)

(defun process-module-running-p (name)
  "True when the process module NAME is running in the current dynamic context."
  (and (member name *running-process-modules*) t))

(defvar *process-module-aliases* '()
  "Alist (alias . process-module-name) of the aliases WITH-PROCESS-MODULES-RUNNING gave.")

(pushnew '*process-module-aliases* cpl:*inherited-specials*)

(defun resolve-process-module-name (name)
  "The process module NAME stands for: itself, or the module it is an alias of."
  (or (cdr (assoc name *process-module-aliases*)) name))

(defgeneric call-with-process-module-running (module alias thunk)
  (:documentation "Call THUNK while MODULE runs under the name ALIAS. Modules with a life of
their own (asynchronous ones) start and stop around THUNK.")
  (:method ((module process-module) alias thunk)
    (declare (ignore alias))
    (funcall thunk)))

(defun call-with-process-modules-running (entries thunk)
  (let ((names '()) (aliases '()))
    (dolist (entry entries)
      (multiple-value-bind (alias name)
          (cond ((and entry (symbolp entry)) (values entry entry))
                ((and (consp entry) (= (length entry) 2) (every #'symbolp entry)
                      (first entry) (second entry))
                 (values (first entry) (second entry)))
                (t (error "WITH-PROCESS-MODULES-RUNNING: expected process module names or ~
                           (alias name) lists, got ~s." entry)))
        (find-process-module name)
        (push alias names)
        (unless (eq alias name) (push (cons alias name) aliases))))
    (let ((*running-process-modules* (union (reverse names) *running-process-modules*))
          (*process-module-aliases* (append aliases *process-module-aliases*)))
      (labels ((run (names)
                 (if (null names)
                     (funcall thunk)
                     (call-with-process-module-running
                      (find-process-module (resolve-process-module-name (first names)))
                      (first names)
                      (lambda () (run (rest names)))))))
        (run (reverse names))))))

(defmacro with-process-modules-running ((&rest module-names) &body body)
  "Run BODY with the process modules MODULE-NAMES (unquoted symbols, or (alias name) lists as
in CRAM, the module then known by the alias) available to PM-EXECUTE and PERFORM, in this
thread and in the plan tasks it starts. Unknown names signal a PROCESS-MODULE-ERROR before
BODY runs."
  `(call-with-process-modules-running ',module-names (lambda () ,@body)))

(defvar *executing-process-module* nil
  "The name (or alias) under which PM-EXECUTE calls the running process module.")

(defun pm-execute (name designator)
  "Execute DESIGNATOR with the running process module NAME and return its result. Calls to
the same module are serialised."
  (let ((module (find-process-module (resolve-process-module-name name))))
    (unless (process-module-running-p name)
      (error 'process-module-error
             :name name
             :reason (format nil "it is not running (running: ~:[none~;~:*~{~(~a~)~^, ~}~]); ~
                                  start it with WITH-PROCESS-MODULES-RUNNING."
                             *running-process-modules*)))
    (sb-thread:with-recursive-lock ((process-module-lock module))
      ;; printed only if someone reads the task tree (as PERFORM's nodes)
      (cpl:with-task-tree-node (:process-module name :designator (lambda () designator))
        (let ((*executing-process-module* name))
          (call-with-process-module-debugger
           (lambda () (funcall (process-module-function module) designator))))))))

(defvar *process-module-debugger-hook* nil
  "NIL, or a debugger hook (a function of a condition and a hook, like *DEBUGGER-HOOK*): a Lisp
error inside a process module then enters the debugger with this as *DEBUGGER-HOOK*, at the
frame that signalled it, with the restart CONTINUE-PM (let the error propagate out of the
process module, as it does when this is NIL). Tasks inherit the value of the thread that
starts the plan.")

(pushnew '*process-module-debugger-hook* cpl:*inherited-specials*)

(defun continue-pm (&optional condition)
  "Invoke the restart CONTINUE-PM (offered while *PROCESS-MODULE-DEBUGGER-HOOK* handles an
error inside a process module): the error propagates out of the process module."
  (let ((restart (find-restart 'continue-pm condition)))
    (unless restart
      (error "CONTINUE-PM: no restart CONTINUE-PM is active~@[ for ~s~]; it exists while ~
              *PROCESS-MODULE-DEBUGGER-HOOK* handles an error inside a process module."
             condition))
    (invoke-restart restart)))

(defun call-with-process-module-debugger (thunk)
  "Call THUNK; with *PROCESS-MODULE-DEBUGGER-HOOK* set, a Lisp error in it first enters the
debugger with that hook, at the signalling frame."
  (let ((hook *process-module-debugger-hook*))
    (if (null hook)
        (funcall thunk)
        (progn
          (unless (or (functionp hook) (and (symbolp hook) (fboundp hook)))
            (error "CPM:*PROCESS-MODULE-DEBUGGER-HOOK* is ~s: expected NIL or a function of a ~
                    condition and a hook." hook))
          (handler-bind ((error
                           (lambda (condition)
                             (unless (typep condition 'cpl:plan-failure)
                               (with-simple-restart
                                   (continue-pm "Let the error propagate out of the process module.")
                                 (let ((*debugger-hook* hook))
                                   (invoke-debugger condition)))))))
            (funcall thunk))))))

(prolog:def-fact-group process-module-matching (matching-process-module)
  ;; (matching-process-module ?designator ?module-name): layers add one rule per module.
  (prolog:<- (matching-process-module ?designator ?module-name)
    (prolog:fail))
  (prolog:<- (available-process-module ?module-name)
    (prolog:bound ?module-name)
    (prolog:lisp-pred process-module-running-p ?module-name)))

(defun matching-process-modules (designator)
  "The names of the running process modules whose MATCHING-PROCESS-MODULE rules accept
DESIGNATOR, in rule order without duplicates."
  (let ((names '()))
    (cut:lazy-dolist (bindings (prolog:prolog '(and (matching-process-module ?designator ?pm)
                                                    (available-process-module ?pm))
                                              `((?designator . ,designator))))
      (pushnew (cut:var-value '?pm bindings) names))
    (nreverse names)))

(defun pm-execute-matching (designator &optional (names (matching-process-modules designator)))
  "Execute DESIGNATOR with the running process modules that match it (or with NAMES, when
given), in order, until one succeeds; the plan failure of the last one propagates. Fails with
NO-MATCHING-PROCESS-MODULE when there is none."
  (progn
    (when (null names)
      (cpl:fail 'no-matching-process-module :designator designator))
    (loop for (name . more) on names
          do (if more
                 (handler-case (return (pm-execute name designator))
                   (cpl:plan-failure (failure)
                     (cpl:log-message :warn '(process-modules) "~s failed: ~a Trying ~s."
                                      name failure (first more))))
                 (return (pm-execute name designator))))))

(setf (documentation 'matching-process-module 'function)
      "Prolog predicate (matching-process-module ?designator ?module-name): the process module
that can execute the motion designator. Extendable: each process module layer adds a rule."
      (documentation 'available-process-module 'function)
      "Prolog predicate (available-process-module ?module-name): the module is running.")
