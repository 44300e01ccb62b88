;;;; PERFORM: motions go to the matching running process module, actions to the plan function
;;;; their grounding names. Also connects designators to the retry strategies of COMMON-FAIL.

(in-package :cram-executive)

(defgeneric perform (designator)
  (:documentation "Execute DESIGNATOR and return the values of its execution.
A motion designator is executed by the running process modules whose
CPM:MATCHING-PROCESS-MODULE rules match it (CPM:NO-MATCHING-PROCESS-MODULE when none does).
An action designator is referenced through DESIG:ACTION-GROUNDING to (plan-function
resolved-designator), and the plan function is called with the resolved designator's
properties as keyword arguments, or to (plan-function argument...), called with the
arguments. When the action has (GOAL occasion) properties that all hold already, it is
skipped and NIL returned (logged as CRAM does: \"Action goal `(...)' already achieved.\").
Every call is logged at :INFO with its designator, `[(PERFORM ACTION) INFO] <time>:' or
`[(PERFORM MOTION) INFO] <time>:', and recorded in the task tree."))

(defmethod perform ((designator t))
  (error "PERFORM: expected an action or motion designator, got ~s." designator))

(defmethod perform ((designator desig:designator))
  (error "PERFORM: expected an action or motion designator, got a ~(~a~) designator: ~s."
         (desig:designator-type designator) designator))

(defun designator-kind-name (designator)
  (let ((type (desig:desig-prop-value designator :type)))
    (if (and type (symbolp type)) type :unknown)))

(defun log-performing (kind designator)
  "CRAM's line for every PERFORM: `[(PERFORM ACTION) INFO] <time>: ' and the designator.
Returns what the task tree node shows for DESIGNATOR: the text just logged (printed once), or,
when nobody reads the line (the level filtered it out, or the log stream discards everything),
a function giving DESIGNATOR, printed only if someone reads the task tree (a designator's
description does not change)."
  (let ((message (cpl:log-message :info (list 'perform kind) "~%~a~%" designator)))
    (if message (string-trim '(#\Newline) message) (lambda () designator))))

(defmethod perform ((designator desig:motion-designator))
  (cpl:with-task-tree-node (:motion (designator-kind-name designator)
                            :designator (log-performing 'motion designator))
    (let ((modules (cpm:matching-process-modules designator)))
      (when (null modules)
        (cpl:fail 'cpm:no-matching-process-module :designator designator))
      (desig:reference designator)
      (cpm:pm-execute-matching designator modules))))

(defun action-plan-arguments (grounding)
  "The plan function and the argument list of an action GROUNDING: for (function
resolved-designator) the resolved designator's entries as keyword arguments (:KEY value, one
value per entry, or the list of values of an entry with several), otherwise the rest of the
grounding. Returns (values function arguments)."
  (destructuring-bind (function &rest rest) grounding
    (values function
            (if (and rest (null (cdr rest)) (typep (first rest) 'desig:action-designator))
                (loop for (key . values) in (desig:description (first rest))
                      append (list key (if (cdr values) values (first values))))
                rest))))

(defun check-plan-function (function designator)
  (unless (or (functionp function) (and (symbolp function) (fboundp function)
                                        (not (macro-function function))
                                        (not (special-operator-p function))))
    (error 'desig:designator-error
           :designator designator
           :reason (format nil "its grounding names the plan function ~s, which is not a ~
                                defined function." function))))

(defun goals-hold-p (goals)
  (every (lambda (goal) (coe:holds goal)) goals))

(defmethod perform ((designator desig:action-designator))
  (let ((shown (log-performing 'action designator))
        (goals (desig:desig-prop-values designator :goal)))
    (if (and goals (goals-hold-p goals))
        (progn
          (cpl:log-message :info '(perform action) "Action goal `~a' already achieved." goals)
          nil)
        (cpl:with-task-tree-node (:action (designator-kind-name designator)
                                  :designator shown)
          (multiple-value-bind (function arguments)
              (action-plan-arguments (desig:reference designator))
            (check-plan-function function designator)
            (cpl:log-message :debug '(perform action) "Performing ~s with ~s." function
                             arguments)
            (multiple-value-prog1
                (cpl:with-task-tree-node (:plan (if (symbolp function) function :anonymous))
                  (apply function arguments))
              (when (and goals (not (goals-hold-p goals)))
                (cpl:log-message :warn '(perform action)
                                 "Goal `~a' of the action ~s does not hold after performing it."
                                 goals (designator-kind-name designator)))))))))

;;; Designator hooks of the COMMON-FAIL retry strategies.

(defmethod common-fail:designator-next-solution ((designator desig:designator))
  (desig:next-solution designator))

(defmethod common-fail:designator-reset ((designator desig:designator))
  (desig:reset designator))

(defmethod common-fail:designator-next-different-location-solution
    ((designator desig:location-designator) distance-threshold angle-threshold)
  (desig:next-different-location-solution designator distance-threshold angle-threshold))
