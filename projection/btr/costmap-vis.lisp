;;;; The costmap visualization of the belief state: the costmap a location designator was last
;;;; resolved with, the pose samples drawn from it, and axis markers of poses (navigation goals).
;;;; Location costmaps register here; pictures, markers and heat maps read it;
;;;; CLEAR-COSTMAP-VIS-OBJECT removes it, as the tutorials call it when they set up a world.

(in-package :cram-bullet-reasoning)

(defvar *costmap-vis-lock* (bt:make-lock "costmap visualization"))

(defvar *current-costmap-function* nil
  "The costmap shown in the visualization (a location costmap), or NIL.")
(defvar *current-costmap-samples* '()
  "The poses sampled from the shown costmap, newest first.")
(defvar *vis-axes* '()
  "Axis markers: (id . pose) pairs, newest first.")

(defparameter *costmap-vis-max-samples* 100
  "How many costmap samples the visualization keeps (the oldest are dropped).")

(defun check-vis-pose (pose caller)
  (unless (typep pose 'cl-transforms:pose)
    (btr-fail "~a: expected a pose or pose-stamped, got ~s" caller pose)))

(defun add-costmap-function-object (costmap)
  "Show COSTMAP (a location costmap; NIL clears it) in the costmap visualization, replacing the
one shown and its samples. Returns COSTMAP."
  (bt:with-lock-held (*costmap-vis-lock*)
    (setf *current-costmap-function* costmap
          *current-costmap-samples* '()))
  costmap)

(defun add-costmap-sample-object (pose)
  "Show POSE as a sample of the shown costmap. Returns POSE."
  (check-vis-pose pose 'add-costmap-sample-object)
  (bt:with-lock-held (*costmap-vis-lock*)
    (push pose *current-costmap-samples*)
    (when (> (length *current-costmap-samples*) *costmap-vis-max-samples*)
      (setf *current-costmap-samples* (subseq *current-costmap-samples* 0 *costmap-vis-max-samples*))))
  pose)

(defun add-vis-axis-object (pose &key (id :default))
  "Show an axis marker at POSE, replacing the marker ID (any object, compared with EQUAL).
Returns POSE."
  (check-vis-pose pose 'add-vis-axis-object)
  (bt:with-lock-held (*costmap-vis-lock*)
    (setf *vis-axes* (acons id pose (remove id *vis-axes* :key #'car :test #'equal))))
  pose)

(defun costmap-vis-object ()
  "The costmap visualization as a plist (:costmap COSTMAP :samples POSES :axes ((id . pose)...)),
or NIL when nothing is shown."
  (bt:with-lock-held (*costmap-vis-lock*)
    (when (or *current-costmap-function* *current-costmap-samples* *vis-axes*)
      (list :costmap *current-costmap-function*
            :samples (copy-list *current-costmap-samples*)
            :axes (copy-alist *vis-axes*)))))

(defun clear-costmap-vis-object (&key (costmap t) (sample t) (axes t))
  "Remove the costmap visualization: the shown costmap (COSTMAP), its samples (SAMPLE) and the
axis markers (AXES), each unless NIL. Returns true when something was removed."
  (bt:with-lock-held (*costmap-vis-lock*)
    (prog1 (or (and costmap *current-costmap-function* t)
               (and sample *current-costmap-samples* t)
               (and axes *vis-axes* t))
      (when costmap (setf *current-costmap-function* nil))
      (when (or costmap sample) (setf *current-costmap-samples* '()))
      (when axes (setf *vis-axes* '())))))
