;;;; The RETE network's working memory and the pieces the alpha and beta networks share: small
;;;; EQ sets, working-memory elements (one per distinct fact), the lock, the counters, and the
;;;; one-sided matching of patterns against facts.
;;;;
;;;; Facts are data: a ?symbol inside an asserted fact is an ordinary constant. Atoms of a fact
;;;; and of a pattern are compared with EQUAL.

(in-package :cram-prolog)

;;; Sets compared with EQ: a short list while small, a hash table once they grow, so that adding
;;; and removing stay cheap however many tokens or facts a memory holds.

(defconstant +rset-list-limit+ 16
  "The size above which an RSET keeps its items in a hash table.")

(defstruct (rset (:constructor make-rset ()) (:copier nil))
  "A set of objects compared with EQ (see RSET-ADD, RSET-REMOVE, DO-RSET)."
  (list '() :type list)
  (table nil)
  (count 0 :type fixnum))

(defun rset-add (set item)
  "Add ITEM, which must not be in SET yet. Returns ITEM."
  (let ((table (rset-table set)))
    (cond (table (setf (gethash item table) t))
          ((< (rset-count set) +rset-list-limit+) (push item (rset-list set)))
          (t (let ((table (make-hash-table :test 'eq)))
               (dolist (x (rset-list set)) (setf (gethash x table) t))
               (setf (gethash item table) t
                     (rset-table set) table
                     (rset-list set) '())))))
  (incf (rset-count set))
  item)

(defun rset-remove (set item)
  "Remove ITEM from SET; true when it was there."
  (let ((table (rset-table set)))
    (cond (table
           (when (remhash item table)
             (when (zerop (decf (rset-count set)))
               (setf (rset-table set) nil))
             t))
          ((member item (rset-list set) :test #'eq)
           (setf (rset-list set) (delete item (rset-list set) :test #'eq :count 1))
           (decf (rset-count set))
           t))))

(defun rset-items (set)
  "A fresh list of the items of SET (safe to iterate while SET changes)."
  (let ((table (rset-table set)))
    (if table
        (loop for x being the hash-keys of table collect x)
        (copy-list (rset-list set)))))

(defmacro do-rset ((var set) &body body)
  "Evaluate BODY with VAR bound to each item of SET, which BODY must not change."
  (let ((s (gensym "SET")) (f (gensym "FN")) (k (gensym)) (v (gensym)))
    `(let ((,s ,set))
       (flet ((,f (,var) ,@body))
         (if (rset-table ,s)
             (maphash (lambda (,k ,v) (declare (ignore ,v)) (,f ,k)) (rset-table ,s))
             (dolist (,k (rset-list ,s)) (,f ,k)))))))

(defun rset-clear (set)
  "Remove every item of SET."
  (setf (rset-list set) '() (rset-table set) nil (rset-count set) 0))

;;; Working memory

(defstruct (wme (:constructor make-wme (fact serial)) (:copier nil))
  "A working-memory element: a FACT as asserted (a private copy), its SERIAL number (the order
of assertion), the ALPHA-MEMORIES holding it and the TOKENS that matched it."
  fact
  (serial 0 :type fixnum)
  (alpha-memories '())
  (tokens (make-rset)))

(defvar *working-memory* (make-hash-table :test 'equal)
  "The facts RETE-ASSERT added: fact → its WME.")

(defvar *next-wme-serial* 0 "The serial number of the last WME made.")

(defvar *working-memory-lock* (sb-thread:make-mutex :name "rete working memory")
  "Serialises every change and every reading of the RETE network and the calls of production
handlers.")

(defmacro with-rete-lock (() &body body)
  "Evaluate BODY holding the RETE network's (recursive) lock."
  `(sb-thread:with-recursive-lock (*working-memory-lock*) ,@body))

(defvar *join-attempts* 0
  "How many (token, fact) pairs join nodes have examined: the work of propagating changes.")

(defvar *prove-attempts* 0
  "How many facts RETE-PROVE and RETE-HOLDS have matched against a pattern.")

(defun check-fact (fact function)
  "Signal a PROLOG-ERROR naming FUNCTION unless FACT is a non-empty proper list."
  (unless (and (consp fact) (alexandria:proper-list-p fact))
    (prolog-error "~s: the fact ~s is not a list (functor argument...)." function fact)))

(defun wmes-by-serial (wmes)
  "WMES (a fresh list) in the order their facts were asserted."
  (sort wmes #'< :key #'wme-serial))

(defun all-wmes ()
  "Every WME of the working memory, in the order of assertion."
  (wmes-by-serial (loop for wme being the hash-values of *working-memory* collect wme)))

;;; Patterns

(defun check-pattern (pattern function &optional production)
  "Signal a PROLOG-ERROR naming FUNCTION (and PRODUCTION) when PATTERN holds a segment variable
that is not the car of a cons (where UNIFY and PAT-MATCH accept it). Returns PATTERN."
  (labels ((walk (x)
             (cond ((is-segvar x)
                    (let ((*print-pretty* nil))
                      (prolog-error "~s~@[ ~s~]: the pattern ~s holds the segment variable ~s ~
                                     outside the first element of a list (write (a !?x b))."
                                    function production pattern x)))
                   ((consp x)
                    (if (is-segvar (car x)) nil (walk (car x)))
                    (walk (cdr x))))))
    (walk pattern)
    pattern))

(defun segmented-p (pattern)
  "True when PATTERN holds a segment variable (!?x)."
  (cond ((is-segvar pattern) t)
        ((consp pattern) (or (segmented-p (car pattern)) (segmented-p (cdr pattern))))
        (t nil)))

(defun match-term (pattern datum bindings)
  "Match PATTERN, whose ?variables are bound in BINDINGS (an alist of direct values), against
the data DATUM, whose ?symbols are constants; atoms compare with EQUAL, ?_ matches anything, a
segment variable !?x takes the shortest run of elements that lets the rest match. Returns (values
bindings t), BINDINGS extended, or (values nil nil)."
  (labels ((m (p d b)
             (cond ((is-var p)
                    (if (is-anonymous-var p)
                        (values b t)
                        (let ((cell (assoc p b :test #'eq)))
                          (cond ((null cell) (values (acons p d b) t))
                                ((equal (cdr cell) d) (values b t))
                                (t (values nil nil))))))
                   ((is-segform p) (match-segvar p d b #'m))
                   ((consp p)
                    (if (consp d)
                        (multiple-value-bind (b2 ok) (m (car p) (car d) b)
                          (if ok (m (cdr p) (cdr d) b2) (values nil nil)))
                        (values nil nil)))
                   ((equal p d) (values b t))
                   (t (values nil nil)))))
    (m pattern datum bindings)))

(defun canonical-var (index)
  "The variable ?<INDEX> of the CRAM-PROLOG package, which pattern shapes use."
  (intern (format nil "?~d" index) :cram-prolog))

(defun pattern-shape (pattern)
  "PATTERN with its variables renamed ?0, ?1 ... in order of first occurrence (segment variables
!?0 ...; ?_ stays): patterns that differ only in the names of their variables have EQUAL shapes."
  (let ((map '()))
    (labels ((rename (var)
               (or (cdr (assoc var map))
                   (let ((new (canonical-var (length map))))
                     (push (cons var new) map)
                     new)))
             (walk (x)
               (cond ((is-anonymous-var x) '?_)
                     ((is-var x) (rename x))
                     ((is-segvar x)
                      (let ((var (var-name x)))
                        (if (is-anonymous-var var)
                            '!?_
                            (intern (format nil "!~a" (symbol-name (rename var))) :cram-prolog))))
                     ((consp x) (cons (walk (car x)) (walk (cdr x))))
                     (t x))))
      (walk pattern))))

(defun shape-needs-test-p (shape)
  "True when matching SHAPE needs more than its constant structure: it repeats a variable or
holds a segment variable."
  (or (segmented-p shape)
      (let ((seen '()))
        (labels ((walk (x)
                   (cond ((is-anonymous-var x) nil)
                         ((is-var x) (if (member x seen) t (progn (push x seen) nil)))
                         ((consp x) (or (walk (car x)) (walk (cdr x))))
                         (t nil))))
          (walk shape)))))

(defun variable-paths (pattern)
  "The variables of PATTERN (without ?_) with the path to their first occurrence, in order:
an alist var → path, a path being a list of T (car) and NIL (cdr) steps."
  (let ((result '()))
    (labels ((walk (x path)
               (cond ((is-anonymous-var x))
                     ((is-var x)
                      (unless (assoc x result) (push (cons x (reverse path)) result)))
                     ((consp x)
                      (walk (car x) (cons t path))
                      (walk (cdr x) (cons nil path))))))
      (walk pattern '()))
    (nreverse result)))

(declaim (inline value-at-path))
(defun value-at-path (datum path)
  "The part of DATUM that PATH (see VARIABLE-PATHS) leads to."
  (dolist (step path datum)
    (setf datum (if step (car datum) (cdr datum)))))

(defun binding-value (var bindings)
  "The value of VAR in BINDINGS (direct values), or VAR itself when unbound."
  (let ((cell (assoc var bindings :test #'eq)))
    (if cell (cdr cell) var)))

(defun prolog-pattern-p (pattern)
  "True when PATTERN is proved by Prolog (its functor has clauses or a handler) rather than
matched against the working memory."
  (let ((functor (car pattern)))
    (and (symbolp functor) (not (is-var functor))
         (let ((pred (gethash functor *predicates*)))
           (and pred (or (pred-sources pred) (pred-dynamic pred) (pred-handler pred)
                         (pred-native pred) (pred-control pred))
                t)))))
