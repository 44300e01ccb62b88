;;;; Location designators: solutions come from registered generators (lowest priority number
;;;; first, concatenated lazily) and are checked by registered validators.

(in-package :cram-designators)

(defclass location-designator (designator) ()
  (:documentation "Describes a place. Its solutions (usually poses) come from the registered
location generators and must pass the registered validators; REFERENCE returns the first
valid one and NEXT-SOLUTION walks the others."))

(defmethod normalize-designator-description ((designator location-designator) description)
  (normalize-description description))

(register-designator-class :location 'location-designator)

(defvar *location-generator-max-retries* 30
  "How many consecutive candidates the validators may reject before a location designator's
solution stream ends.")

(defvar *location-generators* '()
  "The registered generators: a list of (name priority function documentation), sorted by
priority, ties in registration order.")

(defvar *location-validators* '()
  "The registered validators: a list of (name priority function documentation), sorted by
priority, ties in registration order.")

(defvar *solution-filters* '()
  "Predicates (designator solution) added by WITH-DESIGNATOR-SOLUTION-FILTER.")

(defun add-registered (list name priority function documentation what)
  (unless (realp priority)
    (error "~a ~s: the priority must be a real number, got ~s." what name priority))
  (unless (or (functionp function) (and (symbolp function) function))
    (error "~a ~s: expected a function or a function name, got ~s." what name function))
  (unless (or (null documentation) (stringp documentation))
    (error "~a ~s: the documentation must be a string, got ~s." what name documentation))
  (stable-sort (append (remove name list :key #'first)
                       (list (list name priority function documentation)))
               #'< :key #'second))

(defun function-name-of (function)
  (if (symbolp function) function (gensym "ANONYMOUS-")))

(defun register-location-generator-function (priority function &optional documentation)
  "Register FUNCTION (a function name or a function of a location designator returning a
(lazy) list of candidate solutions) as a location generator with PRIORITY (lower runs first).
Registering the same function name again replaces the earlier entry."
  (setf *location-generators*
        (add-registered *location-generators* (function-name-of function) priority function
                        documentation "Location generator"))
  function)

(defmacro register-location-generator (priority function &optional documentation)
  "Register the generator FUNCTION (an unquoted function name, or a (lambda ...) /
#'name form) with PRIORITY; see REGISTER-LOCATION-GENERATOR-FUNCTION."
  `(register-location-generator-function
    ,priority ,(if (and (symbolp function) function) `',function function) ,documentation))

(defun delete-location-generator-function (name)
  "Remove the location generator registered under the function name NAME."
  (setf *location-generators* (remove name *location-generators* :key #'first))
  name)

(defun register-location-validation-function-1 (priority function &optional documentation)
  (setf *location-validators*
        (add-registered *location-validators* (function-name-of function) priority function
                        documentation "Location validator"))
  function)

(defmacro register-location-validation-function (priority function &optional documentation)
  "Register FUNCTION (unquoted name or function form) as a location validator with PRIORITY.
It is called with the designator and a candidate solution and returns :ACCEPT, :REJECT,
:MAYBE-REJECT or :UNKNOWN (T means :ACCEPT and NIL :REJECT). :REJECT rejects at once; a
candidate is valid when the validators end in :ACCEPT or :UNKNOWN, invalid when the last
word was :MAYBE-REJECT without any :ACCEPT."
  `(register-location-validation-function-1
    ,priority ,(if (and (symbolp function) function) `',function function) ,documentation))

(defmacro register-location-validator-function (priority function &optional documentation)
  "Another name of REGISTER-LOCATION-VALIDATION-FUNCTION."
  `(register-location-validation-function ,priority ,function ,documentation))

(defun delete-location-validation-function (name)
  "Remove the location validator registered under the function name NAME."
  (setf *location-validators* (remove name *location-validators* :key #'first))
  name)

(defun location-generators ()
  "The registered location generators as a list of (name priority documentation), in order."
  (mapcar (lambda (e) (list (first e) (second e) (fourth e))) *location-generators*))

(defun location-validators ()
  "The registered location validators as a list of (name priority documentation), in order."
  (mapcar (lambda (e) (list (first e) (second e) (fourth e))) *location-validators*))

(defmacro with-designator-solution-filter ((filter) &body body)
  "Run BODY with FILTER, a function (designator solution) returning true to keep a solution,
added to the location validators. Solutions computed inside BODY stay filtered."
  `(let ((*solution-filters* (cons ,filter *solution-filters*)))
     ,@body))

;;; Validation

(defun validate-location (designator solution validators filters)
  "True when SOLUTION of DESIGNATOR passes the VALIDATORS and FILTERS."
  (let ((state :unknown))
    (dolist (entry validators)
      (let* ((raw (funcall (third entry) designator solution))
             (verdict (case raw
                        ((t) :accept)
                        ((nil) :reject)
                        ((:accept :reject :maybe-reject :unknown) raw)
                        (t (error "Location validator ~s returned ~s: expected :ACCEPT, ~
                                   :REJECT, :MAYBE-REJECT, :UNKNOWN, T or NIL."
                                  (first entry) raw)))))
        (ecase verdict
          (:reject (return-from validate-location nil))
          (:accept (setf state :accept))
          (:maybe-reject (unless (eq state :accept) (setf state :maybe-reject)))
          (:unknown))))
    (and (not (eq state :maybe-reject))
         (every (lambda (filter) (funcall filter designator solution)) filters))))

(defun call-generator (entry designator)
  (let ((result (funcall (third entry) designator)))
    (unless (listp result)
      (error "Location generator ~s returned ~s for ~s: expected a (lazy) list of solutions."
             (first entry) result designator))
    result))

(defun generated-candidates (designator generators)
  "The lazy concatenation of the candidates of GENERATORS for DESIGNATOR. A generator is
called only when the candidates before it are used up, and no candidate is computed before
it is asked for."
  (let ((pending generators) (current nil) (last nil))
    (make-lazy-list
     (lambda ()
       (loop
         (when last
           (setf current (lazy-cdr last) last nil))
         (cond (current
                (setf last current current nil)
                (return (values (car last) t)))
               ((null pending)
                (return (values nil nil)))
               (t
                (setf current (call-generator (pop pending) designator)))))))))

(defmethod compute-solutions ((designator location-designator))
  (let ((candidates (generated-candidates designator *location-generators*))
        (validators *location-validators*)
        (filters *solution-filters*)
        (max-retries *location-generator-max-retries*)
        (started nil)
        (rejected 0))
    (unless (and (integerp max-retries) (>= max-retries 0))
      (error "*LOCATION-GENERATOR-MAX-RETRIES* is ~s: expected a non-negative integer."
             max-retries))
    (make-lazy-list
     (lambda ()
       (loop
         (if started (setf candidates (lazy-cdr candidates)) (setf started t))
         (when (null candidates) (return (values nil nil)))
         (let ((candidate (car candidates)))
           (if (validate-location designator candidate validators filters)
               (progn (setf rejected 0)
                      (return (values candidate t)))
               (when (> (incf rejected) max-retries)
                 (setf candidates nil)
                 (return (values nil nil))))))))))

(defmethod no-solution-error ((designator location-designator))
  (error 'location-resolution-error
         :designator designator
         :reason (format nil "no location solution passed the validators (generators: ~
                              ~{~(~a~)~^, ~}; at most ~d consecutive rejections)."
                         (mapcar #'first *location-generators*)
                         *location-generator-max-retries*)))

;;; Location solutions far enough from each other

(defvar *location-solution-distance-function* nil
  "NIL, or a function (solution-1 solution-2) returning the distance (metres) and the angle
(radians) between two location solutions, as two values, for NEXT-DIFFERENT-LOCATION-SOLUTION.
Without it, poses (CL-TRANSFORMS:POSE, stamped or not) are compared by origin distance and
orientation angle and lists of numbers as points.")

(defun solution-distance (a b)
  (cond (*location-solution-distance-function*
         (funcall *location-solution-distance-function* a b))
        ((and (typep a 'cl-transforms:pose) (typep b 'cl-transforms:pose))
         (values (cl-transforms:v-dist (cl-transforms:origin a) (cl-transforms:origin b))
                 (cl-transforms:angle-between-quaternions (cl-transforms:orientation a)
                                                          (cl-transforms:orientation b))))
        ((and (listp a) (listp b) (every #'realp a) (every #'realp b) (= (length a) (length b)))
         (values (sqrt (reduce #'+ (mapcar (lambda (x y) (expt (- x y) 2)) a b))) 0))
        ((equalp a b) (values 0 0))
        (t (error "Cannot measure the distance between the location solutions ~s and ~s: ~
                   set *LOCATION-SOLUTION-DISTANCE-FUNCTION*." a b))))

(defun next-different-location-solution (designator &optional (distance-threshold 0.05)
                                                        (angle-threshold (/ pi 18)))
  "The next solution of the location DESIGNATOR (an equated successor, as NEXT-SOLUTION) that
is at least DISTANCE-THRESHOLD metres or ANGLE-THRESHOLD radians away from DESIGNATOR's own
solution; NIL when there is none, or when more than *LOCATION-GENERATOR-MAX-RETRIES*
solutions in a row were too close."
  (unless (typep designator 'location-designator)
    (error "next-different-location-solution: expected a location designator, got ~s."
           designator))
  (let ((reference (reference designator))
        (tries 0))
    (loop for next = (next-solution designator) then (next-solution next)
          while next
          do (multiple-value-bind (distance angle)
                 (solution-distance reference (reference next))
               (when (or (>= distance distance-threshold) (>= angle angle-threshold))
                 (return next))
               (when (> (incf tries) *location-generator-max-retries*)
                 (return nil))))))
