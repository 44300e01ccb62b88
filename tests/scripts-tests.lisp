;;;; Checks written as shell scripts (models, ROS launch files), run as FiveAM tests so that
;;;; `make test' reports them in its one closing line.

(defpackage :cram-scripts-tests
  (:use :cl :fiveam))

(in-package :cram-scripts-tests)

(def-suite scripts :in cram-plans-tests:all
  :description "Shell checks: the shipped models, the ROS launch files and the simulated robot node.")
(in-suite scripts)

(defun run-check-script (name)
  "Run tests/NAME from the repository root; return its exit code, output, passed and failed counts."
  (let ((script (asdf:system-relative-pathname "cram-plans/tests/base" (format nil "tests/~a" name))))
    (multiple-value-bind (out err code)
        (uiop:run-program (list "/bin/bash" (namestring script))
                          :output :string :error-output :output :ignore-error-status t
                          :directory (asdf:system-relative-pathname "cram-plans/tests/base" ""))
      (declare (ignore err))
      (let* ((line (find-if (lambda (l) (search " passed, " l))
                            (reverse (uiop:split-string out :separator '(#\Newline)))))
             ;; "N passed, M failed", possibly after the script's name ("name: N passed, ...")
             (passed (and line (let* ((end (search " passed, " line))
                                      (start (position-if-not #'digit-char-p line :end end :from-end t)))
                                 (parse-integer line :start (if start (1+ start) 0) :end end
                                                     :junk-allowed t))))
             (failed (and line (parse-integer line :start (+ (search " passed, " line) 9)
                                                   :junk-allowed t))))
        (values code out passed failed)))))

(defmacro def-script-test (name script min-passed)
  `(test ,name
     (multiple-value-bind (code out passed failed) (run-check-script ,script)
       (is (eql 0 code) "~a exited with ~a:~%~a" ,script code out)
       (is (eql 0 failed) "~a reported failures:~%~a" ,script out)
       (is (and passed (>= passed ,min-passed))
           "~a passed ~a checks, expected at least ~d" ,script passed ,min-passed))))

(def-script-test models-check "models-check.sh" 8)
(def-script-test ros-launch-check "ros-launch-check.sh" 20)
(def-script-test sim-robot-check "sim-robot-check.sh" 25)
