;;;; CRAM's task interface: status fluents of tasks, TOPLEVEL-TASK, tagged tasks (WITH-TAGS and
;;;; :TAG), PARTIAL-ORDER, suspension (SUSPEND, WAKE-UP, WITH-TASK-SUSPENDED, ON-SUSPENSION),
;;;; and the small CPL utilities SLEEP*, FL-PULSED, FL-VALUE-CHANGED and DEF-CPL-PARAMETER.

(in-package :cram-language)

;;; ---- utilities -------------------------------------------------------------------------------

(defun sleep* (seconds)
  "Wait SECONDS (CRAM's name for CPL:SLEEP, which waits on the projection clock when one runs)."
  (sleep seconds))

(defun fl-pulsed (fluent &key (handle-missed-pulses :once))
  "A fluent that is true once for each pulse of FLUENT (CRAM's name for PULSED)."
  (pulsed fluent :handle-missed-pulses handle-missed-pulses))

(defclass value-changed-fluent (fluent)
  ((source :initarg :source :reader changed-source)
   (test :initarg :test :reader changed-test)
   (key :initarg :key :reader changed-key)
   (old :initarg :old :accessor changed-old)
   (read-lock :initform (bt:make-lock "value changed") :reader changed-read-lock))
  (:documentation "A fluent that is true when the value of its source differs from the value
it had when this fluent was last read as true (see FL-VALUE-CHANGED)."))

(defmethod value ((fluent value-changed-fluent))
  (bt:with-lock-held ((changed-read-lock fluent))
    (let ((now (funcall (changed-key fluent) (value (changed-source fluent)))))
      (unless (funcall (changed-test fluent) now (changed-old fluent))
        (setf (changed-old fluent) now)
        t))))

(defun fl-value-changed (fluent &key (test #'eql) (key #'identity))
  "A fluent that is pulsed with FLUENT and is true whenever FLUENT's value (through KEY) is not
TEST-equal to the value it had at the last read that answered true (at creation at first)."
  (unless (typep fluent 'fluent)
    (error "FL-VALUE-CHANGED: expected a fluent, got ~s." fluent))
  (let ((changed (make-instance 'value-changed-fluent
                                :name (format nil "VALUE-CHANGED-~a" (fluent-name fluent))
                                :source fluent :test test :key key
                                :old (funcall key (value fluent)))))
    (add-dependent fluent changed)
    changed))

(defmacro def-cpl-parameter (name &optional value documentation)
  "Define NAME as a global variable kept in a fluent: read it and SETF it like a variable; every
change pulses the fluent, so access is synchronised across tasks."
  (check-type name symbol)
  (let ((holder (intern (format nil "*CPL-PARAMETER-~a*" (symbol-name name))
                        (or (symbol-package name) *package*))))
    `(progn
       (defparameter ,holder (make-fluent :name ',name :value ,value)
         ,(format nil "The fluent behind the CPL parameter ~s.~@[ ~a~]" name documentation))
       (define-symbol-macro ,name (value ,holder))
       ',name)))

;;; ---- status fluents of tasks -----------------------------------------------------------------

(defvar *status-fluents* (make-hash-table :test 'eq :weakness :key :synchronized t)
  "Task → the fluent of its status, made when first asked for.")

(defgeneric status (task)
  (:documentation "A fluent whose value is TASK's status: :CREATED, :RUNNING, :SUSPENDED,
:SUCCEEDED, :FAILED or :EVAPORATED.")
  (:method ((task task))
    (or (gethash task *status-fluents*)
        (setf (gethash task *status-fluents*)
              (make-fluent :name (format nil "STATUS-~a" (task-name task))
                           :value (task-status task)))))
  (:method ((object t))
    (error "CPL:STATUS: ~s is not a task." object)))

(defun note-task-status (task)
  "Put TASK's status into its status fluent, when one was made."
  (let ((fluent (gethash task *status-fluents*)))
    (when fluent (setf (value fluent) (task-status task)))))

(defgeneric result (task)
  (:documentation "The values (a list) of a task that succeeded, or the failure of one that
failed; NIL otherwise.")
  (:method ((task task))
    (case (task-status task)
      (:succeeded (task-values task))
      (:failed (task-failure task)))))

(defun dead-status-p (status) (member status '(:succeeded :failed :evaporated)))

(defun task-dead (task)
  "A fluent that is true once TASK has ended (succeeded, failed or evaporated)."
  (fl-funcall (lambda (status) (and (dead-status-p status) t)) (status task)))

(defun task-alive (task)
  "A fluent that is true while TASK has not ended."
  (fl-funcall (lambda (status) (not (dead-status-p status))) (status task)))

(defun task-running-p (task) "True while TASK runs." (eq (value (status task)) :running))
(defun task-dead-p (task) "True once TASK has ended." (and (dead-status-p (value (status task))) t))
(defun task-failed-p (task) "True when TASK failed." (eq (value (status task)) :failed))

(defun join-task (task)
  "Wait until TASK ends; return its values, or signal its failure."
  (wait-for (task-dead task))
  (case (value (status task))
    (:succeeded (values-list (result task)))
    (:failed (fail (result task)))
    (t (error "JOIN-TASK: the task ~a was evaporated." (task-name task)))))

(defun toplevel-task (&optional (task *current-task*))
  "The top-level task of TASK (the current task by default), NIL outside a plan."
  (loop while (and task (task-parent task)) do (setf task (task-parent task)))
  task)

;;; ---- tagged tasks ----------------------------------------------------------------------------

(defstruct (tagged-task (:include task) (:constructor %make-tagged-task))
  "The task of a (:TAG name ...) form of WITH-TAGS: it runs in the thread that reaches the form."
  (constraints '())
  (wake nil)
  (suspend-requested nil))

(defun make-tagged-task (name)
  (%make-tagged-task :name name :parent *current-task* :status :created))

(defun set-tagged-status (task status)
  (setf (task-status task) status)
  (setf (value (status task)) status))

(defvar *suspension-handlers* '()
  "Thunks ON-SUSPENSION forms of the running code established, innermost first.")

(defun suspend-self (task)
  "Run in TASK's thread: run the suspension handlers, then wait until TASK is woken up."
  (when (and (eq (task-status task) :running) (tagged-task-suspend-requested task))
    (setf (tagged-task-suspend-requested task) nil)
    (let ((wake (make-fluent :name "WAKE" :value nil)))
      (setf (tagged-task-wake task) wake)
      (dolist (handler *suspension-handlers*) (funcall handler))
      (set-tagged-status task :suspended)
      ;; an interrupt runs with interrupts disabled: allow them while waiting, so that the task
      ;; can still be evaporated while it is suspended
      (sb-sys:with-interrupts (wait-for wake))
      (set-tagged-status task :running))))

(defun suspend (task &key reason)
  "Suspend the running tagged TASK: its thread runs the handlers of its ON-SUSPENSION forms,
then waits until WAKE-UP. REASON is for the log."
  (unless (typep task 'tagged-task)
    (error "SUSPEND: ~s is not a tagged task (a tag of WITH-TAGS)." task))
  (when (and (eq (task-status task) :running) (task-thread task))
    (when reason (log-info "Suspending ~a: ~a" (task-name task) reason))
    (setf (tagged-task-suspend-requested task) t)
    (handler-case (bt:interrupt-thread (task-thread task) (lambda () (suspend-self task)))
      (error () nil)))
  task)

(defun wake-up (task)
  "Let the suspended tagged TASK go on."
  (unless (typep task 'tagged-task)
    (error "WAKE-UP: ~s is not a tagged task (a tag of WITH-TAGS)." task))
  (setf (tagged-task-suspend-requested task) nil)
  (let ((wake (tagged-task-wake task)))
    (when wake (setf (value wake) t)))
  task)

(defmacro on-suspension (when-suspended &body body)
  "Run BODY; whenever its task is suspended meanwhile, WHEN-SUSPENDED runs first (in the task's
thread)."
  `(let ((*suspension-handlers* (cons (lambda () ,when-suspended) *suspension-handlers*)))
     ,@body))

(defmacro with-task-suspended ((task &key reason) &body body)
  "Suspend the tagged TASK, wait until it is suspended (or has ended), run BODY, then wake it
up (also when BODY fails)."
  (let ((tk (gensym "TASK")))
    `(let ((,tk ,task))
       (unwind-protect
            (progn
              (suspend ,tk :reason ,reason)
              (wait-for (fl-funcall (lambda (status) (member status '(:suspended :succeeded
                                                                      :failed :evaporated
                                                                      :created)))
                                    (status ,tk)))
              ,@body)
         (wake-up ,tk)))))

(defun run-tagged-task (task thunk)
  "Run THUNK as the tagged TASK in this thread: wait for its ordering constraints, keep its
status fluent, and record it in the task tree as a :TAG node."
  (dolist (constraint (tagged-task-constraints task))
    (wait-for constraint))
  (setf (task-thread task) (bt:current-thread)
        (task-values task) nil (task-failure task) nil)
  (set-tagged-status task :running)
  (let ((ok nil))
    (unwind-protect
         (handler-bind ((plan-failure (lambda (c) (setf (task-failure task) c))))
           (let ((values (multiple-value-list
                          (with-task-tree-node (:tag (task-name task)) (funcall thunk)))))
             (setf (task-values task) values ok t)
             (values-list values)))
      (set-tagged-status task (cond (ok :succeeded)
                                    ((task-failure task) :failed)
                                    (t :evaporated))))))

(defun tag-names (body)
  "The names of the (:TAG name ...) forms in BODY, outside quoted and backquoted data, in
order (a :TAG list whose name is not a symbol is data, not a tag)."
  (let ((names '()))
    (labels ((walk (form)
               (when (consp form)
                 (cond ((member (car form) '(quote sb-int:quasiquote)))
                       ((and (eq (car form) :tag) (consp (cdr form))
                             (cadr form) (symbolp (cadr form)))
                        (pushnew (cadr form) names)
                        (mapc #'walk (cddr form)))
                       (t (loop for rest on form
                                do (walk (car rest))
                                while (consp (cdr rest))))))))
      (mapc #'walk body))
    (nreverse names)))

(defmacro with-tags (&body body)
  "Run BODY with each (:TAG name form...) in it run as a tagged task NAME: NAME is bound around
BODY to the task object (its STATUS fluent, TASK-DEAD, SUSPEND, PARTIAL-ORDER constraints), and
the forms run where the :TAG form stands, recorded as a :TAG node of the task tree."
  (let ((names (tag-names body)))
    `(let ,(mapcar (lambda (name) `(,name (make-tagged-task ',name))) names)
       (declare (ignorable ,@names))
       (macrolet ((:tag (name &body forms)
                    `(run-tagged-task ,name (lambda () ,@forms))))
         ,@body))))

(defmacro :tag (name &body body)
  "(:TAG name form...) is only meaningful inside WITH-TAGS."
  (declare (ignore body))
  `(error "(:TAG ~s ...) is used outside WITH-TAGS." ',name))

(defmacro partial-order ((&body steps) &body orderings)
  "Run STEPS concurrently (as PAR) under the ORDERINGS, each (:ORDER constraining constrained):
the tagged task CONSTRAINED starts only when the tagged task CONSTRAINING has ended."
  (dolist (ordering orderings)
    (unless (and (consp ordering) (eq (first ordering) :order) (= (length ordering) 3))
      (error "PARTIAL-ORDER: malformed ordering ~s; expected (:ORDER constraining constrained)."
             ordering)))
  `(progn
     ,@(loop for (nil constraining constrained) in orderings
             collect `(push (task-dead ,constraining) (tagged-task-constraints ,constrained)))
     (par ,@steps)))
