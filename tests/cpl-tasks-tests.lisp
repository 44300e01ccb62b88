;;;; Tests of CPL's task interface: status fluents, TOPLEVEL-TASK, WITH-TAGS and :TAG,
;;;; PARTIAL-ORDER, suspension, and SLEEP*, FL-PULSED, FL-VALUE-CHANGED, DEF-CPL-PARAMETER.

(defpackage :cram-cpl-tasks-tests
  (:use :cl :fiveam))

(in-package :cram-cpl-tasks-tests)

(def-suite cpl-tasks :in cram-plans-tests:all
  :description "CPL tasks as objects: status fluents, tags, partial order, suspension.")
(in-suite cpl-tasks)

(test tags-are-task-objects-with-status-fluents
  ;; checks run outside the plan's threads: collect inside, assert after
  (let ((seen '()) (before nil) (kind nil) (result nil) (dead nil))
    (cpl:top-level
      (cpl:with-tags
        (setf before (cpl:value (cpl:status first-step))
              kind (typep first-step 'cpl:tagged-task))
        (:tag first-step
          (push (cpl:value (cpl:status first-step)) seen)
          :one)
        (push (cpl:value (cpl:status first-step)) seen)
        (setf result (cpl:result first-step)
              dead (cpl:value (cpl:task-dead first-step)))))
    (is (eq :created before))
    (is-true kind)
    (is (equal '(:succeeded :running) seen))
    (is (equal '(:one) result))
    (is-true dead))
  (let ((tags (cpl:find-task-tree-nodes (lambda (n) (eq :tag (cpl:node-kind n))))))
    (is (= 1 (length tags)))
    (is (eq 'first-step (cpl:node-name (first tags))))))

(test a-failing-tag-fails
  (let ((status nil))
    (cpl:top-level
      (cpl:with-tags
        (cpl:with-failure-handling
            ((cpl:plan-failure (e) (declare (ignore e)) (return)))
          (:tag broken (cpl:fail "broken")))
        (setf status (cpl:value (cpl:status broken)))))
    (is (eq :failed status))))

(test partial-order-orders-tagged-steps
  (let ((order '()) (lock (bt:make-lock)))
    (flet ((note (x) (bt:with-lock-held (lock) (push x order))))
      (cpl:top-level
        (cpl:with-tags
          (cpl:partial-order
              ((:tag third (note :third))
               (:tag second (sleep 0.05) (note :second))
               (:tag first (sleep 0.1) (note :first)))
            (:order first second)
            (:order second third)))))
    (is (equal '(:first :second :third) (reverse order))))
  (signals error (macroexpand '(cpl:partial-order ((foo)) (:before a b)))))

(test toplevel-task-and-task-status
  (let (top status same other)
    (cpl:top-level
      (setf top (cpl:toplevel-task)
            status (cpl:value (cpl:status top)))
      (cpl:par
        (setf same (eq top (cpl:toplevel-task)))
        (setf other (not (eq top cpl:*current-task*)))))
    (is (typep top 'cpl:task))
    (is (eq :running status))
    (is-true same)
    (is-true other)
    (is (eq :succeeded (cpl:value (cpl:status top))) "the status fluent follows the task"))
  (is (null (cpl:toplevel-task))))

(test suspension-runs-handlers-and-waits
  (let ((events '()) (lock (bt:make-lock)) (counter 0) status frozen-ok resumed-ok)
    (flet ((note (x) (bt:with-lock-held (lock) (push x events))))
      (cpl:top-level
        (cpl:with-tags
          (cpl:pursue
            (:tag worker
              (cpl:on-suspension (note :suspended)
                (loop (incf counter) (sleep 0.005))))
            (progn
              (sleep 0.1)
              (cpl:with-task-suspended (worker :reason "testing")
                (setf status (cpl:value (cpl:status worker)))
                (let ((frozen counter))
                  (sleep 0.1)
                  (setf frozen-ok (= frozen counter))
                  (note :body)))
              (let ((before counter))
                (sleep 0.1)
                (setf resumed-ok (> counter before)))))))
      (is (eq :suspended status))
      (is-true frozen-ok "a suspended task does not run")
      (is-true resumed-ok "a woken task runs again")
      (is (equal '(:suspended :body) (reverse events)))))
  (signals error (cpl:suspend 42)))

(test sleep-star-and-fluent-helpers
  (let ((start (get-internal-real-time)))
    (cpl:sleep* 0.05)
    (is (>= (- (get-internal-real-time) start) (* 0.04 internal-time-units-per-second))))
  (let* ((f (cpl:make-fluent :value 1))
         (changed (cpl:fl-value-changed f))
         (pulsed (cpl:fl-pulsed f)))
    (is-false (cpl:value changed))
    (setf (cpl:value f) 1)
    (is-false (cpl:value changed) "the same value is no change")
    (is-true (cpl:value pulsed) "but it was pulsed")
    (setf (cpl:value f) 2)
    (is-true (cpl:value changed))
    (is-false (cpl:value changed) "reading it took the change")
    (signals error (cpl:fl-value-changed 42))))

(cpl:def-cpl-parameter *tasks-test-counter* 10 "A counter kept in a fluent.")

(test def-cpl-parameter-reads-and-sets-a-fluent
  (setf *tasks-test-counter* 10)
  (is (= 10 *tasks-test-counter*))
  (setf *tasks-test-counter* 11)
  (is (= 11 *tasks-test-counter*))
  (is (typep *cpl-parameter-*tasks-test-counter** 'cpl:fluent))
  (is (= 11 (cpl:value *cpl-parameter-*tasks-test-counter**))))

(test tags-are-found-outside-data-only
  (is (equal '(a b) (cpl::tag-names '((:tag a (:tag b 1)) '(:tag quoted 2) `(:tag ,(list 3)))))))
