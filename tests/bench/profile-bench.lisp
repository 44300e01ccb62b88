;;;; Where a warm move-bottle projection spends its time, by layer: the entry functions of each
;;;; layer are wrapped with a timer that counts the time spent in them minus the time spent in
;;;; the wrapped functions they call (self time), so the layers add up without double counting.
;;;; What no wrapped function covers is the plan language, the executive and the plans themselves.
;;;; Concurrent plan branches (CPL:PAR) run in threads of their own; their times add up.

(defpackage :cram-bench.profile
  (:use :cl :cram-bench))

(in-package :cram-bench.profile)

(load-tool "demo.lisp" :cram-plans-demo)

(defparameter *layers*
  '(("world set-up (init-projection, spawning)"
     btw-tut:init-projection btw-tut::spawn-bottle btr:add-object btr:remove-object)
    ("physics (settling)" btr:simulate)
    ("Prolog" prolog:prolog)
    ("designator resolution" desig:reference desig:resolve-designator desig:next-solution)
    ("location costmaps and validation"
     desig::generated-candidates desig::validate-location costmap::costmap-samples)
    ("inverse kinematics" urdf-proj::solve-ik)
    ("collision checks" urdf-proj::robot-collisions urdf-proj::perform-collision-check)
    ("visibility (rendering)" btr:visibility-fraction)
    ("TF updates and lookups" urdf-proj:update-tf-from-belief-state
     cl-transforms-stamped:lookup-transform cl-transforms-stamped:transform-pose-stamped)
    ("robot state in the shim" btr:set-robot-state-from-joints btr::set-joint-states
     btr:link-pose)
    ("logging" cpl:log-message)
    ("task tree" cpl::make-task-tree-node)
    ("viewer recording" cram-viewer:record-motion))
  "(layer-name function...): the functions whose self time is counted for each layer.")

(defvar *self* (make-hash-table :test 'equal :synchronized t) "Layer → self seconds.")
(defvar *children* nil "Cons cell: seconds spent in wrapped callees of the current wrapped call.")

(defvar *lock* (sb-thread:make-mutex :name "layer profile"))

(defun wrap (function layer)
  (sb-int:encapsulate
   function 'layer-profile
   (lambda (f &rest args)
     (let ((start (now-seconds)) (outer *children*) (cell (list 0d0)))
       (multiple-value-prog1 (let ((*children* cell)) (apply f args))
         (let ((total (- (now-seconds) start)))
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
         (runs 30)
         (run (lambda () (cram-plans-demo:run-move-bottle pose :pictures nil :log-stream quiet))))
    (dotimes (i 3) (funcall run))
    (clrhash *self*)
    (let* ((start (now-seconds))
           (total (progn (call-with-layers (lambda () (dotimes (i runs) (funcall run))))
                         (/ (- (now-seconds) start) runs)))
           (rows (sort (loop for (layer) in *layers*
                             collect (list layer (/ (gethash layer *self* 0d0) runs)))
                       #'> :key #'second))
           (covered (reduce #'+ rows :key #'second)))
      (format t "~&Profile of a warm move-bottle projection (~d runs, ~a per run with the timers; ~
                 self time per run by layer):~%" runs (format-seconds total))
      (dolist (r (append rows (list (list "plan language, executive, plans (the rest)"
                                          (max 0d0 (- total covered))))))
        (format t "  ~45a ~10a ~5,1f %~%" (first r) (format-seconds (second r))
                (* 100 (/ (second r) total))))
      (add-row (format nil "move-bottle profile: largest layer is ~a" (first (first rows)))
               (format-seconds (second (first rows)))
               :goal "(profile printed above)"))))
