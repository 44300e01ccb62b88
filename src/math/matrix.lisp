;;;; Double-float matrices as 2D arrays (rows = height, columns = width), as CRAM's cram-math
;;;; has them: constructors, element-wise and matrix arithmetic, determinant and inverse.

(in-package :cram-math)

(deftype double-matrix ()
  "A matrix of double floats: a (height x width) SIMPLE-ARRAY."
  '(simple-array double-float (* *)))

(defun check-matrix (object function)
  (unless (typep object 'double-matrix)
    (error "~s: ~s is not a DOUBLE-MATRIX (see MAKE-DOUBLE-MATRIX)." function object))
  object)

(defun height (matrix)
  "The number of rows of MATRIX."
  (array-dimension (check-matrix matrix 'height) 0))

(defun width (matrix)
  "The number of columns of MATRIX."
  (array-dimension (check-matrix matrix 'width) 1))

(defun check-size (n what function)
  (unless (typep n '(integer 1 100000000))
    (error "~s: the ~a ~s is not a positive integer." function what n)))

(defun make-double-matrix (width height &key initial-contents (initial-element 0d0))
  "A new HEIGHT x WIDTH DOUBLE-MATRIX filled with INITIAL-ELEMENT, or with INITIAL-CONTENTS (a
nested list or array of reals, row by row)."
  (check-size width "width" 'make-double-matrix)
  (check-size height "height" 'make-double-matrix)
  (unless (realp initial-element)
    (error "MAKE-DOUBLE-MATRIX: the initial element ~s is not a real." initial-element))
  (let ((matrix (make-array (list height width) :element-type 'double-float
                                                :initial-element (coerce initial-element 'double-float))))
    (when initial-contents
      (fill-double-matrix matrix :initial-contents initial-contents))
    matrix))

(defun make-double-vector (size &key initial-contents)
  "A column vector: a SIZE x 1 DOUBLE-MATRIX."
  (make-double-matrix 1 size :initial-contents initial-contents))

(defun double-vector-size (vector)
  "The number of rows of the column VECTOR (a matrix of width 1)."
  (unless (= (width vector) 1)
    (error "DOUBLE-VECTOR-SIZE: ~s is not a column vector (its width is ~d)." vector (width vector)))
  (height vector))

(defun flatten-contents (contents)
  (if (or (listp contents) (and (arrayp contents) (not (stringp contents))))
      (loop for x across (if (listp contents) (coerce contents 'vector)
                             (make-array (array-total-size contents) :displaced-to contents))
            append (flatten-contents x))
      (list contents)))

(defun fill-double-matrix (matrix &key (initial-element nil element-p) initial-contents)
  "Fill MATRIX with INITIAL-ELEMENT, or with the reals of INITIAL-CONTENTS (nested lists or
arrays, read row by row); return MATRIX."
  (check-matrix matrix 'fill-double-matrix)
  (cond (initial-contents
         (let ((values (flatten-contents initial-contents)))
           (unless (and (= (length values) (array-total-size matrix)) (every #'realp values))
             (error "FILL-DOUBLE-MATRIX: ~s are not ~d reals for a ~dx~d matrix."
                    initial-contents (array-total-size matrix) (height matrix) (width matrix)))
           (loop for v in values for i from 0
                 do (setf (row-major-aref matrix i) (coerce v 'double-float)))))
        (element-p
         (unless (realp initial-element)
           (error "FILL-DOUBLE-MATRIX: the element ~s is not a real." initial-element))
         (fill (make-array (array-total-size matrix) :element-type 'double-float
                                                     :displaced-to matrix)
               (coerce initial-element 'double-float))))
  matrix)

(defun mref (matrix row column)
  "The element of MATRIX at ROW and COLUMN."
  (aref (check-matrix matrix 'mref) row column))

(defun (setf mref) (value matrix row column)
  (setf (aref (check-matrix matrix '(setf mref)) row column) (coerce value 'double-float)))

(defun same-shape (matrices function)
  (let ((shape (array-dimensions (check-matrix (first matrices) function))))
    (dolist (m (rest matrices) shape)
      (unless (equal shape (array-dimensions (check-matrix m function)))
        (error "~s: the matrices are ~{~dx~d~} and ~{~dx~d~}; they must have the same size."
               function shape (array-dimensions m))))))

(defun map-double-matrix-into (result function &rest matrices)
  "Set each element of RESULT to FUNCTION of the elements at the same place of MATRICES (all of
RESULT's size); return RESULT."
  (same-shape (cons result matrices) 'map-double-matrix-into)
  (dotimes (i (array-total-size result) result)
    (setf (row-major-aref result i)
          (coerce (apply function (mapcar (lambda (m) (row-major-aref m i)) matrices))
                  'double-float))))

(defun map-double-matrix (function matrix &rest more-matrices)
  "A new matrix of FUNCTION applied element-wise to MATRIX and MORE-MATRICES."
  (apply #'map-double-matrix-into (make-double-matrix (width matrix) (height matrix))
         function matrix more-matrices))

(defun double-matrix-from-array (array &optional out)
  "ARRAY (rank 1: a column vector; rank 2) of reals as a DOUBLE-MATRIX (into OUT when given)."
  (let* ((rows (case (and (arrayp array) (array-rank array))
                 (1 (length array)) (2 (array-dimension array 0))
                 (t (error "DOUBLE-MATRIX-FROM-ARRAY: ~s is not an array of rank 1 or 2." array))))
         (columns (if (= (array-rank array) 1) 1 (array-dimension array 1)))
         (out (or out (make-double-matrix columns rows))))
    (unless (equal (array-dimensions out) (list rows columns))
      (error "DOUBLE-MATRIX-FROM-ARRAY: the output matrix is not ~dx~d." rows columns))
    (dotimes (i (array-total-size array) out)
      (let ((v (row-major-aref array i)))
        (unless (realp v) (error "DOUBLE-MATRIX-FROM-ARRAY: ~s holds ~s, not a real." array v))
        (setf (row-major-aref out i) (coerce v 'double-float))))))

(defun double-matrix-from-grid (grid &optional out)
  "The 2D array GRID as a DOUBLE-MATRIX (CRAM's name for GSLL grids; plain arrays here)."
  (double-matrix-from-array grid out))

(defun grid-from-double-matrix (matrix)
  "A copy of MATRIX (a grid, for code written against GSLL)."
  (double-matrix-from-array (check-matrix matrix 'grid-from-double-matrix)))

(defun double-matrix-transpose (matrix &optional (out (make-double-matrix (height matrix)
                                                                          (width matrix))))
  "The transpose of MATRIX (into OUT)."
  (dotimes (r (height matrix) out)
    (dotimes (c (width matrix))
      (setf (aref out c r) (aref matrix r c)))))

(defun double-matrix-product (m-1 m-2 &optional out)
  "The matrix product M-1 M-2 (into OUT, which must not be one of them)."
  (unless (= (width m-1) (height m-2))
    (error "DOUBLE-MATRIX-PRODUCT: a ~dx~d matrix cannot multiply a ~dx~d one."
           (height m-1) (width m-1) (height m-2) (width m-2)))
  (let ((out (or out (make-double-matrix (width m-2) (height m-1)))))
    (dotimes (r (height m-1) out)
      (dotimes (c (width m-2))
        (setf (aref out r c)
              (loop for k below (width m-1) sum (* (aref m-1 r k) (aref m-2 k c))))))))

(macrolet ((scalar-op (name op doc)
             `(defun ,name (matrix scalar &optional (out (make-double-matrix (width matrix)
                                                                             (height matrix))))
                ,doc
                (unless (realp scalar)
                  (error "~s: ~s is not a real." ',name scalar))
                (map-double-matrix-into out (lambda (e) (,op e scalar)) matrix)))
           (element-op (name op doc)
             `(defun ,name (m-1 m-2 &optional (out (make-double-matrix (width m-1) (height m-1))))
                ,doc
                (map-double-matrix-into out #',op m-1 m-2))))
  (scalar-op m.+ + "MATRIX with SCALAR added to each element (into OUT).")
  (scalar-op m.- - "MATRIX with SCALAR subtracted from each element (into OUT).")
  (scalar-op m.* * "MATRIX with each element multiplied by SCALAR (into OUT).")
  (scalar-op m./ / "MATRIX with each element divided by SCALAR (into OUT).")
  (element-op m+ + "The element-wise sum of two matrices of one size (into OUT).")
  (element-op m- - "The element-wise difference of two matrices of one size (into OUT).")
  (element-op m* * "The element-wise product of two matrices of one size (into OUT).")
  (element-op m/ / "The element-wise quotient of two matrices of one size (into OUT)."))

(defun lu-decompose (matrix function)
  "(values lu permutation sign) of the square MATRIX, by Gaussian elimination with partial
pivoting; NIL as first value when it is singular."
  (let* ((n (height matrix))
         (lu (grid-from-double-matrix matrix))
         (permutation (make-array n :initial-contents (loop for i below n collect i)))
         (sign 1))
    (unless (= n (width matrix))
      (error "~s: the ~dx~d matrix is not square." function n (width matrix)))
    (dotimes (k n (values lu permutation sign))
      (let ((pivot (loop with best = k for r from k below n
                         when (> (abs (aref lu r k)) (abs (aref lu best k))) do (setf best r)
                         finally (return best))))
        (when (zerop (aref lu pivot k))
          (return (values nil permutation 0)))
        (unless (= pivot k)
          (dotimes (c n) (rotatef (aref lu k c) (aref lu pivot c)))
          (rotatef (aref permutation k) (aref permutation pivot))
          (setf sign (- sign)))
        (loop for r from (1+ k) below n
              do (let ((factor (/ (aref lu r k) (aref lu k k))))
                   (setf (aref lu r k) factor)
                   (loop for c from (1+ k) below n
                         do (decf (aref lu r c) (* factor (aref lu k c))))))))))

(defun determinant (matrix)
  "The determinant of the square MATRIX."
  (multiple-value-bind (lu permutation sign) (lu-decompose matrix 'determinant)
    (declare (ignore permutation))
    (if lu
        (* sign (loop with p = 1d0 for i below (height lu) do (setf p (* p (aref lu i i)))
                      finally (return p)))
        0d0)))

(defun invert-matrix (matrix)
  "(values inverse determinant) of the square MATRIX; a singular one is an error."
  (multiple-value-bind (lu permutation sign) (lu-decompose matrix 'invert-matrix)
    (unless lu
      (error "INVERT-MATRIX: the matrix ~s is singular." matrix))
    (let* ((n (height lu)) (inverse (make-double-matrix n n)))
      (dotimes (column n)
        ;; solve LU x = P e_column
        (let ((x (make-array n :element-type 'double-float)))
          (dotimes (i n)
            (setf (aref x i) (- (if (= (aref permutation i) column) 1d0 0d0)
                                (loop for j below i sum (* (aref lu i j) (aref x j))))))
          (loop for i from (1- n) downto 0
                do (setf (aref x i) (/ (- (aref x i)
                                          (loop for j from (1+ i) below n
                                                sum (* (aref lu i j) (aref x j))))
                                       (aref lu i i))))
          (dotimes (i n) (setf (aref inverse i column) (aref x i)))))
      (values inverse
              (* sign (loop with p = 1d0 for i below n do (setf p (* p (aref lu i i)))
                            finally (return p)))))))

(defun gauss (covariance mean)
  "The density function of the multivariate normal distribution with COVARIANCE (a k x k
matrix) and MEAN (a k x 1 column vector); it takes a k x 1 column vector."
  (let ((k (double-vector-size mean)))
    (unless (and (= k (height covariance)) (= k (width covariance)))
      (error "GAUSS: the covariance is ~dx~d, the mean has ~d rows." (height covariance)
             (width covariance) k))
    (multiple-value-bind (inverse det) (invert-matrix covariance)
      (unless (> det 0)
        (error "GAUSS: the covariance ~s is not positive definite (determinant ~s)."
               covariance det))
      (let ((c (/ 1d0 (* (expt (* 2 pi) (/ k 2)) (sqrt det)))))
        (lambda (x)
          (unless (and (typep x 'double-matrix) (= (height x) k) (= (width x) 1))
            (error "GAUSS: ~s is not a ~dx1 column vector." x k))
          (let ((d (m- x mean)))
            (* c (exp (* -0.5d0 (aref (double-matrix-product
                                       (double-matrix-transpose d)
                                       (double-matrix-product inverse d))
                                      0 0))))))))))
