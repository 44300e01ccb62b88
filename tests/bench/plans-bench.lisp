;;;; move-bottle in projection: one warm run, and a batch campaign extrapolated to 1 000 runs.

(defpackage :cram-bench.plans
  (:use :cl :cram-bench))

(in-package :cram-bench.plans)

(defparameter *tools* (merge-pathnames "../../tools/" (make-pathname :name nil :type nil :defaults *load-truename*))
  "The tools/ directory.")

(handler-bind ((warning #'muffle-warning))
  (load (merge-pathnames "demo.lisp" *tools*)))

(define-benchmark move-bottle ()
  (let* ((pose btw-tut:*bottle-pose-in-view*)
         (quiet (make-broadcast-stream))
         (runs (loop repeat 7
                     collect (let ((start (now-seconds)))
                               (let ((r (cram-plans-demo:run-move-bottle pose :pictures nil :log-stream quiet)))
                                 (unless (getf r :success) (error "move-bottle failed: ~a" (getf r :error))))
                               (- (now-seconds) start))))
         (median (nth 3 (sort (rest runs) #'<))))
    (add-row "move-bottle projection, warm median (init-projection + spawn + whole plan)"
             (format-seconds median)
             :peer-name "CRAM's own log, seed 000 (Looking → last Parking)" :peer "3.48 s"
             :ratio (/ median 3.48d0) :goal "<= 50 ms" :met (<= median 0.05d0))))

(defun campaign-seconds (n)
  "Wall time of a campaign of N runs on 2 workers, and its success rate text."
  (let ((results (namestring (merge-pathnames (format nil "bench-batch-~d.jsonl" n)
                                              (uiop:temporary-directory))))
        (start (now-seconds)))
    (multiple-value-bind (out err code)
        (uiop:run-program (list (namestring (merge-pathnames "cram-plans-run" *tools*))
                                "--batch" (princ-to-string n) "--seed" "11" "--jobs" "2"
                                "--results" results)
                          :output :string :error-output :string :ignore-error-status t)
      (unless (eql code 0)
        (error "batch exited with ~a: ~a" code
               (let ((at (or (search "Unhandled" err) (search "error" err) 0)))
                 (subseq err at (min (length err) (+ at 300))))))
      (when (probe-file results) (delete-file results))
      (values (- (now-seconds) start)
              (let ((p (search " succeeded (" out)))
                (and p (subseq out (+ p 12) (position #\) out :start p))))))))

(define-benchmark batch-campaign ()
  ;; two campaign sizes give the fixed start-up cost of the workers and the cost per run
  (multiple-value-bind (t10) (campaign-seconds 10)
    (multiple-value-bind (t50 rate) (campaign-seconds 50)
      (let* ((per-run (/ (- t50 t10) 40))
             (startup (- t10 (* 10 per-run)))
             (t1000 (+ startup (* 1000 per-run))))
        (add-row (format nil "1 000 randomized move-bottle projections on 2 workers (from campaigns ~
                              of 10 and 50: ~,1f s start-up + ~,0f ms per run; ~a succeeded)"
                         startup (* 1000 per-run) rate)
                 (format-seconds t1000)
                 :goal "<= 60 s" :met (<= t1000 60))))))
