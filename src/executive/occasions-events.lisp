;;;; Events and occasions: the ON-EVENT hook several layers add handlers to, HOLDS for
;;;; occasion terms, and the event classes and occasion predicates plans use.

(in-package :cram-occasions-events)

(defclass event ()
  ((timestamp :initarg :timestamp :reader event-timestamp
              :initform (multiple-value-bind (s us) (sb-ext:get-time-of-day)
                          (+ s (/ us 1d6)))))
  (:documentation "The root class of events that plans fire with ON-EVENT."))

(setf (documentation 'event-timestamp 'function)
      "Unix time (seconds, double) at which the event was made.")

(defgeneric on-event (event)
  (:method-combination desig:hooks)
  (:documentation "Fire EVENT: every applicable handler runs (most specific class first) and
the list of their values is returned. Layers add handlers with a qualifier naming them, so
handlers from different places for the same class all run:
  (defmethod coe:on-event attach-in-belief ((event cpoe:object-attached-robot)) ...)")
  (:method no-handler ((event event)) nil))

(defmethod on-event :around ((event t))
  (unless (typep event 'event)
    (error "ON-EVENT: expected an event (an instance of COE:EVENT), got ~s." event))
  (call-next-method))

(defgeneric clear-belief ()
  (:method-combination desig:hooks)
  (:documentation "Reset the robot's belief state: every layer's handler runs (the Bullet
belief state, for instance, makes a fresh world). Add handlers with a qualifier naming them:
(defmethod coe:clear-belief my-layer () ...).")
  (:method no-handler () nil))

(define-condition occasion-functor-error (error)
  ((occasion :initarg :occasion :reader occasion-functor-error-occasion))
  (:report (lambda (condition stream)
             (format stream "HOLDS: expected an occasion term (functor argument...), got ~s."
                     (occasion-functor-error-occasion condition))))
  (:documentation "Signalled when HOLDS is given something that is not an occasion term."))

(prolog:def-fact-group occasions (holds)
  (prolog:<- (holds ?occasion)
    (prolog:call ?occasion))
  (prolog:<- (holds ?occasion ?time-specification)
    (prolog:fail)))

(defun normalize-occasion (occasion)
  "OCCASION with a keyword functor replaced by the CPOE occasion symbol of the same name, as
designator macros turn symbols into keywords."
  (unless (and (consp occasion) (symbolp (car occasion)) (car occasion))
    (error 'occasion-functor-error :occasion occasion))
  (if (keywordp (car occasion))
      (let ((symbol (find-symbol (symbol-name (car occasion)) :cram-plan-occasions-events)))
        (if symbol (cons symbol (cdr occasion)) occasion))
      occasion))

(defun holds (occasion &optional (time-specification nil time-p))
  "Prove the occasion term OCCASION, e.g. (cpoe:object-in-hand ?obj :right), in the belief
state; with TIME-SPECIFICATION, at that time (layers with a timeline extend (HOLDS occasion
time)). Returns the lazy list of solutions: NIL when it does not hold."
  (let ((occasion (normalize-occasion occasion)))
    (prolog:prolog (if time-p
                       `(holds ,occasion ,time-specification)
                       `(holds ,occasion)))))
