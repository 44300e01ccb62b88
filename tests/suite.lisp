;;;; The root FiveAM suite; every layer's suite is a child of ALL.

(defpackage :cram-plans-tests
  (:use :cl)
  (:export #:all #:run-all #:shared-models-directory #:calls-during))

(in-package :cram-plans-tests)

(fiveam:def-suite all :description "Every test of cram-plans.")

(defun run-all ()
  "Run suite ALL, print FiveAM's report and one closing line `N passed, N failed'.
Returns true when nothing failed. Counts are per check."
  (let ((results (fiveam:run 'all)))
    (fiveam:explain! results)
    (multiple-value-bind (ok failed skipped) (fiveam:results-status results)
      (declare (ignore ok))
      (format t "~&~d passed, ~d failed~%"
              (- (length results) (length failed) (length skipped))
              (length failed))
      (finish-output)
      (null failed))))

(defun shared-models-directory ()
  "../shared/models/ beside the checkout (as a namestring): reference models that tests and
benchmarks may read when present, never commit."
  (let ((dir (uiop:merge-pathnames* (make-pathname :directory '(:relative :up "shared" "models"))
                                    (asdf:system-source-directory "cram-plans"))))
    (namestring (or (probe-file dir) dir))))

(defun calls-during (name thunk)
  "Call THUNK; return how often the function NAME was called meanwhile, and THUNK's value."
  (let ((calls 0))
    (sb-int:encapsulate name 'count (lambda (f &rest args) (incf calls) (apply f args)))
    (let ((value (unwind-protect (funcall thunk)
                   (sb-int:unencapsulate name 'count))))
      (values calls value))))
