;;;; Sampling costmaps: cost functions that test the drawn cells instead of filling the grid
;;;; (the line of sight), and orientation orderings (the quarter turns of a place, best first for
;;;; an object the robot holds).

(in-package :cram-costmap-tests)

(in-suite costmap)

(defun tested-cost-function (counter)
  "A cost function that is 1 where y > 0 and 0 elsewhere, with a grid evaluator and a cell
test; COUNTER (a cons) counts the grid evaluations in its car and the cell tests in its cdr."
  (costmap:make-cost-function
   (lambda (x y) (declare (ignore x)) (if (> y 0) 1d0 0d0))
   :name 'upper-half
   :grid-evaluator (lambda (costmap window r0 r1 c0 c1)
                     (incf (car counter))
                     (loop for r from r0 below r1
                           do (when (<= (costmap::cell-center-y costmap r) 0)
                                (loop for c from c0 below c1
                                      do (setf (aref window (- r r0) (- c c0)) 0d0)))))
   :cell-test (lambda (costmap row column)
                (declare (ignore column))
                (incf (cdr counter))
                (> (costmap::cell-center-y costmap row) 0))))

(defun two-level-costmap (counter)
  "A 2 x 2 m costmap: 1 where x < 0, 3 where x >= 0, times TESTED-COST-FUNCTION."
  (let ((costmap (costmap:make-location-costmap :width 2 :height 2 :resolution 0.05
                                                :origin-x -1 :origin-y -1)))
    (costmap:register-cost-function costmap (lambda (x y) (declare (ignore y)) (if (< x 0) 1d0 3d0))
                                    'two-levels 0)
    (costmap:register-cost-function costmap (tested-cost-function counter) 'upper-half 1)
    costmap))

(test samples-are-drawn-where-the-cell-tests-pass
  (costmap:seed-costmaps 3)
  (let* ((counter (cons 0 0))
         (costmap (two-level-costmap counter))
         (points (loop repeat 2000 collect (costmap:gen-costmap-sample-point costmap))))
    (is (= 0 (car counter)) "sampling did not fill the grid with the tested function")
    (is (< 2000 (cdr counter) 8000) "the drawn cells were tested (~d tests)" (cdr counter))
    (is (every (lambda (p) (> (cl-transforms:y p) 0)) points) "every sample where the test passes")
    ;; the distribution is the grid's: three times as likely where x >= 0
    (let ((ratio (/ (count-if (lambda (p) (>= (cl-transforms:x p) 0)) points)
                    (max 1 (count-if (lambda (p) (< (cl-transforms:x p) 0)) points)))))
      (is (< 2.5 ratio 3.6) "right against left: ~,2f, expected about 3" ratio))
    ;; the grid of values still holds the tested function, filled by its evaluator
    (let ((grid (costmap::cost-grid costmap)))
      (is (= 1 (car counter)))
      (is (eq t (equalp grid (cell-by-cell-grid costmap))) "the grid, cell by cell"))
    ;; the same seed draws the same samples
    (costmap:seed-costmaps 3)
    (let ((again (two-level-costmap (cons 0 0))))
      (is (equalp points (loop repeat 2000 collect (costmap:gen-costmap-sample-point again)))))))

(test a-costmap-whose-cell-tests-fail-everywhere-has-no-samples
  (let* ((costmap (costmap:make-location-costmap :width 1 :height 1 :resolution 0.1
                                                 :origin-x 0 :origin-y 0))
         (tests 0))
    (costmap:register-cost-function costmap (lambda (x y) (declare (ignore x y)) 1d0) 'flat 0)
    (costmap:register-cost-function
     costmap (costmap:make-cost-function (lambda (x y) (declare (ignore x y)) 0d0)
                                         :name 'nowhere
                                         :cell-test (lambda (c r k) (declare (ignore c r k))
                                                      (incf tests) nil))
     'nowhere 1)
    (signals costmap:invalid-probability-distribution
      (cut:lazy-car (costmap:costmap-samples costmap)))
    (is (= tests costmap::*cell-test-limit*) "gave up after ~d tests" tests)
    (signals error (costmap:make-cost-function #'+ :cell-test 3))))

(test line-of-sight-samples-lie-in-the-blocks-that-see
  (in-kitchen
    (costmap:seed-costmaps 11)
    (let* ((designator (visible-for-mug))
           (costmap (costmap:designator-costmap designator))
           (samples (multiple-value-bind (calls samples)
                        (cram-plans-tests:calls-during 'costmap::clear-blocks-out-of-sight
                                      (lambda ()
                                        (cut:force-ll (cut:lazy-take 30 (costmap:costmap-samples costmap)))))
                      (is (= 0 calls) "the line of sight was not cast for the whole grid")
                      samples))
           (grid (costmap::cost-grid costmap)))
      (is (= 30 (length samples)))
      (is (every (lambda (p)
                   (let ((o (cl-transforms:origin p)))
                     (multiple-value-bind (column row)
                         (values (floor (- (cl-transforms:x o) (costmap:origin-x costmap))
                                        (costmap::resolution costmap))
                                 (floor (- (cl-transforms:y o) (costmap:origin-y costmap))
                                        (costmap::resolution costmap)))
                       (> (aref grid row column) 0d0))))
                 samples)
          "every sample lies in a cell the whole grid keeps"))))

(test line-of-sight-blocks-start-at-multiples-of-the-stride
  (let ((window (make-array '(5 5) :element-type 'double-float :initial-element 1d0)))
    ;; a window from the grid's cell (3 4) on: blocks of 2 start at grid rows 2, 4, 6, columns 4, 6, 8
    (multiple-value-bind (rows columns) (costmap::sight-blocks window 2 3 4)
      (is (equalp #(0 0 0 1 1 1 3 3 3) rows))
      (is (equalp #(0 2 4 0 2 4 0 2 4) columns)))))

(test orientation-orderings-sort-what-the-generators-made
  (let ((a (costmap:make-location-costmap :width 1 :height 1 :resolution 0.1 :origin-x 0 :origin-y 0))
        (b (costmap:make-location-costmap :width 1 :height 1 :resolution 0.1 :origin-x 0 :origin-y 0)))
    (costmap:register-cost-function a (lambda (x y) (declare (ignore x y)) 1d0) 'flat 0)
    ;; the ordering comes from the first costmap, the quarter turns from the second
    (costmap:register-orientation-ordering a (costmap:make-preferred-yaw-ordering (/ pi 2)))
    (costmap:register-orientation-generator b (costmap::make-quarter-turns-orientation-generator))
    (flet ((yaws (costmap)
             (mapcar (lambda (q) (/ (round (cl-transforms:get-yaw q) 1d-6) 1d6))
                     (costmap::generate-orientations costmap 0.5d0 0.5d0))))
      (is (equal '(0.0d0 1.570796d0 3.141593d0 -1.570796d0) (yaws b)))
      (let ((merged (costmap:merge-costmaps a b)))
        (is (equal '(1.570796d0 0.0d0 3.141593d0 -1.570796d0) (yaws merged)))
        (costmap:register-orientation-ordering merged (lambda (x y os) (declare (ignore x y)) (rest os)))
        (signals error (yaws merged) "an ordering that drops orientations")))
    (signals error (costmap:make-preferred-yaw-ordering :north))))

(test places-for-a-held-object-come-as-it-is-held-first
  (in-kitchen
    (let* ((robot (robot))
           (mug (btr:object btr:*current-bullet-world* 'mug-1))
           (base (cl-transforms:make-pose (cl-transforms:make-3d-vector -0.2 0.5 0)
                                          (cl-transforms:axis-angle->quaternion
                                           (cl-transforms:make-3d-vector 0 0 1) 2.0d0)))
           (?from (cl-transforms-stamped:pose->pose-stamped "map" 0d0 base))
           (?mug (mug-designator))
           (designator (desig:a location (reachable-from ?from) (for ?mug))))
      (flet ((first-yaw ()
               (let ((costmap (costmap:merge-costmaps
                               (costmap::reachable-from-costmap designator ?from)
                               (let ((turns (costmap:make-location-costmap)))
                                 (costmap:register-orientation-generator
                                  turns (costmap::make-quarter-turns-orientation-generator))
                                 turns))))
                 (cl-transforms:get-yaw (first (costmap::generate-orientations costmap -0.9d0 0.6d0))))))
        (is (< (abs (first-yaw)) 1d-9) "not held: the orientations as the generators made them")
        ;; held, turned 1.3 rad from the robot's heading: the robot at BASE keeps it so
        (setf (btr:pose robot) (cl-transforms:make-identity-pose)
              (btr:pose mug) (cl-transforms:make-pose (cl-transforms:origin (btr:pose mug))
                                                      (cl-transforms:axis-angle->quaternion
                                                       (cl-transforms:make-3d-vector 0 0 1) 1.3d0)))
        (btr:attach-object robot mug :link "l_gripper_palm_link")
        (let ((yaw (first-yaw)))
          ;; 2.0 + 1.3 = 3.3, nearest quarter turn: pi
          (is (< (abs (cl-transforms:normalize-angle (- yaw pi))) 1d-6) "first yaw ~,3f, expected pi" yaw))))))

(test costmap-seeding-makes-sbcls-random-states
  "A costmap's random state, seeded from its integer seed by the costmap's own key
initialisation, is the state SBCL's SEED-RANDOM-STATE makes from that seed: the same words and
the same draws, for seeds below and above 32 bits (the costmaps' seeds are up to 62 bits)."
  (is-true costmap::*key-seeding-p*)
  (let ((seeds (sb-ext:seed-random-state 2024)))
    (dolist (seed (append '(0 1 #xFFFFFFFF #x100000000 #x3FFFFFFFFFFFFFFF)
                          (loop repeat 50 collect (random (expt 2 62) seeds))))
      (let ((ours (costmap::seeded-random-state seed))
            (sbcls (sb-ext:seed-random-state seed)))
        (is (equalp (sb-kernel::random-state-state sbcls) (sb-kernel::random-state-state ours))
            "seed ~d: the state words differ" seed)
        (is (equal (loop repeat 1000 collect (random 1000003 sbcls))
                   (loop repeat 1000 collect (random 1000003 ours)))
            "seed ~d: the draws differ" seed))))
  ;; a costmap seeded with an integer samples as one given the state SBCL makes from it
  (flet ((samples (random-state)
           (let ((costmap (make-instance 'costmap:location-costmap :width 2 :height 2
                                                        :resolution 0.05 :origin-x -1 :origin-y -1
                                                        :random-state random-state)))
             (costmap:register-cost-function costmap (lambda (x y) (+ 1d0 (* x x) y)) 'bowl)
             (mapcar (lambda (p) (let ((o (cl-transforms:origin p)))
                                   (list (cl-transforms:x o) (cl-transforms:y o))))
                     (cut:force-ll (cut:lazy-take 20 (costmap:costmap-samples costmap)))))))
    (let ((seed 987654321987654))
      (is (equal (samples (sb-ext:seed-random-state seed)) (samples seed))))))

(test a-target-that-is-no-pose-is-named-in-its-error
  "A location's solution that is neither a pose nor a pose-stamped is an error naming it as its
caller describes it, a string or a description made only for the error."
  (let ((made 0))
    (is (search "solution of the cup's place"
                (handler-case (progn (costmap::pose-in-map 42 (lambda () (incf made)
                                                                "solution of the cup's place"))
                                     "")
                  (error (e) (princ-to-string e)))))
    (is (= 1 made))
    (costmap::pose-in-map (cl-transforms:make-identity-pose) (lambda () (incf made) "never"))
    (is (= 1 made) "a pose needs no description")
    (is (search "target pose"
                (handler-case (progn (costmap::pose-in-map "here" "target pose") "")
                  (error (e) (princ-to-string e)))))))
