;;;; CRAM's view of a costmap's values: GET-COST-MAP and GET-MAP-VALUE give the normalised grid
;;;; (a probability distribution summing to 1), GEN-COSTMAP-SAMPLE-POINT draws one point from it.

(in-package :cram-location-costmap)

(define-condition no-cost-functions-registered (error)
  ((costmap :initarg :costmap :initform nil :reader no-cost-functions-costmap))
  (:report (lambda (c s)
             (format s "The location costmap ~a has no cost functions: register one with ~
                        REGISTER-COST-FUNCTION before reading its values."
                     (no-cost-functions-costmap c))))
  (:documentation "Signalled when the values of a costmap without cost functions are asked for."))

(defun check-costmap (costmap function)
  (unless (typep costmap 'location-costmap)
    (error "~s: ~s is not a location costmap (see MAKE-LOCATION-COSTMAP)." function costmap))
  (unless (cost-functions costmap)
    (error 'no-cost-functions-registered :costmap costmap)))

(defun window-sum (window)
  "The sum of the cells of WINDOW, added in row-major order."
  (declare (type (simple-array double-float (* *)) window) (optimize speed))
  (let ((total 0d0))
    (declare (type double-float total))
    (dotimes (i (array-total-size window) total)
      (incf total (row-major-aref window i)))))

(defun costmap-total (costmap)
  "The sum of COSTMAP's cells (row-major order); INVALID-PROBABILITY-DISTRIBUTION when it is 0."
  (or (%total costmap)
      (let ((total (window-sum (cost-window costmap))))
        (when (zerop total)
          (error 'invalid-probability-distribution
                 :costmap costmap
                 :reason (format nil "every cell is 0 (cost functions: ~{~(~a~)~^, ~})."
                                 (mapcar #'first (cost-functions costmap)))))
        (setf (%total costmap) total))))

(defun normalized-grid (costmap)
  "(values grid total): COSTMAP's grid divided by the sum of its cells, and that sum."
  (let ((total (costmap-total costmap)))
    (values (or (%normalized costmap)
                (multiple-value-bind (window region) (cost-window costmap)
                  (declare (type (simple-array double-float (* *)) window))
                  (let ((grid (make-array (list (costmap-rows costmap) (costmap-columns costmap))
                                          :element-type 'double-float :initial-element 0d0)))
                    (declare (type (simple-array double-float (* *)) grid) (type double-float total))
                    (destructuring-bind (r0 r1 c0 c1) region
                      (declare (type fixnum r0 r1 c0 c1))
                      (loop for r of-type fixnum from r0 below r1
                            do (loop for c of-type fixnum from c0 below c1
                                     do (setf (aref grid r c) (/ (aref window (- r r0) (- c c0)) total)))))
                    (setf (%normalized costmap) grid))))
            total)))

(defun normalized-value (costmap row column)
  "The value of COSTMAP's cell (ROW COLUMN) in its normalised grid (GET-COST-MAP), without making
that grid."
  (let ((total (costmap-total costmap)))
    (multiple-value-bind (window region) (cost-window costmap)
      (destructuring-bind (r0 r1 c0 c1) region
        (if (and (<= r0 row) (< row r1) (<= c0 column) (< column c1))
            (/ (aref window (- row r0) (- column c0)) total)
            0d0)))))

(defun positive-cells-within (costmap x y radius)
  "How many cells of COSTMAP are above 0 in its normalised grid (GET-COST-MAP) and have their
centres within RADIUS metres (horizontally) of the map point (X Y).  Signals as GET-COST-MAP
does for a costmap without cost functions or one that is 0 everywhere."
  (check-costmap costmap 'positive-cells-within)
  (loop for (what value) in `(("x" ,x) ("y" ,y) ("radius" ,radius))
        unless (finite-real-p value)
          do (error "POSITIVE-CELLS-WITHIN: the ~a is ~s, expected a finite real (metres)."
                    what value))
  (let ((total (costmap-total costmap))
        (reach2 (expt radius 2))
        (count 0))
    (multiple-value-bind (window region) (cost-window costmap)
      (declare (type (simple-array double-float (* *)) window))
      (destructuring-bind (r0 r1 c0 c1) region
        (loop for r from r0 below r1
              for dy2 = (expt (- (cell-center-y costmap r) y) 2)
              unless (> dy2 reach2)
                do (loop for c from c0 below c1
                         when (and (plusp (/ (aref window (- r r0) (- c c0)) total))
                                   (<= (+ dy2 (expt (- (cell-center-x costmap c) x) 2)) reach2))
                           do (incf count)))))
    count))

(defun get-cost-map (costmap)
  "The value grid of COSTMAP as a probability distribution: a (rows x columns) double-float
array (row = y index, column = x index) whose cells sum to 1, each proportional to the product
of the cost functions at the cell's centre.  A costmap without cost functions signals
NO-COST-FUNCTIONS-REGISTERED, one whose cells are all 0 INVALID-PROBABILITY-DISTRIBUTION."
  (check-costmap costmap 'get-cost-map)
  (values (normalized-grid costmap)))

(defun get-map-value (costmap x y)
  "The normalised value (see GET-COST-MAP) of COSTMAP's cell containing the map point (X Y); 0
outside the grid."
  (unless (typep costmap 'location-costmap)
    (error "GET-MAP-VALUE: ~s is not a location costmap (see MAKE-LOCATION-COSTMAP)." costmap))
  (loop for (what value) in `(("x" ,x) ("y" ,y))
        unless (finite-real-p value)
          do (error "GET-MAP-VALUE: the ~a coordinate is ~s, expected a finite real (metres)."
                    what value))
  (check-costmap costmap 'get-map-value)
  (let ((c (floor (- x (origin-x costmap)) (resolution costmap)))
        (r (floor (- y (origin-y costmap)) (resolution costmap))))
    (costmap-total costmap)
    (if (and (< -1 r (costmap-rows costmap)) (< -1 c (costmap-columns costmap)))
        (normalized-value costmap r c)
        0d0)))

(defun gen-costmap-sample-point (costmap &key sampling-function)
  "One point drawn from COSTMAP as a probability distribution, as a CL-TRANSFORMS:3D-VECTOR at
the centre of the drawn cell, its z one of the heights of the height generators (0 without
any).  SAMPLING-FUNCTION, when given, is called with the normalised grid (GET-COST-MAP) and
returns the cell as (column row); by default the cell is drawn with the costmap's own seeded
random state."
  (check-costmap costmap 'gen-costmap-sample-point)
  (let ((random-state (costmap-random-state costmap)))
    (multiple-value-bind (column row)
        (if sampling-function
            (let ((cell (funcall sampling-function (get-cost-map costmap))))
              (unless (and (listp cell) (= (length cell) 2)
                           (typep (first cell) `(integer 0 (,(costmap-columns costmap))))
                           (typep (second cell) `(integer 0 (,(costmap-rows costmap)))))
                (error "GEN-COSTMAP-SAMPLE-POINT: the sampling function ~s gave ~s, expected ~
                        (column row) of a cell of the ~dx~d grid."
                       sampling-function cell (costmap-columns costmap) (costmap-rows costmap)))
              (values (first cell) (second cell)))
            (multiple-value-bind (row column)
                (floor (draw-sample-cell costmap random-state)
                       (costmap-columns costmap))
              (values column row)))
      (let* ((x (cell-center-x costmap column))
             (y (cell-center-y costmap row))
             (heights (generate-heights costmap x y)))
        (cl-transforms:make-3d-vector x y (elt heights (random (length heights) random-state)))))))

(setf (documentation 'cost-functions 'function)
      "The cost functions of a costmap: entries (name function score), applied by ascending score."
      (documentation 'height-generators 'function)
      "The height generators of a costmap, functions (x y) returning lists of heights."
      (documentation 'orientation-generators 'function)
      "The orientation generators of a costmap, functions (x y previous-orientations).")

(setf (documentation 'origin-x 'function) "The map x of the corner of cell (0 0) of a costmap or occupancy grid."
      (documentation 'origin-y 'function) "The map y of the corner of cell (0 0) of a costmap or occupancy grid."
      (documentation 'resolution 'function) "The size of the cells of a costmap or occupancy grid, in metres."
      (documentation 'width 'function) "The extent of a costmap along x in metres."
      (documentation 'height 'function) "The extent of a costmap along y in metres."
      (documentation 'costmap-columns 'function) "The number of cells of a costmap along x."
      (documentation 'costmap-rows 'function) "The number of cells of a costmap along y."
      (documentation 'cost-function-name 'function) "The name of a COST-FUNCTION."
      (documentation 'cost-function-bounds 'function)
      "NIL, or (x-min y-min x-max y-max) outside which a COST-FUNCTION is 0.")
