;;;; Cost functions, orientation and height generators, occupancy grids and padding masks.

(in-package :cram-location-costmap)

(defun point-xy (point what)
  "(values x y) as double-floats of POINT: a 3D-VECTOR, a pose (its origin), or a list (x y ...)."
  (flet ((ok (x y)
           (unless (and (finite-real-p x) (finite-real-p y) (< (abs x) 1d6) (< (abs y) 1d6))
             (error "~a: the point ~s has non-finite or non-real coordinates." what point))
           (return-from point-xy (values (to-double x) (to-double y)))))
    (typecase point
      (cl-transforms:3d-vector (ok (cl-transforms:x point) (cl-transforms:y point)))
      (cl-transforms:pose (point-xy (cl-transforms:origin point) what))
      (cons (if (and (>= (length point) 2) (every #'realp (subseq point 0 2)))
                (ok (first point) (second point))
                (error "~a: the point ~s, expected (x y ...) of reals." what point)))
      (t (error "~a: the point ~s, expected a 3D-VECTOR, a pose or a list (x y ...)." what point)))))

(defun positive-real (value what)
  (unless (and (finite-real-p value) (> value 0) (< value 1d6))
    (error "~a is ~s, expected a positive real." what value))
  (coerce value 'double-float))

;;; ---- gaussian and range ------------------------------------------------------------------------

(defmacro cell-evaluator ((x y) &body value)
  "A grid evaluator (see MAKE-COST-FUNCTION) that multiplies each cell above 0 by VALUE, a
double-float computed from the cell centre X and Y (double-floats) as the cost function
computes it for that centre: the cost function's values without a call per cell."
  (let ((costmap (gensym "COSTMAP")) (window (gensym "WINDOW")) (xs (gensym "XS"))
        (r0 (gensym "R0")) (r1 (gensym "R1")) (c0 (gensym "C0")) (c1 (gensym "C1"))
        (r (gensym "R")) (c (gensym "C")) (wr (gensym "WR")) (wc (gensym "WC")) (w (gensym "W")))
    `(lambda (,costmap ,window ,r0 ,r1 ,c0 ,c1)
       (declare (type (simple-array double-float (* *)) ,window) (type fixnum ,r0 ,r1 ,c0 ,c1))
       (let ((,xs (make-array (max 0 (- ,c1 ,c0)) :element-type 'double-float)))
         (loop for ,c from ,c0 below ,c1
               do (setf (aref ,xs (- ,c ,c0)) (cell-center-x ,costmap ,c)))
         (loop for ,r of-type fixnum from ,r0 below ,r1
               for ,wr of-type fixnum from 0
               for ,y of-type double-float = (cell-center-y ,costmap ,r)
               do (locally (declare (optimize speed))
                    (dotimes (,wc (- ,c1 ,c0))
                      (let ((,w (aref ,window ,wr ,wc)))
                        (when (> ,w 0d0)
                          (let ((,x (aref ,xs ,wc)))
                            (declare (type double-float ,x))
                            (setf (aref ,window ,wr ,wc)
                                  (* ,w (the double-float (progn ,@value))))))))))))))

(defun covariance-entries (covariance)
  "(values sxx sxy syy) of COVARIANCE: ((sxx sxy) (syx syy)) or a 2x2 array."
  (flet ((entry (r c)
           (let ((v (etypecase covariance
                      (list (nth c (nth r covariance)))
                      (array (aref covariance r c)))))
             (unless (and (realp v) (not (and (floatp v) (sb-ext:float-nan-p v))) (< (abs v) 1d6))
               (error "MAKE-GAUSS-COST-FUNCTION: covariance ~s, entry (~d ~d) is ~s, expected ~
                       a finite real." covariance r c v))
             (to-double v))))
    (unless (or (and (listp covariance) (= (length covariance) 2)
                     (every (lambda (row) (and (listp row) (= (length row) 2))) covariance))
                (and (arrayp covariance) (equal (array-dimensions covariance) '(2 2))))
      (error "MAKE-GAUSS-COST-FUNCTION: covariance ~s, expected ((sxx sxy) (syx syy)) or a ~
              2x2 array." covariance))
    (values (entry 0 0) (/ (+ (entry 0 1) (entry 1 0)) 2) (entry 1 1))))

(defun make-gauss-cost-function (mean covariance)
  "A cost function exp(-d' C^-1 d / 2) / (2 pi sqrt(det C)), d the offset from MEAN (a point
or pose), C the positive definite 2x2 COVARIANCE.  It is zero more than 4 standard deviations
from MEAN along x or y."
  (multiple-value-bind (mx my) (point-xy mean "MAKE-GAUSS-COST-FUNCTION mean")
    (declare (type double-float mx my))
    (multiple-value-bind (sxx sxy syy) (covariance-entries covariance)
      (let ((det (- (* sxx syy) (* sxy sxy))))
        (unless (and (> sxx 0) (> det 0))
          (error "MAKE-GAUSS-COST-FUNCTION: covariance ~s is not positive definite." covariance))
        (let* ((ixx (/ syy det)) (ixy (/ (- sxy) det)) (iyy (/ sxx det))
               (norm (/ 1d0 (* 2 pi (sqrt det))))
               (dx (* 4 (sqrt sxx))) (dy (* 4 (sqrt syy))))
          (declare (type double-float ixx ixy iyy norm))
          (flet ((value (x y)
                   (declare (type double-float x y) (optimize speed))
                   (let ((a (- x mx)) (b (- y my)))
                     (declare (type double-float a b))
                     (* norm (exp (min 0d0 (* -0.5d0 (+ (* ixx a a) (* 2 ixy a b) (* iyy b b)))))))))
            (declare (inline value))
            (make-cost-function
             (lambda (x y) (value (float x 1d0) (float y 1d0)))
             :name 'gauss
             :bounds (list (- mx dx) (- my dy) (+ mx dx) (+ my dy))
             :grid-evaluator (cell-evaluator (x y) (value x y)))))))))

(defun make-range-cost-function (point distance &key invert)
  "A cost function that is 1 within DISTANCE metres (horizontally) of POINT and 0 farther;
with INVERT, 0 within DISTANCE and 1 farther."
  (multiple-value-bind (px py) (point-xy point "MAKE-RANGE-COST-FUNCTION point")
    (unless (and (finite-real-p distance) (>= distance 0) (< distance 1d6))
      (error "MAKE-RANGE-COST-FUNCTION: the distance is ~s, expected a non-negative real." distance))
    (let* ((d (to-double distance)) (d2 (* d d))
           (in (if invert 0d0 1d0)) (out (if invert 1d0 0d0)))
      (declare (type double-float d2 px py in out))
      (flet ((value (x y)
               (declare (type double-float x y) (optimize speed))
               (let ((dx (- x px)) (dy (- y py)))
                 (if (<= (+ (* dx dx) (* dy dy)) d2) in out))))
        (declare (inline value))
        (make-cost-function
         (lambda (x y) (value (float x 1d0) (float y 1d0)))
         :name (if invert 'range-invert 'range)
         :bounds (unless invert (list (- px d) (- py d) (+ px d) (+ py d)))
         :grid-evaluator (cell-evaluator (x y) (value x y)))))))

(defun make-axis-boundary-cost-function (axis boundary predicate)
  "A cost function that is 1 where (PREDICATE coordinate BOUNDARY) holds for the :X or :Y
coordinate AXIS, else 0; with PREDICATE #'< or #'> it knows its half-plane."
  (unless (member axis '(:x :y))
    (error "MAKE-AXIS-BOUNDARY-COST-FUNCTION: axis ~s, expected :X or :Y." axis))
  (unless (realp boundary)
    (error "MAKE-AXIS-BOUNDARY-COST-FUNCTION: boundary ~s, expected a real." boundary))
  (check-cost-function predicate "MAKE-AXIS-BOUNDARY-COST-FUNCTION")
  (let* ((b (coerce boundary 'double-float)) (inf 1d9)
         (bounds (cond ((member predicate (list #'< #'<= '< '<=))
                        (if (eq axis :x) (list (- inf) (- inf) b inf) (list (- inf) (- inf) inf b)))
                       ((member predicate (list #'> #'>= '> '>=))
                        (if (eq axis :x) (list b (- inf) inf inf) (list (- inf) b inf inf))))))
    (make-cost-function
     (lambda (x y) (if (funcall predicate (if (eq axis :x) x y) b) 1d0 0d0))
     :name 'axis-boundary :bounds bounds)))

(defun make-rectangle-cost-function (x-min y-min x-max y-max)
  "A cost function that is 1 inside the axis-aligned rectangle and 0 outside."
  (unless (and (every #'realp (list x-min y-min x-max y-max)) (<= x-min x-max) (<= y-min y-max))
    (error "MAKE-RECTANGLE-COST-FUNCTION: (~s ~s ~s ~s) is not a rectangle x-min y-min x-max y-max."
           x-min y-min x-max y-max))
  (make-cost-function (lambda (x y) (if (and (<= x-min x x-max) (<= y-min y y-max)) 1d0 0d0))
                      :name 'rectangle :bounds (list x-min y-min x-max y-max)
                      :grid-evaluator
                      (when (every (lambda (v) (typep v 'double-float)) (list x-min y-min x-max y-max))
                        (let ((x-min x-min) (y-min y-min) (x-max x-max) (y-max y-max))
                          (declare (type double-float x-min y-min x-max y-max))
                          (cell-evaluator (x y)
                            (if (and (<= x-min x x-max) (<= y-min y y-max)) 1d0 0d0))))))

(defun make-matrix-cost-function (origin-x origin-y resolution matrix)
  "A cost function reading the 2D array MATRIX (row = y index, column = x index) whose cell
(0 0) has its corner at (ORIGIN-X ORIGIN-Y) and cells RESOLUTION metres wide; 0 outside."
  (unless (and (arrayp matrix) (= (array-rank matrix) 2))
    (error "MAKE-MATRIX-COST-FUNCTION: expected a 2D array, got ~s." matrix))
  (let ((res (positive-real resolution "MAKE-MATRIX-COST-FUNCTION resolution"))
        (ox (coerce origin-x 'double-float)) (oy (coerce origin-y 'double-float)))
    (make-cost-function
     (lambda (x y)
       (let ((c (floor (- x ox) res)) (r (floor (- y oy) res)))
         (if (and (< -1 r (array-dimension matrix 0)) (< -1 c (array-dimension matrix 1)))
             (aref matrix r c)
             0d0)))
     :name 'matrix
     :bounds (list ox oy (+ ox (* res (array-dimension matrix 1)))
                   (+ oy (* res (array-dimension matrix 0)))))))

;;; ---- orientations and heights -------------------------------------------------------------------

(defun yaw-quaternion (yaw)
  (cl-transforms:axis-angle->quaternion (cl-transforms:make-3d-vector 0 0 1) yaw))

(defun sampled-yaws (yaw samples step)
  "YAW and, for SAMPLES > 1, angles alternately STEP, -STEP, 2 STEP ... around it."
  (unless (typep samples '(integer 1 1000))
    (error "Orientation samples ~s, expected an integer from 1 to 1000." samples))
  (unless (realp step) (error "Orientation sample step ~s, expected a real (radians)." step))
  (loop for i below samples
        collect (+ yaw (* step (if (oddp i) (/ (1+ i) 2) (- (/ i 2)))))))

(defun make-orientation-generator (yaw-function &key (samples 1) (sample-step (/ pi 18)))
  "An orientation generator from YAW-FUNCTION (x y) -> yaw in radians: SAMPLES orientations
around that yaw, SAMPLE-STEP apart."
  (check-cost-function yaw-function "MAKE-ORIENTATION-GENERATOR")
  (sampled-yaws 0 samples sample-step)
  (lambda (x y previous)
    (declare (ignore previous))
    (mapcar #'yaw-quaternion (sampled-yaws (funcall yaw-function x y) samples sample-step))))

(defun make-angle-to-point-generator (point &key (samples 1) (sample-step (/ pi 18)) (offset 0))
  "An orientation generator turning the x axis of the sampled pose towards POINT (a point or
pose), rotated by OFFSET radians, with SAMPLES orientations SAMPLE-STEP apart."
  (multiple-value-bind (px py) (point-xy point "MAKE-ANGLE-TO-POINT-GENERATOR point")
    (unless (realp offset)
      (error "MAKE-ANGLE-TO-POINT-GENERATOR: offset ~s, expected a real (radians)." offset))
    (make-orientation-generator (lambda (x y) (+ offset (atan (- py y) (- px x))))
                                :samples samples :sample-step sample-step)))

(defun make-identity-orientation-generator ()
  "An orientation generator giving the identity rotation."
  (lambda (x y previous)
    (declare (ignore x y previous))
    (list (cl-transforms:make-identity-rotation))))

(defun make-quarter-turns-orientation-generator ()
  "An orientation generator that gives each previous orientation (the identity when there is
none) and the same turned about the vertical by a quarter, a half and three quarters of a turn:
an object to be put down on a surface may stand turned as its grasp and the robot's side need."
  (lambda (x y previous)
    (declare (ignore x y))
    (loop for k from 0 below 4
          for turn = (cl-transforms:axis-angle->quaternion (cl-transforms:make-3d-vector 0 0 1)
                                                           (* k (/ pi 2)))
          append (mapcar (lambda (q) (cl-transforms:q* turn q))
                         (or previous (list (cl-transforms:make-identity-rotation)))))))

(defun make-preferred-yaw-ordering (yaw)
  "An orientation ordering (REGISTER-ORIENTATION-ORDERING) that puts the orientations whose
yaw is nearest to YAW (radians, map) first; those equally near keep their order."
  (unless (finite-real-p yaw)
    (error "MAKE-PREFERRED-YAW-ORDERING: the yaw is ~s, expected a finite real (radians)." yaw))
  (let ((yaw (float yaw 1d0)))
    (lambda (x y orientations)
      (declare (ignore x y))
      (stable-sort (copy-list orientations) #'<
                   :key (lambda (q)
                          ;; quarter turns give yaws equal up to rounding: their order stays
                          (round (abs (cl-transforms:normalize-angle
                                       (- (cl-transforms:get-yaw q) yaw)))
                                 1d-9))))))

(defun make-constant-height-function (height)
  "A height generator giving HEIGHT (metres) everywhere."
  (unless (and (realp height) (not (and (floatp height) (sb-ext:float-nan-p height))) (< (abs height) 1d6))
    (error "MAKE-CONSTANT-HEIGHT-FUNCTION: the height is ~s, expected a finite real." height))
  (let ((z (list (to-double height))))
    (lambda (x y) (declare (ignore x y)) z)))

;;; ---- occupancy grids ---------------------------------------------------------------------------------

(defclass occupancy-grid ()
  ((origin-x :initarg :origin-x :reader origin-x)
   (origin-y :initarg :origin-y :reader origin-y)
   (resolution :initarg :resolution :reader resolution)
   (bits :initarg :bits :reader occupancy-bits
         :documentation "A (rows x columns) bit array; 1 = occupied."))
  (:documentation "A grid of occupied (1) and free (0) cells over the map."))

(defmethod print-object ((g occupancy-grid) stream)
  (print-unreadable-object (g stream :type t :identity t)
    (format stream "~{~d~^x~} cells of ~,3f m" (reverse (array-dimensions (occupancy-bits g)))
            (resolution g))))

(defun make-occupancy-grid (width height origin-x origin-y resolution &optional bits)
  "An occupancy grid WIDTH x HEIGHT metres with cell (0 0) at ORIGIN, all free unless BITS (a
2D bit array of matching size) is given."
  (let* ((res (positive-real resolution "MAKE-OCCUPANCY-GRID resolution"))
         (cols (max 1 (round (positive-real width "MAKE-OCCUPANCY-GRID width") res)))
         (rows (max 1 (round (positive-real height "MAKE-OCCUPANCY-GRID height") res))))
    (when bits
      (unless (and (typep bits '(simple-array bit (* *))) (equal (array-dimensions bits) (list rows cols)))
        (error "MAKE-OCCUPANCY-GRID: bits ~s, expected a ~dx~d bit array." bits rows cols)))
    (make-instance 'occupancy-grid :origin-x (coerce origin-x 'double-float)
                                   :origin-y (coerce origin-y 'double-float) :resolution res
                                   :bits (or bits (make-array (list rows cols) :element-type 'bit
                                                                               :initial-element 0)))))

(defun occupied-p (grid x y)
  "True when the cell of GRID containing the map point (X Y) is occupied; outside: NIL."
  (let ((bits (occupancy-bits grid))
        (c (floor (- x (origin-x grid)) (resolution grid)))
        (r (floor (- y (origin-y grid)) (resolution grid))))
    (and (< -1 r (array-dimension bits 0)) (< -1 c (array-dimension bits 1))
         (= 1 (aref bits r c)))))

(defun make-padding-mask (radius)
  "A square bit array of side 2 RADIUS + 1 (RADIUS in cells) whose cells within RADIUS of the
centre are 1: the disk by which obstacles grow."
  (unless (typep radius '(integer 0 1000))
    (error "MAKE-PADDING-MASK: radius ~s, expected an integer number of cells from 0 to 1000." radius))
  (let* ((n (1+ (* 2 radius)))
         (mask (make-array (list n n) :element-type 'bit :initial-element 0)))
    (dotimes (r n mask)
      (dotimes (c n)
        (when (<= (+ (expt (- r radius) 2) (expt (- c radius) 2)) (* radius radius))
          (setf (aref mask r c) 1))))))

(defun pad-occupancy-grid (grid radius)
  "A new occupancy grid with every occupied cell of GRID grown by the padding mask of RADIUS cells."
  (let* ((mask (make-padding-mask radius))
         (bits (occupancy-bits grid))
         (rows (array-dimension bits 0)) (cols (array-dimension bits 1))
         (out (make-array (list rows cols) :element-type 'bit :initial-element 0)))
    (dotimes (r rows)
      (dotimes (c cols)
        (when (= 1 (aref bits r c))
          (loop for mr from (max 0 (- radius r)) to (min (* 2 radius) (- (+ rows radius) r 1))
                do (loop for mc from (max 0 (- radius c)) to (min (* 2 radius) (- (+ cols radius) c 1))
                         when (= 1 (aref mask mr mc))
                           do (setf (aref out (+ r mr (- radius)) (+ c mc (- radius))) 1))))))
    (make-instance 'occupancy-grid :origin-x (origin-x grid) :origin-y (origin-y grid)
                                   :resolution (resolution grid) :bits out)))

(defun make-occupancy-grid-cost-function (grid &key invert)
  "A cost function that is 1 in the free cells of the occupancy GRID and 0 in occupied ones
(and outside it); with INVERT, 1 in occupied cells."
  (unless (typep grid 'occupancy-grid)
    (error "MAKE-OCCUPANCY-GRID-COST-FUNCTION: expected an occupancy grid, got ~s." grid))
  (let ((bits (occupancy-bits grid)))
    (declare (type (simple-array bit (* *)) bits))
    (flet ((value (x y)
             (let ((c (floor (- x (origin-x grid)) (resolution grid)))
                   (r (floor (- y (origin-y grid)) (resolution grid))))
               (if (and (< -1 r (array-dimension bits 0)) (< -1 c (array-dimension bits 1)))
                   (if (eq (= 1 (aref bits r c)) (not invert)) 0d0 1d0)
                   (if invert 0d0 1d0)))))
      (make-cost-function
       #'value
       :name 'occupancy
       :grid-evaluator
       (lambda (costmap window r0 r1 c0 c1)
         (declare (type (simple-array double-float (* *)) window) (type fixnum r0 r1 c0 c1))
         (if (and (= (resolution costmap) (resolution grid))
                  (= (origin-x costmap) (origin-x grid)) (= (origin-y costmap) (origin-y grid))
                  (equal (array-dimensions bits)
                         (list (costmap-rows costmap) (costmap-columns costmap))))
             (let ((blocked (if invert 0 1)))
               (declare (type bit blocked))
               (loop for r of-type fixnum from r0 below r1
                     do (loop for c of-type fixnum from c0 below c1
                              when (= blocked (aref bits r c))
                                do (setf (aref window (- r r0) (- c c0)) 0d0))))
             (loop for r from r0 below r1
                   for y = (cell-center-y costmap r)
                   do (loop for c from c0 below c1
                            when (> (aref window (- r r0) (- c c0)) 0d0)
                              do (setf (aref window (- r r0) (- c c0))
                                       (* (aref window (- r r0) (- c c0))
                                          (value (cell-center-x costmap c) y)))))))))))
