;;;; The costmaps' fast paths give what the plain ways give: line of sight with early
;;;; verdicts, the lazily seeded random state, the occupancy grid cache.

(in-package :cram-costmap-tests)

(in-suite costmap)

(defun every-ray-verdicts (costmap window r0 c0 stride height world goals handle)
  "Per block of the LINE-OF-SIGHT grid evaluation of WINDOW (the costmap's cells from (R0 C0)
on): its first row and column in WINDOW and whether enough of the rays to all GOALS are
clear, every ray cast: the verdicts without the early stop."
  (multiple-value-bind (rows columns) (costmap::sight-blocks window stride)
    (let* ((n (length rows))
           (eyes (costmap::sight-eyes costmap rows columns r0 c0 stride height))
           (all (make-array n :element-type 'fixnum))
           (counts (make-list n :initial-element 0)))
      (dotimes (b n) (setf (aref all b) b))
      (dolist (goal goals)
        (let ((clear (costmap::clear-sight world eyes all n goal handle)))
          (setf counts (loop for c in counts for j from 0 collect (+ c (aref clear j))))))
      (loop for c in counts
            for b from 0
            collect (list (aref rows b) (aref columns b)
                          (costmap::enough-points-seen-p c (length goals)))))))

(test line-of-sight-early-verdicts-are-every-ray-verdicts
  (in-kitchen
    (let* ((mug (btr:object btr:*current-bullet-world* 'mug-1))
           (target (costmap::object-center mug))
           (goals (mapcar #'costmap::xyz (costmap::view-target-points target mug)))
           (handle (btr:object-handle mug))
           (world (costmap::world-without '(:pr2)))
           (costmap (costmap:make-location-costmap))
           (r0 100) (c0 100) (size 101)
           (stride 2) (height 1.3d0))
      (dolist (threshold '(0 0.3 0.5 0.9 1))
        (let ((btr:*visibility-threshold* threshold)
              (window (make-array (list size size) :element-type 'double-float :initial-element 0d0)))
          ;; a ring of cells, as the range costs leave before the line of sight
          (dotimes (r size)
            (dotimes (c size)
              (when (< 400 (+ (expt (- r 50) 2) (expt (- c 50) 2)) 2500)
                (setf (aref window r c) 1d0))))
          (let ((expected (every-ray-verdicts costmap window r0 c0 stride height world goals handle)))
            (costmap::clear-blocks-out-of-sight costmap window r0 c0 stride height world goals handle)
            (is (< 0 (count-if #'third expected) (length expected))
                "some blocks see the mug and some do not (threshold ~a)" threshold)
            (is (every (lambda (e)
                         (destructuring-bind (br bc seen) e
                           (eq seen (loop for r from br below (min size (+ br stride))
                                          thereis (loop for c from bc below (min size (+ bc stride))
                                                        thereis (> (aref window r c) 0d0))))))
                       expected)
                "every block is kept exactly when every ray would see enough (threshold ~a)"
                threshold)))))))

(test line-of-sight-p-agrees-with-every-ray
  (in-kitchen
    (let* ((mug (btr:object btr:*current-bullet-world* 'mug-1))
           (points (costmap::view-target-points (costmap::object-center mug) mug))
           (world (costmap::world-without '(:pr2)))
           (handle (btr:object-handle mug))
           (verdicts '()))
      (dolist (threshold '(0.3 0.5 1))
        (let ((btr:*visibility-threshold* threshold))
          (loop for x from -4d0 to 2d0 by 0.5d0
                do (loop for y from -3d0 to 3d0 by 0.5d0
                         do (let* ((eye (cl-transforms:make-3d-vector x y 1.3d0))
                                   (eyes (make-array 3 :element-type 'double-float
                                                       :initial-contents (list x y 1.3d0)))
                                   (index (make-array 1 :element-type 'fixnum :initial-element 0))
                                   (clear (loop for p in points
                                                count (= 1 (aref (costmap::clear-sight
                                                                  world eyes index 1
                                                                  (costmap::xyz p) handle)
                                                                 0))))
                                   (fast (costmap:line-of-sight-p eye points mug :world world)))
                              (push (list fast (costmap::enough-points-seen-p clear (length points))
                                          x y threshold)
                                    verdicts))))))
      (is (null (remove-if (lambda (v) (eq (first v) (second v))) verdicts))
          "LINE-OF-SIGHT-P as every ray's count: mismatches (fast slow x y threshold) ~s"
          (remove-if (lambda (v) (eq (first v) (second v))) verdicts))
      (is (and (find t verdicts :key #'first) (find nil verdicts :key #'first) t)
          "both verdicts occur (~d of ~d seen)" (count t verdicts :key #'first) (length verdicts)))))

(test a-costmap-seeds-its-random-state-when-it-samples
  (flet ((xs (costmap)
           (mapcar (lambda (p) (cl-transforms:x (cl-transforms:origin p)))
                   (cut:force-ll (cut:lazy-take 6 (costmap:costmap-samples costmap))))))
    (let* ((seed (random (expt 2 62) (sb-ext:seed-random-state 21)))
           (eager (make-instance 'costmap:location-costmap
                                 :width 2 :height 2 :resolution 0.1 :origin-x -1 :origin-y -1
                                 :random-state (sb-ext:seed-random-state seed))))
      (costmap:seed-costmaps 21)
      (let ((lazy (costmap:make-location-costmap :width 2 :height 2 :resolution 0.1
                                                 :origin-x -1 :origin-y -1)))
        (is (eql seed (costmap::%random-state lazy)) "not seeded before it samples")
        (dolist (c (list eager lazy))
          (costmap:register-cost-function c (lambda (x y) (+ 1 x (* y y))) 'slope))
        (is (equal (xs eager) (xs lazy)))))
    ;; a merged costmap samples with the first costmap's random state, seeded or not
    (costmap:seed-costmaps 5)
    (let* ((a (costmap:make-location-costmap :width 2 :height 2 :resolution 0.1 :origin-x -1 :origin-y -1))
           (b (costmap:make-location-costmap :width 2 :height 2 :resolution 0.1 :origin-x -1 :origin-y -1))
           (merged (progn (costmap:register-cost-function a (lambda (x y) (+ 2 x y)) 'a)
                          (costmap:register-cost-function b (lambda (x y) (declare (ignore y)) (+ 2 x)) 'b)
                          (costmap:merge-costmaps a b)))
           (reference (make-instance 'costmap:location-costmap
                                     :width 2 :height 2 :resolution 0.1 :origin-x -1 :origin-y -1
                                     :random-state (make-random-state (costmap::costmap-random-state a)))))
      (costmap:register-cost-function reference (lambda (x y) (+ 2 x y)) 'a)
      (costmap:register-cost-function reference (lambda (x y) (declare (ignore y)) (+ 2 x)) 'b)
      (is (equal (xs reference) (xs merged))))
    (signals error (make-instance 'costmap:location-costmap :width 2 :height 2 :resolution 0.1
                                                            :origin-x -1 :origin-y -1 :random-state -3))))

(test occupancy-grids-from-the-cache-are-those-rasterised-anew
  (in-kitchen
    (let* ((kitchen (btr:object btr:*current-bullet-world* :iai-kitchen))
           (joint "sink_area_left_upper_drawer_main_joint")
           (costmap::*occupancy-cache* '())
           (costmap::*link-runs-cache* '()))
      (flet ((grid () (costmap:environment-occupancy-grid :padding 0.3))
             (fresh () (let ((costmap::*occupancy-cache* '()) (costmap::*link-runs-cache* '()))
                         (costmap:environment-occupancy-grid :padding 0.3))))
        (let ((closed (grid)))
          (setf (btr:joint-state kitchen joint) 0.4d0)
          (let ((open (grid)))
            (is (not (equalp (costmap:occupancy-bits closed) (costmap:occupancy-bits open)))
                "the open drawer occupies other cells")
            ;; more states than the cache keeps, then the first ones again
            (loop for q from 0.01d0 by 0.01d0 repeat (+ 2 costmap::*occupancy-cache-size*)
                  do (setf (btr:joint-state kitchen joint) q) (grid))
            (setf (btr:joint-state kitchen joint) 0.4d0)
            (let ((same (equalp (costmap:occupancy-bits (fresh)) (costmap:occupancy-bits (grid)))))
              (is (eq t same) "the open drawer's grid"))
            (setf (btr:joint-state kitchen joint) 0d0)
            (let ((same (equalp (costmap:occupancy-bits (fresh)) (costmap:occupancy-bits (grid)))))
              (is (eq t same) "the closed drawer's grid"))
            (is (eq (grid) (grid)) "a grid asked for again comes from the cache")
            ;; the drawer's links have moved, the kitchen's other links have not
            (let* ((record (cdr (first costmap::*link-runs-cache*)))
                   (moved (count 1 (costmap::link-runs-record-moved record))))
              (is (< 0 moved (length (btr:link-names kitchen))) "~d of ~d links moved" moved
                  (length (btr:link-names kitchen))))
            (is (<= (length costmap::*occupancy-cache*) costmap::*occupancy-cache-size*))))))))

(test rasterising-an-environment-keeps-the-cells-marked-before
  ;; a world with two environments rasterises both into one grid: the second adds its cells
  (in-kitchen
    (let* ((kitchen (btr:object btr:*current-bullet-world* :iai-kitchen))
           (costmap::*link-runs-cache* '())
           (fresh (costmap:environment-occupancy-grid :padding 0.1))
           (bits (make-array (array-dimensions (costmap:occupancy-bits fresh))
                             :element-type 'bit :initial-element 0))
           (free (loop for i below (array-total-size bits)
                       when (zerop (row-major-aref (costmap:occupancy-bits fresh) i)) return i)))
      (is (not (null free)) "the kitchen's grid has a free cell")
      (when free
        (setf (row-major-aref bits free) 1)
        (costmap::rasterise-environment
         bits kitchen (list 'other-grid (btr:urdf kitchen))
         (costmap::origin-x fresh) (costmap::origin-y fresh) (costmap::resolution fresh) 0.1d0
         costmap::*occupancy-z-min* costmap::*occupancy-z-max*)
        (is (= 1 (row-major-aref bits free)) "the cell marked before is still marked")
        (setf (row-major-aref bits free) 0)
        (is (equalp bits (costmap:occupancy-bits fresh)) "and the kitchen's cells are its grid's")))))

(defun cell-by-cell-grid (costmap)
  "COSTMAP's grid computed the plain way: in the cells of its region, the product of its cost
functions called at each centre, in the order they are applied, a cell that is 0 left alone."
  (let ((grid (make-array (list (costmap:costmap-rows costmap) (costmap:costmap-columns costmap))
                          :element-type 'double-float :initial-element 0d0)))
    (multiple-value-bind (r0 r1 c0 c1)
        (costmap::bounds->index-range costmap (costmap::costmap-support-bounds costmap))
      (loop for r from r0 below r1
            do (loop for c from c0 below c1
                     do (let ((v 1d0)
                              (x (costmap::cell-center-x costmap c))
                              (y (costmap::cell-center-y costmap r)))
                          (loop for (nil fn) in (costmap:cost-functions costmap)
                                when (> v 0d0)
                                  do (setf v (* v (float (funcall fn x y) 1d0))))
                          (setf (aref grid r c) v)))))
    grid))

(test grid-evaluators-give-the-cost-functions-values
  (let ((costmap (costmap:make-location-costmap :width 6 :height 5 :resolution 0.05
                                                :origin-x -3 :origin-y -2.5))
        (grid (costmap:make-occupancy-grid 6 5 -3 -2.5 0.05)))
    (setf (aref (costmap:occupancy-bits grid) 40 50) 1
          (aref (costmap:occupancy-bits grid) 41 50) 1)
    (costmap:register-cost-function costmap (costmap:make-range-cost-function '(0.3 -0.2) 2.2) 'range 0)
    (costmap:register-cost-function costmap (costmap:make-range-cost-function '(0.1 0.1) 0.4 :invert t)
                                    'range-invert 1)
    (costmap:register-cost-function costmap (costmap:make-occupancy-grid-cost-function grid) 'occupancy 1)
    (costmap:register-cost-function costmap (costmap:make-gauss-cost-function '(0.5 0) '((0.3 0.1) (0.1 0.5)))
                                    'gauss 2)
    (costmap:register-cost-function costmap (costmap:make-rectangle-cost-function -1.7d0 -1.9d0 1.25d0 2d0)
                                    'rectangle 3)
    (costmap:register-cost-function costmap (lambda (x y) (+ 1 (* x x) (abs y))) 'plain 4)
    (is (every (lambda (entry) (costmap::cost-function-grid-evaluator (second entry)))
               (remove 'plain (costmap:cost-functions costmap) :key #'first))
        "range, gauss, rectangle and occupancy fill the grid themselves")
    (let ((same (equalp (cell-by-cell-grid costmap) (costmap::cost-grid costmap))))
      (is (eq t same) "the grid is that of the functions called cell by cell"))
    (is (< 1000 (costmap::positive-cells (costmap::cost-window costmap))) "many cells are not 0")))

(test items-free-space-fills-the-grid-as-called-cell-by-cell
  ;; the free space around objects on a surface: rectangles grown by a margin, one of them
  ;; with an edge on cell centres (a strict comparison there)
  (let ((costmap (costmap:make-location-costmap :width 4 :height 4 :resolution 0.05
                                                :origin-x -2 :origin-y -2))
        (items '((0.0d0 0.1d0 0.4d0 0.5d0) (-1.0d0 -1.2d0 -0.7d0 -0.6d0) (-0.025d0 -0.025d0 0.3d0 0.2d0)))
        (exact (costmap::items-free-space-function '((0 0 1/2 1/2)) 1/20)))
    (costmap:register-cost-function costmap (costmap:make-range-cost-function '(0 0) 1.6) 'range 0)
    (costmap:register-cost-function costmap (costmap::items-free-space-function items 0.05d0)
                                    'free-space 1)
    (is (costmap::cost-function-grid-evaluator
         (second (find 'free-space (costmap:cost-functions costmap) :key #'first))))
    (is (eq t (equalp (cell-by-cell-grid costmap) (costmap::cost-grid costmap))))
    (is (< 100 (costmap::positive-cells (costmap::cost-window costmap))))
    (is (= 0d0 (funcall (costmap::items-free-space-function items 0.05d0) 0.2d0 0.3d0)))
    (is (= 1d0 (funcall (costmap::items-free-space-function items 0.05d0) 1.2d0 0.3d0)))
    ;; other numbers: the function as it is, called cell by cell
    (is (functionp exact))
    (is (not (typep exact 'costmap::cost-function)))
    (is (= 0d0 (funcall exact 0.1d0 0.1d0)))))

(test normalised-values-and-counts-without-the-normalised-grid
  (let ((costmap (costmap:make-location-costmap :width 4 :height 4 :resolution 0.1
                                                :origin-x -2 :origin-y -2)))
    (costmap:register-cost-function costmap (costmap:make-range-cost-function '(0.5 0.2) 1.1) 'range 0)
    (costmap:register-cost-function costmap (costmap:make-gauss-cost-function '(0.5 0.2) '((0.2 0) (0 0.2)))
                                    'gauss 1)
    (let ((fresh (costmap:make-location-costmap :width 4 :height 4 :resolution 0.1
                                                :origin-x -2 :origin-y -2)))
      (loop for (name fn score) in (costmap:cost-functions costmap)
            do (costmap:register-cost-function fresh fn name score))
      ;; values read before the normalised grid is made are the normalised grid's
      (let ((values (loop for x from -2.5d0 to 2.5d0 by 0.13d0
                          append (loop for y from -2.5d0 to 2.5d0 by 0.17d0
                                       collect (costmap:get-map-value fresh x y))))
            (grid (costmap:get-cost-map costmap)))
        (is (equal values
                   (loop for x from -2.5d0 to 2.5d0 by 0.13d0
                         append (loop for y from -2.5d0 to 2.5d0 by 0.17d0
                                      collect (let ((c (floor (+ x 2) 0.1d0)) (r (floor (+ y 2) 0.1d0)))
                                                (if (and (< -1 r 40) (< -1 c 40)) (aref grid r c) 0d0))))))
        (dolist (point '((0.5 0.2 0.85) (-1 -1 0.5) (1.9 1.9 3) (0 0 0)))
          (destructuring-bind (x y radius) point
            (is (= (loop for r below 40
                         sum (loop for c below 40
                                   count (and (plusp (aref grid r c))
                                              (<= (+ (expt (- (costmap::cell-center-y costmap r) y) 2)
                                                     (expt (- (costmap::cell-center-x costmap c) x) 2))
                                                  (expt radius 2)))))
                   (costmap:positive-cells-within fresh x y radius))
                "cells above 0 within ~a of (~a ~a)" radius x y)))))
    (signals error (costmap:positive-cells-within costmap 0 0 :far))
    (let ((zero (costmap:make-location-costmap :width 1 :height 1 :resolution 0.1 :origin-x 0 :origin-y 0)))
      (costmap:register-cost-function zero (constantly 0) 'zero)
      (signals costmap:invalid-probability-distribution (costmap:positive-cells-within zero 0 0 1)))))

(defvar *rule-padding* 0.25d0 "What the user's padding rule in the next test answers.")

(defun rule-padding () *rule-padding*)

(test metadata-from-rules-is-asked-each-time
  (let ((package (make-package (format nil "COSTMAP-USER-RULES-~d" (random 1000000))
                               :use '(:cl :prolog))))
    (unwind-protect
         (let ((padding (intern "COSTMAP-PADDING" package))
               (group (intern "MY-PADDING" package))
               (rob-int:*robot-name* :pr2))
           (flet ((value () (costmap:costmap-metadata-value 'costmap:costmap-padding)))
             (let ((before (value)))
               (is (eql before (value)) "the robot's padding, from facts")
               (is (costmap::metadata-from-facts-p 'costmap:costmap-padding))
               (eval `(prolog:def-fact-group ,group ()
                        (prolog:<- (,padding ?p) (prolog:lisp-fun rule-padding ?p))))
               (is (not (costmap::metadata-from-facts-p 'costmap:costmap-padding)))
               (is (eql 0.25d0 (value)))
               (let ((*rule-padding* 0.35d0))
                 (is (eql 0.35d0 (value)) "a rule is asked again, not remembered"))
               (eval `(prolog:def-fact-group ,group () (prolog:<- (,padding 0.45d0))))
               (is (eql 0.45d0 (value)) "the user's fact once the rule is gone")
               (prolog:remove-fact-group group)
               (is (eql before (value)) "the robot's padding again"))))
      (ignore-errors (prolog:remove-fact-group (find-symbol "MY-PADDING" package)))
      (delete-package package))))

(test kitchen-restricted-area-is-the-same-for-any-reals
  (flet ((area (x y)
           ;; the area as documented, compared as Common Lisp compares reals
           (cond ((> x 1.2d0) 0d0)
                 ((and (> x 0.5d0) (< -1.5d0 y 2d0)) 1d0)
                 ((and (> x 0d0) (< -1.5d0 y 1d0)) 1d0)
                 ((and (> x -1.5d0) (< -1.5d0 y 2.5d0)) 1d0)
                 ((and (> x -4d0) (< -1d0 y 1d0)) 1d0)
                 (t 0d0))))
    (let ((mismatches '()) (values '()))
      (loop for x from -4.5d0 to 1.5d0 by 0.05d0
            do (loop for y from -2d0 to 3d0 by 0.05d0
                     do (dolist (point (list (list x y) (list (rational x) (rational y))
                                             (list (float x 1f0) (float y 1f0))))
                          (destructuring-bind (px py) point
                            (let ((v (costmap:kitchen-restricted-area px py)))
                              (push v values)
                              (unless (eql v (area px py)) (push point mismatches)))))))
      ;; the boundaries themselves, as doubles and as the rationals just beside them
      (dolist (point '((1.2d0 0d0) (0.5d0 2d0) (6/5 0) (1/2 19/10) (0d0 -1.5d0) (-4d0 0d0)))
        (destructuring-bind (px py) point
          (unless (eql (costmap:kitchen-restricted-area px py) (area px py)) (push point mismatches))))
      (is (null mismatches) "points where the area differs: ~s" mismatches)
      (is (and (member 0d0 values) (member 1d0 values) t)))))

(test turned-link-top-grid-gives-the-function-values
  ;; the top of a turned link: the grid evaluator fills the cells with the values a call at
  ;; their centres gives, and the call takes any reals
  (in-kitchen
    (let* ((kitchen (btr:object btr:*current-bullet-world* :iai-kitchen))
           (name "kitchen_island_surface"))
      (turn-about-z kitchen 0.4d0)
      (let* ((top (costmap::link-top-function kitchen name 0.05d0))
             (costmap (costmap:make-location-costmap :width 6 :height 6 :resolution 0.05d0
                                                     :origin-x -3 :origin-y -3))
             (rows (costmap:costmap-rows costmap)) (cols (costmap:costmap-columns costmap))
             (window (make-array (list rows cols) :element-type 'double-float
                                                  :initial-element 1d0))
             (evaluator (costmap::cost-function-grid-evaluator top))
             (mismatches 0) (ones 0))
        (is (functionp evaluator) "a turned link's top has a grid evaluator")
        (funcall evaluator costmap window 0 rows 0 cols)
        (dotimes (r rows)
          (dotimes (c cols)
            (let ((v (funcall top (costmap::cell-center-x costmap c) (costmap::cell-center-y costmap r))))
              (when (= v 1d0) (incf ones))
              (unless (eql v (aref window r c)) (incf mismatches)))))
        (is (zerop mismatches))
        (is (< 100 ones (* rows cols)) "the top covers some cells, not all")
        (let ((centre (cl-transforms:origin (btr:link-pose kitchen name))))
          (is (eql 1d0 (funcall top (rational (cl-transforms:x centre))
                                (float (cl-transforms:y centre) 1f0)))))))))

(test potential-field-takes-any-real-threshold
  ;; LEFT-OF along the dining table's front edge: the value is the cosine of the angle off
  ;; the direction, 0 below the threshold (a rational or a single-float as a double)
  (in-kitchen
    (let* ((support (costmap::supporting-body (btr:object btr:*current-bullet-world* 'mug-1)))
           (reference (cl-transforms:make-3d-vector -1.5d0 -1d0 0.8d0))
           (f (costmap::potential-field-function :left-of :front reference support 1/2))
           (g (costmap::potential-field-function :left-of :front reference support 0.5f0)))
      (is (not (null support)) "the mug stands on something")
      (let ((values (loop for a from 0 below 360 by 15
                          collect (let ((x (+ -1.5d0 (* 0.3d0 (cos (* a (/ pi 180))))))
                                        (y (+ -1d0 (* 0.3d0 (sin (* a (/ pi 180)))))))
                                    (list (funcall f x y) (funcall g x y)
                                          (funcall f (rational x) (rational y)))))))
        (is (every (lambda (v) (and (eql (first v) (second v)) (eql (first v) (third v)))) values))
        (is (every (lambda (v) (or (zerop (first v)) (<= 0.5d0 (first v) 1d0))) values))
        (is (< 0 (count-if (lambda (v) (zerop (first v))) values) (length values)))))))
