;;;; Pattern variables and binding alists ((?x . value) ...), as the Prolog API returns them.

(in-package :cram-utilities)

(declaim (inline is-var))
(defun is-var (object)
  "True when OBJECT is a pattern variable: a symbol whose name starts with #\\?."
  (and (symbolp object)
       object
       (let ((name (symbol-name object)))
         (and (> (length name) 0) (char= (char name 0) #\?)))))

(defun is-anonymous-var (object)
  "True when OBJECT is the anonymous variable ?_ (of any package)."
  (and (is-var object) (string= (symbol-name object) "?_")))

(defun binding-of (var bindings)
  "The cons (VAR . value) of VAR in BINDINGS, following chains of variables bound to variables;
returns the last cons found, or NIL."
  (let ((cell (assoc var bindings)) (seen 0))
    (loop while (and cell (is-var (cdr cell)) (not (eq (cdr cell) var)))
          do (let ((next (assoc (cdr cell) bindings)))
               (if (or (null next) (> (incf seen) (length bindings)))
                   (return)
                   (setf cell next))))
    cell))

(defun substitute-vars (pattern bindings)
  "PATTERN with every bound variable replaced (recursively) by its value in BINDINGS."
  (cond ((null bindings) pattern)
        ((is-var pattern)
         (let ((cell (binding-of pattern bindings)))
           (cond ((null cell) pattern)
                 ((is-var (cdr cell)) (cdr cell))
                 (t (substitute-vars (cdr cell) bindings)))))
        ((consp pattern)
         (let ((a (substitute-vars (car pattern) bindings))
               (d (substitute-vars (cdr pattern) bindings)))
           (if (and (eq a (car pattern)) (eq d (cdr pattern)))
               pattern
               (cons a d))))
        (t pattern)))

(defun var-value (var bindings)
  "The value of the variable VAR in BINDINGS with all bound variables inside it substituted;
VAR itself (or the last variable of its chain) when unbound. Anything that is not a variable (a
list, a number ...) is returned as it is, as in CRAM: use SUBSTITUTE-VARS for patterns."
  (unless (and (listp bindings) (every #'consp bindings))
    (error "VAR-VALUE of ~s: expected a binding alist ((?var . value) ...), got ~s."
           var (if (listp bindings) (find-if-not #'consp bindings) bindings)))
  (if (is-var var)
      (substitute-vars var bindings)
      var))

(defun is-bound (var bindings)
  "True unless VAR is a variable without a non-variable value in BINDINGS (anything that is not
a variable, a list holding variables included, counts as bound, as in CRAM)."
  (if (is-var var)
      (let ((cell (binding-of var bindings)))
        (and cell (not (is-var (cdr cell))) t))
      t))

(defun is-ground (pattern &optional bindings)
  "True when PATTERN, after substitution with BINDINGS, holds no variable."
  (let ((p (substitute-vars pattern bindings)))
    (labels ((ground-p (x)
               (cond ((is-var x) nil)
                     ((consp x) (and (ground-p (car x)) (ground-p (cdr x))))
                     (t t))))
      (ground-p p))))

(defun vars-in (pattern)
  "The list of distinct variables in PATTERN, in order of first occurrence (without ?_)."
  (let ((vars '()))
    (labels ((walk (x)
               (cond ((is-anonymous-var x))
                     ((is-var x) (pushnew x vars))
                     ((consp x) (walk (car x)) (walk (cdr x))))))
      (walk pattern))
    (nreverse vars)))

(defun rename-vars (pattern)
  "PATTERN with every variable replaced by a fresh uninterned one (consistently)."
  (let ((map '()))
    (labels ((walk (x)
               (cond ((is-anonymous-var x) (make-symbol "?_"))
                     ((is-var x)
                      (or (cdr (assoc x map))
                          (let ((new (make-symbol (symbol-name x))))
                            (push (cons x new) map)
                            new)))
                     ((consp x) (cons (walk (car x)) (walk (cdr x))))
                     (t x))))
      (walk pattern))))

(defun unify (a b &optional bindings)
  "Unify the patterns A and B under BINDINGS. Returns (values new-bindings t) on success and
(values nil nil) on failure. Atoms unify when EQUAL; ?_ unifies with anything; no occurs check.
A segment variable !?x in the car of a cons of either side takes the shortest run of elements of
the other side (a proper list) that lets the rest unify, and binds ?x to it; a segment variable
anywhere else is an error."
  (labels ((deref (x bdgs)
             (loop while (is-var x)
                   do (let ((cell (assoc x bdgs)))
                        (if (and cell (not (eq (cdr cell) x))) (setf x (cdr cell)) (return))))
             x)
           (u (a b bdgs)
             (let ((a (deref a bdgs)) (b (deref b bdgs)))
               (cond ((or (is-segvar a) (is-segvar b))
                      (error "UNIFY: the segment variable ~s is not the car of a cons (unifying ~
                              ~s with ~s)." (if (is-segvar a) a b) a b))
                     ((or (is-anonymous-var a) (is-anonymous-var b)) (values bdgs t))
                     ((and (is-var a) (eq a b)) (values bdgs t))
                     ((is-var a) (values (acons a b bdgs) t))
                     ((is-var b) (values (acons b a bdgs) t))
                     ((is-segform a) (match-segvar a b bdgs #'u))
                     ((is-segform b) (match-segvar b a bdgs #'u))
                     ((and (consp a) (consp b))
                      (multiple-value-bind (b1 ok) (u (car a) (car b) bdgs)
                        (if ok (u (cdr a) (cdr b) b1) (values nil nil))))
                     ((equal a b) (values bdgs t))
                     (t (values nil nil))))))
    (u a b bindings)))

(defun unify-p (a b &optional bindings)
  "True when the patterns A and B unify under BINDINGS (see UNIFY)."
  (nth-value 1 (unify a b bindings)))

(defun add-bdg (var value bindings)
  "Add the binding of VAR to VALUE to BINDINGS, unifying with an existing value of VAR.
Returns (values new-bindings t), or (values nil nil) when VAR is bound to something else."
  (unify var value bindings))

(define-condition unbound-variable-error (error)
  ((variable :initarg :variable :reader unbound-variable-error-variable))
  (:report (lambda (c s)
             (format s "Pattern variable ~s is unbound, but WITH-VARS-STRICTLY-BOUND needs a value."
                     (unbound-variable-error-variable c))))
  (:documentation "Signalled by WITH-VARS-STRICTLY-BOUND for a variable without a value."))

(defmacro with-vars-bound (vars bindings &body body)
  "Evaluate BODY with each variable symbol in VARS bound (as a Lisp variable) to its value in
BINDINGS (the variable itself when unbound). BINDINGS may be a form evaluated once."
  (let ((b (gensym "BDGS")))
    `(let* ((,b ,bindings)
            ,@(mapcar (lambda (v) `(,v (var-value ',v ,b))) vars))
       (declare (ignorable ,@vars))
       ,@body)))

(defmacro with-vars-strictly-bound (vars bindings &body body)
  "Like WITH-VARS-BOUND, but signal UNBOUND-VARIABLE-ERROR for a variable that has no ground value."
  (let ((b (gensym "BDGS")))
    `(let* ((,b ,bindings)
            ,@(mapcar (lambda (v)
                        `(,v (let ((val (var-value ',v ,b)))
                               (unless (is-ground val)
                                 (error 'unbound-variable-error :variable ',v))
                               val)))
                      vars))
       (declare (ignorable ,@vars))
       ,@body)))
