;;;; 3D vectors and unit quaternions: immutable structures with double-float slots.

(in-package :cl-transforms)

(declaim (inline %make-3d-vector %make-quaternion))

(defstruct (3d-vector (:constructor %make-3d-vector (x y z))
                      (:conc-name %v-)
                      (:copier nil))
  "A point or direction in 3D space; immutable, coordinates are double floats (metres)."
  (x 0d0 :type double-float :read-only t)
  (y 0d0 :type double-float :read-only t)
  (z 0d0 :type double-float :read-only t))

(deftype point ()
  "A point in space is represented by a 3D-VECTOR."
  '3d-vector)

(defstruct (quaternion (:constructor %make-quaternion (x y z w))
                       (:conc-name %q-)
                       (:copier nil))
  "A rotation as a unit quaternion (x y z w); immutable, components are double floats."
  (x 0d0 :type double-float :read-only t)
  (y 0d0 :type double-float :read-only t)
  (z 0d0 :type double-float :read-only t)
  (w 1d0 :type double-float :read-only t))

(setf (documentation '3d-vector-p 'function) "True when the object is a 3D-VECTOR."
      (documentation 'quaternion-p 'function) "True when the object is a QUATERNION.")

(defmethod print-object ((v 3d-vector) stream)
  (print-unreadable-object (v stream)
    (with-double-printing
      (format stream "3D-VECTOR (~s ~s ~s)" (%v-x v) (%v-y v) (%v-z v)))))

(defmethod print-object ((q quaternion) stream)
  (print-unreadable-object (q stream)
    (with-double-printing
      (format stream "QUATERNION (~s ~s ~s ~s)" (%q-x q) (%q-y q) (%q-z q) (%q-w q)))))

(defmethod make-load-form ((v 3d-vector) &optional environment)
  (make-load-form-saving-slots v :environment environment))

(defmethod make-load-form ((q quaternion) &optional environment)
  (make-load-form-saving-slots q :environment environment))

;;; Accessors shared by vectors and quaternions

(declaim (inline x y z w))
(defun x (object)
  "The x coordinate of a 3D-VECTOR (or point) or the x component of a QUATERNION."
  (typecase object
    (3d-vector (%v-x object))
    (quaternion (%q-x object))
    (t (input-error object "a 3D-VECTOR or a QUATERNION" 'x))))

(defun y (object)
  "The y coordinate of a 3D-VECTOR (or point) or the y component of a QUATERNION."
  (typecase object
    (3d-vector (%v-y object))
    (quaternion (%q-y object))
    (t (input-error object "a 3D-VECTOR or a QUATERNION" 'y))))

(defun z (object)
  "The z coordinate of a 3D-VECTOR (or point) or the z component of a QUATERNION."
  (typecase object
    (3d-vector (%v-z object))
    (quaternion (%q-z object))
    (t (input-error object "a 3D-VECTOR or a QUATERNION" 'z))))

(defun w (object)
  "The scalar (w) component of a QUATERNION."
  (typecase object
    (quaternion (%q-w object))
    (t (input-error object "a QUATERNION" 'w))))

;;; Constructors

(defun make-3d-vector (x y z)
  "A 3D-VECTOR with coordinates X, Y, Z: any finite reals, stored as double floats."
  (%make-3d-vector (ensure-double x "MAKE-3D-VECTOR x")
                   (ensure-double y "MAKE-3D-VECTOR y")
                   (ensure-double z "MAKE-3D-VECTOR z")))

(declaim (type 3d-vector +zero-vector+))
(sb-ext:define-load-time-global +zero-vector+ (%make-3d-vector 0d0 0d0 0d0)
  "The shared zero vector.")

(declaim (type quaternion +identity-quaternion+))
(sb-ext:define-load-time-global +identity-quaternion+ (%make-quaternion 0d0 0d0 0d0 1d0)
  "The shared identity rotation.")

(defun make-identity-vector ()
  "The zero 3D-VECTOR (0 0 0)."
  +zero-vector+)

(defun make-identity-rotation ()
  "The identity QUATERNION (0 0 0 1)."
  +identity-quaternion+)

(declaim (inline %unit-norm-p %unit-scale %unit-quaternion))
(defun %unit-norm-p (x y z w)
  "True when the quaternion of the double floats X Y Z W has unit norm to within rounding, as
products of unit quaternions do: those need no renormalisation."
  (declare (type double-float x y z w) (optimize (speed 3) (safety 0) (debug 0)))
  (< (abs (- (+ (* x x) (* y y) (* z z) (* w w)) 1d0)) 1d-15))

(defun %unit-scale (x y z w original)
  "The factor that scales the quaternion of the double floats X Y Z W to unit norm. A zero or
non-finite norm signals an error naming what ORIGINAL, a function of no arguments, returns (or,
with ORIGINAL NIL, the components)."
  (declare (type double-float x y z w) (optimize (speed 3) (safety 0) (debug 0)))
  (let ((n2 (+ (* x x) (* y y) (* z z) (* w w))))
    (if (and (> n2 1d-200) (finite-double-p n2))
        (/ 1d0 (sqrt n2))
        (input-error (if original (funcall (the function original)) (list x y z w))
                     "a quaternion with a non-zero, finite norm" 'make-quaternion))))

(defun %unit-quaternion (x y z w &optional original)
  "A QUATERNION from the double floats X Y Z W scaled to unit norm (kept as they are when their
norm is 1 to within rounding). A zero or non-finite norm signals an error naming what ORIGINAL,
a function of no arguments, returns (or the components)."
  (declare (type double-float x y z w) (optimize (speed 3) (safety 0) (debug 0)))
  (if (%unit-norm-p x y z w)
      (%make-quaternion x y z w)
      (let ((s (%unit-scale x y z w original)))
        (declare (type double-float s))
        (%make-quaternion (* x s) (* y s) (* z s) (* w s)))))

(defun make-quaternion (x y z w)
  "A rotation QUATERNION with components X Y Z W (any finite reals), normalised to unit length.
A zero quaternion is not a rotation and signals TRANSFORM-INPUT-ERROR."
  (let* ((dx (ensure-double x "MAKE-QUATERNION x"))
         (dy (ensure-double y "MAKE-QUATERNION y"))
         (dz (ensure-double z "MAKE-QUATERNION z"))
         (dw (ensure-double w "MAKE-QUATERNION w"))
         (m (max (abs dx) (abs dy) (abs dz) (abs dw))))
    ;; ENSURE-DOUBLE gives a double or signals: the arithmetic below is on doubles, unboxed
    (declare (type double-float dx dy dz dw m))
    ;; components so large or so small that their squares overflow or vanish: the direction
    ;; is all that matters, so scale them first
    (when (and (or (> m 1d100) (< 0d0 m 1d-100)))
      (setf dx (/ dx m) dy (/ dy m) dz (/ dz m) dw (/ dw m)))
    ;; the components as given, for the error only: not consed for every quaternion
    (flet ((original () (list x y z w)))
      (declare (dynamic-extent #'original))
      (%unit-quaternion dx dy dz dw #'original))))

(defun copy-3d-vector (vector &key x y z)
  "A 3D-VECTOR like VECTOR with the coordinates given by X, Y, Z replaced."
  (check-type-of vector '3d-vector "a 3D-VECTOR" 'copy-3d-vector)
  (%make-3d-vector (if x (ensure-double x "COPY-3D-VECTOR x") (%v-x vector))
                   (if y (ensure-double y "COPY-3D-VECTOR y") (%v-y vector))
                   (if z (ensure-double z "COPY-3D-VECTOR z") (%v-z vector))))

(defun copy-quaternion (quaternion &key x y z w)
  "A QUATERNION like QUATERNION with the components given by X, Y, Z, W replaced (renormalised)."
  (check-type-of quaternion 'quaternion "a QUATERNION" 'copy-quaternion)
  (make-quaternion (or x (%q-x quaternion)) (or y (%q-y quaternion))
                   (or z (%q-z quaternion)) (or w (%q-w quaternion))))

;;; Vector arithmetic

;;; The overflow guard of the vector operations. Arguments of moderate magnitude cannot make an
;;; operation overflow, so only the others pay for a handler: the test looks at the binary
;;; exponents of all coordinates at once, with integer operations and a single branch. A double
;;; is small when its magnitude is below 2^498 (about 8d149) and a divisor when it is also at
;;; least 2^-497 (about 2d-150): sums, products and quotients of such numbers stay far within
;;; double-float range. NaN and infinity are never small; the operation's own checks name them.

(eval-when (:compile-toplevel :load-toplevel :execute)
  (defconstant +small-exponent-limit+ (+ 1023 498)
    "Biased exponents of small doubles are below this.")
  (defconstant +divisor-exponent-floor+ (- 1023 497)
    "Biased exponents of divisors are at least this."))

(defmacro %exponent-flags (d &optional divisor)
  "An integer of the double float D whose bits above the eleventh are all clear when D is small
(when DIVISOR, when it is a divisor); such flags of several doubles can be combined by LOGIOR."
  (let ((e (gensym "E")))
    `(let ((,e (ldb (byte 11 20) (sb-kernel:double-float-high-bits ,d))))
       ;; e + (2048 - limit) reaches bit 11 exactly when e >= limit; e - floor is negative
       ;; (all high bits set) exactly when e < floor
       ,(if divisor
            `(logior (+ ,e (- 2048 +small-exponent-limit+)) (- ,e +divisor-exponent-floor+))
            `(+ ,e (- 2048 +small-exponent-limit+))))))

(defmacro %vector-flags (v &optional divisor)
  "The LOGIOR of the %EXPONENT-FLAGS of the coordinates of the 3D-VECTOR V."
  (let ((g (gensym "V")))
    `(let ((,g ,v))
       (logior (%exponent-flags (%v-x ,g) ,divisor) (%exponent-flags (%v-y ,g) ,divisor)
               (%exponent-flags (%v-z ,g) ,divisor)))))

(declaim (inline %small-number-p))
(defun %small-number-p (x &optional divisor)
  "True when the scalar argument X is a small double float (a divisor, when DIVISOR), a fixnum
or a single float; false for everything else, which takes the guarded path."
  (typecase x
    (double-float (not (logtest (if divisor (%exponent-flags x t) (%exponent-flags x)) -2048)))
    ((or fixnum single-float) t)
    (t nil)))

(defmacro define-vector-op (name-and-options lambda-list doc &body body)
  "Define NAME as an inline function whose vector arguments are checked to be 3D-VECTORs. A
floating-point overflow in BODY signals TRANSFORM-INPUT-ERROR naming the arguments. NAME may be
given as (NAME :divisors ARGS): the arguments ARGS are divided by."
  (destructuring-bind (name &key divisors) (alexandria:ensure-list name-and-options)
    (let* ((vectors (remove-if-not (lambda (a) (member a '(v v1 v2 a b))) lambda-list))
           (args (remove-if (lambda (a) (member a lambda-list-keywords))
                            (mapcar (lambda (a) (if (consp a) (car a) a)) lambda-list)))
           (scalars (remove-if (lambda (a) (member a vectors)) args))
           (guarded (intern (format nil "%~a/GUARDED" name) :cl-transforms)))
      `(progn
         (defun ,guarded ,args
           ,(format nil "The body of ~a under a handler of floating-point overflow." name)
           (handler-case (progn ,@body)
             (floating-point-overflow ()
               (input-error (list ,@args) "arguments whose result is within double-float range"
                            ',name))))
         (declaim (inline ,name))
         (defun ,name ,lambda-list
           ,doc
           ,@(loop for v in vectors
                   collect `(unless (3d-vector-p ,v) (input-error ,v "a 3D-VECTOR" ',name)))
           ;; arguments of small magnitude cannot overflow: no handler on the common path
           (if (and ,@(loop for a in scalars
                            collect `(%small-number-p ,a ,(and (member a divisors) t)))
                    (not (logtest (logior ,@(loop for v in vectors
                                                  collect `(%vector-flags
                                                            ,v ,(and (member v divisors) t))))
                                  -2048)))
               (progn ,@body)
               (,guarded ,@args)))))))

(define-vector-op v+ (v1 v2)
  "The sum of the 3D-VECTORs V1 and V2."
  (%make-3d-vector (+ (%v-x v1) (%v-x v2)) (+ (%v-y v1) (%v-y v2)) (+ (%v-z v1) (%v-z v2))))

(define-vector-op v- (v1 v2)
  "The difference V1 - V2 of two 3D-VECTORs."
  (%make-3d-vector (- (%v-x v1) (%v-x v2)) (- (%v-y v1) (%v-y v2)) (- (%v-z v1) (%v-z v2))))

(define-vector-op v* (v scalar)
  "The 3D-VECTOR V scaled by the real SCALAR."
  (let ((s (ensure-double scalar "V* scalar")))
    (%make-3d-vector (* s (%v-x v)) (* s (%v-y v)) (* s (%v-z v)))))

(define-vector-op (v/ :divisors (scalar)) (v scalar)
  "The 3D-VECTOR V divided by the non-zero real SCALAR."
  (let ((s (ensure-double scalar "V/ scalar")))
    (when (zerop s) (input-error scalar "a non-zero divisor" 'v/))
    (%make-3d-vector (/ (%v-x v) s) (/ (%v-y v) s) (/ (%v-z v) s))))

(define-vector-op v-inv (v)
  "The 3D-VECTOR -V."
  (%make-3d-vector (- (%v-x v)) (- (%v-y v)) (- (%v-z v))))

(define-vector-op v*-pairwise (v1 v2)
  "The component-wise product of two 3D-VECTORs."
  (%make-3d-vector (* (%v-x v1) (%v-x v2)) (* (%v-y v1) (%v-y v2)) (* (%v-z v1) (%v-z v2))))

(define-vector-op (v/-pairwise :divisors (v2)) (v1 v2)
  "The component-wise quotient V1 / V2 of two 3D-VECTORs; V2 must have no zero coordinate."
  (when (or (zerop (%v-x v2)) (zerop (%v-y v2)) (zerop (%v-z v2)))
    (input-error v2 "a divisor vector without zero coordinates" 'v/-pairwise))
  (%make-3d-vector (/ (%v-x v1) (%v-x v2)) (/ (%v-y v1) (%v-y v2)) (/ (%v-z v1) (%v-z v2))))

(define-vector-op dot-product (v1 v2)
  "The dot product of two 3D-VECTORs."
  (+ (* (%v-x v1) (%v-x v2)) (* (%v-y v1) (%v-y v2)) (* (%v-z v1) (%v-z v2))))

(define-vector-op cross-product (v1 v2)
  "The cross product V1 x V2 of two 3D-VECTORs."
  (let ((ax (%v-x v1)) (ay (%v-y v1)) (az (%v-z v1))
        (bx (%v-x v2)) (by (%v-y v2)) (bz (%v-z v2)))
    (%make-3d-vector (- (* ay bz) (* az by)) (- (* az bx) (* ax bz)) (- (* ax by) (* ay bx)))))

(defun %scaled-norm (x y z)
  "sqrt(x² + y² + z²) of the double floats X Y Z, computed without overflow."
  (declare (type double-float x y z))
  (let ((m (max (abs x) (abs y) (abs z))))
    (if (zerop m)
        0d0
        (let ((x (/ x m)) (y (/ y m)) (z (/ z m)))
          (* m (sqrt (+ (* x x) (* y y) (* z z))))))))

(define-vector-op v-norm (v)
  "The Euclidean length of the 3D-VECTOR V."
  (let ((x (%v-x v)) (y (%v-y v)) (z (%v-z v)))
    (if (< (max (abs x) (abs y) (abs z)) 1d150)
        (sqrt (+ (* x x) (* y y) (* z z)))
        (%scaled-norm x y z))))

(define-vector-op v-dist (v1 v2)
  "The Euclidean distance between the points V1 and V2."
  (let ((dx (- (%v-x v1) (%v-x v2))) (dy (- (%v-y v1) (%v-y v2))) (dz (- (%v-z v1) (%v-z v2))))
    (if (< (max (abs dx) (abs dy) (abs dz)) 1d150)
        (sqrt (+ (* dx dx) (* dy dy) (* dz dz)))
        (%scaled-norm dx dy dz))))

(define-vector-op normalize-vector (v)
  "The 3D-VECTOR V scaled to unit length; the zero vector signals TRANSFORM-INPUT-ERROR."
  (let ((n (v-norm v)))
    (if (> n 1d-300)
        (%make-3d-vector (/ (%v-x v) n) (/ (%v-y v) n) (/ (%v-z v) n))
        (input-error v "a vector of non-zero length" 'normalize-vector))))

(define-vector-op v= (v1 v2 &optional (tolerance 0d0))
  "True when the coordinates of V1 and V2 differ by at most TOLERANCE each."
  (let ((tol (ensure-double tolerance "V= tolerance")))
    (and (<= (abs (- (%v-x v1) (%v-x v2))) tol)
         (<= (abs (- (%v-y v1) (%v-y v2))) tol)
         (<= (abs (- (%v-z v1) (%v-z v2))) tol))))

(define-vector-op interpolate-vector (v1 v2 ratio)
  "The point at RATIO (0 gives V1, 1 gives V2) on the straight line from V1 to V2."
  (let ((r (ensure-double ratio "INTERPOLATE-VECTOR ratio")))
    (%make-3d-vector (+ (%v-x v1) (* r (- (%v-x v2) (%v-x v1))))
                     (+ (%v-y v1) (* r (- (%v-y v2) (%v-y v1))))
                     (+ (%v-z v1) (* r (- (%v-z v2) (%v-z v1)))))))

;;; Quaternion arithmetic on components (shared by the quaternion and transform code)

(defmacro with-quaternion-components (((x y z w) q) &body body)
  "Bind X Y Z W to the components of the QUATERNION Q around BODY."
  (let ((g (gensym "Q")))
    `(let* ((,g ,q)
            (,x (%q-x ,g)) (,y (%q-y ,g)) (,z (%q-z ,g)) (,w (%q-w ,g)))
       (declare (type double-float ,x ,y ,z ,w) (ignorable ,x ,y ,z ,w))
       ,@body)))

(defmacro with-vector-components (((x y z) v) &body body)
  "Bind X Y Z to the coordinates of the 3D-VECTOR V around BODY."
  (let ((g (gensym "V")))
    `(let* ((,g ,v) (,x (%v-x ,g)) (,y (%v-y ,g)) (,z (%v-z ,g)))
       (declare (type double-float ,x ,y ,z) (ignorable ,x ,y ,z))
       ,@body)))

(declaim (inline %q*-components %rotate-components))
(defun %q*-components (ax ay az aw bx by bz bw)
  "The Hamilton product (a b) of two quaternions given by components, as four values x y z w."
  (declare (type double-float ax ay az aw bx by bz bw))
  (values (+ (* aw bx) (* ax bw) (* ay bz) (- (* az by)))
          (+ (* aw by) (- (* ax bz)) (* ay bw) (* az bx))
          (+ (* aw bz) (* ax by) (- (* ay bx)) (* az bw))
          (- (* aw bw) (* ax bx) (* ay by) (* az bz))))

(defun %rotate-components (qx qy qz qw vx vy vz)
  "The vector (VX VY VZ) rotated by the unit quaternion (QX QY QZ QW), as three values."
  (declare (type double-float qx qy qz qw vx vy vz))
  ;; v' = v + w t + u x t with u = (qx qy qz) and t = 2 u x v
  (let* ((tx (* 2d0 (- (* qy vz) (* qz vy))))
         (ty (* 2d0 (- (* qz vx) (* qx vz))))
         (tz (* 2d0 (- (* qx vy) (* qy vx)))))
    (values (+ vx (* qw tx) (- (* qy tz) (* qz ty)))
            (+ vy (* qw ty) (- (* qz tx) (* qx tz)))
            (+ vz (* qw tz) (- (* qx ty) (* qy tx))))))

(declaim (inline %q*))
(defun %q* (a b)
  "The product of the QUATERNIONs A and B (unchecked), renormalised."
  (declare (type quaternion a b) (optimize (speed 3) (safety 0) (debug 0)))
  (with-quaternion-components ((ax ay az aw) a)
    (with-quaternion-components ((bx by bz bw) b)
      (multiple-value-bind (x y z w) (%q*-components ax ay az aw bx by bz bw)
        (%unit-quaternion x y z w)))))

(defun q* (q &rest more)
  "The product of the QUATERNIONs, left to right: (q* a b) rotates by B first, then by A."
  (unless (quaternion-p q) (input-error q "a QUATERNION" 'q*))
  (let ((result q))
    (dolist (next more result)
      (unless (quaternion-p next) (input-error next "a QUATERNION" 'q*))
      (setf result (%q* result next)))))

(define-compiler-macro q* (&whole form q &rest more)
  (if (= (length more) 1)
      (let ((a (gensym "A")) (b (gensym "B")))
        `(let ((,a ,q) (,b ,(first more)))
           (unless (quaternion-p ,a) (input-error ,a "a QUATERNION" 'q*))
           (unless (quaternion-p ,b) (input-error ,b "a QUATERNION" 'q*))
           (%q* ,a ,b)))
      form))

(declaim (inline q-inv))
(defun q-inv (q)
  "The inverse rotation of the unit QUATERNION Q (its conjugate)."
  (unless (quaternion-p q) (input-error q "a QUATERNION" 'q-inv))
  (%make-quaternion (- (%q-x q)) (- (%q-y q)) (- (%q-z q)) (%q-w q)))

(defun q-dot (q1 q2)
  "The four-dimensional dot product of the QUATERNIONs Q1 and Q2."
  (check-type-of q1 'quaternion "a QUATERNION" 'q-dot)
  (check-type-of q2 'quaternion "a QUATERNION" 'q-dot)
  (+ (* (%q-x q1) (%q-x q2)) (* (%q-y q1) (%q-y q2)) (* (%q-z q1) (%q-z q2)) (* (%q-w q1) (%q-w q2))))

(defun q= (q1 q2 &optional (tolerance 1d-12))
  "True when Q1 and Q2 describe the same rotation: their components agree within TOLERANCE,
either directly or after negating one of them (q and -q are the same rotation)."
  (let ((tol (ensure-double tolerance "Q= tolerance")))
    (check-type-of q1 'quaternion "a QUATERNION" 'q=)
    (check-type-of q2 'quaternion "a QUATERNION" 'q=)
    (flet ((close-p (sign)
             (and (<= (abs (- (%q-x q1) (* sign (%q-x q2)))) tol)
                  (<= (abs (- (%q-y q1) (* sign (%q-y q2)))) tol)
                  (<= (abs (- (%q-z q1) (* sign (%q-z q2)))) tol)
                  (<= (abs (- (%q-w q1) (* sign (%q-w q2)))) tol))))
      (or (close-p 1d0) (close-p -1d0)))))

(defun normalize (q)
  "Q scaled to unit length. A QUATERNION given to this library is always stored normalised, so
this returns an equal quaternion; a list (x y z w) of reals is accepted too."
  (cond ((quaternion-p q) (%unit-quaternion (%q-x q) (%q-y q) (%q-z q) (%q-w q)))
        ((and (listp q) (alexandria:proper-list-p q) (= (length q) 4))
         (apply #'make-quaternion q))
        (t (input-error q "a QUATERNION or a list (x y z w)" 'normalize))))

(defun is-normalized (q &optional (tolerance 1d-9))
  "True when the QUATERNION Q has unit norm within TOLERANCE."
  (check-type-of q 'quaternion "a QUATERNION" 'is-normalized)
  (< (abs (- (q-dot q q) 1d0)) (ensure-double tolerance "IS-NORMALIZED tolerance")))

(declaim (inline rotate))
(defun rotate (rotation vector)
  "The 3D-VECTOR VECTOR rotated by the QUATERNION ROTATION."
  (unless (quaternion-p rotation) (input-error rotation "a QUATERNION" 'rotate))
  (unless (3d-vector-p vector) (input-error vector "a 3D-VECTOR" 'rotate))
  (with-quaternion-components ((qx qy qz qw) rotation)
    (with-vector-components ((vx vy vz) vector)
      (multiple-value-call #'%make-3d-vector (%rotate-components qx qy qz qw vx vy vz)))))
