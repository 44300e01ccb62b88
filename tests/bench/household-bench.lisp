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

(defparameter *household-script*
  "(progn (asdf:load-asd ~s)
     (let ((*standard-output* (make-broadcast-stream)) (*error-output* (make-broadcast-stream)))
       (asdf:load-system \"cram-plans\")
       (handler-bind ((warning (function muffle-warning))) (load ~s)))
     (flet ((one ()
              (let ((start (multiple-value-bind (s us) (sb-ext:get-time-of-day) (+ s (* us 1d-6)))))
                (funcall (find-symbol \"INIT-PROJECTION\" :btw-tut))
                (let ((ok (progv (list (find-symbol \"*LOG-STREAM*\" :cpl)) (list (make-broadcast-stream))
                            (handler-case
                                (progn (funcall (find-symbol \"HOUSEHOLD-DEMO\" :cram-projection-demos))
                                       (null (funcall (find-symbol \"HOUSEHOLD-END-STATE-PROBLEMS\" :cram-plans-demo)
                                                      (symbol-value (find-symbol \"*DEMO-OBJECT-TYPES*\" :cram-projection-demos)))))
                              (serious-condition () nil)))))
                  (list (- (multiple-value-bind (s us) (sb-ext:get-time-of-day) (+ s (* us 1d-6))) start) ok)))))
       (one)
       (let ((runs (loop repeat 5 collect (one))))
         (format t \"~~&MEDIAN ~~,9f OK ~~d~~%\" (nth 2 (sort (mapcar (function first) runs) (function <)))
                 (count-if (function second) runs)))))"
  "A fresh SBCL's program: load cram-plans, run the household demo (set + clean) once to warm
up and 5 times more, print the median of the 5 and how many succeeded.")

(defun fresh-process-household ()
  "(median successes) of the household demo's warm runs in a fresh SBCL, or NIL when it could
not run."
  (let* ((script (format nil *household-script*
                         (namestring (merge-pathnames "../cram-plans.asd" *tools-directory*))
                         (namestring (merge-pathnames "demo.lisp" *tools-directory*))))
         (out (run-peer "sbcl" "--dynamic-space-size" "4096" "--noinform" "--non-interactive"
                        "--no-userinit" "--no-sysinit" "--eval" "(require :asdf)" "--eval" script))
         (line (and out (search "MEDIAN " out))))
    (and line (let ((*read-default-float-format* 'double-float))
                (multiple-value-bind (median end) (read-from-string out t nil :start (+ line 7))
                  (list median (read-from-string out t nil :start (+ (search "OK " out :start2 end) 3))))))))

(define-benchmark household-demo ()
  ;; as move-bottle: each in a fresh SBCL (none of the other benchmarks' threads, caches and
  ;; heap), the median of three such processes
  (let* ((results (sort (remove nil (loop repeat 3 collect (fresh-process-household))) #'< :key #'first))
         (middle (and results (nth (floor (length results) 2) results)))
         (ok (reduce #'+ results :key #'second))
         (all (* 5 (length results))))
    (if middle
        (add-row (format nil "household demo set + clean in projection, warm median of 5 runs, median ~
                              of ~d fresh processes (~d/~d succeeded)" (length results) ok all)
                 (format-seconds (first middle)) :goal "<= 300 ms"
                 :met (and (= ok all 15) (<= (first middle) 0.3)))
        (add-row "household demo set + clean in projection, warm median" "failed" :goal "<= 300 ms"
                 :met nil))))

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
