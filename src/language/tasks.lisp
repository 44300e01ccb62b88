;;;; Tasks: real threads that run plan code, inherit the plan's special
;;;; bindings, report success or failure to their parent and can be evaporated.

(in-package :cram-language)

(defvar *current-task* nil
  "The task whose thread is running, NIL outside any TOP-LEVEL.")

(defvar *inherited-specials*
  '(*standard-output* *error-output* *trace-output* *standard-input* *query-io*
    *debug-io* *terminal-io* *package* *readtable*
    *log-stream* *log-tags* *log-level* *log-tally* *sleep-function*
    *debug-on-lisp-errors* *break-on-plan-failures* *debugger-hook* sb-ext:*invoke-debugger-hook*
    *ordered-concurrency* *plan-cpu* *plan-free-mask*)
  "Special variables whose values a child task thread starts with, taken from
the thread that starts it. Other layers add their own with PUSHNEW, e.g. the
projection environment's clock or the current designators.")

(defvar *ordered-concurrency* nil
  "When true (a projection environment binds it), the children of PAR, PURSUE and TRY-ALL start
one at a time: each waits until every task of the plan started before it has ended or waits on
a fluent or for its own children (or until *ORDERED-START-TIMEOUT* has passed). NIL: they all
start at once, as on a robot.")

(defparameter *ordered-start-timeout* 0.5d0
  "Seconds a child waits for the plan to become quiet, with no task of the plan starting,
ending, waiting or waking in that time, before it starts anyway: a sibling that waits in some
other way than on a fluent (polling, say) must not hold the others forever.")

(defvar *evaporation-target* nil
  "Inside a task's thread, the task while it may be evaporated.")

(defstruct (task-group (:constructor make-task-group ()))
  (lock (bt:make-lock "cpl task group"))
  (condition (bt:make-condition-variable :name "cpl task group"))
  (tasks '())
  (finished 0 :type integer))

(defstruct (task (:constructor %make-task) (:copier nil))
  "A plan task: a thread running a piece of plan code."
  (name nil)
  (parent nil)
  (index 0 :type integer)
  (group nil)
  (thread nil)
  (status :created :type keyword)
  (values '())
  (failure nil)
  (finish-order nil)
  (evaporate-requested nil)
  (evaporating nil)
  (aborted nil)
  (released t)    ; NIL while its thread (SPAWN-TASK) still runs the task's code
  (activity nil)  ; the plan's ACTIVITY under *ORDERED-CONCURRENCY*, else NIL
  (waiting nil))  ; what it waits on while not counted as running (a task group, a fluent)

(setf (documentation 'task-name 'function) "The name of a task."
      (documentation 'task-status 'function)
      "One of :CREATED, :RUNNING, :SUCCEEDED, :FAILED, :EVAPORATED."
      (documentation 'task-parent 'function) "The task that started this one, NIL for a top-level task.")

;;; Under *ORDERED-CONCURRENCY* (ordered-start.lisp) a task that waits is not counted as
;;; running. Its waker counts it again before going on (a child that ends wakes its parent
;;; waiting for the children's decision, a pulse wakes the tasks waiting on the fluent), so that
;;; the plan never looks quiet between the two. Each of these runs under the lock of what is
;;; waited on (the task group's, the fluent's).

(defun begin-task-wait (task on)
  "TASK (a task or NIL) begins to wait on ON (a task group or a fluent)."
  (when (and task (task-activity task))
    (setf (task-waiting task) on)
    (activity-change (task-activity task) -1)))

(defun wake-waiting-task (task on)
  "Count TASK as running again when it waits on ON (and is not counted yet)."
  (when (and task (eq (task-waiting task) on))
    (setf (task-waiting task) nil)
    (activity-change (task-activity task) 1)))

(defmacro with-task-waiting ((on) &body body)
  "Run BODY, a wait of the current task on ON (any object: a task group, a fluent, a projection
clock), with the task not counted as running: under *ORDERED-CONCURRENCY* its siblings may
start meanwhile."
  (let ((task (gensym "TASK")) (what (gensym "ON")))
    `(let ((,task *current-task*) (,what ,on))
       (begin-task-wait ,task ,what)
       (unwind-protect (progn ,@body)
         ;; counted as running again, unless its waker did that
         (wake-waiting-task ,task ,what)))))

(defmethod print-object ((task task) stream)
  (print-unreadable-object (task stream :type t :identity t)
    (format stream "~a ~(~a~)" (task-name task) (task-status task))))

(defun current-task-p ()
  "True inside the thread of a running plan task."
  (not (null *current-task*)))

(defun current-task-evaporating-p ()
  (and *current-task* (task-evaporating *current-task*)))

(defun require-task (form)
  "Signal NOT-INSIDE-PLAN-ERROR naming FORM unless a task is running."
  (unless *current-task*
    (error 'not-inside-plan-error :form form)))

(defun capture-inherited-specials ()
  (let ((symbols '()) (values '()))
    (dolist (symbol *inherited-specials*)
      (unless (and (symbolp symbol) symbol)
        (error "*inherited-specials* must hold symbols, found ~s." symbol))
      (when (and (boundp symbol) (not (member symbol symbols)))
        (push symbol symbols)
        (push (symbol-value symbol) values)))
    (cons symbols values)))

(defmacro with-evaporation-deferred (&body body)
  "Run BODY to its end even if the task is evaporated meanwhile; the
evaporation takes effect when BODY returns. Wrap short critical sections in
it, above all calls into foreign code (which must not be unwound), and never
a long or blocking wait."
  `(sb-sys:without-interrupts ,@body))

(defun notify-after-unlock (queue)
  "Wake every thread waiting on QUEUE, called right after leaving the lock they wait with,
once what they wait for has been set under it. Each waiter checks its condition under the
lock in a loop, and a wake-up between its check and its wait is not lost (SBCL's futex
waitqueues). Woken under the lock, a waiter would find the lock taken and wait once more for
it: a second wake-up of a second thread, which the plans' many short hand-overs pay for."
  (sb-thread:condition-broadcast queue))

(defun task-done-p (task)
  "True once TASK has ended: succeeded, failed or evaporated."
  (member (task-status task) '(:succeeded :failed :evaporated)))

(defun finish-task (task status values failure)
  (let ((group (task-group task)))
    (bt:with-lock-held ((task-group-lock group))
      (setf (task-status task) status
            (task-values task) values
            (task-failure task) failure
            (task-finish-order task) (incf (task-group-finished group)))
      ;; the parent, waiting for its children's decision, runs again before this one stops
      (wake-waiting-task (task-parent task) group))
    (notify-after-unlock (task-group-condition group))
    (activity-change (task-activity task) -1)
    (note-task-status task)))

(defun evaporate-self (task)
  "Run by an interrupt inside TASK's thread: unwind it if it may be evaporated."
  (when (eq *evaporation-target* task)
    (setf (task-evaporating task) t)
    (throw task :evaporated)))

(defun call-with-exit-guard (task thunk internal-exit-p)
  "Call THUNK and return its values. A non-local exit out of THUNK that is not one of the
task's own (INTERNAL-EXIT-P, a function of no arguments, returns true for those) targets a
block, catch tag or tagbody of another thread: it is stopped here and becomes a
TASK-EXIT-ERROR naming TASK, so the thread is never unwound past its base."
  (let ((tag (list 'exit-guard)) (finished nil))
    (let ((result (catch tag
                    (unwind-protect
                         (multiple-value-prog1 (cons :values (multiple-value-list (funcall thunk)))
                           (setf finished t))
                      (unless (or finished (funcall (the function internal-exit-p)))
                        (throw tag :foreign-exit))))))
      (if (eq result :foreign-exit)
          (error 'task-exit-error :task-name (task-name task))
          (values-list (cdr result))))))

(defvar *task-in-caller-thread* nil
  "The task RUN-TASK-HERE runs in the thread of its caller (a REPL, a program): that thread's
stack is the caller's, so a non-local exit out of the task's own body (leaving the debugger for
the REPL's top level, a THROW to the caller's CATCH) unwinds it as in Lisp; exits out of its
child tasks' threads remain TASK-EXIT-ERRORs.")

(defun execute-task (task thunk node)
  "The body of a task thread: run THUNK, classify the outcome, report it."
  (let ((status :evaporated) (values '()) (failure nil) (leaving nil))
    (catch task
      (let ((*evaporation-target* task))
        (when (task-evaporate-requested task)
          (setf (task-evaporating task) t)
          (throw task :evaporated))
        (block run
          (handler-bind ((plan-failure
                           (lambda (c)
                             (setf failure c status :failed leaving t)
                             (return-from run)))
                         (error
                           (lambda (c)
                             (when (and *debug-on-lisp-errors* (not (typep c 'task-exit-error)))
                               (debug-in-task task c "Let the error end the task as a plan failure."))
                             (when (typep c 'control-error)
                               ;; a THROW to a tag no frame of this thread established
                               (setf c (make-condition 'task-exit-error
                                                       :task-name (task-name task)
                                                       :detail (handler-case (princ-to-string c)
                                                                 (error () nil)))))
                             (setf failure (make-condition 'common-lisp-error-envelope
                                                           :error c)
                                   status :failed leaving t)
                             (return-from run))))
            (setf values (multiple-value-list
                          (call-with-exit-guard
                           task
                           (if node (lambda () (run-in-node node thunk)) thunk)
                           (lambda () (or leaving (task-evaporating task)
                                          (eq *task-in-caller-thread* task)))))
                  status :succeeded)))))
    (finish-task task status values failure)))

(defun spawn-task (name group index thunk &key node-kind node-name node)
  "Start a thread running THUNK as a child task of the current task, in GROUP.
With NODE-KIND a task tree node of that kind is created for it; with NODE the
given node is used."
  (let* ((activity (and *current-task* (task-activity *current-task*)))
         (task (%make-task :name name :parent *current-task* :index index
                           :group group :status :running :activity activity))
         (bindings (capture-inherited-specials))
         (parent-node *task-tree-node*)
         (node (or node
                   (and node-kind parent-node
                        (make-task-tree-node node-kind (or node-name name)
                                             :parent parent-node)))))
    (activity-change activity 1)
    (sb-sys:without-interrupts
      (bt:with-lock-held ((task-group-lock group))
        (push task (task-group-tasks group)))
      (setf (task-released task) nil)
      (setf (task-thread task)
            (run-in-task-thread
             (format nil "cpl ~a" name)
             (lambda (offer-thread)
               (unwind-protect
                    (progv (car bindings) (cdr bindings)
                      (let ((*current-task* task)
                            (*task-tree-node* parent-node)
                            (*evaporation-target* nil))
                        (execute-task task thunk node)))
                 (release-task task offer-thread))))))
    task))

(defun release-task (task offer-thread)
  "Note that TASK's thread has left the task's code, after calling OFFER-THREAD (which offers
the thread for another task)."
  (funcall offer-thread)
  (let ((group (task-group task)))
    (bt:with-lock-held ((task-group-lock group))
      (setf (task-released task) t))
    (notify-after-unlock (task-group-condition group))))

(defun wait-for-release (task)
  "Wait until TASK's thread has left the task's code."
  (let ((group (task-group task)))
    (bt:with-lock-held ((task-group-lock group))
      (loop until (task-released task)
            do (sb-thread:condition-wait (task-group-condition group) (task-group-lock group))))))

(defun evaporate-task (task)
  "Ask TASK's thread to unwind, unless it has finished already."
  (let ((thread (task-thread task)))
    (when (and thread
               (not (task-evaporate-requested task))
               (not (task-done-p task)))
      (setf (task-evaporate-requested task) t)
      (handler-case (bt:interrupt-thread thread (lambda () (evaporate-self task)))
        (error () nil)))))

(defun stop-plan-from-task (task)
  "Stop the plan TASK belongs to: mark its root task aborted, evaporate the root, and unwind
TASK's own thread."
  (let ((root (loop for tk = task then (task-parent tk)
                    while (task-parent tk)
                    finally (return tk))))
    (setf (task-aborted root) t)
    (unless (eq root task)
      (evaporate-task root))
    (setf (task-evaporating task) t)
    (throw task :evaporated)))

(defun evaporate-and-join (group)
  "Evaporate every unfinished task of GROUP and wait until all their threads have left them."
  (sb-sys:without-interrupts
    (let ((tasks (bt:with-lock-held ((task-group-lock group))
                   (copy-list (task-group-tasks group)))))
      (mapc #'evaporate-task tasks)
      (dolist (task tasks)
        (wait-for-release task)
        (unless (task-done-p task)
          (setf (task-status task) :evaporated)
          (note-task-status task))))))

(defun group-tasks-in-order (group)
  (sort (copy-list (task-group-tasks group)) #'< :key #'task-index))

(defun run-task-group (name thunks decide &key (node-kind :par-child) node-names)
  "Run each of THUNKS in its own child task and wait until DECIDE, called with
the tasks in textual order under the group lock, returns a non-NIL decision
\(:SUCCEEDED values) or (:FAILED condition). Unfinished children are evaporated
and all threads joined before this returns. Returns the decision."
  (let ((group (make-task-group)))
    (unwind-protect
         (progn
           (loop for (thunk . more) on thunks
                 for index from 0
                 do (spawn-task (format nil "~a child ~d" name (1+ index))
                                group index thunk
                                :node-kind node-kind
                                :node-name (or (nth index node-names)
                                               (format nil "child ~d" (1+ index))))
                    (when (and more *ordered-concurrency*)
                      (wait-until-quiet *current-task*)))
           (let ((tasks (group-tasks-in-order group))
                 (lock (task-group-lock group)))
             (bt:with-lock-held (lock)
               (loop
                 (let ((decision (funcall decide tasks)))
                   (when decision (return decision)))
                 (with-task-waiting (group)
                   (sb-thread:condition-wait (task-group-condition group) lock))))))
      (evaporate-and-join group))))

(defun resignal-failure (condition)
  "Signal CONDITION, a failure that came from a child task, in this task."
  (fail condition))

(defun call-on-plan-cpu (thunk)
  "Call THUNK, the top-level task of a plan in this thread: with *KEEP-PLANS-ON-ONE-CPU* and
*ORDERED-CONCURRENCY*, on the CPU it runs on now (*PLAN-CPU*), the thread's CPUs restored
afterwards. As is when this thread may run on one CPU only, or the system does not tell."
  (let* ((mask (and *keep-plans-on-one-cpu* *ordered-concurrency* (null *plan-cpu*)
                    (thread-cpu-mask)))
         (cpu (and mask (> (mask-cpu-count mask) 1) (current-cpu))))
    (if (and cpu (set-thread-cpu-mask (cpu-mask cpu)))
        (unwind-protect (let ((*plan-cpu* cpu) (*plan-free-mask* mask)) (funcall thunk))
          (set-thread-cpu-mask mask))
        (funcall thunk))))

(defun run-task-here (name group thunk node)
  "Run THUNK as the task NAME of GROUP in this thread (which runs no task), as SPAWN-TASK's
thread would: the task's bindings, its outcome in GROUP. Returns the task."
  (let ((task (%make-task :name name :parent nil :index 0 :group group :status :running
                          :thread sb-thread:*current-thread*
                          :activity (and *ordered-concurrency* (make-activity)))))
    (activity-change (task-activity task) 1)
    (bt:with-lock-held ((task-group-lock group))
      (push task (task-group-tasks group)))
    (let ((*current-task* task)
          (*task-tree-node* nil)
          (*task-in-caller-thread* task))
      (call-on-plan-cpu
       (lambda ()
         (unwind-protect
              ;; an interrupt from the keyboard (C-c) evaporates the task: leaving it from the
              ;; debugger (ABORT) is then no foreign exit
              (handler-bind ((sb-sys:interactive-interrupt
                               (lambda (c) (declare (ignore c)) (setf (task-evaporating task) t))))
                (execute-task task thunk node))
           (unless (task-done-p task)
             ;; unwound from outside the plan: nothing is left running
             (setf (task-status task) :evaporated))))))
    task))

(defun call-as-top-level (name thunk)
  "Run THUNK as the top-level task named NAME, with a fresh task tree, and wait
for it. Returns its values; a failure that escapes it is signalled here with
ERROR (a wrapped Lisp error is unwrapped first). Called from a thread that runs
no task (a REPL, a program), the task runs in that thread: no thread is started
and none waits; otherwise (a top-level inside a task whose *CURRENT-TASK* was
unbound) in a new thread."
  (when *current-task*
    (error 'nested-top-level-error :name name :outer *current-task*))
  (let* ((root (make-task-tree-node :top-level name))
         (group (make-task-group))
         (*task-tree-node* nil))
    (setf *last-task-tree* root)
    (let ((decision
            (unwind-protect
                 (if (null *evaporation-target*)
                     (let ((task (run-task-here (format nil "top-level ~a" name) group thunk root)))
                       (if (eq (task-status task) :succeeded)
                           (list :succeeded (task-values task))
                           (list (task-status task) (task-failure task))))
                     (unwind-protect
                          (progn
                            (spawn-task (format nil "top-level ~a" name) group 0 thunk :node root)
                            (let ((task (first (task-group-tasks group)))
                                  (lock (task-group-lock group)))
                              (bt:with-lock-held (lock)
                                (loop
                                  (case (task-status task)
                                    (:succeeded (return (list :succeeded (task-values task))))
                                    ((:failed :evaporated)
                                     (return (list (task-status task) (task-failure task)))))
                                  (sb-thread:condition-wait (task-group-condition group) lock)))))
                       (evaporate-and-join group)))
              (ignore-errors (flush-log)))))
      (destructuring-bind (status payload) decision
        (ecase status
          (:succeeded (values-list payload))
          (:failed (if (typep payload 'common-lisp-error-envelope)
                       (error (envelop-error payload))
                       (error payload)))
          (:evaporated (if (task-aborted (first (task-group-tasks group)))
                           (error 'plan-aborted :name name)
                           (error "The top-level task ~s was evaporated." name))))))))
