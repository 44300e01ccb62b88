;;;; A small benchmark harness: timing helpers, peer commands, one result table.

(defpackage :cram-bench
  (:use :cl)
  (:export #:now-seconds #:median-seconds #:time-per-call #:run-peer #:add-row #:print-table
           #:define-benchmark #:run-benchmarks #:format-seconds #:load-tool
           #:move-bottle-seconds #:*tools-directory*))

(in-package :cram-bench)

(defvar *rows* '() "Rows collected in this run, newest first.")

(defparameter *tools-directory*
  (merge-pathnames "../../tools/" (make-pathname :name nil :type nil :defaults *load-truename*))
  "The repository's tools/ directory.")

(defun load-tool (file &optional package)
  "Load tools/FILE quietly, unless the package named PACKAGE (a string designator) exists."
  (unless (and package (find-package package))
    (handler-bind ((warning #'muffle-warning))
      (load (merge-pathnames file *tools-directory*)))))
(defvar *benchmarks* '() "Registered benchmarks as (name . function), in order of definition.")

(defun move-bottle-seconds ()
  "Wall time of one quiet move-bottle with the bottle in view (tools/demo.lisp's RUN-MOVE-BOTTLE,
loaded by the caller); an error when it fails."
  (let* ((start (now-seconds))
         (r (funcall (find-symbol "RUN-MOVE-BOTTLE" :cram-plans-demo)
                     (symbol-value (find-symbol "*BOTTLE-POSE-IN-VIEW*" :btw-tut))
                     :pictures nil :log-stream (make-broadcast-stream))))
    (unless (getf r :success) (error "move-bottle failed: ~a" (getf r :error)))
    (- (now-seconds) start)))

(defun now-seconds ()
  "Wall clock in seconds with microsecond resolution."
  (multiple-value-bind (s us) (sb-ext:get-time-of-day)
    (+ s (* us 1d-6))))

(defun median-seconds (thunk &key (runs 7) (warmup 1) best)
  "Call THUNK WARMUP times, then RUNS times; return the median (BEST true: the smallest) wall
time of one call in seconds."
  (loop repeat warmup do (funcall thunk))
  (let ((times (loop repeat runs
                     collect (let ((start (now-seconds)))
                               (funcall thunk)
                               (- (now-seconds) start)))))
    (if best
        (reduce #'min times)
        (nth (floor runs 2) (sort times #'<)))))

(defun time-per-call (thunk &key (min-seconds 0.2d0) (runs 5) best)
  "Median (BEST true: the fastest) over RUNS batches of the time of one call of THUNK in
seconds; each batch repeats THUNK until it has taken at least MIN-SECONDS."
  (let ((n 1))
    ;; find a batch size that takes at least MIN-SECONDS
    (loop for dt = (median-seconds (lambda () (dotimes (i n) (funcall thunk))) :runs 1 :warmup 0)
          while (< dt min-seconds)
          do (setf n (* n (max 2 (min 10 (ceiling (* 1.2 min-seconds) (max dt 1d-6)))))))
    (/ (median-seconds (lambda () (dotimes (i n) (funcall thunk))) :runs runs :warmup 0 :best best)
       n)))

(defun run-peer (program &rest args)
  "Run PROGRAM with ARGS; return its standard output as a string, or NIL when it cannot run."
  (handler-case
      (multiple-value-bind (out err code)
          (uiop:run-program (cons program args) :output :string :error-output :string
                                                :ignore-error-status t)
        (declare (ignore err))
        (and (eql code 0) out))
    (error () nil)))

(defun format-seconds (s)
  "Format S seconds with a fitting unit."
  (cond ((null s) "n/a")
        ((< s 1d-6) (format nil "~,1f ns" (* s 1d9)))
        ((< s 1d-3) (format nil "~,2f µs" (* s 1d6)))
        ((< s 1d0) (format nil "~,2f ms" (* s 1d3)))
        (t (format nil "~,2f s" s))))

(defun add-row (measure ours &key peer-name peer ratio goal (met :unknown))
  "Record one table row. OURS and PEER are strings; RATIO a number (ours relative to the peer,
>1 means slower/worse unless the measure says otherwise); MET is T, NIL or :UNKNOWN."
  (push (list measure ours peer-name peer ratio goal met) *rows*))

(defun print-table (&optional (stream *standard-output*))
  "Print every collected row as one aligned table."
  (let ((header '("measure" "cram-plans" "peer" "peer value" "ratio" "goal" "met"))
        (rows (mapcar (lambda (r)
                        (destructuring-bind (m o pn p ratio goal met) r
                          (list m o (or pn "-") (or p "-")
                                (if ratio (format nil "~,3f" ratio) "-")
                                (or goal "-")
                                (case met ((t) "yes") ((nil) "NO") (t "-")))))
                      (reverse *rows*))))
    (let ((widths (apply #'mapcar (lambda (&rest col) (reduce #'max col :key #'length))
                         header rows)))
      (flet ((line (cells)
               (format stream "~{~a~^ | ~}~%"
                       (mapcar (lambda (c w) (format nil "~va" w c)) cells widths))))
        (line header)
        (line (mapcar (lambda (w) (make-string w :initial-element #\-)) widths))
        (mapc #'line rows)))))

(defmacro define-benchmark (name () &body body)
  "Register a benchmark NAME whose BODY measures and calls ADD-ROW."
  `(progn (setf *benchmarks* (append (remove ',name *benchmarks* :key #'car)
                                     (list (cons ',name (lambda () ,@body)))))
          ',name))

(defun run-benchmarks ()
  "Run every registered benchmark (a failing one is reported, not fatal) and print the table."
  (dolist (b *benchmarks*)
    (format t "~&;; bench ~(~a~)~%" (car b)) (finish-output)
    (handler-case (funcall (cdr b))
      (error (e) (add-row (format nil "~(~a~) FAILED: ~a" (car b) e) "-"))))
  (terpri)
  (print-table))
