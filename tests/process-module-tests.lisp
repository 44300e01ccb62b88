;;;; Tests of asynchronous process modules and of process module aliases.

(defpackage :cram-process-module-tests
  (:use :cl :fiveam))

(in-package :cram-process-module-tests)

(def-suite process-modules :in cram-plans-tests:all
  :description "Asynchronous process modules: ON-INPUT, FINISH/FAIL-PROCESS-MODULE, monitoring.")
(in-suite process-modules)

;; designators of a class of their own, described by the function the module runs
(defclass job-designator (desig:designator) ())
(desig:register-designator-class job job-designator)

(defun job (function) (desig:make-designator :job function))

(cpm:def-asynchronous-process-module job-module ())

(defmethod cpm:on-input ((module job-module) designator)
  (funcall (desig:description designator) module designator))

(defun later (seconds thunk)
  "Run THUNK in a thread of its own after SECONDS."
  (sb-thread:make-thread (lambda () (sleep seconds) (funcall thunk))))

(defun now () (get-internal-real-time))

(test pm-execute-returns-before-the-module-finishes
  (let (finished-at returned-at)
    (cpm:with-process-modules-running ((:worker job-module))
      (cpm:pm-execute :worker (job (lambda (module designator)
                                     (later 0.2 (lambda ()
                                                  (setf finished-at (now))
                                                  (cpm:finish-process-module
                                                   module :designator designator))))))
      (setf returned-at (now))
      (cpm:monitor-process-module :worker))
    (is (and finished-at returned-at (> finished-at returned-at)))))

(test monitoring-single-designators
  (let (slow-done quick-monitored)
    (cpm:with-process-modules-running ((:worker job-module))
      (let ((slow (job (lambda (m d)
                         (later 0.3 (lambda ()
                                      (setf slow-done (now))
                                      (cpm:finish-process-module m :designator d))))))
            (quick (job (lambda (m d) (cpm:finish-process-module m :designator d)))))
        (cpm:pm-execute :worker slow)
        (cpm:pm-execute :worker quick)
        (cpm:monitor-process-module :worker :designators quick)
        (setf quick-monitored (now))
        (cpm:monitor-process-module :worker :designators (list slow))))
    (is (> slow-done quick-monitored))))

(define-condition job-failed (cpl:simple-plan-failure) ())

(test failures-reach-the-monitor
  (signals job-failed
    (cpm:with-process-modules-running ((:worker job-module))
      (cpm:pm-execute :worker (job (lambda (m d)
                                     (cpm:fail-process-module
                                      m (make-condition 'job-failed :format-control "no")
                                      :designator d))))
      (cpm:monitor-process-module :worker)))
  (signals job-failed
    (cpm:with-process-modules-running ((:worker job-module))
      (cpm:pm-execute :worker (job (lambda (m d) (declare (ignore m d))
                                     (cpl:fail 'job-failed :format-control "raised"))))
      (cpm:monitor-process-module :worker)))
  (signals error (cpm:finish-process-module :no-such-module))
  (signals error (cpm:fail-process-module :no-such-module 42)))

(test the-module-runs-only-inside-with-process-modules-running
  (let (worker)
    (cpm:with-process-modules-running ((:worker job-module))
      (setf worker (cdr (assoc :worker cpm::*asynchronous-modules*)))
      (is (typep worker 'job-module))
      (is (eq :worker (cpm:asynchronous-process-module-name worker)))
      (is (eq 'job-module (cpm:resolve-process-module-name :worker)))
      (is-true (cpm:process-module-running-p :worker)))
    (is-false (sb-thread:thread-alive-p (cpm::module-worker worker)) "the worker has stopped")
    (is-false (cpm:process-module-running-p :worker))
    (signals cpm:process-module-error (cpm:pm-execute :worker (job #'list)))))

(test aliases-of-synchronous-modules
  (cpm:def-process-module process-module-tests-echo (designator)
    (list :echo (desig:description designator)))
  (cpm:with-process-modules-running ((:echo process-module-tests-echo))
    (is (equal '(:echo "hi") (cpm:pm-execute :echo (job "hi")))))
  (signals error (cpm:with-process-modules-running ((:a :b :c)) t)))
