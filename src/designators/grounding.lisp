;;;; Referencing designators: cached lazy solution lists, REFERENCE, NEXT-SOLUTION, RESET;
;;;; action and motion designators grounded through Prolog; object and human designators.

(in-package :cram-designators)

(defvar *default-role* :default
  "The role REFERENCE passes to RESOLVE-DESIGNATOR when none is given. A projection
environment binds it (e.g. to PROJECTION-ROLE) so that object designators are resolved
against the simulated world.")

;;; Designator classes

(defclass action-designator (designator) ()
  (:documentation "Describes an action. REFERENCE grounds it through the ACTION-GROUNDING
predicate to a list (plan-function resolved-designator) or (plan-function . arguments)."))

(defclass motion-designator (designator) ()
  (:documentation "Describes a motion for a process module. REFERENCE grounds it through the
MOTION-GROUNDING predicate to a command list (command argument...)."))

(defclass object-designator (designator) ()
  (:documentation "Describes an object. Its reference is the data perception attached to it
(an OBJECT-DESIGNATOR-DATA), or what a RESOLVE-DESIGNATOR method finds for the role."))

(defclass human-designator (object-designator) ()
  (:documentation "Describes a human; referenced like an object designator."))

(macrolet ((entry-list-descriptions (&rest classes)
             `(progn
                ,@(loop for class in classes
                        collect `(defmethod normalize-designator-description
                                     ((designator ,class) description)
                                   (normalize-description description))))))
  ;; these designators are described by (KEY VALUE...) entries only
  (entry-list-descriptions action-designator motion-designator object-designator))

(register-designator-class :action 'action-designator)
(register-designator-class :motion 'motion-designator)
(register-designator-class :object 'object-designator)
(register-designator-class :human 'human-designator)

(defclass object-designator-data ()
  ((object-identifier :initarg :object-identifier :initform nil :reader object-identifier)
   (pose :initarg :pose :initform nil :reader object-pose))
  (:documentation "What perception knows about an object: its identifier (the name of the
object in the belief state) and its pose."))

(defmethod print-object ((data object-designator-data) stream)
  (print-unreadable-object (data stream :type t)
    (format stream "~s" (object-identifier data))))

(setf (documentation 'object-identifier 'function)
      "The identifier (name in the belief state) stored in an OBJECT-DESIGNATOR-DATA, or of the
data an object designator references."
      (documentation 'object-pose 'function)
      "The pose stored in an OBJECT-DESIGNATOR-DATA (or the data of an object designator).")

(defmethod object-identifier ((designator object-designator))
  "The object identifier of the data an object designator references."
  (object-identifier (reference designator)))

(defmethod object-pose ((designator object-designator))
  (object-pose (reference designator)))

;;; Solutions

(defgeneric compute-solutions (designator)
  (:documentation "The (lazy) list of all groundings of DESIGNATOR, best first."))

(defgeneric no-solution-error (designator)
  (:documentation "Signal the error for a DESIGNATOR that has no grounding at all.")
  (:method ((designator designator))
    (designator-error designator "it has no solution.")))

(defun ensure-solutions (designator)
  "The cached lazy solution list of DESIGNATOR, computed at the first call."
  (with-slots (lock solutions solutions-ready) designator
    (sb-thread:with-recursive-lock (lock)
      (unless solutions-ready
        (setf solutions (compute-solutions designator)
              solutions-ready t))
      solutions)))

(defun designator-solutions (designator)
  "The lazy list of every grounding of DESIGNATOR, computed once and shared with REFERENCE
and NEXT-SOLUTION. Beware of FORCE-LL on location designators with infinite generators."
  (check-designator designator 'designator-solutions)
  (ensure-solutions designator))

(defgeneric reference (designator &optional role)
  (:documentation "Ground DESIGNATOR and return the result, computing it at the first call and
caching it (calls are serialised per designator). Actions give (plan-function
resolved-designator), motions (command argument...), locations a pose, objects their data.
ROLE selects how object designators are resolved. Signals DESIGNATOR-ERROR when there is no
grounding."))

(defmethod reference ((designator t) &optional role)
  (declare (ignore role))
  (error 'designator-error :designator designator
                           :reason (format nil "REFERENCE: expected a designator (made with A, AN ~
or MAKE-DESIGNATOR), got ~s" designator)))

(defun check-grounding-failed (designator solution)
  "Signal a DESIGNATOR-ERROR when SOLUTION, the first grounding of DESIGNATOR, is a list
\(GROUNDING-FAILED ...) by which a grounding rule reports why it cannot ground DESIGNATOR."
  (when (and (consp solution) (symbolp (car solution)) (car solution)
             (string= (symbol-name (car solution)) "GROUNDING-FAILED"))
    (error 'designator-error
           :designator designator
           :reason (let ((*print-length* 10) (*print-level* 4))
                     (format nil "the designator cannot be grounded: ~{~a~^ ~}"
                             (mapcar (lambda (x) (if (typep x '(or string condition)) (princ-to-string x) (format nil "~s" x)))
                                     (cdr solution)))))))

(defun check-location-pose-property (designator)
  "Signal a DESIGNATOR-ERROR when the location DESIGNATOR has a POSE property that is an atom
other than a pose (a CL-TRANSFORMS:POSE, stamped or not): a string, a number, a symbol."
  (when (typep designator 'location-designator)
    (let ((pose (second (find-if (lambda (entry)
                                   (and (consp entry) (symbolp (car entry))
                                        (string= (symbol-name (car entry)) "POSE")))
                                 (description designator)))))
      ;; lists (((x y z) (qx qy qz qw)) and what custom generators read) are left to the
      ;; generators; an atom other than a pose object (a string, number, symbol) is never one
      (when (and pose (atom pose) (not (typep pose 'cl-transforms:pose)))
        (error 'designator-error
               :designator designator
               :reason (format nil "the location's (pose ~s) is not a pose; expected a ~
CL-TRANSFORMS:POSE or POSE-STAMPED" pose))))))

(defmethod reference ((designator designator) &optional role)
  (declare (ignore role))
  (check-location-pose-property designator)
  (with-slots (lock data effective) designator
    (sb-thread:with-recursive-lock (lock)
      (if effective
          data
          (let ((solutions (ensure-solutions designator)))
            (when (null solutions)
              (no-solution-error designator))
            (check-grounding-failed designator (car solutions))
            (setf (designator-data designator) (car solutions))
            (car solutions))))))

(defgeneric next-solution (designator)
  (:documentation "A new designator, equated after DESIGNATOR's chain, whose reference is the
solution after DESIGNATOR's own one; NIL when there is none."))

(defmethod next-solution ((designator t))
  (error 'designator-error :designator designator
                           :reason (format nil "NEXT-SOLUTION: expected a designator, got ~s"
                                           designator)))

(defmethod next-solution ((designator designator))
  (reference designator)
  (let ((rest (with-slots (lock solutions) designator
                (sb-thread:with-recursive-lock (lock)
                  (and solutions (lazy-cdr solutions))))))
    (when rest
      (let ((next (%make-designator (designator-type designator) (description designator)
                                    :quantifier (quantifier designator))))
        ;; designators walking the same lazy solution list share one lock, so that the list
        ;; is never expanded by two threads at once
        (setf (slot-value next 'lock) (slot-value designator 'lock)
              (slot-value next 'solutions) rest
              (slot-value next 'solutions-ready) t
              (designator-data next) (car rest))
        (equate designator next)
        next))))

(defun reset (designator)
  "A fresh designator with DESIGNATOR's description and no cached solutions, equated after
DESIGNATOR's chain. Returns it."
  (check-designator designator 'reset)
  (let ((fresh (%make-designator (designator-type designator) (description designator)
                                 :quantifier (quantifier designator))))
    (equate designator fresh)
    fresh))

;;; Actions and motions

(defvar *grounding-goals* '()
  "(predicate . goal): the goal (PREDICATE ?DESIGNATOR ?GROUNDING) PROLOG-SOLUTIONS asks with
?DESIGNATOR bound, one object per predicate, so that Prolog compiles it once.")

(defun grounding-goal (predicate)
  "The goal (PREDICATE ?DESIGNATOR ?GROUNDING), the same object for the same PREDICATE."
  (or (cdr (assoc predicate *grounding-goals* :test #'eq))
      (let ((goal (list predicate '?designator '?grounding)))
        (setf *grounding-goals* (acons predicate goal *grounding-goals*))
        goal)))

(defun prolog-solutions (designator predicate &optional check)
  "The lazy list of the ?GROUNDING values of (PREDICATE ?DESIGNATOR ?GROUNDING) with ?DESIGNATOR
bound to DESIGNATOR, each passed to CHECK (when given) as it is read."
  (lazy-mapcar (lambda (bindings)
                 (let ((value (var-value '?grounding bindings)))
                   (when check (funcall check value))
                   value))
               (prolog (grounding-goal predicate) `((?designator . ,designator)))))

(defmethod compute-solutions ((designator action-designator))
  (prolog-solutions designator 'action-grounding
                    (lambda (value)
                      (unless (and (consp value) (or (symbolp (car value)) (functionp (car value)))
                                   (car value))
                        (designator-error designator "ACTION-GROUNDING gave ~s: expected a list ~
                          (plan-function resolved-designator) or (plan-function argument...)."
                                          value)))))

(defmethod no-solution-error ((designator action-designator))
  (designator-error designator "no ACTION-GROUNDING rule matches it: check its TYPE (~s) and ~
                                the properties that action expects."
                    (desig-prop-value designator :type)))

(defmethod compute-solutions ((designator motion-designator))
  (prolog-solutions designator 'motion-grounding
                    (lambda (value)
                      (unless (and (consp value) (symbolp (car value)) (car value))
                        (designator-error designator "MOTION-GROUNDING gave ~s: expected a ~
                                                      command list (command argument...)."
                                          value)))))

(defmethod no-solution-error ((designator motion-designator))
  (designator-error designator "no MOTION-GROUNDING rule matches it: check its TYPE (~s) and ~
                                the properties that motion expects."
                    (desig-prop-value designator :type)))

;;; Objects and humans

(defgeneric resolve-designator (designator role)
  (:documentation "Find the reference of an object or human DESIGNATOR that perception has not
grounded, for ROLE (see *DEFAULT-ROLE*). Layers add methods, e.g. a world lookup by :NAME in
projection. Returns the data, or NIL when nothing is found.")
  (:method ((designator designator) role)
    (declare (ignore role))
    nil))

(defmethod compute-solutions ((designator object-designator))
  (let ((effective (newest-effective-designator designator)))
    (if effective
        (list (designator-data effective))
        (let ((data (resolve-designator designator *default-role*)))
          (and data (list data))))))

(defmethod reference ((designator object-designator) &optional (role *default-role*))
  (with-slots (lock data effective) designator
    (sb-thread:with-recursive-lock (lock)
      (if effective
          data
          (let ((found (let ((newest (newest-effective-designator designator)))
                         (if newest
                             (designator-data newest)
                             (resolve-designator designator role)))))
            (unless found
              (designator-error designator "it has no data: object designators are grounded ~
                by perception (a DETECTING motion or action) or by a RESOLVE-DESIGNATOR method ~
                for the role ~s, and none applied." role))
            (setf (designator-data designator) found))))))
