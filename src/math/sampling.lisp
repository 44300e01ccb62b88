;;;; Sampling from distributions with a seeded random state, and points in polygons.

(in-package :cram-math)

(define-condition invalid-probability-distribution (error)
  ((distribution :initarg :distribution :initform nil
                 :reader invalid-probability-distribution-distribution))
  (:report (lambda (c s)
             (format s "Not a probability distribution one can sample from: ~s."
                     (invalid-probability-distribution-distribution c))))
  (:documentation "The distribution given to a sampling function has no positive mass."))

(defvar *random-state-of-sampling* (sb-ext:seed-random-state 1)
  "The random state SAMPLE, SAMPLE-DISCRETE and SAMPLE-FROM-DISTRIBUTION-MATRIX draw from;
SEED-SAMPLING makes it afresh, so the same seed gives the same samples.")

(defun seed-sampling (seed)
  "Seed *RANDOM-STATE-OF-SAMPLING* with the integer SEED."
  (unless (typep seed '(integer 0))
    (error "SEED-SAMPLING: the seed ~s is not a non-negative integer." seed))
  (setf *random-state-of-sampling* (sb-ext:seed-random-state seed)))

(defun sample (var-fun p-fun &optional (max-retries 10000000))
  "Draw a variable by rejection sampling: VAR-FUN maps a number of [0, 1) to a candidate, P-FUN
gives the candidate's probability in [0, 1]; candidates are drawn until one is accepted (at
most MAX-RETRIES times, then an error)."
  (unless (typep max-retries '(integer 1))
    (error "SAMPLE: the number of retries ~s is not a positive integer." max-retries))
  (loop repeat max-retries
        do (let ((candidate (funcall var-fun (random 1d0 *random-state-of-sampling*))))
             (when (<= (random 1d0 *random-state-of-sampling*) (funcall p-fun candidate))
               (return-from sample candidate))))
  (error "SAMPLE: no candidate was accepted in ~d draws." max-retries))

(defun sample-discrete (var-probs)
  "Draw a variable from the discrete distribution VAR-PROBS, a list of (variable . probability)
with probabilities in [0, 1]."
  (unless (and (consp var-probs)
               (every (lambda (e) (and (consp e) (realp (cdr e)) (<= 0 (cdr e) 1))) var-probs))
    (error "SAMPLE-DISCRETE: ~s is not a non-empty list of (variable . probability) with ~
            probabilities in [0, 1]." var-probs))
  (when (every (lambda (e) (zerop (cdr e))) var-probs)
    (error 'invalid-probability-distribution :distribution var-probs))
  (let ((entries (coerce var-probs 'vector)))
    (car (sample (lambda (u) (aref entries (floor (* u (length entries)))))
                 #'cdr))))

(defun sample-from-distribution-matrix (matrix)
  "A cell (column row) of MATRIX drawn with probability proportional to its value (a
normalised matrix, e.g. a costmap's, is a distribution)."
  (check-matrix matrix 'sample-from-distribution-matrix)
  (let ((total (loop for i below (array-total-size matrix)
                     for v = (row-major-aref matrix i)
                     when (< v 0) do (error 'invalid-probability-distribution :distribution matrix)
                     sum v)))
    (unless (> total 0)
      (error 'invalid-probability-distribution :distribution matrix))
    (let ((r (random total *random-state-of-sampling*)) (sum 0d0))
      (dotimes (i (array-total-size matrix))
        (incf sum (row-major-aref matrix i))
        (when (> sum r)
          (multiple-value-bind (row column) (floor i (width matrix))
            (return-from sample-from-distribution-matrix (list column row)))))
      ;; rounding: the last cell with a value
      (let ((i (position-if #'plusp (make-array (array-total-size matrix) :element-type 'double-float
                                                                           :displaced-to matrix)
                            :from-end t)))
        (multiple-value-bind (row column) (floor i (width matrix))
          (list column row))))))

(defclass 2d-point ()
  ((x :initarg :x :reader x) (y :initarg :y :reader y))
  (:documentation "A point in the plane."))

(defmethod initialize-instance :after ((p 2d-point) &key)
  (unless (and (slot-boundp p 'x) (slot-boundp p 'y) (realp (x p)) (realp (y p)))
    (error "2D-POINT: expected real :X and :Y, got ~s and ~s."
           (and (slot-boundp p 'x) (x p)) (and (slot-boundp p 'y) (y p)))))

(defclass polygon ()
  ((vertices :initarg :vertices :reader vertices
             :documentation "The corners, 2D-POINTs in order, as a vector."))
  (:documentation "A polygon given by its corners."))

(defmethod initialize-instance :after ((polygon polygon) &key (vertices nil vertices-p))
  (unless (and vertices-p (typep vertices 'sequence) (>= (length vertices) 3)
               (every (lambda (v) (typep v '2d-point)) vertices))
    (error "POLYGON: :VERTICES ~s is not a sequence of at least three 2D-POINTs." vertices))
  (setf (slot-value polygon 'vertices) (coerce vertices 'vector)))

(defgeneric point-in-polygon (point polygon)
  (:documentation "True when the 2D-POINT POINT lies inside POLYGON (even-odd rule).")
  (:method ((point 2d-point) (polygon polygon))
    (let* ((vs (vertices polygon)) (n (length vs)) (inside nil) (px (x point)) (py (y point)))
      (loop for i below n
            for j = (1- n) then (1- i)
            for a = (aref vs i) for b = (aref vs (mod j n))
            when (and (not (eq (> (y a) py) (> (y b) py)))
                      (< px (+ (x a) (/ (* (- (x b) (x a)) (- py (y a))) (- (y b) (y a))))))
              do (setf inside (not inside)))
      inside))
  (:method (point polygon)
    (error "POINT-IN-POLYGON: expected a 2D-POINT and a POLYGON, got ~s and ~s." point polygon)))

(defun degrees->radians (degrees)
  "DEGREES in radians."
  (* pi (/ degrees 180)))

(defun radians->degrees (radians)
  "RADIANS in degrees."
  (* 180 (/ radians pi)))

(setf (documentation 'x 'function) "The x coordinate of a 2D-POINT."
      (documentation 'y 'function) "The y coordinate of a 2D-POINT."
      (documentation 'vertices 'function) "The corners of a POLYGON, as a vector of 2D-POINTs.")
