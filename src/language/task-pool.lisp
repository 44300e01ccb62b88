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
  (cpu nil)       ; the CPU the next job's plan keeps to (*PLAN-CPU*), or NIL
  (pinned nil)    ; the CPU the thread is kept on now, or NIL (any it may use)
  (free-mask nil) ; its CPU mask before it was first kept on one
  (thread nil))

;;; ---- the CPU of a plan ----------------------------------------------------------------------
;;; A projected plan runs one task at a time (*ORDERED-CONCURRENCY*): its threads hand the work
;;; to each other. On one CPU a hand-over is a switch of threads; across CPUs it first wakes the
;;; other CPU, which costs more than the work of a short motion. So a plan in projection keeps
;;; its threads on the CPU its top-level task started on (*PLAN-CPU*), for the run.

(defparameter *keep-plans-on-one-cpu* t
  "When true, a plan run under *ORDERED-CONCURRENCY* (projection) keeps its threads, the
top-level task's among them, on the CPU the top-level task starts on, until it ends (the
caller's thread gets its CPUs back then). NIL: the threads run wherever the system puts them.")

(defvar *plan-cpu* nil
  "The CPU the running plan's threads keep to, or NIL. Task threads inherit it.")

(defvar *plan-free-mask* nil
  "While *PLAN-CPU* is set: the CPU mask the plan's top-level thread had before, which a task
thread started by the plan (and so kept on the plan's CPU from its start) gets back after it.")

(defconstant +cpu-mask-bytes+ 128 "The size of Linux's cpu_set_t (1024 CPUs).")

(defmacro %affinity-call (name mask)
  "Call sched_getaffinity or sched_setaffinity (NAME, a string) for the calling thread with the
byte vector MASK; true when it succeeded."
  (let ((m (gensym "MASK")))
    `(let ((,m ,mask))
       (sb-sys:with-pinned-objects (,m)
         (zerop (sb-alien:alien-funcall
                 (sb-alien:extern-alien ,name (function sb-alien:int sb-alien:int
                                                        sb-alien:unsigned-long
                                                        sb-alien:system-area-pointer))
                 0 +cpu-mask-bytes+ (sb-sys:vector-sap ,m)))))))

(defun thread-cpu-mask ()
  "The CPU mask of the calling thread (a byte vector), or NIL when the system does not tell."
  (let ((mask (make-array +cpu-mask-bytes+ :element-type '(unsigned-byte 8) :initial-element 0)))
    (and (%affinity-call "sched_getaffinity" mask) mask)))

(defun set-thread-cpu-mask (mask)
  "Let the calling thread run on the CPUs of MASK (a byte vector of THREAD-CPU-MASK). True when
done."
  (%affinity-call "sched_setaffinity" mask))

(defun mask-cpu-count (mask)
  "How many CPUs the CPU mask MASK (a byte vector of THREAD-CPU-MASK) holds."
  (loop for byte across mask sum (logcount byte)))

(defun mask-cpus (mask)
  "The CPUs (ascending) of the CPU mask MASK (a byte vector of THREAD-CPU-MASK)."
  (loop for cpu below (* 8 (length mask))
        when (logbitp (mod cpu 8) (aref mask (floor cpu 8))) collect cpu))

(defun cpu-mask (cpu)
  "The CPU mask of CPU alone."
  (let ((mask (make-array +cpu-mask-bytes+ :element-type '(unsigned-byte 8) :initial-element 0)))
    (setf (aref mask (floor cpu 8)) (ash 1 (mod cpu 8)))
    mask))

(defun current-cpu ()
  "The CPU the calling thread runs on, or NIL when the system does not tell."
  (let ((cpu (sb-alien:alien-funcall (sb-alien:extern-alien "sched_getcpu" (function sb-alien:int)))))
    (and (<= 0 cpu (1- (* 8 +cpu-mask-bytes+))) cpu)))

(defun keep-slot-on-cpu (slot)
  "In SLOT's thread, before its job: keep it on the CPU of the job's plan (SLOT's CPU), or give
it back the CPUs it had when the job has none."
  (let ((cpu (task-thread-slot-cpu slot)))
    (unless (eql cpu (task-thread-slot-pinned slot))
      (cond (cpu
             (unless (task-thread-slot-free-mask slot)
               (setf (task-thread-slot-free-mask slot) (thread-cpu-mask)))
             (setf (task-thread-slot-pinned slot)
                   (and (set-thread-cpu-mask (cpu-mask cpu)) cpu)))
            ((task-thread-slot-free-mask slot)
             (set-thread-cpu-mask (task-thread-slot-free-mask slot))
             (setf (task-thread-slot-pinned slot) nil))))))

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
      (keep-slot-on-cpu slot)
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
               (setf (task-thread-slot-job slot) job
                     (task-thread-slot-cpu slot) *plan-cpu*))
             ;; woken after the lock is free, the thread takes the job without waiting for the
             ;; lock (a wake-up under the lock makes it wait for the lock, a second wake-up)
             (sb-thread:condition-notify (task-thread-slot-ready slot))
             thread))
          (t
           (let ((slot (make-task-thread-slot)))
             ;; a new thread starts with the CPUs of the thread that starts it: the plan's
             (setf (task-thread-slot-cpu slot) *plan-cpu*
                   (task-thread-slot-pinned slot) *plan-cpu*
                   (task-thread-slot-free-mask slot) (and *plan-cpu* *plan-free-mask*))
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
