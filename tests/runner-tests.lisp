;;;; Tests of tools/cram-plans-run: options, deterministic batch campaigns, shards, summaries,
;;;; and campaigns that lose a worker (a test hook makes one kill itself with SIGKILL).

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

(test help-prints-usage-and-exits-0
  (multiple-value-bind (code out) (run-cli "--help")
    (is (eql 0 code))
    (is (search "usage: cram-plans-run" out))
    (is (search "--memory-every" out))))

(defun run-cli-env (assignment &rest args)
  (let ((script (asdf:system-relative-pathname "cram-plans" "tools/cram-plans-run")))
    (multiple-value-bind (out err code)
        (uiop:run-program (list* "env" assignment (namestring script) args)
                          :output :string :error-output :string :ignore-error-status t)
      (values code out err))))

(defun run-cli-killing (spec &rest args)
  "Run tools/cram-plans-run with ARGS and the test hook CRAM_PLANS_RUN_TEST_KILL=SPEC, which
makes a worker kill itself with SIGKILL before a run; exit code, output and error output."
  (apply #'run-cli-env (format nil "CRAM_PLANS_RUN_TEST_KILL=~a" spec) args))

(test killed-worker-is-reported-and-its-runs-run-again
  (let ((killed (temp-file "killed.jsonl")) (calm (temp-file "calm.jsonl")))
    (unwind-protect
         (multiple-value-bind (code out err)
             (run-cli-killing "3" "--batch" "6" "--seed" "7" "--jobs" "2" "--memory-every" "2"
                              "--results" killed)
           (declare (ignore out))
           (is (eql 0 code) "a campaign whose worker died still succeeds: ~a" err)
           (is (search "was killed by signal 9 (SIGKILL)" err) "the report names how the worker ended")
           (is (search "before run 3" err) "the report names the run it died on")
           (is (search "| test hook: worker generation 0 kills itself" err)
               "the report shows the tail of the worker's own output")
           (is (search "restarting worker " err))
           (is (search "RSS" err) "--memory-every reports the workers' memory")
           (is (eql 0 (run-cli "--batch" "6" "--seed" "7" "--jobs" "1" "--results" calm)))
           (let ((rk (records killed)))
             (is (equal '(0 1 2 3 4 5) (mapcar (lambda (h) (gethash "index" h)) rk))
                 "every index exactly once, in order")
             (is (equal (mapcar #'record-key (records calm)) (mapcar #'record-key rk))
                 "the runs a dead worker lost give the same results when run again")))
      (dolist (f (list killed calm)) (when (probe-file f) (delete-file f))))))

(test run-that-kills-every-worker-is-recorded-as-failed
  (let ((path (temp-file "always.jsonl")))
    (unwind-protect
         (multiple-value-bind (code out err)
             (run-cli-killing "2:always" "--batch" "5" "--seed" "3" "--jobs" "2" "--results" path)
           (is (eql 0 code) "~a" err)
           (is (search "run 2 killed two workers" err))
           (is (search "all 5 runs reported" err))
           (is (search "5 runs, " out))
           (let* ((rs (records path))
                  (two (find 2 rs :key (lambda (h) (gethash "index" h)))))
             (is (equal '(0 1 2 3 4) (mapcar (lambda (h) (gethash "index" h)) rs)))
             (is (and two (null (gethash "success" two))))
             (is (and two (search "two workers died" (gethash "error" two))))))
      (when (probe-file path) (delete-file path)))))

(test worker-heap-stays-flat-over-a-campaign
  ;; before the fix every init-projection kept its world (~180 KB) for good: +7 MB over 40 runs
  (let ((path (temp-file "flat.jsonl")))
    (unwind-protect
         (multiple-value-bind (code out err)
             (run-cli "--batch" "60" "--seed" "5" "--jobs" "1" "--memory-every" "20" "--results" path)
           (declare (ignore out))
           (is (eql 0 code) "~a" err)
           (let ((heaps (loop with start = 0
                              for at = (search "Lisp heap" err :start2 start)
                              while at
                              collect (let ((*read-default-float-format* 'double-float))
                                        (read-from-string err t nil :start (+ at 10)))
                              do (setf start (1+ at)))))
             (is (= 3 (length heaps)) "one memory report every 20 runs: ~s" heaps)
             (when (= 3 (length heaps))
               (is (< (- (third heaps) (first heaps)) 2.0)
                   "the Lisp heap after a full GC grew from ~,1f MB to ~,1f MB over 40 runs"
                   (first heaps) (third heaps)))))
      (when (probe-file path) (delete-file path)))))

;;; ---- the saved core (tools/cram-plans-core) ----------------------------------------------------

(defun line-without-seconds (line)
  "LINE, a run's JSON line, without its \"seconds\" field (the only wall-clock value)."
  (let* ((start (search "\"seconds\":" line))
         (end (and start (position #\, line :start start))))
    (if end (concatenate 'string (subseq line 0 start) (subseq line (1+ end))) line)))

(defun file-lines (path)
  (with-open-file (s path) (loop for l = (read-line s nil) while l collect l)))

(defun core-script (&rest args)
  "Run tools/cram-plans-core with ARGS (each \"NAME=VALUE\" one sets the environment); its exit
code, standard output (trimmed) and error output."
  (let ((script (asdf:system-relative-pathname "cram-plans" "tools/cram-plans-core")))
    (multiple-value-bind (out err code)
        (uiop:run-program (append (list "env") (remove-if-not (lambda (a) (find #\= a)) args)
                                  (list (namestring script)) (remove-if (lambda (a) (find #\= a)) args))
                          :output :string :error-output :string :ignore-error-status t)
      (values code (string-trim '(#\Space #\Newline) out) err))))

(test saved-core-gives-the-runs-of-loaded-workers
  ;; the tool and its workers start from a saved core; the same campaign from workers that load
  ;; the systems (the fallback when the core cannot be built) gives byte-identical JSON lines
  (let ((cored (temp-file "cored.jsonl")) (loaded (temp-file "loaded.jsonl")))
    (unwind-protect
         (multiple-value-bind (code core) (core-script)
           (is (eql 0 code))
           (is (and (plusp (length core)) (probe-file core)) "tools/cram-plans-core builds the core: ~s" core)
           (multiple-value-bind (out err code)
               (uiop:run-program (list "sbcl" "--core" core "--noinform" "--non-interactive"
                                       "--no-userinit" "--no-sysinit" "--eval"
                                       "(progn (prin1 (list cram-plans-demo::*saved-core-p*
                                                            (cram-native:native-version) ; reopened .so
                                                            (cram-native:world-count)
                                                            (cram-native:world-alive-p
                                                             (btr:world-handle btr:*current-bullet-world*))
                                                            (namestring (uiop:temporary-directory))))
                                               (terpri))")
                                 :output :string :error-output :string :ignore-error-status t)
             (declare (ignore err))
             (is (eql 0 code))
             (let ((state (ignore-errors (read-from-string out))))
               (is (eq t (first state)) "the core knows it is one: ~s" out)
               (is (integerp (second state)) "libcram_native.so answers in the core: ~s" out)
               (is (eql 1 (third state)) "one native world, the fresh belief state: ~s" out)
               (is (eq t (fourth state)) "the belief state is a live world: ~s" out)))
           (is (eql 0 (run-cli "--batch" "5" "--seed" "13" "--jobs" "2" "--results" cored)))
           (multiple-value-bind (code out err)
               (run-cli-env "CRAM_PLANS_CORE_DIR=/dev/null/no-core" "--batch" "5" "--seed" "13"
                            "--jobs" "2" "--results" loaded)
             (declare (ignore out))
             (is (eql 0 code) "~a" err)
             (is (search "warning: cannot create /dev/null/no-core; loading the systems instead" err)
                 "without a core the tool says so in one line and loads the systems"))
           (let ((a (mapcar #'line-without-seconds (file-lines cored)))
                 (b (mapcar #'line-without-seconds (file-lines loaded))))
             (is (= 5 (length a)))
             (is (equal a b) "the core's runs equal the loaded workers' runs byte for byte")))
      (dolist (f (list cored loaded)) (when (probe-file f) (delete-file f))))))

(test saved-core-builds-race-safely
  ;; two processes building the same core at once: both get it, no temporary file is left
  (let ((dir (uiop:ensure-directory-pathname (temp-file "cores"))))
    (unwind-protect
         (let* ((script (namestring (asdf:system-relative-pathname "cram-plans" "tools/cram-plans-core")))
                (env (format nil "CRAM_PLANS_CORE_DIR=~a" (string-right-trim "/" (namestring dir))))
                (processes (loop repeat 2
                                 collect (uiop:launch-program (list "env" env script)
                                                              :output :stream :error-output nil)))
                (paths (mapcar (lambda (p)
                                 (prog1 (string-trim '(#\Space #\Newline)
                                                     (uiop:slurp-stream-string (uiop:process-info-output p)))
                                   (uiop:wait-process p)))
                               processes)))
           (is (equal (first paths) (second paths)) "both builders name the same core: ~s" paths)
           (is (and (plusp (length (first paths))) (probe-file (first paths))))
           (is (equal (list (first paths))
                      (mapcar #'namestring (directory (merge-pathnames "*.core" dir)))))
           (is (null (directory (merge-pathnames "*.tmp-*" dir))) "no temporary core is left")
           (multiple-value-bind (code key) (core-script "--key")
             (is (eql 0 code))
             (is (search key (first paths)) "the core is named by the key of its inputs"))
           (multiple-value-bind (code key) (core-script "CL_SOURCE_REGISTRY=/nonexistent//:" "--key")
             (declare (ignore code))
             (is (not (search key (first paths))) "another input gives another key")))
      (uiop:delete-directory-tree dir :validate t :if-does-not-exist :ignore))))

(test a-household-campaign-records-each-run
  ;; two seeded household runs on two workers: one JSON line each, with the demo's name, the
  ;; outcome, and the sweeps (what the paths of its motions hit: the demo's arms reach into drawers
  ;; past their fronts, so a run has some); the summary counts them
  (let ((results (temp-file "household.jsonl")))
    (unwind-protect
         (multiple-value-bind (code out err)
             (run-cli "--demo" "household" "--batch" "2" "--seed" "1" "--jobs" "2" "--results" results)
           (is (member code '(0 1)) "exit ~a: ~a" code err)
           (let ((records (records results)))
             (is (= 2 (length records)))
             (dolist (r records)
               (is (equal "household" (gethash "demo" r)))
               (is (member (gethash "success" r) '(t nil)))
               (is (integerp (gethash "sweeps" r)) "no sweep count: ~s" (alexandria:hash-table-alist r)))
             (is (some (lambda (r) (plusp (gethash "sweeps" r 0))) records)
                 "a household run with no sweep counted"))
           (is (search "2 runs" out) "no summary: ~a" out)
           (is (search "sweeps (a moving link or carried object and what its path hits)" out)))
      (ignore-errors (delete-file results)))))

;;; ---- the pool the workers of a campaign take their runs from (tools/campaign-pool.lisp) -----------

(defparameter *pool-form*
  "(let* ((dir (uiop:ensure-directory-pathname
               (format nil \"~apool-test-~d\" (namestring (uiop:temporary-directory)) (sb-posix:getpid))))
         (out '()))
    (unwind-protect
         (progn
           ;; two workers taking turns: each claims the next run no one has
           (let* ((pool (cram-plans-demo::write-pool dir '(10 11 12 13 14)))
                  (a (cram-plans-demo::run-source '(99) pool 0 0))
                  (b (cram-plans-demo::run-source '() pool 1 0)))
             (push (list (funcall a) (funcall a) (funcall b) (funcall a) (funcall b) (funcall b)
                         (funcall a) (funcall b))
                   out)
             (push (list (cram-plans-demo::pool-claims pool 0 0) (cram-plans-demo::pool-claims pool 1 0)
                         (cram-plans-demo::pool-claims pool 1 1))
                   out))
           (uiop:delete-directory-tree dir :validate t)
           ;; two threads claiming at once from a pool of 600
           (let* ((pool (cram-plans-demo::write-pool dir (loop for i below 600 collect i)))
                  (got (make-array 2 :initial-element nil))
                  (threads (loop for w below 2
                                 collect (let ((w w))
                                           (sb-thread:make-thread
                                            (lambda ()
                                              (loop with next = (cram-plans-demo::run-source '() pool w 0)
                                                    for i = (funcall next) while i
                                                    do (push i (aref got w)))))))))
             (mapc (function sb-thread:join-thread) threads)
             (push (list (reverse (aref got 0)) (reverse (aref got 1))
                         (cram-plans-demo::pool-claims pool 0 0) (cram-plans-demo::pool-claims pool 1 0))
                   out)))
      (uiop:delete-directory-tree dir :validate t :if-does-not-exist :ignore))
    (prin1 (reverse out)) (terpri))"
  "A program for a process of the saved core: claims from campaign pools, printed as a list.")

(test pool-gives-each-run-to-one-worker
  (multiple-value-bind (code core) (core-script)
    (is (eql 0 code))
    (multiple-value-bind (out err code)
        (uiop:run-program (list "sbcl" "--core" core "--noinform" "--non-interactive" "--no-userinit"
                                "--no-sysinit" "--eval" *pool-form*)
                          :output :string :error-output :string :ignore-error-status t)
      (is (eql 0 code) "~a" err)
      (destructuring-bind (&optional turns claims threads) (ignore-errors (read-from-string out))
        ;; the given run first, then the pool's runs in order, each to the first who asks
        (is (equal '(99 10 11 12 13 14 nil nil) turns) "~s" turns)
        (is (equal '((10 12) (11 13 14) ()) claims) "~s" claims)
        (destructuring-bind (&optional a b claims-a claims-b) threads
          (is (equal (loop for i below 600 collect i) (sort (copy-list (append a b)) #'<))
              "every run of the pool exactly once: ~d and ~d runs" (length a) (length b))
          (is (equal a claims-a))
          (is (equal b claims-b)))))))

(test saved-core-holds-a-warm-up-run-but-no-trace-of-it
  ;; the core is saved after a move-bottle run of its own (what a plan compiles on first use,
  ;; the IK chains' reach maps), which leaves no recorded run, run number or world behind
  (multiple-value-bind (code core) (core-script)
    (is (eql 0 code))
    (multiple-value-bind (out err code)
        (uiop:run-program (list "sbcl" "--core" core "--noinform" "--non-interactive" "--no-userinit"
                                "--no-sysinit" "--eval"
                                "(progn (prin1 (list cram-viewer::*run-counter*
                                                     (length (cram-viewer:recorded-runs))
                                                     cram-viewer:*record-runs*
                                                     (length urdf-proj::*kept-reach-maps*)
                                                     (cram-native:world-count)))
                                        (terpri))")
                          :output :string :error-output :string :ignore-error-status t)
      (is (eql 0 code) "~a" err)
      (let ((state (ignore-errors (read-from-string out))))
        (is (equal '(0 0 t 2 1) state) "run counter, recorded runs, recorder, kept reach maps, worlds: ~s"
            state)))))

;;; ---- the CPU of each worker (tools/worker-cpu.lisp) ------------------------------------------

(defparameter *worker-cpu-form*
  "(flet ((in-thread (pin)
           ;; in a thread of its own, whose CPUs are its own
           (sb-thread:join-thread
            (sb-thread:make-thread
             (lambda ()
               (let ((cram-plans-demo::*pin-workers* pin))
                 (list (cram-plans-demo::pin-to-slot-cpu 1)
                       (cpl::mask-cpus (cpl::thread-cpu-mask)))))))))
    (prin1 (list (mapcar (lambda (slot) (cram-plans-demo::slot-cpu slot '(0 1))) '(0 1 2 3))
                 (mapcar (lambda (slot) (cram-plans-demo::slot-cpu slot '(2 5 7))) '(0 1 2 3))
                 (cram-plans-demo::slot-cpu 0 '())
                 (cpl::mask-cpus (cpl::cpu-mask 3))
                 (cpl::mask-cpus (cpl::thread-cpu-mask))
                 (in-thread t)
                 (in-thread nil)))
    (terpri))"
  "A program for a process of the saved core: the CPUs workers take, printed as a list.")

(test workers-take-the-cpus-in-turn
  (multiple-value-bind (code core) (core-script)
    (is (eql 0 code))
    (multiple-value-bind (out err code)
        (uiop:run-program (list "sbcl" "--core" core "--noinform" "--non-interactive" "--no-userinit"
                                "--no-sysinit" "--eval" *worker-cpu-form*)
                          :output :string :error-output :string :ignore-error-status t)
      (is (eql 0 code) "~a" err)
      (destructuring-bind (&optional in-turn three none mask cpus pinned free)
          (ignore-errors (read-from-string out))
        (is (equal '(0 1 0 1) in-turn))
        (is (equal '(2 5 7 2) three))
        (is (null none))
        (is (equal '(3) mask))
        (if (< (length cpus) 2)
            (is (equal (list nil cpus) pinned) "one CPU: nothing to choose")
            ;; a worker of slot 1 keeps to the second CPU it may use; with pinning off, to all
            (progn (is (equal (list (second cpus) (list (second cpus))) pinned) "~s" out)
                   (is (equal (list nil cpus) free))))))))

(test workers-are-left-free-by-the-environment-of-their-run
  ;; the saved core was built without CRAM_PLANS_PIN_WORKERS: the worker's own environment counts
  (multiple-value-bind (code core) (core-script)
    (is (eql 0 code))
    (multiple-value-bind (out err code)
        (uiop:run-program (list "env" "CRAM_PLANS_PIN_WORKERS=0" "sbcl" "--core" core "--noinform"
                                "--non-interactive" "--no-userinit" "--no-sysinit" "--eval"
                                "(progn (prin1 (sb-thread:join-thread
                                                (sb-thread:make-thread
                                                 (lambda ()
                                                   (list (cram-plans-demo::pin-to-slot-cpu 1)
                                                         (cpl::mask-cpus (cpl::thread-cpu-mask)))))))
                                        (prin1 (cpl::mask-cpus (cpl::thread-cpu-mask)))
                                        (terpri))")
                          :output :string :error-output :string :ignore-error-status t)
      (is (eql 0 code) "~a" err)
      (with-input-from-string (s out)
        (let ((in-thread (ignore-errors (read s))) (cpus (ignore-errors (read s))))
          (is (equal (list nil cpus) in-thread) "left on every CPU it may use: ~s" out))))))
