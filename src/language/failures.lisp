;;;; FAIL, WITH-FAILURE-HANDLING and retry counters.

(in-package :cram-language)

(defun condition-initargs (class-name)
  "The initargs the slots of the condition class CLASS-NAME accept, or :UNKNOWN."
  (handler-case
      (let ((class (find-class class-name)))
        (unless (sb-mop:class-finalized-p class)
          (sb-mop:finalize-inheritance class))
        (loop for slot in (sb-mop:class-slots class)
              append (sb-mop:slot-definition-initargs slot)))
    (error () :unknown)))

(defun check-condition-initargs (class-name initargs)
  "Signal an error naming the first of the plist INITARGS that no slot of the condition class
CLASS-NAME accepts."
  (let ((valid (condition-initargs class-name)))
    (unless (eq valid :unknown)
      (loop for (key nil) on initargs by #'cddr
            unless (member key valid)
              do (error "FAIL: ~s is not an initarg of the condition class ~s; it accepts ~
                         ~:[none~;~:*~{~s~^ ~}~]."
                        key class-name (remove-duplicates valid))))))

(defun coerce-to-failure (arguments)
  "Turn the arguments of FAIL into a condition object."
  (let ((first (first arguments)))
    (cond ((null arguments)
           (make-condition 'simple-plan-failure :format-control "Plan failure."))
          ((stringp first)
           (make-condition 'simple-plan-failure :format-control first
                                                :format-arguments (rest arguments)))
          ((typep first 'condition)
           (when (rest arguments)
             (error "FAIL: extra arguments ~s after the condition object ~s."
                    (rest arguments) first))
           first)
          ((and (symbolp first) (find-class first nil)
                (subtypep first 'condition))
           (unless (evenp (length (rest arguments)))
             (error "FAIL: odd number of initargs ~s for condition class ~s."
                    (rest arguments) first))
           (check-condition-initargs first (rest arguments))
           (apply #'make-condition first (rest arguments)))
          ((symbolp first)
           (error "FAIL: ~s does not name a condition class; expected a format ~
                   string, a condition object or a condition class name." first))
          (t
           (error "FAIL: expected a format string, a condition object or a ~
                   condition class name, got ~s." first)))))

(eval-when (:compile-toplevel :load-toplevel :execute)
  (defclass failure-generic-function (standard-generic-function) ()
    (:metaclass sb-mop:funcallable-standard-class)
    (:documentation "The class of FAIL: a generic function whose first argument may be left
out (it defaults to the format string \"Plan failure.\")."))

  (defmethod sb-mop:compute-discriminating-function ((function failure-generic-function))
    (let ((dispatch (call-next-method)))
      (lambda (&rest arguments)
        (if arguments
            (apply dispatch arguments)
            (funcall dispatch "Plan failure."))))))

(defgeneric fail (datum &rest arguments)
  (:generic-function-class failure-generic-function)
  (:documentation "Signal a plan failure. DATUM and ARGUMENTS are a format control string and its
arguments (giving a SIMPLE-PLAN-FAILURE), a condition object, or a condition
class name followed by initargs; with no arguments a SIMPLE-PLAN-FAILURE is
signalled. Inside a task a plan failure is signalled with SIGNAL, so handlers
of WITH-FAILURE-HANDLING run before anything unwinds, and a failure nobody
handles ends the task. A condition that is not a PLAN-FAILURE, or any failure
outside a task, is raised with ERROR. Never returns.
FAIL is a generic function: specialise DATUM with methods of your own (e.g. to turn
objects of your classes into failures, or to log with a :BEFORE method); DATUM may be left out.
The default method handles strings, condition objects and condition class names.")
  (:method ((datum t) &rest arguments)
    (signal-failure (coerce-to-failure (cons datum arguments)))))

(defun signal-failure (condition)
  "Signal the failure CONDITION the way FAIL does; never returns."
  (if (and *current-task* (typep condition 'plan-failure))
      (progn
        (when (break-on-failure-p condition)
          (debug-in-task *current-task* condition "Signal the plan failure (failure handling may catch it)."))
        (signal condition)
        ;; Every task thread handles PLAN-FAILURE at its root, so SIGNAL
        ;; only returns if a handler declined and no root handler exists.
        (error condition))
      (error condition)))

;;; WITH-FAILURE-HANDLING

(defun matching-failure (condition type)
  "CONDITION, or the error wrapped in it, when it is of TYPE; else NIL."
  (cond ((typep condition type) condition)
        ((and (typep condition 'common-lisp-error-envelope)
              (typep (envelop-error condition) type))
         (envelop-error condition))
        (t nil)))

(defun check-failure-clause (clause)
  (unless (and (consp clause)
               (consp (cdr clause))
               (listp (second clause))
               (<= (length (second clause)) 1)
               (every #'symbolp (second clause)))
    (error "WITH-FAILURE-HANDLING: malformed clause ~s; expected ~
            (condition-type ([variable]) form...)." clause)))

(defmacro with-failure-handling (clauses &body body)
  "Run BODY; when a failure of a type named by one of CLAUSES is signalled in
it, run that clause in the dynamic context of the signal, before anything
unwinds. CLAUSES have the form (TYPE (VAR) FORM...) where TYPE is any type
specifier, e.g. (OR A B), and VAR may be omitted. A clause may
  - call the local function (RETRY) to start BODY again from its beginning,
  - leave the whole form with (RETURN value) (an implicit BLOCK NIL), or
  - return normally, so the failure keeps propagating.
A COMMON-LISP-ERROR-ENVELOPE matches a clause whose type matches the error it
wraps, and VAR is then bound to that error. Each retry is counted in the
innermost task tree node, and each caught failure is recorded there."
  (mapc #'check-failure-clause clauses)
  (let ((start (gensym "START"))
        (node (gensym "NODE")))
    `(block nil
       (let ((,node *task-tree-node*))
         (declare (ignorable ,node))
         (tagbody
            ,start
            (flet ((retry ()
                     "Start the body of the enclosing WITH-FAILURE-HANDLING again."
                     (note-retry ,node)
                     (go ,start)))
              (declare (ignorable #'retry))
              (return
                (handler-bind
                    ,(loop for (type lambda-list . clause-body) in clauses
                           for condition = (gensym "CONDITION")
                           for matched = (gensym "MATCHED")
                           for var = (or (first lambda-list) (gensym "E"))
                           collect `(condition
                                     (lambda (,condition)
                                       (let ((,matched (matching-failure ,condition ',type)))
                                         (when ,matched
                                           (note-caught-failure ,node ,matched)
                                           (let ((,var ,matched))
                                             (declare (ignorable ,var))
                                             ,@clause-body))))))
                  ,@body))))))))

(setf (documentation 'retry 'function)
      "Inside a clause of WITH-FAILURE-HANDLING, (RETRY) starts the body of that
form again from its beginning. It is a local function of each
WITH-FAILURE-HANDLING; there is no global definition.")

;;; Retry counters

(defstruct (retry-counter (:constructor make-retry-counter (name initial &aux (value initial))))
  name initial value)

(defun check-counter-value (name value)
  (unless (and (integerp value) (>= value 0))
    (error "WITH-RETRY-COUNTERS: counter ~s needs a non-negative integer, got ~s."
           name value))
  value)

(define-symbol-macro %retry-counters '())

(defun counter-variable (name env)
  (let* ((expansion (macroexpand-1 '%retry-counters env))
         (table (if (and (consp expansion) (eq (first expansion) 'quote))
                    (second expansion)
                    '()))
         (entry (assoc name table)))
    (unless entry
      (error "Unknown retry counter ~s: it is not bound by an enclosing ~
              WITH-RETRY-COUNTERS (known: ~:[none~;~:*~{~s~^, ~}~])."
             name (mapcar #'car table)))
    (cdr entry)))

(defmacro with-retry-counters (counter-definitions &body body &environment env)
  "Bind retry counters for BODY. Each definition is (NAME COUNT) with COUNT
evaluated to a non-negative integer. Inside BODY, DO-RETRY, GET-COUNTER and
RESET-COUNTER refer to the counters by NAME."
  (dolist (definition counter-definitions)
    (unless (and (consp definition) (symbolp (first definition))
                 (consp (cdr definition)) (null (cddr definition)))
      (error "WITH-RETRY-COUNTERS: malformed counter definition ~s; expected (name count)."
             definition)))
  (let* ((outer (let ((expansion (macroexpand-1 '%retry-counters env)))
                  (if (and (consp expansion) (eq (first expansion) 'quote))
                      (second expansion)
                      '())))
         (variables (loop for (name) in counter-definitions
                          collect (gensym (symbol-name name)))))
    `(let ,(loop for (name count) in counter-definitions
                 for variable in variables
                 collect `(,variable (make-retry-counter
                                      ',name (check-counter-value ',name ,count))))
       (symbol-macrolet ((%retry-counters
                           '(,@(loop for (name) in counter-definitions
                                     for variable in variables
                                     collect (cons name variable))
                             ,@outer)))
         ,@body))))

(defmacro do-retry (counter-name &body body &environment env)
  "When the retry counter COUNTER-NAME is above zero, decrement it and run
BODY, returning its values; otherwise return NIL without running BODY."
  (let ((variable (counter-variable counter-name env)))
    `(when (> (retry-counter-value ,variable) 0)
       (decf (retry-counter-value ,variable))
       ,@body)))

(defmacro get-counter (counter-name &environment env)
  "The number of retries left in the counter COUNTER-NAME."
  `(retry-counter-value ,(counter-variable counter-name env)))

(defmacro reset-counter (counter-name &environment env)
  "Set the counter COUNTER-NAME back to its initial count."
  (let ((variable (counter-variable counter-name env)))
    `(setf (retry-counter-value ,variable) (retry-counter-initial ,variable))))
