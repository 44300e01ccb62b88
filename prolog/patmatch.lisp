;;;; One-sided pattern matching (PAT-MATCH) with segment variables, and the variable helpers that
;;;; go with it: segment variables !?x match a run of list elements and bind ?x to it.

(in-package :cram-utilities)

(defun is-unnamed-var (object)
  "True when OBJECT is the unnamed variable ?_ (of any package)."
  (is-anonymous-var object))

(defun is-segvar (object)
  "True when OBJECT is a segment variable: a symbol whose name starts with !? (e.g. !?rest)."
  (and (symbolp object)
       (let ((name (symbol-name object)))
         (and (>= (length name) 2) (char= (char name 0) #\!) (char= (char name 1) #\?)))))

(defun is-segform (form)
  "True when FORM is a cons whose car is a segment variable."
  (and (consp form) (is-segvar (car form))))

(defun var-name (var)
  "The variable a pattern variable binds: VAR itself for ?x, ?x (in the package of !?x) for the
segment variable !?x. Anything else is an error."
  (cond ((is-var var) var)
        ((is-segvar var)
         (let ((name (subseq (symbol-name var) 1)) (package (symbol-package var)))
           (if package (intern name package) (make-symbol name))))
        (t (error "VAR-NAME: ~s is neither a pattern variable (?x) nor a segment variable (!?x)."
                  var))))

(defun gen-var (&optional (base "?VAR-"))
  "A fresh, uninterned pattern variable whose name starts with the string BASE (which must
start with #\\?)."
  (unless (and (stringp base) (plusp (length base)) (char= (char base 0) #\?))
    (error "GEN-VAR: the base ~s is not a string starting with #\\?." base))
  (gensym base))

(defun is-genvar (var)
  "True when the pattern variable VAR was made by GEN-VAR (it is uninterned)."
  (unless (is-var var)
    (error "IS-GENVAR: ~s is not a pattern variable." var))
  (null (symbol-package var)))

(defun map-tree (function tree)
  "A copy of the cons TREE with FUNCTION applied to every atom other than the NILs that end
lists."
  (cond ((null tree) nil)
        ((atom tree) (funcall function tree))
        (t (cons (map-tree function (car tree)) (map-tree function (cdr tree))))))

(defun list-splits (list)
  "For a proper LIST, every split (prefix . rest) of it, shortest prefix first; NIL for a dotted
or circular list."
  (when (alexandria:proper-list-p list)
    (loop for i from 0 to (length list)
          collect (cons (subseq list 0 i) (nthcdr i list)))))

(defun match-segvar (pattern sequence bindings continuation)
  "Match the segment form PATTERN, (!?x . rest), against SEQUENCE under BINDINGS: ?x takes the
shortest prefix of SEQUENCE for which CONTINUATION, called as (continuation rest remaining
bindings) and returning (values bindings matched-p), matches the rest. Returns (values bindings
matched-p); a dotted SEQUENCE never matches."
  (let ((var (var-name (car pattern))))
    (if (null (cdr pattern))
        (if (alexandria:proper-list-p sequence)
            (add-bdg var (copy-list sequence) bindings)
            (values nil nil))
        (let ((splits (list-splits sequence)))
          (dolist (split splits (values nil nil))
            (multiple-value-bind (new-bindings matched-p)
                (funcall continuation (cdr pattern) (cdr split) bindings)
              (when matched-p
                (multiple-value-bind (final ok) (add-bdg var (car split) new-bindings)
                  (when ok (return (values final t)))))))))))

(defun check-match-subject (sequence)
  (when (or (is-var sequence) (is-segvar sequence))
    (error "PAT-MATCH: found the variable ~s in the matched data; variables belong in the pattern."
           sequence)))

(defun match-test (options function)
  "The :TEST of the keyword list OPTIONS (#'EQL when absent); any other key is an error."
  (loop for (key value) on options by #'cddr
        unless (eq key :test)
          do (error "~s: unknown option ~s; the only option is :TEST." function key))
  (when (oddp (length options))
    (error "~s: odd keyword list ~s." function options))
  (getf options :test #'eql))

(defun pat-match (pattern sequence &optional bindings &rest options)
  "Match PATTERN, which may hold variables ?x and segment variables !?x (in the car of a cons),
against SEQUENCE, which must hold none. Atoms are compared with the function of the option
:TEST (EQL by default). Returns (values bindings
matched-p); a segment variable takes the shortest run of elements that lets the rest match."
  (unless (listp bindings)
    (error "PAT-MATCH: the bindings ~s are not a binding alist." bindings))
  (let ((test (match-test options 'pat-match)))
  (labels ((match (pattern sequence bindings)
             (check-match-subject sequence)
             (cond ((is-var pattern)
                    (if (is-unnamed-var pattern)
                        (values bindings t)
                        (let ((cell (assoc pattern bindings)))
                          (if cell
                              (if (equal (substitute-vars (cdr cell) bindings) sequence)
                                  (values bindings t)
                                  (values nil nil))
                              (values (acons pattern sequence bindings) t)))))
                   ((is-segvar pattern)
                    (error "PAT-MATCH: the segment variable ~s must be the car of a cons, as in ~
                            (a ~s b)." pattern pattern))
                   ((and (atom pattern) (atom sequence))
                    (if (funcall test pattern sequence) (values bindings t) (values nil nil)))
                   ((is-segform pattern)
                    (match-segvar pattern sequence bindings #'match))
                   ((and (consp pattern) (consp sequence))
                    (multiple-value-bind (new-bindings matched-p)
                        (match (car pattern) (car sequence) bindings)
                      (if matched-p
                          (match (cdr pattern) (cdr sequence) new-bindings)
                          (values nil nil))))
                   (t (values nil nil)))))
    (match pattern sequence bindings))))

(defun pat-match-p (pattern sequence &optional bindings &rest options)
  "True when PATTERN matches SEQUENCE (see PAT-MATCH; OPTIONS is :TEST)."
  (nth-value 1 (apply #'pat-match pattern sequence bindings options)))

(defun pattern-vars (pattern)
  "The variables PAT-MATCH binds for PATTERN: its ?x variables and the variables of its
segment variables, without ?_."
  (let ((vars '()))
    (labels ((walk (x)
               (cond ((is-unnamed-var x))
                     ((is-var x) (pushnew x vars))
                     ((is-segvar x) (let ((v (var-name x)))
                                      (unless (is-unnamed-var v) (pushnew v vars))))
                     ((consp x) (walk (car x)) (walk (cdr x))))))
      (walk pattern))
    (nreverse vars)))

(defmacro with-pat-vars-bound (pattern sequence &body body)
  "Evaluate BODY with each variable of PATTERN (not evaluated) bound as a Lisp variable to what
it matched in SEQUENCE (evaluated). A pattern that does not match is an error; a pattern without
variables warns."
  (let ((bindings (gensym "BINDINGS")) (matched (gensym "MATCHED")) (value (gensym "SEQUENCE"))
        (vars (pattern-vars pattern)))
    `(let ((,value ,sequence))
       (multiple-value-bind (,bindings ,matched) (pat-match ',pattern ,value)
         (unless ,matched
           (error "WITH-PAT-VARS-BOUND: the pattern ~s does not match ~s." ',pattern ,value))
         ,@(unless vars
             `((warn "WITH-PAT-VARS-BOUND: the pattern ~s holds no variables." ',pattern)))
         (let ,(mapcar (lambda (var) `(,var (var-value ',var ,bindings))) vars)
           (declare (ignorable ,@vars))
           ,@body)))))

(defun bindings-equal (lhs rhs &key (test #'equal))
  "True when every variable bound in LHS has, under TEST, the same value in RHS (as CRAM, a
one-sided comparison)."
  (loop for (var . value) in lhs
        always (funcall test value (cdr (assoc var rhs)))))

(defun patterns-eq (pattern-1 pattern-2)
  "True when the two patterns are equal up to the names of their variables: the same atoms
(EQL) and variables at the same places."
  (cond ((and (is-var pattern-1) (is-var pattern-2)) t)
        ((and (consp pattern-1) (consp pattern-2))
         (and (patterns-eq (car pattern-1) (car pattern-2))
              (patterns-eq (cdr pattern-1) (cdr pattern-2))))
        (t (eql pattern-1 pattern-2))))

(setf (documentation 'lazy-tail-p 'function)
      "True for the unexpanded end of a lazy list."
      (documentation 'unbound-variable-error-variable 'function)
      "The pattern variable an UNBOUND-VARIABLE-ERROR is about.")
