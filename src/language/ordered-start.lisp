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

(defun %activity-change (activity delta &key (tell t))
  "ACTIVITY-CHANGE with ACTIVITY's lock held. True when no task runs any more; then, with
TELL, the starters are told at once (else the caller tells them once it has left the lock)."
  (setf (activity-changes activity) (logand (1+ (activity-changes activity)) most-positive-fixnum))
  (when (zerop (incf (activity-running activity) delta))
    (when tell (sb-thread:condition-broadcast (activity-quiet activity)))
    t))

(defun activity-change (activity delta)
  "Count DELTA more running tasks in ACTIVITY (NIL: none is counted); tell the starters when
none runs."
  (when activity
    (when (sb-thread:with-mutex ((activity-lock activity))
            (%activity-change activity delta :tell nil))
      (notify-after-unlock (activity-quiet activity)))))

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
          ;; as any wait: the plan may now be quiet for a starter further in
          (%activity-change activity -1)
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
            (%activity-change activity 1)))))))
