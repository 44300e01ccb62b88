;;;; The household demo in projection: set + clean, warm median; and a seeded campaign of
;;;; 1 000 household runs on 2 workers from the saved core, its success rate and its wall time
;;;; (CRAM_HOUSEHOLD_RUNS=N for another size).

(defpackage :cram-bench.household
  (:use :cl :cram-bench))

(in-package :cram-bench.household)

(load-tool "demo.lisp" :cram-plans-demo)

(defparameter *household-campaign-runs*
  (let ((v (uiop:getenv "CRAM_HOUSEHOLD_RUNS")))
    (or (and v (ignore-errors (parse-integer v))) 1000))
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

(defun median-run-seconds (records)
  "The median of the records' run times (their \"seconds\" field), or NIL."
  (let ((times (sort (remove nil (mapcar (lambda (r) (gethash "seconds" r)) records)) #'<)))
    (and times (nth (floor (length times) 2) times))))

(define-benchmark household-campaign ()
  (let* ((tool (namestring (merge-pathnames "cram-plans-run" *tools-directory*)))
         (results (format nil "~a/cram-plans-household-bench-~d.jsonl"
                          (string-right-trim "/" (namestring (uiop:temporary-directory)))
                          (sb-posix:getpid)))
         (start (progn
                  ;; the saved core first: the campaign's time is the runs' time
                  (uiop:run-program (list tool "--build-core") :output nil :error-output nil
                                                               :ignore-error-status t)
                  (now-seconds))))
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
                            success rate (~d/~d)"
                       *household-campaign-runs* ok n)
               (format nil "~,1f %" rate) :goal ">= 95 %" :met (and (= n *household-campaign-runs*)
                                                                    (>= rate 95)))
      (add-row (format nil "~d seeded household runs on 2 workers from the saved core: wall time ~
                            of the whole campaign (median run ~a)"
                       *household-campaign-runs* (format-seconds (median-run-seconds records)))
               (format-seconds seconds)
               :goal (format nil "<= ~a" (format-seconds (* 180 (/ *household-campaign-runs* 1000))))
               :met (and (= n *household-campaign-runs*)
                         (<= seconds (* 180 (/ *household-campaign-runs* 1000))))))))
