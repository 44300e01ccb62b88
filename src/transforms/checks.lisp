;;;; Input checking: every constructor coerces reals to double floats and rejects anything else
;;;; with a TRANSFORM-INPUT-ERROR that names the value and what was expected.

(in-package :cl-transforms)

(define-condition transform-input-error (error)
  ((value :initarg :value :reader transform-input-error-value)
   (expected :initarg :expected :reader transform-input-error-expected)
   (place :initarg :place :initform nil :reader transform-input-error-place))
  (:report (lambda (c stream)
             (let ((*print-length* 8) (*print-level* 3) (*print-pretty* nil))
               (format stream "~@[~a: ~]expected ~a, got ~s"
                       (transform-input-error-place c)
                       (transform-input-error-expected c)
                       (transform-input-error-value c)))))
  (:documentation "Signalled when a transforms function receives a value it cannot use: a non-real
coordinate, NaN or infinity, a zero quaternion or axis, a malformed matrix or list. The report names
the offending value and what was expected."))

(setf (documentation 'transform-input-error-value 'function)
      "The offending value of a TRANSFORM-INPUT-ERROR."
      (documentation 'transform-input-error-expected 'function)
      "A description of what a TRANSFORM-INPUT-ERROR expected instead of its value.")

(declaim (ftype (function (t t &optional t) nil) input-error))
(defun input-error (value expected &optional place)
  "Signal a TRANSFORM-INPUT-ERROR about VALUE, which should have been EXPECTED, found at PLACE."
  (error 'transform-input-error :value value :expected expected :place place))

(declaim (inline finite-double-p))
(defun finite-double-p (d)
  "True when the double float D is neither NaN nor an infinity."
  (declare (type double-float d))
  (/= (ldb (byte 11 20) (sb-kernel:double-float-high-bits d)) #x7ff))

(defun single->double (f)
  "The double float nearest to the shortest decimal that reads back as the single float F, so
that 0.1 becomes 0.1d0 rather than 0.10000000149011612d0."
  (declare (type single-float f))
  (if (zerop f)
      (if (minusp (float-sign f)) -0d0 0d0)
      (multiple-value-bind (position digits) (sb-impl::flonum-to-digits (abs f))
        (let ((r (* (parse-integer digits) (expt 10 (- position (length digits))))))
          (float (if (minusp f) (- r) r) 1d0)))))

(defun %coerce-real-slow (value place)
  "Coerce VALUE, which is not already a finite double float, to one, or signal an input error."
  (typecase value
    (double-float
     (input-error value "a finite real number (not NaN or infinity)" place))
    (float
     (cond ((or (sb-ext:float-nan-p value) (sb-ext:float-infinity-p value))
            (input-error value "a finite real number (not NaN or infinity)" place))
           ((typep value 'single-float) (single->double value))
           (t (coerce value 'double-float))))
    (real
     (handler-case (let ((d (coerce value 'double-float)))
                     (if (finite-double-p d)
                         d
                         (input-error value "a real number within double-float range" place)))
       (arithmetic-error ()
         (input-error value "a real number within double-float range" place))))
    (t (input-error value "a real number" place))))

(declaim (inline ensure-double))
(defun ensure-double (value &optional place)
  "VALUE as a finite double float. Any real is accepted; anything else (NIL, a string, a symbol,
NaN, an infinity) signals TRANSFORM-INPUT-ERROR naming VALUE and PLACE."
  (if (and (typep value 'double-float) (finite-double-p value))
      value
      (%coerce-real-slow value place)))

(defun check-type-of (value type expected place)
  "Return VALUE when it is of TYPE; otherwise signal TRANSFORM-INPUT-ERROR naming it."
  (if (typep value type)
      value
      (input-error value expected place)))

(define-compiler-macro check-type-of (&whole form value type expected place)
  ;; a quoted TYPE is tested by compiled code, not parsed at run time
  (if (and (consp type) (eq (first type) 'quote) (symbolp (second type)))
      (let ((v (gensym "VALUE")))
        `(let ((,v ,value))
           (if (typep ,v ,type) ,v (input-error ,v ,expected ,place))))
      form))

(defmacro with-double-printing (&body body)
  "Run BODY with double floats printed with their d0 exponent marker, as CRAM shows them."
  `(let ((*read-default-float-format* 'single-float))
     ,@body))
