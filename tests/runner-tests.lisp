;;;; Tests of tools/cram-plans-run: options, deterministic batch campaigns, shards, summaries.

(defpackage :cram-runner-tests
  (:use :cl :fiveam))

(in-package :cram-runner-tests)

(def-suite runner :in cram-plans-tests:all :description "The command line runner and batch mode.")
(in-suite runner)

(defun run-cli (&rest args)
  "Run tools/cram-plans-run with ARGS; return exit code, standard output and error output."
  (let ((script (asdf:system-relative-pathname "cram-plans" "tools/cram-plans-run")))
    (multiple-value-bind (out err code)
        (uiop:run-program (cons (namestring script) args) :output :string :error-output :string
                                                          :ignore-error-status t)
      (values code out err))))

(defun records (path)
  "The JSON lines of PATH as hash tables, without the wall-clock duration."
  (with-open-file (s path)
    (loop for line = (read-line s nil) while line
          collect (let ((h (yason:parse line))) (remhash "seconds" h) h))))

(defun record-key (h)
  (list (gethash "index" h) (gethash "seed" h) (gethash "pose" h) (gethash "success" h)
        (gethash "distance" h) (gethash "error" h) (gethash "new_grasp" h) (gethash "look_direction" h)))

(defun summary-line (output)
  "The line `N runs, K succeeded (P %)' of a summary OUTPUT."
  (let* ((at (or (search " runs, " output) 0))
         (start (1+ (or (position #\Newline output :end at :from-end t) -1))))
    (subseq output start (or (position #\Newline output :start at) (length output)))))

(defun temp-file (name)
  (namestring (merge-pathnames (format nil "cram-runner-~d-~a" (sb-posix:getpid) name)
                               (uiop:temporary-directory))))

(test bad-options-exit-2-and-name-the-value
  (multiple-value-bind (code out err) (run-cli "--demo" "flying")
    (declare (ignore out))
    (is (eql 2 code))
    (is (search "flying" err)))
  (multiple-value-bind (code out err) (run-cli "--shard" "3/2" "--batch" "2")
    (declare (ignore out))
    (is (eql 2 code))
    (is (search "3/2" err)))
  (multiple-value-bind (code out err) (run-cli "--bottle-pose" "1,2")
    (declare (ignore out))
    (is (eql 2 code))
    (is (search "1,2" err))))

(test batch-is-deterministic-and-shards-partition-it
  (let ((a (temp-file "a.jsonl")) (b (temp-file "b.jsonl"))
        (s1 (temp-file "s1.jsonl")) (s2 (temp-file "s2.jsonl")))
    (unwind-protect
         (progn
           (is (eql 0 (run-cli "--batch" "3" "--seed" "7" "--jobs" "2" "--results" a)))
           (is (eql 0 (run-cli "--batch" "3" "--seed" "7" "--jobs" "1" "--results" b)))
           (let ((ra (records a)) (rb (records b)))
             (is (= 3 (length ra)))
             (is (equal (mapcar #'record-key ra) (mapcar #'record-key rb))
                 "the same seed gives the same runs, whatever the number of workers")
             (is (equal '(0 1 2) (mapcar (lambda (h) (gethash "index" h)) ra))))
           (is (eql 0 (run-cli "--batch" "3" "--seed" "7" "--jobs" "1" "--shard" "1/2" "--results" s1)))
           (is (eql 0 (run-cli "--batch" "3" "--seed" "7" "--jobs" "1" "--shard" "2/2" "--results" s2)))
           (let ((whole (mapcar #'record-key (records a)))
                 (shards (append (mapcar #'record-key (records s1)) (mapcar #'record-key (records s2)))))
             (is (= 3 (length shards)))
             (is (null (set-difference whole shards :test #'equal)) "the shards together are the campaign"))
           (multiple-value-bind (code out) (run-cli "--summary" s1 s2)
             (is (eql 0 code))
             (multiple-value-bind (code2 out2) (run-cli "--summary" a)
               (is (eql 0 code2))
               (is (string= (summary-line out) (summary-line out2))
                   "the summary of the merged shards equals that of the whole campaign")
               (is (search "3 runs" out)))))
      (dolist (f (list a b s1 s2)) (when (probe-file f) (delete-file f))))))
