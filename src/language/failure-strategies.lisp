;;;; Failure handling strategies: retry a failed plan with the next solution
;;;; of a designator or the next element of a lazy list.

(in-package :cram-common-failures)

;;; Designator hooks. The designator layer (cram-designators) defines methods
;;; on these generic functions for its designator classes, e.g.
;;;   (defmethod common-fail:designator-next-solution ((d designator))
;;;     (next-solution d))
;;; so that the strategies below work without this package depending on it.

(defgeneric designator-next-solution (designator)
  (:documentation "The designator whose reference is the next solution of
DESIGNATOR, or NIL when there is none. Methods are defined by the designator
layer; RETRY-WITH-DESIGNATOR-SOLUTIONS calls it.")
  (:method ((designator t))
    (error "COMMON-FAIL:DESIGNATOR-NEXT-SOLUTION has no method for ~s: expected a ~
            designator of a loaded designator layer (cram-designators)." designator)))

(defgeneric designator-reset (designator)
  (:documentation "Drop the cached solutions of DESIGNATOR so that it is
resolved afresh; returns the reset designator. Methods are defined by the
designator layer.")
  (:method ((designator t))
    (error "COMMON-FAIL:DESIGNATOR-RESET has no method for ~s: expected a ~
            designator of a loaded designator layer (cram-designators)." designator)))

(defgeneric designator-next-different-location-solution
    (designator distance-threshold angle-threshold)
  (:documentation "The next solution of the location DESIGNATOR whose pose is
at least DISTANCE-THRESHOLD metres or ANGLE-THRESHOLD radians away from the
current one, or NIL when there is none. Methods are defined by the designator
layer; RETRY-WITH-LOC-DESIGNATOR-SOLUTIONS calls it.")
  (:method ((designator t) distance-threshold angle-threshold)
    (declare (ignore distance-threshold angle-threshold))
    (error "COMMON-FAIL:DESIGNATOR-NEXT-DIFFERENT-LOCATION-SOLUTION has no method ~
            for ~s: expected a location designator of a loaded designator layer."
           designator)))

(defvar *default-location-distance-threshold* 0.05
  "Metres by which the next location solution must differ from the previous one.")

(defvar *default-location-angle-threshold* (/ pi 18)
  "Radians by which the next location solution must differ (if not by distance).")

(defun log-tags (namespace)
  (if (listp namespace) namespace (list namespace)))

(defun rethrow (failure-class cause)
  "Signal FAILURE-CLASS (a failure class name or NIL for none) because of CAUSE."
  (when failure-class
    (unless (and (symbolp failure-class) (find-class failure-class nil)
                 (subtypep failure-class 'condition))
      (error "Retry strategy: :RETHROW-FAILURE must name a condition class, got ~s."
             failure-class))
    (if (subtypep failure-class '(or low-level-failure high-level-failure))
        (cpl:fail failure-class
                  :description (if (typep cause 'condition)
                                   (cram-language::failure-description cause)
                                   (princ-to-string cause)))
        (cpl:fail failure-class))))

(defun check-reset-designators (designators)
  (unless (listp designators)
    (error "Retry strategy: :RESET-DESIGNATORS must be a list of designators, got ~s."
           designators))
  (mapc #'designator-reset designators))

;; Expansion shared by the two designator strategies; NEXT-FORM is the form
;; computing the next solution.
(defun expand-designator-strategy (name designator retries next-form
                                   error-object-or-string warning-namespace
                                   reset-designators rethrow-failure body)
  (unless (symbolp designator)
    (error "~s: the designator must be a variable (it is set to the next ~
            solution), got ~s." name designator))
  (let ((tags (list 'quote (log-tags warning-namespace)))
        (next (gensym "NEXT"))
        (cause (gensym "CAUSE")))
    `(let ((,cause ,error-object-or-string))
       (cpl:log-message :warn ,tags "~a" ,cause)
       (cpl:do-retry ,retries
         (let ((,next ,next-form))
           (cond (,next
                  (cpl:log-message :info ,tags "Retrying with the next solution of ~a."
                                   ',designator)
                  (setf ,designator ,next)
                  (check-reset-designators ,reset-designators)
                  ,@body
                  (cpl:retry))
                 (t
                  (cpl:log-message :warn ,tags "No more solutions of ~a to try."
                                   ',designator)))))
       (cpl:log-message :warn ,tags "Giving up retrying after: ~a" ,cause)
       (rethrow ,rethrow-failure ,cause))))

(defmacro retry-with-designator-solutions (designator retries
                                           (&key error-object-or-string
                                              (warning-namespace '(common-fail))
                                              reset-designators rethrow-failure)
                                           &body body)
  "Use inside a WITH-FAILURE-HANDLING clause. Logs ERROR-OBJECT-OR-STRING with
the tags WARNING-NAMESPACE (a symbol or list, not evaluated); then, while the
retry counter RETRIES (a WITH-RETRY-COUNTERS name) lasts and DESIGNATOR (a
variable) has a next solution (DESIGNATOR-NEXT-SOLUTION), sets DESIGNATOR to
it, resets RESET-DESIGNATORS (a list, evaluated), runs BODY and calls RETRY.
When exhausted, signals RETHROW-FAILURE (a failure class name, evaluated) if
given; otherwise returns so the failure keeps propagating."
  (expand-designator-strategy 'retry-with-designator-solutions designator retries
                              `(designator-next-solution ,designator)
                              error-object-or-string warning-namespace
                              reset-designators rethrow-failure body))

(defmacro retry-with-loc-designator-solutions
    (designator retries (&key error-object-or-string
                           (warning-namespace '(common-fail))
                           reset-designators rethrow-failure
                           (distance-threshold '*default-location-distance-threshold*)
                           (angle-threshold '*default-location-angle-threshold*))
     &body body)
  "As RETRY-WITH-DESIGNATOR-SOLUTIONS for a location DESIGNATOR, but the next
solution must lie at least DISTANCE-THRESHOLD metres (default
*DEFAULT-LOCATION-DISTANCE-THRESHOLD*, 0.05) or ANGLE-THRESHOLD radians away
from the current one (DESIGNATOR-NEXT-DIFFERENT-LOCATION-SOLUTION)."
  (expand-designator-strategy 'retry-with-loc-designator-solutions designator retries
                              `(designator-next-different-location-solution
                                ,designator ,distance-threshold ,angle-threshold)
                              error-object-or-string warning-namespace
                              reset-designators rethrow-failure body))

(defmacro retry-with-list-solutions (list retries (&key error-object-or-string
                                                     (warning-namespace '(common-fail))
                                                     rethrow-failure)
                                     &body body)
  "Use inside a WITH-FAILURE-HANDLING clause. LIST is a variable holding a
lazy list (CUT lazy lists or ordinary lists) whose first element was just
tried. Logs ERROR-OBJECT-OR-STRING; then, while the retry counter RETRIES
lasts and LIST has more elements, sets LIST to its rest (CUT:LAZY-CDR), runs
BODY (which reads the new first element) and calls RETRY. When exhausted,
signals RETHROW-FAILURE if given; otherwise returns so the failure keeps
propagating."
  (unless (symbolp list)
    (error "RETRY-WITH-LIST-SOLUTIONS: the list must be a variable, got ~s." list))
  (let ((tags (list 'quote (log-tags warning-namespace)))
        (rest (gensym "REST"))
        (cause (gensym "CAUSE")))
    `(let ((,cause ,error-object-or-string))
       (cpl:log-message :warn ,tags "~a" ,cause)
       (cpl:do-retry ,retries
         (let ((,rest (cut:lazy-cdr ,list)))
           (cond (,rest
                  (cpl:log-message :info ,tags "Retrying with the next element of ~a." ',list)
                  (setf ,list ,rest)
                  ,@body
                  (cpl:retry))
                 (t
                  (cpl:log-message :warn ,tags "No more elements of ~a to try." ',list)))))
       (cpl:log-message :warn ,tags "Giving up retrying after: ~a" ,cause)
       (rethrow ,rethrow-failure ,cause))))

(defun next-different-location-solution (designator
                                         &optional (distance-threshold
                                                    *default-location-distance-threshold*)
                                           (angle-threshold *default-location-angle-threshold*))
  "The next solution of the location DESIGNATOR whose pose is at least DISTANCE-THRESHOLD
metres or ANGLE-THRESHOLD radians away from its current one, or NIL when there is none (the
designator layer's DESIG:NEXT-DIFFERENT-LOCATION-SOLUTION, under the name CRAM's failure
handling code calls)."
  (unless (and (realp distance-threshold) (>= distance-threshold 0))
    (error "NEXT-DIFFERENT-LOCATION-SOLUTION: the distance threshold ~s is not a non-negative ~
            number of metres." distance-threshold))
  (unless (and (realp angle-threshold) (>= angle-threshold 0))
    (error "NEXT-DIFFERENT-LOCATION-SOLUTION: the angle threshold ~s is not a non-negative ~
            number of radians." angle-threshold))
  (designator-next-different-location-solution designator distance-threshold angle-threshold))
