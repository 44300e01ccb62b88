;;;; First-goal guards: an index of clauses by the first goal of their bodies. A clause whose
;;;; first argument is a variable and whose body begins by testing that variable with a guard
;;;; predicate (e.g. (desig-prop ?designator (:type :going))) cannot succeed for a call whose
;;;; first argument the guard rejects; a predicate's entry passes such clauses over without
;;;; matching their heads. The designators layer registers DESIG-PROP, so that a grounding or
;;;; process-module rule written for one designator type costs nothing for the others.

(in-package :cram-prolog)

(defstruct (first-goal-guard (:constructor make-first-goal-guard (functor pattern-key object-key)))
  "A guard predicate FUNCTOR: PATTERN-KEY maps the arguments of a guard goal after the tested
variable (source terms) to the key the goal requires, or NIL when the goal is not indexable;
OBJECT-KEY maps a call's first argument (an atom or a Lisp object, never a variable or a cons)
to its key, or :ALL when the guard may accept it whatever the key."
  (functor nil :type symbol)
  (pattern-key nil :type function)
  (object-key nil :type function))

(defvar *first-goal-guards* '()
  "The registered first-goal guards (REGISTER-FIRST-GOAL-GUARD), one per functor.")

(defun register-first-goal-guard (functor pattern-key object-key)
  "Make FUNCTOR (a predicate symbol) a first-goal guard. A clause with a variable first argument
?X whose body begins with (FUNCTOR ?X . args) is tried only for calls whose first argument has
the key (funcall PATTERN-KEY args) (when that is not NIL). The key of a call's first argument
is (funcall OBJECT-KEY argument): :ALL for an argument it does not know, NIL for one that no
guard goal accepts. Keys compare with EQUAL. The promise behind it: the guard goal fails
whenever the two keys differ. Every predicate selects its clauses anew."
  (check-type functor symbol)
  (let ((guard (make-first-goal-guard functor (coerce pattern-key 'function)
                                      (coerce object-key 'function))))
    (with-database-lock ()
      (setf *first-goal-guards*
            (cons guard (remove functor *first-goal-guards* :key #'first-goal-guard-functor)))
      (reselect-all-clauses))
    functor))

(defun reselect-all-clauses ()
  "Make every predicate defined by clauses select them anew on its next call (after the guards
changed)."
  (with-database-lock ()
    (maphash (lambda (functor pred)
               (declare (ignore functor))
               (unless (or (pred-native pred) (pred-control pred))
                 (invalidate-pred pred)))
             *predicates*)))

(defun clause-guard (clause)
  "(values guard key) of CLAUSE's first body goal when it is a registered guard testing the
clause's variable first argument with an indexable pattern; NIL otherwise."
  (destructuring-bind (head &rest body) (clause-source clause)
    (let ((var (and (consp (cdr head)) (cadr head)))
          (goal (first body)))
      (when (and (source-var-p var) (not (anonymous-var-p var))
                 (consp goal) (symbolp (car goal)) (consp (cdr goal)) (eq (cadr goal) var))
        (let ((guard (find (car goal) *first-goal-guards* :key #'first-goal-guard-functor)))
          (when guard
            (let ((key (funcall (first-goal-guard-pattern-key guard) (cddr goal))))
              (and key (values guard key)))))))))

(defun guard-selection (var-clauses)
  "NIL when none of VAR-CLAUSES (the clauses with a variable first argument, in order) is
guarded; else the function of a call's first argument (an atom or object) returning those of
VAR-CLAUSES its guards do not rule out, in order."
  (let* ((guards (mapcar (lambda (c) (multiple-value-list (clause-guard c))) var-clauses))
         (guard (first (find-if #'first guards))))
    ;; one guard predicate per index: the clauses guarded by another are kept as unguarded
    (when guard
      (let* ((keys (mapcar (lambda (g) (and (eq (first g) guard) (second g))) guards))
             (distinct (remove-duplicates (remove nil keys) :test #'equal :from-end t))
             (unguarded (loop for c in var-clauses for k in keys unless k collect c))
             (buckets (mapcar (lambda (key)
                                (cons key (loop for c in var-clauses for k in keys
                                                when (or (null k) (equal k key)) collect c)))
                              distinct))
             (object-key (first-goal-guard-object-key guard)))
        (lambda (a)
          (let ((key (funcall object-key a)))
            (if (eq key :all)
                var-clauses
                (let ((bucket (assoc key buckets :test #'equal)))
                  (if bucket (cdr bucket) unguarded)))))))))
