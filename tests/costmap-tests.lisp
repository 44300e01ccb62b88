;;;; Tests of the location costmaps: grids and cost functions, sampling and determinism,
;;;; occupancy, and the VISIBLE-FOR, REACHABLE-FOR and ON designators in the kitchen.

(defpackage :cram-costmap-tests
  (:use :cl :fiveam))

(in-package :cram-costmap-tests)

(def-suite costmap :in cram-plans-tests:all
  :description "Location costmaps and the location designators resolved through them.")
(in-suite costmap)

;;; ---- helpers ---------------------------------------------------------------------------------

(defun small-costmap (&key (width 2) (height 2) (resolution 0.1) (origin-x -1) (origin-y -1))
  (costmap:make-location-costmap :width width :height height :resolution resolution
                                 :origin-x origin-x :origin-y origin-y))

(defun pose-xy (pose)
  (let ((o (cl-transforms:origin pose))) (list (cl-transforms:x o) (cl-transforms:y o))))

(defun yaw-of (pose)
  (cl-transforms:get-yaw (cl-transforms:orientation pose)))

(defun angle-difference (a b)
  (abs (atan (sin (- a b)) (cos (- a b)))))

(defun take-samples (costmap n)
  (cut:force-ll (cut:lazy-take n (costmap:costmap-samples costmap))))

;;; ---- grid, cost functions, sampling -------------------------------------------------------------

(test grid-geometry-from-arguments
  (let ((c (small-costmap :width 3 :height 2 :resolution 0.05)))
    (is (= 60 (costmap:costmap-columns c)))
    (is (= 40 (costmap:costmap-rows c)))
    (is (= -1d0 (costmap:origin-x c)))
    (costmap:register-cost-function c (lambda (x y) (declare (ignore x y)) 1) 'flat)
    (is (equal '(40 60) (array-dimensions (costmap:get-cost-map c))))))

(test grid-geometry-from-metadata
  (let ((rob-int:*robot-name* :pr2))
    (let ((c (costmap:make-location-costmap)))
      (is (= 300 (costmap:costmap-columns c)))
      (is (= 300 (costmap:costmap-rows c)))
      (is (= -6d0 (costmap:origin-y c)))
      (is (< (abs (- 0.04d0 (costmap:resolution c))) 1d-9)))))

(test cost-functions-multiply
  (let ((c (small-costmap))
        (g (costmap:make-gauss-cost-function '(0.2 0.1) '((0.1 0) (0 0.2))))
        (r (costmap:make-range-cost-function '(0 0) 0.5)))
    (costmap:register-cost-function c g 'gauss)
    (costmap:register-cost-function c r 'range)
    (let ((m (costmap:get-cost-map c)))
      ;; cell (row 12, column 13) has its centre at (0.35, 0.25), cell (10 10) at (0.05 0.05);
      ;; the grid is normalised, so compare the ratio of two cells
      (is (< (abs (- (/ (aref m 12 13) (aref m 10 10))
                     (/ (* (funcall g 0.35d0 0.25d0) (funcall r 0.35d0 0.25d0))
                        (* (funcall g 0.05d0 0.05d0) (funcall r 0.05d0 0.05d0)))))
             1d-9))
      (is (> (aref m 12 13) 0))
      ;; (0.85, 0.85) is out of range
      (is (= 0 (costmap:get-map-value c 0.85 0.85)))
      (is (> (costmap:get-map-value c 0.2 0.1) (costmap:get-map-value c 0.4 -0.3))))))

(test gauss-peak-and-symmetry
  (let ((g (costmap:make-gauss-cost-function (cl-transforms:make-3d-vector 1 2 0) '((0.25 0) (0 0.25)))))
    (is (< (abs (- (funcall g 1 2) (/ 1 (* 2 pi 0.25)))) 1d-9))
    (is (< (abs (- (funcall g 1.3d0 2) (funcall g 0.7d0 2))) 1d-12))
    (is (> (funcall g 1.1 2) (funcall g 1.5 2)))))

(test range-and-inverted-range
  (let ((r (costmap:make-range-cost-function '(1 1) 0.5))
        (i (costmap:make-range-cost-function '(1 1) 0.5 :invert t)))
    (is (= 1 (funcall r 1.2 1.2)))
    (is (= 0 (funcall r 1.6 1)))
    (is (= 0 (funcall i 1.2 1.2)))
    (is (= 1 (funcall i 1.6 1)))))

(test sampling-follows-the-values
  (let* ((matrix (make-array '(1 2) :element-type 'double-float :initial-contents '((1d0 3d0))))
         (c (progn (costmap:seed-costmaps 11)
                   (small-costmap :width 2 :height 1 :resolution 1 :origin-x 0 :origin-y 0))))
    (costmap:register-cost-function c (costmap:make-matrix-cost-function 0 0 1 matrix) 'matrix)
    (let* ((costmap::*redraw-limit* 0)
           (samples (take-samples c 4000))
           (right (count-if (lambda (p) (> (first (pose-xy p)) 1)) samples)))
      (is (< 2800 right 3200) "~d of 4000 samples in the cell of value 3" right)
      (is (every (lambda (p) (<= 0 (first (pose-xy p)) 2)) samples)))))

(test samples-are-pose-stamped-in-map-and-do-not-repeat
  (costmap:seed-costmaps 5)
  (let ((c (small-costmap)))
    (costmap:register-cost-function c (costmap:make-range-cost-function '(0 0) 0.3) 'range)
    (let ((samples (take-samples c 50)))
      (is (every (lambda (p) (typep p 'cl-transforms-stamped:pose-stamped)) samples))
      (is (every (lambda (p) (equal "map" (cl-transforms-stamped:frame-id p))) samples))
      (is (every (lambda (p) (<= (sqrt (reduce #'+ (mapcar (lambda (v) (* v v)) (pose-xy p)))) 0.36))
                 samples))
      (is (notany (lambda (a b) (equal (pose-xy a) (pose-xy b))) samples (rest samples))))))

(test same-seed-same-samples
  (flet ((draw (seed)
           (costmap:seed-costmaps seed)
           (let ((c (small-costmap)))
             (costmap:register-cost-function c (costmap:make-gauss-cost-function '(0 0) '((0.1 0) (0 0.1))) 'g)
             (mapcar #'pose-xy (take-samples c 10)))))
    (is (equal (draw 3) (draw 3)))
    (is (not (equal (draw 3) (draw 4))))))

(test orientation-and-height-generators
  (costmap:seed-costmaps 2)
  (let ((c (small-costmap)))
    (costmap:register-cost-function c (costmap:make-range-cost-function '(0 0) 0.8) 'range)
    (costmap:register-orientation-generator
     c (costmap:make-angle-to-point-generator '(0.5 0.5) :samples 3 :sample-step 0.1))
    (costmap:register-height-generator c (costmap:make-constant-height-function 0.7))
    (let ((samples (take-samples c 30)))
      (is (every (lambda (p) (= 0.7d0 (cl-transforms:z (cl-transforms:origin p)))) samples))
      ;; three orientations per position: facing the point, then +0.1 and -0.1
      (loop for (a b d) on samples by #'cdddr
            for (x y) = (pose-xy a)
            for facing = (atan (- 0.5 y) (- 0.5 x))
            do (is (< (angle-difference (yaw-of a) facing) 1d-6))
               (is (< (angle-difference (yaw-of b) (+ facing 0.1)) 1d-6))
               (is (< (angle-difference (yaw-of d) (- facing 0.1)) 1d-6))
               (is (equal (pose-xy a) (pose-xy d)))))))

(test merged-costmaps-multiply
  (let ((a (small-costmap)) (b (small-costmap)))
    (costmap:register-cost-function a (costmap:make-range-cost-function '(0 0) 0.5) 'r1)
    (costmap:register-cost-function b (costmap:make-axis-boundary-cost-function :x 0 #'>) 'half)
    (let ((m (costmap:merge-costmaps a b)))
      (is (> (costmap:get-map-value m 0.2 0) 0))
      (is (= 0 (costmap:get-map-value m -0.2 0)))
      (is (= 0 (costmap:get-map-value m 0.7 0))))))

(test bad-input-is-an-error
  (signals error (costmap:make-gauss-cost-function '(0 0) '((1 2) (2 1))))
  (signals error (costmap:make-gauss-cost-function '(0 0) '((1 0))))
  (signals error (costmap:make-range-cost-function '(0 0) -1))
  (signals error (costmap:make-range-cost-function "here" 1))
  (signals error (costmap:seed-costmaps -3))
  (signals error (costmap:make-location-costmap :width 0 :height 1 :resolution 0.1
                                                :origin-x 0 :origin-y 0))
  (signals error (costmap:register-cost-function (small-costmap) 42 'bad))
  (signals error (costmap:make-padding-mask 2.5))
  (let ((c (small-costmap)))
    (costmap:register-cost-function c (lambda (x y) (declare (ignore x y)) -1) 'negative)
    (signals costmap:invalid-probability-distribution (costmap:get-cost-map c)))
  (let ((c (small-costmap)))
    (costmap:register-cost-function c (costmap:make-range-cost-function '(50 50) 1) 'far-away)
    (signals costmap:invalid-probability-distribution (take-samples c 1))))

(test padding-mask-and-occupancy-grid
  (let ((mask (costmap:make-padding-mask 2)))
    (is (equal '(5 5) (array-dimensions mask)))
    (is (= 1 (aref mask 2 2)))
    (is (= 1 (aref mask 0 2)))
    (is (= 0 (aref mask 0 0))))
  (let ((grid (costmap:make-occupancy-grid 1 1 0 0 0.1)))
    (setf (aref (costmap:occupancy-bits grid) 5 5) 1)
    (is (costmap:occupied-p grid 0.55 0.55))
    (is (not (costmap:occupied-p grid 0.35 0.55)))
    (let ((padded (costmap:pad-occupancy-grid grid 2)))
      (is (costmap:occupied-p padded 0.35 0.55))
      (is (not (costmap:occupied-p padded 0.25 0.25))))
    (let ((f (costmap:make-occupancy-grid-cost-function grid)))
      (is (= 0 (funcall f 0.55 0.55)))
      (is (= 1 (funcall f 0.15 0.15))))))

(defun cells-near-box (rows cols origin-x origin-y resolution x0 y0 x1 y1 padding)
  "The cells whose centres lie within PADDING of the box, tested one by one."
  (let ((bits (make-array (list rows cols) :element-type 'bit :initial-element 0)))
    (dotimes (r rows bits)
      (dotimes (c cols)
        (let* ((x (+ origin-x (* (+ c 0.5d0) resolution)))
               (y (+ origin-y (* (+ r 0.5d0) resolution)))
               (dx (max 0d0 (- x0 x) (- x x1)))
               (dy (max 0d0 (- y0 y) (- y y1))))
          (when (<= (+ (* dx dx) (* dy dy)) (* padding padding))
            (setf (aref bits r c) 1)))))))

(test a-box-is-rasterised-as-its-cells-one-by-one
  (let ((state (sb-ext:seed-random-state 3)) (differing 0) (marked 0))
    (dotimes (i 2000)
      (let* ((resolution (nth (random 3 state) '(0.02d0 0.05d0 0.1d0)))
             (ox (- (random 4d0 state) 5d0)) (oy (- (random 4d0 state) 5d0))
             (x0 (- (random 8d0 state) 4d0)) (y0 (- (random 8d0 state) 4d0))
             (x1 (+ x0 (if (zerop (random 5 state)) 0d0 (random 2d0 state))))
             (y1 (+ y0 (random 2d0 state)))
             (padding (if (zerop (random 4 state)) 0d0 (random 0.6d0 state)))
             (bits (make-array '(60 70) :element-type 'bit :initial-element 0)))
        (costmap::rasterise-box bits ox oy resolution x0 y0 x1 y1 padding)
        (incf marked (count 1 (make-array 4200 :element-type 'bit :displaced-to bits)))
        (unless (equalp bits (cells-near-box 60 70 ox oy resolution x0 y0 x1 y1 padding))
          (incf differing))))
    (is (= 0 differing) "~d of 2000 boxes differ from the cell-by-cell test" differing)
    (is (> marked 10000) "only ~d cells were marked in all" marked)))

(defun cells-near-polygon (rows cols origin-x origin-y resolution corners padding)
  "The cells (a bit array) whose centres lie within PADDING of the convex polygon CORNERS ((x y)
..., counter-clockwise) or inside it, each tested on its own."
  (let ((bits (make-array (list rows cols) :element-type 'bit :initial-element 0))
        (edges (loop for (a . rest) on corners
                     collect (list a (or (first rest) (first corners))))))
    (dotimes (r rows bits)
      (dotimes (c cols)
        (let ((x (+ origin-x (* (+ c 0.5d0) resolution)))
              (y (+ origin-y (* (+ r 0.5d0) resolution))))
          (when (or (every (lambda (e)
                             (destructuring-bind ((ax ay) (bx by)) e
                               (>= (- (* (- bx ax) (- y ay)) (* (- by ay) (- x ax))) 0d0)))
                           edges)
                    (some (lambda (e)
                            (destructuring-bind ((ax ay) (bx by)) e
                              (let* ((vx (- bx ax)) (vy (- by ay)) (dx (- x ax)) (dy (- y ay))
                                     (len2 (+ (* vx vx) (* vy vy)))
                                     (k (if (< len2 1d-18) 0d0
                                            (max 0d0 (min 1d0 (/ (+ (* dx vx) (* dy vy)) len2)))))
                                     (qx (- dx (* k vx))) (qy (- dy (* k vy))))
                                (<= (+ (* qx qx) (* qy qy)) (* padding padding)))))
                          edges))
            (setf (aref bits r c) 1)))))))

(test a-turned-box-is-rasterised-as-its-cells-one-by-one
  ;; the outlines of links turned about the vertical (LINK-FOOTPRINT): rectangles turned by any
  ;; angle, some by a few degrees only, with and without padding
  (let ((state (sb-ext:seed-random-state 5)) (differing 0) (marked 0))
    (dotimes (i 600)
      (let* ((resolution (nth (random 3 state) '(0.02d0 0.05d0 0.1d0)))
             (ox (- (random 2d0 state) 3d0)) (oy (- (random 2d0 state) 3d0))
             (cx (- (random 2d0 state) 1d0)) (cy (- (random 2d0 state) 1d0))
             (hx (+ 0.01d0 (random 0.8d0 state))) (hy (+ 0.01d0 (random 0.8d0 state)))
             (angle (if (zerop (random 2 state)) (- (random 0.1d0 state) 0.05d0) (random 6.3d0 state)))
             (cs (cos angle)) (sn (sin angle))
             (corners (loop for (u v) in `((,(- hx) ,(- hy)) (,hx ,(- hy)) (,hx ,hy) (,(- hx) ,hy))
                            collect (list (+ cx (- (* cs u) (* sn v))) (+ cy (+ (* sn u) (* cs v))))))
             (padding (if (zerop (random 4 state)) 0d0 (random 0.4d0 state)))
             (bits (make-array '(60 70) :element-type 'bit :initial-element 0)))
        (costmap::rasterise-polygon bits ox oy resolution corners padding)
        (incf marked (count 1 (make-array 4200 :element-type 'bit :displaced-to bits)))
        (unless (equalp bits (cells-near-polygon 60 70 ox oy resolution corners padding))
          (incf differing))))
    (is (= 0 differing) "~d of 600 turned boxes differ from the cell-by-cell test" differing)
    (is (> marked 10000) "only ~d cells were marked in all" marked)))
