;;;; The grid location costmap: cost functions that multiply, normalised sampling from a
;;;; seeded random state, orientation and height generators.

(in-package :cram-location-costmap)

;;; ---- random state --------------------------------------------------------------------------

(defvar *costmap-random-state* (sb-ext:seed-random-state 1)
  "The random state every costmap draws its own sampling seed from.  It is independent of
CL:*RANDOM-STATE*; reseed it with SEED-COSTMAPS to get the same samples again.")

(defun seed-costmaps (seed)
  "Reseed *COSTMAP-RANDOM-STATE* with the non-negative integer SEED, so that the costmaps
made from now on sample the same poses as after any earlier (SEED-COSTMAPS SEED)."
  (unless (typep seed '(integer 0))
    (error "SEED-COSTMAPS: the seed is ~s, expected a non-negative integer." seed))
  (setf *costmap-random-state* (sb-ext:seed-random-state seed))
  seed)

;;; Seeding a random state from a costmap's seed. SBCL seeds its MT19937 state from an integer
;;; wider than 32 bits with the generator's reference key initialisation (init_by_array over
;;; the integer's 32-bit words), written with generic arithmetic: about 40 microseconds and
;;; 15 kB of garbage per state, and a household run seeds about a hundred. SEEDED-RANDOM-STATE
;;; computes the same state with 32-bit arithmetic (10 microseconds, the 2.5 kB of the state);
;;; it is used only when it gives SBCL's states for a set of test seeds (checked once, at load
;;; time), else SBCL's own seeding is.

(deftype mt-word () '(unsigned-byte 32))

(defun mt-state-from-key (key)
  "The MT19937 state vector (627 words: 0, the matrix constant, the index 624, then the 624
words of the state) that the reference key initialisation makes from KEY, a vector of 32-bit
words."
  (declare (type (simple-array mt-word (*)) key) (optimize speed (safety 0)))
  (let ((s (make-array 627 :element-type 'mt-word)) (n 624) (l (length key)))
    (declare (type (simple-array mt-word (627)) s) (type (integer 1 1000000) l))
    (macrolet ((mix (x) `(logxor ,x (ash ,x -30)))
               (word (x) `(ldb (byte 32 0) ,x)))
      (setf (aref s 0) 0 (aref s 1) #x9908B0DF (aref s 2) n (aref s 3) 19650218)
      (loop for i of-type (integer 1 624) from 1 below n
            do (setf (aref s (+ i 3)) (word (+ (* 1812433253 (mix (aref s (+ i 2)))) i))))
      (let ((i 1) (j 0))
        (declare (type (integer 0 1000000) i j))
        (flet ((advance ()
                 (incf i)
                 (when (>= i n) (setf (aref s 3) (aref s (+ n 2)) i 1))))
          (loop repeat (max n l)
                do (setf (aref s (+ i 3))
                         (word (+ (logxor (aref s (+ i 3)) (word (* (mix (aref s (+ i 2))) 1664525)))
                                  (aref key j) j)))
                   (advance)
                   (incf j)
                   (when (>= j l) (setf j 0)))
          (loop repeat (1- n)
                do (setf (aref s (+ i 3))
                         (word (- (logxor (aref s (+ i 3)) (word (* (mix (aref s (+ i 2))) 1566083941)))
                                  i)))
                   (advance))))
      (setf (aref s 3) #x80000000))
    s))

(defun key-words (seed)
  "The non-negative integer SEED as 32-bit words, least significant first."
  (let* ((n (ceiling (integer-length seed) 32))
         (key (make-array n :element-type 'mt-word)))
    (dotimes (i n key) (setf (aref key i) (ldb (byte 32 (* 32 i)) seed)))))

(defun key-seeded-state (seed)
  "A random state made from SEED (wider than 32 bits) by MT-STATE-FROM-KEY."
  (sb-kernel::%make-random-state (mt-state-from-key (key-words seed))))

(defvar *key-seeding-p*
  (ignore-errors
   (every (lambda (seed)
            (equalp (sb-kernel::random-state-state (key-seeded-state seed))
                    (sb-kernel::random-state-state (sb-ext:seed-random-state seed))))
          (list (expt 2 32) 123456789012345 (1- (expt 2 62)) (expt 3 80))))
  "True when KEY-SEEDED-STATE makes the states SBCL's SEED-RANDOM-STATE makes (checked at load).")

(defun seeded-random-state (seed)
  "A random state seeded with the non-negative integer SEED, the same as
\(SB-EXT:SEED-RANDOM-STATE SEED) makes."
  (if (and *key-seeding-p* (> seed #xFFFFFFFF))
      (key-seeded-state seed)
      (sb-ext:seed-random-state seed)))

(defun finite-real-p (x)
  "True for a real that is neither NaN nor an infinity (test this before comparing X: a
comparison with NaN traps)."
  (and (realp x)
       (not (and (floatp x) (or (sb-ext:float-nan-p x) (sb-ext:float-infinity-p x))))))

(defun to-double (x)
  "The real X as a double-float; single-floats by their shortest decimal value, so that 0.1
becomes 0.1d0 rather than 0.10000000149011612d0."
  (if (typep x 'single-float) (float (rationalize x) 1d0) (float x 1d0)))

;;; ---- conditions ------------------------------------------------------------------------------

(define-condition invalid-probability-distribution (error)
  ((costmap :initarg :costmap :initform nil :reader invalid-distribution-costmap)
   (reason :initarg :reason :reader invalid-distribution-reason))
  (:report (lambda (c s)
             (format s "The location costmap ~a is not a probability distribution: ~a"
                     (invalid-distribution-costmap c) (invalid-distribution-reason c))))
  (:documentation "Signalled when a costmap cannot be sampled: every cell is zero, or a cost
function produced a negative or non-finite value."))

;;; ---- metadata ---------------------------------------------------------------------------------

(defparameter *metadata-variables* '(?v0 ?v1 ?v2 ?v3)
  "The variables of the metadata queries: ?V0 for the first value, and so on.")

(defun metadata-variables (arity)
  (if (<= arity (length *metadata-variables*))
      (subseq *metadata-variables* 0 arity)
      (loop for i below arity collect (intern (format nil "?V~d" i) :cram-location-costmap))))

(defvar *metadata-answers* (make-hash-table :test 'equal :synchronized t)
  "(predicate arity robot-name) -> (generation . values): the first answers of metadata
predicates that come from facts (METADATA-FROM-FACTS-P); :NONE for no answer.")

(defun metadata-answer (predicate arity)
  "The values of the first solution of (PREDICATE ?V0 ...) with ARITY variables, or :NONE;
kept while the answer comes from facts and the database and the current robot are the same."
  (flet ((ask ()
           (let* ((vars (metadata-variables arity))
                  (solution (cut:lazy-car (prolog `(,predicate ,@vars)))))
             (if solution (mapcar (lambda (v) (cut:var-value v solution)) vars) :none))))
    (if (or *reading-user-metadata* (not (metadata-from-facts-p predicate)))
        (ask)
        (let* ((key (list predicate arity rob-int:*robot-name*))
               (generation (prolog:database-generation))
               (cached (gethash key *metadata-answers*)))
          (if (and cached (eql (car cached) generation))
              (cdr cached)
              (let ((values (ask)))
                (setf (gethash key *metadata-answers*) (cons generation values))
                values))))))

(defun costmap-metadata-value (predicate &key (arity 1) (default nil default-p))
  "The first solution of the metadata PREDICATE (a symbol such as COSTMAP-PADDING) as one
value, or as a list of ARITY values when ARITY > 1.  Without a solution, DEFAULT when given,
else an error naming the predicate.  An answer that comes from facts is kept until the Prolog
database or the current robot change (METADATA-FROM-FACTS-P)."
  (let ((values (metadata-answer predicate arity)))
    (cond ((listp values)
           (dolist (v values)
             (unless (realp v)
               (error "Costmap metadata (~(~a~) ...) gave ~s, expected real numbers."
                      predicate values)))
           (if (= arity 1) (first values) (copy-list values)))
          (default-p default)
          (t (error "No costmap metadata (~(~a~)~{ ~a~}): declare it for the robot ~s, e.g. ~
                     (def-fact-group my-metadata (costmap:~(~a~)) (<- (costmap:~(~:*~a~) ...)))."
                    predicate (metadata-variables arity) rob-int:*robot-name* predicate)))))

;;; ---- cost functions ----------------------------------------------------------------------------

(defclass cost-function ()
  ((name :initarg :name :initform nil :reader cost-function-name
         :documentation "A symbol naming the function, for errors and pictures.")
   (bounds :initarg :bounds :initform nil :reader cost-function-bounds
           :documentation "NIL, or (x-min y-min x-max y-max) outside which the value is 0.")
   (grid-evaluator :initarg :grid-evaluator :initform nil :reader cost-function-grid-evaluator
                   :documentation "NIL, or a function (costmap window row-0 row-1 col-0 col-1)
that multiplies the cells of the costmap in rows ROW-0..ROW-1 and columns COL-0..COL-1 (end
exclusive) by the function's values at their centres; WINDOW holds those cells only, the cell
\(row column) at (- row row-0) (- column col-0).")
   (cell-test :initarg :cell-test :initform nil :reader cost-function-cell-test
              :documentation "NIL, or for a function whose values are 0 and 1 only a function
\(costmap row column) true where its value at the cell is 1: samples are drawn without the
function and a drawn cell where it is 0 is drawn again (DRAW-SAMPLE-CELL)."))
  (:metaclass sb-mop:funcallable-standard-class)
  (:documentation "A cost function (x y) -> non-negative real that may know where it is zero
(its bounds) and how to fill a whole grid quickly.  Plain functions (x y) work as well."))

(defun make-cost-function (function &key name bounds grid-evaluator cell-test)
  "A COST-FUNCTION calling FUNCTION (x y); BOUNDS (x-min y-min x-max y-max) tells where it can
be non-zero, GRID-EVALUATOR (costmap window row-0 row-1 col-0 col-1) multiplies the block of
cells rows ROW-0..ROW-1, columns COL-0..COL-1 (end exclusive), which WINDOW holds with the
cell (row column) at (- row row-0) (- column col-0), by the function's values (a cell that is
0 may be left alone). CELL-TEST (costmap row column), for a FUNCTION whose values are 0 and
1 only, is true where its value at the cell is 1, as the grid evaluator finds it: samples are
then drawn without FUNCTION and tested at the cells drawn, so that FUNCTION is evaluated only
there (the samples follow the same distribution)."
  (unless (functionp function)
    (error "MAKE-COST-FUNCTION: expected a function of (x y), got ~s." function))
  (when bounds
    (unless (and (listp bounds) (= (length bounds) 4) (every #'realp bounds))
      (error "MAKE-COST-FUNCTION: bounds ~s, expected (x-min y-min x-max y-max)." bounds)))
  (when cell-test
    (unless (functionp cell-test)
      (error "MAKE-COST-FUNCTION: cell test ~s, expected a function (costmap row column)."
             cell-test)))
  (let ((f (make-instance 'cost-function :name name :bounds bounds
                                         :grid-evaluator grid-evaluator :cell-test cell-test)))
    (sb-mop:set-funcallable-instance-function f function)
    f))

(defmethod print-object ((f cost-function) stream)
  (print-unreadable-object (f stream :type t :identity t)
    (format stream "~@[~s~]" (cost-function-name f))))

;;; ---- the costmap -----------------------------------------------------------------------------

(defclass location-costmap ()
  ((origin-x :initarg :origin-x :reader origin-x
             :documentation "Map x of the corner of cell (0 0).")
   (origin-y :initarg :origin-y :reader origin-y
             :documentation "Map y of the corner of cell (0 0).")
   (resolution :initarg :resolution :reader resolution
               :documentation "Cell size in metres.")
   (width :initarg :width :reader width :documentation "Extent along x in metres.")
   (height :initarg :height :reader height :documentation "Extent along y in metres.")
   (columns :reader costmap-columns) (rows :reader costmap-rows)
   (cost-functions :initform '() :initarg :cost-functions :accessor cost-functions
                   :documentation "Entries (name function score), applied by ascending score.")
   (orientation-generators :initform '() :initarg :orientation-generators
                           :accessor orientation-generators)
   (orientation-orderings :initform '() :accessor orientation-orderings
                          :documentation "Functions (x y orientations) that put the orientations
the generators made in another order (REGISTER-ORIENTATION-ORDERING).")
   (height-generators :initform '() :initarg :height-generators :accessor height-generators)
   (window :initform nil :accessor %window
           :documentation "NIL, or the values of the cells of REGION (COST-WINDOW).")
   (sampling-window :initform nil :accessor %sampling-window
                    :documentation "NIL, or the values of the cells of REGION without the cost
functions that samples test (SAMPLING-WINDOW).")
   (sampling-distribution :initform nil :accessor %sampling-distribution
                          :documentation "NIL, or the distribution samples are drawn from.")
   (exact-sampling :initform nil :accessor %exact-sampling
                   :documentation "True once samples are drawn from COST-WINDOW's values, as
when too many drawn cells failed their tests in a row (DRAW-SAMPLE-CELL).")
   (matrix :initform nil :accessor %matrix
           :documentation "NIL, or the values of all cells (COST-GRID), made when asked for.")
   (total :initform nil :accessor %total
          :documentation "NIL, or the sum of the cells in row-major order (COSTMAP-TOTAL).")
   (normalized :initform nil :accessor %normalized
               :documentation "NIL, or the normalised copy of the grid for GET-COST-MAP.")
   (region :initform nil :accessor %region
           :documentation "(row-0 row-1 col-0 col-1) outside which the grid is 0.")
   (distribution :initform nil :accessor %distribution)
   (random-state :initarg :random-state :accessor %random-state
                 :documentation "The costmap's random state, or until it is first asked for
\(COSTMAP-RANDOM-STATE) the integer it is seeded with: seeding one takes longer than building
most costmaps, and many are merged or only counted and never sampled."))
  (:documentation "A grid over the map whose cell values are the product of the registered
cost functions; samples are poses drawn with probability proportional to the cell values."))

(defun costmap-random-state (costmap)
  "The random state COSTMAP samples with, seeded from its seed the first time it is asked for."
  (let ((state (%random-state costmap)))
    (if (integerp state)
        (setf (%random-state costmap) (seeded-random-state state))
        state)))

(defmethod print-object ((c location-costmap) stream)
  (print-unreadable-object (c stream :type t :identity t)
    (format stream "~dx~d cells of ~,3f m~@[ ~{~(~a~)~^*~}~]" (costmap-columns c) (costmap-rows c)
            (resolution c) (mapcar #'first (cost-functions c)))))

(defun make-location-costmap (&key width height resolution origin-x origin-y)
  "A new, empty location costmap.  Every key left out comes from the metadata predicates
COSTMAP-SIZE, COSTMAP-RESOLUTION and COSTMAP-ORIGIN of the current robot.  (MAKE-INSTANCE
'LOCATION-COSTMAP ...) with CRAM's initargs :WIDTH :HEIGHT :RESOLUTION :ORIGIN-X :ORIGIN-Y
:COST-FUNCTIONS :HEIGHT-GENERATORS :ORIENTATION-GENERATORS makes the same costmap.)"
  (make-instance 'location-costmap :width width :height height :resolution resolution
                                   :origin-x origin-x :origin-y origin-y))

(defun check-generator-list (list what)
  (unless (and (listp list)
               (every (lambda (g) (or (functionp g) (and (symbolp g) g (fboundp g)))) list))
    (error "LOCATION-COSTMAP: the ~a ~s are not a list of functions." what list)))

(defmethod initialize-instance :after ((c location-costmap) &key)
  (flet ((given (slot) (and (slot-boundp c slot) (slot-value c slot))))
    (let* ((size (unless (and (given 'width) (given 'height))
                   (costmap-metadata-value 'costmap-size :arity 2)))
           (origin (unless (and (given 'origin-x) (given 'origin-y))
                     (costmap-metadata-value 'costmap-origin :arity 2)))
           (width (or (given 'width) (first size)))
           (height (or (given 'height) (second size)))
           (resolution (or (given 'resolution) (costmap-metadata-value 'costmap-resolution)))
           (origin-x (or (given 'origin-x) (first origin)))
           (origin-y (or (given 'origin-y) (second origin))))
      (loop for (what value) in `(("width" ,width) ("height" ,height) ("resolution" ,resolution))
            unless (and (finite-real-p value) (> value 0) (< value 1d4))
              do (error "MAKE-LOCATION-COSTMAP: the ~a is ~s, expected a positive real (metres)."
                        what value))
      (loop for (what value) in `(("origin x" ,origin-x) ("origin y" ,origin-y))
            unless (and (finite-real-p value) (< (abs value) 1d6))
              do (error "MAKE-LOCATION-COSTMAP: the ~a is ~s, expected a finite real." what value))
      (when (> (/ (* width height) (* resolution resolution)) 2.5d7)
        (error "MAKE-LOCATION-COSTMAP: ~s x ~s m at ~s m resolution is more than 25 million ~
                cells; use a coarser resolution." width height resolution))
      (setf (slot-value c 'width) width
            (slot-value c 'height) height
            (slot-value c 'resolution) (to-double resolution)
            (slot-value c 'origin-x) (to-double origin-x)
            (slot-value c 'origin-y) (to-double origin-y))))
  (let ((entries (cost-functions c)))
    (unless (and (listp entries)
                 (every (lambda (e) (and (consp e) (consp (cdr e))
                                         (or (functionp (second e))
                                             (and (symbolp (second e)) (second e)
                                                  (fboundp (second e))))))
                        entries))
      (error "LOCATION-COSTMAP: the cost functions ~s are not a list of entries (name function ~
              [score]) as COST-FUNCTIONS of another costmap gives." entries))
    (setf (cost-functions c) '())
    (loop for (name function . score) in entries
          do (if score
                 (register-cost-function c function name (first score))
                 (register-cost-function c function name))))
  (check-generator-list (orientation-generators c) "orientation generators")
  (check-generator-list (height-generators c) "height generators")
  (unless (slot-boundp c 'random-state)
    (setf (slot-value c 'random-state) (random (expt 2 62) *costmap-random-state*)))
  (unless (or (random-state-p (slot-value c 'random-state))
              (typep (slot-value c 'random-state) '(integer 0)))
    (error "LOCATION-COSTMAP: the random state ~s, expected a random state or a non-negative ~
            integer to seed one with." (slot-value c 'random-state)))
  (setf (slot-value c 'columns) (max 1 (round (to-double (width c)) (resolution c)))
        (slot-value c 'rows) (max 1 (round (to-double (height c)) (resolution c)))))

(declaim (inline cell-center))
(defun cell-center (origin resolution index)
  "ORIGIN + (INDEX + 0.5) RESOLUTION: in doubles when ORIGIN and RESOLUTION are (as the
costmap keeps them), else as the reals they are."
  ;; the same sum twice: in the first branch the compiler knows the types and adds doubles
  (if (and (typep origin 'double-float) (typep resolution 'double-float) (typep index 'fixnum))
      (+ origin (* (+ index 0.5d0) resolution))
      (+ origin (* (+ index 0.5d0) resolution))))

(defun cell-center-x (costmap column)
  "The map x of the centre of the cells in COLUMN."
  (cell-center (origin-x costmap) (resolution costmap) column))

(defun cell-center-y (costmap row)
  "The map y of the centre of the cells in ROW."
  (cell-center (origin-y costmap) (resolution costmap) row))

(defun invalidate-costmap (costmap)
  (setf (%window costmap) nil (%matrix costmap) nil (%total costmap) nil
        (%distribution costmap) nil (%region costmap) nil (%normalized costmap) nil
        (%sampling-window costmap) nil (%sampling-distribution costmap) nil
        (%exact-sampling costmap) nil)
  costmap)

(defgeneric costmap-generator-name->score (name)
  (:documentation "The score that orders the cost function registered under NAME: functions
with smaller scores are applied first.  Specialise it with (eql name) methods.")
  (:method ((name t)) 10))

(defun check-cost-function (function what)
  (unless (or (functionp function) (and (symbolp function) (fboundp function)))
    (error "~a: expected a function or a function name, got ~s." what function)))

(defun register-cost-function (costmap function name &optional (score (costmap-generator-name->score name)))
  "Add FUNCTION, a function (x y) -> non-negative real or a COST-FUNCTION, to COSTMAP under
NAME.  The costmap's value is the product of all functions, applied in order of SCORE."
  (unless (typep costmap 'location-costmap)
    (error "REGISTER-COST-FUNCTION: expected a location costmap, got ~s." costmap))
  (check-cost-function function "REGISTER-COST-FUNCTION")
  (unless (realp score)
    (error "REGISTER-COST-FUNCTION: score ~s of ~s, expected a real number." score name))
  (setf (cost-functions costmap)
        (stable-sort (append (cost-functions costmap)
                             (list (list name (if (symbolp function) (fdefinition function) function)
                                         score)))
                     #'< :key #'third))
  (invalidate-costmap costmap))

(defun register-orientation-generator (costmap generator)
  "Add GENERATOR, a function (x y previous-orientations) returning a list of quaternions, to
COSTMAP.  Generators run in registration order, each given the previous one's result (the
first is given the identity rotation)."
  (check-cost-function generator "REGISTER-ORIENTATION-GENERATOR")
  (setf (orientation-generators costmap) (append (orientation-generators costmap) (list generator)))
  costmap)

(defun register-orientation-ordering (costmap ordering)
  "Add ORDERING, a function (x y orientations) returning the same ORIENTATIONS (a list of
quaternions) in the order the samples at (X Y) should come in, to COSTMAP. Orderings run after
all orientation generators, in registration order: a costmap merged with others orders the
orientations that all of them made (e.g. the quarter turns of a place on a surface, best first
for the robot that puts an object down there)."
  (check-cost-function ordering "REGISTER-ORIENTATION-ORDERING")
  (setf (orientation-orderings costmap) (append (orientation-orderings costmap) (list ordering)))
  costmap)

(defun register-height-generator (costmap generator)
  "Add GENERATOR, a function (x y) returning a list of heights (z in metres), to COSTMAP.  The
first registered generator gives the heights of the samples (default: 0)."
  (check-cost-function generator "REGISTER-HEIGHT-GENERATOR")
  (setf (height-generators costmap) (append (height-generators costmap) (list generator)))
  costmap)

(defun merge-costmaps (&rest costmaps)
  "A new costmap on the grid of the first of COSTMAPS with the cost functions, orientation and
height generators of all of them."
  (let ((costmaps (remove nil (if (and (= (length costmaps) 1) (listp (first costmaps)))
                                  (first costmaps) costmaps))))
    (when (null costmaps) (error "MERGE-COSTMAPS: no costmap given."))
    (dolist (c costmaps)
      (unless (typep c 'location-costmap)
        (error "MERGE-COSTMAPS: expected location costmaps, got ~s." c)))
    (if (= (length costmaps) 1)
        (first costmaps)
        (let* ((first (first costmaps))
               (merged (make-instance 'location-costmap
                                      :width (width first) :height (height first)
                                      :resolution (resolution first)
                                      :origin-x (origin-x first) :origin-y (origin-y first)
                                      :cost-functions '()
                                      :random-state (let ((state (%random-state first)))
                                                      (if (integerp state)
                                                          state
                                                          (make-random-state state))))))
          (dolist (c costmaps merged)
            (loop for (name fn score) in (cost-functions c)
                  do (register-cost-function merged fn name score))
            (dolist (g (orientation-generators c)) (register-orientation-generator merged g))
            (dolist (o (orientation-orderings c)) (register-orientation-ordering merged o))
            (dolist (g (height-generators c)) (register-height-generator merged g)))))))

;;; ---- computing the grid -----------------------------------------------------------------------

(defun bounds->index-range (costmap bounds)
  "(values row-0 row-1 col-0 col-1), end exclusive, of the cells whose centres lie in BOUNDS."
  (let* ((res (resolution costmap)) (cols (costmap-columns costmap)) (rows (costmap-rows costmap)))
    (if (null bounds)
        (values 0 rows 0 cols)
        (destructuring-bind (x0 y0 x1 y1) bounds
          (flet ((lo (v origin n) (max 0 (min n (ceiling (- (/ (- v origin) res) 0.5d0)))))
                 (hi (v origin n) (max 0 (min n (1+ (floor (- (/ (- v origin) res) 0.5d0)))))))
            (values (lo y0 (origin-y costmap) rows) (hi y1 (origin-y costmap) rows)
                    (lo x0 (origin-x costmap) cols) (hi x1 (origin-x costmap) cols)))))))

(defun intersect-bounds (a b)
  (cond ((null a) b) ((null b) a)
        (t (list (max (first a) (first b)) (max (second a) (second b))
                 (min (third a) (third b)) (min (fourth a) (fourth b))))))

(defun costmap-support-bounds (costmap)
  (reduce #'intersect-bounds
          (mapcar (lambda (e) (and (typep (second e) 'cost-function)
                                   (cost-function-bounds (second e))))
                  (cost-functions costmap))
          :initial-value nil))

(defun check-cell-value (costmap name value x y)
  (unless (and (finite-real-p value) (>= value 0))
    (error 'invalid-probability-distribution
           :costmap costmap
           :reason (format nil "the cost function ~(~a~) gave ~s at (~,3f ~,3f), expected a ~
                                finite non-negative real." name value x y))))

(defun multiply-by-function (costmap window name function r0 r1 c0 c1)
  "Multiply the non-zero cells of the costmap in rows R0..R1 and columns C0..C1 (end
exclusive), which WINDOW holds from cell (R0 C0) on, by FUNCTION (x y) at their centres."
  (declare (type (simple-array double-float (* *)) window) (type fixnum r0 r1 c0 c1)
           (type function function))
  (let ((xs (make-array (max 0 (- c1 c0)) :element-type 'double-float)))
    (loop for c from c0 below c1 do (setf (aref xs (- c c0)) (cell-center-x costmap c)))
    (loop for r of-type fixnum from r0 below r1
          for wr of-type fixnum from 0
          for y of-type double-float = (cell-center-y costmap r)
          do (loop for wc of-type fixnum from 0 below (- c1 c0)
                   when (> (aref window wr wc) 0d0)
                     do (let* ((x (aref xs wc))
                               (v (funcall function x y)))
                          (unless (typep v 'double-float)
                            (check-cell-value costmap name v x y)
                            (setf v (coerce v 'double-float)))
                          (locally (declare (type double-float v))
                            (unless (and (not (sb-ext:float-nan-p v)) (>= v 0d0)
                                         (< v most-positive-double-float))
                              (check-cell-value costmap name v x y))
                            (setf (aref window wr wc) (* (aref window wr wc) v))))))))

(defun sampling-test-p (entry)
  "True when the cost function of ENTRY ((name function score)) has a cell test
\(MAKE-COST-FUNCTION :CELL-TEST): samples test it at the cells drawn instead of the grid."
  (let ((fn (second entry)))
    (and (typep fn 'cost-function) (cost-function-cell-test fn) t)))

(defun multiply-window (costmap window entries r0 r1 c0 c1)
  "Multiply WINDOW (the costmap's cells rows R0..R1, columns C0..C1) by the cost functions of
ENTRIES, in their order."
  (when (and (< r0 r1) (< c0 c1))
    (loop for (name fn) in entries
          for evaluator = (and (typep fn 'cost-function) (cost-function-grid-evaluator fn))
          do (if evaluator
                 (funcall evaluator costmap window r0 r1 c0 c1)
                 (multiply-by-function costmap window name fn r0 r1 c0 c1))))
  window)

(defun copy-window (window)
  "A fresh copy of the double-float matrix WINDOW."
  (declare (type (simple-array double-float (* *)) window))
  (let ((copy (make-array (array-dimensions window) :element-type 'double-float)))
    (replace (sb-ext:array-storage-vector copy) (sb-ext:array-storage-vector window))
    copy))

(defun fresh-window (costmap entries)
  "The window of the cells where all of COSTMAP's cost functions with bounds can be non-zero
\(its region, now kept in the costmap), each the product of the cost functions of ENTRIES."
  (multiple-value-bind (r0 r1 c0 c1) (bounds->index-range costmap (costmap-support-bounds costmap))
    (setf (%region costmap) (list r0 (max r0 r1) c0 (max c0 c1)))
    (multiply-window costmap (make-array (list (max 0 (- r1 r0)) (max 0 (- c1 c0)))
                                         :element-type 'double-float :initial-element 1d0)
                     entries r0 r1 c0 c1)))

(defun sampling-window (costmap)
  "(values window region) as COST-WINDOW, but without the cost functions that have a cell test
\(their values are 0 or 1): what samples are drawn from before they are tested. The same as
COST-WINDOW's when no function has one."
  (if (notany #'sampling-test-p (cost-functions costmap))
      (cost-window costmap)
      (progn
        (unless (%sampling-window costmap)
          (setf (%sampling-window costmap)
                (fresh-window costmap (remove-if #'sampling-test-p (cost-functions costmap)))))
        (values (%sampling-window costmap) (%region costmap)))))

(defun cost-window (costmap)
  "(values window region): the values of COSTMAP in the cells of REGION (row-0 row-1 col-0
col-1, end exclusive), outside which every value is 0: the cells where all cost functions
with bounds can be non-zero.  WINDOW is a (row-1 - row-0) x (col-1 - col-0) double-float array
whose cell (0 0) is the costmap's cell (row-0 col-0), each the product of the cost functions
at the cell's centre; computed once and kept until another function is registered."
  (unless (%window costmap)
    (let ((tested (remove-if-not #'sampling-test-p (cost-functions costmap))))
      (setf (%window costmap)
            (if tested
                ;; the functions with cell tests are 0 or 1: multiplied last, the products are
                ;; the same
                (multiple-value-bind (window region) (sampling-window costmap)
                  (destructuring-bind (r0 r1 c0 c1) region
                    (multiply-window costmap (copy-window window) tested r0 r1 c0 c1)))
                (fresh-window costmap (cost-functions costmap))))))
  (values (%window costmap) (%region costmap)))

(defun cost-grid (costmap)
  "The value grid of COSTMAP, not normalised: a (rows x columns) double-float array, row = y
index, column = x index, each cell the product of the cost functions at its centre (0 outside
the cells COST-WINDOW computes); made once and kept until another function is registered."
  (or (%matrix costmap)
      (multiple-value-bind (window region) (cost-window costmap)
        (declare (type (simple-array double-float (* *)) window))
        (let ((m (make-array (list (costmap-rows costmap) (costmap-columns costmap))
                             :element-type 'double-float :initial-element 0d0)))
          (destructuring-bind (r0 r1 c0 c1) region
            (loop for r from r0 below r1
                  do (loop for c from c0 below c1
                           do (setf (aref m r c) (aref window (- r r0) (- c c0))))))
          (setf (%matrix costmap) m)))))
