;;;; The designator protocol: classes, descriptions, equation chains, errors and printing.

(in-package :cram-designators)

;;; A method combination for hooks: every applicable method runs (most specific first) and the
;;; list of their values is returned. Methods may carry any qualifiers, so several layers can add
;;; handlers for the same class by giving each handler its own qualifier name.

(define-method-combination hooks ()
  ((methods *))
  "Run every applicable method, whatever its qualifiers, most specific first; return the list
of the primary values. Layers add independent handlers by naming them with a qualifier, as in
(defmethod on-event my-handler ((event some-event)) ...). :AROUND methods wrap the whole
call as usual."
  (flet ((around-p (method) (equal (method-qualifiers method) '(:around))))
    (let* ((around (remove-if-not #'around-p methods))
           (primary (remove-if #'around-p methods))
           (form `(list ,@(mapcar (lambda (method) `(call-method ,method)) primary))))
      (if around
          `(call-method ,(first around) (,@(rest around) (make-method ,form)))
          form))))

;;; Conditions

(define-condition designator-error (error)
  ((designator :initarg :designator :initform nil :reader designator-error-designator)
   (reason :initarg :reason :initform "" :reader designator-error-reason))
  (:report (lambda (condition stream)
             (let ((*print-length* 20) (*print-level* 6))
               (format stream "Designator error: ~a~%Designator: ~s"
                       (designator-error-reason condition)
                       (designator-error-designator condition)))))
  (:documentation "Signalled when a designator cannot be built or referenced: no grounding,
no data, a malformed description. DESIGNATOR-ERROR-DESIGNATOR is the offending designator
and DESIGNATOR-ERROR-REASON a text saying what was expected."))

(setf (documentation 'designator-error-designator 'function)
      "The designator a DESIGNATOR-ERROR is about."
      (documentation 'designator-error-reason 'function)
      "The text of a DESIGNATOR-ERROR saying what went wrong.")

(define-condition location-resolution-error (designator-error) ()
  (:documentation "A DESIGNATOR-ERROR signalled when no generated location solution passes
the validators (or the retry cap ended the search)."))

(defun designator-error (designator format-control &rest format-arguments)
  "Signal a DESIGNATOR-ERROR about DESIGNATOR with a reason built by FORMAT."
  (error 'designator-error :designator designator
                           :reason (apply #'format nil format-control format-arguments)))

;;; Class registry

(defvar *designator-classes* '()
  "Alist (type-keyword . class-name) of the registered designator classes.")

(defun %register-designator-class (type class-name)
  "REGISTER-DESIGNATOR-CLASS of the symbols TYPE and CLASS-NAME."
  (unless (and type (symbolp type))
    (error "REGISTER-DESIGNATOR-CLASS: the designator type ~s is not a symbol." type))
  (unless (and class-name (symbolp class-name))
    (error "REGISTER-DESIGNATOR-CLASS: the class name ~s is not a symbol." class-name))
  (let ((type (intern (symbol-name type) :keyword)))
    (setf *designator-classes*
          (append (remove type *designator-classes* :key #'car)
                  (list (cons type class-name))))
    type))

(defmacro register-designator-class (type class-name)
  "Register CLASS-NAME (a subclass of DESIGNATOR) as the class of the designators of TYPE (e.g.
:ACTION, or a symbol of any package, taken by its name), so that MAKE-DESIGNATOR makes them. As
in CRAM the arguments are not evaluated (a quoted symbol is accepted too). A later registration
of the same TYPE replaces the earlier one. Returns the type keyword."
  (flet ((literal (x) (if (and (consp x) (eq (car x) 'quote)) (second x) x)))
    `(%register-designator-class ',(literal type) ',(literal class-name))))

(defun find-designator-class (type &optional (errorp t))
  "The class name registered for TYPE (a symbol in any package, compared by name). With
ERRORP, an unknown type signals an error listing the known types; otherwise NIL."
  (let ((entry (or (assoc type *designator-classes*)
                   (and (or (symbolp type) (stringp type))
                        (assoc (string type) *designator-classes*
                               :key #'symbol-name :test #'string=)))))
    (cond (entry (cdr entry))
          (errorp (error "Unknown designator type ~s: expected one of ~{~(~a~)~^, ~}."
                         type (mapcar #'car *designator-classes*)))
          (t nil))))

;;; The designator class

(defvar *chain-lock* (sb-thread:make-mutex :name "designator chains")
  "Serialises every change of a parent/successor link.")

(defun now-unix ()
  (multiple-value-bind (seconds microseconds) (sb-ext:get-time-of-day)
    (+ seconds (/ microseconds 1d6))))

(defclass designator ()
  ((description :initarg :description :initform '() :reader description)
   (quantifier :initarg :quantifier :initform :a :reader quantifier)
   (parent :initform nil :reader parent)
   (successor :initform nil :reader successor)
   ;; shortcuts along the chain: NIL, or a designator of the same chain older (FIRST-HINT) or
   ;; younger (LAST-HINT) than this one, which was the chain's first or newest when it was set
   (first-hint :initform nil)
   (last-hint :initform nil)
   (data :initform nil :reader designator-data)
   (effective :initform nil :reader effective)
   (timestamp :initform (now-unix) :reader timestamp)
   (solutions :initform nil)
   (solutions-ready :initform nil)
   (lock :initform (sb-thread:make-mutex :name "designator")))
  (:documentation "A symbolic description, an ordered list of (KEY VALUE...) entries with
keyword keys, of something the robot acts on. Designators describing the same entity are
linked into an equation chain (PARENT / SUCCESSOR); REFERENCE grounds a designator and caches
the result in its data."))

(defun data (designator)
  "The data of DESIGNATOR (CRAM's name for DESIGNATOR-DATA): the reference cached in it by
REFERENCE, or the object data perception gave it; NIL before it is grounded."
  (unless (typep designator 'designator)
    (error "DESIG:DATA: ~s is not a designator." designator))
  (designator-data designator))

(setf (documentation 'description 'function)
      "The ordered list of (KEY VALUE...) entries of a designator; keys are keywords."
      (documentation 'quantifier 'function)
      "The quantifier of a designator: :A, :AN or :ALL."
      (documentation 'parent 'function)
      "The designator this one was equated after, NIL for the first of a chain."
      (documentation 'successor 'function)
      "The next (younger) designator of the equation chain, NIL for the newest."
      (documentation 'designator-data 'function)
      "The reference cached in a designator (its grounding, or perception's object data), or NIL."
      (documentation 'effective 'function)
      "True once the designator has been grounded (its data is set)."
      (documentation 'timestamp 'function)
      "Unix time (seconds, double) at which the designator was created.")

(defun designator-p (object)
  "True when OBJECT is a designator."
  (typep object 'designator))

(defgeneric properties (designator)
  (:documentation "The description of DESIGNATOR (a list of (KEY VALUE...) entries).")
  (:method ((designator designator)) (description designator)))

(defgeneric designator-type (designator)
  (:documentation "The type keyword of DESIGNATOR's class, e.g. :ACTION or :LOCATION.")
  (:method ((designator designator))
    (or (car (rassoc (class-name (class-of designator)) *designator-classes*))
        (error "Designator class ~s is not registered." (class-name (class-of designator))))))

(defgeneric (setf designator-data) (data designator)
  (:documentation "Set the cached reference of DESIGNATOR; a non-NIL DATA makes it effective.")
  (:method (data (designator designator))
    (setf (slot-value designator 'effective) (and data t)
          (slot-value designator 'data) data)))

(defun normalize-key (key entry)
  (cond ((keywordp key) key)
        ((and (symbolp key) key (not (is-var key)))
         (intern (symbol-name key) :keyword))
        (t (error "Designator property ~s: expected a (KEY VALUE...) list with a symbol key, ~
                   got the key ~s." entry key))))

(defun normalize-description (description)
  "DESCRIPTION checked and normalised to a fresh list of (KEYWORD VALUE...) lists. A dotted
entry (KEY . VALUE) with an atomic VALUE becomes (KEY VALUE)."
  (unless (and (listp description) (null (cdr (last description))))
    (error "Designator description ~s: expected a proper list of (KEY VALUE...) entries."
           description))
  (loop for entry in description
        collect (cond ((and (consp entry) (listp (cdr entry)))
                       (cons (normalize-key (car entry) entry) (copy-list (cdr entry))))
                      ((consp entry)
                       (list (normalize-key (car entry) entry) (cdr entry)))
                      (t (error "Designator property ~s: expected a (KEY VALUE...) list."
                                entry)))))

(defgeneric normalize-designator-description (designator description)
  (:documentation "DESCRIPTION checked and normalised for the new DESIGNATOR. By default a list
is normalised to (KEYWORD VALUE...) entries and anything else (a string, a pose ...) is kept as
it is, for designator classes of one's own; the action, motion, location, object and human
designators need entry lists.")
  (:method ((designator designator) description)
    (if (listp description) (normalize-description description) description)))

(defun %make-designator (type description &key (quantifier :a) parent)
  (unless (member quantifier '(:a :an :all))
    (error "Designator quantifier ~s: expected :A, :AN or :ALL." quantifier))
  (let* ((class (find-designator-class type))
         (designator (make-instance class :quantifier quantifier)))
    (setf (slot-value designator 'description)
          (normalize-designator-description designator description))
    (when parent (equate parent designator))
    designator))

(defun description-entries (designator)
  "The (KEY VALUE...) entries of DESIGNATOR's description; none when it is not a list."
  (let ((description (description designator)))
    (if (listp description) description '())))

(defun make-designator (type description &optional parent)
  "Make a designator of TYPE (:action, :motion, :location, :object, :human or another
registered type; a symbol of any package) from DESCRIPTION, a list of (KEY VALUE...)
entries. With PARENT the new designator is equated after PARENT's chain."
  (%make-designator type description :parent parent))

;;; Property access

(defun check-designator (object what)
  (unless (typep object 'designator)
    (error "~a: expected a designator, got ~s." what object)))

(defun desig-prop-value (designator key)
  "The first value of the first entry of DESIGNATOR with KEY (a symbol, compared by name), or
NIL when there is none. The second value is true when such an entry exists."
  (check-designator designator 'desig-prop-value)
  (let ((entry (find-entry designator key)))
    (values (second entry) (and entry t))))

(defun find-entry (designator key)
  (let ((name (if (symbolp key) (symbol-name key) (error "Property key ~s: expected a symbol." key))))
    (find name (description-entries designator) :key (lambda (e) (symbol-name (car e)))
                                                 :test #'string=)))

(defun desig-prop-values (designator key)
  "The values of all entries of DESIGNATOR with KEY, in order (one per entry)."
  (check-designator designator 'desig-prop-values)
  (let ((name (symbol-name key)))
    (loop for entry in (description-entries designator)
          when (string= name (symbol-name (car entry))) collect (second entry))))

(defun merge-descriptions (old new)
  "OLD with the entries whose keys appear in NEW replaced (at the place of their first
occurrence) by NEW's entries for that key; NEW's other keys are appended."
  (let ((new-keys (remove-duplicates (mapcar #'car new)))
        (placed '())
        (result '()))
    (dolist (entry old)
      (let ((key (car entry)))
        (cond ((not (member key new-keys)) (push entry result))
              ((member key placed))
              (t (push key placed)
                 (dolist (n new) (when (eq (car n) key) (push n result)))))))
    (dolist (n new)
      (unless (member (car n) placed) (push n result)))
    (nreverse result)))

(defun copy-designator (designator &key new-description)
  "A fresh designator of DESIGNATOR's class and quantifier whose description is DESIGNATOR's
merged with NEW-DESCRIPTION (entries of NEW-DESCRIPTION replace those with the same key). The
copy is not equated with DESIGNATOR and has no data."
  (check-designator designator 'copy-designator)
  (%make-designator (designator-type designator)
                    (merge-descriptions (description designator)
                                        (normalize-description new-description))
                    :quantifier (quantifier designator)))

(defun update-designator-properties (designator new-properties)
  "A fresh designator like DESIGNATOR in which each entry whose key appears in NEW-PROPERTIES
is replaced by NEW-PROPERTIES' entries for that key (new keys are appended). Not equated."
  (copy-designator designator :new-description new-properties))

(defun extend-designator-properties (designator extra-properties)
  "A fresh designator like DESIGNATOR with EXTRA-PROPERTIES appended to its description
without merging (keys may then appear twice). Not equated."
  (check-designator designator 'extend-designator-properties)
  (%make-designator (designator-type designator)
                    (append (description designator) (normalize-description extra-properties))
                    :quantifier (quantifier designator)))

(defun make-effective-designator (parent &key new-properties data-object)
  "A fresh designator of PARENT's class whose description is PARENT's merged with
NEW-PROPERTIES and whose data is DATA-OBJECT (so it is effective). Not equated: the caller
equates it with PARENT when it describes the same entity."
  (let ((designator (copy-designator parent :new-description new-properties)))
    (setf (designator-data designator) data-object)
    designator))

;;; Equation chains

(defgeneric on-equate-designators (successor parent)
  (:method-combination hooks)
  (:documentation "Hook run after EQUATE linked SUCCESSOR behind PARENT's chain. Add handlers
with a qualifier naming them: (defmethod on-equate-designators my-name (s p) ...). Returns the
list of the handlers' values.")
  (:method no-handler ((successor designator) (parent designator)) nil))

(defmacro %chain-end (designator link hint)
  "The designator at the end of DESIGNATOR's chain that following LINK (PARENT or SUCCESSOR)
reaches, by the HINT slots (which only point that way along the same chain) where set; the
hint of DESIGNATOR is then set to it, so that the next walk is one step."
  `(let ((start ,designator))
     (let ((d start))
       (loop (let ((hint (slot-value d ',hint)))
               (cond (hint (setf d hint))
                     ((,link d) (setf d (,link d)))
                     (t (return)))))
       (unless (eq d start) (setf (slot-value start ',hint) d))
       d)))

(defun first-desig (designator)
  "The oldest designator of DESIGNATOR's equation chain."
  (check-designator designator 'first-desig)
  (%chain-end designator parent first-hint))

(defun current-desig (designator)
  "The newest designator of DESIGNATOR's equation chain."
  (check-designator designator 'current-desig)
  (%chain-end designator successor last-hint))

(defun desig-equal (designator-1 designator-2)
  "True when the two designators belong to the same equation chain."
  (eq (first-desig designator-1) (first-desig designator-2)))

(defun equate (parent successor)
  "Link SUCCESSOR's chain behind the newest designator of PARENT's chain, so that both
describe the same entity, run the ON-EQUATE-DESIGNATORS hook and return SUCCESSOR. Equating
two designators that are already equal is an error."
  (check-designator parent 'equate)
  (check-designator successor 'equate)
  (let (youngest oldest)
    (sb-thread:with-recursive-lock (*chain-lock*)
      (when (desig-equal parent successor)
        (error "Cannot equate ~s with ~s: they are already in the same equation chain."
               successor parent))
      (let ((first (first-desig parent))
            (newest (current-desig successor)))
        (setf youngest (current-desig parent)
              oldest (first-desig successor))
        (setf (slot-value youngest 'successor) oldest
              (slot-value oldest 'parent) youngest
              ;; the joined chain's ends, for the two that are no longer ends
              (slot-value oldest 'first-hint) first
              (slot-value youngest 'last-hint) newest)))
    (on-equate-designators successor parent)
    successor))

(defun get-equal-designators (designator)
  "All designators of DESIGNATOR's equation chain, oldest first."
  (loop for d = (first-desig designator) then (successor d)
        while d collect d))

(defun newest-effective-designator (designator)
  "The newest effective designator of DESIGNATOR's equation chain, or NIL when none is."
  (loop for d = (current-desig designator) then (parent d)
        while d
        when (effective d) return d))

;;; Printing

(defvar *print-depth* 0)

(defun write-property-value (entry stream)
  "Write the description ENTRY (KEY VALUE...) as CRAM prints it: the key and the values that
are symbols without package prefix or colon, other values as WRITE prints them, so keywords
inside a list value keep their colons: (TYPE BOTTLE), (ARM (:LEFT :RIGHT)), (POSE ((:POSE ...)))."
  (flet ((bare (v)
           (if (and (symbolp v) v)
               (write-string (symbol-name v) stream)
               (write v :stream stream))))
    (if (and (consp entry) (null (cdr (last entry))))
        (progn
          (write-char #\( stream)
          (loop for (v . rest) on entry
                do (bare v)
                   (when rest (write-char #\Space stream)))
          (write-char #\) stream))
        (bare entry))))

(defun designator-type-name (designator)
  "The name PRINT-OBJECT shows for DESIGNATOR's type: its type keyword's, else its class's."
  (handler-case (symbol-name (designator-type designator))
    (error () (symbol-name (class-name (class-of designator))))))

(defun write-designator (quantifier type-name description stream)
  "Write to STREAM what PRINT-OBJECT writes for a designator of QUANTIFIER, TYPE-NAME (see
DESIGNATOR-TYPE-NAME) and DESCRIPTION."
  (let ((indent (* 4 (1+ *print-depth*))))
    (format stream "#<~a ~a" (if (eq quantifier :all) "ALL" "A") type-name)
    (let ((*print-depth* (1+ *print-depth*)))
      (if (listp description)
          (dolist (entry description)
            (terpri stream)
            (loop repeat indent do (write-char #\Space stream))
            (write-property-value entry stream))
          (format stream " ~s" description)))
    (write-char #\> stream)))

(defmethod print-object ((designator designator) stream)
  (if *print-readably*
      (error 'print-not-readable :object designator)
      (write-designator (quantifier designator) (designator-type-name designator)
                        (description designator) stream))
  designator)
