;;;; MAN-INT's object knowledge in context: where objects of a type are likely to be and where
;;;; they go, per environment, human and context.  Methods are written for object types; a
;;;; call for a type without a method of its own uses its nearest supertype that has one.

(in-package :cram-manipulation-interfaces)

(define-condition no-object-knowledge (manipulation-knowledge-error) ()
  (:documentation "Signalled when neither an object type nor any of its supertypes has a
method of an object knowledge generic for the given context."))

(defun check-knowledge-arguments (function object-type context)
  (unless (and (keywordp object-type) object-type)
    (knowledge-error "~(~a~): the object type is ~s, expected a keyword such as :BOWL."
                     function object-type))
  (unless (symbolp context)
    (knowledge-error "~(~a~): the context is ~s, expected a keyword such as :TABLE-SETTING."
                     function context)))

(defun types-with-methods (generic context)
  "The object types for which GENERIC has a method (for CONTEXT when it specialises on one)."
  (let ((types '()))
    (dolist (method (sb-mop:generic-function-methods generic) (sort types #'string<))
      (destructuring-bind (type-spec &optional e h context-spec) (method-eql-specs method)
        (declare (ignore e h))
        (when (and type-spec (or (null context-spec) (eq context-spec context)))
          (pushnew type-spec types))))))

(defun method-eql-specs (method)
  "The EQL specialiser objects of METHOD's arguments (NIL where it is not an EQL specialiser)."
  (mapcar (lambda (s) (and (typep s 'sb-mop:eql-specializer) (sb-mop:eql-specializer-object s)))
          (sb-mop:method-specializers method)))

(defun most-specific-type-method (generic object-type environment human context)
  "The nearest of OBJECT-TYPE and its supertypes for which GENERIC has a method specialised on
that type and applicable to ENVIRONMENT, HUMAN and CONTEXT; NIL when there is none."
  (loop for type in (object-type-supertypes object-type)
        when (some (lambda (m) (eql (first (method-eql-specs m)) type))
                   (compute-applicable-methods generic (list type environment human context)))
          return type))

(defvar *requested-object-type* nil
  "The object type a GET-OBJECT-LIKELY-LOCATION or GET-OBJECT-DESTINATION call asked about,
while a method of one of its supertypes answers it.")

(defun requested-object-type (type)
  "The object type the current knowledge call asked about (e.g. :SPOON while the :CUTLERY
method answers), else TYPE."
  (or *requested-object-type* type))

(defun call-with-type-dispatch (generic name object-type environment human context)
  (check-knowledge-arguments name object-type context)
  (let ((type (most-specific-type-method generic object-type environment human context)))
    (unless type
      (error 'no-object-knowledge
             :format-control "~(~a~): no knowledge of ~s~@[ (nor of its supertypes ~{~s~^, ~})~] ~
                              in the context ~s; types known in that context: ~{~s~^, ~}."
             :format-arguments (list name object-type (rest (object-type-supertypes object-type))
                                     context (types-with-methods generic context))))
    (let ((*requested-object-type* object-type))
      (funcall generic type environment human context))))

(defgeneric get-object-likely-location (object-type environment human context)
  (:documentation "A location designator for where an object of OBJECT-TYPE (a keyword) is
likely to be found in ENVIRONMENT (the environment's name, e.g. :IAI-KITCHEN) for HUMAN (or
NIL) in CONTEXT (e.g. :TABLE-SETTING, :TABLE-CLEANING). Methods specialise OBJECT-TYPE with
EQL; a type without a method uses its nearest supertype with one; with none, a
NO-OBJECT-KNOWLEDGE error.")
  (:method (object-type environment human context)
    (call-with-type-dispatch #'get-object-likely-location 'get-object-likely-location
                             object-type environment human context)))

(defgeneric get-object-destination (object-type environment human context)
  (:documentation "A location designator for where an object of OBJECT-TYPE (a keyword) goes
in ENVIRONMENT for HUMAN in CONTEXT (e.g. :TABLE-SETTING: on the table; :TABLE-CLEANING: back
or into the dishwasher). Dispatch on the type as GET-OBJECT-LIKELY-LOCATION.")
  (:method (object-type environment human context)
    (call-with-type-dispatch #'get-object-destination 'get-object-destination
                             object-type environment human context)))
