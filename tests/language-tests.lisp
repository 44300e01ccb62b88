;;;; Tests of the plan language: failure handling, concurrency, fluents.

(defpackage :cram-language-tests
  (:use :cl :fiveam)
  (:shadowing-import-from :cram-language #:fail)
  (:import-from :cram-language
                #:top-level #:named-top-level #:seq #:par #:pursue #:try-all
                #:try-in-order #:try-each-in-order #:with-failure-handling
                #:retry #:with-retry-counters #:do-retry #:get-counter #:reset-counter
                #:plan-failure #:simple-plan-failure #:composite-failure
                #:composite-failures #:common-lisp-error-envelope
                #:make-fluent #:value #:wait-for #:whenever #:pulsed
                #:fl-and #:fl-or #:fl-not #:fl< #:fl> #:fl= #:fl-funcall))

(in-package :cram-language-tests)

(def-suite language :in cram-plans-tests:all
  :description "The plan language CPL and the common failures.")

(in-suite language)

(defun thread-count ()
  "The number of threads, without SBCL's finalizer thread (started on demand
by the garbage collector at any time) and the task threads waiting for a task."
  (count-if-not (lambda (thread) (member (bt:thread-name thread)
                                         (list "finalizer" cpl:*idle-task-thread-name*)
                                         :test #'equal))
                (bt:all-threads)))

(defun settled-thread-count (start)
  "The number of threads, after waiting up to 3 s for it to fall to START."
  (loop repeat 300
        for count = (thread-count)
        until (<= count start)
        do (cl:sleep 0.01)
        finally (return (thread-count))))

(defmacro deftest (name &body body)
  "A test that also checks that no thread is left behind."
  `(test ,name
     (let ((start (thread-count)))
       ,@body
       (is (= start (settled-thread-count start))
           "threads leaked: ~d at start, ~d after" start (thread-count)))))

(defun elapsed-since (start)
  (/ (- (get-internal-real-time) start) internal-time-units-per-second))

(define-condition failure-a (simple-plan-failure) ())
(define-condition failure-b (simple-plan-failure) ())
(define-condition failure-c (simple-plan-failure) ())

;;; with-failure-handling and retry counters

(deftest retries-exactly-n-times
  (let ((attempts 0) (left-inside nil))
    (let ((caught (handler-case
                      (top-level
                        (with-retry-counters ((tries 3))
                          (with-failure-handling
                              ((failure-a (e)
                                 (declare (ignore e))
                                 (do-retry tries (retry))
                                 (setf left-inside (get-counter tries))))
                            (incf attempts)
                            (fail 'failure-a :format-control "attempt ~d"
                                             :format-arguments (list attempts)))))
                    (plan-failure (c) c))))
      (is (= 4 attempts))
      (is (eql 0 left-inside))
      (is (typep caught 'failure-a))
      (is (string= "attempt 4" (princ-to-string caught))))))

(deftest return-leaves-with-value
  (is (equal '(:caught "boom 7")
             (top-level
               (with-failure-handling
                   ((plan-failure (e) (return (list :caught (princ-to-string e)))))
                 (fail "boom ~a" 7)
                 :not-reached)))))

(deftest success-returns-body-values
  (is (equal '(1 2)
             (multiple-value-list
              (top-level
                (with-failure-handling ((plan-failure () (return :no)))
                  (values 1 2)))))))

(deftest falling-through-resignals
  (let ((inner-saw nil))
    (is (eq :outer
            (top-level
              (with-failure-handling ((failure-a () (return :outer)))
                (with-failure-handling ((failure-a (e) (setf inner-saw (type-of e))))
                  (fail 'failure-a)
                  :inner-body)))))
    (is (eq 'failure-a inner-saw))))

(deftest or-clause-types
  (flet ((try-class (class)
           (handler-case
               (top-level
                 (with-failure-handling (((or failure-a failure-b) (e)
                                           (return (list :caught (type-of e)))))
                   (fail class)))
             (plan-failure (c) (list :escaped (type-of c))))))
    (is (equal '(:caught failure-a) (try-class 'failure-a)))
    (is (equal '(:caught failure-b) (try-class 'failure-b)))
    (is (equal '(:escaped failure-c) (try-class 'failure-c)))))

(deftest retry-counter-reset-and-unknown-name
  (let ((trace '()))
    (top-level
      (with-retry-counters ((outer 2))
        (with-retry-counters ((inner 1))
          (push (do-retry inner :ran) trace)
          (push (do-retry inner :ran) trace)
          (reset-counter inner)
          (push (get-counter inner) trace)
          (push (get-counter outer) trace))))
    (is (equal '(2 1 nil :ran) trace)))
  (signals error (macroexpand-1 '(do-retry no-such-counter (print 1))))
  (signals error (top-level (with-retry-counters ((c -1)) (get-counter c)))))

;;; fail

(deftest fail-forms
  (flet ((caught (thunk)
           (handler-case (top-level (funcall thunk))
             (serious-condition (c) c))))
    (let ((c (caught (lambda () (fail "no ~a found" "cup")))))
      (is (typep c 'simple-plan-failure))
      (is (string= "no cup found" (princ-to-string c))))
    (is (typep (caught (lambda () (fail))) 'simple-plan-failure))
    (let ((c (caught (lambda () (fail 'common-fail:navigation-pose-unreachable
                                      :description "pose in wall")))))
      (is (typep c 'common-fail:navigation-low-level-failure))
      (is (string= "pose in wall" (common-fail:description c))))
    ;; a description made when it is first read, once
    (let* ((made 0)
           (c (make-condition 'common-fail:manipulation-pose-unreachable
                              :description (lambda () (incf made) "arm in shelf"))))
      (is (= 0 made))
      (is (string= "arm in shelf" (common-fail:description c)))
      (is (search "MANIPULATION-POSE-UNREACHABLE: arm in shelf" (princ-to-string c)))
      (is (= 1 made))
      (let ((failed (caught (lambda () (fail c)))))
        (is (eq c failed))
        (is (string= "arm in shelf" (common-fail:description failed)))
        (is (= 1 made))))
    (signals error (common-fail:description (make-condition 'simple-error)))
    (let* ((object (make-condition 'failure-b))
           (c (caught (lambda () (fail object)))))
      (is (eq object c)))
    ;; a non-plan-failure condition becomes an ordinary error
    (is (typep (caught (lambda () (fail 'simple-error :format-control "plain")))
               'simple-error))
    (is (typep (caught (lambda () (fail 42))) 'error))
    (is (typep (caught (lambda () (fail 'no-such-condition-class))) 'error)))
  ;; outside any task, fail raises with ERROR
  (is (typep (handler-case (fail "outside") (error () :error) (plan-failure (c) c))
             'simple-plan-failure)))

(deftest fail-runs-handlers-before-unwinding
  (let ((order '()))
    (top-level
      (with-failure-handling ((failure-a () (push :handler order) (return)))
        (unwind-protect (fail 'failure-a)
          (push :cleanup order))))
    (is (equal '(:cleanup :handler) order))))

;;; top-level

(deftest top-level-resignals-same-object
  (let* ((inside nil)
         (outside (handler-case
                      (top-level
                        (handler-bind ((failure-b (lambda (c) (setf inside c))))
                          (fail 'failure-b)))
                    (failure-b (c) c))))
    (is (not (null inside)))
    (is (eq inside outside))))

(deftest top-level-lisp-error-unwrapped
  (let ((c (handler-case (top-level (par (error "plain ~a" 1) (cpl:sleep 5)))
             (error (c) c))))
    (is (typep c 'simple-error))
    (is (string= "plain 1" (princ-to-string c)))))

(deftest nested-top-level-is-an-error
  (is (typep (handler-case (top-level (top-level 1)) (error (c) c))
             'cpl:nested-top-level-error))
  (is (typep (handler-case (par 1 2) (error (c) c)) 'cpl:not-inside-plan-error))
  (is (typep (handler-case (pursue 1) (error (c) c)) 'cpl:not-inside-plan-error))
  (is (eq :top-level (cpl:node-name cpl:*last-task-tree*))))

(deftest named-top-level-and-current-task
  (is (equal '(t :demo)
             (named-top-level (:name :demo)
               (list (cpl:current-task-p) (cpl:node-name cpl:*task-tree-node*)))))
  (is (not (cpl:current-task-p))))

;;; par, pursue, try-*

(deftest par-returns-last-form-value
  (let ((start (get-internal-real-time)))
    (is (eq :second (top-level (par (progn (cpl:sleep 0.1) :first) :second))))
    (is (>= (elapsed-since start) 0.09))))

(deftest par-runs-concurrently
  (let ((a (make-fluent :name 'a)) (b (make-fluent :name 'b)) (first-result nil))
    (is (eq :b-seen
            (top-level
              (par (setf first-result (progn (setf (value a) t)
                                             (and (wait-for b :timeout 5) :a-seen)))
                   (progn (setf (value b) t)
                          (and (wait-for a :timeout 5) :b-seen)))))
        "the two children of PAR must run at the same time")
    (is (eq :a-seen first-result))))

(deftest par-failure-kills-siblings
  (let ((sibling-unwound nil) (iterations 0))
    (let ((c (handler-case
                 (top-level
                   (par (unwind-protect (loop (incf iterations) (cpl:sleep 0.005))
                          (setf sibling-unwound t))
                        (progn (cpl:sleep 0.05) (fail 'failure-c))))
               (plan-failure (c) c))))
      (is (typep c 'failure-c))
      (is (eq t sibling-unwound))
      (is (plusp iterations))
      (let ((frozen iterations))
        (cl:sleep 0.05)
        (is (= frozen iterations) "the killed sibling kept running")))))

(deftest evaporation-waits-for-deferred-section
  (let ((section-done nil) (after-section nil))
    (is (typep (handler-case
                   (top-level
                     (par (progn (cpl:with-evaporation-deferred
                                   (cl:sleep 0.15)
                                   (setf section-done t))
                                 (setf after-section t))
                          (progn (cpl:sleep 0.02) (fail 'failure-a))))
                 (plan-failure (c) c))
               'failure-a))
    (is (eq t section-done))
    (is (null after-section))))

(deftest nested-par-failure-kills-grandchildren
  (let ((unwound 0) (lock (bt:make-lock)))
    (flet ((forever ()
             (unwind-protect (loop (cpl:sleep 0.01))
               (bt:with-lock-held (lock) (incf unwound)))))
      (is (eq :recovered
              (top-level
                (with-failure-handling ((failure-a () (return :recovered)))
                  (par (par (forever) (forever))
                       (par (forever) (progn (cpl:sleep 0.05) (fail 'failure-a))))))))
      (is (= 3 unwound)))))

(deftest par-failure-handled-by-retry
  (let ((runs 0))
    (is (eq :done
            (top-level
              (with-retry-counters ((c 2))
                (with-failure-handling ((failure-a () (do-retry c (retry))))
                  (par (cpl:sleep 0.01)
                       (when (< (incf runs) 3) (fail 'failure-a)))
                  :done)))))
    (is (= 3 runs))))

(deftest pursue-returns-first-finisher
  (let ((slow-unwound nil) (start (get-internal-real-time)))
    (is (eq :fast (top-level
                    (pursue (unwind-protect (progn (cpl:sleep 10) :slow)
                              (setf slow-unwound t))
                            (progn (cpl:sleep 0.05) :fast)))))
    (is (< (elapsed-since start) 5))
    (is (eq t slow-unwound)))
  (is (typep (handler-case (top-level (pursue (cpl:sleep 10) (fail 'failure-b)))
               (plan-failure (c) c))
             'failure-b)))

(deftest try-all-semantics
  (is (eq :ok (top-level (try-all (fail 'failure-a) (progn (cpl:sleep 0.02) :ok)
                                  (fail 'failure-b)))))
  (let ((c (handler-case (top-level (try-all (fail 'failure-a) (fail 'failure-b)))
             (plan-failure (c) c))))
    (is (typep c 'composite-failure))
    (is (equal '(failure-a failure-b) (mapcar #'type-of (composite-failures c))))))

(deftest try-in-order-semantics
  (let ((order '()))
    (is (eq :third
            (top-level
              (try-in-order (progn (push 1 order) (fail 'failure-a))
                            (progn (push 2 order) (fail 'failure-b))
                            (progn (push 3 order) :third)
                            (progn (push 4 order) :fourth)))))
    (is (equal '(3 2 1) order)))
  (let ((c (handler-case
               (top-level (try-in-order (fail 'failure-a) (fail 'failure-b) (fail "c")))
             (plan-failure (c) c))))
    (is (typep c 'composite-failure))
    (is (equal '(failure-a failure-b simple-plan-failure)
               (mapcar #'type-of (composite-failures c))))
    (is (search "3 alternatives" (princ-to-string c)))))

(deftest try-each-in-order-semantics
  (is (eq :b (top-level
               (try-each-in-order (x '(:a :b :c))
                 (if (eq x :b) x (fail "not ~a" x))))))
  (let ((c (handler-case
               (top-level (try-each-in-order (x '(1 2)) (fail "no ~a" x)))
             (plan-failure (c) c))))
    (is (equal '("no 1" "no 2") (mapcar #'princ-to-string (composite-failures c))))))

(defvar *plan-parameter* :global)

(deftest children-inherit-specials
  (pushnew '*plan-parameter* cpl:*inherited-specials*)
  (unwind-protect
       (is (equal '(:bound :bound)
                  (let ((*plan-parameter* :bound))
                    (top-level (list *plan-parameter* (par :x *plan-parameter*))))))
    (setf cpl:*inherited-specials* (remove '*plan-parameter* cpl:*inherited-specials*))))
