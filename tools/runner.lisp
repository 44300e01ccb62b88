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
  "usage: cram-plans-run [--demo move-bottle|switch-bottles|pepper] [--seed N]
                      [--bottle-pose x,y,z[,yaw]] [--input \"1 1\"] [--out DIR] [--quiet]
       cram-plans-run --batch N [--seed N] [--jobs J] [--shard I/N] [--results FILE]
       cram-plans-run --summary FILE...")

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
                          (unless (member d '("move-bottle" "switch-bottles" "pepper") :test #'string=)
                            (usage-fail "--demo ~s is unknown, expected move-bottle, switch-bottles or pepper" d))
                          (setf (getf options :demo) d)))
                       ((string= option "--seed") (setf (getf options :seed) (parse-integer-option option (value))))
                       ((string= option "--bottle-pose") (setf (getf options :pose) (parse-pose-option (value))))
                       ((string= option "--input") (setf (getf options :input) (value)))
                       ((string= option "--out") (setf (getf options :out) (value)))
                       ((string= option "--quiet") (setf (getf options :quiet) t))
                       ((string= option "--batch") (setf (getf options :batch) (parse-integer-option option (value) :min 1)))
                       ((string= option "--jobs") (setf (getf options :jobs) (parse-integer-option option (value) :min 1)))
                       ((string= option "--results") (setf (getf options :results) (value)))
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
                       (t (usage-fail "unknown option ~s~%~a" option *usage*))))))
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

(defun run-record (campaign-seed index)
  "Run move-bottle number INDEX of the campaign CAMPAIGN-SEED; a hash table for one JSON line."
  (let ((seed (run-seed campaign-seed index)))
    (multiple-value-bind (pose numbers) (random-bottle-pose seed)
      (seed-everything seed)
      (let ((result (run-move-bottle pose :pictures nil :log-stream (make-broadcast-stream)))
            (record (make-hash-table :test 'equal)))
        (setf (gethash "index" record) index
              (gethash "seed" record) seed
              (gethash "pose" record) numbers
              (gethash "success" record) (and (getf result :success) t)
              (gethash "distance" record) (getf result :distance)
              (gethash "seconds" record) (getf result :seconds)
              (gethash "error" record) (let ((e (getf result :error)))
                                         (and e (first-line e))))
        (dolist (key '(:look-direction :new-grasp :new-arm :grasp-failure :perception-failure))
          (setf (gethash (string-downcase (substitute #\_ #\- (symbol-name key))) record)
                (getf result key)))
        record))))

(defun first-line (text)
  (subseq text 0 (or (position #\Newline text) (length text))))

(defun record->json (record)
  (with-output-to-string (s)
    (yason:encode record s)))

(defun worker (campaign-seed indices path)
  "Run the campaign runs INDICES, appending one JSON line per run to PATH."
  (with-open-file (out path :direction :output :if-exists :append :if-does-not-exist :create)
    (dolist (i indices)
      (write-line (record->json (run-record campaign-seed i)) out)
      (finish-output out)))
  (uiop:quit 0))

;;; ---- campaigns -----------------------------------------------------------------------------------

(defun shard-indices (n shard)
  "The run indices 0…N-1 of SHARD (I . COUNT): every COUNT-th index starting at I-1."
  (destructuring-bind (i . count) (or shard '(1 . 1))
    (loop for k from (1- i) below n by count collect k)))

(defun count-lines-of (path)
  (if (probe-file path)
      (with-open-file (s path) (loop for line = (read-line s nil) while line count t))
      0))

(defun progress-bar (done total)
  (let* ((width 40) (filled (if (zerop total) width (floor (* width done) total))))
    (format *error-output* "~c[~a~a] ~d/~d" #\Return (make-string filled :initial-element #\#)
            (make-string (- width filled) :initial-element #\.) done total)
    (finish-output *error-output*)))

(defun run-batch (n &key (seed 1) (jobs 2) shard results)
  "Run the runs of SHARD (default: all N) of the campaign SEED in JOBS worker processes, write
their JSON lines in index order to RESULTS (default batch-SEED.jsonl) and return the path."
  (let* ((indices (shard-indices n shard))
         (results (or results (format nil "batch-~d~@[-~{~d-of-~d~}~].jsonl" seed
                                      (and shard (list (car shard) (cdr shard))))))
         (tmp (uiop:ensure-directory-pathname
               (format nil "~a/cram-plans-batch-~d-~d" (string-right-trim "/" (namestring (uiop:temporary-directory)))
                       (sb-posix:getpid) (get-universal-time))))
         (jobs (max 1 (min jobs (length indices))))
         (slices (loop for j below jobs
                       collect (loop for k in indices for pos from 0
                                     when (= (mod pos jobs) j) collect k)))
         (files (loop for j below jobs collect (merge-pathnames (format nil "worker-~d.jsonl" j) tmp)))
         (demo (namestring (merge-pathnames "demo.lisp" *tools-directory*))))
    (ensure-directories-exist tmp)
    (let ((processes
            (loop for slice in slices for file in files
                  collect (uiop:launch-program
                           (list "sbcl" "--noinform" "--non-interactive" "--no-userinit" "--no-sysinit"
                                 "--eval" "(require :asdf)" "--load" demo
                                 "--eval" (format nil "(cram-plans-demo::worker ~d '~s ~s)"
                                                  seed slice (namestring file)))
                           :output nil :error-output nil))))
      (loop with shown = -1
            for done = (reduce #'+ (mapcar #'count-lines-of files))
            do (unless (= done shown) (progress-bar done (length indices)) (setf shown done))
            while (some #'uiop:process-alive-p processes)
            do (sleep 0.5))
      (progress-bar (reduce #'+ (mapcar #'count-lines-of files)) (length indices))
      (terpri *error-output*)
      (mapc #'uiop:wait-process processes))
    (let ((lines (sort (loop for f in files
                             append (with-open-file (s f :if-does-not-exist nil)
                                      (and s (loop for l = (read-line s nil) while l collect l))))
                       #'< :key (lambda (l) (gethash "index" (yason:parse l))))))
      (with-open-file (out results :direction :output :if-exists :supersede)
        (dolist (l lines) (write-line l out)))
      (uiop:delete-directory-tree tmp :validate t :if-does-not-exist :ignore)
      (unless (= (length lines) (length indices))
        (error "batch: ~d of ~d runs reported a result (a worker died)" (length lines) (length indices)))
      results)))

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
    (dolist (key '("look_direction" "new_grasp" "new_arm" "grasp_failure" "perception_failure"))
      (let ((runs (count-if (lambda (r) (plusp (or (gethash key r) 0))) records))
            (total (reduce #'+ records :key (lambda (r) (or (gethash key r) 0)))))
        (format stream "  ~20a ~5d / ~5d  ~a~%" key runs total
                (make-string (if (zerop n) 0 (round (* 30 runs) n)) :initial-element #\#))))
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
                 (ignore-errors (write-task-tree dir)))
               (format t "~&~:[FAILURE~;SUCCESS~]: bottle ~@[~,3f m~] from the destination~@[; error: ~a~]~%"
                       (getf result :success) (getf result :distance) (getf result :error))
               (getf result :success)))
            ((string= (getf options :demo) "switch-bottles")
             (btw-tut:init-projection)
             (let ((btr:*snapshot-directory* (and dir (namestring dir))))
               (handler-case (progn (btw-tut:test-switch-two-bottles) t)
                 (error (e) (format t "~&FAILURE: ~a~%" e) nil))))
            (t
             (demo:init-projection)
             (let ((btr:*snapshot-directory* (and dir (namestring dir)))
                   (*standard-input* (make-string-input-stream (or (getf options :input) "2"))))
               (handler-case (progn (demo:interaction) t)
                 (error (e) (format t "~&FAILURE: ~a~%" e) nil))))))))

(defun run-command-line (&optional (args (rest sb-ext:*posix-argv*)))
  "The entry of tools/cram-plans-run: parse ARGS, run, and exit 0 on success, 1 on failure,
2 on bad options."
  (let ((code (handler-case
                  (let ((options (parse-options args)))
                    (cond ((getf options :summary)
                           (summarize (read-json-lines (getf options :summary)))
                           0)
                          ((getf options :batch)
                           (let ((path (run-batch (getf options :batch) :seed (getf options :seed)
                                                                        :jobs (getf options :jobs)
                                                                        :shard (getf options :shard)
                                                                        :results (getf options :results))))
                             (format t "~&results: ~a~%" path)
                             (summarize (read-json-lines (list path)))
                             0))
                          (t (if (run-demo options) 0 1))))
                (usage-error (e) (format *error-output* "~&cram-plans-run: ~a~%" e) 2))))
    (finish-output)
    (finish-output *error-output*)
    (uiop:quit code)))
