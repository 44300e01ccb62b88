;;;; The threads plan tasks run in. Starting a thread costs about 0.1 ms (its stack is mapped
;;;; and faulted in); a plan of a few dozen key poses starts a handful of tasks per run, so a
;;;; thread that has finished its task waits for the next one instead of exiting. At most
;;;; *MAX-IDLE-TASK-THREADS* wait; the others exit as before. A waiting thread holds nothing of
;;;; the task it ran (its bindings were unwound with it) and carries a name of its own, so that
;;;; tools that look for the running plan's threads ("cpl ..." names) do not see it.

(in-package :cram-language)

(defparameter *max-idle-task-threads* 8
  "How many finished task threads wait for a next task (0: every task thread exits when its task
ends, as a fresh thread per task).")

(defparameter *idle-task-thread-name* "plan thread (idle)"
  "The name of a task thread while it waits for a task.")

(defstruct (task-thread-slot (:constructor make-task-thread-slot ()))
  (lock (sb-thread:make-mutex :name "plan thread"))
  (ready (sb-thread:make-waitqueue :name "plan thread"))
  (job nil)
  (thread nil))

(defvar *idle-task-threads* '() "Slots of the task threads waiting for a task.")
(defvar *idle-task-threads-lock* (sb-thread:make-mutex :name "plan threads"))

(defun next-job (slot)
  "Wait for SLOT's next job and take it: a function, or :EXIT."
  (sb-thread:with-mutex ((task-thread-slot-lock slot))
    (loop until (task-thread-slot-job slot)
          do (sb-thread:condition-wait (task-thread-slot-ready slot) (task-thread-slot-lock slot)))
    (shiftf (task-thread-slot-job slot) nil)))

(defun offer-task-thread (slot)
  "While there is room, name this thread idle and put SLOT among the idle task threads (a job
handed to it now waits in SLOT until this thread has come back for it). True when it was put."
  (sb-thread:with-mutex (*idle-task-threads-lock*)
    (when (< (length *idle-task-threads*) *max-idle-task-threads*)
      ;; named inside the lock: a thread that exits instead never carries the idle name, and
      ;; no job can be handed to SLOT (renaming it) before it is named
      (setf (sb-thread:thread-name sb-thread:*current-thread*) *idle-task-thread-name*)
      (push slot *idle-task-threads*)
      (return-from offer-task-thread t)))
  ;; no room: this thread exits, under a name that is neither a task's nor an idle thread's
  (setf (sb-thread:thread-name sb-thread:*current-thread*) "plan thread (exiting)")
  nil)

(defun task-thread-loop (slot first-job)
  "The body of a task thread: run FIRST-JOB, then, while it offers this thread for the next
one, wait for and run that."
  (let ((job first-job))
    (loop
      (when (eq job :exit) (return))
      (let ((offered nil))
        (funcall (the function job) (lambda () (setf offered (offer-task-thread slot))))
        (setf job nil)
        (unless offered (return)))
      (setf job (next-job slot)))))

(defun run-in-task-thread (name job)
  "Run JOB in a thread named NAME: an idle task thread when there is one, else a new one. JOB,
a function of one argument, handles every condition and exit of its own; it is called with a
function of no arguments that it calls once when it is done, before it tells anyone so: that
offers the thread for the next job. Returns the thread."
  (let ((slot (sb-thread:with-mutex (*idle-task-threads-lock*)
                (pop *idle-task-threads*))))
    (cond (slot
           (let ((thread (task-thread-slot-thread slot)))
             (setf (sb-thread:thread-name thread) name)
             (sb-thread:with-mutex ((task-thread-slot-lock slot))
               (setf (task-thread-slot-job slot) job))
             ;; woken after the lock is free, the thread takes the job without waiting for the
             ;; lock (a wake-up under the lock makes it wait for the lock, a second wake-up)
             (sb-thread:condition-notify (task-thread-slot-ready slot))
             thread))
          (t
           (let ((slot (make-task-thread-slot)))
             (setf (task-thread-slot-thread slot)
                   (sb-thread:make-thread (lambda () (task-thread-loop slot job)) :name name)))))))

(defun stop-idle-task-threads ()
  "Let every idle task thread exit and wait for them (before saving a core, or to give their
stacks back). Threads running a task are not touched. Returns how many exited."
  (let ((slots (sb-thread:with-mutex (*idle-task-threads-lock*)
                 (shiftf *idle-task-threads* '()))))
    (dolist (slot slots)
      (sb-thread:with-mutex ((task-thread-slot-lock slot))
        (setf (task-thread-slot-job slot) :exit)
        (sb-thread:condition-notify (task-thread-slot-ready slot))))
    (dolist (slot slots)
      (sb-thread:join-thread (task-thread-slot-thread slot) :default nil))
    (length slots)))

;; a core cannot be saved while other threads run
(pushnew 'stop-idle-task-threads sb-ext:*save-hooks*)
