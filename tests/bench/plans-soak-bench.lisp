;;;; The memory soak: a long campaign of randomized move-bottle runs (20 000 on 2 workers by
;;;; default) must run to completion with every index reported and no worker dying, and each
;;;; worker's RSS must stay flat after warm-up (goal: < 5 MB per 1000 runs). The workers report
;;;; their RSS and Lisp heap every 1000 runs; the benchmark prints the curve and a verdict line.
;;;; CRAM_SOAK_RUNS and CRAM_SOAK_JOBS change the size of the campaign (e.g. for a quick try);
;;;; CRAM_SOAK_RUNS=0 skips the soak.

(defpackage :cram-bench.soak
  (:use :cl :cram-bench))

(in-package :cram-bench.soak)

(load-tool "demo.lisp" :cram-plans-demo)

(defun env-integer (name default)
  (or (ignore-errors (parse-integer (uiop:getenv name))) default))

(defparameter *soak-runs* (env-integer "CRAM_SOAK_RUNS" 20000) "Runs of the soak campaign.")
(defparameter *soak-jobs* (env-integer "CRAM_SOAK_JOBS" 2) "Worker processes of the soak campaign.")
(defparameter *goal-mb-per-1000* 5 "Largest accepted RSS growth per 1000 runs after warm-up (MB).")
(defparameter *warm-up-samples* 2
  "Memory samples of each worker counted as warm-up (with samples every 1000 runs: 2000 runs).")

(defun slope-per-1000 (points)
  "Least-squares slope of POINTS ((runs . megabytes) ...) in MB per 1000 runs, or NIL."
  (let ((n (length points)))
    (when (>= n 2)
      (let* ((mx (/ (reduce #'+ points :key #'car) n))
             (my (/ (reduce #'+ points :key #'cdr) n))
             (sxx (reduce #'+ points :key (lambda (p) (expt (- (car p) mx) 2))))
             (sxy (reduce #'+ points :key (lambda (p) (* (- (car p) mx) (- (cdr p) my))))))
        (and (plusp sxx) (* 1000 (/ sxy sxx)))))))

(defun check-complete (path n)
  "Signal an error unless the JSON lines file PATH reports every index 0…N-1 exactly once;
return the number of successful runs."
  (let ((seen (make-array n :element-type 'bit :initial-element 0)) (lines 0) (ok 0))
    (with-open-file (s path)
      (loop for line = (read-line s nil) while line
            do (let* ((record (yason:parse line)) (i (gethash "index" record)))
                 (incf lines)
                 (unless (and (integerp i) (< -1 i n) (zerop (aref seen i)))
                   (error "soak: index ~s reported twice or out of range" i))
                 (setf (aref seen i) 1)
                 (when (eq t (gethash "success" record)) (incf ok)))))
    (unless (= lines n) (error "soak: ~d of ~d runs reported" lines n))
    ok))

(defun print-curve (samples)
  "Print the memory samples, one line per report, grouped by worker process."
  (format t "~&soak: memory of each worker after a full GC (MB)~%")
  (format t "  ~8a ~7@a ~8@a ~8@a~%" "worker" "runs" "RSS" "heap")
  (dolist (s (sort (copy-list samples)
                   (lambda (a b) (or (< (car a) (car b))
                                     (and (= (car a) (car b)) (< (cadr a) (cadr b)))
                                     (and (equal (subseq a 0 2) (subseq b 0 2)) (< (caddr a) (caddr b)))))))
    (destructuring-bind (worker generation runs rss heap) s
      (format t "  ~8a ~7d ~8,1f ~8,1f~%"
              (if (plusp generation) (format nil "~d/r~d" worker generation) worker) runs rss heap))))

(defun soak ()
  "Run the soak campaign, print its memory curve and verdict, and add its row."
  (let* ((n *soak-runs*) (jobs *soak-jobs*)
         (every (max 1 (min 1000 (floor n (* 10 jobs)))))
         (path (namestring (merge-pathnames (format nil "cram-soak-~d.jsonl" (sb-posix:getpid))
                                            (uiop:temporary-directory))))
         (start (now-seconds)))
    (when (zerop n)
      (add-row "soak: skipped (CRAM_SOAK_RUNS=0)" "-")
      (return-from soak))
    (format t "~&soak: ~d runs on ~d workers, memory every ~d runs of each worker~%" n jobs every)
    (finish-output)
    (unwind-protect
         (multiple-value-bind (results raw deaths)
             (cram-plans-demo:run-batch n :seed 13 :jobs jobs :results path :memory-every every)
           (let* ((seconds (- (now-seconds) start))
                  (ok (check-complete results n))
                  (samples (mapcar (lambda (h) (list (gethash "worker" h) (gethash "generation" h)
                                                     (gethash "runs" h) (or (gethash "rss_mb" h) 0)
                                                     (gethash "heap_mb" h)))
                                   raw))
                  (processes (sort (remove-duplicates (mapcar (lambda (s) (subseq s 0 2)) samples)
                                                      :test #'equal)
                                   (lambda (a b) (or (< (first a) (first b))
                                                     (and (= (first a) (first b)) (< (second a) (second b)))))))
                  (slopes (loop for p in processes
                                for points = (nthcdr *warm-up-samples*
                                                     (sort (remove-if-not (lambda (s) (equal p (subseq s 0 2)))
                                                                          samples)
                                                           #'< :key #'third))
                                collect (list p (slope-per-1000 (mapcar (lambda (s) (cons (third s) (fourth s))) points))
                                              (slope-per-1000 (mapcar (lambda (s) (cons (third s) (fifth s))) points)))))
                  (rss-slopes (remove nil (mapcar #'second slopes)))
                  (worst (and rss-slopes (reduce #'max rss-slopes)))
                  ;; the goal: flat memory and no worker that died on the way
                  (met (and worst (< worst *goal-mb-per-1000*) (null deaths))))
             (print-curve samples)
             (dolist (s slopes)
               (format t "  worker ~a~:[~*~;/r~d~]: after warm-up RSS ~@[~,2@f~]~:[n/a~;~] MB, heap ~@[~,3@f~]~:[n/a~;~] MB per 1000 runs~%"
                       (first (first s)) (plusp (second (first s))) (second (first s)) (second s) (second s) (third s) (third s)))
             (format t "soak verdict: ~:[FAIL~;PASS~] — ~d of ~d runs reported (every index once), ~d succeeded, ~
                        ~d worker death~:p, ~d s; largest RSS growth after warm-up ~:[n/a~;~:*~,2f MB~] per 1000 runs ~
                        (goal < ~d MB, no worker death)~%"
                     met n n ok (length deaths) (round seconds) worst *goal-mb-per-1000*)
             (add-row (format nil "soak: ~d move-bottle runs on ~d workers complete (~d worker death~:p), ~
                               worst RSS growth per 1000 runs after warm-up"
                              n jobs (length deaths))
                      (if worst (format nil "~,2f MB" worst) "n/a")
                      :goal (format nil "< ~d MB, no worker death" *goal-mb-per-1000*) :met met)))
      (when (probe-file path) (delete-file path)))))

(define-benchmark plans-soak ()
  (soak))
