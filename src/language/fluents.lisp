;;;; Fluents: values that change over time and that plans can wait on.

(in-package :cram-language)

(defclass fluent ()
  ((name :initarg :name :reader fluent-name
         :documentation "A symbol or string naming the fluent.")
   (lock :initform (bt:make-lock "fluent") :reader fluent-lock)
   (changed :initform (bt:make-condition-variable :name "fluent changed")
            :reader fluent-changed)
   (pulse-count :initform 0 :accessor fluent-pulse-count)
   (dependents :initform '() :accessor fluent-dependents)
   (waiting-tasks :initform '() :accessor fluent-waiting-tasks))
  (:documentation "The base class of fluents. A fluent is pulsed whenever its
value (or the value of a fluent it depends on) may have changed; WAIT-FOR and
WHENEVER wake up on pulses."))

(defclass value-fluent (fluent)
  ((value :initarg :value :initform nil))
  (:documentation "A fluent holding a value that is set with (SETF VALUE)."))

(defclass fluent-net (fluent)
  ((function :initarg :function :reader fluent-net-function)
   (arguments :initarg :arguments :reader fluent-net-arguments))
  (:documentation "A fluent whose value is a function of other fluents (and
constants), recomputed on every read; it is pulsed whenever one of its
fluent arguments is."))

(defclass pulsed-fluent (fluent)
  ((source :initarg :source :reader pulsed-source)
   (mode :initarg :mode :reader pulsed-mode)
   (seen :initarg :seen :accessor pulsed-seen)
   (consume-lock :initform (bt:make-lock "pulsed fluent") :reader pulsed-consume-lock))
  (:documentation "A fluent that is true once for each pulse of its source
fluent (see PULSED)."))

(setf (documentation 'fluent-name 'function) "The name of a fluent.")

(defmethod print-object ((fluent fluent) stream)
  (print-unreadable-object (fluent stream :type t :identity t)
    (format stream "~a" (fluent-name fluent))))

(defmethod print-object ((fluent value-fluent) stream)
  (print-unreadable-object (fluent stream :type t :identity t)
    (format stream "~a ~s" (fluent-name fluent) (slot-value fluent 'value))))

(defun make-fluent (&key (name (gensym "FLUENT-")) value)
  "Create a VALUE-FLUENT named NAME with the initial VALUE."
  (unless (or (symbolp name) (stringp name))
    (error "MAKE-FLUENT: the name must be a symbol or string, got ~s." name))
  (make-instance 'value-fluent :name name :value value))

(defgeneric value (object)
  (:documentation "The current value of a fluent; any other object is its own value.")
  (:method ((object t)) object)
  (:method ((fluent value-fluent)) (slot-value fluent 'value))
  (:method ((fluent fluent-net))
    (apply (fluent-net-function fluent) (mapcar #'value (fluent-net-arguments fluent))))
  (:method ((fluent pulsed-fluent))
    (bt:with-lock-held ((pulsed-consume-lock fluent))
      (let ((count (fluent-pulse-count (pulsed-source fluent)))
            (seen (pulsed-seen fluent)))
        (when (> count seen)
          (setf (pulsed-seen fluent)
                (ecase (pulsed-mode fluent)
                  (:once count)
                  (:always (1+ seen))))
          t)))))

(defgeneric (setf value) (new-value fluent)
  (:documentation "Set the value of a VALUE-FLUENT and pulse it, waking every
task waiting on it or on a fluent depending on it.")
  (:method (new-value (fluent value-fluent))
    (setf (slot-value fluent 'value) new-value)
    (pulse fluent)
    new-value)
  (:method (new-value (object t))
    (declare (ignore new-value))
    (error "(SETF VALUE): ~s is not a value fluent; only fluents made by ~
            MAKE-FLUENT can be set." object)))

(defun live-dependents (fluent)
  "FLUENT's dependents that are still alive; prunes collected ones. Called with
the fluent's lock held."
  (let ((alive '()) (pointers '()))
    (dolist (pointer (fluent-dependents fluent))
      (let ((dependent (sb-ext:weak-pointer-value pointer)))
        (when dependent
          (push dependent alive)
          (push pointer pointers))))
    (setf (fluent-dependents fluent) (nreverse pointers))
    alive))

(defun pulse (fluent)
  "Signal that FLUENT may have changed: wake everything waiting on FLUENT and,
transitively, on fluents computed from it."
  (unless (typep fluent 'fluent)
    (error "PULSE: expected a fluent, got ~s." fluent))
  (let ((visited '()))
    (labels ((walk (f)
               (unless (member f visited :test #'eq)
                 (push f visited)
                 (let ((dependents
                         (bt:with-lock-held ((fluent-lock f))
                           (incf (fluent-pulse-count f))
                           (dolist (task (shiftf (fluent-waiting-tasks f) '()))
                             (wake-waiting-task task f))
                           (sb-thread:condition-broadcast (fluent-changed f))
                           (live-dependents f))))
                   (mapc #'walk dependents)))))
      (walk fluent)))
  fluent)

(defun add-dependent (fluent dependent)
  (bt:with-lock-held ((fluent-lock fluent))
    (push (sb-ext:make-weak-pointer dependent) (fluent-dependents fluent))))

(defun wait-on-fluent (fluent predicate timeout)
  "Wait until (PREDICATE FLUENT) returns true and return that value, or NIL
when TIMEOUT seconds passed first."
  (when timeout (check-real-seconds timeout 'wait-for))
  (let ((deadline (and timeout
                       (+ (monotonic-microseconds) (* timeout 1000000))))
        (lock (fluent-lock fluent)))
    (bt:with-lock-held (lock)
      (loop
        (let ((result (funcall predicate fluent)))
          (when result (return result)))
        (let ((remaining (and deadline
                              (/ (- deadline (monotonic-microseconds)) 1000000))))
          (when (and remaining (<= remaining 0))
            (return nil))
          ;; a pulse counts the tasks waiting here as running again (PULSE)
          (when (and *current-task* (task-activity *current-task*))
            (push *current-task* (fluent-waiting-tasks fluent)))
          (unwind-protect
               (with-task-waiting (fluent)
                 (bt:condition-wait (fluent-changed fluent) lock
                                    :timeout (and remaining (float remaining 1d0))))
            (setf (fluent-waiting-tasks fluent)
                  (delete *current-task* (fluent-waiting-tasks fluent)))))))))

(defun wait-for (fluent &key timeout)
  "Block until the value of FLUENT is non-NIL and return that value. With
TIMEOUT (seconds), return NIL when it expires first. A non-fluent is its own
value: a true one returns at once, NIL is an error (it would wait forever)."
  (cond ((typep fluent 'fluent)
         (wait-on-fluent fluent #'value timeout))
        (fluent fluent)
        (t (error "WAIT-FOR: expected a fluent, got ~s, which can never become true."
                  fluent))))

(defun call-whenever (fluent function)
  (unless (typep fluent 'fluent)
    (error "WHENEVER: expected a fluent, got ~s." fluent))
  (let ((last-count -1))
    (loop
      (wait-on-fluent fluent
                      (lambda (f)
                        (let ((count (fluent-pulse-count f)))
                          (when (> count last-count)
                            (let ((value (value f)))
                              (when value (setf last-count count))
                              value))))
                      nil)
      (funcall function))))

(defmacro whenever ((fluent-form) &body body)
  "Run BODY each time the fluent FLUENT-FORM is pulsed while its value is
true (and once at the start if it is true then). Loops until BODY leaves with
RETURN (an implicit BLOCK NIL) or the task is evaporated."
  `(block nil
     (call-whenever ,fluent-form (lambda () ,@body))))

(defun pulsed (fluent &key (handle-missed-pulses :once))
  "A fluent that becomes true when FLUENT is pulsed; reading it as true
consumes the pulse. With HANDLE-MISSED-PULSES :ONCE (the default) several
pulses since the last read count as one; with :ALWAYS each pulse gives one
true read."
  (unless (typep fluent 'fluent)
    (error "PULSED: expected a fluent, got ~s." fluent))
  (unless (member handle-missed-pulses '(:once :always))
    (error "PULSED: HANDLE-MISSED-PULSES must be :ONCE or :ALWAYS, got ~s."
           handle-missed-pulses))
  (let ((pulsed (make-instance 'pulsed-fluent
                               :name (format nil "PULSED-~a" (fluent-name fluent))
                               :source fluent :mode handle-missed-pulses
                               :seen (fluent-pulse-count fluent))))
    (add-dependent fluent pulsed)
    pulsed))

;;; Fluent networks

(defun fl-apply (function arguments &key name)
  "A FLUENT-NET whose value is FUNCTION applied to the current values of
ARGUMENTS (fluents or constants)."
  (unless (or (functionp function) (and (symbolp function) (fboundp function)))
    (error "FL-APPLY: expected a function or a function name, got ~s." function))
  (let ((net (make-instance 'fluent-net
                            :name (or name (format nil "~a" (if (functionp function)
                                                                "FL-FUNCALL"
                                                                function)))
                            :function function :arguments arguments)))
    (dolist (argument arguments)
      (when (typep argument 'fluent)
        (add-dependent argument net)))
    net))

(defun fl-funcall (function &rest arguments)
  "A FLUENT-NET whose value is FUNCTION called on the current values of
ARGUMENTS (fluents or constants)."
  (fl-apply function arguments))

(defun fl-and (&rest arguments)
  "A fluent that is T while the values of all ARGUMENTS are true."
  (fl-apply (lambda (&rest values) (every #'identity values)) arguments :name "FL-AND"))

(defun fl-or (&rest arguments)
  "A fluent whose value is the first true value of ARGUMENTS, or NIL."
  (fl-apply (lambda (&rest values) (some #'identity values)) arguments :name "FL-OR"))

(defun fl-not (argument)
  "A fluent that is T while the value of ARGUMENT is NIL."
  (fl-apply #'not (list argument) :name "FL-NOT"))

(macrolet ((define-fluent-operators (&rest specs)
             `(progn
                ,@(loop for (name function doc) in specs
                        collect `(defun ,name (&rest arguments)
                                   ,doc
                                   (fl-apply #',function arguments
                                             :name ,(symbol-name name)))))))
  (define-fluent-operators
    (fl< < "A fluent that is true while the values of ARGUMENTS increase strictly (as <).")
    (fl> > "A fluent that is true while the values of ARGUMENTS decrease strictly (as >).")
    (fl= = "A fluent that is true while the values of ARGUMENTS are numerically equal (as =).")
    (fl<= <= "A fluent that is true while the values of ARGUMENTS do not decrease (as <=).")
    (fl>= >= "A fluent that is true while the values of ARGUMENTS do not increase (as >=).")
    (fl-eq eq "A fluent that is true while the values of its two ARGUMENTS are EQ.")
    (fl-eql eql "A fluent that is true while the values of its two ARGUMENTS are EQL.")
    (fl+ + "A fluent whose value is the sum of the values of ARGUMENTS.")
    (fl- - "A fluent whose value is the difference of the values of ARGUMENTS.")
    (fl* * "A fluent whose value is the product of the values of ARGUMENTS.")
    (fl/ / "A fluent whose value is the quotient of the values of ARGUMENTS.")))
