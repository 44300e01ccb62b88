;;;; Where a warm move-bottle projection spends its time, by layer: the entry functions of each
;;;; layer are wrapped with a timer that counts the time spent in them minus the time spent in
;;;; the wrapped functions they call (self time), so the layers add up without double counting.
;;;; The plan language, the executive and the plans are layers of their own; what no wrapped
;;;; function covers is the rest. Concurrent plan branches (CPL:PAR) run in threads of their own
;;;; and their times add up; the time their parent waits for them is printed on a line of its
;;;; own and left out of the sum (it overlaps the branches' time).

(defpackage :cram-bench.profile
  (:use :cl :cram-bench))

(in-package :cram-bench.profile)

(load-tool "demo.lisp" :cram-plans-demo)

(defparameter *waiting-layer* "waiting for child tasks (CPL:TOP-LEVEL, CPL:PAR)"
  "The layer of the time a thread waits for the tasks it started.")

(defparameter *layers*
  `(("world set-up (init-projection, spawning)"
     btw-tut:init-projection btw-tut::spawn-bottle btr:add-object btr:remove-object)
    ("physics (settling)" btr:simulate)
    ("Prolog" prolog:prolog)
    ("designator resolution" desig:reference desig:resolve-designator desig:next-solution)
    ("location costmaps and validation"
     desig::generated-candidates desig::validate-location costmap::costmap-samples)
    ("inverse kinematics" urdf-proj::solve-ik)
    ("collision checks" urdf-proj::robot-collisions urdf-proj::perform-collision-check)
    ("sweep checks between key poses" urdf-proj:robot-sweeps)
    ("visibility (rendering)" btr:visibility-fraction)
    ("TF updates and lookups" urdf-proj:update-tf-from-belief-state
     cl-transforms-stamped:lookup-transform cl-transforms-stamped:transform-pose-stamped)
    ("robot state in the shim" btr:set-robot-state-from-joints btr::set-joint-states
     btr:link-pose)
    ("logging" cpl:log-message)
    ("task tree" cpl::make-task-tree-node cpl::finish-node cpl::note-caught-failure cpl::note-retry)
    ("viewer recording" cram-viewer:record-motion)
    ;; the plan language, the executive and the plans themselves, layer by layer
    ("plan tasks (starting and finishing their threads)" cpl::spawn-task
     cpl::capture-inherited-specials cpl::finish-task)
    ("the run's harness (fresh belief state, result, recovery counts)"
     cram-plans-demo:run-move-bottle cram-plans-demo::reset-projection)
    ("failures (signalling, handling)" cpl:fail cpl::coerce-to-failure)
    ("designators (making, copying, properties)" desig:make-designator desig:copy-designator
     desig:desig-prop-value desig:desig-prop-values desig:equate)
    ("executive (perform, action grounding)" exe:perform exe::action-plan-arguments)
    ("process modules (dispatch)" cpm:pm-execute cpm:matching-process-modules)
    ("projected motions (teleport, arms, gripper, look)" urdf-proj::execute-command)
    ("events and occasions" coe:on-event coe:holds)
    ("pick-and-place plans" pp-plans::pick-up pp-plans::place pp-plans::perform-arm-action
     pp-plans::navigate pp-plans::look-at pp-plans::perceive pp-plans::move-torso
     pp-plans::position-arms pp-plans::park-arms pp-plans::set-gripper pp-plans::release
     pp-plans::grip pp-plans::move-arms-in-sequence)
    ("the tutorial's plan (move-bottle and its retries)" btw-tut:move-bottle btw-tut::find-object
     btw-tut::pick-up-object)
    (,*waiting-layer* cpl::run-task-group cpl::call-as-top-level))
  "(layer-name function...): the functions whose self time is counted for each layer.")

(defvar *self* (make-hash-table :test 'equal :synchronized t) "Layer → self seconds.")
(defvar *children* nil "Cons cell: seconds spent in wrapped callees of the current wrapped call.")

(defvar *lock* (sb-thread:make-mutex :name "layer profile"))

(defun gc-seconds ()
  "Seconds spent in garbage collection by this process so far."
  (/ sb-ext:*gc-run-time* (float internal-time-units-per-second 1d0)))

(defun busy-seconds ()
  "Wall-clock seconds minus the seconds spent in garbage collection: a collection stops every
thread, so its pause counts in the garbage collection layer, not in the layer it interrupted."
  (- (now-seconds) (gc-seconds)))

(defun wrap (function layer)
  (sb-int:encapsulate
   function 'layer-profile
   (lambda (f &rest args)
     (let ((start (busy-seconds)) (outer *children*) (cell (list 0d0)))
       (multiple-value-prog1 (let ((*children* cell)) (apply f args))
         (let ((total (- (busy-seconds) start)))
           (sb-thread:with-mutex (*lock*)
             (incf (gethash layer *self* 0d0) (- total (car cell))))
           (when outer (incf (car outer) total))))))))

(defun call-with-layers (thunk)
  (let ((wrapped '()))
    (unwind-protect
         (progn
           (loop for (layer . functions) in *layers*
                 do (dolist (f functions)
                      (when (and (fboundp f) (not (member f wrapped)))
                        (wrap f layer) (push f wrapped))))
           (funcall thunk))
      (dolist (f wrapped) (sb-int:unencapsulate f 'layer-profile)))))

(define-benchmark move-bottle-profile ()
  (let* ((pose btw-tut:*bottle-pose-in-view*)
         (quiet (make-broadcast-stream))
         (runs 60)
         (run (lambda () (cram-plans-demo:run-move-bottle pose :pictures nil :log-stream quiet))))
    (dotimes (i 3) (funcall run))
    (clrhash *self*)
    (let* ((start (now-seconds))
           (gc-start (gc-seconds))
           (total (progn (call-with-layers (lambda () (dotimes (i runs) (funcall run))))
                         (/ (- (now-seconds) start) runs)))
           (rows (sort (cons (list "garbage collection (every thread stopped)"
                                   (/ (- (gc-seconds) gc-start) runs))
                             (loop for (layer) in *layers*
                                   unless (equal layer *waiting-layer*)
                                     collect (list layer (/ (gethash layer *self* 0d0) runs))))
                       #'> :key #'second))
           (covered (reduce #'+ rows :key #'second))
           (rest (max 0d0 (- total covered)))
           (rest-share (/ rest total)))
      (format t "~&Profile of a warm move-bottle projection (~d runs, ~a per run with the timers; ~
                 self time per run by layer):~%" runs (format-seconds total))
      (dolist (r (append rows (list (list "the rest (no layer above)" rest))))
        (format t "  ~50a ~10a ~5,1f %~%" (first r) (format-seconds (second r))
                (* 100 (/ (second r) total))))
      (format t "  (~a: ~a per run, overlapping the tasks' own time above)~%"
              *waiting-layer* (format-seconds (/ (gethash *waiting-layer* *self* 0d0) runs)))
      (add-row (format nil "move-bottle profile: largest layer is ~a" (first (first rows)))
               (format-seconds (second (first rows)))
               :goal "(profile printed above)")
      (add-row "move-bottle profile: time in no named layer (the rest)"
               (format nil "~,1f %" (* 100 rest-share))
               :goal "<= 15 %" :met (<= rest-share 0.15d0)))))
