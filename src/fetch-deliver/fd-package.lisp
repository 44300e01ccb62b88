;;;; Package CRAM-FETCH-DELIVER-PLANS (FD-PLANS): the household action layer above pick and
;;;; place — navigating, turning towards, searching, fetching, delivering and transporting.
;;;; Like CRAM's, it exports nothing: users reach it through action designators such as
;;;;   (an action (type transporting) (object (an object (type bowl))) (context table-setting))

(defpackage :cram-fetch-deliver-plans
  (:nicknames :fd-plans)
  (:use :cl :cram-prolog)
  ;; the designator helpers of the pick-and-place groundings this layer extends
  (:import-from :cram-mobile-pick-place-plans #:prop #:resolved))

(in-package :cram-fetch-deliver-plans)

(define-condition fetch-deliver-error (simple-error) ()
  (:documentation "Bad input to a fetch-and-deliver action: the message names the value and
what was expected."))

(defun fd-error (control &rest arguments)
  (error 'fetch-deliver-error :format-control control :format-arguments arguments))

(defun log-fd (level tag control &rest arguments)
  (apply #'cpl:log-message level (list 'fd-plans tag) control arguments))

(defun robot-name ()
  (pp-plans:current-robot-name))

(defun environment-name ()
  "The name of the environment object of the belief state (e.g. IAI-KITCHEN), or NIL."
  (let ((env (ignore-errors (btr:get-environment-object))))
    (and env (btr:name env))))

(defun location-designator-or-nil (value what designator)
  (cond ((null value) nil)
        ((typep value 'desig:location-designator) value)
        (t (fd-error "The ~(~a~) of ~s: expected a location designator, got ~s."
                     what designator value))))

(defun object-designator-or-error (value what designator)
  (unless (typep value 'desig:object-designator)
    (fd-error "The ~(~a~) action ~s needs an OBJECT designator, got ~s." what designator value))
  value)
