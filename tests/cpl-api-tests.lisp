;;;; Tests of CPL's package as CRAM users use it: (:use :cpl) alone, FAIL as a generic function.

(defpackage :cram-cpl-api-tests
  (:use :cl :fiveam))

(in-package :cram-cpl-api-tests)

(def-suite cpl-api :in cram-plans-tests:all
  :description "CPL's package and FAIL as CRAM user code sees them.")
(in-suite cpl-api)

(test cpl-alone-is-a-working-package
  (let ((package (or (find-package :cram-cpl-api-user)
                     (make-package :cram-cpl-api-user :use '(:cpl)))))
    (let ((*package* package))
      (is (= 61 (eval (read-from-string
                       "(progn (defun add-one (x) (+ x 1))
                               (let ((xs (list 1 2))) (add-one (* 20 (reduce #'+ xs)))))")))))
    (is (eq 'cl:car (find-symbol "CAR" package)))
    (is (eq 'cpl:sleep (find-symbol "SLEEP" package)) "CPL's own SLEEP, not CL's")
    (is (not (eq 'cpl:sleep 'cl:sleep)))
    (is (eq 'cpl:top-level (find-symbol "TOP-LEVEL" package)))
    (delete-package package)))

(test cpl-exports-every-common-lisp-symbol-but-sleep
  (let ((missing '()))
    (do-external-symbols (s :common-lisp)
      (unless (or (eq s 'cl:sleep)
                  (eq (nth-value 1 (find-symbol (symbol-name s) :cpl)) :external))
        (push s missing)))
    (is (null missing))))

(defclass gripper-report ()
  ((force :initarg :force :reader gripper-report-force)))

(define-condition gripper-too-weak (cpl:simple-plan-failure)
  ((force :initarg :force :reader gripper-too-weak-force)))

(defmethod cpl:fail ((report gripper-report) &rest arguments)
  (declare (ignore arguments))
  (cpl:fail 'gripper-too-weak :force (gripper-report-force report)
                              :format-control "Gripper force ~a N."
                              :format-arguments (list (gripper-report-force report))))

(test fail-is-a-generic-function-users-specialise
  (is (typep #'cpl:fail 'generic-function))
  (let ((caught (cpl:top-level
                  (cpl:with-failure-handling
                      ((gripper-too-weak (e) (return (gripper-too-weak-force e))))
                    (cpl:fail (make-instance 'gripper-report :force 3.5))))))
    (is (= 3.5 caught)))
  (signals gripper-too-weak (cpl:fail (make-instance 'gripper-report :force 1))))

(test fail-keeps-its-default-behaviour
  (signals cpl:simple-plan-failure (cpl:fail))
  (let ((no-arguments (copy-list '())))
    (signals cpl:simple-plan-failure (apply #'cpl:fail no-arguments))
    (is (string= "Plan failure."
                 (handler-case (apply #'cpl:fail no-arguments)
                   (cpl:plan-failure (e) (princ-to-string e))))))
  (is (string= "bad 7"
               (handler-case (cpl:fail "bad ~a" 7) (cpl:plan-failure (e) (princ-to-string e)))))
  (signals error (cpl:fail 42)))
