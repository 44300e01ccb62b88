;;;; Ordered starts of concurrent children. The children of PAR, PURSUE and TRY-ALL run in
;;;; threads of their own; in projection, where every motion is an instant, which of two
;;;; children that both move the robot goes first is up to the threads, and so the belief state
;;;; each motion starts from (a gripper opening while the arm reaches, say) differs from run to
;;;; run. Under *ORDERED-CONCURRENCY* a child starts only once the plan is quiet: every task of
;;;; the plan started so far has ended or waits (on a fluent, or for its own children). A plan
;;;; whose children coordinate through fluents still runs concurrently; one whose children just
;;;; act runs them one after the other in textual order, the same way every time.

(in-package :cram-language)

(defstruct (activity (:constructor make-activity ()))
  "How many tasks of one plan run (not waiting), and the tasks waiting to start a child, the
most recent first."
  (lock (sb-thread:make-mutex :name "cpl plan activity"))
  (quiet (sb-thread:make-waitqueue :name "cpl plan quiet"))
  (running 0 :type fixnum)
  (changes 0 :type fixnum)   ; how often RUNNING changed
  (starters '()))

(defun activity-change (activity delta)
  "Count DELTA more running tasks in ACTIVITY (NIL: none is counted); tell the starters when
none runs."
  (when activity
    (sb-thread:with-mutex ((activity-lock activity))
      (setf (activity-changes activity) (logand (1+ (activity-changes activity)) most-positive-fixnum))
      (when (zerop (incf (activity-running activity) delta))
        (sb-thread:condition-broadcast (activity-quiet activity))))))

;;; A task that waits is not counted as running. Its waker counts it again before going on
;;; (a child that ends wakes its parent waiting for the children's decision, a pulse wakes the
;;; tasks waiting on the fluent), so that the plan never looks quiet between the two. Each of
;;; these runs under the lock of what is waited on (the task group's, the fluent's).

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

(defun end-task-wait (task on)
  "TASK's wait on ON ended: counted as running again, unless its waker did that."
  (wake-waiting-task task on))

(defmacro with-task-waiting ((on) &body body)
  "Run BODY, a wait of the current task on ON (any object) that no fluent or task group
expresses (a projection clock's, say), with the task not counted as running: under
*ORDERED-CONCURRENCY* its siblings may start meanwhile."
  (let ((task (gensym "TASK")) (what (gensym "ON")))
    `(let ((,task *current-task*) (,what ,on))
       (begin-task-wait ,task ,what)
       (unwind-protect (progn ,@body)
         (end-task-wait ,task ,what)))))

(defun task-depth (task)
  "How many tasks TASK lies below its plan's top-level task."
  (loop for tk = (task-parent task) then (task-parent tk) while tk count t))

(defun next-starter (activity)
  "Of the tasks of ACTIVITY waiting to start a child, the one to go on first: the deepest in
the task tree (a nested PAR's children start before the next children of the one around it),
of those the first to wait."
  (let ((best nil) (best-depth -1))
    (dolist (task (reverse (activity-starters activity)) best)
      (let ((depth (task-depth task)))
        (when (> depth best-depth) (setf best task best-depth depth))))))

(defun wait-until-quiet (task)
  "Before TASK starts its next child: wait until no task of its plan runs and TASK is the next
of the tasks waiting so (NEXT-STARTER), or *ORDERED-START-TIMEOUT* has passed with nothing
happening in the plan. No wait without *ORDERED-CONCURRENCY*."
  (let ((activity (and task (task-activity task))))
    (when activity
      (let* ((patience (round (* *ordered-start-timeout* 1000000)))
             (deadline (+ (monotonic-microseconds) patience))
             (seen -1))
        (sb-thread:with-mutex ((activity-lock activity))
          (push task (activity-starters activity))
          (decf (activity-running activity))
          (unwind-protect
               (loop until (and (<= (activity-running activity) 0)
                                (eq (next-starter activity) task))
                     do (let ((now (monotonic-microseconds)))
                          ;; the plan goes on: the timeout counts from its last change
                          (unless (= seen (activity-changes activity))
                            (setf seen (activity-changes activity)
                                  deadline (+ now patience)))
                          (when (<= deadline now) (return))
                          (sb-thread:condition-wait (activity-quiet activity) (activity-lock activity)
                                                    :timeout (/ (- deadline now) 1000000d0))))
            (setf (activity-starters activity) (remove task (activity-starters activity) :count 1))
            (incf (activity-running activity))))))))
