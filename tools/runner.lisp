;;;; The command line of tools/cram-plans-run: single demo runs with options, and batch
;;;; campaigns of randomized move-bottle projections over several worker processes, sharded
;;;; for cluster schedulers, with JSON lines and a summary. Loaded by tools/demo.lisp.

(in-package :cram-plans-demo)

;;; ---- options ---------------------------------------------------------------------------------

(define-condition usage-error (error)
  ((message :initarg :message :reader usage-error-message))
  (:report (lambda (c s) (write-string (usage-error-message c) s)))
  (:documentation "A bad command line option or value."))

(defun usage-fail (fmt &rest args)
  (error 'usage-error :message (apply #'format nil fmt args)))

(defparameter *usage*
  "usage: cram-plans-run [--demo move-bottle|switch-bottles|pepper|household] [--seed N]
                      [--bottle-pose x,y,z[,yaw]] [--input \"1 1\"] [--out DIR] [--quiet]
       cram-plans-run [--demo household] --batch N [--seed N] [--jobs J] [--shard I/N] [--results FILE]
                      [--memory-every K]
       cram-plans-run --summary FILE...
       cram-plans-run --help

Single runs (default: --demo move-bottle, bottle in view):
  --demo NAME         move-bottle, switch-bottles, pepper or household (CRAM's household demo:
                      set the breakfast table, then clean it up; with --seed, spawn poses
                      jittered and the kitchen varied)
  --seed N            seed of every random choice (default 1)
  --bottle-pose P     move-bottle's bottle at x,y,z[,yaw] (metres, radians)
  --input TEXT        what the pepper demo reads from the user (default \"2\")
  --robot ros         run move-bottle over ROS against the simulated robot (private roscore,
                      launch/sim_robot.launch); success: the bottle at its destination there
  --speed S           time factor of the simulated robot with --robot ros (default 1)
  --out DIR           write the log's pictures, start/grasped/placed.png and the task tree
  --quiet             no log on standard output
Batch campaigns of randomized move-bottle runs, or household runs with --demo household (one
JSON line per run, in index order):
  --batch N           N runs; the same seed gives the same runs however they are split
  --jobs J            worker processes (default 2); a worker that dies is reported with its
                      exit status and last output, and its lost runs are re-run
  --shard I/N         only every N-th run starting at run I (for job arrays)
  --results FILE      where the JSON lines go (default batch-SEED.jsonl)
  --memory-every K    each worker reports its RSS and Lisp heap every K runs
  --summary FILE...   success rate and histograms of JSON lines files (merged shards)
The tool and its workers start from a saved SBCL core (${XDG_CACHE_HOME:-~/.cache}/cram-plans/
cores/), built on first use and whenever a source changes (tools/cram-plans-core);
cram-plans-run --build-core only builds it; CRAM_PLANS_NO_CORE=1 loads the systems instead.
Exit status: 0 success, 1 plan failure, 2 bad options.")

(defun parse-integer-option (option value &key (min 0))
  (let ((n (and value (ignore-errors (parse-integer value)))))
    (unless (and n (>= n min))
      (usage-fail "~a needs an integer >= ~d, got ~s" option min value))
    n))

(defun parse-pose-option (value)
  "x,y,z[,yaw] → ((x y z) quaternion about z)."
  (let ((numbers (mapcar (lambda (s) (let ((*read-default-float-format* 'double-float)
                                           (*read-eval* nil))
                                       (ignore-errors (read-from-string s))))
                         (uiop:split-string (or value "") :separator ","))))
    (unless (and (<= 3 (length numbers) 4) (every #'realp numbers))
      (usage-fail "--bottle-pose needs x,y,z or x,y,z,yaw in metres and radians, got ~s" value))
    (yaw-pose (first numbers) (second numbers) (third numbers) (or (fourth numbers) 0))))

(defun yaw-pose (x y z yaw)
  (list (list x y z) (list 0 0 (sin (/ yaw 2)) (cos (/ yaw 2)))))

(defun parse-options (args)
  "A plist of the options in ARGS (strings); a USAGE-ERROR names anything unknown or malformed."
  (let ((options (list :demo "move-bottle" :seed 1 :jobs 2 :out nil :quiet nil)))
    (loop while args
          do (let ((option (pop args)))
               (flet ((value () (if args (pop args) (usage-fail "~a needs a value" option))))
                 (cond ((string= option "--demo")
                        (let ((d (value)))
                          (unless (member d '("move-bottle" "switch-bottles" "pepper" "household")
                                          :test #'string=)
                            (usage-fail "--demo ~s is unknown, expected move-bottle, switch-bottles, ~
                                         pepper or household" d))
                          (setf (getf options :demo) d)))
                       ((string= option "--seed") (setf (getf options :seed) (parse-integer-option option (value))))
                       ((string= option "--bottle-pose") (setf (getf options :pose) (parse-pose-option (value))))
                       ((string= option "--input") (setf (getf options :input) (value)))
                       ((string= option "--robot") (setf (getf options :robot) (value)))
                       ((string= option "--speed")
                        (let* ((v (value)) (n (let ((*read-eval* nil)) (ignore-errors (read-from-string v)))))
                          (unless (and (realp n) (plusp n))
                            (usage-fail "--speed needs a positive number, got ~s" v))
                          (setf (getf options :speed) n)))
                       ((string= option "--out") (setf (getf options :out) (value)))
                       ((string= option "--quiet") (setf (getf options :quiet) t))
                       ((string= option "--batch") (setf (getf options :batch) (parse-integer-option option (value) :min 1)))
                       ((string= option "--jobs") (setf (getf options :jobs) (parse-integer-option option (value) :min 1)))
                       ((string= option "--results") (setf (getf options :results) (value)))
                       ((string= option "--memory-every")
                        (setf (getf options :memory-every) (parse-integer-option option (value) :min 1)))
                       ((member option '("--help" "-h") :test #'string=) (setf (getf options :help) t))
                       ((string= option "--shard")
                        (let* ((v (value)) (slash (position #\/ v))
                               (i (and slash (ignore-errors (parse-integer v :end slash))))
                               (n (and slash (ignore-errors (parse-integer v :start (1+ slash))))))
                          (unless (and i n (<= 1 i n))
                            (usage-fail "--shard needs I/N with 1 <= I <= N, got ~s" v))
                          (setf (getf options :shard) (cons i n))))
                       ((string= option "--summary")
                        (setf (getf options :summary) (or args (usage-fail "--summary needs JSON lines files"))
                              args nil))
                       (t (usage-fail "unknown option ~s (cram-plans-run --help lists the options)" option))))))
    options))

;;; ---- seeds and poses ---------------------------------------------------------------------------

(defun run-seed (campaign-seed index)
  "The seed of run INDEX of a campaign: independent of how the campaign is sharded."
  (mod (+ (* campaign-seed 1000003) (* (1+ index) 7919)) 2147483647))

(defun seed-everything (seed)
  "Seed every random choice of a projection run."
  (setf *random-state* (sb-ext:seed-random-state seed)
        urdf-proj:*ik-random-state* (sb-ext:seed-random-state (+ seed 1)))
  (costmap:seed-costmaps (+ seed 2)))

(defun random-bottle-pose (seed)
  "A bottle pose standing on the table in front of the robot (x -2.0 … -1.1, y -1.0 … -0.8,
any yaw), drawn from SEED."
  (let ((state (sb-ext:seed-random-state seed)))
    (flet ((uniform (lo hi) (+ lo (random (float (- hi lo) 1d0) state))))
      (let ((x (uniform -2.0d0 -1.1d0)) (y (uniform -1.0d0 -0.8d0)) (yaw (uniform (- pi) pi)))
        (values (yaw-pose x y 0.8608d0 yaw) (list x y 0.8608d0 yaw))))))

;;; ---- one batch run -------------------------------------------------------------------------------

(defparameter *recovery-keys*
  '("look_direction" "new_grasp" "new_arm" "grasp_failure" "perception_failure")
  "The JSON keys of the recovery and failure counts of a run.")

(defvar *campaign-demo* "move-bottle"
  "The demo a campaign's runs run: \"move-bottle\" or \"household\".")

(defun run-record (campaign-seed index)
  "Run number INDEX of the campaign CAMPAIGN-SEED (move-bottle, or the household demo when
*CAMPAIGN-DEMO* says so); a hash table for one JSON line."
  (if (string= *campaign-demo* "household")
      (household-run-record campaign-seed index)
      (move-bottle-run-record campaign-seed index)))

(defun move-bottle-run-record (campaign-seed index)
  "Run move-bottle number INDEX of the campaign CAMPAIGN-SEED; a hash table for one JSON line."
  (let ((seed (run-seed campaign-seed index)))
    (multiple-value-bind (pose numbers) (random-bottle-pose seed)
      (seed-everything seed)
      (let ((result (run-move-bottle pose :pictures nil :log-stream (make-broadcast-stream)
                                                   :reuse-world t))
            (record (make-hash-table :test 'equal)))
        (setf (gethash "index" record) index
              (gethash "seed" record) seed
              (gethash "pose" record) numbers
              (gethash "success" record) (and (getf result :success) t)
              (gethash "distance" record) (getf result :distance)
              (gethash "seconds" record) (getf result :seconds)
              (gethash "error" record) (let ((e (getf result :error)))
                                         (and e (first-line e)))
              (gethash "sweeps" record) (getf result :sweeps 0))
        (loop for key in '(:look-direction :new-grasp :new-arm :grasp-failure :perception-failure)
              for name in *recovery-keys*
              do (setf (gethash name record) (getf result key)))
        record))))

(defun failure-record (campaign-seed index message)
  "The record of run INDEX of the campaign CAMPAIGN-SEED when the run could not end by itself
(an error outside the plan, or its worker died): not a success, MESSAGE as the error."
  (let ((seed (run-seed campaign-seed index))
        (record (make-hash-table :test 'equal)))
    (setf (gethash "index" record) index
          (gethash "seed" record) seed
          (gethash "pose" record) (and (string= *campaign-demo* "move-bottle")
                                       (nth-value 1 (random-bottle-pose seed)))
          (gethash "success" record) nil
          (gethash "distance" record) nil
          (gethash "seconds" record) 0
          (gethash "error" record) message
          (gethash "sweeps" record) 0)
    (dolist (key *recovery-keys*) (setf (gethash key record) 0))
    record))

(defun first-line (text)
  (subseq text 0 (or (position #\Newline text) (length text))))

(defun record->json (record)
  (with-output-to-string (s)
    (yason:encode record s)))

;;; ---- workers --------------------------------------------------------------------------------------

(defun rss-megabytes (&optional (pid "self"))
  "The resident set size of the process PID (default: this one) in MB, or NIL when unknown."
  (with-open-file (s (format nil "/proc/~a/status" pid) :if-does-not-exist nil)
    (and s (loop for l = (read-line s nil) while l
                 when (and (> (length l) 6) (string= "VmRSS:" l :end2 6))
                   return (/ (* 1024 (parse-integer l :start 6 :junk-allowed t)) 1d6)))))

(defun memory-sample (slot generation runs)
  "A hash table: this worker's RSS and Lisp heap in use (MB) after a full collection, after
RUNS runs."
  (sb-ext:gc :full t)
  (let ((h (make-hash-table :test 'equal)))
    (setf (gethash "worker" h) slot
          (gethash "generation" h) generation
          (gethash "runs" h) runs
          (gethash "rss_mb" h) (rss-megabytes)
          (gethash "heap_mb" h) (/ (sb-kernel:dynamic-usage) 1d6))
    h))

(defun test-kill-hook (index generation)
  "Test hook: when the environment variable CRAM_PLANS_RUN_TEST_KILL is INDEX, the first worker
(generation 0) that is about to run INDEX kills itself with SIGKILL; INDEX:always kills every
worker that reaches it. A line on standard output announces it."
  (let* ((spec (uiop:getenv "CRAM_PLANS_RUN_TEST_KILL"))
         (colon (and spec (position #\: spec)))
         (at (and spec (ignore-errors (parse-integer spec :end colon)))))
    (when (and at (= at index)
               (or (zerop generation) (and colon (string= "always" (subseq spec (1+ colon))))))
      (format t "~&test hook: worker generation ~d kills itself (SIGKILL) before run ~d~%"
              generation index)
      (finish-output)
      (sb-posix:kill (sb-posix:getpid) sb-posix:sigkill))))

(defun write-indices (path indices)
  "Write the run INDICES (a sequence) to the file PATH, for READ-INDICES."
  (with-open-file (s path :direction :output :if-exists :supersede)
    (with-standard-io-syntax (prin1 indices s))))

(defun read-indices (path)
  "The run indices WRITE-INDICES wrote to the file PATH."
  (with-open-file (s path)
    (with-standard-io-syntax
      (let ((*read-eval* nil)) (read s)))))

(defparameter *worker-nursery-bytes* 200000000
  "Bytes a campaign worker conses between two garbage collections: a household run conses some
120 MB, and collects in about 40 ms per run at this size against 55 ms at SBCL's default of
54 MB (two or three collections per run, each copying what survives).")

(defun worker (campaign-seed indices-file results-file
               &key (slot 0) (generation 0) memory-every memory-file (demo *campaign-demo*) pool)
  "The body of one worker process: run the campaign runs listed in INDICES-FILE in order, then
\(with POOL, a pool file of WRITE-POOL) the runs it claims from the pool one at a time,
appending one JSON line per run to RESULTS-FILE (a run that signals outside the plan is
recorded as a failure), and every MEMORY-EVERY runs a memory sample to MEMORY-FILE. Exits 0.
Nobody replays a worker's runs: the viewer's recorder is off (CRAM-VIEWER:*RECORD-RUNS*).
The process keeps to the CPU of its SLOT (PIN-TO-SLOT-CPU)."
  (pin-to-slot-cpu slot)
  (setf cram-viewer:*record-runs* nil
        *campaign-demo* demo
        (sb-ext:bytes-consed-between-gcs) *worker-nursery-bytes*)
  (with-open-file (out results-file :direction :output :if-exists :append :if-does-not-exist :create)
    (loop with next = (run-source (read-indices indices-file) pool slot generation)
          for i = (funcall next)
          while i
          for done from 1
          do (test-kill-hook i generation)
             (let ((record (handler-case (run-record campaign-seed i)
                             ((or error storage-condition) (e)
                               (failure-record campaign-seed i
                                               (or (ignore-errors (first-line (princ-to-string e)))
                                                   (string (type-of e))))))))
               (write-line (record->json record) out)
               (finish-output out))
             (when (and memory-every memory-file (zerop (mod done memory-every)))
               (with-open-file (m memory-file :direction :output :if-exists :append
                                              :if-does-not-exist :create)
                 (write-line (record->json (memory-sample slot generation done)) m)))))
  (uiop:quit 0))

;;; ---- the campaign supervisor ------------------------------------------------------------------------

(defstruct (worker-slot (:conc-name slot-))
  "One worker position of a campaign and the process that currently fills it."
  id (generation 0) process indices results log memory pool
  (results-offset 0) (memory-offset 0) (stalls 0) finished)

(defun slot-runs (slot)
  "The runs of SLOT's current process: those it was given, then those it claimed from the
campaign's pool (POOL-CLAIMS)."
  (append (slot-indices slot)
          (and (slot-pool slot) (pool-claims (slot-pool slot) (slot-id slot) (slot-generation slot)))))

(defun shard-indices (n shard)
  "The run indices 0…N-1 of SHARD (I . COUNT): every COUNT-th index starting at I-1."
  (destructuring-bind (i . count) (or shard '(1 . 1))
    (loop for k from (1- i) below n by count collect k)))

(defun read-new-lines (path offset)
  "The complete lines appended to the file PATH after byte OFFSET, and the offset after the last
of them (a line still being written is left for the next call)."
  (with-open-file (s path :element-type '(unsigned-byte 8) :if-does-not-exist nil)
    (let ((length (if s (file-length s) 0)))
      (if (<= length offset)
          (values '() offset)
          (let ((bytes (make-array (- length offset) :element-type '(unsigned-byte 8))))
            (file-position s offset)
            (let* ((n (read-sequence bytes s))
                   (end (position 10 bytes :end n :from-end t)))
              (if end
                  (values (remove "" (uiop:split-string
                                      (sb-ext:octets-to-string bytes :end end
                                                                     :external-format '(:utf-8 :replacement #\?))
                                      :separator '(#\Newline))
                                  :test #'string=)
                          (+ offset end 1))
                  (values '() offset))))))))

(defun output-tail (path &key (lines 15) (bytes 8192))
  "The last LINES lines of the file PATH (from its last BYTES bytes)."
  (with-open-file (s path :element-type '(unsigned-byte 8) :if-does-not-exist nil)
    (when s
      (let* ((start (max 0 (- (file-length s) bytes)))
             (buffer (make-array (- (file-length s) start) :element-type '(unsigned-byte 8))))
        (file-position s start)
        (read-sequence buffer s)
        (let ((all (remove-if (lambda (l) (zerop (length (string-trim " " l))))
                              (uiop:split-string (sb-ext:octets-to-string
                                                  buffer :external-format '(:utf-8 :replacement #\?))
                                                 :separator '(#\Newline)))))
          (last all lines))))))

(defun exit-description (process)
  "How the worker PROCESS ended, for a person: its exit status or the signal that killed it."
  (let ((code (sb-ext:process-exit-code process)))
    (case (sb-ext:process-status process)
      (:exited (format nil "exited with status ~d" code))
      (:signaled (format nil "was killed by signal ~d~@[ (~a)~]" code
                         (cdr (assoc code '((1 . "SIGHUP") (2 . "SIGINT") (4 . "SIGILL") (6 . "SIGABRT")
                                            (7 . "SIGBUS") (8 . "SIGFPE") (9 . "SIGKILL")
                                            (11 . "SIGSEGV") (15 . "SIGTERM"))))))
      (t (format nil "ended (~(~a~) ~a)" (sb-ext:process-status process) code)))))

(defvar *saved-core-p* nil
  "True in the saved core that tools/cram-plans-core builds (SAVE-CORE in tools/build-core.lisp
sets it): the workers of a campaign then start from that core instead of loading the systems.")

(defun worker-image-options (demo)
  "The SBCL options that give a worker its image: this process's saved core when the tool runs
from one and the file is still there, else loading DEMO (tools/demo.lisp) as before."
  (let ((core (and *saved-core-p* sb-ext:*core-pathname* (probe-file sb-ext:*core-pathname*))))
    (if core
        (list "--core" (namestring core) "--noinform" "--non-interactive" "--no-userinit" "--no-sysinit")
        (list "--noinform" "--non-interactive" "--no-userinit" "--no-sysinit"
              "--eval" "(require :asdf)" "--load" demo))))

(defun launch-worker (slot indices seed tmp memory-every)
  "Start the next process of SLOT on the run INDICES, its files in the directory TMP."
  (let ((base (format nil "worker-~d-~d" (slot-id slot) (slot-generation slot)))
        (demo (namestring (merge-pathnames "demo.lisp" *tools-directory*))))
    (flet ((file (type) (namestring (merge-pathnames (format nil "~a.~a" base type) tmp))))
      (write-indices (file "indices") indices)
      (setf (slot-indices slot) indices
            (slot-results slot) (file "jsonl") (slot-log slot) (file "log") (slot-memory slot) (file "memory")
            (slot-results-offset slot) 0 (slot-memory-offset slot) 0
            (slot-process slot)
            (sb-ext:run-program
             "sbcl" (append (worker-image-options demo)
                            (list "--eval" (format nil "(cram-plans-demo::worker ~d ~s ~s :slot ~d :generation ~d ~
                                                        :memory-every ~s :memory-file ~s :demo ~s :pool ~s)"
                                                   seed (file "indices") (file "jsonl") (slot-id slot)
                                                   (slot-generation slot) memory-every (file "memory")
                                                   *campaign-demo* (slot-pool slot))))
             :search t :wait nil :input nil :output (file "log") :if-output-exists :supersede
             :error :output :environment (worker-environment))))))

(defun worker-environment ()
  "The environment of a worker process: this one's, with the browser viewer off (a worker has
nobody to show it to) unless CRAM_PLANS_VIEWER is set."
  (let ((env (sb-ext:posix-environ)))
    (if (uiop:getenv "CRAM_PLANS_VIEWER") env (cons "CRAM_PLANS_VIEWER=0" env))))

(defparameter *poll-interval* 0.05
  "Seconds between two looks of the campaign supervisor at its workers' files and processes
(reading a few appended lines costs microseconds; a long interval delays the end of a campaign).")

(defvar *max-stalls* 4
  "A campaign stops with an error when the processes of one worker slot die this many times in a
row without finishing a single run (the workers cannot work at all).")

(defun collect-slot (slot lines samples stream)
  "Take the new result lines of SLOT into the table LINES (index → line; the first line of an
index wins) and its new memory samples into the list in the cons SAMPLES, printing them."
  (multiple-value-bind (new offset) (read-new-lines (slot-results slot) (slot-results-offset slot))
    (setf (slot-results-offset slot) offset)
    (dolist (line new)
      (let* ((record (ignore-errors (yason:parse line)))
             (index (and (hash-table-p record) (gethash "index" record))))
        (when (and (integerp index) (not (gethash index lines)))
          (setf (gethash index lines) line)))))
  (multiple-value-bind (new offset) (read-new-lines (slot-memory slot) (slot-memory-offset slot))
    (setf (slot-memory-offset slot) offset)
    (dolist (line new)
      (let ((sample (ignore-errors (yason:parse line))))
        (when (hash-table-p sample)
          (push sample (car samples))
          (format stream "~&memory: worker ~d~:[~*~; (restart ~d)~]: ~6d runs, RSS ~7,1f MB, Lisp heap ~6,1f MB~%"
                  (gethash "worker" sample) (plusp (gethash "generation" sample))
                  (gethash "generation" sample) (gethash "runs" sample)
                  (or (gethash "rss_mb" sample) 0) (gethash "heap_mb" sample)))))))

(defun settle-slot (slot lines seed tmp memory-every stream)
  "SLOT's process has ended: finish the slot, or report the death of its worker and start a
new one on the runs it lost. A run that two workers in a row died on is recorded as a failure.
Returns a plist describing the death, or NIL."
  (let* ((process (slot-process slot))
         (clean (and (eql 0 (sb-ext:process-exit-code process))
                     (eq :exited (sb-ext:process-status process))))
         ;; a worker that ended by itself reported every run it claimed before it claimed the
         ;; next: its claims are looked up only after a death
         (runs (if clean (slot-indices slot) (slot-runs slot)))
         (remaining (remove-if (lambda (i) (gethash i lines)) runs))
         (ran (- (length runs) (length remaining))))
    (sb-ext:process-close process)
    (if (and (null remaining) clean)
        (progn (setf (slot-finished slot) t) nil)
        (let ((how (exit-description process))
              (tail (output-tail (slot-log slot))))
          (format stream "~&batch: worker ~d (pid ~d) ~a after ~d of its ~d runs~:[~;, before run ~:*~d~]~%~
                          ~:[  (it printed nothing)~%~;~:*~{  | ~a~%~}~]"
                  (slot-id slot) (sb-ext:process-pid process) how ran (length runs)
                  (first remaining) tail)
          (if (zerop ran) (incf (slot-stalls slot)) (setf (slot-stalls slot) 0))
          (when (>= (slot-stalls slot) *max-stalls*)
            (error "batch: worker ~d died ~d times in a row without finishing a run; the last one ~a.~
                    ~%Its last output:~%~{  | ~a~%~}" (slot-id slot) (slot-stalls slot) how tail))
          (let ((given-up nil))
            (when (and remaining (plusp (slot-generation slot)) (zerop ran))
              ;; the previous process of this slot died at the same run: do not try it a third time
              (setf given-up (pop remaining))
              (setf (gethash given-up lines)
                    (record->json (failure-record seed given-up
                                                  (format nil "two workers died running this run (the last ~a)" how))))
              (format stream "batch: run ~d killed two workers; it is recorded as a failure~%" given-up))
            (incf (slot-generation slot))
            (if remaining
                (progn (format stream "batch: restarting worker ~d on the ~d runs it lost~%"
                               (slot-id slot) (length remaining))
                       (launch-worker slot remaining seed tmp memory-every))
                (setf (slot-finished slot) t))
            (list :worker (slot-id slot) :pid (sb-ext:process-pid process) :how how
                  :lost (if given-up (cons given-up remaining) remaining) :given-up given-up :tail tail))))))

(defun progress-bar (done total &optional (stream *error-output*))
  (let* ((width 40) (filled (if (zerop total) width (floor (* width done) total))))
    (format stream "~c[~a~a] ~d/~d" #\Return (make-string filled :initial-element #\#)
            (make-string (- width filled) :initial-element #\.) done total)
    (finish-output stream)))

(defun run-batch (n &key (seed 1) (jobs 2) shard results memory-every (stream *error-output*))
  "Run the runs of SHARD (default: all N) of the campaign SEED in JOBS worker processes and
write their JSON lines in index order to RESULTS (default batch-SEED.jsonl), every index once.
A worker that dies is reported on STREAM with its exit status and the tail of its output, and a
new worker re-runs the runs it lost. With MEMORY-EVERY, each worker reports its RSS and heap
every MEMORY-EVERY runs. Returns the path, the memory samples (hash tables: worker,
generation, runs, rss_mb, heap_mb) and the deaths (plists)."
  (let* ((indices (shard-indices n shard))
         (results (or results (format nil "batch-~d~@[-~{~d-of-~d~}~].jsonl" seed
                                      (and shard (list (car shard) (cdr shard))))))
         (tmp (uiop:ensure-directory-pathname
               (format nil "~a/cram-plans-batch-~d-~d" (string-right-trim "/" (namestring (uiop:temporary-directory)))
                       (sb-posix:getpid) (get-universal-time))))
         (jobs (max 1 (min jobs (length indices))))
         (slots (loop for j below jobs collect (make-worker-slot :id j)))
         (lines (make-hash-table))
         (samples (list '()))
         (deaths '()))
    (ensure-directories-exist tmp)
    ;; the folder of the results file, made before the runs (out/ may not exist yet)
    (handler-case (ensure-directories-exist results)
      (file-error (e)
        (error "batch: cannot make the folder of the results file ~s: ~a" results e)))
    (unwind-protect
         (progn
           ;; the workers claim the runs one at a time from a pool (campaign-pool.lisp)
           (let ((pool (write-pool tmp indices)))
             (dolist (slot slots)
               (setf (slot-pool slot) pool)
               (launch-worker slot '() seed tmp memory-every)))
           (loop with shown = -1
                 for active = (remove-if #'slot-finished slots)
                 while active
                 do (dolist (slot active)
                      (let ((alive (sb-ext:process-alive-p (slot-process slot))))
                        (collect-slot slot lines samples stream)
                        (unless alive
                          (let ((death (settle-slot slot lines seed tmp memory-every stream)))
                            (when death (push death deaths))))))
                    (let ((percent (floor (* 100 (hash-table-count lines)) (max 1 (length indices)))))
                      (unless (= shown percent) ; at most 100 redraws, also in a log file
                        (setf shown percent)
                        (progress-bar (hash-table-count lines) (length indices) stream)))
                    (sleep *poll-interval*))
           (progress-bar (hash-table-count lines) (length indices) stream)
           (terpri stream))
      (dolist (slot slots)
        (let ((p (slot-process slot)))
          (when (and p (sb-ext:process-alive-p p))
            (sb-ext:process-kill p sb-posix:sigterm)
            (sb-ext:process-wait p)
            (sb-ext:process-close p))))
      (uiop:delete-directory-tree tmp :validate t :if-does-not-exist :ignore))
    (let ((missing (remove-if (lambda (i) (gethash i lines)) indices)))
      (when missing
        (error "batch: ~d of ~d runs reported no result (first missing: ~d)"
               (length missing) (length indices) (first missing))))
    (with-open-file (out results :direction :output :if-exists :supersede)
      (dolist (i indices) (write-line (gethash i lines) out)))
    (when deaths
      (let ((given-up (remove nil (mapcar (lambda (d) (getf d :given-up)) deaths)))
            (lost (make-hash-table)))
        (dolist (d deaths) (dolist (i (getf d :lost)) (setf (gethash i lost) t)))
        (dolist (i given-up) (remhash i lost))
        (format stream "batch: ~d worker~:p died; ~d lost run~:p ran again in new workers"
                (length deaths) (hash-table-count lost))
        (when given-up
          (format stream "; ~d run~:p that killed two workers ~:[are~;is~] recorded as failed: ~{~d~^, ~}"
                  (length given-up) (= 1 (length given-up)) given-up))
        (format stream "; all ~d runs reported~%" (length indices))))
    (values results (reverse (car samples)) (reverse deaths))))

(defun read-json-lines (paths)
  "Every record (hash table) in the JSON lines files PATHS."
  (loop for p in paths
        append (with-open-file (s p :if-does-not-exist nil)
                 (unless s (usage-fail "--summary: file ~s does not exist" p))
                 (loop for l = (read-line s nil) while l
                       when (plusp (length (string-trim " " l))) collect (yason:parse l)))))

(defun summarize (records &optional (stream *standard-output*))
  "Print the success rate and the histograms of failures and recoveries of RECORDS; return the
success rate."
  (let* ((n (length records))
         (ok (count-if (lambda (r) (eq t (gethash "success" r))) records))
         (errors (make-hash-table :test 'equal)))
    (dolist (r records)
      (unless (eq t (gethash "success" r))
        (let ((e (gethash "error" r)))
          (incf (gethash (if (stringp e) (subseq e 0 (min 70 (length e))) "bottle not at the destination")
                         errors 0)))))
    (format stream "~&~d runs, ~d succeeded (~,1f %)~%" n ok (if (zerop n) 0 (/ (* 100.0 ok) n)))
    (when (plusp n)
      (let ((times (sort (mapcar (lambda (r) (gethash "seconds" r)) records) #'<)))
        (format stream "time per run: median ~,3f s, max ~,3f s~%" (nth (floor n 2) times) (car (last times)))))
    (format stream "recoveries (runs with at least one / total):~%")
    (dolist (key *recovery-keys*)
      (let ((runs (count-if (lambda (r) (plusp (or (gethash key r) 0))) records))
            (total (reduce #'+ records :key (lambda (r) (or (gethash key r) 0)))))
        (format stream "  ~20a ~5d / ~5d  ~a~%" key runs total
                (make-string (if (zerop n) 0 (round (* 30 runs) n)) :initial-element #\#))))
    (let ((types (make-hash-table :test 'equal)))
      (dolist (r records)
        (let ((f (gethash "failure" r)))
          (when (stringp f) (incf (gethash f types 0)))))
      (when (plusp (hash-table-count types))
        (format stream "failure types:~%")
        (maphash (lambda (f c) (format stream "  ~5d  ~a~%" c f)) types)))
    (let ((swept (count-if (lambda (r) (plusp (or (gethash "sweeps" r) 0))) records))
          (total (reduce #'+ records :key (lambda (r) (or (gethash "sweeps" r) 0)))))
      (format stream "sweeps (a moving link or carried object and what its path hits): ~d in ~d runs, ~,2f per run~%"
              total swept (if (zerop n) 0 (/ total n))))
    (format stream "failures:~%")
    (if (zerop (hash-table-count errors))
        (format stream "  none~%")
        (maphash (lambda (e c) (format stream "  ~5d  ~a~%" c e)) errors))
    (if (zerop n) 0 (/ ok n))))

;;; ---- the command line ------------------------------------------------------------------------------

(defun run-demo (options)
  (let* ((out (getf options :out))
         (dir (and out (uiop:ensure-directory-pathname (merge-pathnames out (uiop:getcwd)))))
         (log (if (getf options :quiet) (make-broadcast-stream) *standard-output*)))
    (when dir (ensure-directories-exist dir))
    (seed-everything (getf options :seed))
    (let ((cpl:*log-stream* log) (*standard-output* log))
      (cond ((string= (getf options :demo) "move-bottle")
             (let ((result (let ((*snapshot-grasped* t))
                             (run-move-bottle (or (getf options :pose) btw-tut:*bottle-pose-in-view*)
                                              :out-dir dir :pictures (and dir t) :log-stream log))))
               (when dir
                 (btr:png-snapshot (merge-pathnames "placed.png" dir) :look-at '(-0.8 2.0 0.9))
                 (ignore-errors (write-task-tree dir))
                 (format t "~&replay: ~a~%" (cram-viewer:write-replay dir)))
               (format t "~&~:[FAILURE~;SUCCESS~]: bottle ~@[~,3f m~] from the destination~@[; error: ~a~]~%"
                       (getf result :success) (getf result :distance) (getf result :error))
               (getf result :success)))
            ((string= (getf options :demo) "household")
             (let ((result (run-household (getf options :seed) :log-stream log)))
               (format t "~&~:[FAILURE~;SUCCESS~]: household demo in ~,2f s~@[ (~a)~]~@[: ~a~]~%"
                       (getf result :success) (getf result :seconds) (getf result :failure)
                       (getf result :error))
               (getf result :success)))
            ((string= (getf options :demo) "switch-bottles")
             (btw-tut:init-projection)
             (let ((btr:*snapshot-directory* (and dir (namestring dir))))
               (handler-case (progn (btw-tut:test-switch-two-bottles) t)
                 (error (e) (format t "~&FAILURE: ~a~%" e) nil))))
            (t
             ;; the README's recipe: (init-projection) (spawn-products-one) (interaction)
             (demo:init-projection)
             (demo:spawn-products-one)
             (let ((btr:*snapshot-directory* (and dir (namestring dir)))
                   (*standard-input* (make-string-input-stream (or (getf options :input) "2"))))
               (handler-case
                   (multiple-value-bind (product found) (demo:interaction)
                     (cond ((and product (not found))
                            (format t "~&FAILURE: ~(~a~) not found~%" product)
                            nil)
                           (t t)))
                 (error (e) (format t "~&FAILURE: ~a~%" e) nil))))))))

(defun run-command-line (&optional (args (rest sb-ext:*posix-argv*)))
  "The entry of tools/cram-plans-run: parse ARGS, run, and exit 0 on success, 1 on failure,
2 on bad options."
  (let ((code (handler-case
                  (let ((options (parse-options args)))
                    (cond ((getf options :help)
                           (format t "~a~%" *usage*)
                           0)
                          ((getf options :summary)
                           (summarize (read-json-lines (getf options :summary)))
                           0)
                          ((getf options :batch)
                           (setf *campaign-demo* (getf options :demo))
                           (unless (member *campaign-demo* '("move-bottle" "household") :test #'string=)
                             (usage-fail "--batch runs move-bottle or household, not ~a" *campaign-demo*))
                           (let ((path (run-batch (getf options :batch) :seed (getf options :seed)
                                                                        :jobs (getf options :jobs)
                                                                        :shard (getf options :shard)
                                                                        :results (getf options :results)
                                                                        :memory-every (getf options :memory-every))))
                             (format t "~&results: ~a~%" path)
                             (summarize (read-json-lines (list path)))
                             0))
                          ((getf options :robot)   ; tools/robot-run.lisp, loaded on demand
                           (load (merge-pathnames "robot-run.lisp" *tools-directory*))
                           (if (uiop:symbol-call :cram-plans-demo :run-robot-demo options) 0 1))
                          (t (if (run-demo options) 0 1))))
                (usage-error (e) (format *error-output* "~&cram-plans-run: ~a~%" e) 2))))
    (finish-output)
    (finish-output *error-output*)
    (uiop:quit code)))
