;;;; The household demo in projection: set + clean, warm median; and a seeded campaign of
;;;; household runs on 2 workers, its success rate (CRAM_HOUSEHOLD_RUNS=N for another size).

(defpackage :cram-bench.household
  (:use :cl :cram-bench))

(in-package :cram-bench.household)

(load-tool "demo.lisp" :cram-plans-demo)

(defparameter *household-campaign-runs*
  (let ((v (uiop:getenv "CRAM_HOUSEHOLD_RUNS")))
    (or (and v (ignore-errors (parse-integer v))) 200))
  "How many seeded household runs the campaign row runs.")

(defun household-seconds ()
  "Wall time of one quiet household demo (set + clean, the fixed spawn), and whether it
succeeded (returned and its end state is right)."
  (let ((start (now-seconds)))
    (btw-tut:init-projection)
    (let ((ok (let ((cpl:*log-stream* (make-broadcast-stream)))
                (handler-case (progn (demos:household-demo)
                                     (null (cram-plans-demo::household-end-state-problems
                                            demos:*demo-object-types*)))
                  (serious-condition () nil)))))
      (values (- (now-seconds) start) ok))))

(define-benchmark household-demo ()
  (household-seconds)                   ; warm-up
  (let* ((runs (loop repeat 5 collect (multiple-value-list (household-seconds))))
         (times (sort (mapcar #'first runs) #'<))
         (median (nth 2 times))
         (ok (count-if #'second runs)))
    (add-row (format nil "household demo set + clean in projection, warm median of 5 (~d/5 succeeded)" ok)
             (format-seconds median) :goal "<= 300 ms" :met (and (= ok 5) (<= median 0.3)))))

(define-benchmark household-campaign ()
  (let* ((tool (namestring (merge-pathnames "cram-plans-run" *tools-directory*)))
         (results (format nil "~a/cram-plans-household-bench-~d.jsonl"
                          (string-right-trim "/" (namestring (uiop:temporary-directory)))
                          (sb-posix:getpid)))
         (start (now-seconds)))
    (uiop:run-program (list tool "--demo" "household" "--batch"
                            (princ-to-string *household-campaign-runs*) "--seed" "1"
                            "--jobs" "2" "--results" results)
                      :output nil :error-output nil :ignore-error-status t)
    (let* ((seconds (- (now-seconds) start))
           (records (ignore-errors (cram-plans-demo:read-json-lines (list results))))
           (n (length records))
           (ok (count-if (lambda (r) (eq t (gethash "success" r))) records))
           (rate (if (zerop n) 0 (/ (* 100.0 ok) n))))
      (ignore-errors (delete-file results))
      (add-row (format nil "~d seeded household runs (spawn jittered, kitchen varied) on 2 workers: ~
                            success rate (~d/~d; the campaign took ~a)"
                       *household-campaign-runs* ok n (format-seconds seconds))
               (format nil "~,1f %" rate) :goal ">= 95 %" :met (and (= n *household-campaign-runs*)
                                                                    (>= rate 95))))))
