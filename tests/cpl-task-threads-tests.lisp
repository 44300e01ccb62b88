;;;; Tests of the threads plan tasks run in: a finished task's thread runs the next task, keeps
;;;; nothing of the task before, and a late evaporation request meant for the task before does
;;;; not reach the next one.

(defpackage :cram-cpl-task-threads-tests
  (:use :cl :fiveam))

(in-package :cram-cpl-task-threads-tests)

(def-suite cpl-task-threads :in cram-plans-tests:all
  :description "The threads plan tasks run in: reuse, bindings, late evaporation requests.")
(in-suite cpl-task-threads)

(defun make-barrier (n)
  "A function that returns once N calls of it have begun (or after 5 s): branches of a PAR that
call it all run at the same time, each in a thread of its own, however fast each one is."
  (let ((arrived (list 0)))
    (lambda ()
      (sb-ext:atomic-incf (car arrived))
      (loop repeat 5000 while (< (car arrived) n) do (sleep 0.001)))))

(defun par-threads ()
  "The threads the two branches of a PAR ran in."
  (let ((a nil) (b nil) (meet (make-barrier 2)))
    (cpl:top-level
      (cpl:par (progn (funcall meet) (setf a sb-thread:*current-thread*))
               (progn (funcall meet) (setf b sb-thread:*current-thread*))))
    (list a b)))

(defmacro with-idle-limit ((n) &body body)
  "Run BODY with at most N idle task threads (the threads read the global value), the idle
threads stopped before and after."
  (let ((old (gensym)))
    `(let ((,old cpl:*max-idle-task-threads*))
       (cpl:stop-idle-task-threads)
       (unwind-protect (progn (setf cpl:*max-idle-task-threads* ,n) ,@body)
         (setf cpl:*max-idle-task-threads* ,old)
         (cpl:stop-idle-task-threads)))))

(defun idle-threads ()
  (remove cpl:*idle-task-thread-name* (sb-thread:list-all-threads)
          :key #'sb-thread:thread-name :test-not #'equal))

(test finished-task-threads-run-the-next-tasks
  (with-idle-limit (8)
    (let ((first (par-threads)) (second (par-threads)))
      (is (= 2 (length (remove-duplicates first))))
      (is (subsetp second first) "the second PAR started new threads: ~s, then ~s" first second)
      (is (= 2 (length (idle-threads))))
      (is (every (lambda (th) (equal cpl:*idle-task-thread-name* (sb-thread:thread-name th))) second))
      (is (= 2 (cpl:stop-idle-task-threads)))
      (is (null (idle-threads)))
      (is (notany #'sb-thread:thread-alive-p first)))))

(test no-idle-threads-when-the-limit-is-zero
  (with-idle-limit (0)
    (let ((threads (par-threads)))
      (is (null (idle-threads)))
      (loop repeat 100 while (some #'sb-thread:thread-alive-p threads) do (sleep 0.01))
      (is (notany #'sb-thread:thread-alive-p threads)))))

(test idle-threads-stay-bounded
  (with-idle-limit (3)
    (let ((meet (make-barrier 6)))
      (cpl:top-level (cpl:par (funcall meet) (funcall meet) (funcall meet)
                              (funcall meet) (funcall meet) (funcall meet))))
    (is (= 3 (length (idle-threads))))))

(defvar *inherited* :global "A special the tests' plans inherit.")
(pushnew '*inherited* cpl:*inherited-specials*)

(test a-task-sees-its-own-bindings-not-those-of-the-task-before
  (with-idle-limit (8)
    ;; the two branches push at the same time: atomically, into the car of a cons
    (let ((seen (list '())) (meet (make-barrier 2)) (meet-again (make-barrier 2)))
      (let ((*inherited* :first))
        (cpl:top-level (cpl:par (progn (funcall meet) (sb-ext:atomic-push *inherited* (car seen)))
                                (progn (funcall meet) (sb-ext:atomic-push *inherited* (car seen))))))
      (cpl:top-level (cpl:par (progn (funcall meet-again)
                                     (sb-ext:atomic-push *inherited* (car seen)))
                              (progn (funcall meet-again)
                                     (sb-ext:atomic-push *inherited* (car seen)))))
      (is (equal '(:global :global :first :first) (car seen)))
      ;; a task thread waiting for work holds no binding of a task (NIL: none of its own)
      (is (= 2 (length (idle-threads))))
      (is (every (lambda (th)
                   (member (sb-thread:symbol-value-in-thread '*inherited* th nil) '(nil :global)))
                 (idle-threads))))))

(test a-late-evaporation-request-does-not-reach-the-next-task
  (with-idle-limit (8)
   (let ((old nil) (thread nil) (reused nil) (done nil))
    (cpl:top-level (cpl:par (setf old cpl:*current-task* thread sb-thread:*current-thread*)))
    (is (cpl:task-done-p old))
    (cpl:top-level
      (cpl:par (progn
                 (setf reused (eq thread sb-thread:*current-thread*))
                 ;; the interrupt an evaporation of the old task sends, arriving now
                 (sb-thread:interrupt-thread sb-thread:*current-thread*
                                             (lambda () (cpl::evaporate-self old)))
                 (cpl:sleep 0.02)
                 (setf done t))))
    (is (eq t reused) "the PAR child did not reuse the thread")
    (is (eq t done) "the next task was unwound by a request for the one before"))))

(defun within-seconds (seconds thunk)
  "THUNK's value when it returns within SECONDS (run in a thread of its own), else :TIMEOUT: a
lost wake-up shows as a timeout, not as a hung test run."
  (let ((thread (sb-thread:make-thread thunk :name "hand-over test")))
    (multiple-value-bind (value status) (sb-thread:join-thread thread :timeout seconds :default :timeout)
      (declare (ignore status))
      (when (eq value :timeout) (ignore-errors (sb-thread:terminate-thread thread)))
      value)))

(test many-hand-overs-are-never-lost
  ;; the wake-ups come after the locks are left (CPL::NOTIFY-AFTER-UNLOCK, the task threads'
  ;; pool): a thousand PARs in turn, each child ending at once or after a short wait, with and
  ;; without ordered starts, all end and each child ran once
  (with-idle-limit (4)
    (dolist (ordered '(t nil))
      (let ((result
              (within-seconds
               60 (lambda ()
                    (let ((cpl::*ordered-concurrency* ordered) (runs (list 0)))
                      (cpl:top-level
                        (dotimes (i 1000)
                          (cpl:par (sb-ext:atomic-incf (car runs))
                                   (progn (when (zerop (mod i 7)) (sleep 0.0001))
                                          (sb-ext:atomic-incf (car runs)))
                                   (sb-ext:atomic-incf (car runs)))))
                      (car runs))))))
        (is (eql 3000 result) "ordered starts ~a: ~s" ordered result)))))

(defun thread-cpus () (cpl::mask-cpus (cpl::thread-cpu-mask)))

(defun par-cpus (&key (ordered t))
  "The CPUs the top-level task and the two children of a PAR may run on, with ordered starts as
in projection (ORDERED) or without: (top-level first-child second-child plan-cpu)."
  (let ((cpl::*ordered-concurrency* ordered) (top nil) (a nil) (b nil) (plan nil))
    (cpl:top-level
      (setf top (thread-cpus) plan cpl:*plan-cpu*)
      (cpl:par (setf a (thread-cpus)) (setf b (thread-cpus))))
    (list top a b plan)))

(test a-projected-plan-keeps-its-threads-on-one-cpu
  (let ((before (thread-cpus)))
    (if (< (length before) 2)
        (pass "this thread may run on one CPU only: nothing to keep")
        (with-idle-limit (4)
          (destructuring-bind (top a b plan) (par-cpus)
            (is (integerp plan))
            (is (equal (list plan) top) "the top-level task runs on the plan's CPU")
            (is (equal top a) "a child on another CPU: ~s ~s" top a)
            (is (equal top b)))
          (is (equal before (thread-cpus)) "the caller's CPUs come back after the plan")
          ;; the same threads run a plan without ordered starts on any CPU again
          (destructuring-bind (top a b plan) (par-cpus :ordered nil)
            (is (null plan))
            (is (equal before top))
            (is (equal before a) "a task thread kept its plan's CPU: ~s" a)
            (is (equal before b)))
          (let ((cpl:*keep-plans-on-one-cpu* nil))
            (destructuring-bind (top a b plan) (par-cpus)
              (is (null plan))
              (is (equal before top))
              (is (equal before a))
              (is (equal before b))))))))
