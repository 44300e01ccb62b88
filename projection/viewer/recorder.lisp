;;;; Recording projection runs: after each motion of the simulated robot the belief state is
;;;; stored cheaply (object poses and joint values, one double vector per step), grouped into
;;;; runs by the top-level task tree the motion belongs to; location designators' costmaps and
;;;; samples and LOOK-AT targets are kept with the step they led to.

(in-package :cram-viewer)

(defvar *record-runs* t
  "When true (the default), every motion in projection records a replay step. Recording costs a
few microseconds per motion (see tests/bench/): base poses and joint values only.")

(defvar *max-recorded-runs* 16
  "How many runs RECORDED-RUNS keeps; older ones are dropped (so batch campaigns keep nothing
but the last few).")

(defvar *max-steps-per-run* 5000
  "Steps beyond this many in one run are not recorded (a run that loops stays bounded).")

(defstruct (run (:constructor %make-run))
  "One recorded projection run: the steps of one top-level plan (or of motions outside any)."
  (id 0 :type integer)
  (root nil)                       ; task tree root node, or NIL
  (world-handle -1)                ; native handle of the world of the last step
  (start-unix 0d0 :type double-float)
  (steps (make-array 16 :adjustable t :fill-pointer 0))
  (descriptors (make-hash-table :test 'equal)) ; object name → descriptor (first seen)
  (last-names nil)
  (costmaps-dropped nil))          ; true once DROP-OLD-COSTMAPS went through this older run

(defstruct (replay-step (:conc-name step-) (:constructor %make-step))
  "The belief state after one motion."
  (index 0 :type integer)
  (label "" :type string)
  (unix 0d0 :type double-float)
  (node nil)                       ; the motion's task tree node (outcome known later)
  (names nil)
  (state nil)
  (overlays nil))                  ; list of overlay JSON objects

(setf (documentation 'run-id 'function) "The number of a recorded run (1, 2, ...)."
      (documentation 'run-steps 'function) "The steps of a recorded run, a vector, oldest first."
      (documentation 'run-root 'function) "The task tree root of a run, or NIL."
      (documentation 'step-label 'function) "The motion label of a step (\"going\", \"looking\" ...)."
      (documentation 'step-index 'function) "The position of a step in its run, from 0.")

(defvar *runs* '() "Recorded runs, newest first.")
(defvar *run-counter* 0)
(defvar *recorder-lock* (sb-thread:make-mutex :name "viewer recorder"))
(defvar *pending-overlays* '()
  "Overlays noted since the last step (location samples, look targets), newest first.")

(defvar *generation* 0
  "Incremented whenever a step is recorded or an overlay changes: the live viewer waits on it.")
(defvar *generation-queue* (sb-thread:make-waitqueue :name "viewer generation"))
(defvar *generation-waiters* 0
  "How many threads wait in WAIT-FOR-CHANGE (under *RECORDER-LOCK*): a change wakes the queue
only when someone waits on it, so a run nobody watches makes no wake-up system call.")

(defun note-change ()
  "With *RECORDER-LOCK* held: count a change and wake the threads waiting for one."
  (incf *generation*)
  (when (plusp *generation-waiters*)
    (sb-thread:condition-broadcast *generation-queue*)))

(defun bump-generation ()
  "Note a change and wake the live viewer's streams."
  (sb-thread:with-mutex (*recorder-lock*)
    (note-change)))

(defun wait-for-change (generation timeout)
  "Wait up to TIMEOUT seconds until *GENERATION* differs from GENERATION; return it."
  (sb-thread:with-mutex (*recorder-lock*)
    (when (= generation *generation*)
      (incf *generation-waiters*)
      (unwind-protect
           (sb-thread:condition-wait *generation-queue* *recorder-lock* :timeout timeout)
        (decf *generation-waiters*)))
    *generation*))

(defun recorded-runs ()
  "The recorded runs, oldest first (at most *MAX-RECORDED-RUNS*)."
  (sb-thread:with-mutex (*recorder-lock*) (reverse *runs*)))

(defun last-run ()
  "The most recently recorded run, or NIL."
  (sb-thread:with-mutex (*recorder-lock*) (first *runs*)))

(defun find-run (id)
  "The recorded run numbered ID; an error naming ID and the known ones when it is gone."
  (or (find id (recorded-runs) :key #'run-id)
      (error "viewer: there is no recorded run ~s; recorded runs: ~{~d~^ ~}"
             id (mapcar #'run-id (recorded-runs)))))

(defvar *overlays-with-costmaps* '()
  "The overlays that still hold a costmap, newest first (at most *MAX-RECORDED-COSTMAPS*).")

(defun clear-runs ()
  "Forget every recorded run."
  (sb-thread:with-mutex (*recorder-lock*)
    (setf *runs* '() *pending-overlays* '() *overlays-with-costmaps* '()))
  t)

(defun run-label (run)
  "A short name of RUN: the top-level's name and its number."
  (format nil "run ~d~@[: ~a~]" (run-id run)
          (and (run-root run) (cpl::name-string (cpl:node-name (run-root run))))))

(defun task-root (node)
  (loop while (and node (cpl:node-parent node)) do (setf node (cpl:node-parent node)))
  node)

(defun current-run (root world)
  "The run that a step under ROOT in WORLD belongs to (a new one when ROOT changed)."
  (let ((run (first *runs*)))
    (if (and run (eq (run-root run) root)
             (or root (= (run-world-handle run) (btr:world-handle world))))
        run
        (let ((new (%make-run :id (incf *run-counter*) :root root
                              :world-handle (btr:world-handle world)
                              :start-unix (cpl::unix-time))))
          (push new *runs*)
          (when (> (length *runs*) *max-recorded-runs*)
            (setf *runs* (subseq *runs* 0 *max-recorded-runs*)))
          (drop-runs-beyond-step-budget)
          (drop-old-costmaps)
          new))))

(defvar *max-recorded-steps* 2000
  "How many steps the recorded runs together keep: when a new run starts, the oldest runs are
dropped until the others hold at most this many (a long household run records hundreds of
steps, each with the task tree node it belongs to).")

(defun drop-runs-beyond-step-budget ()
  "Drop the oldest recorded runs (never the newest) while the runs hold more than
*MAX-RECORDED-STEPS* steps."
  (loop while (and (rest *runs*)
                   (> (reduce #'+ *runs* :key (lambda (r) (fill-pointer (run-steps r))))
                      *max-recorded-steps*))
        do (setf *runs* (butlast *runs*))))

(defvar *max-runs-with-costmaps* 2
  "How many of the newest recorded runs keep the costmaps of their location designators (a
costmap is a grid of doubles; a household run samples hundreds): older runs keep the samples.")

(defun drop-old-costmaps ()
  "Forget the costmaps of the overlays of all but the *MAX-RUNS-WITH-COSTMAPS* newest runs, so
that recording many long runs stays bounded. A run older than the newest gets no steps any more:
once gone through, it is not gone through again."
  (dolist (run (nthcdr *max-runs-with-costmaps* *runs*))
    (unless (run-costmaps-dropped run)
      (loop for step across (run-steps run)
            do (dolist (overlay (step-overlays step))
                 (when (and (hash-table-p overlay) (gethash "costmap" overlay))
                   (setf (gethash "costmap" overlay) nil))))
      (unless (eq run (first *runs*))
        (setf (run-costmaps-dropped run) t)))))

(defvar *max-recorded-costmaps* 24
  "How many overlays keep their location designator's costmap, all runs and pending overlays
together: when another costmap is noted, the oldest one kept is dropped (its samples stay). A
costmap is a grid of doubles (0.7 MB in the kitchen) and a household run samples hundreds of
one-off designators while it checks base poses, so keeping every costmap of a run filled the
heap.")

(defun keep-overlay-costmap (overlay)
  "Note that OVERLAY holds a costmap; drop the costmaps of the oldest overlays beyond
*MAX-RECORDED-COSTMAPS*. Call with *RECORDER-LOCK* held."
  (push overlay *overlays-with-costmaps*)
  (let ((beyond (nthcdr (max 0 *max-recorded-costmaps*) *overlays-with-costmaps*)))
    (when beyond
      (dolist (old beyond) (setf (gethash "costmap" old) nil))
      (setf *overlays-with-costmaps*
            (subseq *overlays-with-costmaps* 0 (max 0 *max-recorded-costmaps*))))))

(defun record-motion (label &optional (world btr:*current-bullet-world*))
  "Record the state of WORLD after the motion LABEL as a step of the current run (see
*RECORD-RUNS*). Called after every motion of the simulated robot; returns the step or NIL."
  (when (and *record-runs* (typep world 'btr:bt-reasoning-world)
             (native:world-alive-p (btr:world-handle world)))
    (let ((node cpl:*task-tree-node*))
      (multiple-value-bind (names state) (capture-state world)
        (sb-thread:with-mutex (*recorder-lock*)
          (prog1
              (let ((run (current-run (task-root node) world)))
                (setf (run-world-handle run) (btr:world-handle world))
                (when (< (fill-pointer (run-steps run)) *max-steps-per-run*)
                  (unless (eq names (run-last-names run))
                    (dolist (n names)
                      (let ((key (string-downcase (princ-to-string n))))
                        (unless (gethash key (run-descriptors run))
                          (setf (gethash key (run-descriptors run))
                                (object-descriptor (btr:object world n))))))
                    (setf (run-last-names run) names))
                  (let ((step (%make-step :index (fill-pointer (run-steps run)) :label (string label)
                                          :unix (cpl::unix-time) :node node :names names :state state
                                          :overlays (reverse *pending-overlays*))))
                    (setf *pending-overlays* '())
                    (vector-push-extend step (run-steps run))
                    step)))
            (note-change)))))))

(defun step-failed-p (step)
  "True when the motion of STEP failed (its task tree node says so)."
  (let ((node (step-node step)))
    (and node (eq (cpl:node-outcome node) :failed))))

(defun step-object-pose (run step name)
  "The pose (list of 7 numbers) of the object NAME (a symbol or string) at STEP of RUN."
  (let ((key (if (stringp name) name (string-downcase (princ-to-string name))))
        (k 0))
    (dolist (n (step-names step) (error "viewer: no object ~s at step ~d of run ~d" name
                                        (step-index step) (run-id run)))
      (let* ((nk (string-downcase (princ-to-string n)))
             (d (gethash nk (run-descriptors run))))
        (when (string= nk key) (return (pose7 (step-state step) k)))
        (incf k (+ 7 (length (gethash "joints" d))))))))

;;; ---- overlays noted while a run goes on --------------------------------------------------------

(defun note-overlay (overlay)
  "Keep OVERLAY (a JSON object) for the next recorded step."
  (sb-thread:with-mutex (*recorder-lock*)
    (push overlay *pending-overlays*)))

(defvar *noted-costmaps* (make-hash-table :test 'eq :weakness :key :synchronized t)
  "Location designator → its overlay (samples are added to it as they are validated).")

(defun pose-stamped-list (pose)
  (let* ((p (if (typep pose 'cl-transforms-stamped:pose-stamped) pose pose))
         (o (cl-transforms:origin p)) (q (cl-transforms:orientation p)))
    (list (cl-transforms:x o) (cl-transforms:y o) (cl-transforms:z o)
          (cl-transforms:x q) (cl-transforms:y q) (cl-transforms:z q) (cl-transforms:w q))))

(defparameter *deferred-print-variables*
  '(*package* *print-pretty* *print-case* *print-base* *print-radix* *print-readably*
    *print-circle* *print-lines* *print-right-margin* *print-miser-width* *read-default-float-format*)
  "The printer variables a deferred designator text is printed with as they were when it was
deferred.")

(defstruct (deferred-designator
            (:constructor %defer-designator (quantifier type-name description class bindings)))
  "What a location overlay shows of its designator: its quantifier, type and description (they
do not change) and the printer variables of the moment, printed only when the overlay is sent
\(OVERLAY-DESIGNATOR-TEXT). Not the designator itself, which would keep its costmap alive."
  quantifier type-name description class bindings (text nil))

(defmethod print-object ((d deferred-designator) stream)
  (if *print-readably*
      (error 'print-not-readable :object d)
      (desig::write-designator (deferred-designator-quantifier d) (deferred-designator-type-name d)
                               (deferred-designator-description d) stream))
  d)

(defun defer-designator-text (designator)
  "A DEFERRED-DESIGNATOR of DESIGNATOR: OVERLAY-DESIGNATOR-TEXT prints it later as
CPL::DESIGNATOR-STRING prints DESIGNATOR now."
  (%defer-designator (desig:quantifier designator) (desig::designator-type-name designator)
                     (desig:description designator) (type-of designator)
                     (mapcar #'symbol-value *deferred-print-variables*)))

(defun overlay-designator-text (value)
  "The designator text of a location overlay: VALUE itself (a string or NIL), or the text of a
DEFERRED-DESIGNATOR, printed the first time it is asked for."
  (if (deferred-designator-p value)
      (or (deferred-designator-text value)
          (setf (deferred-designator-text value)
                (progv *deferred-print-variables* (deferred-designator-bindings value)
                  (handler-case (let ((*print-length* 20) (*print-level* 6))
                                  (prin1-to-string value))
                    (error () (format nil "<unprintable ~s>" (deferred-designator-class value)))))))
      value))

(defun location-sample-observer (designator solution)
  "Location validator that only watches: every candidate pose of a location designator with a
costmap is kept (with the costmap) for the replay's overlays. Always :UNKNOWN."
  (when (and *record-runs* (typep solution 'cl-transforms:pose)
             (or cpl:*task-tree-node* (viewer-overlays-wanted-p)))
    (let ((overlay (gethash designator *noted-costmaps*)))
      (unless overlay
        (let ((costmap (gethash designator costmap::*designator-costmaps*)))
          (setf overlay (obj "type" "location" "designator" (defer-designator-text designator)
                             "costmap" (and (typep costmap 'costmap:location-costmap) costmap)
                             "samples" '()))
          (setf (gethash designator *noted-costmaps*) overlay)
          (note-overlay overlay)
          (when (gethash "costmap" overlay)
            (sb-thread:with-mutex (*recorder-lock*) (keep-overlay-costmap overlay)))))
      (sb-thread:with-mutex (*recorder-lock*)
        (when (< (length (gethash "samples" overlay)) 500)
          (push (pose-stamped-list solution) (gethash "samples" overlay))))))
  :unknown)

(defvar *viewer-overlays-wanted* nil
  "True while a live viewer runs: location samples outside a plan are noted too.")
(defun viewer-overlays-wanted-p () *viewer-overlays-wanted*)

(desig:register-location-validation-function 1 location-sample-observer
  "Watches the candidate poses of location designators for the viewer's replay (never rejects).")

(defun note-look-target (target)
  "Keep the target point (x y z) of a LOOK-AT motion for the next recorded step."
  (when *record-runs*
    (note-overlay (obj "type" "target" "point" (coerce target 'list)))))

;;; ---- hooks into the projection ---------------------------------------------------------------

(pushnew 'record-motion urdf-proj::*after-motion-hooks*)
(pushnew 'note-look-target urdf-proj::*look-target-hooks*)
