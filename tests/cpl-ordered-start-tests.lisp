;;;; Tests of ordered starts (CPL:*ORDERED-CONCURRENCY*, bound in projection): the children of
;;;; PAR and PURSUE start in textual order, each once the plan is quiet; children that wait on
;;;; fluents still run concurrently; a child that waits some other way holds the others up for
;;;; CPL:*ORDERED-START-TIMEOUT* at most; failures and evaporation work as without it.

(defpackage :cram-cpl-ordered-start-tests
  (:use :cl :fiveam))

(in-package :cram-cpl-ordered-start-tests)

(def-suite cpl-ordered-start :in cram-plans-tests:all
  :description "Ordered starts of concurrent children (projection's deterministic PAR).")
(in-suite cpl-ordered-start)

(defmacro ordered (&body body)
  "BODY in a top-level plan with ordered starts; the plan's value."
  `(let ((cpl:*ordered-concurrency* t)) (cpl:top-level ,@body)))

(defun note (cell x)
  "Push X onto the car of CELL, atomically (the children run in threads of their own)."
  (sb-ext:atomic-push x (car cell)))

(defun busy (seconds)
  "Work for SECONDS of real time without waiting on anything the plan knows."
  (let ((end (+ (get-internal-real-time) (* seconds internal-time-units-per-second))))
    (loop while (< (get-internal-real-time) end))))

(test children-start-in-textual-order
  ;; the first child works longest: without ordered starts the others overtake it
  (dotimes (k 20)
    (let ((seen (list '())))
      (ordered (cpl:par (progn (busy 0.002) (note seen :a)) (note seen :b) (note seen :c)))
      (is (equal '(:a :b :c) (reverse (car seen)))))))

(test nested-children-start-before-those-around-them
  (dotimes (k 10)
    (let ((seen (list '())))
      (ordered (cpl:par (progn (note seen 1)
                               (cpl:par (progn (busy 0.001) (note seen 2)) (note seen 3))
                               (note seen 4))
                        (note seen 5)
                        (cpl:par (note seen 6) (note seen 7))))
      (is (equal '(1 2 3 4 5 6 7) (reverse (car seen)))))))

(test without-ordered-starts-children-run-at-once
  ;; the contrast: the slow first child is overtaken
  (let ((seen (list '())))
    (cpl:top-level (cpl:par (progn (busy 0.05) (note seen :a)) (note seen :b)))
    (is (equal '(:b :a) (reverse (car seen))))))

(test children-waiting-on-fluents-still-run-concurrently
  ;; the first child waits for what the second does; then for what the third does
  (let ((seen (list '())) (ready (cpl:make-fluent :value nil)) (done (cpl:make-fluent :value nil)))
    (is (eq :finished
            (ordered (cpl:par (progn (note seen :waiting) (cpl:wait-for ready) (note seen :woken)
                                     (cpl:wait-for done) (note seen :last))
                              (progn (note seen :second) (setf (cpl:value ready) t))
                              (progn (note seen :third) (setf (cpl:value done) t)))
                     :finished)))
    (let ((order (reverse (car seen))))
      (is (equal '(:waiting :second) (subseq order 0 2)))
      (is (< (position :woken order) (position :last order)))
      (is (< (position :third order) (position :last order))))))

(test a-child-waiting-otherwise-holds-the-others-up-for-the-timeout-only
  ;; the first child polls a variable the second sets: not a wait the plan knows about
  (let ((flag (list nil)) (start (get-internal-real-time)))
    (ordered (cpl:par (loop until (car flag) do (sleep 0.001)) (setf (car flag) t)))
    (let ((seconds (/ (- (get-internal-real-time) start) internal-time-units-per-second)))
      (is (< seconds (+ cpl:*ordered-start-timeout* 1)) "took ~,3f s" seconds))))

(test failures-and-pursue-with-ordered-starts
  (let ((seen (list '())))
    ;; a failing first child: the failure comes out, the later children are evaporated or
    ;; never run
    (signals cpl:simple-plan-failure
      (ordered (cpl:par (cpl:fail "first") (note seen :second))))
    ;; PURSUE: the first child waits forever on a fluent; the second decides
    (is (eq :second (ordered (cpl:pursue (cpl:wait-for (cpl:make-fluent :value nil))
                                         (progn (note seen :pursued) :second)))))
    (is (member :pursued (car seen)))))
