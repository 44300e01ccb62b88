;;;; CRAM's RETE API: a working memory of facts, productions (conjunctions of patterns) and
;;;; handlers called when a production starts or stops to hold. A change of the working memory
;;;; re-matches only the productions that have a pattern the changed fact fits, and reports the
;;;; difference between their old and new matches.

(in-package :cram-prolog)

(defvar *working-memory* (make-hash-table :test 'equal)
  "The facts RETE-ASSERT added (fact → T).")

(defvar *working-memory-lock* (sb-thread:make-mutex :name "rete working memory")
  "Serialises changes of the working memory and the calls of production handlers.")

(defstruct (production (:constructor make-production (name patterns)))
  "A production: NAME, its PATTERNS (terms whose ?variables are bound across them), the
handlers registered for it and the matches found last (a list of (facts . bindings))."
  name patterns (handlers '()) (matches '()) (active nil))

(defvar *productions* (make-hash-table :test 'eq) "Production name → PRODUCTION.")

(defun check-fact (fact function)
  (unless (and (consp fact) (alexandria:proper-list-p fact))
    (prolog-error "~s: the fact ~s is not a list (functor argument...)." function fact)))

(defun working-memory-facts ()
  (loop for fact being the hash-keys of *working-memory* collect fact))

(defun alpha-network-size ()
  "The number of facts in the working memory."
  (hash-table-count *working-memory*))

(defun clear-alpha-network ()
  "Remove every fact from the working memory (no handler is called) and forget the matches of
the productions."
  (sb-thread:with-recursive-lock (*working-memory-lock*)
    (clrhash *working-memory*)
    (loop for p being the hash-values of *productions* do (setf (production-matches p) '())))
  t)

(defun prolog-pattern-p (pattern)
  "True when PATTERN is proved by Prolog (its functor has clauses or a handler) rather than
matched against the working memory."
  (let ((functor (car pattern)))
    (and (symbolp functor) (not (is-var functor))
         (let ((pred (gethash functor *predicates*)))
           (and pred (or (pred-sources pred) (pred-dynamic pred) (pred-handler pred)
                         (pred-native pred) (pred-control pred))
                t)))))

(defun match-patterns (patterns bindings)
  "Every way the PATTERNS match the working memory (Prolog patterns are proved) under BINDINGS:
a list of (facts . bindings), FACTS the working-memory facts matched, in order."
  (if (null patterns)
      (list (cons '() bindings))
      (let ((pattern (first patterns)))
        (if (prolog-pattern-p pattern)
            (loop for solution in (force-ll (prolog pattern bindings))
                  append (loop for (facts . b) in (match-patterns (rest patterns)
                                                                  (append solution bindings))
                               collect (cons facts b)))
            (loop for fact in (working-memory-facts)
                  append (multiple-value-bind (b ok) (unify pattern fact bindings)
                           (when ok
                             (loop for (facts . b2) in (match-patterns (rest patterns) b)
                                   collect (cons (cons fact facts) b2)))))))))

(defun production-bindings (production bindings)
  "The keyword arguments of a handler call: :?VAR value for each variable of PRODUCTION."
  (loop for var in (vars-in (production-patterns production))
        append (list (intern (symbol-name var) :keyword) (var-value var bindings))))

(defun call-handlers (production operation bindings)
  (dolist (handler (production-handlers production))
    (apply handler operation (production-bindings production bindings))))

(defun rematch-production (production)
  "Match PRODUCTION afresh; call its handlers with :ASSERT for new matches and :RETRACT for
vanished ones."
  (let* ((old (production-matches production))
         (new (match-patterns (production-patterns production) '())))
    (setf (production-matches production) new)
    (dolist (m old)
      (unless (member (car m) new :key #'car :test #'equal)
        (call-handlers production :retract (cdr m))))
    (dolist (m new)
      (unless (member (car m) old :key #'car :test #'equal)
        (call-handlers production :assert (cdr m))))))

(defun affected-productions (fact)
  (loop for p being the hash-values of *productions*
        when (and (production-active p)
                  (some (lambda (pattern) (nth-value 1 (unify pattern fact)))
                        (production-patterns p)))
          collect p))

(defun rete-assert (fact)
  "Add FACT (a list) to the working memory; the productions it completes call their handlers
with :ASSERT. Returns FACT."
  (check-fact fact 'rete-assert)
  (sb-thread:with-recursive-lock (*working-memory-lock*)
    (unless (gethash fact *working-memory*)
      (setf (gethash (copy-tree fact) *working-memory*) t)
      (mapc #'rematch-production (affected-productions fact))))
  fact)

(defun rete-retract (fact)
  "Remove FACT from the working memory; the productions that held through it call their handlers
with :RETRACT. Returns FACT."
  (check-fact fact 'rete-retract)
  (sb-thread:with-recursive-lock (*working-memory-lock*)
    (when (remhash fact *working-memory*)
      (mapc #'rematch-production (affected-productions fact))))
  fact)

(defmacro with-facts-asserted ((&rest facts) &body body)
  "Evaluate BODY with the FACTS (evaluated) asserted into the working memory; they are
retracted when BODY is left."
  (let ((list (gensym "FACTS")))
    `(let ((,list (list ,@facts)))
       (unwind-protect
            (progn (mapc #'rete-assert ,list) ,@body)
         (mapc #'rete-retract ,list)))))

(defun rete-prove (patterns &optional bindings)
  "The solutions (a list of binding alists for the variables of PATTERNS) of the conjunction
PATTERNS against the working memory (patterns of Prolog predicates are proved by Prolog)."
  (unless (and (listp patterns) (every #'consp patterns))
    (prolog-error "RETE-PROVE: ~s is not a list of patterns." patterns))
  (sb-thread:with-recursive-lock (*working-memory-lock*)
    (remove-duplicates
     (loop for (nil . b) in (match-patterns patterns bindings)
           collect (filter-bindings patterns b bindings))
     :test #'equal :from-end t)))

(def-prolog-handler rete-holds (bindings ?fact)
  (sb-thread:with-recursive-lock (*working-memory-lock*)
    (loop for fact in (working-memory-facts)
          for (b ok) = (multiple-value-list (unify ?fact fact bindings))
          when ok collect b)))

(defvar *object-ids* (make-hash-table :test 'eq :weakness :key :synchronized t)
  "Object → its number (OBJECT-ID).")
(defvar *next-object-id* 0)

(defun object-id (object)
  "A number that stays the same for OBJECT (compared with EQ) while it lives, for facts about
objects."
  (or (gethash object *object-ids*)
      (sb-thread:with-recursive-lock (*working-memory-lock*)
        (or (gethash object *object-ids*)
            (setf (gethash object *object-ids*) (incf *next-object-id*))))))

;;; Productions

(defun register-production (name patterns)
  "Define (or redefine) the production NAME as the conjunction of PATTERNS."
  (unless (and name (symbolp name))
    (prolog-error "REGISTER-PRODUCTION: the name ~s is not a symbol." name))
  (unless (and (consp patterns) (every (lambda (p) (and (consp p) (alexandria:proper-list-p p)))
                                       patterns))
    (prolog-error "REGISTER-PRODUCTION ~s: ~s is not a non-empty list of patterns." name patterns))
  (sb-thread:with-recursive-lock (*working-memory-lock*)
    (setf (gethash name *productions*) (make-production name patterns)))
  name)

(defmacro def-production (name &body patterns)
  "Define the production NAME: the conjunction of PATTERNS (not evaluated)."
  `(register-production ',name ',patterns))

(defun find-production (name function)
  (or (gethash name *productions*)
      (prolog-error "~s: there is no production named ~s." function name)))

(defun remove-production (name)
  "Forget the production NAME. True when it existed."
  (sb-thread:with-recursive-lock (*working-memory-lock*)
    (and (remhash name *productions*) t)))

(defun clear-productions ()
  "Forget every production."
  (sb-thread:with-recursive-lock (*working-memory-lock*)
    (clrhash *productions*))
  t)

(defmacro with-productions ((&rest productions) &body body)
  "Evaluate BODY with the PRODUCTIONS ((name pattern...) ...) defined (shadowing productions of
those names); afterwards the productions are as before."
  `(let ((*productions* (alexandria:copy-hash-table *productions*)))
     ,@(loop for (name . patterns) in productions
             collect `(register-production ',name ',patterns))
     ,@body))

(defun register-production-handler (name handler)
  "Call HANDLER, a function (operation &key ?var... &allow-other-keys), with :ASSERT whenever the
production NAME starts to hold for some values of its variables and with :RETRACT when it stops
to; the matches that hold when it is registered are reported with :ASSERT at once."
  (unless (functionp handler)
    (prolog-error "REGISTER-PRODUCTION-HANDLER: ~s is not a function." handler))
  (sb-thread:with-recursive-lock (*working-memory-lock*)
    (let ((production (find-production name 'register-production-handler)))
      (pushnew handler (production-handlers production))
      (if (production-active production)
          (dolist (m (production-matches production))
            (apply handler :assert (production-bindings production (cdr m))))
          (progn (setf (production-active production) t
                       (production-matches production) '())
                 (rematch-production production)))
      name)))

(defun remove-production-handler (name handler)
  "Stop calling HANDLER for the production NAME."
  (sb-thread:with-recursive-lock (*working-memory-lock*)
    (let ((production (find-production name 'remove-production-handler)))
      (setf (production-handlers production) (remove handler (production-handlers production)))
      (unless (production-handlers production)
        (setf (production-active production) nil (production-matches production) '()))
      name)))

(defmacro with-production-handlers ((&rest handlers) &body body)
  "Evaluate BODY with HANDLERS ((production-name lambda-list form...) ...) registered (see
REGISTER-PRODUCTION-HANDLER); they are removed when BODY is left."
  (let ((names (loop for h in handlers collect (gensym (format nil "~a-HANDLER" (first h))))))
    `(let ,(loop for (nil lambda-list . forms) in handlers for n in names
                 collect `(,n (lambda ,lambda-list ,@forms)))
       (unwind-protect
            (progn ,@(loop for h in handlers for n in names
                           collect `(register-production-handler ',(first h) ,n))
                   ,@body)
         ,@(loop for h in handlers for n in names
                 collect `(remove-production-handler ',(first h) ,n))))))

(setf (documentation 'rete-holds 'function)
      "Prolog predicate (rete-holds ?fact): ?fact unifies with a fact of the working memory.")
