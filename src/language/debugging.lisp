;;;; Entering the debugger from inside a plan: at the frame of a Lisp error in a task
;;;; (*DEBUG-ON-LISP-ERRORS*) or where a plan failure is signalled (*BREAK-ON-PLAN-FAILURES*),
;;;; in the task's own thread, with restarts to go on or to abort the plan.

(in-package :cram-language)

(defvar *debug-on-lisp-errors* nil
  "When true, a Lisp error (not a plan failure) inside a task enters the debugger in the task's
thread, at the frame that signalled it, before it becomes a COMMON-LISP-ERROR-ENVELOPE. The
debugger offers the restarts CONTINUE (the error ends the task as a plan failure, as it does
when this is NIL) and ABORT-PLAN (the whole plan stops; its top-level call signals a
PLAN-ABORTED error). Tasks inherit the value of the thread that starts the plan.")

(defvar *break-on-plan-failures* nil
  "A type specifier, like *BREAK-ON-SIGNALS* for plan failures: FAIL inside a task enters the
debugger, in the task's thread, for a failure of this type before it is signalled (T: every
failure; NIL, the default: none). The restart CONTINUE signals the failure as usual, so
WITH-FAILURE-HANDLING sees it; ABORT-PLAN stops the whole plan.")

(define-condition plan-aborted (error)
  ((name :initarg :name :reader plan-aborted-name))
  (:report (lambda (condition stream)
             (format stream "The plan ~s was aborted from the debugger (restart ABORT-PLAN)."
                     (plan-aborted-name condition))))
  (:documentation "Signalled by a top-level call whose plan was stopped with the restart
ABORT-PLAN."))

(setf (documentation 'plan-aborted-name 'function)
      "The name of the top-level plan a PLAN-ABORTED error is about.")

(defun break-on-failure-p (condition)
  "True when CONDITION is of the type *BREAK-ON-PLAN-FAILURES* names."
  (let ((spec *break-on-plan-failures*))
    (and spec
         (handler-case (typep condition spec)
           (error ()
             (error "CPL:*BREAK-ON-PLAN-FAILURES* is ~s: expected a type specifier such as T, ~
                     NIL or COMMON-FAIL:MANIPULATION-LOW-LEVEL-FAILURE." spec))))))

(defun debug-in-task (task condition continue-report)
  "Enter the debugger for CONDITION in the thread of TASK (the current task), at the signalling
frame. Returns when the user picks CONTINUE (described by CONTINUE-REPORT); the restart
ABORT-PLAN stops the plan and unwinds this task."
  (progn
    (restart-case (with-simple-restart (continue "~a" continue-report)
                    (invoke-debugger condition))
      (abort-plan ()
        :report "Abort the plan: stop every task of it; its top-level call signals PLAN-ABORTED."
        (stop-plan-from-task task)))))

(defun abort-plan (&optional condition)
  "Invoke the restart ABORT-PLAN (of the debugger inside a task, see *DEBUG-ON-LISP-ERRORS*):
stop the whole plan, whose top-level call then signals PLAN-ABORTED. With CONDITION, the
restart associated with it."
  (let ((restart (find-restart 'abort-plan condition)))
    (unless restart
      (error "ABORT-PLAN: no restart ABORT-PLAN is active~@[ for ~s~]; it exists while the ~
              debugger is open inside a task."
             condition))
    (invoke-restart restart)))
