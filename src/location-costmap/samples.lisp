;;;; Sampling a location costmap: the distribution over its cells, the cells drawn (tested by
;;;; the cost functions that test cells instead of filling the grid), and the lazy list of
;;;; pose samples with their heights and orientations.

(in-package :cram-location-costmap)

(defstruct (distribution (:conc-name dist-))
  (cells #() :type (simple-array fixnum (*)))
  (cumulative #() :type (simple-array double-float (*)))
  (total 0d0 :type double-float))

(defun positive-cells (window)
  "How many cells of WINDOW are above 0."
  (declare (type (simple-array double-float (* *)) window) (optimize speed))
  (let ((n 0))
    (declare (type fixnum n))
    (dotimes (i (array-total-size window) n)
      (when (> (row-major-aref window i) 0d0) (incf n)))))

(defun window-distribution (costmap window region)
  "The distribution over the costmap's cells of REGION that WINDOW holds (COST-WINDOW's
values, or SAMPLING-WINDOW's). Signals INVALID-PROBABILITY-DISTRIBUTION when every cell is 0."
  (let* ((cols (costmap-columns costmap))
         (count (positive-cells window))
         (cells (make-array count :element-type 'fixnum))
         (cumulative (make-array count :element-type 'double-float))
         (sum 0d0) (k 0))
    (declare (type (simple-array double-float (* *)) window) (type double-float sum)
             (type fixnum k cols) (type (simple-array fixnum (*)) cells)
             (type (simple-array double-float (*)) cumulative))
    (destructuring-bind (r0 r1 c0 c1) region
      (declare (type fixnum r0 r1 c0 c1) (optimize speed))
      (loop for r of-type fixnum from r0 below r1
            for wr of-type fixnum from 0
            do (loop for c of-type fixnum from c0 below c1
                     for wc of-type fixnum from 0
                     do (let ((v (aref window wr wc)))
                          (when (> v 0d0)
                            (incf sum v)
                            (setf (aref cells k) (+ c (* r cols)) (aref cumulative k) sum)
                            (incf k))))))
    (when (zerop count)
      (error 'invalid-probability-distribution
             :costmap costmap
             :reason (format nil "every cell is 0 (cost functions: ~{~(~a~)~^, ~})."
                             (mapcar #'first (cost-functions costmap)))))
    (make-distribution :cells cells :cumulative cumulative :total sum)))

(defun costmap-distribution (costmap)
  "The distribution over the cells of COSTMAP by their values (COST-WINDOW)."
  (or (%distribution costmap)
      (setf (%distribution costmap)
            (multiple-value-call #'window-distribution costmap (cost-window costmap)))))

(defun sampling-distribution (costmap)
  "The distribution samples of COSTMAP are drawn from before their cells are tested
\(SAMPLING-WINDOW), or COSTMAP-DISTRIBUTION when no cost function tests cells or after
DRAW-SAMPLE-CELL gave up testing."
  (if (or (%exact-sampling costmap) (notany #'sampling-test-p (cost-functions costmap)))
      (costmap-distribution costmap)
      (or (%sampling-distribution costmap)
          (setf (%sampling-distribution costmap)
                (multiple-value-call #'window-distribution costmap (sampling-window costmap))))))

(defparameter *redraw-limit* 16
  "How often a cell that was already sampled is redrawn before it may be used again.")

(defparameter *cell-test-limit* 48
  "How many drawn cells in a row may fail the cell tests of a costmap's cost functions before
its samples are drawn from its whole grid of values instead (COST-WINDOW): about the rays of
its line of sight for a few blocks, against the rays of all of them.")

(defun cell-passes-p (costmap cell)
  "True when the row-major CELL of COSTMAP passes the cell tests of its cost functions."
  (multiple-value-bind (row column) (floor cell (costmap-columns costmap))
    (loop for entry in (cost-functions costmap)
          always (or (not (sampling-test-p entry))
                     (funcall (cost-function-cell-test (second entry)) costmap row column)))))

(defun draw-sample-cell (costmap random-state &optional used)
  "A row-major cell of COSTMAP drawn with probability proportional to its value: drawn from
SAMPLING-DISTRIBUTION and, while the cost functions that test cells reject it, drawn again
(rejected cells count as USED, an EQL hash table of cells already taken, which are redrawn up
to *REDRAW-LIMIT* times); after *CELL-TEST-LIMIT* rejections in a row, from the whole grid's
values (COSTMAP-DISTRIBUTION: INVALID-PROBABILITY-DISTRIBUTION when every cell is 0)."
  (flet ((draw ()
           (let* ((distribution (sampling-distribution costmap))
                  (cell (draw-cell distribution random-state)))
             (when used
               (loop repeat *redraw-limit* while (gethash cell used)
                     do (setf cell (draw-cell distribution random-state))))
             cell)))
    (loop repeat *cell-test-limit*
          do (let ((cell (draw)))
               (when (or (%exact-sampling costmap) (cell-passes-p costmap cell))
                 (return-from draw-sample-cell cell))
               (when used (setf (gethash cell used) t))))
    (setf (%exact-sampling costmap) t)
    (draw)))

(defun draw-cell (distribution random-state)
  "A row-major cell index drawn with probability proportional to its value."
  (let* ((cumulative (dist-cumulative distribution))
         (r (random (dist-total distribution) random-state))
         (lo 0) (hi (1- (length cumulative))))
    (declare (type fixnum lo hi) (type double-float r))
    (loop while (< lo hi)
          do (let ((mid (ash (+ lo hi) -1)))
               (if (> (aref cumulative mid) r) (setf hi mid) (setf lo (1+ mid)))))
    (aref (dist-cells distribution) lo)))

(defun generate-heights (costmap x y)
  "The heights of the samples at (X Y): those of the first height generator, else (0)."
  (let ((g (first (height-generators costmap))))
    (if g
        (let ((zs (funcall g x y)))
          (unless (and (listp zs) zs (every #'realp zs))
            (error "The height generator ~s of ~s gave ~s at (~,3f ~,3f), expected a non-empty ~
                    list of reals." g costmap zs x y))
          zs)
        (list 0d0))))

(defun generate-orientations (costmap x y)
  "The orientations of the samples at (X Y): each orientation generator transforms the list of
the previous one, starting from the identity; then the orderings sort them."
  (let ((orientations (list (cl-transforms:make-identity-rotation))))
    (flet ((check (result what fn)
             (unless (and (listp result) result
                          (every (lambda (q) (typep q 'cl-transforms:quaternion)) result))
               (error "The orientation ~a ~s of ~s gave ~s at (~,3f ~,3f), expected a ~
                       non-empty list of quaternions." what fn costmap result x y))
             result))
      (dolist (g (orientation-generators costmap))
        (setf orientations (check (funcall g x y orientations) "generator" g)))
      (dolist (o (orientation-orderings costmap) orientations)
        (let ((count (length orientations)))
          (setf orientations (check (funcall o x y orientations) "ordering" o))
          (unless (= count (length orientations))
            (error "The orientation ordering ~s of ~s gave ~d orientations for ~d at (~,3f ~,3f), ~
                    expected the same ones in another order." o costmap (length orientations)
                    count x y)))))))

(defun costmap-samples (costmap &key (frame-id "map") (jitter t))
  "The infinite lazy list of pose-stamped samples of COSTMAP in FRAME-ID: positions drawn with
probability proportional to the cell values (a cell already used is redrawn, up to
*REDRAW-LIMIT* times), uniformly placed inside the cell when JITTER, one pose per height and
orientation of the generators.  The random numbers come from the costmap's own random state,
which MAKE-LOCATION-COSTMAP seeded from *COSTMAP-RANDOM-STATE*."
  (sampling-distribution costmap)       ; signals now when every cell is 0
  (let ((random-state (costmap-random-state costmap))
        (used (make-hash-table))
        (pending '())
        (cols (costmap-columns costmap))
        (res (resolution costmap)))
    (cut:make-lazy-list
     (lambda ()
       (loop
         (when pending (return (values (pop pending) t)))
         (let ((cell (draw-sample-cell costmap random-state used)))
           (setf (gethash cell used) t)
           (multiple-value-bind (row col) (floor cell cols)
             (let* ((x (+ (cell-center-x costmap col)
                          (if jitter (* res (- (random 1d0 random-state) 0.5d0)) 0d0)))
                    (y (+ (cell-center-y costmap row)
                          (if jitter (* res (- (random 1d0 random-state) 0.5d0)) 0d0)))
                    (zs (generate-heights costmap x y))
                    (orientations (generate-orientations costmap x y)))
               (setf pending
                     (loop for z in zs
                           append (loop for q in orientations
                                        collect (cl-transforms-stamped:make-pose-stamped
                                                 frame-id 0d0
                                                 (cl-transforms:make-3d-vector x y z) q))))))))))))
