;;;; Line of sight by ray casts in the Bullet belief state: the LINE-OF-SIGHT cost function of
;;;; VISIBLE-FOR costmaps and the test of the visibility validator.
;;;;
;;;; A place sees its target when enough of the rays from the camera height there to the
;;;; target's points are clear (ENOUGH-POINTS-SEEN-P).  The rays to the points are cast one
;;;; point at a time, and a place whose verdict is settled (enough rays clear already, or too
;;;; few rays left to make enough) gets no more rays: the verdicts are those of casting every
;;;; ray, with fewer rays.

(in-package :cram-location-costmap)

;;; Rays stop *LINE-OF-SIGHT-TOLERANCE* short of their target: what lies that close to the
;;; target (the surface it rests on, the target's own body) does not block the view, and the
;;; rays do not have to be tested against the target's shape.

(defparameter *line-of-sight-tolerance* 0.08d0
  "Rays of a line-of-sight test end this many metres before their target point.")

(defun object-handle-of (object)
  (and object (btr:object-handle object)))

(defun xyz (point)
  (list (coerce (cl-transforms:x point) 'double-float) (coerce (cl-transforms:y point) 'double-float)
        (coerce (cl-transforms:z point) 'double-float)))

(defun points-needed (total)
  "How many of TOTAL view target points must be seen for the target to be seen: the share
BTR:*VISIBILITY-THRESHOLD* asks of an object's visible part, at least one."
  (max 1 (ceiling (* (min 1 (max 0 btr:*visibility-threshold*)) total))))

(defun enough-points-seen-p (count total)
  "True when COUNT of TOTAL view target points seen make the object seen: the share of them
BTR:*VISIBILITY-THRESHOLD* asks of an object's visible part (at least one; all of a single
point)."
  (>= count (points-needed total)))

(defun sight-ray-ends (eyes indexes count goal)
  "(values from to), flat double vectors of the rays from the eyes INDEXES[0..COUNT) of EYES
\(a flat double vector, 3 per eye) to GOAL (x y z), each shortened by
*LINE-OF-SIGHT-TOLERANCE*."
  (declare (type (simple-array double-float (*)) eyes) (type (simple-array fixnum (*)) indexes)
           (type fixnum count))
  (let ((from (make-array (* 3 count) :element-type 'double-float))
        (to (make-array (* 3 count) :element-type 'double-float))
        (tolerance (float *line-of-sight-tolerance* 1d0)))
    (destructuring-bind (tx ty tz) goal
      (declare (type double-float tx ty tz))
      (locally (declare (optimize speed))
        (dotimes (j count)
          (let* ((i (* 3 (aref indexes j))) (o (* 3 j))
                 (ex (aref eyes i)) (ey (aref eyes (+ i 1))) (ez (aref eyes (+ i 2)))
                 (dx (- tx ex)) (dy (- ty ey)) (dz (- tz ez))
                 (len (sqrt (the (double-float 0d0) (+ (* dx dx) (* dy dy) (* dz dz)))))
                 (k (if (> len tolerance) (- 1d0 (/ tolerance len)) 0d0)))
            (setf (aref from o) ex (aref from (+ o 1)) ey (aref from (+ o 2)) ez
                  (aref to o) (+ ex (* k dx)) (aref to (+ o 1)) (+ ey (* k dy))
                  (aref to (+ o 2)) (+ ez (* k dz)))))))
    (values from to)))

(defun clear-sight (world eyes indexes count goal target-handle)
  "A bit vector of COUNT bits: 1 where the shortened ray from the eye INDEXES[j] of EYES (see
SIGHT-RAY-ENDS) to GOAL hits nothing in WORLD but the object with TARGET-HANDLE."
  (multiple-value-bind (from to) (sight-ray-ends eyes indexes count goal)
    (let ((hits (cram-native:ray-hit-objects (btr:world-handle world) from to))
          (clear (make-array count :element-type 'bit :initial-element 0)))
      (declare (type (simple-array (signed-byte 32) (*)) hits))
      (dotimes (j count clear)
        (let ((hit (aref hits j)))
          (when (or (< hit 0) (and target-handle (= hit target-handle)))
            (setf (aref clear j) 1)))))))

(defun eye-sees-p (world ex ey ez goals target-handle)
  "True when enough of the rays from the eye (EX EY EZ) to GOALS ((x y z) ...) are clear
\(ENOUGH-POINTS-SEEN-P); a ray is cast only while the verdict is open."
  (let ((eyes (make-array 3 :element-type 'double-float
                            :initial-contents (list (float ex 1d0) (float ey 1d0) (float ez 1d0))))
        (indexes (make-array 1 :element-type 'fixnum :initial-element 0))
        (need (points-needed (length goals)))
        (seen 0))
    (loop for goal in goals
          for left downfrom (1- (length goals))
          do (incf seen (aref (clear-sight world eyes indexes 1 goal target-handle) 0))
          when (>= seen need) return t
          when (< (+ seen left) need) return nil
          finally (return (>= seen need)))))

(defun world-without (names &optional (world btr:*current-bullet-world*))
  "A copy of WORLD without the objects NAMES (those WORLD has), e.g. without the robot whose
body would block the rays cast from where it is going to stand."
  (let ((copy (btr:copy-world world)))
    (dolist (name names copy)
      (when (btr:object copy name)
        (btr:remove-object copy name)))))

(declaim (inline block-end))
(defun block-end (first start count stride)
  "The end (exclusive, at most COUNT) in a window whose first row (or column) is the grid's
FIRST of the STRIDE rows of the grid (blocks start at multiples of STRIDE) that hold the
window's row START."
  (declare (type fixnum first start count stride))
  (min count (- (* stride (1+ (floor (+ first start) stride))) first)))

(defun sight-blocks (window stride &optional (r0 0) (c0 0))
  "(values rows columns): the first rows and columns (in WINDOW) of the STRIDE x STRIDE blocks
of the grid that WINDOW holds from the grid's cell (R0 C0) on, with a cell of WINDOW above 0,
row by row. The blocks start at the grid's rows and columns that are multiples of STRIDE (the
first and last in WINDOW may be cut), so that every window of the grid has the same blocks."
  (declare (type (simple-array double-float (* *)) window) (type fixnum stride r0 c0))
  (let ((rows '()) (columns '())
        (n-rows (array-dimension window 0)) (n-columns (array-dimension window 1)))
    (loop with br of-type fixnum = 0
          while (< br n-rows)
          do (let ((r-end (block-end r0 br n-rows stride)))
               (loop with bc of-type fixnum = 0
                     while (< bc n-columns)
                     do (let ((c-end (block-end c0 bc n-columns stride)))
                          (when (loop for r of-type fixnum from br below r-end
                                        thereis (loop for c of-type fixnum from bc below c-end
                                                        thereis (> (aref window r c) 0d0)))
                            (push br rows) (push bc columns))
                          (setf bc c-end)))
               (setf br r-end)))
    (values (coerce (nreverse rows) '(simple-array fixnum (*)))
            (coerce (nreverse columns) '(simple-array fixnum (*))))))

(defun block-eye (costmap row column stride)
  "(values x y): the map point at the centre of the STRIDE x STRIDE block of the costmap's grid
\(blocks start at multiples of STRIDE) that holds the cell (ROW COLUMN)."
  (values (cell-center-x costmap (+ (* stride (floor column stride)) (* 0.5d0 (1- stride))))
          (cell-center-y costmap (+ (* stride (floor row stride)) (* 0.5d0 (1- stride))))))

(defun sight-eyes (costmap rows columns r0 c0 stride height)
  "The eyes (a flat double vector, 3 per block) at the centres of the blocks (BLOCK-EYE) of
the costmap's cells whose first rows and columns are ROWS and COLUMNS counted from cell (R0
C0), at HEIGHT."
  (declare (type (simple-array fixnum (*)) rows columns) (type fixnum r0 c0 stride))
  (let* ((n (length rows))
         (eyes (make-array (* 3 n) :element-type 'double-float)))
    (dotimes (b n eyes)
      (multiple-value-bind (x y) (block-eye costmap (+ r0 (aref rows b)) (+ c0 (aref columns b)) stride)
        (setf (aref eyes (* 3 b)) x
              (aref eyes (+ 1 (* 3 b))) y
              (aref eyes (+ 2 (* 3 b))) height)))))

(defun clear-blocks-out-of-sight (costmap window r0 c0 stride height world goals handle)
  "Set to 0 the STRIDE x STRIDE blocks of WINDOW (the costmap's cells from (R0 C0) on; blocks
as SIGHT-BLOCKS makes them) that have a cell above 0 and from whose centre, at HEIGHT, too few
of GOALS are seen \(ENOUGH-POINTS-SEEN-P).  The rays go to one goal at a time, from the blocks
whose verdict is still open."
  (declare (type (simple-array double-float (* *)) window) (type fixnum r0 c0 stride))
  (multiple-value-bind (rows columns) (sight-blocks window stride r0 c0)
    (declare (type (simple-array fixnum (*)) rows columns))
    (let* ((n (length rows))
           (eyes (sight-eyes costmap rows columns r0 c0 stride height))
           (seen (make-array n :element-type 'fixnum :initial-element 0))
           (open (make-array n :element-type 'fixnum))
           (open-count n)
           (need (points-needed (length goals)))
           (n-rows (array-dimension window 0)) (n-columns (array-dimension window 1)))
      (declare (type fixnum open-count need))
      (dotimes (b n) (setf (aref open b) b))
      (loop for goal in goals
            for left of-type fixnum downfrom (1- (length goals))
            while (plusp open-count)
            do (let ((clear (clear-sight world eyes open open-count goal handle))
                     (kept 0))
                 (declare (type fixnum kept) (type simple-bit-vector clear))
                 (dotimes (j open-count)
                   (let ((b (aref open j)))
                     (incf (aref seen b) (aref clear j))
                     (when (and (< (aref seen b) need) (>= (+ (aref seen b) left) need))
                       (setf (aref open kept) b)
                       (incf kept))))
                 (setf open-count kept)))
      (dotimes (b n)
        (when (< (aref seen b) need)
          (let ((br (aref rows b)) (bc (aref columns b)))
            (loop for r of-type fixnum from br below (block-end r0 br n-rows stride)
                  do (loop for c of-type fixnum from bc below (block-end c0 bc n-columns stride)
                           do (setf (aref window r c) 0d0)))))))))

(defun make-line-of-sight-cost-function (target camera-height &key (world btr:*current-bullet-world*)
                                                                   target-object (stride 2)
                                                                   ignore-objects
                                                                   (points (list target)))
  "A cost function that is 1 at the map points from which enough of the rays at CAMERA-HEIGHT
to POINTS (3D points; default TARGET alone; ENOUGH-POINTS-SEEN-P) reach them (or
TARGET-OBJECT) unobstructed in WORLD, else 0; the objects named IGNORE-OBJECTS (e.g. the
robot) do not block.  On a grid it tests the centre of each STRIDE x STRIDE block of cells
that are not zero yet, casting a ray to a point only while the block's verdict is open; the
samples of a costmap test only the blocks they are drawn in (a :CELL-TEST, MAKE-COST-FUNCTION)."
  (unless (typep stride '(integer 1 64))
    (error "MAKE-LINE-OF-SIGHT-COST-FUNCTION: stride ~s, expected an integer from 1 to 64." stride))
  (unless (and (realp camera-height) (< (abs camera-height) 1d3))
    (error "MAKE-LINE-OF-SIGHT-COST-FUNCTION: camera height ~s, expected a real." camera-height))
  (let* ((world (if ignore-objects (world-without ignore-objects world) world))
         (goals (progn (xyz target) (mapcar #'xyz points)))
         (h (coerce camera-height 'double-float))
         (handle (object-handle-of target-object)))
    (make-cost-function
     (lambda (x y)
       (if (eye-sees-p world x y h goals handle) 1d0 0d0))
     :name 'line-of-sight
     :grid-evaluator
     (lambda (costmap window r0 r1 c0 c1)
       (declare (ignore r1 c1))
       (clear-blocks-out-of-sight costmap window r0 c0 stride h world goals handle))
     ;; samples test the blocks they are drawn in, each once (the costmaps merged from this
     ;; one, which other threads may sample, share the verdicts)
     :cell-test
     (let ((verdicts (make-hash-table :test 'equal :synchronized t)))
       (lambda (costmap row column)
         (multiple-value-bind (x y) (block-eye costmap row column stride)
           (let ((key (cons x y)))
             (multiple-value-bind (known found) (gethash key verdicts)
               (if found
                   known
                   (setf (gethash key verdicts) (eye-sees-p world x y h goals handle)))))))))))

(defun view-target-points (target target-object)
  "The points a line of sight must reach to see TARGET: TARGET itself, and for an object the
centre and top of its bounding box and the middles of its four vertical sides."
  (if (null target-object)
      (list target)
      (multiple-value-bind (lo hi) (btr:aabb target-object)
        (let* ((cx (/ (+ (cl-transforms:x lo) (cl-transforms:x hi)) 2))
               (cy (/ (+ (cl-transforms:y lo) (cl-transforms:y hi)) 2))
               (cz (/ (+ (cl-transforms:z lo) (cl-transforms:z hi)) 2))
               (sx (* 0.4d0 (- (cl-transforms:x hi) (cl-transforms:x lo))))
               (sy (* 0.4d0 (- (cl-transforms:y hi) (cl-transforms:y lo))))
               (top (- (cl-transforms:z hi) (* 0.1d0 (- (cl-transforms:z hi) (cl-transforms:z lo))))))
          (list (cl-transforms:make-3d-vector cx cy cz)
                (cl-transforms:make-3d-vector cx cy top)
                (cl-transforms:make-3d-vector (- cx sx) cy cz)
                (cl-transforms:make-3d-vector (+ cx sx) cy cz)
                (cl-transforms:make-3d-vector cx (- cy sy) cz)
                (cl-transforms:make-3d-vector cx (+ cy sy) cz))))))

(defun line-of-sight-p (eye points target-object &key (world btr:*current-bullet-world*))
  "True when enough of the rays from EYE (a 3D point) to POINTS (ENOUGH-POINTS-SEEN-P) reach
their point (up to *LINE-OF-SIGHT-TOLERANCE*), or TARGET-OBJECT, unobstructed in WORLD."
  (destructuring-bind (ex ey ez) (xyz eye)
    (eye-sees-p world ex ey ez (mapcar #'xyz points) (object-handle-of target-object))))
