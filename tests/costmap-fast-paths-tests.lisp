;;;; The costmaps' fast paths give what the plain ways give: line of sight with early
;;;; verdicts, the lazily seeded random state, the occupancy grid cache.

(in-package :cram-costmap-tests)

(in-suite costmap)

(defun every-ray-verdicts (costmap matrix region stride height world goals handle)
  "Per block of the LINE-OF-SIGHT grid evaluation, whether enough of the rays to all GOALS are
clear, every ray cast: the verdicts without the early stop."
  (destructuring-bind (r0 r1 c0 c1) region
    (multiple-value-bind (rows columns) (costmap::sight-blocks matrix r0 r1 c0 c1 stride)
      (let* ((n (length rows))
             (eyes (make-array (* 3 n) :element-type 'double-float))
             (all (make-array n :element-type 'fixnum)))
        (dotimes (b n)
          (setf (aref eyes (* 3 b)) (costmap::cell-center-x costmap (+ (aref columns b) (* 0.5d0 (1- stride))))
                (aref eyes (+ 1 (* 3 b))) (costmap::cell-center-y costmap (+ (aref rows b) (* 0.5d0 (1- stride))))
                (aref eyes (+ 2 (* 3 b))) height
                (aref all b) b))
        (let ((counts (make-list n :initial-element 0)))
          (dolist (goal goals)
            (let ((clear (costmap::clear-sight world eyes all n goal handle)))
              (setf counts (loop for c in counts for j from 0 collect (+ c (aref clear j))))))
          (loop for c in counts
                for b from 0
                collect (list (aref rows b) (aref columns b)
                              (costmap::enough-points-seen-p c (length goals)))))))))

(test line-of-sight-early-verdicts-are-every-ray-verdicts
  (in-kitchen
    (let* ((mug (btr:object btr:*current-bullet-world* 'mug-1))
           (target (costmap::object-center mug))
           (goals (mapcar #'costmap::xyz (costmap::view-target-points target mug)))
           (handle (btr:object-handle mug))
           (world (costmap::world-without '(:pr2)))
           (costmap (costmap:make-location-costmap))
           (region '(100 200 100 200))
           (stride 2) (height 1.3d0))
      (dolist (threshold '(0 0.3 0.5 0.9 1))
        (let ((btr:*visibility-threshold* threshold)
              (matrix (make-array (list (costmap:costmap-rows costmap) (costmap:costmap-columns costmap))
                                  :element-type 'double-float :initial-element 0d0)))
          (destructuring-bind (r0 r1 c0 c1) region
            ;; a ring of cells, as the range costs leave before the line of sight
            (loop for r from r0 below r1
                  do (loop for c from c0 below c1
                           when (< 400 (+ (expt (- r 150) 2) (expt (- c 150) 2)) 2500)
                             do (setf (aref matrix r c) 1d0)))
            (let ((expected (every-ray-verdicts costmap matrix region stride height world goals handle)))
              (costmap::clear-blocks-out-of-sight costmap matrix r0 r1 c0 c1 stride height world
                                                  goals handle)
              (is (< 0 (count-if #'third expected) (length expected))
                  "some blocks see the mug and some do not (threshold ~a)" threshold)
              (is (every (lambda (e)
                           (destructuring-bind (br bc seen) e
                             (eq seen (loop for r from br below (min r1 (+ br stride))
                                            thereis (loop for c from bc below (min c1 (+ bc stride))
                                                          thereis (> (aref matrix r c) 0d0))))))
                         expected)
                  "every block is kept exactly when every ray would see enough (threshold ~a)"
                  threshold))))))))

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
           (costmap::*occupancy-cache* '()))
      (flet ((grid () (costmap:environment-occupancy-grid :padding 0.3))
             (fresh () (let ((costmap::*occupancy-cache* '()))
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
            (is (<= (length costmap::*occupancy-cache*) costmap::*occupancy-cache-size*))))))))
