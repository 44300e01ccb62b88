;;;; Ordered starts of concurrent children. The children of PAR, PURSUE and TRY-ALL run in
;;;; threads of their own; in projection, where every motion is an instant, which of two
;;;; children that both move the robot goes first is up to the threads, and so the belief state
;;;; each motion starts from (a gripper opening while the arm reaches, say) differs from run to
;;;; run. Under *ORDERED-CONCURRENCY* a child starts only once the plan is quiet: every task of
;;;; the plan started so far has ended or waits (on a fluent, or for its own children). A plan
;;;; whose children coordinate through fluents still runs concurrently; one whose children just
;;;; act runs them one after the other in textual order, the same way every time.

(in-package :cram-language)

(defvar *ordered-concurrency* nil
  "When true (a projection environment binds it), the children of PAR, PURSUE and TRY-ALL start
one at a time: each waits until every task of the plan started before it has ended or waits on
a fluent or for its own children (or until *ORDERED-START-TIMEOUT* has passed). NIL: they all
start at once, as on a robot.")

(defparameter *ordered-start-timeout* 0.05d0
  "Seconds a child waits for the plan to become quiet before it starts anyway (a sibling that
waits in some other way than on a fluent, e.g. polling, must not hold the others forever).")

(defstruct (activity (:constructor make-activity ()))
  "How many tasks of one plan run (not waiting), and the tasks waiting to start a child, the
most recent first."
  (lock (sb-thread:make-mutex :name "cpl plan activity"))
  (quiet (sb-thread:make-waitqueue :name "cpl plan quiet"))
  (running 0 :type fixnum)
  (starters '()))

(defun activity-change (activity delta)
  "Count DELTA more running tasks in ACTIVITY (NIL: none is counted); tell the starters when
none runs."
  (when activity
    (sb-thread:with-mutex ((activity-lock activity))
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

(defun wait-until-quiet (task)
  "Before TASK starts its next child: wait until no task of its plan runs and TASK is the most
recent of the tasks waiting so (a nested PAR's children start before those of the one around
it), or *ORDERED-START-TIMEOUT* has passed. No wait without *ORDERED-CONCURRENCY*."
  (let ((activity (and task (task-activity task))))
    (when activity
      (let ((deadline (+ (monotonic-microseconds)
                         (round (* *ordered-start-timeout* 1000000)))))
        (sb-thread:with-mutex ((activity-lock activity))
          (push task (activity-starters activity))
          (decf (activity-running activity))
          (unwind-protect
               (loop until (and (<= (activity-running activity) 0)
                                (eq (first (activity-starters activity)) task))
                     do (let ((left (- deadline (monotonic-microseconds))))
                          (when (<= left 0) (return))
                          (sb-thread:condition-wait (activity-quiet activity) (activity-lock activity)
                                                    :timeout (/ left 1000000d0))))
            (setf (activity-starters activity) (remove task (activity-starters activity) :count 1))
            (incf (activity-running activity))))))))
