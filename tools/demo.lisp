;;;; Headless demos of cram-plans: (cram-plans-demo:main "out") runs move-bottle in
;;;; projection, writes pictures and the task tree, and exits 0 when the bottle arrived.
;;;; (cram-plans-demo:run-command-line args) is the entry of tools/cram-plans-run.

(require :asdf)
(let ((root (merge-pathnames "../" (make-pathname :name nil :type nil
                                                   :defaults (or *load-truename* *default-pathname-defaults*)))))
  (handler-bind ((warning #'muffle-warning))
    ;; the truename (no "tools/../"): the pathname ASDF's source registry finds, so that later
    ;; lookups (ASDF:SYSTEM-RELATIVE-PATHNAME ...) do not load cram-plans.asd again
    (asdf:load-asd (truename (merge-pathnames "cram-plans.asd" root)))
    (asdf:load-system "cram-plans/cram-bullet-world-tutorial")
    (asdf:load-system "cram-plans/cram-pepper-demo")
    (asdf:load-system "cram-plans/cram-projection-demos")
    (asdf:load-system "cram-plans/replay")   ; runs recorded; --out writes replay.html
    (asdf:load-system "yason")
    (require :sb-posix)))

(defpackage :cram-plans-demo
  (:use :cl)
  (:export #:main #:run-command-line #:run-move-bottle #:random-bottle-pose #:run-batch
           #:summarize #:read-json-lines #:*tolerance*))

(in-package :cram-plans-demo)

(defparameter *tools-directory*
  (make-pathname :name nil :type nil :defaults (or *load-truename* *default-pathname-defaults*))
  "The tools/ directory of cram-plans.")

(defparameter *tolerance* 0.03
  "Metres within which the bottle must end at BTW-TUT:*FINAL-OBJECT-DESTINATION*.")

(defun distance-to-destination ()
  (let ((o (btr:object btr:*current-bullet-world* 'btw-tut::bottle-1)))
    (if o
        (cl-transforms:v-dist (cl-transforms:origin (btr:pose o))
                              (cl-transforms:origin btw-tut:*final-object-destination*))
        most-positive-double-float)))

(defparameter *recovery-lines*
  '((:look-direction :warn "PERCEPTION-FAILURE") (:new-grasp :info "TRYING-NEW-GRASP")
    (:new-arm :info "TRYING-NEW-ARM") (:grasp-failure :warn "GRASP-FAILURE")
    (:perception-failure :warn "PERCEPTION-FAILURE"))
  "(key level tag): a move-bottle run's recovery or failure KEY counts its log lines of LEVEL
tagged (TAG): `Turning head.', `Trying to grasp from', `Trying the … arm', `[(GRASP-FAILURE)
WARN]', `[(PERCEPTION-FAILURE) WARN]'.")

(defun recovery-counts (tally)
  "The plist of recovery and failure counts of a run whose log lines CPL:*LOG-TALLY* counted
in TALLY."
  (loop for (key level tag) in *recovery-lines*
        collect key
        collect (let ((n 0))
                  (maphash (lambda (line count)
                             (destructuring-bind (l &rest tags) line
                               (when (and (eq l level) tags (null (cdr tags)) (symbolp (car tags))
                                          (string= tag (symbol-name (car tags))))
                                 (incf n count))))
                           tally)
                  n)))

(defvar *preparsed-urdfs* '()
  "(text . robot) pairs: URDF texts and what CL-URDF:PARSE-URDF made of them when the saved
core was built (SAVE-CORE in tools/build-core.lisp); empty in a process that loaded the systems.")

(defun call-with-preparsed-urdfs (thunk)
  "Call THUNK; meanwhile CL-URDF:PARSE-URDF of a text in *PREPARSED-URDFS* returns its parse
from the saved core (the same text gives the same robot) instead of parsing it again."
  (if (null *preparsed-urdfs*)
      (funcall thunk)
      (progn
        (sb-int:encapsulate 'cl-urdf:parse-urdf 'preparsed
                            (lambda (parse &rest args)
                              (or (and (= 1 (length args)) (stringp (first args))
                                       (cdr (assoc (first args) *preparsed-urdfs* :test #'string=)))
                                  (apply parse args))))
        (unwind-protect (funcall thunk)
          (sb-int:unencapsulate 'cl-urdf:parse-urdf 'preparsed)))))

(defun reset-projection ()
  "BTW-TUT:INIT-PROJECTION for many runs in one process (a campaign worker). INIT-PROJECTION
gives a copy of the belief state it built first, so every run starts from the same copy and a
run's result does not depend on which runs this process made before it; the first call takes
the URDFs parsed when the saved core was built."
  (if (btw-tut::template-world-for btw-tut::*kitchen-urdf* btw-tut::*robot-urdf*)
      (btw-tut:init-projection)
      (call-with-preparsed-urdfs #'btw-tut:init-projection)))

(defun monotonic-seconds ()
  "Seconds on the system's monotonic clock, to the nanosecond (SBCL's internal real time
advances in steps of a few milliseconds)."
  (multiple-value-bind (seconds nanoseconds) (sb-unix::clock-gettime 1)   ; CLOCK_MONOTONIC
    (+ seconds (* nanoseconds 1d-9))))

(defun run-move-bottle (pose &key out-dir (pictures t) (log-stream *standard-output*) reuse-world)
  "Run move-bottle with the bottle at POSE in a fresh belief state (with REUSE-WORLD, a copy of
the one this process made first: see RESET-PROJECTION). Returns a plist: :success, :distance,
:seconds, :error, the recovery counts of the log (*RECOVERY-LINES*), and :log, the log's text
\(NIL when LOG-STREAM discards everything, a broadcast stream without components: then the log
is neither formatted nor kept)."
  (if reuse-world (reset-projection) (btw-tut:init-projection))
  (let* ((btr:*snapshot-directory* (and pictures out-dir (namestring out-dir)))
         ;; a log that goes nowhere is not captured either: nobody formats its lines
         (quiet (and (typep log-stream 'broadcast-stream)
                     (null (broadcast-stream-streams log-stream))))
         (captured (and (not quiet) (make-string-output-stream)))
         (stream (if quiet log-stream (make-broadcast-stream captured log-stream)))
         (tally (make-hash-table :test 'equal))
         (start (monotonic-seconds))
         (sweeps 0)
         (error nil))
    (when (and pictures out-dir)
      (btw-tut::spawn-bottle pose)
      (btr:png-snapshot (merge-pathnames "start.png" out-dir) :look-at '(-1.5 -0.7 0.8)))
    (let ((cpl:*log-stream* stream) (cpl:*log-tally* tally)
          (urdf-proj:*sweep-hooks* (cons (lambda (sweep) (declare (ignore sweep)) (incf sweeps))
                                         urdf-proj:*sweep-hooks*)))
      (handler-case
          (progn
            (btw-tut:move-bottle pose))
        (error (e) (setf error (princ-to-string e)))))
    (let* ((seconds (- (monotonic-seconds) start))
           (distance (distance-to-destination))
           (log (and captured (get-output-stream-string captured))))
      (append (list :success (and (null error) (<= distance *tolerance*))
                    :distance (if (< distance 1d6) distance nil)
                    :seconds (float seconds 1d0)
                    :error error
                    :sweeps sweeps)
              (recovery-counts tally)
              (list :log log)))))

(defmethod coe:on-event grasped-snapshot ((event cpoe:object-attached-robot))
  (let ((dir btr:*snapshot-directory*))
    (when (and dir (boundp '*snapshot-grasped*) (symbol-value '*snapshot-grasped*))
      (btr:png-snapshot (merge-pathnames "grasped.png" (uiop:ensure-directory-pathname dir))
                        :look-at '(-1.5 -0.5 0.9)))))

(defvar *snapshot-grasped* nil "When true, the first grasp of a run writes grasped.png.")
(pushnew '*snapshot-grasped* cpl:*inherited-specials*)
(pushnew 'btr:*snapshot-directory* cpl:*inherited-specials*)

(defun write-task-tree (out-dir)
  (let ((tree cpl:*last-task-tree*))
    (when tree
      (with-open-file (s (merge-pathnames "task-tree.json" out-dir) :direction :output
                                                                     :if-exists :supersede)
        (write-string (cpl:task-tree-to-json tree) s))
      (cpl:write-task-tree-html (merge-pathnames "task-tree.html" out-dir) tree))))

(defun main (out-dir &key (pose btw-tut:*bottle-pose-in-view*))
  "Run move-bottle headless with the bottle at POSE, print the CRAM-style log, write
start.png, grasped.png, placed.png, task-tree.json and task-tree.html to OUT-DIR and exit with
status 0 when the bottle ends within *TOLERANCE* of the destination, else 1."
  (let* ((dir (uiop:ensure-directory-pathname (merge-pathnames out-dir (uiop:getcwd))))
         (result (progn (ensure-directories-exist dir)
                        (let ((*snapshot-grasped* t))
                          (run-move-bottle pose :out-dir dir)))))
    (btr:png-snapshot (merge-pathnames "placed.png" dir) :look-at '(-0.8 2.0 0.9))
    (handler-case (write-task-tree dir)
      (error (e) (format t "~&Task tree not written: ~a~%" e)))
    (format t "~&~:[FAILURE~;SUCCESS~]: bottle ~@[~,3f m~] from the destination (tolerance ~a m)~
               ~@[; error: ~a~]~%Pictures and task tree in ~a~%"
            (getf result :success) (getf result :distance) *tolerance* (getf result :error)
            (namestring dir))
    (finish-output)
    (uiop:quit (if (getf result :success) 0 1))))

;; one compilation unit: runner.lisp calls functions it defines further down
(with-compilation-unit ()
  (load (merge-pathnames "runner.lisp" *tools-directory*))
  (load (merge-pathnames "campaign-pool.lisp" *tools-directory*))
  (load (merge-pathnames "worker-cpu.lisp" *tools-directory*))
  (load (merge-pathnames "household-run.lisp" *tools-directory*)))
