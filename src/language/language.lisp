;;;; The plan macros: TOP-LEVEL, SEQ, PAR, PURSUE, TRY-ALL, TRY-IN-ORDER,
;;;; TRY-EACH-IN-ORDER, DEF-CRAM-FUNCTION.

(in-package :cram-language)

(defmacro named-top-level ((&key (name (error "NAMED-TOP-LEVEL needs a :NAME.")))
                           &body body)
  "Run BODY as a top-level plan named NAME (evaluated): in a new thread, as the
root task, with a fresh task tree stored in *LAST-TASK-TREE*; wait for it and
return its values. A failure escaping BODY is signalled in the caller with
ERROR. Entering a top-level from inside a task signals NESTED-TOP-LEVEL-ERROR.
BODY and every PAR, PURSUE, TRY-ALL ... child run in threads of their own: a
RETURN-FROM, THROW or GO from inside one of them to a block, catch tag or
tagbody outside it is not taken; the task fails with TASK-EXIT-ERROR instead,
which reaches the caller of the top-level like any Lisp error, after every task
thread has ended."
  `(call-as-top-level ,name (lambda () ,@body)))

(defmacro top-level (&body body)
  "Run BODY as an unnamed top-level plan; see NAMED-TOP-LEVEL."
  `(named-top-level (:name :top-level) ,@body))

(defmacro seq (&body forms)
  "Run FORMS one after another and return the values of the last (as PROGN)."
  `(progn ,@forms))

(defun form-label (form)
  (let* ((head (if (consp form) (first form) form))
         (text (if (symbolp head)
                   (string-downcase (symbol-name head))
                   (let ((*print-length* 3) (*print-level* 2) (*print-pretty* nil))
                     (prin1-to-string head)))))
    (if (> (length text) 60) (subseq text 0 60) text)))

(defun thunks-form (forms)
  `(list ,@(loop for form in forms collect `(lambda () ,form))))

(defun decide-par (tasks)
  (let ((failed (find :failed tasks :key #'task-status)))
    (cond (failed (list :failed (task-failure failed)))
          ((every (lambda (task) (eq (task-status task) :succeeded)) tasks)
           (list :succeeded (task-values (car (last tasks)))))
          (t nil))))

(defun decide-pursue (tasks)
  (let ((done (remove-if-not (lambda (task)
                               (member (task-status task) '(:succeeded :failed)))
                             tasks)))
    (when done
      (let ((first (reduce (lambda (a b)
                             (if (< (task-finish-order a) (task-finish-order b)) a b))
                           done)))
        (if (eq (task-status first) :succeeded)
            (list :succeeded (task-values first))
            (list :failed (task-failure first)))))))

(defun decide-try-all (tasks)
  (let ((winner (find :succeeded tasks :key #'task-status)))
    (cond (winner (list :succeeded (task-values winner)))
          ((every (lambda (task) (eq (task-status task) :failed)) tasks)
           (list :failed (make-condition 'composite-failure
                                         :failures (mapcar #'task-failure tasks))))
          (t nil))))

(defun call-concurrently (operator thunks labels decide)
  (require-task operator)
  (if (null thunks)
      nil
      (with-task-tree-node ((intern (symbol-name operator) :keyword) operator)
        (destructuring-bind (status payload)
            (run-task-group (string-downcase operator) thunks decide
                            :node-names labels)
          (ecase status
            (:succeeded (values-list payload))
            (:failed (resignal-failure payload)))))))

(defmacro par (&body forms)
  "Run FORMS concurrently, each in its own child task (thread). When any child
fails, the others are evaporated and its failure is signalled in this task.
Otherwise waits for all of them and returns the values of the last form in
textual order. Must run inside a plan (TOP-LEVEL)."
  `(call-concurrently 'par ,(thunks-form forms) ',(mapcar #'form-label forms)
                      #'decide-par))

(defmacro pursue (&body forms)
  "Run FORMS concurrently; the first child to finish decides: its values are
returned, or its failure is signalled, and the other children are evaporated.
Must run inside a plan."
  `(call-concurrently 'pursue ,(thunks-form forms) ',(mapcar #'form-label forms)
                      #'decide-pursue))

(defmacro try-all (&body forms)
  "Run FORMS concurrently; the first child that succeeds decides the values
and the others are evaporated. When all fail, a COMPOSITE-FAILURE holding
their failures (in textual order) is signalled. Must run inside a plan."
  `(call-concurrently 'try-all ,(thunks-form forms) ',(mapcar #'form-label forms)
                      #'decide-try-all))

(defun call-in-order (operator thunks)
  (require-task operator)
  (let ((failures '()))
    (dolist (thunk thunks)
      (block attempt
        (handler-bind ((plan-failure (lambda (c)
                                       (push c failures)
                                       (return-from attempt))))
          (return-from call-in-order (funcall thunk)))))
    (fail 'composite-failure :failures (nreverse failures))))

(defmacro try-in-order (&body forms)
  "Run FORMS one after another until one succeeds and return its values. A
plan failure in a form moves on to the next one; when all fail, a
COMPOSITE-FAILURE with their failures in order is signalled. Must run inside
a plan."
  `(call-in-order 'try-in-order ,(thunks-form forms)))

(defmacro try-each-in-order ((variable list) &body body)
  "Run BODY with VARIABLE bound to each element of LIST (evaluated) in turn
until it succeeds, and return its values. When BODY fails for every element
a COMPOSITE-FAILURE with all failures is signalled (an empty LIST fails with
an empty composite failure). Must run inside a plan."
  (check-type variable symbol)
  (let ((element (gensym "ELEMENT")))
    `(call-in-order 'try-each-in-order
                    (mapcar (lambda (,element)
                              (lambda () (let ((,variable ,element)) ,@body)))
                            (let ((list ,list))
                              (unless (listp list)
                                (error "TRY-EACH-IN-ORDER: expected a list, got ~s." list))
                              list)))))

;;; Plan functions

(defun split-definition-body (body)
  "Split BODY into (values forms declarations docstring)."
  (multiple-value-bind (forms declarations docstring)
      (alexandria:parse-body body :documentation t)
    (values forms declarations docstring)))

(defmacro def-cram-function (name lambda-list &body body)
  "Define a plan function: a DEFUN whose body runs as a :PLAN node named NAME
in the task tree of the running top-level (outside a plan it is an ordinary
function). (:TAG name form...) forms in BODY are tagged tasks (see WITH-TAGS), and
WALKER:EXPAND-PLAN expands calls of NAME into BODY."
  (check-type name symbol)
  (multiple-value-bind (forms declarations docstring) (split-definition-body body)
    `(progn
       (cram-walker:register-plan ',name ',lambda-list ',forms)
       (defun ,name ,lambda-list
         ,@(when docstring (list docstring))
         ,@declarations
         (with-task-tree-node (:plan ',name)
           (block ,name (with-tags ,@forms)))))))

(defmacro def-top-level-cram-function (name lambda-list &body body)
  "Define a function that runs its body as a top-level plan named NAME (see
NAMED-TOP-LEVEL) each time it is called; (:TAG name form...) forms in BODY are tagged
tasks."
  (check-type name symbol)
  (multiple-value-bind (forms declarations docstring) (split-definition-body body)
    `(progn
       (cram-walker:register-plan ',name ',lambda-list ',forms)
       (defun ,name ,lambda-list
         ,@(when docstring (list docstring))
         ,@declarations
         (named-top-level (:name ',name)
           (block ,name (with-tags ,@forms)))))))

(defmacro def-plan (name lambda-list &body body)
  "CRAM's older name of DEF-CRAM-FUNCTION."
  `(def-cram-function ,name ,lambda-list ,@body))

(defmacro def-top-level-plan (name lambda-list &body body)
  "CRAM's older name of DEF-TOP-LEVEL-CRAM-FUNCTION."
  `(def-top-level-cram-function ,name ,lambda-list ,@body))
