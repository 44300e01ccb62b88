;;;; Costmaps from the Bullet belief state: occupancy of the environment's static geometry,
;;;; base poses in collision (line of sight: sight.lisp).

(in-package :cram-location-costmap)

(defparameter *occupancy-z-min* 0.05d0
  "Geometry below this height (metres) does not block the robot base.")

(defparameter *occupancy-z-max* 1.9d0
  "Geometry above this height (metres) does not block the robot base.")

(defvar *occupancy-cache* '()
  "Recently used occupancy grids: a list of (key . grid), the most recently used first.")

(defparameter *occupancy-cache-size* 32
  "How many occupancy grids *OCCUPANCY-CACHE* keeps (each some 11 kB for the PR2's 300 x 300
cells): a household run opens and closes a dozen drawers and doors and asks for grids of two
paddings in each state.")

(defun recent-entry (symbol key test)
  "The entry (key . value) under KEY (compared with TEST) of the list of recently used entries
in the special variable SYMBOL, moved to its front; NIL when there is none."
  (let ((entry (assoc key (symbol-value symbol) :test test)))
    (when (and entry (not (eq entry (first (symbol-value symbol)))))
      (setf (symbol-value symbol) (cons entry (remove entry (symbol-value symbol) :test #'eq))))
    entry))

(defun add-recent-entry (symbol key value size)
  "Put (KEY . VALUE) at the front of the list of recently used entries in the special variable
SYMBOL, keeping at most SIZE entries. Returns VALUE."
  (push (cons key value) (symbol-value symbol))
  (when (> (length (symbol-value symbol)) size)
    (setf (symbol-value symbol) (subseq (symbol-value symbol) 0 size)))
  value)

(defun vector-key (pose)
  (let ((o (cl-transforms:origin pose)) (q (cl-transforms:orientation pose)))
    (list (cl-transforms:x o) (cl-transforms:y o) (cl-transforms:z o)
          (cl-transforms:x q) (cl-transforms:y q) (cl-transforms:z q) (cl-transforms:w q))))

(defun static-obstacles (world)
  "The articulated objects of WORLD that are not the robot: the environments."
  (let ((robot (btr:get-robot-object world)))
    (remove-if-not (lambda (o) (and (btr:robot-object-p o) (not (eq o robot))))
                   (btr:objects world))))

(declaim (inline cell-index))
(defun cell-index (v)
  "FLOOR of the double V, a cell index (far outside a grid's cells is clamped later)."
  (declare (type double-float v))
  (let ((c (max -1d9 (min 1d9 v))))
    (declare (type (double-float -1d9 1d9) c))
    (values (floor c))))

(defun apply-runs (bits runs)
  "Mark the cells of the runs RUNS (a fixnum vector of row, first and last column triples) in
the bit matrix BITS."
  (declare (type (simple-array bit (* *)) bits) (type (simple-array fixnum (*)) runs)
           (optimize speed))
  (let ((cols (array-dimension bits 1))
        (flat (sb-ext:array-storage-vector bits)))
    (declare (type simple-bit-vector flat))
    (loop for k of-type fixnum from 0 below (length runs) by 3
          do (let ((start (+ (* (aref runs k) cols) (aref runs (+ k 1)))))
               (fill flat 1 :start start
                            :end (+ start (- (aref runs (+ k 2)) (aref runs (+ k 1))) 1))))
    bits))

(defun box-runs (rows cols origin-x origin-y resolution x0 y0 x1 y1 padding)
  "The runs (a fixnum vector of row, first and last column triples) of the cells of a grid of
ROWS x COLS cells (cell (0 0) at ORIGIN) whose centres are within PADDING of the rectangle
[X0 X1] x [Y0 Y1]. Each row's cells form one run: its ends are found by testing the cells near
them, the cells between are taken without a test."
  (declare (type fixnum rows cols) (type double-float origin-x origin-y resolution
                                                      x0 y0 x1 y1 padding)
           (optimize speed))
  (let* ((c0 (max 0 (cell-index (/ (- x0 padding origin-x) resolution))))
         (c1 (min (1- cols) (cell-index (/ (- (+ x1 padding) origin-x) resolution))))
         (r0 (max 0 (cell-index (/ (- y0 padding origin-y) resolution))))
         (r1 (min (1- rows) (cell-index (/ (- (+ y1 padding) origin-y) resolution))))
         (p2 (* padding padding))
         (runs (make-array (* 3 (max 0 (1+ (- r1 r0)))) :element-type 'fixnum))
         (k 0))
    (declare (type fixnum c0 c1 r0 r1 k) (type double-float p2))
    (when (<= c0 c1)
      (loop for r of-type fixnum from r0 to r1
            for y of-type double-float = (+ origin-y (* (+ r 0.5d0) resolution))
            for dy of-type double-float = (max 0d0 (- y0 y) (- y y1))
            for dy2 of-type double-float = (* dy dy)
            when (<= dy2 p2)
              do (flet ((inside (c)
                          (declare (type fixnum c))
                          (let* ((x (+ origin-x (* (+ c 0.5d0) resolution)))
                                 (dx (max 0d0 (- x0 x) (- x x1))))
                            (<= (+ (* dx dx) dy2) p2))))
                   (declare (inline inside))
                   ;; the run's ends as the cell arithmetic puts them, then moved to where the
                   ;; test itself says (the run is contiguous: the distance grows away from it)
                   (let* ((left (- p2 dy2))
                          (reach (if (> left 0d0) (sqrt left) 0d0))
                          (a (max c0 (min (1+ c1) (- (cell-index (- 0.5d0 (/ (- x0 reach origin-x) resolution)))))))
                          (b (min c1 (max (1- c0) (cell-index (- (/ (- (+ x1 reach) origin-x) resolution) 0.5d0))))))
                     (declare (type fixnum a b))
                     (loop while (and (> a c0) (inside (1- a))) do (decf a))
                     (loop while (and (<= a c1) (not (inside a))) do (incf a))
                     (loop while (and (< b c1) (inside (1+ b))) do (incf b))
                     (loop while (and (>= b a) (not (inside b))) do (decf b))
                     (when (<= a b)
                       (setf (aref runs k) r (aref runs (+ k 1)) a (aref runs (+ k 2)) b)
                       (incf k 3))))))
    (if (= k (length runs)) runs (subseq runs 0 k))))

(defun rasterise-box (bits origin-x origin-y resolution x0 y0 x1 y1 padding)
  "Mark the cells of BITS whose centres are within PADDING of the rectangle [X0 X1] x [Y0 Y1]
\(BOX-RUNS)."
  (declare (type (simple-array bit (* *)) bits))
  (apply-runs bits (box-runs (array-dimension bits 0) (array-dimension bits 1)
                             origin-x origin-y resolution x0 y0 x1 y1 padding)))

(defun convex-hull-2d (points)
  "The convex hull of POINTS ((x y) ...), counter-clockwise, without repeated corners."
  (let ((sorted (sort (remove-duplicates (copy-list points) :test #'equal)
                      (lambda (a b) (or (< (first a) (first b))
                                        (and (= (first a) (first b)) (< (second a) (second b))))))))
    (labels ((cross (o a b) (- (* (- (first a) (first o)) (- (second b) (second o)))
                             (* (- (second a) (second o)) (- (first b) (first o)))))
           (chain (pts)
             (let ((hull '()))
               (dolist (p pts (reverse hull))
                 (loop while (and (cdr hull) (<= (cross (second hull) (first hull) p) 0d0))
                       do (pop hull))
                 (push p hull)))))
      (if (< (length sorted) 3)
          sorted
          (let ((lower (chain sorted)) (upper (chain (reverse sorted))))
            (append (butlast lower) (butlast upper)))))))

(defun link-footprint (env index name)
  "The corners (x y), counter-clockwise, of the outline on the floor of the box of link INDEX
\(named NAME) of ENV in the link's own frame (BTR:LOCAL-AABB) as the link stands: for a link
turned about the vertical, its turned rectangle, not the larger box around it in the map."
  (multiple-value-bind (lo hi) (btr:local-aabb env index)
    (let ((pose (btr:link-pose env name)) (points '()))
      (dolist (x (list (cl-transforms:x lo) (cl-transforms:x hi)))
        (dolist (y (list (cl-transforms:y lo) (cl-transforms:y hi)))
          (dolist (z (list (cl-transforms:z lo) (cl-transforms:z hi)))
            (let ((p (cl-transforms:transform-point (cl-transforms:pose->transform pose)
                                                    (cl-transforms:make-3d-vector x y z))))
              (push (list (cl-transforms:x p) (cl-transforms:y p)) points)))))
      (convex-hull-2d points))))

(defun axis-aligned-p (corners tolerance)
  "True when the polygon CORNERS is a rectangle along the map's axes within TOLERANCE metres
\(a fraction of a costmap cell): its box in the map is as good as the polygon."
  (let ((x0 (reduce #'min corners :key #'first)) (x1 (reduce #'max corners :key #'first))
        (y0 (reduce #'min corners :key #'second)) (y1 (reduce #'max corners :key #'second)))
    (every (lambda (c) (and (or (< (abs (- (first c) x0)) tolerance)
                                (< (abs (- (first c) x1)) tolerance))
                            (or (< (abs (- (second c) y0)) tolerance)
                                (< (abs (- (second c) y1)) tolerance))))
           corners)))

(defun link-top-function (env link margin)
  "A cost function that is 1 on the top of the link LINK (a name) of ENV shrunk by MARGIN on
every side (at least its centre lines), 0 elsewhere: the link's own box as it stands, so that
on a table turned about the vertical no place lies beyond its edge (its box in the map reaches
past the edges). For a link along the map's axes, its box in the map, as before."
  (let* ((index (position link (btr:link-names env) :test #'string=))
         (corners (link-footprint env index link)))
    (multiple-value-bind (lo hi) (btr:aabb env index)
      (if (axis-aligned-p corners 0.005d0)
          (shrunk-box-function lo hi margin)
          (multiple-value-bind (llo lhi) (btr:local-aabb env index)
            (let* ((pose (btr:link-pose env link))
                   (axis (cl-transforms:rotate (cl-transforms:orientation pose)
                                               (cl-transforms:make-3d-vector 1 0 0)))
                   (yaw (atan (cl-transforms:y axis) (cl-transforms:x axis)))
                   (c (float (cos yaw) 1d0)) (s (float (sin yaw) 1d0))
                   (ox (float (cl-transforms:x (cl-transforms:origin pose)) 1d0))
                   (oy (float (cl-transforms:y (cl-transforms:origin pose)) 1d0))
                   (mx (/ (+ (cl-transforms:x llo) (cl-transforms:x lhi)) 2))
                   (my (/ (+ (cl-transforms:y llo) (cl-transforms:y lhi)) 2))
                   (x0 (float (min mx (+ (cl-transforms:x llo) margin)) 1d0))
                   (x1 (float (max mx (- (cl-transforms:x lhi) margin)) 1d0))
                   (y0 (float (min my (+ (cl-transforms:y llo) margin)) 1d0))
                   (y1 (float (max my (- (cl-transforms:y lhi) margin)) 1d0)))
              (declare (type double-float c s ox oy x0 x1 y0 y1))
              ;; the same arithmetic in doubles for a call and for the grid's cells
              (flet ((value (x y)
                       (declare (type double-float x y) (optimize speed))
                       (let* ((dx (- x ox)) (dy (- y oy))
                              (lx (+ (* c dx) (* s dy))) (ly (- (* c dy) (* s dx))))
                         (if (and (<= x0 lx x1) (<= y0 ly y1)) 1d0 0d0))))
                (declare (inline value))
                (make-cost-function
                 (lambda (x y) (value (float x 1d0) (float y 1d0)))
                 :name 'link-top
                 :bounds (list (cl-transforms:x lo) (cl-transforms:y lo)
                               (cl-transforms:x hi) (cl-transforms:y hi))
                 :grid-evaluator (cell-evaluator (x y) (value x y))))))))))

(defun polygon-runs (rows cols origin-x origin-y resolution corners padding)
  "The runs (as BOX-RUNS) of the cells of a grid of ROWS x COLS cells (cell (0 0) at ORIGIN)
whose centres are within PADDING of the convex polygon CORNERS ((x y) ..., counter-clockwise).
The cells near a convex polygon form one run in each row: its ends are found by testing cells
from the ends of the row inwards, the cells between are taken without a test."
  (declare (type fixnum rows cols) (type double-float origin-x origin-y resolution padding))
  (let* ((n (length corners))
         (ax (make-array n :element-type 'double-float))
         (ay (make-array n :element-type 'double-float))
         (ex (make-array n :element-type 'double-float))
         (ey (make-array n :element-type 'double-float))
         (xs (mapcar (lambda (c) (float (first c) 1d0)) corners))
         (ys (mapcar (lambda (c) (float (second c) 1d0)) corners))
         (c0 (max 0 (cell-index (/ (- (reduce #'min xs) padding origin-x) resolution))))
         (c1 (min (1- cols) (cell-index (/ (- (+ (reduce #'max xs) padding) origin-x) resolution))))
         (r0 (max 0 (cell-index (/ (- (reduce #'min ys) padding origin-y) resolution))))
         (r1 (min (1- rows) (cell-index (/ (- (+ (reduce #'max ys) padding) origin-y) resolution))))
         (p2 (* padding padding))
         (runs (make-array (* 3 (max 0 (1+ (- r1 r0)))) :element-type 'fixnum))
         (k 0))
    (declare (type (simple-array double-float (*)) ax ay ex ey) (type fixnum n c0 c1 r0 r1 k)
             (type double-float p2))
    (loop for (a . rest) on corners
          for b = (or (first rest) (first corners))
          for i from 0
          do (setf (aref ax i) (float (first a) 1d0) (aref ay i) (float (second a) 1d0)
                   (aref ex i) (- (float (first b) 1d0) (aref ax i))
                   (aref ey i) (- (float (second b) 1d0) (aref ay i))))
    (flet ((near-p (c y)
             (declare (type fixnum c) (type double-float y) (optimize speed))
             (let ((x (+ origin-x (* (+ c 0.5d0) resolution)))
                   (inside t) (best most-positive-double-float))
               (declare (type double-float x best))
               (dotimes (i n (or inside (<= best p2)))
                 (let* ((dx (- x (aref ax i))) (dy (- y (aref ay i)))
                        (vx (aref ex i)) (vy (aref ey i))
                        (len2 (+ (* vx vx) (* vy vy)))
                        (k (if (< len2 1d-18) 0d0
                               (max 0d0 (min 1d0 (/ (+ (* dx vx) (* dy vy)) len2)))))
                        (qx (- dx (* k vx))) (qy (- dy (* k vy))))
                   (when (< (- (* vx dy) (* vy dx)) 0d0) (setf inside nil))
                   (setf best (min best (+ (* qx qx) (* qy qy)))))))))
      (loop for r of-type fixnum from r0 to r1
            for y of-type double-float = (+ origin-y (* (+ r 0.5d0) resolution))
            do (let ((a c0) (b c1))
                 (declare (type fixnum a b))
                 (loop while (and (<= a c1) (not (near-p a y))) do (incf a))
                 (when (<= a c1)
                   (loop while (and (> b a) (not (near-p b y))) do (decf b))
                   (setf (aref runs k) r (aref runs (+ k 1)) a (aref runs (+ k 2)) b)
                   (incf k 3)))))
    (if (= k (length runs)) runs (subseq runs 0 k))))

(defun rasterise-polygon (bits origin-x origin-y resolution corners padding)
  "Mark the cells of BITS whose centres are within PADDING of the convex polygon CORNERS
\((x y) ..., counter-clockwise; POLYGON-RUNS)."
  (declare (type (simple-array bit (* *)) bits))
  (apply-runs bits (polygon-runs (array-dimension bits 0) (array-dimension bits 1)
                                 origin-x origin-y resolution corners padding)))

;;; The runs of an environment's links are kept between grids: a link that stands where it
;;; stood for an earlier grid of the same geometry is not rasterised again. The links that have
;;; never moved (the furniture's bodies, its shelves and boards) are kept together in one bit
;;; array, so that a new grid (a drawer opened) costs or'ing it in and the runs of the links that
;;; have moved, not a pass over every link.

(defvar *link-runs-cache* '()
  "The runs of the links of recently rasterised environments (ENVIRONMENT-OCCUPANCY-GRID): a
list of (key . LINK-RUNS-RECORD), the most recently used first. KEY: the environment object, its
URDF and the grid's geometry, padding and heights.")

(defstruct (link-runs-record (:constructor make-link-runs-record (links moved)))
  "What *LINK-RUNS-CACHE* keeps of one environment and grid geometry. LINKS: a vector with per
link index a list of up to *LINK-POSES-KEPT* entries (pose . runs), the most recently used
first: the link's map pose (7 doubles) and its runs there. MOVED: a bit per link, 1 once the
link has stood at a second pose. STILL: the cells of the links that have not (their only
entry's runs), NIL until made again after a link moved."
  links moved (still nil))

(defparameter *link-poses-kept* 4
  "How many poses of one link *LINK-RUNS-CACHE* keeps the runs of: a drawer or door that is
opened and closed again comes back to a pose whose runs are known.")

(defparameter *link-runs-cache-size* 8
  "How many environments and grid geometries *LINK-RUNS-CACHE* keeps (a household run asks for
two paddings of one kitchen).")

(defun link-runs-entry (key link-count)
  "The LINK-RUNS-RECORD of *LINK-RUNS-CACHE* under KEY (made empty when there is none), moved to
the front."
  (let ((entry (recent-entry '*link-runs-cache* key #'equal)))
    (if entry
        (cdr entry)
        (add-recent-entry '*link-runs-cache* key
                          (make-link-runs-record (make-array link-count :initial-element nil)
                                                 (make-array link-count :element-type 'bit
                                                                        :initial-element 0))
                          *link-runs-cache-size*))))

(defun same-pose-p (poses index pose)
  "True when the 7 doubles of link INDEX in POSES (ROBOT-LINK-POSES) are those of POSE."
  (declare (type (simple-array double-float (*)) poses pose) (type fixnum index))
  (loop for k of-type fixnum from 0 below 7
        always (= (aref poses (+ (* 7 index) k)) (aref pose k))))

(defun link-runs (env index name aabbs rows cols origin-x origin-y resolution padding z-min z-max)
  "The runs of the cells that link INDEX (named NAME) of ENV occupies, within PADDING of the
outline of its own box as it stands (LINK-FOOTPRINT), or none when its box (in AABBS, 6 per
link) lies outside Z-MIN .. Z-MAX or is flat."
  (declare (type (simple-array double-float (*)) aabbs))
  (let ((k (* 6 index)))
    (if (and (> (- (aref aabbs (+ k 3)) (aref aabbs k)) 1d-6)
             (> (- (aref aabbs (+ k 4)) (aref aabbs (+ k 1))) 1d-6)
             (> (aref aabbs (+ k 5)) z-min)
             (< (aref aabbs (+ k 2)) z-max))
        ;; the link's own box turned as it stands (a table turned by a few degrees would block
        ;; a larger box around it)
        (let ((corners (link-footprint env index name)))
          (if (and (>= (length corners) 3)
                   (not (axis-aligned-p corners (* 0.25d0 resolution))))
              (polygon-runs rows cols origin-x origin-y resolution corners padding)
              (box-runs rows cols origin-x origin-y resolution
                        (aref aabbs k) (aref aabbs (+ k 1)) (aref aabbs (+ k 3)) (aref aabbs (+ k 4))
                        padding)))
        (make-array 0 :element-type 'fixnum))))

(defun rasterise-environment (bits env key origin-x origin-y resolution padding z-min z-max)
  "Mark in BITS the cells the links of ENV occupy (LINK-RUNS). Of *LINK-RUNS-CACHE*'s record
under KEY: the cells of the links that have never moved are marked at once (one bit array kept
for them), and a link that stands where it stood for one of the last grids is not rasterised
again."
  (declare (type (simple-array bit (* *)) bits))
  (let* ((handle (btr:object-handle env))
         (world (btr::whandle env))
         (poses (cram-native:robot-link-poses world handle))
         (names (coerce (btr:link-names env) 'simple-vector))
         (record (link-runs-entry key (length names)))
         (links (link-runs-record-links record))
         (moved (link-runs-record-moved record))
         (aabbs nil)
         (rows (array-dimension bits 0)) (cols (array-dimension bits 1)))
    (declare (type simple-bit-vector moved))
    (flet ((runs-here (i)
             ;; the runs of link I where it stands now: kept ones, else found and kept
             (let* ((entries (aref links i))
                    (known (find-if (lambda (entry) (same-pose-p poses i (car entry))) entries)))
               (cond ((and known (eq known (first entries))) (cdr known))
                     (known (setf (aref links i) (cons known (remove known entries :test #'eq)))
                            (cdr known))
                     (t (let ((runs (link-runs env i (svref names i)
                                               (or aabbs (setf aabbs (btr:link-aabbs env)))
                                               rows cols origin-x origin-y resolution padding
                                               (float z-min 1d0) (float z-max 1d0))))
                          (push (cons (subseq poses (* 7 i) (* 7 (1+ i))) runs) (aref links i))
                          (when (> (length (aref links i)) *link-poses-kept*)
                            (setf (aref links i) (subseq (aref links i) 0 *link-poses-kept*)))
                          runs))))))
      ;; a link seen before that stands elsewhere now has moved
      (dotimes (i (length names))
        (let ((entries (aref links i)))
          (when (and (zerop (sbit moved i)) entries (not (same-pose-p poses i (car (first entries)))))
            (setf (sbit moved i) 1
                  (link-runs-record-still record) nil))))
      ;; the links that have not moved: their cells made once, then or'ed in
      (let ((still (link-runs-record-still record)))
        (unless (and still (equal (array-dimensions still) (array-dimensions bits)))
          (setf still (make-array (array-dimensions bits) :element-type 'bit :initial-element 0))
          (dotimes (i (length names))
            (when (zerop (sbit moved i)) (apply-runs still (runs-here i))))
          (setf (link-runs-record-still record) still))
        (bit-ior bits still bits))
      (dotimes (i (length names) bits)
        (when (= 1 (sbit moved i)) (apply-runs bits (runs-here i)))))))

(defun environment-occupancy-grid (&key (world btr:*current-bullet-world*) (padding 0d0)
                                        width height origin-x origin-y resolution
                                        (z-min *occupancy-z-min*) (z-max *occupancy-z-max*))
  "The occupancy grid of the static geometry of WORLD: every link of every environment
(articulated object other than the robot) whose bounding box reaches between Z-MIN and Z-MAX
occupies the cells within PADDING metres of the outline of its own box as it stands
\(LINK-FOOTPRINT).  The grid geometry defaults to the costmap
metadata.  Grids are cached per environment pose and joint state."
  (let* ((size (unless (and width height) (costmap-metadata-value 'costmap-size :arity 2)))
         (origin (unless (and origin-x origin-y) (costmap-metadata-value 'costmap-origin :arity 2)))
         (width (or width (first size))) (height (or height (second size)))
         (origin-x (coerce (or origin-x (first origin)) 'double-float))
         (origin-y (coerce (or origin-y (second origin)) 'double-float))
         (resolution (coerce (or resolution (costmap-metadata-value 'costmap-resolution)) 'double-float))
         (padding (progn (unless (and (realp padding) (<= 0 padding 100))
                           (error "ENVIRONMENT-OCCUPANCY-GRID: padding ~s, expected a real ~
                                   from 0 to 100 metres." padding))
                         (coerce padding 'double-float)))
         (environments (static-obstacles world))
         (geometry (list width height origin-x origin-y resolution padding z-min z-max))
         (key (append geometry
                      (mapcar (lambda (e) (list (btr:name e) (btr:urdf e) (vector-key (btr:pose e))
                                                (mapcar #'cdr (btr:joint-states e))))
                              environments)))
         (cached (recent-entry '*occupancy-cache* key #'equalp)))
    (if cached
        (cdr cached)
        (let* ((grid (make-occupancy-grid width height origin-x origin-y resolution))
               (bits (occupancy-bits grid)))
          (dolist (env environments)
            (rasterise-environment bits env (list* env (btr:urdf env) geometry)
                                   origin-x origin-y resolution padding z-min z-max))
          (add-recent-entry '*occupancy-cache* key grid *occupancy-cache-size*)))))

;;; ---- robot base poses in collision -------------------------------------------------------------------

(defun floor-object-p (object)
  (member :floor (btr:item-types object)))

(defun robot-pose-collisions (robot-name pose &key (world btr:*current-bullet-world*) in-place)
  "The names of the objects the robot ROBOT-NAME touches when it stands at POSE, checked in a
copy of WORLD (or, with IN-PLACE, in WORLD itself, which must then be a scratch copy); the floor
and the objects attached to the robot are left out."
  (let ((pose (if (typep pose 'cl-transforms-stamped:pose-stamped)
                  (cl-transforms-stamped:pose-stamped->pose pose)
                  pose)))
    (flet ((check (copy)
             (let ((robot (find-world-object robot-name copy)))
               (unless (and robot (btr:robot-object-p robot))
                 (error "There is no robot ~s in the belief state (objects: ~{~s~^ ~})."
                        robot-name (btr:object-names copy)))
               (setf (btr:pose robot) pose)
               (let ((attached (mapcar #'first (btr:attached-objects robot))))
                 (loop for name in (btr:find-objects-in-contact copy robot)
                       for object = (btr:object copy name)
                       unless (or (member name attached) (and object (floor-object-p object)))
                         collect name)))))
      (if in-place
          (check world)
          (btr:with-copied-world (world)
            (check btr:*current-bullet-world*))))))

(defun find-world-object (name &optional (world btr:*current-bullet-world*))
  "The object of WORLD called NAME, compared by symbol name (so :MUG-1 finds MUG-1), or NIL."
  (or (and (symbolp name) (btr:object world name))
      (let ((string (string name)))
        (find-if (lambda (o) (string-equal (symbol-name (btr:name o)) string))
                 (btr:objects world)))))
