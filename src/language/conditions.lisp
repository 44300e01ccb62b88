;;;; Plan failure conditions and the errors of the plan language itself.

(in-package :cram-language)

(define-condition plan-failure (serious-condition)
  ()
  (:report (lambda (condition stream)
             (format stream "Plan failure of class ~s." (type-of condition))))
  (:documentation "The root of all plan failures. A SERIOUS-CONDITION, not an
ERROR: plans signal failures with FAIL and handle them with
WITH-FAILURE-HANDLING."))

(define-condition simple-plan-failure (simple-condition plan-failure)
  ()
  (:report (lambda (condition stream)
             (if (simple-condition-format-control condition)
                 (apply #'format stream
                        (simple-condition-format-control condition)
                        (simple-condition-format-arguments condition))
                 (format stream "Plan failure of class ~s." (type-of condition)))))
  (:default-initargs :format-control nil :format-arguments '())
  (:documentation "A plan failure described by a format control and arguments,
the type that FAIL uses when it is given a string."))

(define-condition composite-failure (plan-failure)
  ((failures :initarg :failures :initform '() :reader composite-failures))
  (:report (lambda (condition stream)
             (let ((failures (composite-failures condition)))
               (format stream "Composite failure of ~d alternative~:p:~{~%  ~a~}"
                       (length failures)
                       (mapcar (lambda (f)
                                 (format nil "~s: ~a" (type-of f)
                                         (handler-case (princ-to-string f)
                                           (error () "<unprintable>"))))
                               failures)))))
  (:documentation "Signalled by TRY-ALL, TRY-IN-ORDER and TRY-EACH-IN-ORDER when
every alternative failed; COMPOSITE-FAILURES lists their failures in order."))

(setf (documentation 'composite-failures 'function)
      "The failures collected in a COMPOSITE-FAILURE, in the order of the alternatives.")

(define-condition common-lisp-error-envelope (plan-failure)
  ((error :initarg :error :reader envelop-error))
  (:report (lambda (condition stream)
             (format stream "Lisp error inside a plan: ~s: ~a"
                     (type-of (envelop-error condition))
                     (handler-case (princ-to-string (envelop-error condition))
                       (error () "<unprintable>")))))
  (:documentation "Wraps an ordinary Lisp error raised inside a task so that it
travels to the parent task as a plan failure. WITH-FAILURE-HANDLING clauses
match both the envelope and the error inside it."))

(setf (documentation 'envelop-error 'function)
      "The Lisp error wrapped in a COMMON-LISP-ERROR-ENVELOPE.")

(define-condition not-inside-plan-error (error)
  ((form :initarg :form :reader not-inside-plan-form))
  (:report (lambda (condition stream)
             (format stream "~s is not inside a plan: wrap it in CPL:TOP-LEVEL ~
                             (or a DEF-TOP-LEVEL-CRAM-FUNCTION)."
                     (not-inside-plan-form condition))))
  (:documentation "Signalled when a plan form that needs a task (PAR, PURSUE,
TRY-ALL ...) runs outside any TOP-LEVEL."))

(define-condition nested-top-level-error (error)
  ((name :initarg :name :reader nested-top-level-name)
   (outer :initarg :outer :reader nested-top-level-outer))
  (:report (lambda (condition stream)
             (format stream "Top-level ~s started inside the running task ~s: ~
                             top-levels cannot be nested."
                     (nested-top-level-name condition)
                     (nested-top-level-outer condition))))
  (:documentation "Signalled when TOP-LEVEL is entered from inside a task."))

(define-condition task-exit-error (error)
  ((task-name :initarg :task-name :reader task-exit-task-name)
   (detail :initarg :detail :initform nil :reader task-exit-detail))
  (:report (lambda (condition stream)
             (format stream "A non-local exit (RETURN-FROM, THROW or GO) tried to leave the ~
                             plan task ~s for a point outside it~@[ (~a)~]. Plan tasks run in ~
                             their own threads: a task's code must return normally or signal a ~
                             failure (CPL:FAIL); the exit was not taken."
                     (task-exit-task-name condition)
                     (task-exit-detail condition))))
  (:documentation "Signalled in the parent (ultimately by TOP-LEVEL) when code inside a plan
task (the TOP-LEVEL body, a PAR, PURSUE, TRY-ALL ... child) made a RETURN-FROM, THROW or GO to a
block, catch tag or tagbody outside the task. Such exits would cross threads; the task fails
with this error instead and every task thread is joined."))

(setf (documentation 'task-exit-task-name 'function)
      "The name of the plan task that a TASK-EXIT-ERROR tried to leave.")

(defgeneric failure-description (condition)
  (:documentation "A one-line human-readable text describing CONDITION, used
in the task tree next to its class name. Layers with their own failure
classes may specialise it.")
  (:method ((condition condition))
    (let ((text (handler-case (princ-to-string condition)
                  (error () (format nil "<unprintable ~s>" (type-of condition))))))
      (substitute #\Space #\Newline text))))

;; FAIL (failures.lisp) is a generic function whose first argument may be left out; a call
;; without arguments is written with the default format string, so that the compiler does not
;; warn about it (defined here, before the first call of FAIL is compiled)
(define-compiler-macro fail (&whole form &rest arguments)
  (if arguments form '(fail "Plan failure.")))
