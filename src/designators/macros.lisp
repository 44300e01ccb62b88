;;;; The designator construction macros A, AN and ALL.
;;;;
;;;; (an action (type picking-up) (arm ?arm) (object (an object (type bottle))))
;;;; builds at run time the description ((:type :picking-up) (:arm <value of ?arm>)
;;;; (:object #<A OBJECT (TYPE BOTTLE)>)). Inside property values:
;;;;   - a symbol starting with ? is a Lisp variable reference (it must be bound);
;;;;   - a symbol with earmuffs, *like-this*, is a reference to that special variable;
;;;;   - NIL, T and keywords stay as they are; every other symbol becomes a keyword;
;;;;   - numbers, strings and other atoms are taken as they are;
;;;;   - (a ...), (an ...) and (all ...) become nested designators;
;;;;   - (quote x), (function f) and backquoted forms are evaluated;
;;;;   - any other list is walked element by element with these same rules.
;;;; A designator form written in place of a property, (an object (type bowl)), is the property
;;;; keyed by its type, (object #<AN OBJECT (TYPE BOWL)>).
;;;; A property (when condition (key value...)...) contributes its properties only when
;;;; CONDITION (any Lisp form) evaluates to true. Symbols are never replaced by their global
;;;; values at macroexpansion time: a *special* is read when the designator is built.

(in-package :cram-designators)

(defun symbol-named-p (object &rest names)
  (and (symbolp object) object (member (symbol-name object) names :test #'string=)))

(defun earmuffed-p (symbol)
  (let ((name (symbol-name symbol)))
    (and (> (length name) 2)
         (char= (char name 0) #\*)
         (char= (char name (1- (length name))) #\*))))

(defun quasiquote-p (form)
  (and (consp form) (symbolp (car form))
       (string= (symbol-name (car form)) "QUASIQUOTE")))

(defun designator-form-p (form)
  (and (consp form) (symbol-named-p (car form) "A" "AN" "ALL")
       (consp (cdr form)) (symbolp (second form))))

(defun value-form (value)
  "The Lisp form that computes the designator property VALUE written in an A/AN/ALL form."
  (cond ((null value) nil)
        ((eq value t) t)
        ((keywordp value) value)
        ((symbolp value)
         (cond ((is-var value) value)
               ((earmuffed-p value) value)
               (t (intern (symbol-name value) :keyword))))
        ((atom value) (if (or (numberp value) (stringp value) (characterp value))
                          value
                          `(quote ,value)))
        ((designator-form-p value)
         (destructuring-bind (quantifier type &rest properties) value
           (designator-expansion (intern (symbol-name quantifier) :keyword) type properties)))
        ((member (car value) '(quote function)) value)
        ((quasiquote-p value) value)
        ((null (cdr (last value)))
         `(list ,@(mapcar #'value-form value)))
        (t `(cons ,(value-form (car value)) ,(value-form (cdr value))))))

(defun property-form (property)
  "A form computing the list of description entries PROPERTY stands for."
  (cond ((not (consp property))
         (error "Designator property ~s: expected a list (KEY VALUE...) or ~
                 (WHEN condition (KEY VALUE...)...)." property))
        ((designator-form-p property)
         ;; a designator written where a property goes, (a motion (type detecting)
         ;; (an object (type bowl))): the property (OBJECT <that designator>)
         `(list (list ,(intern (symbol-name (second property)) :keyword)
                      ,(value-form property))))
        ((eq (car property) 'when)
         (when (null (cdr property))
           (error "Designator property ~s: WHEN needs a condition form." property))
         `(if ,(second property)
              (append ,@(mapcar #'property-form (cddr property)))
              nil))
        ((or (not (symbolp (car property))) (null (car property)) (is-var (car property)))
         (error "Designator property ~s: the key must be a symbol not starting with ?, got ~s."
                property (car property)))
        (t `(list (list ,(intern (symbol-name (car property)) :keyword)
                        ,@(mapcar #'value-form (cdr property)))))))

(defun designator-type-keyword (quantifier type)
  "The type keyword for TYPE; with the quantifier :ALL a plural name (OBJECTS) is trimmed to
the registered singular. Unknown types are reported when the designator is built."
  (unless (and (symbolp type) type)
    (error "Designator type ~s: expected a symbol such as ACTION or LOCATION." type))
  (let* ((name (symbol-name type))
         (singular (and (eq quantifier :all)
                        (> (length name) 1)
                        (char-equal (char name (1- (length name))) #\S)
                        (subseq name 0 (1- (length name))))))
    (intern (if (and singular (not (find-designator-class name nil))) singular name) :keyword)))

(defun designator-expansion (quantifier type properties)
  (let ((forms (mapcar #'property-form properties)))
    `(%make-designator ,(designator-type-keyword quantifier type)
                       ,(if (every (lambda (form) (eq (car form) 'list)) forms)
                            `(list ,@(mapcar #'second forms))
                            `(append ,@forms))
                       :quantifier ,quantifier)))

(defmacro a (type &rest properties)
  "Build a designator of TYPE (ACTION, MOTION, LOCATION, OBJECT, HUMAN) from PROPERTIES,
each (KEY VALUE...) or (WHEN condition (KEY VALUE...)...). ?-symbols and *specials* in
values are evaluated, other symbols become keywords, nested (A ...)/(AN ...) forms become
designators and other lists are walked element by element."
  (designator-expansion :a type properties))

(defmacro an (type &rest properties)
  "Same as A, for types starting with a vowel: (an action (type going) ...)."
  (designator-expansion :an type properties))

(defmacro all (type &rest properties)
  "Same as A with the quantifier :ALL (a plural type name such as OBJECTS is accepted)."
  (designator-expansion :all type properties))
